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
