"""Seed 000 eq. 1-14 against the paper's numbers and an eigen-decomposition."""

import math

import numpy as np
import pytest

from nav.usbl import accuracy as acc


def test_usbl_mean_error_at_500_m_is_26_2():
    assert acc.usbl_mean_error(500.0, 0.2, math.radians(3)) == pytest.approx(26.2, abs=0.05)


def test_usbl_position_lines_from_gradients():
    # eq. 3-4: sigma / |grad|, with grad of alpha = atan(x/y) and of r = sqrt(x^2 + y^2)
    x, y, eps = 120.0, -310.0, 1e-6
    ga = [
        (math.atan2(x + eps, y) - math.atan2(x - eps, y)) / (2 * eps),
        (math.atan2(x, y + eps) - math.atan2(x, y - eps)) / (2 * eps),
    ]
    la, lr = acc.usbl_position_line_errors(math.hypot(x, y), 0.2, math.radians(3))
    assert la == pytest.approx(math.radians(3) / math.hypot(*ga), rel=1e-6)
    assert lr == pytest.approx(0.2)
    a, b = acc.usbl_ellipse(500.0, 0.2, math.radians(3))
    assert a == pytest.approx(500 * math.radians(3)) and b == pytest.approx(0.2)


def test_dr_single_step_gives_25_54_m_per_100_m():
    P = acc.dr_covariance_single_step(
        np.array([100.0, 500.0]), math.radians(90), 1.0, math.radians(3), 0.25
    )
    m = acc.mean_error(P)
    assert m[0] == pytest.approx(25.54, abs=0.005)
    assert m[1] == pytest.approx(127.7, abs=0.05)  # seed 000 section 3


def test_dr_random_walk_grows_with_sqrt_t():
    P = acc.dr_covariance_random_walk(np.array([100.0, 400.0]), 1.0, 1.0, 0.05, 0.25)
    m = acc.mean_error(P)
    assert m[1] / m[0] == pytest.approx(2.0)
    one = acc.dr_step_covariance(1.0, 1.0, 1.0, 0.05, 0.25)
    assert np.allclose(P[0], 100 * one)


def test_ellipse_parameters_agree_with_eigendecomposition():
    rng = np.random.default_rng(0)
    A = rng.normal(0, 3, (500, 2, 2))
    P = A @ np.swapaxes(A, 1, 2)
    e = acc.ellipse_parameters(P)
    w, V = np.linalg.eigh(P)
    assert np.allclose(e.a, np.sqrt(w[:, 1])) and np.allclose(e.b, np.sqrt(w[:, 0]))
    major = V[:, :, 1]
    # tau is the direction of the major eigenvector (mod pi)
    d = (np.arctan2(major[:, 1], major[:, 0]) - e.tau) % np.pi
    assert np.allclose(np.minimum(d, np.pi - d), 0, atol=1e-9)
    # where sx2 > sy2, eq. 14's one-argument form gives the same angle
    sel = P[:, 0, 0] > P[:, 1, 1]
    tau14 = 0.5 * np.arctan(2 * P[sel, 0, 1] / (P[sel, 0, 0] - P[sel, 1, 1]))
    assert np.allclose(tau14, e.tau[sel])


def test_dr_ellipse_major_axis_follows_course_and_b_equals_usbl_a():
    # seed 000 Figure 6: with COG 90 deg the largest error lies along the course, and b equals
    # the USBL ellipse's a at the same distance (sigma_COG = sigma_alpha = 3 deg)
    P = acc.dr_covariance_single_step(500.0, math.radians(90), 1.0, math.radians(3), 0.25)
    e = acc.ellipse_parameters(P)
    assert float(e.tau) == pytest.approx(0.0, abs=1e-12)
    assert float(e.azimuth_rad) == pytest.approx(math.pi / 2)
    assert float(e.b) == pytest.approx(acc.usbl_ellipse(500.0, 0.2, math.radians(3))[0])
