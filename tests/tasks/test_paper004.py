"""Seed 004 experiments end to end (small batches): Table 1's row 1 beside the PCRB, the near-beacon
breakdown of the EKF, determinism, the CMNF gains as plain data, bad geometry and bad input."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from tasks.core.runner import run

SMALL = ["path.duration_s=60.0", "filters.train_paths=800", "runner.block_size=40"]
FAST = [*SMALL, "report.figures=false"]


def _metrics(out):
    return json.loads((out / "metrics.json").read_text())


def _case(m, bearing):
    return next(c for c in m["cases"] if math.isclose(c["bearing_sigma_deg"], bearing))


@pytest.fixture(scope="module")
def table1(tmp_path_factory):
    out = tmp_path_factory.mktemp("t1") / "run"
    run("paper-004/table-1", n_runs=80, seed=0, out_dir=out, overrides=SMALL, progress=False)
    return out


@pytest.mark.slow
def test_table1_row1_filters_are_equal_and_sit_on_the_pcrb_level(table1):
    m = _metrics(table1)
    for bearing, level in ((0.5, 8.28), (1.0, 14.73)):
        c = _case(m, bearing)
        js = [f["j_bar_m2"] for f in c["filters"]]
        # 60 s of the path: the maximum of the posterior error is later (k ~ 130), so the bound
        # is below the 300 s level but the filters are equal and above their bound
        assert max(js) / min(js) < 1.10, js
        for f in c["filters"]:
            assert f["pcrb_level_m2"] < level
            assert f["j_bar_m2"] >= 0.95 * f["pcrb_level_m2"], f
            assert f["diverged_paths"] == 0 and f["absent_pairs"] == 0
        paper = {f["filter"]: f["paper_m2"] for f in c["filters"]}
        assert paper == (
            {"CMNF": 14.89, "UPMF": 14.80, "EKF": 14.93}
            if bearing == 1.0
            else {"CMNF": None, "UPMF": None, "EKF": None}
        )
    hi, lo = _case(m, 1.0), _case(m, 0.5)
    for a, b in zip(hi["filters"], lo["filters"], strict=True):
        assert a["j_bar_m2"] > b["j_bar_m2"]  # more bearing noise, larger J-bar
    text = (table1 / "tables.md").read_text()
    assert "Table 1, row 1" in text and "nan" not in text.lower()
    for name in (
        "nominal-3d.png",
        "nominal-components.png",
        "sample-paths-bearing1deg-s0x1.png",
        "error-bearing1deg-s0x1.pdf",
    ):
        assert (table1 / name).is_file(), name


@pytest.mark.slow
def test_cmnf_gains_are_saved_as_plain_data_and_reused(table1, tmp_path):
    gains = sorted((table1 / "gains").glob("*.npz"))
    assert len(gains) == 2
    with np.load(gains[0], allow_pickle=False) as z:
        assert {"F", "f", "H", "h", "p_tilde", "p_hat", "info"} <= set(z.files)
    again = tmp_path / "again"
    run(
        "paper-004/table-1",
        n_runs=80,
        seed=0,
        out_dir=again,
        overrides=[*FAST, f"filters.gains_dir={json.dumps(str(table1 / 'gains'))}"],
        progress=False,
    )
    assert (again / "metrics.json").read_text() == (table1 / "metrics.json").read_text()
    # gains of another setting are refused
    with pytest.raises(Exception, match="trained for another setting"):
        run(
            "paper-004/table-1",
            n_runs=4,
            seed=1,
            out_dir=tmp_path / "other",
            overrides=[*FAST, f"filters.gains_dir={json.dumps(str(table1 / 'gains'))}"],
            progress=False,
        )


@pytest.mark.slow
def test_same_seed_same_numbers_whatever_the_worker_count(tmp_path):
    outs = []
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        over = [*FAST, "path.duration_s=20.0", "runner.block_size=8", "filters.train_paths=200"]
        run(
            "paper-004/table-1",
            n_runs=24,
            seed=3,
            out_dir=out,
            overrides=over,
            workers=workers,
            progress=False,
        )
        outs.append((out / "metrics.json").read_text())
    assert outs[0] == outs[1]


def test_near_beacon_ekf_breaks_down_at_the_documented_spread(tmp_path):
    out = tmp_path / "nb"
    over = [
        "filters.train_paths=1000",
        "report.figures=false",
        "sweep.initial_variance_m2=[1.0, 10.0]",
    ]
    run("paper-004/near-beacon", n_runs=400, seed=0, out_dir=out, overrides=over, progress=False)
    m = _metrics(out)
    j = {
        c["initial_variance_m2"]: {f["filter"]: f["j_bar_m2"] for f in c["filters"]}
        for c in m["cases"]
    }
    # S_0 = I: equal, pinned at k = 1 (3 + trace S_0 = 6)
    assert max(j[1.0].values()) / min(j[1.0].values()) < 1.05
    assert all(abs(v - 6.0) < 0.6 for v in j[1.0].values())
    # S_0 = 10 I: the EKF at least twice the others (the reading notes: ~1e5 against ~33)
    assert j[10.0]["EKF"] >= 2 * max(j[10.0]["UPMF"], j[10.0]["CMNF"])
    assert m["claims"]["bearing0.5deg-s0x10: EKF J-bar at least twice the UPMF's and the CMNF's"]
    assert m["ekf_starts_to_lose_m2"] == 10.0


@pytest.mark.slow
def test_near_beacon_cmnf_trained_on_few_paths_stays_on_the_bound_or_is_flagged(tmp_path):
    """2000 training paths, S_0 = 5 I, seed 2. Every filter that follows the path has J-bar at
    its PCRB level 3 + trace S_0 = 18 (pinned at k = 1). The paper's unclipped CMNF does not:
    a test path passing under the beacon's x gets a tangent residual beyond its training paths
    and a correction of hundreds of metres (J-bar 88), which the report names; the winsorised
    CMNF stays on the bound and no warning is given."""
    over = [
        "filters.train_paths=2000",
        "report.figures=false",
        "sweep.initial_variance_m2=[5.0]",
        "report.documented_variance_m2=5.0",
    ]
    cm = {}
    for clip in ("6.0", "0.0"):
        out = tmp_path / f"clip{clip}"
        o = [*over, f"filters.clip_sigmas={clip}"]
        run("paper-004/near-beacon", n_runs=4000, seed=2, out_dir=out, overrides=o, progress=False)
        m = _metrics(out)
        f = next(f for f in m["cases"][0]["filters"] if f["filter"] == "CMNF")
        cm[clip] = (f, [w for w in m["warnings"] if "CMNF: on the test paths" in w])
    f, w = cm["6.0"]
    assert f["j_bar_m2"] <= 1.05 * f["pcrb_level_m2"], f
    assert f["worse_than_prediction"] == [] and w == []
    f, w = cm["0.0"]
    assert f["j_bar_m2"] > 2 * f["pcrb_level_m2"], f
    assert f["worse_than_prediction"] and len(w) == 1
    assert "its correction made the estimate worse than its own prediction" in w[0]


def test_beacon_straight_above_the_path_degrades_with_a_warning_and_no_nan(tmp_path):
    base = tmp_path / "base"
    over = [*FAST, "path.duration_s=30.0", "sweep.bearing_sigma_deg=[0.5]"]
    run("paper-004/table-1", n_runs=40, seed=0, out_dir=base, overrides=over, progress=False)
    bad = tmp_path / "above"
    # beacon 4 right above the start of the path; pairs within 3 m horizontally are not produced
    beacons = "[[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], [0.0, 0.0, 0.0]]"
    run(
        "paper-004/table-1",
        n_runs=40,
        seed=0,
        out_dir=bad,
        overrides=[*over, f"beacons={beacons}", "noise.min_rho_m=3.0"],
        progress=False,
    )
    text = (bad / "metrics.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    m = _metrics(bad)
    w = " ".join(m["warnings"])
    assert "beacon 4 comes 90.0 deg above the nominal path" in w
    assert "bearing pairs not produced" in w
    jb = {f["filter"]: f["j_bar_m2"] for f in _metrics(base)["cases"][0]["filters"]}
    ja = {f["filter"]: f["j_bar_m2"] for f in m["cases"][0]["filters"]}
    assert ja["EKF"] > 1.5 * jb["EKF"], (ja, jb)
    for f in m["cases"][0]["filters"]:
        assert f["absent_pairs"] > 0 and f["j_bar_m2"] is not None


def _bauv(tmp_path, name, *args):
    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", name, *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    "name, args, pattern",
    [
        (
            "paper-004/table-1",
            ["--set", "sweep.bearing_sigma_deg=[50.0]"],
            "sweep.bearing_sigma_deg",
        ),
        ("paper-004/table-1", ["--set", "beacons=[[1.0, 2.0]]"], "beacons"),
        ("paper-004/table-1", ["--set", "filters.train_paths=1"], "filters.train_paths"),
        ("paper-004/table-1", ["--set", "filters.gains_dir='/no/such/dir'"], "filters.gains_dir"),
        ("paper-004/table-1", ["--set", "path.duration_s=10.5"], "path.duration_s = 10.5"),
        (
            "paper-004/table-1",
            [
                "--set",
                "path.duration_s=90000.0",
                "--set",
                "runner.block_size=100000",
                "--runs",
                "100000",
            ],
            "path.duration_s = 90000",
        ),
        (
            "paper-004/table-1",
            [
                "--set",
                "guidance.limits=true",
                "--set",
                "guidance.v_min_m_s=5.0",
                "--set",
                "guidance.v_max_m_s=1.0",
            ],
            "guidance.v_min_m_s = 5.0",
        ),
        (
            "paper-004/near-beacon",
            ["--set", "report.documented_variance_m2=7.0"],
            "report.documented_variance_m2 = 7.0",
        ),
        (
            "paper-004/near-beacon",
            [
                "--set",
                "beacons=[[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], "
                "[-5.0, -5.0, 0.0], [100.0, 100.0, 0.0]]",
                "--set",
                "filters.train_paths=11",
            ],
            "filters.train_paths = 11: with 5 beacons a CMNF gain row has 11 unknowns",
        ),
        ("paper-004/table-1", ["--set", "filters.clip_sigmas=-1.0"], "filters.clip_sigmas"),
        (
            "paper-004/table-1-seabed",
            ["--set", "multibeam.beams_elevation=3", "--set", "multibeam.beams_azimuth=3"],
            "3 x 3: Appendix A's harmonic fit of the seabed prediction has 9 unknowns",
        ),
    ],
)
def test_cli_refuses_bad_input_in_one_line(tmp_path, name, args, pattern):
    out = tmp_path / "bad"
    res = _bauv(tmp_path, name, "--runs", "2", "--out", str(out), *args)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and pattern in lines[0] and "Traceback" not in res.stderr, lines
    assert not out.exists()


def test_box_limited_guidance_runs_and_costs_accuracy(tmp_path):
    over = [*FAST, "path.duration_s=30.0", "sweep.bearing_sigma_deg=[0.5]"]
    free, lim = tmp_path / "free", tmp_path / "lim"
    run("paper-004/table-1", n_runs=40, seed=0, out_dir=free, overrides=over, progress=False)
    run(
        "paper-004/table-1",
        n_runs=40,
        seed=0,
        out_dir=lim,
        overrides=[*over, "guidance.limits=true", "guidance.v_max_m_s=2.5"],
        progress=False,
    )
    jf = _metrics(free)["cases"][0]["filters"]
    jl = _metrics(lim)["cases"][0]["filters"]
    for a, b in zip(jf, jl, strict=True):
        assert b["j_bar_m2"] > a["j_bar_m2"]  # the speed limit keeps it from catching up


def test_a_runs_draws_do_not_depend_on_its_block():
    from bauv_sim.kinematic.seed004 import PathNoise, Seed004Noise
    from bauv_sim.rng import generator

    noise = Seed004Noise()
    block = PathNoise(noise, 7, 4, 3, (5, 9, 2))
    alone = PathNoise(noise, 7, 4, 3, (9,))
    np.testing.assert_array_equal(block.w[1], alone.w[0])
    np.testing.assert_array_equal(block.eps[1], alone.eps[0])
    w = generator(3, 2, "seed004", "w").standard_normal((7, 3))
    np.testing.assert_array_equal(block.w[2], w)


@pytest.mark.slow
def test_row2_seabed_prediction_runs_for_both_readings_and_reports_the_shift_error(tmp_path):
    out = tmp_path / "row2"
    over = [
        "path.duration_s=15.0",
        "filters.train_paths=30",
        "runner.block_size=6",
        "report.figures=false",
    ]
    run("paper-004/table-1-seabed", n_runs=6, seed=0, out_dir=out, overrides=over, progress=False)
    m = _metrics(out)
    assert [c["prediction"] for c in m["cases"]] == ["seabed-one_attitude", "seabed-turning"]
    for c in m["cases"]:
        cmnf = next(f for f in c["filters"] if f["filter"] == "CMNF")
        assert cmnf["j_bar_m2"] is not None and math.isfinite(cmnf["j_bar_m2"])
        assert cmnf["paper_m2"] == 27.25
        assert m["claims"][f"{c['label']}: CMNF J-bar finite"]
        for e in c["shift_error"]:
            assert e["shifts"] + e["not_produced"] == 6 * 15 and 0 < e["median_m"] <= e["p90_m"]
            assert len(e["bias_m"]) == 3
    text = (out / "tables.md").read_text()
    assert "Table 1, row 2" in text and "shift estimate" in text and "nan" not in text.lower()


def test_training_seabeds_are_not_the_test_seabeds():
    from bauv_sim.sensors.multibeam import HarmonicSeabed
    from tasks.paper004.seabed import TRAIN_RUN_OFFSET

    test = HarmonicSeabed.draw(0, (0, 1))
    train = HarmonicSeabed.draw(0, (TRAIN_RUN_OFFSET, TRAIN_RUN_OFFSET + 1))
    assert not np.allclose(test.a, train.a)


def test_row2_seabed_out_of_range_degrades_with_warnings_and_no_nan(tmp_path):
    """The seed's seabed lies ~20-35 m below the path: a 25 m multibeam range loses the far
    beams (fewer beams per shift, a warning), a 5 m range loses them all (no shift is produced,
    the commanded displacement stands in, a warning); nothing is NaN and the CMNF stays finite."""
    over = [
        "path.duration_s=10.0",
        "filters.train_paths=30",
        "runner.block_size=6",
        "report.figures=false",
        "sweep.prediction=['seabed-one_attitude']",
    ]
    beams = {}
    for rng_m in (25.0, 5.0):
        out = tmp_path / f"r{rng_m:g}"
        run(
            "paper-004/table-1-seabed",
            n_runs=6,
            seed=0,
            out_dir=out,
            overrides=[*over, f"multibeam.max_range_m={rng_m}"],
            progress=False,
        )
        m = _metrics(out)
        text = (out / "metrics.json").read_text() + (out / "tables.md").read_text()
        assert "nan" not in text.lower()
        (c,) = m["cases"]
        cmnf = next(f for f in c["filters"] if f["filter"] == "CMNF")
        assert cmnf["j_bar_m2"] is not None and math.isfinite(cmnf["j_bar_m2"])
        e = next(e for e in c["shift_error"] if e["filter"] == "CMNF")
        beams[rng_m] = e["beams_mean"]
        assert any("beams per shift had an echo" in w for w in m["warnings"]), m["warnings"]
        if rng_m == 5.0:
            assert e["shifts"] == 0 and e["not_produced"] == 6 * 10 and e["median_m"] is None
            assert any("seabed shifts not produced" in w for w in m["warnings"])
    assert 0 == beams[5.0] < beams[25.0] < 0.9 * 64


@pytest.mark.slow
def test_row2_same_numbers_whatever_the_worker_count(tmp_path):
    # row 2 (ray casting, seabed shifts, the CMNF trained with them): a block's numbers come
    # from its runs' streams alone, not from the worker that flies it
    over = [
        "path.duration_s=8.0",
        "filters.train_paths=20",
        "runner.block_size=4",
        "report.figures=false",
    ]
    outs = []
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        run(
            "paper-004/table-1-seabed",
            n_runs=12,
            seed=5,
            out_dir=out,
            overrides=over,
            workers=workers,
            progress=False,
        )
        outs.append((out / "metrics.json").read_text())
    assert outs[0] == outs[1]
