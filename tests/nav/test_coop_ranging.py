"""The travel-time range models of nav.cooperative: values against the geometry worked out here,
analytic Jacobians against finite differences, and the centralised update against filterpy."""

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from nav.cooperative import (
    ClockOptions,
    CoopOptions,
    OwttRangeMeasurement,
    TeamEkf,
    TwttRangeMeasurement,
)
from nav.errors import NavInputError

C = 1500.0


def _numeric_jacobian(model, x, eps=1e-6):
    J = np.zeros((x.shape[0], 1, x.shape[1]))
    for j in range(x.shape[1]):
        step = eps * max(1.0, np.abs(x[:, j]).max())
        xp, xm = x.copy(), x.copy()
        xp[:, j] += step
        xm[:, j] -= step
        J[:, 0, j] = (model.h(xp)[:, 0] - model.h(xm)[:, 0]) / (2 * step)
    return J


def _two_vehicle_state(rng, n):
    # blocks [e, n, b, d] for vehicle 0 (at 0) and 1 (at 4)
    x = np.zeros((n, 8))
    x[:, 0:2] = rng.normal(0, 50, (n, 2))
    x[:, 4:6] = rng.normal(0, 50, (n, 2))
    x[:, [2, 6]] = rng.normal(0, 1e-3, (n, 2))
    x[:, [3, 7]] = rng.normal(0, 1e-6, (n, 2))
    return x


def test_owtt_value_is_the_slant_range_at_the_two_instants_plus_the_clock_difference():
    rng = np.random.default_rng(1)
    n = 5
    x = _two_vehicle_state(rng, n)
    vr, vs = rng.normal(0, 1, (n, 2)), rng.normal(0, 1, (n, 2))
    lag_r, lag_s, dz = rng.uniform(0, 0.2, n), rng.uniform(0.1, 1.0, n), rng.normal(0, 5, n)
    m = OwttRangeMeasurement(
        receiver_at=4,
        sender_at=0,
        sigma_m=0.1,
        dz_m=dz,
        receiver_lag_s=lag_r,
        sender_lag_s=lag_s,
        receiver_velocity_m_s=vr,
        sender_velocity_m_s=vs,
        sound_speed_m_s=C,
        receiver_drift=True,
        sender_drift=True,
    )
    for r in range(n):
        p_rx = x[r, 4:6] - vr[r] * lag_r[r]
        p_tx = x[r, 0:2] - vs[r] * lag_s[r]
        b_rx = x[r, 6] - x[r, 7] * lag_r[r]
        b_tx = x[r, 2] - x[r, 3] * lag_s[r]
        want = np.sqrt(np.sum((p_rx - p_tx) ** 2) + dz[r] ** 2) + C * (b_rx - b_tx)
        assert m.h(x)[r, 0] == pytest.approx(want, rel=1e-13)


@pytest.mark.parametrize("drift", [False, True])
def test_owtt_jacobian_equals_finite_differences(drift):
    rng = np.random.default_rng(2)
    n = 20
    x = _two_vehicle_state(rng, n)
    m = OwttRangeMeasurement(
        receiver_at=0,
        sender_at=4,
        sigma_m=0.1,
        dz_m=rng.normal(0, 5, n),
        receiver_lag_s=rng.uniform(0, 0.2, n),
        sender_lag_s=rng.uniform(0.1, 1.0, n),
        receiver_velocity_m_s=rng.normal(0, 1, (n, 2)),
        sender_velocity_m_s=rng.normal(0, 1, (n, 2)),
        sound_speed_m_s=C,
        receiver_drift=drift,
        sender_drift=drift,
    )
    H = m.H(x)
    assert np.allclose(H, _numeric_jacobian(m, x), rtol=1e-6, atol=1e-6)
    # the clock columns are +-c and -+c lag: not zero
    assert np.allclose(H[:, 0, 2], C) and np.allclose(H[:, 0, 6], -C)
    if drift:
        assert np.all(np.abs(H[:, 0, 3]) > 0)


def test_twtt_has_no_clock_terms_and_its_jacobian_equals_finite_differences():
    rng = np.random.default_rng(3)
    n = 20
    x = _two_vehicle_state(rng, n)
    m = TwttRangeMeasurement(
        receiver_at=0,
        sender_at=4,
        sigma_m=0.1,
        dz_m=rng.normal(0, 5, n),
        receiver_lag_s=0.3,
        sender_lag_s=0.3,
        receiver_velocity_m_s=rng.normal(0, 1, (n, 2)),
        sender_velocity_m_s=rng.normal(0, 1, (n, 2)),
    )
    H = m.H(x)
    assert np.allclose(H, _numeric_jacobian(m, x), rtol=1e-6, atol=1e-6)
    assert np.all(H[:, 0, [2, 3, 6, 7]] == 0)
    x2 = x.copy()
    x2[:, [2, 6]] += 0.01  # a clock change does not move a two-way range
    assert np.array_equal(m.h(x), m.h(x2))


def test_models_refuse_bad_input_with_the_field_named():
    with pytest.raises(NavInputError, match="sigma_m"):
        OwttRangeMeasurement(receiver_at=0, sender_at=3, sigma_m=0.0)
    with pytest.raises(NavInputError, match="sender_at"):
        TwttRangeMeasurement(receiver_at=3, sender_at=3, sigma_m=0.1)
    with pytest.raises(NavInputError, match="sound_speed_m_s"):
        OwttRangeMeasurement(receiver_at=0, sender_at=3, sigma_m=0.1, sound_speed_m_s=-1.0)


def test_the_centralised_update_equals_filterpy_on_a_small_team():
    # two vehicles, offsets and drifts in the state; one OWTT range; filterpy's EKF (Joseph form)
    # on the same prior, Jacobian and noise
    clock = ClockOptions(offset_sigma_s=2e-3, drift_sigma=1e-6)
    opts = CoopOptions(clock=clock, leader_clock=clock)
    start = np.array([[[0.0, 0.0], [80.0, 30.0]]])
    cov = np.array([[np.diag([4.0, 9.0]), np.array([[25.0, 3.0], [3.0, 16.0]])]])
    team = TeamEkf(start, cov, opts)
    team.predict(np.array([[[1.0, 0.5], [0.8, -0.2]]]), np.array([[np.eye(2)] * 2]) * 0.01, 1.0)
    x0, P0 = team.x.copy(), team.P.copy()
    vr, vs = np.array([[0.9, 0.1]]), np.array([[0.7, -0.3]])
    kw = dict(
        sigma_m=0.3,
        sound_speed_m_s=C,
        dz_m=np.array([-4.0]),
        receiver_lag_s=np.array([0.1]),
        sender_lag_s=np.array([0.16]),
        receiver_velocity_m_s=vr,
        sender_velocity_m_s=vs,
    )
    z = 88.0
    team.update_range(1, 0, np.array([z]), **kw)

    model = OwttRangeMeasurement(
        receiver_at=4, sender_at=0, receiver_drift=True, sender_drift=True, **kw
    )
    f = ExtendedKalmanFilter(dim_x=8, dim_z=1)
    f.x = x0[0].reshape(8, 1)
    f.P = P0[0].copy()
    f.R = np.array([[0.3**2]])
    f.update(
        np.array([[z]]),
        lambda s: model.H(s.reshape(1, 8))[0],
        lambda s: model.h(s.reshape(1, 8)).reshape(1, 1),
    )
    assert np.allclose(team.x[0], f.x[:, 0], rtol=1e-12, atol=1e-12)
    assert np.allclose(team.P[0], f.P, rtol=1e-10, atol=1e-16)
    # the range moved the clock offsets (it observes them)
    assert abs(team.x[0, 6] - x0[0, 6]) > 1e-6


def test_prediction_is_the_two_state_clock_model_worked_out_by_hand():
    # x = [e, n, b, d] per vehicle; over dt: p += step, b += d dt; P -> F P F^T + Q with
    # F = [[I, 0], [0, [[1, dt], [0, 1]]]] and Q = blockdiag(step_cov, clock Q of Brown & Hwang)
    qb, qd, dt = 1e-12, 1e-18, 2.0
    clock = ClockOptions(
        offset_sigma_s=1e-3, drift_sigma=1e-6, offset_noise_s2_per_s=qb, drift_noise_per_s=qd
    )
    opts = CoopOptions(clock=clock, leader_clock=clock)
    start = np.array([[[0.0, 0.0], [10.0, 20.0]]])
    team = TeamEkf(start, np.array([[np.eye(2), 2 * np.eye(2)]]), opts)
    team.x[0, 3], team.x[0, 7] = 3e-6, -2e-6  # drifts
    team.x[0, 2], team.x[0, 6] = 1e-3, -5e-4  # offsets
    team.P[0, 2, 3] = team.P[0, 3, 2] = 1e-10  # an offset-drift correlation
    x0, P0 = team.x[0].copy(), team.P[0].copy()
    step = np.array([[[1.0, -0.5], [0.3, 0.2]]])
    step_cov = np.array([[np.eye(2) * 0.01, np.eye(2) * 0.04]])
    team.predict(step, step_cov, dt)
    F = np.eye(8)
    F[2, 3] = F[6, 7] = dt
    Q = np.zeros((8, 8))
    Q[:2, :2], Q[4:6, 4:6] = step_cov[0, 0], step_cov[0, 1]
    for b in (2, 6):
        Q[b, b] = qb * dt + qd * dt**3 / 3
        Q[b, b + 1] = Q[b + 1, b] = qd * dt**2 / 2
        Q[b + 1, b + 1] = qd * dt
    want = x0.copy()
    want[[0, 1, 4, 5]] += step[0].ravel()
    want[2] += 3e-6 * dt
    want[6] += -2e-6 * dt
    assert np.allclose(team.x[0], want, rtol=0, atol=1e-15)
    assert np.allclose(team.P[0], F @ P0 @ F.T + Q, rtol=1e-12, atol=1e-30)
    # the decentralised navigator predicts its block the same way
    from nav.cooperative import CoopNavigator

    nav = CoopNavigator(start[:, 1], np.array([2 * np.eye(2)]), clock)
    nav.x[0], nav.P[0] = x0[4:], P0[4:, 4:]
    nav.predict(step[:, 1], step_cov[:, 1], dt)
    assert np.allclose(nav.x[0], want[4:], rtol=0, atol=1e-15)
    assert np.allclose(nav.P[0], (F @ P0 @ F.T + Q)[4:, 4:], rtol=1e-12, atol=1e-30)


def test_a_two_way_range_does_not_touch_the_clocks_and_a_one_way_range_does():
    from nav.cooperative import CoopNavigator, PeerEstimate

    n = 4
    clock = ClockOptions(offset_sigma_s=1e-3, drift_sigma=1e-6)
    peer = PeerEstimate.from_parts(
        np.tile([50.0, 0.0], (n, 1)), np.tile(np.eye(2), (n, 1, 1)), np.zeros(n), np.full(n, 1e-8)
    )
    out = {}
    for kind in ("twtt", "owtt"):
        nav = CoopNavigator(np.zeros((n, 2)), np.tile(np.eye(2) * 4.0, (n, 1, 1)), clock)
        x0, P0 = nav.x.copy(), nav.P.copy()
        info, w = nav.fuse_range(
            np.full(n, 51.5), peer, sigma_m=0.1, depth_m=5.0, peer_depth_m=5.0, kind=kind
        )
        assert info.applied.all() and np.all((w > 0) & (w < 1))
        assert not np.allclose(nav.x[:, 0], x0[:, 0])  # the position moved
        out[kind] = (nav.x - x0, nav.P - P0)
    # two-way: no information on the clocks (CI may widen them: its bound, 1/w, where the range
    # says nothing)
    dx, dP = out["twtt"]
    assert np.all(dx[:, 2:] == 0) and np.all(dP[:, 2, 2] >= 0)
    dx, dP = out["owtt"]
    assert np.all(np.abs(dx[:, 2]) > 0) and np.all(dP[:, 2, 2] < 0)
