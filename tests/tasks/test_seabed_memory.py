"""The batch's memory check counts the seabed grid and the multibeam images sized from the
scenario (issue 21: ``--set seabed.half_extent_m=1e7`` allocated a 29 TiB grid inside the batch
check and ended in a traceback). The estimates are checked against tracemalloc's measured peaks."""

import tracemalloc

import numpy as np
import pytest

from bauv_sim import seabed
from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError
from tasks.core import registry
from tests.tasks.refusal import run_in_process


def _no_grid(*_a, **_k):
    raise AssertionError("a seabed grid was generated before the memory check")


@pytest.mark.parametrize(
    ("name", "overrides", "pattern"),
    [
        (
            "mission/short",
            ["seabed.half_extent_m=10000", "seabed.cell_m=0.05"],
            "seabed.half_extent_m = 10000 with seabed.cell_m = 0.05 m (400001 x 400001 grid "
            "points): the batch would need about 1.54e+04 GB of memory, above the limit",
        ),
        (
            "mission/seed004",
            ["seabed.half_extent_m=10000"],
            "seabed.half_extent_m = 10000 with seabed.cell_m = 0.5 m (40001 x 40001 grid points)",
        ),
        (
            "mission/swarm",
            ["seabed.half_extent_m=10000", "seabed.cell_m=0.1"],
            "(200001 x 200001 grid points): the batch would need about",
        ),
        (
            "mission/correction",
            ["seabed.half_extent_m=10000", "seabed.cell_m=0.1"],
            "(200001 x 200001 grid points): the batch would need about",
        ),
        (
            "mission/seed004",
            [
                'navigation.prediction="seabed"',
                "seed004.train_paths=100000",
                "multibeam.beams_elevation=64",
                "multibeam.beams_azimuth=64",
            ],
            "seed004.train_paths = 100000 imaged with multibeam.beams_elevation x beams_azimuth "
            "= 64 x 64 beams",
        ),
        (
            "paper-004/table-1-seabed",
            [
                "filters.train_paths=100000",
                "multibeam.beams_elevation=64",
                "multibeam.beams_azimuth=64",
            ],
            "filters.train_paths = 100000 imaged with multibeam.beams_elevation x beams_azimuth "
            "= 64 x 64 beams: the batch would need about",
        ),
        (
            "mission/short",
            ["seabed.half_extent_m=1e7"],
            "seabed.half_extent_m = 10000000.0: Input should be less than or equal to 10000",
        ),
        (
            "mission/short",
            ["seabed.cell_m=0.001", "seabed.half_extent_m=1"],
            "seabed.cell_m = 0.001: Input should be greater than or equal to 0.01",
        ),
    ],
    ids=["short", "seed004", "swarm", "correction", "seed004-images", "paper004", "1e7", "cell"],
)
def test_a_seabed_too_big_is_one_line_before_anything_is_allocated(
    name, overrides, pattern, tmp_path, capsys, monkeypatch
):
    """One line naming the fields, exit 2, nothing written, no grid generated, no block run."""
    monkeypatch.setattr(seabed, "generate", _no_grid)
    for exp in registry.all_experiments():
        monkeypatch.setattr(type(exp), "run_block", _no_grid)
    out = tmp_path / "out"
    sets = [a for o in overrides for a in ("--set", o)]
    code, err = run_in_process(capsys, "run", name, "--quiet", "--out", str(out), *sets)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and pattern in lines[0], err
    assert not out.exists()


def test_resume_checks_the_memory_before_it_generates_the_seabed(tmp_path, monkeypatch):
    """plan_resume runs the experiment's checks, which generate the seabed: the memory comes
    first there too (MissionExperiment.check)."""
    exp = registry.get("mission/short")
    scn = load_config(
        exp.scenario_type, exp.preset, (), ["seabed.half_extent_m=10000", "seabed.cell_m=0.05"]
    )
    monkeypatch.setattr(seabed, "generate", _no_grid)
    with pytest.raises(ConfigError, match="400001 x 400001 grid points"):
        exp.check(scn, 1)


def test_the_grid_estimate_is_the_measured_peak_of_generating_it():
    """grid_bytes against tracemalloc's peak of generate on a 1001 x 1001 grid, within 10%."""
    c = seabed.SeabedConfig(half_extent_m=500.0, cell_m=1.0)
    tracemalloc.start()
    try:
        bed = seabed.generate(c)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert bed.depth_m.shape == (1001, 1001)
    assert 0.9 * peak < c.grid_bytes < 1.1 * peak, (c.grid_bytes, peak)


@pytest.mark.slow
def test_a_mission_block_peaks_at_its_estimate():
    """A mission block on a 2001 x 2001 grid (the scene's seabed dominates a 2 s flight): the
    block's estimate (the per-block terms) is its measured peak within 30%."""
    exp = registry.get("mission/short")
    scn = load_config(
        exp.scenario_type,
        exp.preset,
        (),
        ["seabed.half_extent_m=1000", "seabed.cell_m=1", "timing.max_duration_s=2"],
    )
    tracemalloc.start()
    try:
        exp.run_block(scn, 0, (0,))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    block = sum(t.bytes for t in exp.memory(scn, 1) if t.per_block)
    assert 0.7 * peak < block < 1.3 * peak, (block, peak)


def _image_peak(make, n: int, beams: int) -> float:
    """Peak bytes of one step of a seabed-sensing prediction over ``n`` paths (two images and
    the shift), per path and beam. ``make`` runs once before the measurement: numba compiles
    the seabed kernels (or loads them from its cache) at their first call, a one-time cost of
    the process and not a step's (unwarmed, on a checkout with no numba cache, the first call
    measured 800-1430 B per path and beam against the surrogate's 470)."""
    make()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        make()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return (peak - base) / (n * beams)


@pytest.mark.slow
def test_the_surrogates_image_estimate_is_its_measured_peak():
    """mission/seed004's surrogate images (HeightfieldPrediction), 12 x 12 beams on 300 paths:
    IMAGE_BYTES_PER_PATH_BEAM within 30% of the measured peak per path and beam."""
    from bauv_sim.sensors.multibeam import MultibeamConfig
    from tasks.missions.seed004 import IMAGE_BYTES_PER_PATH_BEAM
    from tasks.paper004.seabed import HeightfieldPrediction, heightfield

    exp = registry.get("mission/seed004")
    scn = load_config(exp.scenario_type, exp.preset)
    bed = heightfield(scn.seabed)
    bed.max_slope  # noqa: B018  (cached before the measurement, as in the training)
    m, n = 12, 300
    cfg = MultibeamConfig(beams_elevation=m, beams_azimuth=m)
    x = np.column_stack([np.linspace(-50, 50, n), np.zeros(n), np.full(n, -2.0)])
    u = np.tile([0.0, 0.3, 2.0], (n, 1))

    def step():
        p = HeightfieldPrediction(bed, cfg, "quadratic", 0, tuple(range(n)), 1.0, np.eye(3))
        p.after(0, x, u)
        p.before(1, x, u)
        p.after(1, x + [2.0, 0.0, 0.0], u)
        p(1, x, u)

    per = _image_peak(step, n, m * m)
    assert 0.7 * per < IMAGE_BYTES_PER_PATH_BEAM < 1.3 * per, (IMAGE_BYTES_PER_PATH_BEAM, per)


def test_paper004s_image_estimate_is_its_measured_peak():
    """paper-004's seabed row (SeabedPrediction over the harmonic seabed), 12 x 12 beams on 500
    paths: IMAGE_BYTES_PER_PATH_BEAM within 30% of the measured peak per path and beam."""
    from bauv_sim.kinematic.seed004 import NominalPathConfig
    from bauv_sim.sensors.multibeam import MultibeamConfig
    from tasks.paper004.seabed import SeabedPrediction
    from tasks.paper004.table1 import IMAGE_BYTES_PER_PATH_BEAM

    m, n = 12, 500
    cfg = MultibeamConfig(beams_elevation=m, beams_azimuth=m)
    path = NominalPathConfig()
    x = np.tile(path.start_m, (n, 1)).astype(float)
    u = np.tile(path.controls()[0], (n, 1))

    def step():
        p = SeabedPrediction(
            "one_attitude", 0, tuple(range(n)), path.dt_s, path.controls(), "test", cfg=cfg
        )
        p.before(0, x, u)
        p.after(0, x + [2.0, 0.0, 0.0], u)
        p(0, x, u)

    per = _image_peak(step, n, m * m)
    assert 0.7 * per < IMAGE_BYTES_PER_PATH_BEAM < 1.3 * per, (IMAGE_BYTES_PER_PATH_BEAM, per)
