"""``fleet/survey``: the batch's runs are independent of their block, the command's outputs,
and bad values refused (issue 27, check 2)."""

import numpy as np
import pytest

from bauv_sim.config import load_config
from tasks.core.export import read_parquet
from tasks.fleet.run import OUTCOMES, fly_block
from tasks.fleet.scenario import FleetScenario
from tests.tasks.refusal import assert_refused, run_in_process

SHORT = ["timing.max_duration_s=150", "plan.lanes=2", "plan.lane_length_m=40"]


def _scn(*extra):
    return load_config(FleetScenario, {}, (), [*SHORT, *extra])


@pytest.mark.slow
def test_a_batch_of_n_equals_n_batches_of_one():
    scn = _scn()
    runs = (0, 5, 9)
    together = fly_block(scn, 7, runs)
    for j, r in enumerate(runs):
        alone = fly_block(scn, 7, (r,))
        for k in OUTCOMES:
            a, b = together.outcomes[k][j], alone.outcomes[k][0]
            assert a == pytest.approx(b, rel=1e-9, abs=1e-9), k
        for k, v in together.tracks.items():
            np.testing.assert_allclose(v[:, j], alone.tracks[k][:, 0], rtol=1e-9, atol=1e-9)
        assert np.array_equal(together.reached[j], alone.reached[0])
    # the runs differ (their own streams) and the short plan was flown to its end
    assert len(set(together.outcomes["ekf_mean_error_m"])) == 3
    assert together.outcomes["completed"].all()


def _values(path):
    return {k: c.values for k, c in read_parquet(path)[0].items()}


@pytest.mark.slow
def test_the_command_writes_its_run_data_the_same_for_any_worker_count(tmp_path, capsys):
    sets = [a for s in [*SHORT, "runner.block_size=2"] for a in ("--set", s)]
    tables = {}
    for w in (1, 2):
        out = tmp_path / f"w{w}"
        code, err = run_in_process(
            capsys, "run", "fleet/survey", "--runs", "5", "--workers", str(w), "--quiet",
            "--out", str(out), *sets,
        )  # fmt: skip
        assert code == 0, err
        runs = _values(out / "data" / "runs" / "runs.parquet")
        wps = _values(out / "data" / "waypoints" / "waypoints.parquet")
        tracks = [_values(out / "data" / "tracks" / f"block-{b:06d}.parquet") for b in range(3)]
        tables[w] = (runs, wps, tracks)
        assert (out / "metrics.json").is_file() and (out / "tables.md").is_file()
    (r1, w1, t1), (r2, w2, t2) = tables[1], tables[2]
    assert list(r1) == ["run", *OUTCOMES]
    assert np.array_equal(r1["run"], np.arange(5))
    for k in r1:
        assert np.array_equal(r1[k], r2[k]), k
    for k in w1:
        assert np.array_equal(w1[k], w2[k], equal_nan=True), k
    for a, b in zip(t1, t2, strict=True):
        for k in a:
            assert np.array_equal(a[k], b[k]), k
    assert len(w1["run"]) == 5 * 3  # 3 way-points of the 2-lane plan
    assert np.isfinite(r1["ekf_mean_error_m"]).all()


@pytest.mark.slow
@pytest.mark.parametrize(
    "arg, pattern",
    [
        ("plan.lanes=0", "plan.lanes"),
        ("current.kind=randomised", "current.kind = 'randomised'"),
        ("sensors.usbl.processing_delay_s=6", "sensors.usbl.processing_delay_s = 6"),
        ("sensors.log.period_s=0.3", "sensors.log.period_s = 0.3"),
        ("timing.record_every_s=0.3", "timing.record_every_s = 0.3"),
        ("runner.block_size=0", "runner.block_size"),
    ],
)
def test_bad_values_are_refused(tmp_path, arg, pattern):
    assert_refused(tmp_path, "fleet/survey", "--set", arg, pattern=pattern)


def test_the_plan_is_a_lawn_mower_about_an_hour_long():
    scn = load_config(FleetScenario, {})
    wps = scn.waypoints()
    assert len(wps) == 2 * scn.plan.lanes - 1
    assert wps[0] == (150.0, -150.0) and wps[-1] == (150.0, 150.0)
    assert scn.plan_length_m() == pytest.approx(11 * 300 + 10 * 30)
