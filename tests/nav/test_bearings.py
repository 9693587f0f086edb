"""Seed 004's navigation against independent truth: eq. 17 and its Jacobian, the EKF against
filterpy, the UPMF's pseudo-measurements and bias, the locally optimal control (full information
gives J = trace(S^W)), the box-limited control against brute force, the CMNF's stated accuracy on
fresh paths, the PCRB against the Kalman filter, and bad geometry."""

import math
from functools import partial

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from bauv_sim.kinematic.seed004 import (
    SECTION6_BEACONS,
    NominalPathConfig,
    PathNoise,
    Seed004Noise,
    Seed004World,
    TrainingNoise,
    true_bearings,
)
from nav.bearings import (
    PredictedShift,
    SystemPrediction,
    bearing_jacobian,
    bearings,
    ekf_update,
    pinv_floor,
    predict,
    pseudo_measurements,
    upmf_update,
    velocity,
)
from nav.bearings.cmnf import CmnfGains, cmnf_step, train
from nav.bearings.local_control import ControlLimits, limited_control, optimal_control
from nav.bearings.pcrb import bearing_information, pcrb
from nav.errors import NavInputError

B = np.array(SECTION6_BEACONS)
S_EPS = math.tan(math.radians(0.5)) ** 2 * np.eye(2)


def _points(n=50, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform([-50, -60, -30], [450, 60, -1], size=(n, 3))


def test_bearings_are_eq17_with_the_full_bearing_and_match_the_world():
    x = _points()
    h, ok = bearings(x, B)
    assert ok.all()
    for i in range(len(x)):
        for b in range(len(B)):
            dx, dy, dz = B[b] - x[i]
            phi = math.atan2(dy, dx)  # the full bearing
            assert h[i, b, 0] == pytest.approx(dy / dx, rel=1e-12)
            assert h[i, b, 1] == pytest.approx(dz * math.cos(phi) / dx, rel=1e-12)
    hw, okw = true_bearings(x, B, 1e-3, 1e3)
    np.testing.assert_allclose(hw, h, rtol=1e-13)
    assert (okw == ok).all()


def test_jacobian_equals_central_finite_differences():
    x = _points(20)
    jac = bearing_jacobian(x, B)
    eps = 1e-5
    for a in range(3):
        dx = np.zeros(3)
        dx[a] = eps
        fd = (bearings(x + dx, B)[0] - bearings(x - dx, B)[0]) / (2 * eps)
        np.testing.assert_allclose(jac[..., a], fd, rtol=1e-6, atol=1e-10)


def test_pseudo_measurements_are_linear_in_the_state_without_noise():
    x = _points()
    h, _ = bearings(x, B)
    yp, psi1, psi2 = pseudo_measurements(h, x, B)
    np.testing.assert_allclose(yp, np.einsum("nbij,nj->nbi", psi1, x), rtol=1e-9, atol=1e-9)
    # eq. 20's noise term: a tangent error e gives Psi2 e to first order (Psi2 = dx cos phi, dx
    # cos lambda times the derivative of the angle, which eq. 19 takes exactly)
    assert psi2.shape == (len(x), len(B), 2)


def test_ekf_step_equals_filterpys_extended_kalman_filter_on_one_path():
    rng = np.random.default_rng(3)
    s_w = np.diag([1.0, 0.5, 0.2])
    x_true = np.array([10.0, 5.0, -12.0])
    x_hat = np.array([[11.0, 4.0, -11.0]])
    P = np.diag([2.0, 3.0, 1.5])[None]
    f = ExtendedKalmanFilter(dim_x=3, dim_z=8, dim_u=3)
    f.x = x_hat[0].copy()
    f.P = P[0].copy()
    f.F = np.eye(3)
    f.B = np.eye(3)
    f.Q = s_w
    f.R = np.kron(np.eye(4), S_EPS)
    pred = SystemPrediction(1.0, s_w)
    for k in range(15):
        u = np.array([[0.05, 0.3, 2.0]])
        x_true = x_true + velocity(u[0]) + rng.normal(0, 0.5, 3)
        y = bearings(x_true[None], B)[0] + rng.normal(0, math.sqrt(S_EPS[0, 0]), (1, 4, 2))
        x_t, P_t = predict(x_hat, P, pred(k, x_hat, u))
        x_hat, P = ekf_update(x_t, P_t, y, np.ones((1, 4), bool), B, S_EPS)
        f.predict(u=velocity(u[0]))
        f.update(
            y.reshape(8),
            HJacobian=lambda z: bearing_jacobian(z[None], B).reshape(8, 3),
            Hx=lambda z: bearings(z[None], B)[0].reshape(8),
        )
        np.testing.assert_allclose(x_hat[0], f.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P[0], f.P, rtol=1e-8, atol=1e-12)


def test_locally_optimal_control_lands_on_the_next_nominal_point():
    path = NominalPathConfig()
    xn, vn = path.path(), path.velocities()
    x = _points(30)
    for k in (0, 17, 150):
        u = optimal_control(x, xn[k], vn[k], 1.0)
        np.testing.assert_allclose(
            x + velocity(u) * 1.0, np.broadcast_to(xn[k + 1], x.shape), atol=1e-9
        )
        # the independent geometry of Lemma 1: aim at d, horizontal distance in gamma
        d = xn[k] - x + vn[k]
        np.testing.assert_allclose(u[:, 1], np.arctan2(d[:, 1], d[:, 0]))
        np.testing.assert_allclose(u[:, 2], np.linalg.norm(d, axis=1))


def test_full_information_control_gives_j_equal_to_trace_sw():
    path = NominalPathConfig(duration_s=40.0)
    noise = Seed004Noise()
    n = 20_000
    world = Seed004World(path, noise, B, TrainingNoise(noise, 4, 11, n))
    xn, vn = path.path(), path.velocities()
    x = world.start()
    J = []
    for k in range(path.n_steps):
        x = world.advance(k, x, optimal_control(x, xn[k], vn[k], path.dt_s))
        J.append(np.mean(np.sum((x - xn[k + 1]) ** 2, axis=1)))
    J = np.array(J)
    # ||W||^2 ~ chi^2(3): mean 3, variance 6; each J_k is a mean of n
    se = math.sqrt(6 / n)
    assert np.all(np.abs(J - 3.0) < 4.5 * se), (J.min(), J.max())
    assert abs(J.mean() - 3.0) < 4 * se / math.sqrt(len(J))


def test_box_limited_control_is_the_brute_force_optimum():
    rng = np.random.default_rng(5)
    lim = ControlLimits(
        max_turn_rate=math.radians(20),
        max_pitch_rate=math.radians(5),
        max_gamma=math.radians(15),
        v_min=0.5,
        v_max=2.5,
    )
    x = rng.normal([0, 0, -10], 3.0, (12, 3))
    xn, vn = np.array([0.0, 0.0, -10.0]), np.array([2.0, 0.0, 0.1])
    up = np.column_stack([rng.uniform(-0.2, 0.2, 12), rng.uniform(-3, 3, 12), np.full(12, 2.0)])
    u = limited_control(x, xn, vn, 1.0, up, lim)
    d = xn - x + vn
    g = np.linspace(-1, 1, 61)
    for i in range(len(x)):
        th = up[i, 1] + g * lim.max_turn_rate
        ga = np.clip(up[i, 0] + g * lim.max_pitch_rate, -lim.max_gamma, lim.max_gamma)
        v = np.linspace(lim.v_min, lim.v_max, 81)
        G, T, V = np.meshgrid(ga, th, v, indexing="ij")
        e = velocity(np.stack([G, T, V], -1))
        cost = np.sum((d[i] - e) ** 2, axis=-1)
        best = cost.min()
        got = np.sum((d[i] - velocity(u[i])) ** 2)
        assert got <= best + 1e-9
        assert abs(u[i, 1] - up[i, 1]) <= lim.max_turn_rate + 1e-12
        assert abs(u[i, 0]) <= lim.max_gamma + 1e-12
        assert lim.v_min <= u[i, 2] <= lim.v_max
    wide = ControlLimits(math.pi, math.pi, math.radians(89), 0.0, 100.0)
    x2 = rng.normal([0, 0, -10], 0.5, (8, 3))
    up2 = optimal_control(x2, xn, vn, 1.0)
    np.testing.assert_allclose(
        limited_control(x2, xn, vn, 1.0, up2, wide), optimal_control(x2, xn, vn, 1.0), atol=1e-12
    )


def _closed_loop(path, noise, n, seed, update):
    draws = PathNoise(noise, path.n_steps, 4, seed, tuple(range(n)))
    world = Seed004World(path, noise, B, draws)
    xn, vn = path.path(), path.velocities()
    pred = SystemPrediction(path.dt_s, noise.s_w)
    x = world.start()
    x_hat = np.broadcast_to(xn[0], (n, 3)).copy()
    P = np.broadcast_to(noise.s_0, (n, 3, 3)).copy()
    errs = []
    for k in range(path.n_steps):
        u = optimal_control(x_hat, xn[k], vn[k], path.dt_s)
        x_t, P_t = predict(x_hat, P, pred(k, x_hat, u))
        x = world.advance(k, x, u)
        y, present = world.observe(k + 1, x)
        x_hat, P = update(x_t, P_t, y, present, B, noise.s_eps)
        errs.append(x - x_hat)
    return np.array(errs), P


@pytest.mark.slow
def test_upmf_is_unbiased_on_1e4_paths():
    path = NominalPathConfig(duration_s=30.0)
    e, _ = _closed_loop(path, Seed004Noise(), 10_000, 4, upmf_update)
    m, se = e.mean(1), e.std(1) / math.sqrt(e.shape[1])
    assert np.all(np.abs(m) < 3 * se), np.abs(m / se).max()
    # the gain of eq. 21 as printed (measured angles) is biased in x on the same draws
    p, _ = _closed_loop(path, Seed004Noise(), 10_000, 4, partial(upmf_update, form="printed"))
    z = p.mean(1) / (p.std(1) / math.sqrt(p.shape[1]))
    assert z[:, 0].mean() > 2.0


def test_upmf_with_the_printed_true_state_in_the_innovation_would_not_be_a_filter():
    # eq. 21 as printed uses Psi1 X_k (the truth) in the innovation; the filter uses the
    # prediction: check that the estimate does not depend on the truth beyond the measurement
    x_t = _points(5)
    P = np.broadcast_to(np.eye(3), (5, 3, 3)).copy()
    y = bearings(x_t + 1.0, B)[0]
    a = upmf_update(x_t, P, y, np.ones((5, 4), bool), B, S_EPS)[0]
    assert np.isfinite(a).all()
    assert np.abs(a - x_t).max() > 0.1  # the measurement moved it


@pytest.mark.slow
@pytest.mark.parametrize("correction", ["residual", "pseudo"])
def test_cmnf_stated_covariance_is_within_10_percent_of_the_empirical_one_on_fresh_paths(
    correction,
):
    path = NominalPathConfig(duration_s=40.0)
    noise = Seed004Noise()
    xn, vn = path.path(), path.velocities()
    pred = SystemPrediction(path.dt_s, noise.s_w)

    def control(k, x_hat):
        return optimal_control(x_hat, xn[k], vn[k], path.dt_s)

    world = Seed004World(path, noise, B, TrainingNoise(noise, 4, 21, 6000))
    gains, trace = train(
        world, xn[0], path.n_steps, control, pred, B, correction=correction, nominal=xn
    )
    # the reading notes: with the eq. 7 control the prediction is the nominal point, F_k = 0
    assert np.abs(gains.F).max() < 1e-6
    n = 6000
    fresh = Seed004World(path, noise, B, PathNoise(noise, path.n_steps, 4, 22, tuple(range(n))))
    x = fresh.start()
    x_hat = np.broadcast_to(xn[0], (n, 3)).copy()
    ratios = []
    for k in range(path.n_steps):
        u = control(k, x_hat)
        alpha = x_hat + pred(k, x_hat, u).displacement_m
        x = fresh.advance(k, x, u)
        y, present = fresh.observe(k + 1, x)
        _, x_hat = cmnf_step(gains, k + 1, alpha, correction, y, present, B)
        emp = np.mean(np.sum((x - x_hat) ** 2, axis=1))
        ratios.append(np.trace(gains.p_hat[k]) / emp)
    ratios = np.array(ratios)
    assert np.all(np.abs(ratios - 1) < 0.10), (ratios.min(), ratios.max())
    # and the training trace agrees with eq. 4: J_{k+1} = 3 + E||e_k||^2
    np.testing.assert_allclose(trace.j[2:], 3 + trace.mse[1:-1], rtol=0.06)


def test_cmnf_gains_round_trip_as_plain_npz(tmp_path):
    rng = np.random.default_rng(0)
    g = CmnfGains(
        F=rng.normal(size=(4, 3, 3)),
        f=rng.normal(size=(4, 3)),
        H=rng.normal(size=(4, 3, 8)),
        h=rng.normal(size=(4, 3)),
        p_tilde=rng.normal(size=(4, 3, 3)),
        p_hat=rng.normal(size=(4, 3, 3)),
        info={"seed": 3, "correction": "residual"},
    )
    p = g.save(tmp_path / "g.npz")
    with np.load(p, allow_pickle=False) as z:
        assert all(z[k].dtype != object for k in z.files)
    back = CmnfGains.load(p)
    for k in ("F", "f", "H", "h", "p_tilde", "p_hat"):
        np.testing.assert_array_equal(getattr(back, k), getattr(g, k))
    assert back.info == g.info


def test_pinv_floor_zeroes_rounding_noise_and_inverts_regular_matrices():
    a = np.full((3, 3), 1e-30) + 1e-31 * np.eye(3)
    assert np.abs(pinv_floor(a, 1e-9)).max() == 0.0
    assert np.abs(np.linalg.pinv(a)).max() > 1e20  # the relative cut-off would amplify it
    m = np.array([[2.0, 0.3], [0.3, 1.0]])
    np.testing.assert_allclose(pinv_floor(m, 1e-9), np.linalg.inv(m), rtol=1e-12)


def test_pcrb_of_a_linear_gaussian_model_is_the_kalman_covariance():
    rng = np.random.default_rng(2)
    F = np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.1], [0.0, 0.0, 0.95]])
    Q = np.diag([0.1, 0.2, 0.05])
    H = rng.normal(size=(2, 3))
    R = np.diag([0.5, 0.3])
    P0 = np.diag([4.0, 2.0, 1.0])
    N = 25
    info = np.broadcast_to(H.T @ np.linalg.inv(R) @ H, (N, 3, 3))
    bound = pcrb(np.linalg.inv(P0), Q, info, f=F)
    P = P0
    np.testing.assert_allclose(bound[0], P0)
    for k in range(N):
        P = F @ P @ F.T + Q
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        P = (np.eye(3) - K @ H) @ P
        np.testing.assert_allclose(bound[k + 1], P, rtol=1e-9, atol=1e-12)


def test_bearing_information_is_the_jacobians_fisher_information():
    x = _points(6)
    jac = bearing_jacobian(x, B)
    info = bearing_information(x, B, S_EPS)
    want = sum(jac[:, b].transpose(0, 2, 1) @ np.linalg.inv(S_EPS) @ jac[:, b] for b in range(4))
    np.testing.assert_allclose(info, want, rtol=1e-12)


def test_beacon_straight_above_makes_no_bearing_and_no_nan():
    above = np.array([[0.0, 0.0, 0.0]])
    x = np.array([[0.0, 0.0, -10.0], [3.0, 1.0, -10.0]])
    h, ok = bearings(x, above)
    assert not ok[0, 0] and ok[1, 0]
    assert np.isfinite(h).all() and np.isfinite(bearing_jacobian(x, above)).all()
    P = np.broadcast_to(np.eye(3), (2, 3, 3)).copy()
    y, present = true_bearings(x, above, 1e-3, 1e3)
    for upd in (ekf_update, upmf_update):
        xh, Ph = upd(x + 0.5, P, y, present, above, S_EPS)
        assert np.isfinite(xh).all() and np.isfinite(Ph).all()
        np.testing.assert_allclose(xh[0], x[0] + 0.5)  # no observation: the prediction stays
        np.testing.assert_allclose(Ph[0], P[0])


def test_predicted_shift_is_added_to_the_estimate_and_its_covariance():
    x = _points(4)
    P = np.broadcast_to(np.eye(3), (4, 3, 3)).copy()
    d = np.arange(12.0).reshape(4, 3)
    c = np.broadcast_to(2 * np.eye(3), (4, 3, 3))
    xt, Pt = predict(x, P, PredictedShift(d, c))
    np.testing.assert_allclose(xt, x + d)
    np.testing.assert_allclose(Pt, 3 * np.broadcast_to(np.eye(3), (4, 3, 3)))


def test_pseudo_noise_mean_is_the_monte_carlo_mean_of_eq20s_noise():
    """The UPMF's correction (its unbiased form takes this mean off Y'): the mean of eq. 20's
    noise term at the true position, ``Y' - Psi1(Y) X`` with ``Y = h(X) + E``, by Monte Carlo
    with antithetic draws (the odd orders cancel pairwise), against the second-order formula;
    beacons west (phi in the left half-plane) and east, below and above the vehicle's depth."""
    from nav.bearings import pseudo_noise_mean

    beacons = np.array([[-80.0, 30.0, 0.0], [120.0, -40.0, 5.0]])
    x = np.array([[0.0, 0.0, -10.0]])
    h, ok = bearings(x, beacons)
    assert ok.all()
    sig = 0.02  # fourth-order terms ~ sig^2 relative: 0.04 %
    want = pseudo_noise_mean(x, h, beacons, sig**2 * np.eye(2))[0]
    n = 200_000
    eps = np.random.default_rng(0).normal(0.0, sig, (n, 2, 2))
    xr = np.broadcast_to(x, (n, 3))

    def noise(y):
        yp, psi1, _ = pseudo_measurements(y, xr, beacons)
        return yp - np.einsum("nbij,nj->nbi", psi1, xr)

    r = 0.5 * (noise(h + eps) + noise(h - eps))
    mean, se = r.mean(axis=0), r.std(axis=0) / math.sqrt(n)
    assert np.all(np.abs(want) > 20 * se)  # a mean well resolved by the draws
    assert np.all(np.abs(mean - want) < 0.01 * np.abs(want) + 4 * se), (mean, want, se)


@pytest.mark.slow
def test_upmf_update_is_unbiased_given_a_prediction_at_the_truth():
    """Eq. 20's pseudo-measurement noise ``Psi2 E`` has a mean that is not zero (the measured cos
    phi, cos lambda depend on E); the unbiased UPMF takes it off, so with the prediction at the
    truth the update's error ``K (Psi2 E - mean)`` has zero mean. 1e5 antithetic noise pairs
    (``+E`` and ``-E``: the odd orders cancel pairwise, the mean is unchanged) on section 6's
    beacons at sigma = 0.02 (fourth-order terms ~1e-5 m): the mean error of each coordinate lies
    within 4 standard errors of zero; without the correction it is 35 and 290 standard errors off
    in y and z."""
    n, sig = 100_000, 0.02
    x_true = np.array([200.0, 10.0, -20.0])
    X = np.broadcast_to(x_true, (n, 3)).copy()
    h, ok = bearings(X, B)
    assert ok.all()
    eps = np.random.default_rng(1).normal(0.0, sig, h.shape)
    P = np.broadcast_to(25.0 * np.eye(3), (n, 3, 3)).copy()
    errs = [
        upmf_update(X, P, y, np.ones((n, 4), bool), B, sig**2 * np.eye(2))[0] - X
        for y in (h + eps, h - eps)
    ]
    pair = 0.5 * (errs[0] + errs[1])
    mean, se = pair.mean(axis=0), pair.std(axis=0) / math.sqrt(n)
    assert np.all(np.abs(mean) < 4 * se), mean / se
    assert np.all(errs[0].std(axis=0) > 0.5)  # the measurement moved the estimate


def test_upmf_printed_form_is_eq_19_21_worked_out():
    """Eq. 19-21 as printed (Psi1, Psi2 at the measured angles, the innovation at the prediction),
    written out here per path and beacon with phi put in the quadrant of the beacon seen from the
    prediction (seed README), against ``upmf_update(form="printed")``; two beacons, one west of
    the vehicle, a non-diagonal prior covariance."""
    beacons = np.array([[300.0, 60.0, 0.0], [-150.0, -40.0, -5.0]])
    rng = np.random.default_rng(7)
    x_t = rng.normal([50.0, 0.0, -20.0], [20.0, 20.0, 3.0], (5, 3))
    A = rng.normal(size=(5, 3, 3))
    P = A @ np.swapaxes(A, 1, 2) + np.eye(3)
    y = bearings(x_t + rng.normal(0, 2.0, (5, 3)), beacons)[0] + rng.normal(0, 0.01, (5, 2, 2))
    s_eps = np.diag([1e-4, 2e-4])
    got_x, got_p = upmf_update(x_t, P, y, np.ones((5, 2), bool), beacons, s_eps, form="printed")
    for i in range(5):
        rows1, rows2, yp = [], [], []
        for (xb, yb, zb), (tp, tl) in zip(beacons, y[i], strict=True):
            dx = xb - x_t[i, 0]
            phi = math.atan(tp) + (math.pi if dx < 0 else 0.0)
            lam = math.atan(tl)
            sp, cp, sl, cl = math.sin(phi), math.cos(phi), math.sin(lam), math.cos(lam)
            yp += [xb * sp - yb * cp, xb * sl - zb * cp * cl]  # eq. 19's left-hand side
            rows1 += [[sp, -cp, 0.0], [sl, 0.0, -cp * cl]]  # Psi1
            rows2 += [dx * cp, dx * cl]  # Psi2's diagonal
        psi1, psi2 = np.array(rows1), np.diag(rows2)
        R = np.kron(np.eye(2), s_eps)
        K = P[i] @ psi1.T @ np.linalg.pinv(psi1 @ P[i] @ psi1.T + psi2 @ R @ psi2.T)  # eq. 21
        x_hat = x_t[i] + K @ (np.array(yp) - psi1 @ x_t[i])
        p_hat = (np.eye(3) - K @ psi1) @ P[i]
        np.testing.assert_allclose(got_x[i], x_hat, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(got_p[i], 0.5 * (p_hat + p_hat.T), rtol=1e-9, atol=1e-9)


def test_cmnf_gains_are_eq22_worked_out_on_a_tiny_training_set():
    """Eq. 22's gains written out with numpy's own moments on 40 samples where the order of the
    covariances matters: ``alpha`` and ``beta`` of other dimensions than the state with
    non-symmetric cross-covariances (F_k = cov(X, alpha) cov^+(alpha, alpha), f_k = E X - F_k E
    alpha, and section 5.2's stated covariances)."""
    from nav.bearings.cmnf import DEFAULT_FLOOR, correction_gain, prediction_gain

    rng = np.random.default_rng(3)
    n = 40
    alpha = rng.normal(size=(n, 3)) @ np.array([[2.0, 0.5, 0.0], [0.0, 1.0, -0.7], [0.3, 0.0, 1.5]])
    x = alpha @ np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 3.0], [-1.0, 0.0, 1.0]]).T
    x += rng.normal(0.0, 0.5, (n, 3)) + [10.0, -4.0, 2.0]

    def cov(a, b):
        return np.cov(a.T, b.T, bias=True)[: a.shape[1], a.shape[1] :]

    F, f, p_t = prediction_gain(x, alpha, DEFAULT_FLOOR)
    F_want = cov(x, alpha) @ np.linalg.pinv(cov(alpha, alpha))
    assert np.abs(F_want - F_want.T).max() > 1.0  # a transposed gain would differ
    np.testing.assert_allclose(F, F_want, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(f, x.mean(0) - F_want @ alpha.mean(0), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(p_t, cov(x, x) - F_want @ cov(alpha, x), rtol=1e-9, atol=1e-9)

    x_tilde = alpha @ F_want.T + f
    # beta: noisy linear functions of the prediction error with a mean that is not zero (eq. 22's
    # h_k = -H_k E beta then matters)
    e = x - x_tilde + rng.normal(0.0, 0.3, (n, 3))
    b = np.column_stack([e, rng.normal(size=n)]) @ rng.normal(size=(4, 5)) + [
        3.0,
        -2.0,
        1.0,
        0.5,
        4.0,
    ]
    H, h, p_h = correction_gain(x, x_tilde, b, p_t, DEFAULT_FLOOR)
    H_want = cov(x - x_tilde, b) @ np.linalg.pinv(cov(b, b))
    np.testing.assert_allclose(H, H_want, rtol=1e-8, atol=1e-9)
    assert np.abs(H_want @ b.mean(0)).max() > 0.3
    np.testing.assert_allclose(h, -H_want @ b.mean(0), rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(p_h, p_t - H_want @ cov(b, x - x_tilde), rtol=1e-8, atol=1e-9)


def test_cmnf_prediction_gain_recovers_a_linear_gaussian_model():
    """With ``X = A alpha + a + W`` (A not symmetric, W ~ N(0, Q) independent of alpha), the best
    linear prediction is ``A alpha + a`` with error covariance Q: eq. 22's F_k, f_k and stated
    P~_k on 1e5 samples recover A, a and Q within their sampling error."""
    from nav.bearings.cmnf import DEFAULT_FLOOR, prediction_gain

    rng = np.random.default_rng(4)
    n = 100_000
    A = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 3.0], [-1.0, 0.0, 1.0]])
    a = np.array([10.0, -4.0, 2.0])
    Q = np.diag([0.25, 1.0, 0.5])
    alpha = rng.normal([5.0, 0.0, -3.0], [2.0, 1.0, 1.5], (n, 3))
    x = alpha @ A.T + a + rng.normal(size=(n, 3)) * np.sqrt(np.diag(Q))
    F, f, p_t = prediction_gain(x, alpha, DEFAULT_FLOOR)
    np.testing.assert_allclose(F, A, atol=0.02)  # standard errors ~0.005 / sigma_alpha
    np.testing.assert_allclose(f, a, atol=0.1)
    np.testing.assert_allclose(p_t, Q, atol=0.03)


def test_cmnf_step_is_eq22_with_the_fitted_gains():
    """One CMNF step with given non-symmetric gains is eq. 22 written out per path: ``X~ = F alpha
    + f`` and ``X^ = X~ + H beta + h`` with eq. 24's residual ``beta = Y - Psi(X~)`` (eq. 17's
    tangents at the prediction), for step 2 of a two-step gain set."""
    rng = np.random.default_rng(12)
    F = np.stack([np.eye(3), [[1.0, 0.4, 0.0], [-0.3, 0.9, 0.2], [0.0, 0.5, 1.1]]])
    H = rng.normal(0.0, 3.0, (2, 3, 8))
    gains = CmnfGains(
        F=F,
        f=rng.normal(size=(2, 3)),
        H=H,
        h=rng.normal(size=(2, 3)),
        p_tilde=np.zeros((2, 3, 3)),
        p_hat=np.zeros((2, 3, 3)),
    )
    alpha = _points(6, seed=3)
    y = bearings(alpha + rng.normal(0, 2.0, (6, 3)), B)[0]
    x_tilde, x_hat = cmnf_step(gains, 2, alpha, "residual", y, np.ones((6, 4), bool), B)
    for i in range(6):
        xt = F[1] @ alpha[i] + gains.f[1]
        b = (y[i] - bearings(xt[None], B)[0][0]).ravel()
        np.testing.assert_allclose(x_tilde[i], xt, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(x_hat[i], xt + H[1] @ b + gains.h[1], rtol=1e-12, atol=1e-9)


def test_ekf_with_absent_pairs_is_filterpys_update_on_the_pairs_present():
    """The bearing EKF is nav.ekf's update with the BearingTangents model: a path missing some
    pairs (not measured, or beacon 2 straight above) gets filterpy's EKF update on the pairs it
    has, and a path with none keeps its prediction."""
    rng = np.random.default_rng(8)
    above = B.copy()
    above[1, :2] = [120.0, 30.0]  # path 1 is straight below beacon 2: that pair is unobservable
    x_t = np.array([[100.0, 10.0, -20.0], [120.0, 30.0, -15.0], [60.0, -40.0, -25.0]])
    P_t = np.stack([np.diag([2.0, 3.0, 1.5]), np.diag([1.0, 1.0, 2.0]), np.diag([4.0, 2.0, 1.0])])
    P_t[0, 0, 1] = P_t[0, 1, 0] = 0.4
    y = bearings(x_t + rng.normal(0, 0.7, (3, 3)), above)[0]
    present = np.array([[True, False, True, True], [True, True, True, False], [False] * 4])
    x_hat, P = ekf_update(x_t, P_t, y, present, above, S_EPS)
    for i, use in enumerate([[0, 2, 3], [0, 2], []]):
        if not use:
            assert np.array_equal(x_hat[i], x_t[i]) and np.array_equal(P[i], P_t[i])
            continue
        f = ExtendedKalmanFilter(dim_x=3, dim_z=2 * len(use))
        f.x, f.P, f.R = x_t[i].copy(), P_t[i].copy(), np.kron(np.eye(len(use)), S_EPS)
        sub = above[use]
        f.update(
            y[i, use].reshape(-1),
            HJacobian=lambda z, sub=sub: bearing_jacobian(z[None], sub).reshape(-1, 3),
            Hx=lambda z, sub=sub: bearings(z[None], sub)[0].reshape(-1),
        )
        np.testing.assert_allclose(x_hat[i], f.x, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(P[i], f.P, rtol=1e-10, atol=1e-14)


def test_the_filter_bank_step_is_each_filters_prediction_and_update():
    """bank.step, the one step the table and the mission use: the EKF and the UPMF (either form)
    are eq. 21's prediction and their update, the CMNF is eq. 22 on alpha = X^ + shift with its
    stated covariance of the step; a misspelt filter, a UPMF form or the CMNF without gains is a
    NavInputError."""
    from nav.bearings import bank

    rng = np.random.default_rng(21)
    x_hat = _points(5, seed=4)
    P = np.broadcast_to(np.diag([1.0, 2.0, 0.5]), (5, 3, 3)).copy()
    shift = PredictedShift(rng.normal(0, 2.0, (5, 3)), np.diag([0.3, 0.2, 0.1]))
    y = bearings(x_hat + rng.normal(0, 1.0, (5, 3)), B)[0]
    present = rng.random((5, 4)) > 0.2
    gains = CmnfGains(
        F=rng.normal(size=(3, 3, 3)),
        f=rng.normal(size=(3, 3)),
        H=rng.normal(size=(3, 3, 8)),
        h=rng.normal(size=(3, 3)),
        p_tilde=np.zeros((3, 3, 3)),
        p_hat=np.stack([np.diag([1.0, 2.0, 3.0]) * (k + 1) for k in range(3)]),
    )
    x_t, P_t = x_hat + shift.displacement_m, P + shift.covariance_m2
    for form in ("unbiased", "printed"):
        opts = bank.BankOptions(S_EPS, upmf_form=form, gains=gains)
        for name, update in (("EKF", ekf_update), ("UPMF", upmf_update)):
            got = bank.step(name, 2, x_hat, P, shift, y, present, B, opts)
            kw = {"form": form} if name == "UPMF" else {}
            want = update(x_t, P_t, y, present, B, S_EPS, **kw)
            assert np.array_equal(got.x_tilde, x_t)
            assert np.array_equal(got.x_hat, want[0]) and np.array_equal(got.p_hat, want[1])
        got = bank.step("CMNF", 2, x_hat, P, shift, y, present, B, opts)
        want = cmnf_step(gains, 2, x_hat + shift.displacement_m, "residual", y, present, B)
        assert np.array_equal(got.x_tilde, want[0]) and np.array_equal(got.x_hat, want[1])
        assert np.array_equal(got.p_hat, np.broadcast_to(gains.p_hat[1], (5, 3, 3)))
    assert bank.FILTERS == ("EKF", "UPMF", "CMNF")
    opts = bank.BankOptions(S_EPS)
    for name, o, match in (
        ("ekf", opts, "filter 'ekf': must be one of EKF, UPMF, CMNF"),
        ("CMNF", opts, "filter 'CMNF': needs fitted gains"),
        ("UPMF", bank.BankOptions(S_EPS, upmf_form="eq21"), "upmf_form = 'eq21'"),
    ):
        with pytest.raises(NavInputError, match=match):
            bank.step(name, 1, x_hat, P, shift, y, present, B, o)
