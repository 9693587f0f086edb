"""``trn/relief``: the kinematic truth and the DVL dead reckoning against worked values, the
registered experiment end to end (metrics, tables, figures, no NaN), TRN error against relief
and against the PCRB within Monte Carlo tolerance, 1 vs 2 workers bit for bit, bad input."""

import json
import math

import numpy as np
import pytest

from bauv_sim.config import load_config
from bauv_sim.rng import generator
from tasks.core.runner import run
from tasks.trn.run import METHODS, lawnmower_truth, run_block
from tasks.trn.scenario import DEFAULT_RELIEF_M, TrnReliefScenario
from tests.tasks.refusal import assert_refused

FAST = [
    "track.duration_s=60",
    "filters.particles=400",
    "filters.grid_points=24",
    "sweep.relief_std_m=[0.5, 2.0]",
    "sweep.map_sigma_m=[0.1]",
]


def _no_nan(text: str) -> dict:
    def refuse(c):
        raise AssertionError(f"{c} in metrics.json")

    return json.loads(text, parse_constant=refuse)


def test_lawnmower_truth_flies_the_legs_at_constant_speed_and_depth():
    scn = load_config(TrnReliefScenario, overrides=["track.duration_s=500"])
    t = scn.track
    truth = lawnmower_truth(t, 0.2, seed=3, run=5)
    pos, v = truth.pos_world_m[0], truth.vel_ground_world_m_s[0]
    assert np.allclose(pos[:, 2], -t.depth_m)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), t.speed_m_s, rtol=1e-12)
    g = generator(3, 5, "trn", "track")
    start = g.uniform(-t.start_box_m, t.start_box_m, 2)
    h0 = g.uniform(0.0, 2.0 * np.pi)
    np.testing.assert_allclose(pos[0, :2], start)
    # the first leg along h0: its last sample before the corner (at the corner's sample the
    # heading is the next leg's, and the step into it is the trapezoid's average)
    k_end = round(t.leg_m / t.speed_m_s / 0.2)
    along = np.array([math.sin(h0), math.cos(h0)])
    step = t.speed_m_s * 0.2
    np.testing.assert_allclose(pos[k_end - 1, :2], start + (t.leg_m - step) * along, atol=1e-9)
    # then spacing_m at 90 deg to the right, then back along h0 + 180 deg
    k_gap = round((t.leg_m + t.spacing_m) / t.speed_m_s / 0.2)
    right = np.array([math.cos(h0), -math.sin(h0)])
    # a turn takes one sample period: each corner is cut by dt v / sqrt(2)
    corner = start + t.leg_m * along + t.spacing_m * right
    assert np.linalg.norm(pos[k_gap, :2] - corner) < 2 * step / math.sqrt(2) + 1e-9
    k_back = round((2 * t.leg_m + t.spacing_m) / t.speed_m_s / 0.2)
    back = np.linalg.norm(pos[k_back, :2] - (start + t.spacing_m * right))
    assert back < 3 * step / math.sqrt(2) + 1e-9
    assert np.allclose(np.diff(truth.t_s), 0.2)


def test_noise_free_dvl_dead_reckoning_keeps_exactly_the_initial_error(tmp_path):
    """Without beam, range and heading noise, DR on the DVL over the seabed is the truth shifted
    by the start's error: its error at the end is that error's norm (drawn here from the run's
    own stream)."""
    quiet = [
        "sensors.dvl.beam.sigma_m_s=0",
        "sensors.dvl.range.sigma_m=0",
        "sensors.compass.heading.sigma_deg=0",
    ]
    run(
        "trn/relief",
        n_runs=1,
        seed=4,
        out_dir=tmp_path / "run",
        overrides=[*FAST, *quiet, "report.figures=false"],
        progress=False,
    )
    m = _no_nan((tmp_path / "run" / "metrics.json").read_text())
    sigma = load_config(TrnReliefScenario).filters.initial_sigma_m
    e0 = float(np.hypot(*(sigma * generator(4, 0, "trn", "initial").standard_normal(2))))
    for s in m["settings"]:
        dr = s["methods"]["DR-DVL"]
        for key in ("final_mean_m", "mean_m", "rmse_m"):
            assert dr[key] == pytest.approx(e0, abs=1e-6), (key, dr[key], e0)


@pytest.mark.slow
def test_a_small_batch_writes_metrics_tables_and_figures_without_nan(tmp_path):
    out, summary = run(
        "trn/relief", n_runs=2, seed=1, out_dir=tmp_path / "run", overrides=FAST, progress=False
    )
    m = _no_nan((out / "metrics.json").read_text())
    assert m["experiment"] == "trn/relief" and m["n_runs"] == 2
    assert [(s["relief_std_m"], s["map_sigma_m"]) for s in m["settings"]] == [
        (0.5, 0.1),
        (2.0, 0.1),
    ]
    for s in m["settings"]:
        assert set(s["methods"]) == set(METHODS)
        for stats in s["methods"].values():
            assert stats["runs"] == 2
            assert all(math.isfinite(v) for v in stats.values())
        assert 0 < s["pcrb_rms_m"] < 30 and 0 < s["pcrb_final_m"] < 30
        # marginalising a per-ping bias only removes information
        assert s["pcrb_bias_rms_m"] >= s["pcrb_rms_m"]
        assert s["pcrb_bias_final_m"] >= s["pcrb_final_m"]
    for name in ("tables.md", "trn-relief.png", "trn-relief.pdf", "trn-error-time.png"):
        assert (out / name).is_file(), name
    assert "nan" not in (out / "tables.md").read_text().lower()
    # the whole table in the file; the terminal's copy narrowed (headers wrapped, tests/tasks/
    # test_console.py)
    assert "| DR-DVL final (m) |" in (out / "tables.md").read_text() and "DR-DVL" in summary.text


# ---------------------------------------------------------------------------------------------
# TRN error against relief, and against the PCRB (one batch of runs over the default reliefs)

N_TREND = 8


@pytest.fixture(scope="module")
def trend():
    """Every default relief, one map error, ``N_TREND`` runs of 150 s."""
    scn = load_config(
        TrnReliefScenario,
        overrides=[
            "track.duration_s=150",
            "filters.particles=1000",
            "filters.grid_points=32",
            "sweep.map_sigma_m=[0.1]",
        ],
    )
    assert scn.sweep.relief_std_m == list(DEFAULT_RELIEF_M)
    return run_block(scn, 7, tuple(range(N_TREND)))


@pytest.mark.slow
@pytest.mark.parametrize("method", ["TRN-PF", "TRN-PMF"])
def test_trn_error_falls_as_the_relief_grows(trend, method):
    """Each run's mean error over the updates, paired over the runs (same tracks, wave shapes
    and noise at every relief): no step up beyond 2 standard errors of the paired difference
    from one relief to the next, and 0.25 m of relief clearly worse than 2 m."""
    k = METHODS.index(method)
    err = trend["mean_m"][:, :, k]  # (runs, reliefs)
    assert np.isfinite(err).all()
    mean = err.mean(axis=0)
    for i in range(len(DEFAULT_RELIEF_M) - 1):
        d = err[:, i + 1] - err[:, i]
        se = d.std(ddof=1) / np.sqrt(len(d))
        assert d.mean() <= 2 * se, (method, DEFAULT_RELIEF_M[i : i + 2], mean)
    d = err[:, 0] - err[:, DEFAULT_RELIEF_M.index(2.0)]
    assert d.mean() > 2 * d.std(ddof=1) / np.sqrt(len(d)), (method, mean)
    # and TRN beats DR on the DVL from 0.5 m of relief up
    dr = trend["mean_m"][:, :, 0].mean(axis=0)
    assert np.all(mean[1:] < dr[1:]), (mean, dr)


@pytest.mark.parametrize("method", ["TRN-PF", "TRN-PMF"])
def test_filters_are_not_below_the_pcrb(trend, method):
    """The PCRB bounds any estimator's MSE: over the runs and updates, each filter's RMSE is at
    least the bound's RMS level, less 3 standard errors (over the runs)."""
    k = METHODS.index(method)
    n = N_TREND
    for s in range(len(DEFAULT_RELIEF_M)):
        sq = trend["rms_m"][:, s, k] ** 2  # each run's mean squared error over the updates
        rmse = float(np.sqrt(sq.mean()))
        se = float(sq.std(ddof=1) / np.sqrt(n)) / (2 * rmse)
        bound = float(np.sqrt(trend["pcrb_sum"][s, 0, 1:].mean() / n))
        assert rmse + 3 * se >= bound, (method, DEFAULT_RELIEF_M[s], rmse, se, bound)
        # and the bound is informative: below the initial spread's RMS
        assert bound < load_config(TrnReliefScenario).filters.initial_sigma_m * math.sqrt(2)


# ---------------------------------------------------------------------------------------------
# The runner: same seed, same numbers whatever the worker count; bad input


@pytest.mark.slow
def test_one_and_two_workers_give_the_same_bytes(tmp_path):
    args = dict(n_runs=4, seed=9, overrides=[*FAST, "report.figures=false", "runner.block_size=1"])
    one, _ = run("trn/relief", out_dir=tmp_path / "one", progress=False, **args)
    two, _ = run("trn/relief", out_dir=tmp_path / "two", workers=2, progress=False, **args)
    assert (one / "metrics.json").read_bytes() == (two / "metrics.json").read_bytes()
    for a in sorted((one / "blocks").glob("block-*.sha256")):
        assert a.read_text() == (two / "blocks" / a.name).read_text()


@pytest.mark.slow
@pytest.mark.parametrize(
    ("setting", "pattern"),
    [
        ("sweep.relief_std_m=[0.5, -1.0]", "sweep.relief_std_m = [0.5, -1.0]"),
        ("sweep.map_sigma_m=[0.1, 0.1]", "sweep.map_sigma_m"),
        ("map.cell_m=2", "map.cell_m = 2.0: finer than terrain.cell_m"),
        ("track.depth_m=39", "outside the DVL's bottom lock"),
        ("terrain.half_extent_m=300", "terrain.half_extent_m = 300.0"),
        ("filters.particles=5", "filters.particles"),
        ("track.speed_m_s=nan", "track.speed_m_s"),
        ("track.duration_s=0.5", "fewer than one TRN update"),
    ],
)
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, setting, pattern):
    assert_refused(tmp_path, "trn/relief", "--set", setting, pattern=pattern)


def test_a_method_with_no_finite_run_says_no_data():
    """Estimates that ran away to infinity leave the statistics; with none left the metrics hold
    None (a dash in the table, a "no data" warning), never NaN."""
    from tasks.trn.report import TrnReliefMetrics, method_stats, tables, warnings_of

    bad = np.array([np.inf, np.nan])
    empty = method_stats(bad, bad, bad)
    assert empty.runs == 0 and empty.final_mean_m is None and empty.rmse_m is None
    half = method_stats(np.array([1.0, np.inf]), np.array([2.0, 1.0]), np.array([2.0, 1.0]))
    assert half.runs == 1 and half.final_mean_m == 1.0 and half.final_se_m == 0.0
    ok = method_stats(np.array([1.0, 3.0]), np.array([1.0, 1.0]), np.array([1.0, 1.0]))
    setting = {
        "relief_std_m": 1.0,
        "map_sigma_m": 0.1,
        "methods": {"DR-DVL": ok, "TRN-PF": empty, "TRN-PMF": half},
        "pcrb_rms_m": 0.5,
        "pcrb_final_m": 0.4,
        "pcrb_bias_rms_m": 0.6,
        "pcrb_bias_final_m": 0.5,
        "no_lock_pings": 0,
        "updates_without_soundings": 0,
        "reinitialisations": {"TRN-PF": 0, "TRN-PMF": 0},
        "diverged_updates": {"TRN-PF": 0, "TRN-PMF": 0},
        "non_finite_runs": {"DR-DVL": 0, "TRN-PF": 2, "TRN-PMF": 1},
    }
    m = TrnReliefMetrics(
        experiment="trn/relief",
        n_runs=2,
        seed=0,
        duration_s=60.0,
        update_period_s=1.0,
        map_cell_m=10.0,
        map_offset_m=0.5,
        settings=[setting],
        warnings=[],
    )
    w = warnings_of(m)
    assert any("TRN-PF: no data" in line for line in w), w
    assert any("TRN-PMF: 1 run with a non-finite error" in line for line in w), w
    _no_nan(m.model_dump_json())
    row = tables(m)[0].cells()[0]
    assert row[5:8] == ["-", "-", "-"] and "nan" not in " ".join(row).lower(), row


def test_lost_beams_and_bottom_lock_degrade_without_nan(tmp_path):
    """Beams lost at random (range dropouts): pings with fewer than three echoes have no bottom
    lock (water track carries the DR) but their echoes still sound the seabed, pings with no
    echo give the filters nothing (a prediction only); the report counts both and writes no
    NaN."""
    out, summary = run(
        "trn/relief",
        n_runs=1,
        seed=2,
        out_dir=tmp_path / "run",
        overrides=[*FAST, "sensors.dvl.range.dropout_probability=0.7", "report.figures=false"],
        progress=False,
    )
    m = _no_nan((out / "metrics.json").read_text())
    for s in m["settings"]:
        # P(fewer than 3 of 4 beams) = 1 - 0.3^4 - 4 0.3^3 0.7 = 0.92; P(no beam) = 0.7^4 = 0.24
        pings = 60 / 0.2
        assert 0.85 * pings < s["no_lock_pings"] < pings
        assert 0 < s["updates_without_soundings"] < 0.5 * 60
        assert all(v["runs"] == 1 for v in s["methods"].values())
    assert any("without bottom lock" in w for w in m["warnings"])
    assert any("had no sounding" in w for w in m["warnings"])
    assert "warning:" in summary.text
