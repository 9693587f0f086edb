"""The batched EKF against filterpy's ExtendedKalmanFilter, path by path, and its robustness."""

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from scipy.stats import chi2

from nav.ekf import BatchEKF, update
from nav.errors import FilterDivergedError, NavInputError
from nav.models import CourseSpeedDepthMotion, UsblMeasurement

TX = np.array([0.0, 0.0, -6.0])
USBL = UsblMeasurement(TX, 0.2, math.radians(3), math.radians(3))
MOTION = CourseSpeedDepthMotion(math.radians(8), 0.257, 0.25)


def _inputs(n, T, k_fix, seed=3):
    rng = np.random.default_rng(seed)
    x0 = np.column_stack([rng.normal(300, 5, n), rng.normal(340, 5, n), np.full(n, -3.0)])
    u = np.stack(
        [
            np.radians(220) + rng.uniform(-0.4, 0.4, (n, T)),
            1.0 + rng.uniform(-0.7, 0.7, (n, T)),
            rng.uniform(-0.7, 0.7, (n, T)),
        ],
        axis=-1,
    )
    truth = x0[:, None, :] + np.cumsum(MOTION.increment(u, 1.0), axis=1)
    z = USBL.h(truth.reshape(-1, 3)).reshape(n, T, 3)
    z = z + rng.normal(0, [0.2, 0.05, 0.05], z.shape)
    z[..., 1] %= 2 * np.pi
    return x0, u, z, k_fix


def test_batched_ekf_equals_filterpy_path_by_path():
    n, T = 6, 120
    x0, u, z, k_fix = _inputs(n, T, 5)
    P0 = np.diag([4.5, 4.5, 0.0625])
    batch = BatchEKF(x0, P0)
    xs_b, Ps_b = [], []
    for k in range(T):
        batch.predict(MOTION, u[:, k], 1.0)
        if (k + 1) % k_fix == 0:
            batch.update(USBL, z[:, k])
        xs_b.append(batch.x.copy())
        Ps_b.append(batch.P.copy())
    for i in range(n):
        ekf = ExtendedKalmanFilter(dim_x=3, dim_z=3, dim_u=3)
        ekf.x = x0[i].copy()
        ekf.P = P0.copy()
        ekf.F = np.eye(3)
        ekf.B = np.eye(3)
        ekf.R = USBL.R()
        for k in range(T):
            uk = u[i : i + 1, k]
            ekf.Q = MOTION.Q(uk, 1.0)[0]
            ekf.predict(u=MOTION.increment(uk, 1.0)[0])
            if (k + 1) % k_fix == 0:
                ekf.update(
                    z[i, k],
                    HJacobian=lambda x: USBL.H(x[None])[0],
                    Hx=lambda x: USBL.h(x[None])[0],
                    residual=lambda a, b: USBL.residual(a[None], b[None])[0],
                )
            assert np.allclose(ekf.x, xs_b[k][i], rtol=0, atol=1e-9)
            assert np.allclose(ekf.P, Ps_b[k][i], rtol=0, atol=1e-9)


def test_joseph_update_keeps_covariance_symmetric_positive():
    x0, u, z, _ = _inputs(50, 40, 1, seed=9)
    f = BatchEKF(x0, np.diag([4.5, 4.5, 0.06]))
    for k in range(40):
        f.predict(MOTION, u[:, k], 1.0)
        f.update(USBL, z[:, k])
        assert np.allclose(f.P, np.swapaxes(f.P, 1, 2), atol=0)
        assert np.all(np.linalg.eigvalsh(f.P) > 0)
    f.check(40.0)


def test_inactive_component_equals_update_without_it():
    rng = np.random.default_rng(1)
    n = 20
    x = rng.normal(0, 30, (n, 3))
    A = rng.normal(0, 1, (n, 3, 3))
    P = A @ np.swapaxes(A, 1, 2) + np.eye(3)
    H = rng.normal(0, 1, (n, 3, 3))
    y = rng.normal(0, 1, (n, 3))
    R = np.diag([0.04, 0.01, 0.02])
    active = np.tile([True, False, True], (n, 1))
    xa, Pa, info = update(x, P, y, H, R, active=active)
    keep = [0, 2]
    xb, Pb, _ = update(x, P, y[:, keep], H[:, keep], R[np.ix_(keep, keep)])
    assert np.allclose(xa, xb, atol=1e-12) and np.allclose(Pa, Pb, atol=1e-12)
    assert np.all(info.dof == 2)


def test_absent_runs_are_unchanged_and_gate_rejects_outliers():
    x0, u, z, _ = _inputs(40, 2, 1, seed=5)
    f = BatchEKF(x0, np.diag([4.5, 4.5, 0.06]))
    f.predict(MOTION, u[:, 0], 1.0)
    x_before, P_before = f.x.copy(), f.P.copy()
    present = np.arange(40) % 2 == 0
    zz = z[:, 0].copy()
    zz[::4, 0] += 60.0  # gross range outliers on every other present run
    info = f.update(USBL, zz, present=present, gate_probability=0.99)
    assert np.array_equal(f.x[~present], x_before[~present])
    assert np.array_equal(f.P[~present], P_before[~present])
    assert np.all(np.isnan(info.nis[~present]))
    limit = chi2.ppf(0.99, 3)
    assert np.array_equal(info.rejected, present & (info.nis > limit))
    assert info.rejected[::4].all()
    assert np.array_equal(f.x[info.rejected], x_before[info.rejected])


def test_vehicle_above_the_transceiver_gives_finite_update():
    x = np.array([[0.0, 0.0, -3.0], [0.2, -0.1, -3.0]])
    f = BatchEKF(x, np.diag([4.5, 4.5, 0.06]))
    z = USBL.h(np.array([[0.5, 0.4, -3.2], [0.1, 0.1, -2.9]]))
    f.update(USBL, z)
    assert np.all(np.isfinite(f.x)) and np.all(np.isfinite(f.P))
    f.check(0.0)


def test_bad_inputs_raise():
    f = BatchEKF(np.zeros((1, 3)), np.eye(3))
    f.x[0, 0] = np.nan
    with pytest.raises(FilterDivergedError, match="t = 7"):
        f.check(7.0)
    with pytest.raises(NavInputError, match="positive variances"):
        update(
            np.zeros((1, 1)), np.eye(1)[None], np.zeros((1, 1)), np.eye(1)[None], np.zeros((1, 1))
        )
