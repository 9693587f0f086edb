"""The batched EKF against filterpy's ExtendedKalmanFilter, path by path, its robustness, and the
single-run EKF against the batched one."""

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from scipy.stats import chi2

from nav.ekf import BatchEKF, SingleRunEKF, check_estimate, update, update_one
from nav.errors import FilterDivergedError, NavInputError
from nav.models import (
    CourseSpeedDepthMotion,
    CurrentAwareMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    UsblMeasurement,
)

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
    batch = BatchEKF(MOTION)
    x, P = x0, np.broadcast_to(P0, (n, 3, 3))
    xs_b, Ps_b = [], []
    for k in range(T):
        x, P = batch.predict(x, P, u[:, k], 1.0)
        if (k + 1) % k_fix == 0:
            x, P, _ = batch.update(x, P, USBL, z[:, k])
        xs_b.append(x)
        Ps_b.append(P)
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
    f = BatchEKF(MOTION)
    x, P = x0, np.broadcast_to(np.diag([4.5, 4.5, 0.06]), (50, 3, 3))
    for k in range(40):
        x, P = f.predict(x, P, u[:, k], 1.0)
        x, P, _ = f.update(x, P, USBL, z[:, k])
        assert np.allclose(P, np.swapaxes(P, 1, 2), atol=0)
        assert np.all(np.linalg.eigvalsh(P) > 0)
    check_estimate(x, P, 40.0)


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
    f = BatchEKF(MOTION)
    x_before, P_before = f.predict(
        x0, np.broadcast_to(np.diag([4.5, 4.5, 0.06]), (40, 3, 3)), u[:, 0], 1.0
    )
    present = np.arange(40) % 2 == 0
    zz = z[:, 0].copy()
    zz[::4, 0] += 60.0  # gross range outliers on every other present run
    x, P, info = f.update(x_before, P_before, USBL, zz, present=present, gate_probability=0.99)
    assert np.array_equal(x[~present], x_before[~present])
    assert np.array_equal(P[~present], P_before[~present])
    assert np.all(np.isnan(info.nis[~present]))
    limit = chi2.ppf(0.99, 3)
    assert np.array_equal(info.rejected, present & (info.nis > limit))
    assert info.rejected[::4].all()
    assert np.array_equal(x[info.rejected], x_before[info.rejected])


def test_vehicle_above_the_transceiver_gives_finite_update():
    x = np.array([[0.0, 0.0, -3.0], [0.2, -0.1, -3.0]])
    z = USBL.h(np.array([[0.5, 0.4, -3.2], [0.1, 0.1, -2.9]]))
    x, P, info = BatchEKF(MOTION).update(
        x, np.broadcast_to(np.diag([4.5, 4.5, 0.06]), (2, 3, 3)), USBL, z
    )
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(P)) and np.all(info.dof == 2)
    check_estimate(x, P, 0.0)


def test_bad_inputs_raise():
    x = np.zeros((1, 3))
    x[0, 0] = np.nan
    with pytest.raises(FilterDivergedError, match="t = 7"):
        check_estimate(x, np.eye(3)[None], 7.0)
    with pytest.raises(FilterDivergedError, match="rows \\[0\\]"):
        check_estimate(np.zeros((1, 3)), -np.eye(3)[None], 7.0)
    args = (np.zeros((1, 1)), np.eye(1)[None], np.zeros((1, 1)), np.eye(1)[None], np.zeros((1, 1)))
    with pytest.raises(NavInputError, match="positive variances"):
        update(*args)
    with pytest.raises(NavInputError, match="positive variances"):
        update_one(*args, np.ones((1, 1), bool))


# --------------------------------------------------------------------------------------------
# The single-run EKF equals the batched EKF


def _spd(rng, d):
    A = rng.normal(size=(d, d))
    return A @ A.T + 0.1 * np.eye(d)


CURRENT = CurrentAwareMotion(MOTION, 0.005)


@pytest.mark.parametrize("motion", [MOTION, CURRENT], ids=["position", "current"])
def test_single_run_prediction_equals_the_batched_prediction(motion):
    rng = np.random.default_rng(21)
    d = motion.dim
    for _ in range(50):
        x = rng.normal(0, 100, (1, d))
        x[0, 3:] = rng.normal(0, 0.3, d - 3)
        P = _spd(rng, d)[None]
        u = np.array([[rng.uniform(-7, 7), rng.uniform(0, 2), rng.normal(0, 0.3)]])
        dt = rng.uniform(0.01, 5.0)
        xf, Pf = SingleRunEKF(motion).predict(x, P, u, dt)
        xb, Pb = BatchEKF(motion).predict(x, P, u, dt)
        assert xf.shape == xb.shape and Pf.shape == Pb.shape
        assert np.allclose(xf, xb, rtol=1e-12, atol=1e-12)
        assert np.allclose(Pf, Pb, rtol=1e-12, atol=1e-12)


def test_single_run_prediction_of_the_current_state_is_eq_17_in_its_written_order():
    """The per-tick prediction of the position-and-current state is ``x + (dt S sin C,
    dt S cos C, -dz, 0, 0) + dt (c_e, c_n, 0, 0, 0)`` added in that order, bit for bit (the
    navigator's numbers do not depend on how the single-run path stores them)."""
    import math

    rng = np.random.default_rng(22)
    for _ in range(200):
        x = rng.normal(0, 100, (1, 5))
        x[0, 3:] = rng.normal(0, 0.3, 2)
        P = _spd(rng, 5)[None]
        c, s, dz = rng.uniform(-7, 7), rng.uniform(0, 2), rng.normal(0, 0.3)
        dt = rng.uniform(0.01, 5.0)
        xf, _ = SingleRunEKF(CURRENT).predict(x, P, np.array([[c, s, dz]]), dt)
        expected = x.copy()
        expected[0, :3] += [dt * s * math.sin(c), dt * s * math.cos(c), -dz]
        expected[0, :2] += dt * x[0, 3:5]
        assert np.array_equal(xf, expected)


def _measurement_cases(rng, model, d, n=60):
    """States near the transceiver (some vertically above it: azimuth inactive), covariances,
    and measurements of nearby truths with a gross error on every fifth."""
    x = np.zeros((n, d))
    x[:, :3] = TX + rng.normal(0, 30, (n, 3)) * [1, 1, 0.1]
    x[::7, :2] = TX[:2] + rng.uniform(-0.5, 0.5, (len(x[::7]), 2))
    x[:, 3:] = rng.normal(0, 0.3, (n, d - 3))
    P = np.stack([_spd(rng, d) for _ in range(n)])
    truth = x + rng.normal(0, 1.0, x.shape)
    z = model.h(truth)
    z[::5, 0] += 40.0 * model.R()[0, 0] ** 0.5 + 5.0
    return x, P, z


@pytest.mark.parametrize("dim", [3, 5])
@pytest.mark.parametrize("gate", [None, 0.95])
@pytest.mark.parametrize(
    "model",
    [USBL, HorizontalPositionMeasurement(1.5), DepthMeasurement(0.1)],
    ids=["usbl", "gps", "depth"],
)
def test_single_run_update_equals_the_batched_update(model, gate, dim):
    rng = np.random.default_rng(5)
    x, P, z = _measurement_cases(rng, model, dim)
    present = np.arange(len(x)) % 9 != 4
    xb, Pb, ib = BatchEKF(MOTION).update(x, P, model, z, present, gate)
    fast = SingleRunEKF(MOTION)
    for i in range(len(x)):
        xo, Po, io = fast.update(
            x[i : i + 1], P[i : i + 1], model, z[i : i + 1], present[i : i + 1], gate
        )
        assert np.allclose(xo, xb[i : i + 1], rtol=1e-12, atol=1e-12)
        assert np.allclose(Po, Pb[i : i + 1], rtol=1e-12, atol=1e-12)
        assert io.applied[0] == ib.applied[i] and io.rejected[0] == ib.rejected[i]
        assert io.dof[0] == ib.dof[i]
        assert io.nis[0] == pytest.approx(ib.nis[i], rel=1e-12, nan_ok=True)
    # every branch was taken: applied, absent, and (with the gate) rejected
    assert ib.applied.any() and (~present).any()
    assert ib.rejected.any() == (gate is not None)
    if model is USBL:
        assert (ib.dof == 2).any()  # the azimuth was inactive above the transceiver


def test_single_run_update_on_components_equals_the_batched_update():
    rng = np.random.default_rng(11)
    for d, m in [(3, 3), (5, 3), (5, 1), (5, 2)]:
        for _ in range(20):
            P = _spd(rng, d)[None]
            x = rng.normal(size=(1, d))
            H = rng.normal(size=(1, m, d))
            y = rng.normal(size=(1, m))
            R = np.diag(rng.uniform(0.1, 1.0, m))
            active = rng.random((1, m)) > 0.3
            for gate in (None, 0.9):
                xb, Pb, ib = update(x, P, y, H, R, active, None, gate)
                xo, Po, io = update_one(x, P, y, H, R, active, gate)
                assert np.allclose(xb, xo, rtol=1e-12, atol=1e-12)
                assert np.allclose(Pb, Po, rtol=1e-12, atol=1e-12)
                assert ib.rejected[0] == io.rejected[0] and ib.applied[0] == io.applied[0]
                assert ib.nis[0] == pytest.approx(io.nis[0], rel=1e-12, nan_ok=True)


@pytest.mark.parametrize("m", [1, 2, 3, 4])
def test_small_spd_inverse_equals_numpy(m):
    from nav.ekf import inverse_spd_small

    rng = np.random.default_rng(m)
    A = rng.normal(size=(200, m, m))
    S = A @ np.swapaxes(A, 1, 2) + 0.05 * np.eye(m)
    np.testing.assert_allclose(inverse_spd_small(S), np.linalg.inv(S), rtol=1e-9, atol=1e-9)
    bad = S.copy()
    bad[3] = 0.0
    with pytest.raises(NavInputError):
        inverse_spd_small(bad)


# --------------------------------------------------------------------------------------------
# The gate's chi-square quantile, against closed forms


def _chi2_quantile(p, dof):
    """The chi-square quantile from closed forms, with nothing of the code or scipy: dof 1 is the
    squared normal quantile, dof 2 the exponential's (mean 2), dof 3 solves the closed-form CDF
    ``erf(sqrt(x / 2)) - sqrt(2 x / pi) exp(-x / 2)`` by bisection."""
    from statistics import NormalDist

    if dof == 1:
        return NormalDist().inv_cdf((1 + p) / 2) ** 2
    if dof == 2:
        return -2.0 * math.log1p(-p)
    assert dof == 3
    lo, hi = 0.0, 100.0
    for _ in range(200):
        x = 0.5 * (lo + hi)
        cdf = math.erf(math.sqrt(x / 2)) - math.sqrt(2 * x / math.pi) * math.exp(-x / 2)
        lo, hi = (x, hi) if cdf < p else (lo, x)
    return 0.5 * (lo + hi)


def test_gate_limit_is_the_chi_square_quantile_of_the_innovations_dimension():
    from nav.ekf import gate_limit

    # the closed forms reproduce the printed table (95 %: 3.8415, 5.9915, 7.8147)
    assert [round(_chi2_quantile(0.95, d), 4) for d in (1, 2, 3)] == [3.8415, 5.9915, 7.8147]
    for p in (0.9, 0.95, 0.99, 0.999):
        for d in (1, 2, 3):
            assert gate_limit(p, d) == pytest.approx(_chi2_quantile(p, d), rel=1e-9), (p, d)


@pytest.mark.parametrize("probability", [0.95, 0.99])
def test_gate_rejects_exactly_beyond_the_quantile_of_the_active_components(probability):
    """A 3-component measurement with 1, 2 or 3 components active (H = I, P = I, R = I, so S = 2 I
    and NIS = |y|^2 / 2): an innovation whose NIS is 0.1 % inside the closed-form quantile of the
    number of active components is applied, one 0.1 % beyond it is rejected, in the batched update
    and in the single-run one."""
    H, P, R = np.eye(3)[None], np.eye(3)[None], np.eye(3)
    for m in (1, 2, 3):
        active = np.array([[True, True, True][:m] + [False] * (3 - m)])
        limit = _chi2_quantile(probability, m)
        for factor, rejected in ((0.999, False), (1.001, True)):
            y = np.zeros((1, 3))
            y[0, :m] = math.sqrt(2 * factor * limit / m)
            _, _, info = update(np.zeros((1, 3)), P, y, H, R, active, None, probability)
            assert info.nis[0] == pytest.approx(factor * limit, rel=1e-12)
            assert info.dof[0] == m
            assert info.rejected[0] == rejected and info.applied[0] != rejected, (m, factor)
            _, _, one = update_one(np.zeros((1, 3)), P, y, H, R, active, probability)
            assert one.rejected[0] == rejected and one.applied[0] != rejected, (m, factor)
