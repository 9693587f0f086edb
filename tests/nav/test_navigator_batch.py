"""The batched online navigator against the scalar one run by run, and its update against
filterpy (issue 27, check 2)."""

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from nav.ekf import BatchEKF
from nav.errors import NavInputError
from nav.models import (
    CourseSpeedDepthMotion,
    CurrentAwareMotion,
    DepthMeasurement,
    UsblMeasurement,
)
from nav.navigator import Measurement, Navigator
from nav.navigator.batch import BatchNavigator

MOTION = CourseSpeedDepthMotion(math.radians(2.0), 0.08, 0.05)
TRANS = np.array([0.0, 0.0, -6.0])
DT = 0.2


def _pair(n, current, gate, lockout, rng):
    x0 = rng.normal(0, 3, (n, 3)) + [50, -20, -3]
    P0 = np.diag([9.0, 9.0, 0.0025])
    kw = dict(
        history_s=4.0,
        gate_probability=gate,
        current_sigma0_m_s=0.3 if current else None,
        max_consecutive_rejections=lockout,
    )
    batch = BatchNavigator(n, 0.0, x0, P0, MOTION, DT, **kw)
    scalars = [Navigator(0.0, x0[i], P0, MOTION, **kw) for i in range(n)]
    return batch, scalars


@pytest.mark.slow
@pytest.mark.parametrize(
    "current, gate, lockout", [(True, 0.999, 3), (False, 0.999, None), (True, None, None)]
)
def test_each_run_equals_the_scalar_navigator(current, gate, lockout):
    """Predict every tick, depth every 5 ticks, USBL fixes valid at every 25th tick arriving
    1-8 ticks late per run, a fifth of them gross outliers (rejected by the gate, then let
    through by the lock-out)."""
    rng = np.random.default_rng(11)
    n, T = 7, 400
    batch, scalars = _pair(n, current, gate, lockout, rng)
    truth = np.array([50.0, -20.0, -3.0]) + np.zeros((n, 3))
    model = UsblMeasurement(TRANS, 0.2, math.radians(3), math.radians(3))
    depth = DepthMeasurement(0.05)
    pending = {}
    rejected_any = applied_any = False
    for k in range(1, T):
        t = k * DT
        head = rng.uniform(0, 2 * math.pi) + rng.normal(0, 0.05, n)
        spd = rng.uniform(0.5, 1.5, n)
        truth[:, 0] += DT * spd * np.sin(head) + 0.05
        truth[:, 1] += DT * spd * np.cos(head)
        batch.predict(t, head, spd, 0.0)
        for i, s in enumerate(scalars):
            s.predict(t, head[i], spd[i], 0.0)
        if k % 5 == 0:
            z = -truth[:, 2:3] + rng.normal(0, 0.05, (n, 1))
            batch.fuse(depth, z, np.ones(n, dtype=bool))
            for i, s in enumerate(scalars):
                s.fuse(Measurement(z[i], depth))
        if k % 25 == 0:
            z = model.h(truth) + rng.normal(0, [0.2, 0.05, 0.05], (n, 3))
            z[rng.random(n) < 0.2] += [30.0, 0.5, 0.3]
            pending[k] = (z, t, k + rng.integers(1, 9, n))
        arrived = np.zeros(n, dtype=bool)
        z_arr, tv = np.zeros((n, 3)), np.zeros(n)
        for _, (z, tvalid, due) in list(pending.items()):
            now = due == k
            arrived |= now
            z_arr[now], tv[now] = z[now], tvalid
        if arrived.any():
            nis, applied, rejected = batch.fuse(model, z_arr, arrived, tv)
            rejected_any |= rejected.any()
            applied_any |= applied.any()
            for i in np.flatnonzero(arrived):
                info = scalars[i].fuse(Measurement(z_arr[i], model, tv[i]))
                assert applied[i] == (not info.rejected[0]), (k, i)
                assert nis[i] == pytest.approx(float(info.nis[0]), rel=1e-9), (k, i)
        for i, s in enumerate(scalars):
            est = s.estimate
            np.testing.assert_allclose(batch.x[i, :3], est.x, rtol=0, atol=1e-9, err_msg=f"{k} {i}")
            np.testing.assert_allclose(batch.P[i, :3, :3], est.P, rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(batch.dr_position[i], s.dr_position, atol=1e-9)
            if current:
                np.testing.assert_allclose(
                    batch.current_estimate()[i], s.current_estimate[0], atol=1e-9
                )
    assert applied_any
    assert rejected_any == (gate is not None)
    assert batch.n_applied.sum() == sum(s.n_applied for s in scalars)
    assert batch.n_rejected.sum() == sum(s.n_rejected for s in scalars)


@pytest.mark.parametrize("current", [True, False])
def test_the_closed_form_prediction_equals_the_batched_ekf(current):
    rng = np.random.default_rng(2)
    n = 20
    nav = BatchNavigator(n, 0.0, np.zeros((n, 3)), np.eye(3), MOTION, DT,
                         current_sigma0_m_s=0.3 if current else None)  # fmt: skip
    d = nav.dim
    A = rng.normal(0, 1, (n, d, d))
    P = A @ np.swapaxes(A, 1, 2)
    x = rng.normal(0, 5, (n, d))
    u = np.stack([rng.uniform(0, 6, n), rng.uniform(0, 2, n), rng.normal(0, 0.1, n)], 1)
    motion = CurrentAwareMotion(MOTION, 0.005) if current else MOTION
    xe, Pe = BatchEKF(motion).predict(x, P, u, DT)
    xg, Pg = nav._predict(x, P, u, DT)
    np.testing.assert_allclose(xg, xe, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Pg, Pe, rtol=1e-12, atol=1e-12)


def test_a_usbl_update_equals_filterpy():
    """One gated-off USBL update of each run against filterpy's ExtendedKalmanFilter."""
    rng = np.random.default_rng(4)
    n = 9
    x0 = rng.normal(0, 30, (n, 3)) + [0, 0, -3]
    P0 = np.diag([4.0, 9.0, 0.01])
    nav = BatchNavigator(n, 0.0, x0, P0, MOTION, DT)
    model = UsblMeasurement(TRANS, 0.2, math.radians(3), math.radians(3))
    z = model.h(x0 + rng.normal(0, 2, (n, 3)))
    nav.fuse(model, z, np.ones(n, dtype=bool))
    for i in range(n):
        f = ExtendedKalmanFilter(3, 3)
        f.x, f.P, f.R = x0[i].copy(), P0.copy(), model.R()
        f.update(
            z[i], lambda x: model.H(x[None])[0], lambda x: model.h(x[None])[0],
            residual=lambda a, b: model.residual(a[None], b[None])[0],
        )  # fmt: skip
        np.testing.assert_allclose(nav.x[i], f.x, atol=1e-9)
        np.testing.assert_allclose(nav.P[i], f.P, atol=1e-9)


def test_bad_measurements_are_refused():
    nav = BatchNavigator(2, 0.0, np.zeros((2, 3)), np.eye(3), MOTION, DT, history_s=1.0)
    for k in range(1, 20):
        nav.predict(k * DT, np.zeros(2), np.ones(2), 0.0)
    depth = DepthMeasurement(0.05)
    yes = np.ones(2, dtype=bool)
    with pytest.raises(NavInputError, match="older than the navigation history"):
        nav.fuse(depth, np.ones((2, 1)), yes, np.array([0.5, 3.0]))
    with pytest.raises(NavInputError, match="future"):
        nav.fuse(depth, np.ones((2, 1)), yes, np.array([9.0, 3.0]))
    with pytest.raises(NavInputError, match="not finite"):
        nav.fuse(depth, np.array([[1.0], [np.nan]]), yes)
    with pytest.raises(NavInputError, match="not after"):
        nav.predict(1.0, np.zeros(2), np.ones(2))
    with pytest.raises(NavInputError, match="non-finite input in batch row 1"):
        nav.predict(9.0, np.array([0.0, np.nan]), np.ones(2))
