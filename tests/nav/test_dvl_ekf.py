"""The EKF with DVL updates (nav.dvl.DvlVelocityMeasurement) estimates a 0.3 m/s current
consistently (NEES in its chi-square band over many runs), batched and online with the same
numbers; and dead reckoning on DVL velocity beats dead reckoning on heading and log speed in that
current (issue 23, check 2, at the navigation level)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bauv_sim.frames import R_from_roll_pitch_heading as R_frames
from nav.dead_reckoning import dead_reckon
from nav.dvl import DvlVelocityMeasurement, dvl_track, velocity_world_from_dvl
from nav.ekf import BatchEKF, SingleRunEKF, update_with
from nav.metrics import nees, nees_band
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion, UsblMeasurement
from nav.navigator import Measurement, OnlineNavigator

DT = 0.2  # s, navigation tick = DVL ping
LEVER = np.array([0.8, -0.15, -0.25])  # m, body FLU
SIGMA_DVL = 0.01  # m/s per axis
SIGMA_HEADING = math.radians(1.0)
SIGMA_SPEED = 0.02  # m/s
CURRENT = 0.3  # m/s
USBL = UsblMeasurement(np.array([0.0, 0.0, 0.0]), 0.5, math.radians(1), math.radians(1))


def _matched_world(n, steps, seed):
    """A world matched to the filter's discrete-time model: the truth moves over each tick with
    the heading and speed through water of the tick's end plus a constant current; the sensors
    add white noise. Returns the truth and the measurements, leading axes (n, steps + 1)."""
    rng = np.random.default_rng(seed)
    t = DT * np.arange(steps + 1)
    psi0 = rng.uniform(0, 2 * np.pi, (n, 1))
    heading = psi0 + 0.8 * np.sin(2 * np.pi * t / 40.0)  # weaving, rad
    speed = 1.2 + 0.1 * np.sin(2 * np.pi * t / 25.0) + 0 * psi0  # horizontal, through water
    roll = 0.05 * np.sin(0.9 * t) + 0 * psi0
    pitch = 0.03 * np.cos(0.6 * t) + 0 * psi0
    att = np.stack([roll, pitch, heading], axis=-1)
    cdir = rng.uniform(0, 2 * np.pi, n)
    current = CURRENT * np.column_stack([np.sin(cdir), np.cos(cdir)])
    v_water = np.stack([speed * np.sin(heading), speed * np.cos(heading), 0 * speed], -1)
    v_ground = v_water + np.concatenate([current, np.zeros((n, 1))], -1)[:, None]
    pos = np.zeros((n, steps + 1, 3))
    pos[:, 0] = rng.normal(0.0, 2.0, (n, 3)) * [1, 1, 0.05] + [0, 0, -20.0]
    for k in range(1, steps + 1):
        pos[:, k] = pos[:, k - 1] + DT * v_ground[:, k]
    omega = np.stack(
        [0 * t + 0.01, 0 * t - 0.02, -0.8 * 2 * np.pi / 40 * np.cos(2 * np.pi * t / 40)], -1
    )
    omega = np.broadcast_to(omega, (n, steps + 1, 3))
    R = R_frames(roll, pitch, heading)
    v_dvl = np.einsum("nkji,nkj->nki", R, v_ground) + np.cross(omega, LEVER)
    meas = dict(
        heading=heading + SIGMA_HEADING * rng.standard_normal(heading.shape),
        speed=speed + SIGMA_SPEED * rng.standard_normal(speed.shape),
        dvl=v_dvl + SIGMA_DVL * rng.standard_normal(v_dvl.shape),
        usbl=USBL.h(pos) + rng.standard_normal(pos.shape) * [0.5, math.radians(1), math.radians(1)],
    )
    meas["att"] = np.stack([roll, pitch, meas["heading"]], -1)
    return dict(t=t, pos=pos, current=current, omega=omega, att=att), meas


MOTION = CurrentAwareMotion(CourseSpeedDepthMotion(SIGMA_HEADING, SIGMA_SPEED, 1e-3), 0.0)
P0 = np.diag([4.0, 4.0, 0.01, 0.3**2, 0.3**2])


def _dvl_model(meas, truth, rows, k, current_estimate):
    """The ping's model; the heading's noise term linearised about the current estimate."""
    return DvlVelocityMeasurement(
        meas["att"][rows, k],
        meas["speed"][rows, k],
        SIGMA_DVL,
        sigma_speed_m_s=SIGMA_SPEED,
        angular_velocity_body_rad_s=truth["omega"][rows, k],
        lever_arm_body_m=LEVER,
        sigma_heading_rad=SIGMA_HEADING,
        current_for_noise_m_s=current_estimate,
    )


def _x0(truth):
    n = truth["pos"].shape[0]
    return np.concatenate([np.broadcast_to([0.0, 0.0, -20.0], (n, 3)), np.zeros((n, 2))], -1)


def _batched(truth, meas, usbl_every):
    n, K = truth["pos"].shape[:2]
    rows = np.arange(n)
    x, P = _x0(truth), np.broadcast_to(P0, (n, 5, 5)).copy()
    ekf = BatchEKF(MOTION)
    for k in range(1, K):
        u = np.stack([meas["heading"][:, k], meas["speed"][:, k], np.zeros(n)], -1)
        x, P = ekf.predict(x, P, u, DT)
        x, P, _ = update_with(x, P, _dvl_model(meas, truth, rows, k, x[:, 3:]), meas["dvl"][:, k])
        if usbl_every and k % usbl_every == 0:
            x, P, _ = ekf.update(x, P, USBL, meas["usbl"][:, k])
    return x, P


def _online(truth, meas, run, usbl_every, late_every):
    """One run through OnlineNavigator: predict each tick, DVL pings fused with their own model
    (every late_every-th one a tick late, at its time of validity), USBL fixes."""
    nav = OnlineNavigator(
        SingleRunEKF(MOTION), 0.0, _x0(truth)[run], P0, MOTION.base, history_s=2.0
    )
    t = truth["t"]
    late = None
    for k in range(1, len(t)):
        nav.predict(t[k], meas["heading"][run, k], meas["speed"][run, k], 0.0)
        if late is not None:
            nav.fuse(late)
            late = None
        model = _dvl_model(meas, truth, run, k, nav.current_estimate[0])
        ping = Measurement(meas["dvl"][run, k], model, t[k])
        if late_every and k % late_every == 3:
            late = ping
        else:
            nav.fuse(ping)
        if usbl_every and k % usbl_every == 0:
            nav.fuse(Measurement(meas["usbl"][run, k], USBL, t[k]))
    assert late is None
    return nav


def test_dvl_updates_batched_and_online_give_the_same_numbers():
    truth, meas = _matched_world(3, 300, seed=11)
    x, P = _batched(truth, meas, usbl_every=75)
    for run in range(3):
        nav = _online(truth, meas, run, usbl_every=75, late_every=10)
        assert np.allclose(nav.estimate.x, x[run, :3], rtol=0, atol=1e-9)
        assert np.allclose(nav.estimate.P, P[run, :3, :3], rtol=0, atol=1e-12)
        c, C = nav.current_estimate
        assert np.allclose(c, x[run, 3:], atol=1e-11) and np.allclose(C, P[run, 3:, 3:], atol=1e-14)
        assert np.linalg.norm(c - truth["current"][run]) < 0.01  # near the true 0.3 m/s


@pytest.mark.slow
def test_dvl_updates_estimate_the_current_consistently():
    """200 runs of 90 s, DVL pings at 5 Hz and no position fix: the current converges to the
    true 0.3 m/s within its stated covariance (NEES of the current and of the whole state in
    the 99 % chi-square band of the average over the runs)."""
    n = 200
    truth, meas = _matched_world(n, 450, seed=12)
    x, P = _batched(truth, meas, usbl_every=0)
    err_c = x[:, 3:] - truth["current"]
    nees_c = nees(err_c, P[:, 3:, 3:])
    lo, hi = nees_band(2, n, 0.99)
    print(f"current NEES {nees_c.mean():.2f} in [{lo:.2f}, {hi:.2f}]")
    assert lo < nees_c.mean() < hi
    # converged: the stated sigma is a small fraction of the current, and so is the error
    sig = np.sqrt(np.diagonal(P[:, 3:, 3:], axis1=1, axis2=2))
    assert np.all(sig < 0.002)
    assert np.sqrt(np.mean(np.sum(err_c**2, -1))) < 0.003
    # the position (horizontal) with it, its drift now corrected by the current
    err = np.concatenate([x[:, :2] - truth["pos"][:, -1, :2], err_c], -1)
    idx = [0, 1, 3, 4]
    nees_all = nees(err, P[:, idx][:, :, idx])
    lo4, hi4 = nees_band(4, n, 0.99)
    print(f"horizontal position + current NEES {nees_all.mean():.2f} in [{lo4:.2f}, {hi4:.2f}]")
    assert lo4 < nees_all.mean() < hi4


def _survey(seed, duration_s=600.0):
    """A lawn-mower survey in a 0.3 m/s current, integrated on a 100 Hz grid: legs of 120 s,
    180-degree turns at 0.1 rad/s, trim pitch and roll, the DVL on its lever arm sampled at
    5 Hz; compass (1 deg), log (0.02 m/s), gyros (1 mrad/s) and DVL (0.01 m/s per axis) noisy."""
    rng = np.random.default_rng(seed)
    fine = 0.01
    tf = np.arange(0.0, duration_s + fine / 2, fine)
    leg, turn_rate = 120.0, 0.1
    turn_s = math.pi / turn_rate
    phase = tf % (leg + turn_s)
    sign = np.where((tf // (leg + turn_s)) % 2 == 0, 1.0, -1.0)
    rate = np.where(phase >= leg, sign * turn_rate, 0.0)  # heading rate, clockwise, rad/s
    psi0 = rng.uniform(0, 2 * np.pi)
    heading = psi0 + np.concatenate([[0.0], np.cumsum(0.5 * fine * (rate[1:] + rate[:-1]))])
    speed = 1.0
    cdir = rng.uniform(0, 2 * np.pi)
    c = CURRENT * np.array([math.sin(cdir), math.cos(cdir), 0.0])
    v_ground = np.stack([speed * np.sin(heading), speed * np.cos(heading), 0 * tf], -1) + c
    pos = np.concatenate(
        [np.zeros((1, 3)), np.cumsum(0.5 * fine * (v_ground[1:] + v_ground[:-1]), axis=0)]
    )
    roll, pitch = 0.03, -0.04
    every = round(DT / fine)
    i = np.arange(0, len(tf), every)
    t = tf[i]
    att = np.column_stack([np.full(len(i), roll), np.full(len(i), pitch), heading[i]])
    R = R_frames(att[:, 0], att[:, 1], att[:, 2])
    omega = np.einsum("kji,j->ki", R, [0, 0, 1.0]) * -rate[i, None]  # yaw rate = -heading rate
    v_dvl = np.einsum("kji,kj->ki", R, v_ground[i]) + np.cross(omega, LEVER)
    att_m = att + rng.standard_normal(att.shape) * [
        math.radians(0.1),
        math.radians(0.1),
        SIGMA_HEADING,
    ]
    omega_m = omega + 1e-3 * rng.standard_normal(omega.shape)
    v_dvl_m = v_dvl + SIGMA_DVL * rng.standard_normal(v_dvl.shape)
    speed_m = speed + SIGMA_SPEED * rng.standard_normal(len(i))
    return t, pos[i], att_m, omega_m, v_dvl_m, speed_m


def test_dr_on_dvl_beats_dr_on_heading_and_log_in_a_current():
    finals_dvl, finals_log, means_dvl, means_log = [], [], [], []
    for seed in range(8):
        t, pos, att_m, omega_m, v_dvl_m, speed_m = _survey(seed)
        v_world = velocity_world_from_dvl(v_dvl_m, att_m, omega_m, LEVER)
        dr_dvl = dvl_track(pos[0], v_world[None], t).position_m[0]
        u = np.column_stack([att_m[1:, 2], speed_m[1:], np.zeros(len(t) - 1)])  # held
        dr_log, _ = dead_reckon(pos[0][None], u[None], DT, CourseSpeedDepthMotion(0.1, 0.1, 0.1))
        e_dvl = np.linalg.norm(dr_dvl[:, :2] - pos[:, :2], axis=-1)
        e_log = np.linalg.norm(dr_log[0, :, :2] - pos[:, :2], axis=-1)
        finals_dvl.append(e_dvl[-1])
        finals_log.append(e_log[-1])
        means_dvl.append(e_dvl.mean())
        means_log.append(e_log.mean())
        # the log's DR misses the current's drift, 0.3 m/s over the whole survey
        assert abs(e_log[-1] - CURRENT * t[-1]) < 0.1 * CURRENT * t[-1]
        assert e_dvl[-1] < e_log[-1] / 20
    fd, fl = np.array(finals_dvl), np.array(finals_log)
    md, ml = np.array(means_dvl), np.array(means_log)
    print(
        f"\nDR over 600 s in a {CURRENT} m/s current, 8 seeds: final horizontal error "
        f"DVL {fd.mean():.2f} m (max {fd.max():.2f}) vs heading + log {fl.mean():.1f} m "
        f"(max {fl.max():.1f}): {fl.mean() / fd.mean():.0f}x smaller; mean error DVL "
        f"{md.mean():.2f} m vs log {ml.mean():.1f} m ({ml.mean() / md.mean():.0f}x)"
    )
    # the DVL's own error: white velocity and heading noise, a random walk of a few dm at most
    assert fd.max() < 1.0
