"""The recording contract over every registered mission (issue 28, check 1): a short scenario of
each, run through the runner as ``bauv run`` does, and its ``recording.rrd`` read back.

What is expected comes from the run itself, not from the recording: the runner's stored blocks
(:mod:`tasks.core.store`) hold every flight of the run as plain data
(:class:`~tasks.closed_loop.result.MissionRun`), with each vehicle's per-tick truth and the
estimates its navigation part declared. For every vehicle of every flight the recording must hold
the hull posed by that truth, the truth track, each declared estimate's track equal to its column
(and, where it has a covariance, the ellipsoids whose squared half sizes sum to the covariance's
trace), labels naming the vehicle and the method; and the scene's seabed. A mission registered
later is picked up by the registry (its short scenario: :data:`DEFAULT_SHORT`, unless it needs
its own below).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tasks.closed_loop.recording_vehicle import estimate_covariance, estimate_positions, slug
from tasks.closed_loop.result import MissionRun
from tasks.core import registry, store
from tasks.core.recording import entity_paths, read_static, read_time_series
from tasks.core.runner import run

MISSIONS = [n for n in registry.names() if n.startswith("mission/")]

DEFAULT_SHORT = ("timing.max_duration_s=30",)
"""A mission's short scenario unless it has its own (:data:`SHORT`)."""

SHORT = {
    "mission/correction": ("correction.leg_length_m=15",),
    "mission/seed004": (
        "seed004.duration_s=20",
        "timing.max_duration_s=20",
        "seed004.train_paths=200",
        "seed004.surrogate_test_paths=100",
    ),
    # on the acoustic network: the team methods' estimates of every vehicle are declared too
    "mission/swarm": (
        "timing.max_duration_s=20",
        "followers.count=2",
        'navigation.methods=["ga1","ekf"]',
        "followers.network.enabled=true",
    ),
    "mission/trn": ("timing.max_duration_s=70", "trn.t_dive_s=40"),
}
"""Missions whose preset needs more than a time limit to be short (e.g. the correction's legs,
which the flight completes before anything is reported)."""

POS = "Points3D:positions"


def flights_of(value, key: str = "") -> dict[str, MissionRun]:
    """Every :class:`MissionRun` in a stored block's value, by the key of the mapping that holds
    it (``""`` for one held in a field or a list): the run's flights."""
    out: dict[str, MissionRun] = {}
    if isinstance(value, MissionRun):
        out[key] = value
    elif isinstance(value, dict):
        for k, v in value.items():
            out |= flights_of(v, str(k))
    elif isinstance(value, (list, tuple)):
        for v in value:
            out |= flights_of(v, key)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            out |= flights_of(getattr(value, f.name), "")
    return out


@pytest.fixture(scope="module", params=MISSIONS)
def mission(request, tmp_path_factory):
    name = request.param
    out = tmp_path_factory.mktemp(name.replace("/", "-")) / "run"
    overrides = [*SHORT.get(name, DEFAULT_SHORT), "report.figures=false"]
    run(name, n_runs=1, seed=0, out_dir=out, progress=False, overrides=overrides)
    blocks = sorted((out / "blocks").glob("block-*.zip"))
    flights = {k: f for b in blocks for k, f in flights_of(store.load(b).value).items()}
    flights = {k: f for k, f in flights.items() if f.vehicles}
    return name, out / "recording.rrd", flights


@pytest.mark.slow
def test_every_mission_writes_one_recording_with_its_scene(mission):
    name, rec, flights = mission
    assert rec.is_file(), f"{name}: no recording.rrd"
    assert flights, f"{name}: no flight in the run's blocks"
    assert not list(rec.parent.glob("*.rrd"))[1:], f"{name}: more than one recording"
    paths = entity_paths(rec)
    assert "/world/seabed" in paths, f"{name}: no seabed"
    assert read_static(rec, "world/seabed", "Mesh3D:vertex_positions"), name


@pytest.mark.slow
def test_every_vehicle_has_its_hull_truth_and_estimates(mission):
    name, rec, flights = mission
    paths = entity_paths(rec)
    multi = len(flights) > 1
    for flight, fr in flights.items():
        for vn, v in fr.vehicles.items():
            tag = f"{flight}/{vn}" if multi else vn
            where = f"{name} {tag}"
            truth = v["truth_pos"]
            assert f"/world/{tag}/body/hull" in paths, f"{where}: no hull"
            _, trans = read_time_series(rec, f"world/{tag}/body", "Transform3D:translation")
            assert np.allclose(trans, truth, atol=1e-4), f"{where}: hull not at the truth"
            t, pos = read_time_series(rec, f"world/{tag}/truth/position", POS)
            assert np.allclose(t, v["t"]) and np.allclose(pos, truth, atol=1e-4), where
            with_cov = 0
            for e in v.estimates:
                if e.column not in v.ticks:
                    continue
                m = slug(e.method)
                _, est = read_time_series(rec, f"world/{tag}/{m}/position", POS)
                ok = np.isfinite(estimate_positions(v, e)).all(axis=1)
                assert np.allclose(est, estimate_positions(v, e)[ok], atol=1e-4), where + m
                (label,) = read_static(rec, f"world/{tag}/{m}/position", "Points3D:labels")[0]
                assert vn in label and e.method in label, f"{where}: label {label!r}"
                P = estimate_covariance(v, e)
                if P is None:
                    continue
                with_cov += 1
                tc, half = read_time_series(
                    rec, f"world/{tag}/{m}/covariance", "Ellipsoids3D:half_sizes"
                )
                k = np.searchsorted(v["t"], tc)
                assert np.allclose(t[k], tc)
                trace = np.trace(P[k], axis1=1, axis2=2)
                assert np.allclose((half**2).sum(axis=1), trace, rtol=1e-4), where + m
            assert with_cov >= 1, f"{where}: no estimate with a covariance"
