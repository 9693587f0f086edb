"""The mission recording read back: what a user needs to find a problem without code (issue 12).

Every value is checked against the run data it came from, recomputed here: the position NEES
from the EKF's estimate, covariance and truth; the events from the way-point index and the fix
tables; the accepted flag from the fix table.
"""

import numpy as np
import pytest

from tasks.closed_loop.report import record_mission
from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.recording import read_text_log, read_time_series
from tasks.core.runner import plan_batch

SCALARS = "Scalars:scalars"


def _record(name, tmp_path, seed=0, *overrides):
    scn = plan_batch(name, overrides=list(overrides)).scenario
    res = fly(WaypointMission(), scn, seed, 0)
    assert res.failed is None, res.failed
    return tmp_path / record_mission(name, scn, res, tmp_path), res.lead


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    return _record("mission/survey", tmp_path_factory.mktemp("survey"))


@pytest.mark.slow
def test_survey_recording_has_the_estimated_current_beside_the_true_one(survey):
    rec, a = survey
    every = max(1, round(1.0 / float(a["t"][1] - a["t"][0])))
    for comp, j in (("east", 0), ("north", 1)):
        t, est = read_time_series(rec, f"current/bauv/ekf_current_{comp}", SCALARS)
        assert np.allclose(t, a["t"][::every])
        assert np.allclose(est.ravel(), a["ekf_current"][::every, j])
        _, true = read_time_series(rec, f"current/bauv/true_{comp}", SCALARS)
        assert np.allclose(true.ravel(), a["truth_current"][::every, j])
    # the survey's EKF learns the 0.25 m/s current: at the end within 0.1 m/s of the truth
    assert np.hypot(*(a["ekf_current"][-1] - a["truth_current"][-1, :2])) < 0.1
    _, arrows = read_time_series(rec, "world/bauv/current/ekf_current", "Arrows3D:vectors")
    assert np.allclose(arrows[:, :2], 20.0 * a["ekf_current"][::every], atol=1e-5)


def test_survey_recording_has_the_position_nees_and_its_band(survey):
    rec, a = survey
    t, nees = read_time_series(rec, "consistency/bauv/ekf_nees", SCALARS)
    e = a["ekf_pos"] - a["truth_pos"]
    expected = np.array([ei @ np.linalg.inv(Pi) @ ei for ei, Pi in zip(e, a["ekf_P"], strict=True)])
    assert np.allclose(t, a["t"]) and np.allclose(nees.ravel(), expected, rtol=1e-9)
    _, lo = read_time_series(rec, "consistency/bauv/ekf_nees_band_low", SCALARS)
    _, hi = read_time_series(rec, "consistency/bauv/ekf_nees_band_high", SCALARS)
    # chi-square, 3 degrees of freedom, 2.5 % and 97.5 % quantiles
    assert lo.ravel()[0] == pytest.approx(0.2158, abs=1e-4)
    assert hi.ravel()[0] == pytest.approx(9.3484, abs=1e-4)
    _, nis = read_time_series(rec, "consistency/bauv/nis_usbl", SCALARS)
    fx = a.fixes["usbl"]
    assert np.allclose(nis.ravel(), fx["nis"].values[np.isfinite(fx["nis"].values)])


def test_survey_recording_has_the_accepted_flag_of_every_fix(survey):
    rec, a = survey
    fx = a.fixes["usbl"]
    t, flag = read_time_series(rec, "fixes/bauv/usbl_accepted", SCALARS)
    order = np.argsort(fx["t_arrival"].values, kind="stable")
    assert len(t) == len(fx["t_arrival"].values) > 100
    assert np.array_equal(flag.ravel(), fx["accepted"].values[order].astype(float))
    _, acc = read_time_series(rec, "world/bauv/usbl/accepted/latest", "Points3D:positions")
    assert len(acc) == int(fx["accepted"].values.sum())
    # innovation: the accepted fix minus the EKF's estimate at its time of validity
    _, inn = read_time_series(rec, "innovation/bauv/usbl_east", SCALARS)
    exp = fx["position"].values[:, 0] - np.interp(fx["t_valid"].values, a["t"], a["ekf_pos"][:, 0])
    assert np.allclose(inn.ravel(), exp[order])


def test_survey_recording_has_the_event_log(survey):
    rec, a = survey
    events = read_text_log(rec, "events/bauv")
    texts = [e[2] for e in events]
    assert texts[0].startswith("bauv: start") and texts[-1].startswith("bauv: end")
    reached = [e for e in events if "reached" in e[2]]
    wp = a["guidance_waypoint"]
    changes = np.flatnonzero(np.diff(wp) != 0) + 1
    assert len(reached) == len(changes) == len(a.waypoints)
    assert np.allclose([e[0] for e in reached], a["t"][changes])
    rejected = [e for e in events if "rejected" in e[2]]
    assert len(rejected) == int((~a.fixes["usbl"]["accepted"].values).sum())
    assert [e[0] for e in events] == sorted(e[0] for e in events)


@pytest.mark.slow
def test_gate_rejections_are_events_and_rejected_fixes(tmp_path):
    bad = [
        "sensors.usbl.period_s=1.0",
        "sensors.usbl.range.outlier_probability=0.1",
        "sensors.usbl.range.outlier_sigma_m=40",
    ]
    rec, a = _record("mission/short", tmp_path, 3, *bad)
    ok = a.fixes["usbl"]["accepted"].values
    assert (~ok).sum() >= 5
    events = read_text_log(rec, "events/bauv")
    rej = [e for e in events if "rejected" in e[2]]
    assert len(rej) == (~ok).sum() and all(e[1] == "WARN" for e in rej)
    _, pos = read_time_series(rec, "world/bauv/usbl/rejected/latest", "Points3D:positions")
    assert len(pos) == (~ok).sum()


@pytest.mark.slow
def test_fins_and_tail_move_with_their_true_joint_angles(tmp_path):
    rec, a = _record("mission/short", tmp_path)
    for entity, col, j, axis in [
        ("world/bauv/body/fin_port", "truth_fin_angles", 0, (0, -1, 0)),
        ("world/bauv/body/peduncle", "truth_tail_angles", 0, (0, 0, 1)),
        ("world/bauv/body/peduncle/caudal_fin", "truth_tail_angles", 1, (0, 0, 1)),
    ]:
        _, q = read_time_series(rec, entity, "Transform3D:quaternion")
        angle = a[col][:, j]
        assert np.ptp(angle) > 0.05, entity  # it moves
        # quaternion xyzw of a rotation by `angle` about `axis`
        exp = np.column_stack([np.sin(angle / 2)[:, None] * axis, np.cos(angle / 2)])
        assert np.allclose(q, exp, atol=1e-6), entity


@pytest.mark.slow
def test_heading_is_recorded_unwrapped(tmp_path):
    rec, a = _record("mission/short", tmp_path)
    _, h = read_time_series(rec, "heading/bauv/true", SCALARS)
    step = np.abs(np.diff(h.ravel()))
    assert step.max() < 30.0  # no 360 deg jump
    assert np.allclose(np.mod(h.ravel(), 360.0), np.mod(np.degrees(a["truth_rph"][:, 2]), 360.0))


def test_passage_recording_splits_fixes_and_logs_rejections(tmp_path):
    from tasks.core.registry import get
    from tasks.paper000 import passage as paper000

    # fixes beyond 150 m never come, and USBL range outliers a 99 % gate rejects
    overrides = [
        "sensors.usbl.max_range_m=150",
        "sensors.usbl.range.outlier_probability=0.2",
        "sensors.usbl.range.outlier_sigma_m=50",
        "filter.gate_probability=0.99",
    ]
    scn = plan_batch("paper-000/test-1", overrides=overrides).scenario
    rec = tmp_path / paper000.record_passage(get("paper-000/test-1"), scn, 0, 0, tmp_path)
    p = paper000.simulate_passages(scn, 0, (0,))
    ok, rej = p.usbl_produced[0], p.gate_rejected[0] & p.usbl_produced[0]
    assert (~ok).sum() > 0 and rej.sum() > 0
    _, flag = read_time_series(rec, "fixes/usbl_accepted", SCALARS)
    assert np.array_equal(flag.ravel(), (~rej[ok]).astype(float))
    _, pos = read_time_series(rec, "world/usbl/rejected/latest", "Points3D:positions")
    assert len(pos) == rej.sum()
    events = read_text_log(rec, "events")
    assert sum("rejected by the gate" in e[2] for e in events) == rej.sum()
    assert sum("no USBL fix" in e[2] for e in events) == (~ok).sum()
    closest = [e for e in events if "closest approach" in e[2]]
    assert closest and closest[0][0] == pytest.approx(scn.passage.closest_approach_time_s)


def _static_colour(path, entity, component):
    """The static colour of an entity in a recording, as (r, g, b)."""
    import rerun.chunk as rc

    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path == "/" + entity and chunk.is_static:
            rb = chunk.to_record_batch()
            if component in rb.schema.names:
                rgba = int(rb.column(component).to_pylist()[0][0])
                return (rgba >> 24) & 255, (rgba >> 16) & 255, (rgba >> 8) & 255
    raise KeyError(f"{entity}:{component} not in {path}")


@pytest.mark.slow
def test_paper003_recording_draws_each_method_in_its_figure_colour(tmp_path):
    # one style table (issue 22): the hex of the figures is the colour in rerun
    from tasks.core import style
    from tasks.core.runner import run

    out, _ = run(
        "paper-003/test-1",
        n_runs=1,
        seed=0,
        out_dir=tmp_path / "run",
        progress=False,
        overrides=["report.figures=false"],
    )
    rec = out / "recording.rrd"
    for method in ("DR", "GA1", "GA2", "EKF"):
        want = style.rgb(method)
        k = method.lower()
        assert _static_colour(rec, f"world/{k}/path", "LineStrips3D:colors") == want, method
        assert _static_colour(rec, f"distance/{k}", "SeriesLines:colors") == want, method


def _vehicle(pos, cov, truth):
    from tasks.closed_loop.result import EstimateTrack, VehicleRun
    from tasks.core.export import Column

    t = np.arange(len(truth), dtype=float)
    ticks = {
        "t": Column(t, "s", "time"),
        "truth_pos": Column(np.asarray(truth, float), "m", "truth", ("east", "north", "up")),
        "est": Column(np.asarray(pos, float), "m", "estimate", ("east", "north")),
        "est_P": Column(np.asarray(cov, float), "m^2", "covariance", ("east", "north")),
    }
    return VehicleRun("v", ticks, estimates=(EstimateTrack("est", "TRN-PF", "est_P"),))


def test_nees_of_a_horizontal_estimate_is_its_quadratic_form_and_singular_is_left_out():
    from tasks.closed_loop.recording_vehicle import estimate_covariance, estimate_positions, nees

    truth = [[0.0, 0.0, -5.0], [1.0, 1.0, -6.0], [0.0, 0.0, -7.0]]
    pos = [[1.0, 2.0], [1.0, 1.0], [3.0, 0.0]]
    cov = [np.diag([1.0, 4.0]), np.diag([2.0, 2.0]), np.zeros((2, 2))]
    v = _vehicle(pos, cov, truth)
    e = v.estimates[0]
    values, dof = nees(v, e)
    # e = (1, 2) with P = diag(1, 4): 1/1 + 4/4 = 2; e = 0: 0; singular P: left out (NaN)
    assert dof == 2 and values[0] == pytest.approx(2.0) and values[1] == 0.0
    assert np.isnan(values[2])
    # a horizontal estimate is drawn at the true depth, its covariance as a flat ellipse
    assert np.array_equal(estimate_positions(v, e)[:, 2], [-5.0, -6.0, -7.0])
    P3 = estimate_covariance(v, e)
    assert P3.shape == (3, 3, 3) and np.all(P3[:, 2, :] == 0) and np.all(P3[:, :2, :2] == cov)
    # a covariance stored flat, (T, 4), is the same matrices
    flat = _vehicle(pos, np.reshape(cov, (3, 4)), truth)
    assert np.array_equal(estimate_covariance(flat, flat.estimates[0]), P3)


def test_method_names_become_entity_path_parts():
    from tasks.closed_loop.recording_vehicle import slug

    assert [slug(m) for m in ("EKF", "TRN-PF", "team leader-ekf", "DR-log")] == [
        "ekf",
        "trn_pf",
        "team_leader_ekf",
        "dr_log",
    ]
