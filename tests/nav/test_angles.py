"""Laws of the navigation angle conversions: ranges, round trips, inverses, known directions and
finite differences, with the expected values written out here."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from nav import angles as an

RNG = np.random.default_rng(2025)
PI = math.pi
# inputs where a floor-modulo rounds to the modulus itself, and the range ends
EDGES = np.array(
    [
        -1e-18,
        -1e-300,
        np.nextafter(-PI, -np.inf),
        -PI,
        PI,
        np.nextafter(PI, np.inf),
        2 * PI,
        -2 * PI,
        np.nextafter(2 * PI, 0.0),
        0.0,
        -0.0,
    ]
)


def test_wrap_ranges_periodicity_and_idempotence():
    a = np.concatenate([RNG.uniform(-50, 50, 2000), EDGES])
    w = an.wrap_pi(a)
    assert np.all((w >= -PI) & (w < PI))
    w2 = an.wrap_2pi(a)
    assert np.all((w2 >= 0) & (w2 < 2 * PI))
    for x in (w, w2):  # the same angle
        assert np.allclose(np.sin(x), np.sin(a), atol=1e-13)
        assert np.allclose(np.cos(x), np.cos(a), atol=1e-13)
    assert np.array_equal(an.wrap_2pi(w2), w2)
    inside = RNG.uniform(0, 2 * PI, 100)
    assert np.array_equal(an.wrap_2pi(inside), inside)
    assert an.wrap_pi(PI) == -PI


def test_scalar_wraps_equal_the_array_wraps():
    a = np.concatenate([RNG.uniform(-50, 50, 500), EDGES])
    assert np.array_equal([an.wrap_pi_scalar(float(x)) for x in a], an.wrap_pi(a))
    assert np.array_equal([an.wrap_2pi_scalar(float(x)) for x in a], an.wrap_2pi(a))
    assert isinstance(an.wrap_pi_scalar(7.0), float)


def test_diff_course_is_the_smaller_angle_between_two_courses():
    a, b = RNG.uniform(-10, 10, 500), RNG.uniform(-10, 10, 500)
    d = an.diff_course(a, b)
    assert np.all((d >= 0) & (d <= PI))
    assert np.allclose(d, an.diff_course(b, a), atol=1e-12)
    # the angle between the unit vectors, written out: acos of their dot product
    dot = np.sin(a) * np.sin(b) + np.cos(a) * np.cos(b)
    assert np.allclose(d, np.arccos(np.clip(dot, -1, 1)), atol=1e-7)
    assert an.diff_course(math.radians(350), math.radians(10)) == pytest.approx(math.radians(20))


def test_unit_vector_cardinal_directions_and_round_trip():
    assert np.allclose(an.unit_vector(0.0), [0, 1], atol=1e-16)  # north is +y
    assert np.allclose(an.unit_vector(PI / 2), [1, 0], atol=1e-16)  # east is +x
    assert np.all(an.unit_vector(math.radians(220)) < 0)  # south-west
    c = RNG.uniform(-20, 20, 500)
    u = an.unit_vector(c)
    assert u.shape == (500, 2) and np.allclose(np.hypot(u[:, 0], u[:, 1]), 1.0)
    assert np.allclose(an.wrap_pi(an.course_of(u) - c), 0, atol=1e-12)
    e, n = an.unit_vector_scalar(math.radians(220))
    assert isinstance(e, float) and e < 0 and n < 0


def test_scalar_vector_forms_equal_the_array_forms_to_an_ulp():
    c = RNG.uniform(-20, 20, 500)
    scalar = np.array([an.unit_vector_scalar(float(x)) for x in c])
    np.testing.assert_array_max_ulp(scalar, an.unit_vector(c), maxulp=1)
    v = RNG.normal(size=(500, 2))
    course = np.array([an.course_of_scalar(float(e), float(n)) for e, n in v])
    np.testing.assert_array_max_ulp(course, an.course_of(v), maxulp=1)


def test_course_of_range_at_the_edges():
    # atan2 of a tiny negative east component is a tiny negative course, which a bare
    # floor-modulo rounds to exactly 2 pi
    for east in (-1e-18, -1e-300, -0.0, 0.0):
        c = an.course_of([east, 1.0])
        assert 0.0 <= c < 2 * PI
        assert 0.0 <= an.course_of_scalar(east, 1.0) < 2 * PI
    assert an.course_of(np.zeros(2)) == 0.0 and an.course_of_scalar(0.0, 0.0) == 0.0
    assert an.course_of([1.0, 0.0, 99.0]) == pytest.approx(PI / 2)  # the up component is ignored


def test_velocity_from_course_speed_and_back_with_broadcasting():
    c = RNG.uniform(0, 2 * PI, (4, 50))
    s = RNG.uniform(0.1, 3, 50)
    v = an.velocity_from_course_speed(c, s)
    assert v.shape == (4, 50, 2)
    # seed 000 eq. 8: dx = S sin C, dy = S cos C
    assert np.allclose(v[..., 0], s * np.sin(c)) and np.allclose(v[..., 1], s * np.cos(c))
    c2, s2 = an.course_speed_from_velocity(v)
    assert np.allclose(an.wrap_pi(c2 - c), 0, atol=1e-12) and np.allclose(s2, s)
    assert an.velocity_from_course_speed(1.0, np.ones(3)).shape == (3, 2)
    c3, s3 = an.course_speed_from_velocity([3.0, -4.0, 12.0])
    assert s3 == pytest.approx(5.0) and c3 == pytest.approx(PI - math.atan(3 / 4))


def test_heading_and_yaw_are_inverse_and_point_the_same_way():
    yaw = RNG.uniform(-10, 10, 300)
    h = an.heading_from_yaw(yaw)
    assert np.all((h >= 0) & (h < 2 * PI))
    # the direction of yaw psi is (cos psi, sin psi) in (east, north); its course is the heading
    assert np.allclose(an.wrap_pi(an.course_of(np.stack([np.cos(yaw), np.sin(yaw)], -1)) - h), 0)
    back = an.yaw_from_heading(h)
    assert np.all((back >= -PI) & (back < PI))
    assert np.allclose(an.wrap_pi(back - yaw), 0, atol=1e-12)
    assert an.heading_from_yaw(0.0) == pytest.approx(PI / 2)  # yaw 0 points east
    assert an.heading_from_yaw(PI / 2) == pytest.approx(0.0, abs=1e-15)  # yaw 90 deg: north


def test_heading_rate_is_the_derivative_of_the_heading():
    eps = 1e-5  # s
    for yaw0, w in [(0.3, 0.2), (-2.0, -1.3), (1.5708, 0.05)]:  # the last crosses north
        change = an.wrap_pi(
            an.heading_from_yaw(yaw0 + w * eps) - an.heading_from_yaw(yaw0 - w * eps)
        )
        assert float(change) / (2 * eps) == pytest.approx(
            an.heading_rate_from_yaw_rate(w), rel=1e-6
        )
        assert an.yaw_rate_from_heading_rate(an.heading_rate_from_yaw_rate(w)) == w
    assert isinstance(an.heading_rate_from_yaw_rate(0.5), float)
    assert np.array_equal(an.heading_rate_from_yaw_rate(np.array([1.0, -2.0])), [-1.0, 2.0])


def test_level_body_yaw_rate_gives_the_heading_rate():
    # a level body turning with body angular velocity (0, 0, w): integrate R' = R [w]x and read
    # the heading of the body x axis from the rotation (scipy: independent of nav)
    w, dt = 0.4, 1e-4
    R0 = Rotation.from_euler("z", 1.2)
    step = Rotation.from_rotvec([0.0, 0.0, w * dt])
    heads = [an.course_of((R0 * step**k).as_matrix()[:, 0]) for k in (0, 1, 2)]
    rate = float(an.wrap_pi(heads[2] - heads[0])) / (2 * dt)
    assert rate == pytest.approx(an.heading_rate_from_yaw_rate(w), rel=1e-9)


def test_seed004_theta_and_course():
    assert an.course_from_theta(0.0) == pytest.approx(PI / 2)  # +x axis is east
    assert an.course_from_theta(PI / 2) == pytest.approx(0.0, abs=1e-15)  # +y axis is north
    c = RNG.uniform(0, 2 * PI, 100)
    theta = an.theta_from_course(c)
    assert np.all((theta >= -PI) & (theta < PI))
    assert np.allclose(an.wrap_pi(an.course_from_theta(theta) - c), 0, atol=1e-12)


def test_range_azimuth_elevation_definition_and_round_trip():
    # seed 000 eq. 15 with depths positive down: vehicle at 3 m, transceiver at 6 m
    r, alpha, beta = an.range_azimuth_elevation([30.0, 40.0, 3.0])
    assert r == pytest.approx(math.sqrt(30**2 + 40**2 + 3**2))
    assert alpha == pytest.approx(math.atan2(30, 40))
    assert beta == pytest.approx(-math.atan((3.0 - 6.0) / 50.0))
    d = RNG.normal(0, 100, (500, 3))
    rae = an.range_azimuth_elevation(d)
    assert np.all((rae[:, 1] >= 0) & (rae[:, 1] < 2 * PI))
    assert np.all(np.abs(rae[:, 2]) <= PI / 2)
    assert np.allclose(an.rel_from_range_azimuth_elevation(rae), d, atol=1e-9)
    above = an.range_azimuth_elevation([0.0, 0.0, 5.0])
    assert np.allclose(above, [5.0, 0.0, PI / 2])
    assert an.elevation_angle(-1.0, 1.0) == pytest.approx(-PI / 4)


def test_fold_azimuth_elevation_keeps_the_direction():
    """Law: the folded angles give the same unit vector, with the elevation in [-90, 90] deg and
    the azimuth in [0, 360) deg; inside that range nothing changes."""
    from nav.angles import fold_azimuth_elevation

    rng = np.random.default_rng(3)
    a = rng.uniform(-np.pi, 3 * np.pi, 2000)
    b = rng.uniform(-1.49 * np.pi, 1.49 * np.pi, 2000)
    fa, fb = fold_azimuth_elevation(a, b)

    def unit(az, el):
        return np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], -1)

    assert np.allclose(unit(fa, fb), unit(a, b), atol=1e-12)
    assert np.all(np.abs(fb) <= np.pi / 2) and np.all((fa >= 0) & (fa < 2 * np.pi))
    inside = np.abs(b) <= np.pi / 2
    assert np.array_equal(fb[inside], b[inside])
    assert np.allclose(fold_azimuth_elevation(0.3, np.radians(95.0)), (0.3 + np.pi, np.radians(85)))
