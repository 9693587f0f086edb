"""The online navigator: late measurements land at their time of validity; a measurement
carries its model, and any mix of them is fused."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from nav.dead_reckoning import dead_reckon
from nav.ekf import BatchEKF, SingleRunEKF
from nav.errors import NavInputError
from nav.models import (
    BearingMeasurement,
    CourseSpeedDepthMotion,
    CurrentAwareMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    SlantRangeMeasurement,
    UsblMeasurement,
)
from nav.navigator import (
    BroadcastRangeNavigator,
    FollowerOptions,
    Measurement,
    Navigator,
    OnlineNavigator,
)
from nav.relative import GaOptions

MOTION = CourseSpeedDepthMotion(math.radians(3), 0.05, 0.02)
USBL = UsblMeasurement(np.array([50.0, 80.0, -30.0]), 0.2, math.radians(1), math.radians(1))


def _nav(**kw):
    return Navigator(0.0, np.array([0.0, 0.0, -5.0]), np.diag([9.0, 9.0, 0.25]), MOTION, **kw)


def _inputs(k):
    rng = np.random.default_rng(k)
    return 0.3 + 0.05 * rng.standard_normal(), 1.0 + 0.05 * rng.standard_normal()


def test_without_measurements_the_ekf_is_the_dr():
    nav = _nav()
    for k in range(1, 50):
        nav.predict(0.1 * k, *_inputs(k))
    assert np.allclose(nav.estimate.x, nav.dr_position)
    assert nav.estimate.t_s == pytest.approx(4.9)
    assert nav.current_estimate is None


def test_online_dr_is_the_batched_dr_and_restarts():
    nav = _nav(current_sigma0_m_s=0.2)
    u = np.array([[[*_inputs(k), 0.01 * k] for k in range(1, 30)]])
    for k in range(1, 30):
        nav.predict(0.1 * k, *u[0, k - 1])
        if k == 10:
            nav.update(HorizontalPositionMeasurement(1.0), np.array([5.0, -3.0]))
    x, _ = dead_reckon(np.array([[0.0, 0.0, -5.0]]), u, 0.1, MOTION)
    assert np.allclose(nav.dr_position, x[0, -1], atol=1e-12)  # fixes never move the DR
    nav.reset_dr(np.array([1.0, 2.0, -3.0]))
    assert np.array_equal(nav.dr_position, [1.0, 2.0, -3.0])


def test_late_fix_equals_a_fix_applied_on_time():
    on_time, late = _nav(), _nav()
    z = np.array([120.0, math.radians(200), math.radians(-12)])
    for k in range(1, 40):
        t = 0.1 * k
        on_time.predict(t, *_inputs(k))
        late.predict(t, *_inputs(k))
        if k == 20:
            on_time.update(USBL, z)
        if k == 27:  # arrives 0.7 s late, valid at t = 2.0 s
            late.update(USBL, z, t_valid_s=2.0)
    assert np.allclose(late.estimate.x, on_time.estimate.x, atol=1e-12)
    assert np.allclose(late.estimate.P, on_time.estimate.P, atol=1e-12)
    assert not np.allclose(late.estimate.x, late.dr_position)


def test_too_old_or_future_measurements_are_refused():
    nav = _nav(history_s=1.0)
    for k in range(1, 40):
        nav.predict(0.1 * k, *_inputs(k))
    with pytest.raises(NavInputError, match="older than the navigation history"):
        nav.update(HorizontalPositionMeasurement(2.0), np.array([1.0, 2.0]), t_valid_s=1.0)
    with pytest.raises(NavInputError, match="future"):
        nav.update(HorizontalPositionMeasurement(2.0), np.array([1.0, 2.0]), t_valid_s=10.0)
    with pytest.raises(NavInputError, match="not finite"):
        nav.update(HorizontalPositionMeasurement(2.0), np.array([np.nan, 2.0]))
    with pytest.raises(NavInputError, match="not after"):
        nav.predict(0.5, 0.0, 1.0)


def test_gps_and_depth_updates_and_gate():
    nav = _nav(gate_probability=0.99)
    nav.predict(1.0, 0.0, 1.0)
    before = nav.estimate
    info = nav.update(HorizontalPositionMeasurement(1.0), np.array([0.5, 1.5]))
    assert info.applied[0] and nav.n_applied == 1
    # the fix pulls the estimate by K (z - h): with P = 9 + q, R = 1 the gain is P / (P + 1)
    p = before.P[0, 0]
    assert nav.estimate.x[0] == pytest.approx(before.x[0] + p / (p + 1) * (0.5 - before.x[0]))
    nav.update(DepthMeasurement(0.05), np.array([5.5]))
    assert -nav.estimate.x[2] == pytest.approx(5.5, abs=0.05)
    info = nav.update(HorizontalPositionMeasurement(1.0), np.array([80.0, -60.0]))
    assert info.rejected[0] and nav.n_rejected == 1


def _fly(nav):
    """A mission segment: inputs at 10 Hz, depth every second, a late USBL fix, GPS fixes (the
    last one gross)."""
    infos = []
    for k in range(1, 80):
        t = 0.1 * k
        nav.predict(t, *_inputs(k), 0.002)
        if k % 10 == 0:
            infos.append(nav.update(DepthMeasurement(0.05), np.array([5.0 + 0.001 * k])))
        if k == 47:  # valid at 4 s, near where the vehicle then is
            z = USBL.h(np.array([[1.5, 3.5, -5.2]]))[0]
            infos.append(nav.update(USBL, z, t_valid_s=4.0))
        if k in (60, 61, 62, 63):
            z = np.array([4.0, 5.0]) if k < 63 else np.array([80.0, -60.0])
            infos.append(nav.update(HorizontalPositionMeasurement(1.0), z))
    return infos


@pytest.mark.parametrize("with_current", [False, True])
def test_navigator_is_generic_over_the_estimator(with_current):
    motion = CurrentAwareMotion(MOTION, 0.01) if with_current else MOTION
    d = motion.dim
    x0 = np.zeros(d)
    x0[2] = -5.0
    P0 = np.diag([9.0, 9.0, 0.25, 0.04, 0.04][:d])
    navs = [
        OnlineNavigator(est(motion), 0.0, x0, P0, MOTION, gate_probability=0.99)
        for est in (SingleRunEKF, BatchEKF)
    ]
    runs = [_fly(nav) for nav in navs]
    fast, batched = navs
    assert np.allclose(fast.estimate.x, batched.estimate.x, rtol=1e-12, atol=1e-12)
    assert np.allclose(fast.estimate.P, batched.estimate.P, rtol=1e-12, atol=1e-12)
    assert [i.applied[0] for i in runs[0]] == [i.applied[0] for i in runs[1]]
    assert (fast.n_applied, fast.n_rejected) == (batched.n_applied, batched.n_rejected)
    assert fast.n_rejected == 1  # the gross GPS fix
    assert np.array_equal(fast.dr_position, batched.dr_position)
    if with_current:
        c_f, C_f = fast.current_estimate
        c_b, C_b = batched.current_estimate
        assert np.allclose(c_f, c_b, atol=1e-12) and np.allclose(C_f, C_b, atol=1e-12)
        assert np.all(np.diag(C_f) < 0.04)  # the fixes told it something about the current
    else:
        assert fast.current_estimate is None


def test_navigator_builds_todays_configuration():
    kw = dict(history_s=5.0, gate_probability=0.99, max_consecutive_rejections=3)
    P0 = np.diag([9.0, 9.0, 0.25])
    preset = Navigator(0.0, np.array([0.0, 0.0, -5.0]), P0, MOTION, current_sigma0_m_s=0.2, **kw)
    P5 = np.zeros((5, 5))
    P5[:3, :3] = P0
    P5[3, 3] = P5[4, 4] = 0.2**2
    explicit = OnlineNavigator(
        SingleRunEKF(CurrentAwareMotion(MOTION, 0.005)), 0.0, [0, 0, -5.0, 0, 0], P5, MOTION, **kw
    )
    _fly(preset)
    _fly(explicit)
    assert np.array_equal(preset.estimate.x, explicit.estimate.x)
    assert np.array_equal(preset.estimate.P, explicit.estimate.P)
    assert np.array_equal(preset.current_estimate[0], explicit.current_estimate[0])


def test_lock_out_applies_a_fix_after_consecutive_rejections():
    nav = _nav(gate_probability=0.99, max_consecutive_rejections=2)
    nav.predict(1.0, 0.0, 1.0)
    far = np.array([80.0, -60.0])
    gps = HorizontalPositionMeasurement(1.0)
    assert nav.update(gps, far).rejected[0] and nav.update(gps, far).rejected[0]
    assert nav.update(DepthMeasurement(0.05), np.array([5.0])).applied[0]  # counted per model
    info = nav.update(gps, far)  # the third in a row goes in without the gate
    assert info.applied[0] and not info.rejected[0] and nav.n_rejected == 2
    assert nav.estimate.x[0] > 40.0
    assert nav.update(gps, np.array([200.0, 0.0])).rejected[0]  # the gate is back


# ---------------------------------------------------------------------------------------------
# Consistency on a world that follows the filter's own models (Bar-Shalom's NEES/NIS tests)

N_RUNS, DT_S, FIX_EVERY, N_TICKS = 150, 1.0, 20, 400
SIGMA_WALK = 0.005  # (m/s)/sqrt(s), the navigator's default random walk of the current
SIGMA_C0 = 0.2  # m/s, initial sigma of each current component
P0 = np.diag([4.0, 4.0, 0.25])


def _matched_world(seed: int = 11):
    """N_RUNS runs of a vehicle whose truth follows :class:`CurrentAwareMotion` exactly: the
    measured heading, speed through water and depth change are the true ones plus gaussian noise
    of the motion model's sigmas, the current walks with ``SIGMA_WALK``, the start and the current
    are drawn from the navigator's initial covariance, and each USBL fix is ``h(x) + v``, ``v ~
    N(0, R)`` (the truth's noise is written out: the same numbers as the models'). Returns the NIS
    of every fix, and the NEES of the full state (position and current, 5-D) at the last tick and
    of the position (3-D) just before the last fix, one sample per run each."""
    rng = np.random.default_rng(seed)
    # the truth's noise, written out (the filter's models are given the same numbers)
    R_sd = np.array([0.2, math.radians(1), math.radians(1)])  # as USBL
    sd_u = np.array([math.radians(3), 0.05, 0.02])  # as MOTION
    nis, nees_end, nees_prior = [], [], []
    for _ in range(N_RUNS):
        x0 = np.array([0.0, 0.0, -5.0])
        truth = np.concatenate([x0 + rng.multivariate_normal(np.zeros(3), P0), np.zeros(2)])
        truth[3:] = SIGMA_C0 * rng.standard_normal(2)
        nav = Navigator(
            0.0, x0, P0, MOTION, current_sigma0_m_s=SIGMA_C0, current_walk_m_s_per_sqrt_s=SIGMA_WALK
        )
        for k in range(1, N_TICKS + 1):
            u_true = np.array([0.4 + 0.002 * k, 1.0, 0.0])
            u = u_true + sd_u * rng.standard_normal(3)
            truth[:3] += MOTION.increment_one(u_true, DT_S) + DT_S * np.r_[truth[3:], 0.0]
            truth[3:] += SIGMA_WALK * math.sqrt(DT_S) * rng.standard_normal(2)
            nav.predict(k * DT_S, *u)
            if k % FIX_EVERY == 0:
                if k == N_TICKS:
                    e = nav.estimate.x - truth[:3]
                    nees_prior.append(e @ np.linalg.solve(nav.estimate.P, e))
                z = USBL.h(truth[None, :3])[0] + R_sd * rng.standard_normal(3)
                nis.append(nav.update(USBL, z).nis[0])
        last = nav._hist[-1]  # the full state (position and current) and its covariance
        e = last.x[0] - truth
        Ps = last.P[0]
        nees_end.append(e @ np.linalg.solve(Ps, e))
    return np.array(nis), np.array(nees_end), np.array(nees_prior)


def _band(dim, n, p=0.99):
    from scipy.stats import chi2

    return chi2.ppf((1 - p) / 2, dim * n) / n, chi2.ppf((1 + p) / 2, dim * n) / n


@pytest.mark.slow
def test_navigator_is_consistent_on_a_matched_world():
    """Innovations of a consistent filter are white: the NIS of all fixes of all runs is one
    sample of size N_RUNS * fixes, and its mean must lie in the 99% chi-square band of that size;
    the NEES at a fixed time is one sample per run (band of size N_RUNS). Scaling the filter's R
    or Q by 4 or 1/4 moves them out (benchmarks/mutation_consistency.py)."""
    nis, nees_end, nees_prior = _matched_world()
    lo, hi = _band(3, len(nis))
    assert lo < nis.mean() < hi, (nis.mean(), lo, hi)
    lo, hi = _band(5, N_RUNS)
    assert lo < nees_end.mean() < hi, (nees_end.mean(), lo, hi)
    lo, hi = _band(3, N_RUNS)
    assert lo < nees_prior.mean() < hi, (nees_prior.mean(), lo, hi)


# -- measurements with their models -----------------------------------------------------------


def _numeric_jacobian(model, x, eps=1e-6):
    J = np.zeros((model.h(x).shape[-1], x.shape[-1]))
    for i in range(x.shape[-1]):
        dx = np.zeros_like(x)
        dx[0, i] = eps
        J[:, i] = model.residual(model.h(x + dx), model.h(x - dx))[0] / (2 * eps)
    return J


@pytest.mark.parametrize(
    "model",
    [
        SlantRangeMeasurement(np.array([30.0, -20.0, -2.0]), 0.5, np.array([0.3, -0.1, 0.2])),
        BearingMeasurement(np.array([-40.0, 25.0, -50.0]), 0.01),
        BearingMeasurement(np.array([2.0, -30.0]), 0.01),  # bearing near south: the wrap
    ],
    ids=["slant range", "bearing", "bearing south"],
)
def test_new_measurement_models_have_their_analytic_jacobians(model):
    x = np.array([[3.0, 4.0, -7.0, 0.1, -0.2]])  # with a current appended: zero columns
    J = model.H(x)[0]
    assert J.shape == (1, 5)
    assert np.allclose(J, _numeric_jacobian(model, x), atol=1e-7)
    assert np.all(J[:, 3:] == 0.0)
    assert model.active(x).all()


def test_slant_range_and_bearing_predict_the_geometry():
    p = np.array([13.0, 4.0, -1.0])
    x = np.array([[1.0, -1.0, -5.0]])
    arm = np.array([0.0, 0.0, 1.0])
    # |(1, -1, -4) - (13, 4, -1)| = |(-12, -5, -3)|
    assert SlantRangeMeasurement(p, 1.0, arm).h(x)[0, 0] == pytest.approx(math.sqrt(178.0))
    # a beacon due east is at 90 deg, due south-west at 225 deg
    assert BearingMeasurement(np.array([11.0, -1.0]), 0.1).h(x)[0, 0] == pytest.approx(math.pi / 2)
    b = BearingMeasurement(np.array([-9.0, -11.0]), 0.1)
    assert b.h(x)[0, 0] == pytest.approx(math.radians(225))
    # a measured bearing just past north against a prediction just before it: a small residual
    assert b.residual(np.array([[0.01]]), np.array([[2 * math.pi - 0.01]]))[0, 0] == (
        pytest.approx(0.02)
    )
    # on the beacon: no direction, the bearing is left out
    assert not BearingMeasurement(np.array([1.2, -1.0]), 0.1).active(x).any()


def test_a_broadcast_position_covariance_bounds_its_projection():
    C = np.array([[4.0, 1.0], [1.0, 2.0]])
    m = SlantRangeMeasurement(np.zeros(3), 0.5, position_covariance_m2=C)
    lam = np.linalg.eigvalsh(C)[-1]
    assert m.R()[0, 0] == pytest.approx(0.25 + lam)
    for a in np.linspace(0, 2 * np.pi, 37):
        u = np.array([math.sin(a), math.cos(a)])
        assert 0.25 + u @ C @ u <= m.R()[0, 0] + 1e-12
    iso = SlantRangeMeasurement(np.zeros(3), 0.5, position_covariance_m2=9.0 * np.eye(3))
    assert iso.R()[0, 0] == pytest.approx(9.25)  # exact for an isotropic covariance
    assert SlantRangeMeasurement(np.zeros(3), 0.5).R()[0, 0] == pytest.approx(0.25)


def test_fuse_is_the_update_with_the_measurements_own_model():
    a, b = _nav(gate_probability=0.99), _nav(gate_probability=0.99)
    z = np.array([120.0, math.radians(200), math.radians(-12)])
    for k in range(1, 30):
        for nav in (a, b):
            nav.predict(0.1 * k, *_inputs(k))
        if k == 20:
            ia = a.update(USBL, z, 1.55)
            ib = b.fuse(Measurement(z, USBL, 1.55))
            assert ia.nis[0] == ib.nis[0]
    assert np.array_equal(a.estimate.x, b.estimate.x)
    assert np.array_equal(a.estimate.P, b.estimate.P)


def test_any_mix_of_measurements_is_fused_and_finds_the_vehicle():
    """A vehicle 30 m from where its navigator believes it is, seen by ranges to two known
    positions, a bearing to a beacon, depth and one GPS fix: the estimate goes to the truth,
    which dead reckoning (the same inputs) never does."""
    truth = np.array([20.0, -10.0, -5.0])
    nav = Navigator(0.0, truth + [30.0, 0.0, 0.0], np.diag([900.0, 900.0, 1.0]), MOTION)
    rng = np.random.default_rng(3)
    ends = [np.array([200.0, 150.0, -2.0]), np.array([-150.0, 180.0, -10.0])]
    beacon = np.array([-120.0, -160.0, -40.0])
    for k in range(1, 121):
        t = 0.5 * k
        nav.predict(t, 0.0, 0.0)  # hovering: the truth stays put
        meas = [
            Measurement(
                np.array([-truth[2] + 0.05 * rng.standard_normal()]), DepthMeasurement(0.05)
            )
        ]
        for p in ends:
            r = np.linalg.norm(truth - p) + 0.3 * rng.standard_normal()
            meas.append(Measurement(np.array([r]), SlantRangeMeasurement(p, 0.3), t - 0.2))
        bearing = math.atan2(beacon[0] - truth[0], beacon[1] - truth[1]) % (2 * math.pi)
        bearing += 0.01 * rng.standard_normal()
        meas.append(Measurement(np.array([bearing]), BearingMeasurement(beacon, 0.01)))
        if k == 60:
            meas.append(Measurement(truth[:2] + 2.0, HorizontalPositionMeasurement(3.0)))
        for m in meas:
            assert nav.fuse(m).applied[0]
    err = np.linalg.norm(nav.estimate.x - truth)
    assert err < 1.0, err
    assert np.linalg.norm(nav.dr_position - truth) == pytest.approx(30.0)
    # the stated covariance covers the error (3 sigma)
    d = nav.estimate.x - truth
    assert d @ np.linalg.solve(nav.estimate.P, d) < 14.2  # chi-square(3) at 0.997


# -- the follower on ranges to a broadcast position (seed 003) --------------------------------


@dataclass(frozen=True)
class _Leader:
    t_s: float
    position_world_m: np.ndarray
    transducer_world_m: np.ndarray
    velocity_world_m_s: np.ndarray
    covariance_m2: np.ndarray | None = None
    current_world_m_s: np.ndarray | None = None


def _follower(method="ekf", **kw):
    opts = FollowerOptions(method, math.radians(2.0), 0.3, GaOptions(sigma_range_m=0.1), **kw)
    plan = _Leader(0.0, np.zeros(3), np.zeros(3), np.array([0.0, 1.0]))
    return BroadcastRangeNavigator(opts, np.array([10.0, 0.0, -3.0]), plan, history_ticks=5)


def test_follower_dead_reckons_through_water_and_over_ground_with_the_leaders_current():
    f = _follower("ekf")
    f.advance(0.0, 0.0, 1.0, 3.0, initial=True)
    cur = np.array([0.2, 0.0])
    at = np.array([0.0, 0.0, -3.0])  # the leader 10 m west at the same depth
    lead = _Leader(0.0, at, at, np.array([0.0, 1.0]), None, cur)
    res = f.range_fix(0.0, 0.0, 10.0, lead, np.zeros(3))  # brings the current
    assert res.accepted and np.array_equal(res.position_m, [10.0, 0.0, -3.0])  # no innovation
    for k in range(1, 11):  # 10 s north at 1 m/s through water
        f.advance(float(k), 0.0, 1.0, 3.0)
    # the pure DR is through water; the method's estimate drifts with the current too
    assert np.allclose(f.dr_position, [10.0, 10.0, -3.0], atol=1e-12)
    est, rep = f.end_tick(10.0, False)
    assert np.allclose(est.x, [12.0, 10.0, -3.0], atol=1e-9)  # carried east by the current
    assert np.array_equal(rep.current, cur)
    # "dr" ignores the messages, current included
    d = _follower("dr")
    d.advance(0.0, 0.0, 1.0, 3.0, initial=True)
    res = d.range_fix(0.0, 0.0, 10.0, lead, np.zeros(3))
    assert (res.accepted, res.reason) == (False, "dr")
    d.advance(1.0, 0.0, 1.0, None)
    assert np.array_equal(d.end_tick(1.0, False)[1].current, np.zeros(2))


def test_follower_range_geometry_and_report():
    f = _follower("ekf", depth_sigma_m=0.1, dr_warning_s=5.0)
    f.advance(0.0, 0.0, 0.0, 3.0, initial=True)
    # the leader's transducer 4 m above the follower's, 12 m west of the follower's reference
    # point; the follower's own transducer 1 m ahead (north) of its reference point
    trans = np.array([-2.0, 0.0, 1.0])
    lead = _Leader(4.5, np.array([-2.0, 0.0, 0.5]), trans, np.array([0.0, 1.0]), 0.04 * np.eye(2))
    arm = np.array([0.0, 1.0, 0.0])
    t, t_valid = 5.0, 4.5
    centre = trans[:2] + np.array([0.0, 1.0]) * (t - t_valid) - arm[:2]  # (-2, -0.5)
    dz = 1.0 - (-3.0)
    true_ref = np.array([10.0, -0.5])  # 12 m east of the centre: a horizontal range of 12 m
    slant = math.hypot(12.0, dz)
    for k in range(1, 6):
        f.advance(float(k), 0.0, 0.0, 3.0)
    res = f.range_fix(t, t_valid, slant, lead, arm)
    assert res.accepted and res.reason == "ok"
    assert res.horizontal_m == pytest.approx(12.0)
    assert np.allclose(res.centre_m, centre)
    # the estimate (10, 0) moves towards the circle: east-west is observed, not north
    assert abs(res.position_m[0] - true_ref[0]) < 0.05
    est, rep = f.end_tick(t, True)
    assert est.P[2, 2] == pytest.approx(0.01)
    assert est.x[2] == -3.0
    assert rep.fix_event and rep.since_fix == 0.0
    assert np.allclose(rep.leader_est, [-2.0, 0.5])  # moved on 0.5 s at 1 m/s north
    assert rep.leader_course == pytest.approx(0.0)
    assert f.dr_gaps_s() == [(0.0, 5.0)]  # 5 s without a range before it: a gap (>= 5 s)
    assert f.counts["accepted"] == 1
    # a slant range shorter than the depth difference has no horizontal solution
    bad = f.range_fix(t, t_valid, 3.0, lead, arm)
    assert (bad.accepted, bad.reason, bad.horizontal_m) == (False, "degenerate", 0.0)
    assert f.counts["degenerate"] == 1
