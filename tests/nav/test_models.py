"""Motion and measurement models against finite differences and the paper's formulas."""

import math

import numpy as np
import pytest

from nav.models import (
    CourseSpeedDepthMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    UsblMeasurement,
)
from nav.usbl.accuracy import dr_step_covariance

RNG = np.random.default_rng(2024)
TX = np.array([12.0, -7.0, -6.0])
USBL = UsblMeasurement(TX, 0.2, math.radians(3), math.radians(3), min_horizontal_m=1.0)
MOTION = CourseSpeedDepthMotion(math.radians(8), 0.257, 0.25)


def numeric_jacobian(fn, x, eps=1e-4):
    cols = []
    for j in range(x.shape[-1]):
        dx = np.zeros_like(x)
        dx[..., j] = eps
        diff = fn(x + dx) - fn(x - dx)
        diff[..., 1] = (diff[..., 1] + np.pi) % (2 * np.pi) - np.pi  # azimuth wraps
        cols.append(diff / (2 * eps))
    return np.stack(cols, axis=-1)


def test_usbl_jacobian_matches_finite_differences():
    x = TX + RNG.uniform(-400, 400, (200, 3)) * np.array([1, 1, 0.02])
    x[:, 2] = -3.0
    H = USBL.H(x)
    H_num = numeric_jacobian(USBL.h, x)
    assert np.allclose(H, H_num, rtol=1e-6, atol=1e-9)


def test_usbl_measurement_definition_matches_seed000_eq15():
    # vehicle at depth 3 m, transceiver at depth 6 m (seed 000 Figure 7), depth positive down
    x = np.array([[TX[0] + 30.0, TX[1] + 40.0, -3.0]])
    r, a, b = USBL.h(x)[0]
    dzd = 3.0 - 6.0  # z1 - z with depth coordinates
    assert r == pytest.approx(math.sqrt(30**2 + 40**2 + dzd**2))
    assert a == pytest.approx(math.atan2(30, 40))
    assert b == pytest.approx(-math.atan(dzd / 50.0))


def test_usbl_invert_round_trip_and_fix_covariance():
    x = TX + RNG.uniform(-300, 300, (50, 3))
    assert np.allclose(USBL.invert(USBL.h(x)), x, atol=1e-9)
    z = USBL.h(x)
    # first-order covariance equals J R J^T with J from finite differences of the inverse
    eps = 1e-6
    cols = []
    for j in range(3):
        dz = np.zeros_like(z)
        dz[:, j] = eps
        cols.append((USBL.invert(z + dz) - USBL.invert(z - dz)) / (2 * eps))
    J = np.stack(cols, axis=-1)
    assert np.allclose(
        USBL.fix_covariance(z), J @ USBL.R() @ np.swapaxes(J, -1, -2), rtol=1e-5, atol=1e-8
    )


def test_usbl_vertical_geometry_is_finite_and_drops_azimuth():
    above = np.array([[TX[0], TX[1], -3.0], [TX[0] + 0.3, TX[1] - 0.2, -3.0]])
    H = USBL.H(above)
    assert np.all(np.isfinite(H)) and np.all(np.isfinite(USBL.h(above)))
    act = USBL.active(above)
    assert not act[:, 1].any() and act[:, [0, 2]].all()
    assert np.all(H[:, 1] == 0.0)


def _plain_residual(z, hx):
    # eq. 19 with the angles wrapped, no folding (the measurement as the chart of h reads it)
    y = np.asarray(z, dtype=float) - hx
    y[..., 1:] = (y[..., 1:] + np.pi) % (2 * np.pi) - np.pi
    return y


@pytest.mark.parametrize("up", [True, False])
def test_usbl_residual_folds_a_fix_past_the_pole_back_against_the_prediction(up):
    """A fix whose elevation error carries it over the zenith (or under the nadir) is reported as
    the direction over the top (azimuth + pi); its innovation against a prediction on the near
    side must be the small one of the unfolded direction, not an azimuth innovation of pi."""
    sign = 1.0 if up else -1.0
    # predicted vehicle 2 m north of the point straight above (below) the transceiver, 30 m up
    x = np.array([[TX[0], TX[1] + 2.0, TX[2] + sign * 30.0]])
    hx = USBL.h(x)
    a_pred, b_pred = hx[0, 1], hx[0, 2]
    assert abs(abs(b_pred) - math.pi / 2) < math.radians(4)
    # the true direction: 8 deg of elevation beyond the pole from the prediction, same azimuth
    db = sign * math.radians(8.0)
    b_true = b_pred + db  # past +-90 deg
    assert abs(b_true) > math.pi / 2
    # what the USBL reports (its own fold, independent of the model): azimuth + pi, pi - beta
    a_rep = (a_pred + math.pi) % (2 * math.pi)
    b_rep = (math.pi - b_true) if up else (-math.pi - b_true)
    assert abs(b_rep) <= math.pi / 2
    z = np.array([[hx[0, 0], a_rep, b_rep]])
    y = USBL.residual(z, hx)
    assert y[0, 1] == pytest.approx(0.0, abs=1e-12)
    assert y[0, 2] == pytest.approx(db, abs=1e-12)
    # the plain wrapped difference is the wrong chart: an azimuth innovation of pi
    assert abs(_plain_residual(z, hx)[0, 1]) == pytest.approx(math.pi, abs=1e-12)


def test_usbl_residual_away_from_the_pole_is_the_wrapped_difference():
    x = TX + RNG.uniform(-300, 300, (500, 3)) * np.array([1, 1, 0.05])
    hx = USBL.h(x)
    z = USBL.h(x + RNG.normal(0, 2.0, x.shape))
    assert np.array_equal(USBL.residual(z, hx), _plain_residual(z, hx))


def test_motion_increment_and_jacobians():
    u = np.column_stack(
        [RNG.uniform(0, 2 * np.pi, 40), RNG.uniform(0.2, 2, 40), RNG.normal(0, 0.3, 40)]
    )
    x = RNG.normal(0, 50, (40, 3))
    dt = 1.5
    fx = MOTION.f(x, u, dt)
    assert np.allclose(fx[:, 0], x[:, 0] + dt * u[:, 1] * np.sin(u[:, 0]))  # east: S sin C
    assert np.allclose(fx[:, 1], x[:, 1] + dt * u[:, 1] * np.cos(u[:, 0]))  # north: S cos C
    assert np.allclose(fx[:, 2], x[:, 2] - u[:, 2])  # depth increase lowers z
    eps = 1e-6
    cols = []
    for j in range(3):
        du = np.zeros_like(u)
        du[:, j] = eps
        cols.append((MOTION.f(x, u + du, dt) - MOTION.f(x, u - du, dt)) / (2 * eps))
    assert np.allclose(MOTION.G(u, dt), np.stack(cols, -1), atol=1e-7)


def test_process_noise_horizontal_block_is_seed000_eq10():
    u = np.column_stack([RNG.uniform(0, 2 * np.pi, 30), RNG.uniform(0.2, 2, 30), np.zeros(30)])
    Q = MOTION.Q(u, 1.0)
    P10 = dr_step_covariance(u[:, 0], u[:, 1], 1.0, MOTION.sigma_course_rad, MOTION.sigma_speed_m_s)
    assert np.allclose(Q[:, :2, :2], P10, rtol=1e-12, atol=1e-15)
    assert np.allclose(Q[:, 2, 2], 0.25**2) and np.allclose(Q[:, :2, 2], 0)
    G = MOTION.G(u, 1.0)
    var = np.diag([MOTION.sigma_course_rad**2, MOTION.sigma_speed_m_s**2, 0.25**2])
    np.testing.assert_allclose(Q, G @ var @ np.swapaxes(G, 1, 2), rtol=1e-13, atol=1e-16)


def test_increment_of_one_run_is_the_batched_increment():
    u = np.column_stack(
        [RNG.uniform(-7, 7, 200), RNG.uniform(0.0, 2, 200), RNG.normal(0, 0.3, 200)]
    )
    one = np.array([MOTION.increment_one(row, 0.7) for row in u])
    np.testing.assert_array_max_ulp(one, MOTION.increment(u, 0.7), maxulp=2)


@pytest.mark.parametrize(
    "model",
    [USBL, HorizontalPositionMeasurement(2.0), DepthMeasurement(0.1)],
    ids=["usbl", "gps", "depth"],
)
def test_position_measurements_read_the_position_of_a_longer_state(model):
    x3 = TX + RNG.uniform(-50, 50, (30, 3))
    x3[:3, :2] = TX[:2]  # straight above the transceiver: the USBL azimuth is inactive
    x5 = np.column_stack([x3, RNG.normal(0, 0.3, (30, 2))])
    assert np.array_equal(model.h(x5), model.h(x3))
    assert np.array_equal(model.active(x5), model.active(x3))
    H5 = model.H(x5)
    assert H5.shape[-1] == 5
    assert np.array_equal(H5[..., :3], model.H(x3)) and np.all(H5[..., 3:] == 0.0)


def test_usbl_noise_is_seed000s_diag_of_range_azimuth_elevation_variances():
    """Seed 000, eq. 23: ``R = diag(sigma_r^2, sigma_alpha^2, sigma_beta^2)`` in the order of the
    measurement (range, azimuth, elevation), here with three different sigmas; and the USBL-only
    fix's stated covariance is the scatter of fixes inverted from measurements drawn in the test
    with those sigmas (2e5 draws: each variance within 2 %, 6.7 standard errors; the inverse is
    nonlinear by ~sigma^2, 0.07 % here)."""
    s_r, s_a, s_b = 0.2, math.radians(0.5), math.radians(1.5)
    usbl = UsblMeasurement(TX, s_r, s_a, s_b)
    np.testing.assert_array_equal(usbl.R(), np.diag([s_r**2, s_a**2, s_b**2]))
    x = TX + np.array([60.0, 80.0, 20.0])
    z0 = usbl.h(x[None])[0]
    n = 200_000
    noise = np.random.default_rng(5).normal(0.0, [s_r, s_a, s_b], (n, 3))
    fixes = usbl.invert(z0 + noise)
    emp = np.cov(fixes.T)
    stated = usbl.fix_covariance(z0)
    np.testing.assert_allclose(np.diag(emp), np.diag(stated), rtol=0.02)
    corr = stated / np.sqrt(np.outer(np.diag(stated), np.diag(stated)))
    emp_corr = emp / np.sqrt(np.outer(np.diag(emp), np.diag(emp)))
    np.testing.assert_allclose(emp_corr, corr, atol=0.02)
