"""The online navigator: late measurements land at their time of validity."""

import math

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.models import (
    CourseSpeedDepthMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    UsblMeasurement,
)
from nav.navigator import Navigator

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


@pytest.mark.parametrize("with_current", [False, True])
def test_fast_prediction_equals_the_generic_ekf_prediction(with_current):
    from nav.ekf import predict
    from nav.models import CurrentAwareMotion

    rng = np.random.default_rng(3)
    nav = Navigator(
        0.0, np.zeros(3), np.eye(3), MOTION, current_sigma0_m_s=0.3 if with_current else None
    )
    d = nav.dim
    A = rng.normal(size=(d, d))
    P = (A @ A.T + np.eye(d))[None]
    x = rng.normal(size=(1, d))
    u = np.array([[1.1, 0.9, 0.05]])
    m = CurrentAwareMotion(MOTION, 0.005) if with_current else MOTION
    assert type(nav.motion) is type(m)
    xf, Pf = nav._predict(x, P, u, 0.2)
    xg, Pg = predict(x, P, m.f(x, u, 0.2), m.F(x, u, 0.2), m.Q(u, 0.2))
    assert np.allclose(xf, xg, atol=1e-14) and np.allclose(Pf, Pg, atol=1e-14)


def test_single_run_update_equals_the_batched_update():
    from nav.ekf import update
    from nav.navigator import _update_one

    rng = np.random.default_rng(11)
    for d, m in [(3, 3), (5, 3), (5, 1), (5, 2)]:
        A = rng.normal(size=(d, d))
        P = (A @ A.T + np.eye(d))[None]
        x = rng.normal(size=(1, d))
        H = rng.normal(size=(1, m, d))
        y = rng.normal(size=(1, m))
        R = np.diag(rng.uniform(0.1, 1.0, m))
        active = rng.random((1, m)) > 0.3
        for gate in (None, 0.9):
            xb, Pb, ib = update(x, P, y, H, R, active, None, gate)
            xo, Po, io = _update_one(x, P, y, H, R, active, gate)
            assert np.allclose(xb, xo, atol=1e-12) and np.allclose(Pb, Po, atol=1e-12)
            assert ib.rejected[0] == io.rejected[0] and ib.applied[0] == io.applied[0]
            if active.any():
                assert ib.nis[0] == pytest.approx(io.nis[0])
