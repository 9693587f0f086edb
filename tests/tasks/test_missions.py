"""Closed-loop missions: contracts over every registered mission, sensors in the physics loop,
recording read-back, robustness and failure reporting."""

import json
import math

import numpy as np
import pytest

from bauv_sim.frames import R_from_quat_wxyz
from tasks.closed_loop import mission as cl
from tasks.core import registry
from tasks.core.recording import read_time_series
from tasks.core.runner import plan_batch, run

MISSIONS = [n for n in registry.names() if n.startswith("mission/")]
SHORT = "mission/short"


def scenario(name, *overrides):
    return plan_batch(name, overrides=list(overrides)).scenario


@pytest.fixture(scope="module")
def short_run():
    return cl.run_mission(scenario(SHORT), 0, 0)


# ---------------------------------------------------------------------------------------------
# contracts over every registered mission


@pytest.mark.parametrize("name", MISSIONS)
def test_mission_contract(name):
    exp = registry.get(name)

    def flight(seed, run):
        return exp.flight_scenario(scenario(name, "timing.max_duration_s=20"), seed, run)

    scn = flight(0, 0)
    env = cl.make_environment(scn, 0, 0, exp.task_type)
    ts = env.reset()
    pilot = cl.Pilot(
        scn.autopilot, env.task.speed_table, scn.timing.control_tick_s, env.action_spec()
    )
    steps = 0
    while not ts.last():
        for key, value in ts.observation.items():
            assert np.all(np.isfinite(value)), (name, key, value)
        action = pilot(ts.observation)
        assert env.action_spec().minimum.shape == action.shape
        assert np.all(action >= env.action_spec().minimum - 1e-12)
        assert np.all(action <= env.action_spec().maximum + 1e-12)
        ts = env.step(action)
        steps += 1
    assert steps == round(20 / scn.timing.control_tick_s)
    a = cl.run_mission(scn, 0, 0, task_type=exp.task_type)
    b = cl.run_mission(flight(0, 0), 0, 0, task_type=exp.task_type)
    c = cl.run_mission(flight(1, 0), 1, 0, task_type=exp.task_type)
    assert a.failed is None and b.failed is None and c.failed is None
    for key in ("truth", "ekf", "dr", "heading_meas", "P"):
        assert np.array_equal(a.arrays[key], b.arrays[key]), key  # same seed: bit for bit
    assert a.summary == b.summary
    state0 = [np.r_[r.arrays["truth"][0], r.arrays["quat"][0]] for r in (a, c)]
    assert not np.array_equal(*state0)  # initial state (position and attitude)
    assert not np.array_equal(a.arrays["heading_meas"], c.arrays["heading_meas"])  # noise


# ---------------------------------------------------------------------------------------------
# sensors sampled from the physics


def test_compass_and_pressure_errors_have_their_configured_statistics(short_run):
    a = short_run.arrays
    e = np.degrees(np.angle(np.exp(1j * (a["heading_meas"] - a["rph"][:, 2]))))
    n = e.size
    assert abs(e.mean()) < 5 * 2.0 / math.sqrt(n)
    assert e.std() == pytest.approx(2.0, rel=5 * math.sqrt(1 / (2 * n)))
    k = np.arange(len(a["t"])) % 5 == 0  # the pressure sensor samples every 1 s (5 ticks)
    d = a["depth_meas"][k] + a["truth"][k, 2]
    assert abs(d.mean()) < 5 * 0.05 / math.sqrt(d.size)
    assert d.std() == pytest.approx(0.05, rel=5 * math.sqrt(1 / (2 * d.size)))


def test_log_reads_speed_through_water_not_over_ground():
    # current from astern on the first leg (course about north): over ground is faster
    scn = scenario(
        SHORT, "current.direction_deg=0", "current.speed_m_s=0.3", "timing.max_duration_s=60"
    )
    a = cl.run_mission(scn, 0, 0).arrays
    k = (np.arange(len(a["t"])) % 5 == 0) & a["speed_from_log"] & (a["t"] > 10)
    h, p = a["rph"][k, 2], a["rph"][k, 1]
    x_axis = np.column_stack([np.cos(p) * np.sin(h), np.cos(p) * np.cos(h), np.sin(p)])
    stw = np.einsum("ij,ij->i", a["vel_water"][k], x_axis)
    sog = np.einsum("ij,ij->i", a["vel"][k], x_axis)
    err_stw = a["speed_meas"][k] - 1.01 * stw  # 1 % scale factor configured
    err_sog = a["speed_meas"][k] - sog
    assert abs(err_stw.mean()) < 5 * 0.05 / math.sqrt(k.sum())
    assert err_stw.std() == pytest.approx(0.05, rel=0.35)
    assert err_sog.mean() == pytest.approx(-0.3, abs=0.05)  # the current the log cannot see


def test_gps_only_with_the_antenna_out_of_the_water():
    scn = scenario(
        SHORT, "guidance.waypoints.0.surface=true", "guidance.hold_s=5", "guidance.fixes_needed=2"
    )
    run = cl.run_mission(scn, 0, 0)
    a = run.arrays
    env = cl.make_environment(scn, 0, 0)
    env.reset()
    arm = np.array(env.task.sensors_cfg.gps.antenna_body_m)
    antenna_z = a["truth"][:, 2] + np.einsum("ij,j->i", R_from_quat_wxyz(a["quat"])[:, 2], arm)
    gps = [f for f in run.fixes if f["kind"] == "gps"]
    assert len(gps) >= 2
    ticks = {round(t, 6): i for i, t in enumerate(a["t"])}
    for f in gps:
        assert antenna_z[ticks[round(f["t_valid_s"], 6)]] > 0.0
    deep = a["truth"][:, 2] < -0.5
    assert deep.sum() > 100 and not a["gps_event"][deep].any()
    assert run.waypoints[0]["reached_by_estimate"] and run.summary["completed"] == 1.0


def test_usbl_stops_beyond_its_range():
    scn = scenario(
        SHORT,
        "sensors.usbl.max_range_m=40",
        "sensors.usbl.period_s=1.0",
        "sensors.usbl.processing_delay_s=0.0",
    )
    run = cl.run_mission(scn, 0, 0)
    a = run.arrays
    env = cl.make_environment(scn, 0, 0)
    env.reset()
    tx = env.task.transceiver
    rng = np.linalg.norm(a["truth"] - tx, axis=1)
    ticks = {round(t, 6): i for i, t in enumerate(a["t"])}
    usbl = [f for f in run.fixes if f["kind"] == "usbl"]
    assert usbl
    for f in usbl:
        assert rng[ticks[round(f["t_valid_s"], 6)]] <= 40.0 + 0.5  # transponder lever arm
    scheduled = np.arange(len(a["t"])) % 5 == 0
    assert (rng[scheduled] > 41.0).sum() > 10  # many scheduled moments were out of range


# ---------------------------------------------------------------------------------------------
# recording, robustness, failures


def test_recording_holds_the_physics_trajectory_and_the_estimates(short_run, tmp_path):
    scn = scenario(SHORT)
    rec = tmp_path / cl.record_mission(SHORT, scn, short_run, tmp_path)
    a = short_run.arrays
    t, truth = read_time_series(rec, "world/truth/position", "Points3D:positions")
    assert np.allclose(t, a["t"]) and np.allclose(truth, a["truth"], atol=1e-4)
    _, ekf = read_time_series(rec, "world/ekf/position", "Points3D:positions")
    assert np.allclose(ekf, a["ekf"], atol=1e-4)
    _, trans = read_time_series(rec, "world/vehicle", "Transform3D:translation")
    assert np.allclose(trans, a["truth"], atol=1e-4)
    _, quat = read_time_series(rec, "world/vehicle", "Transform3D:quaternion")
    assert np.allclose(
        np.abs(np.einsum("ij,ij->i", quat, a["quat"][:, [1, 2, 3, 0]])), 1.0, atol=1e-5
    )
    _, half = read_time_series(rec, "world/ekf/covariance", "Ellipsoids3D:half_sizes")
    assert len(half) > 50 and np.all(half > 0)


def test_gate_keeps_the_mission_on_track_with_usbl_outliers():
    bad = [
        "sensors.usbl.period_s=1.0",
        "sensors.usbl.range.outlier_probability=0.1",
        "sensors.usbl.range.outlier_sigma_m=40",
    ]
    gated = cl.run_mission(scenario(SHORT, *bad), 3, 0)
    ungated = cl.run_mission(scenario(SHORT, *bad, "navigation.gate_enabled=false"), 3, 0)
    assert gated.summary["usbl_rejected"] >= 5
    assert ungated.summary["usbl_rejected"] == 0
    assert gated.summary["ekf_max_error_m"] < 5.0
    assert ungated.summary["ekf_max_error_m"] > 2 * gated.summary["ekf_max_error_m"]


def test_a_diverging_run_is_reported_and_the_batch_completes(tmp_path):
    out = tmp_path / "batch"
    run(
        SHORT,
        n_runs=2,
        seed=4,
        out_dir=out,
        progress=False,
        overrides=[
            "timing.max_duration_s=20",
            "faults.physics_nan_at_s=5",
            "faults.physics_nan_runs=[1]",
            "report.figures=false",
            "report.recording=false",
        ],
    )
    m = json.loads((out / "metrics.json").read_text())
    assert m["n_failed"] == 1 and m["runs"][0]["failed"] is None
    msg = m["runs"][1]["failed"]
    assert "run 1 (seed 4)" in msg and "t = 5.2" in msg and "PhysicsError" in msg


def test_mission_navigator_is_not_overconfident():
    """The EKF's horizontal NEES averaged over runs and time stays near its dimension (2). Time
    samples are correlated, so this is a loose band rather than a chi-square test; it failed (4.0)
    while the USBL transponder's lever arm was missing from the measurement model."""
    nees = []
    for run_index in range(4):
        a = cl.run_mission(scenario(SHORT), 5, run_index).arrays
        e = (a["ekf"] - a["truth"])[:, :2]
        P = a["P"][:, :2, :2]
        late = a["t"] > 20.0
        nees.append(np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])[late])
    mean = float(np.mean(np.concatenate(nees)))
    assert 0.8 < mean < 3.0, mean


def test_correction_mission_corrects_dr_and_the_course(tmp_path):
    """Seed 001 on the physical vehicle, one run (both flights): CP2 from two surfacings makes
    leg 3's DR several times better and the compensated course stays on the desired course."""
    out = tmp_path / "corr"
    run(
        "mission/correction",
        n_runs=1,
        seed=0,
        out_dir=out,
        progress=False,
        overrides=["report.recording=false", "report.figures=false"],
    )
    m = json.loads((out / "metrics.json").read_text())
    r = m["runs"][0]
    assert r["failed"] is None and r["correction_error"] is None
    comp, direct = r["compensated"], r["direct"]
    assert comp["uncorrected_mean_error_m"] > 3 * comp["corrected_mean_error_m"]
    assert comp["course_deviation_deg"] < 0.5 * direct["course_deviation_deg"]
    assert comp["current_error_m_s"] < 0.05  # uniform 0.3 m/s current
    assert m["improvement_factor"] == pytest.approx(
        comp["uncorrected_mean_error_m"] / comp["corrected_mean_error_m"]
    )
