"""Laws of the frame conversions: round trips, inverses, known directions."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bauv_sim import frames as fr

RNG = np.random.default_rng(12345)


def test_wrap_ranges():
    a = RNG.uniform(-50, 50, 1000)
    w = fr.wrap_pi(a)
    assert np.all((w >= -np.pi) & (w < np.pi))
    assert np.allclose(np.sin(w), np.sin(a)) and np.allclose(np.cos(w), np.cos(a))
    w2 = fr.wrap_2pi(a)
    assert np.all((w2 >= 0) & (w2 < 2 * np.pi))
    assert fr.wrap_2pi(-1e-18) < 2 * np.pi


def test_course_velocity_round_trip_and_cardinal_directions():
    c = RNG.uniform(0, 2 * np.pi, 100)
    s = RNG.uniform(0.1, 3, 100)
    v = fr.velocity_from_course_speed(c, s)
    c2, s2 = fr.course_speed_from_velocity(v)
    assert np.allclose(fr.wrap_pi(c2 - c), 0, atol=1e-12) and np.allclose(s2, s)
    # north is +y, east is +x, course 220 deg points south-west
    assert np.allclose(fr.velocity_from_course_speed(0.0, 1.0), [0, 1], atol=1e-15)
    assert np.allclose(fr.velocity_from_course_speed(np.pi / 2, 1.0), [1, 0], atol=1e-15)
    v220 = fr.velocity_from_course_speed(np.radians(220), 1.0)
    assert v220[0] < 0 and v220[1] < 0


def test_range_azimuth_elevation_round_trip_and_definition():
    d = RNG.normal(0, 100, (500, 3))
    rae = fr.range_azimuth_elevation(d)
    assert np.allclose(fr.rel_from_range_azimuth_elevation(rae), d)
    # seed 000 eq. 15 with depth z positive down: beta = -atan(dz_depth / l)
    rae1 = fr.range_azimuth_elevation([30.0, 40.0, 3.0])  # vehicle 3 m above the transceiver
    assert rae1[0] == pytest.approx(np.sqrt(2500 + 9))
    assert rae1[1] == pytest.approx(np.arctan2(30, 40))
    assert rae1[2] == pytest.approx(-np.arctan((3.0 - 6.0) / 50.0))  # depths 3 m and 6 m


def test_heading_yaw_and_seed004_theta():
    h = RNG.uniform(0, 2 * np.pi, 100)
    assert np.allclose(fr.wrap_pi(fr.heading_from_yaw(fr.yaw_from_heading(h)) - h), 0, atol=1e-12)
    assert fr.course_from_theta(0.0) == pytest.approx(np.pi / 2)  # +x axis is east
    assert fr.course_from_theta(np.pi / 2) == pytest.approx(0.0)  # +y axis is north
    assert np.allclose(fr.wrap_pi(fr.course_from_theta(fr.theta_from_course(h)) - h), 0, atol=1e-12)


def test_attitude_round_trip_and_quaternions_against_scipy():
    n = 300
    roll = RNG.uniform(-np.pi, np.pi, n)
    pitch = RNG.uniform(-1.5, 1.5, n)
    heading = RNG.uniform(0, 2 * np.pi, n)
    R = fr.R_from_roll_pitch_heading(roll, pitch, heading)
    assert np.allclose(R @ np.swapaxes(R, -1, -2), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1)
    back = fr.roll_pitch_heading_from_R(R)
    assert np.allclose(fr.wrap_pi(back[:, 0] - roll), 0, atol=1e-9)
    assert np.allclose(back[:, 1], pitch, atol=1e-9)
    assert np.allclose(fr.wrap_pi(back[:, 2] - heading), 0, atol=1e-9)
    q = fr.quat_wxyz_from_R(R)
    assert np.allclose(fr.R_from_quat_wxyz(q), R, atol=1e-12)
    # scipy takes xyzw and must agree
    assert np.allclose(Rotation.from_quat(fr.quat_wxyz_to_xyzw(q)).as_matrix(), R, atol=1e-12)
    assert np.allclose(fr.quat_xyzw_to_wxyz(fr.quat_wxyz_to_xyzw(q)), q)


def test_attitude_sign_conventions():
    # pitch nose up: forward axis gains +z; roll starboard down: port axis (+y body) gains +z
    R = fr.R_from_roll_pitch_heading(0.0, 0.3, 0.0)
    assert R[2, 0] == pytest.approx(np.sin(0.3))
    R = fr.R_from_roll_pitch_heading(0.3, 0.0, 0.0)
    assert R[2, 1] == pytest.approx(np.sin(0.3))
    # heading 90 deg: forward axis points east
    R = fr.R_from_roll_pitch_heading(0.0, 0.0, np.pi / 2)
    assert np.allclose(R[:, 0], [1, 0, 0], atol=1e-15)
    v_body = np.array([1.0, 2.0, 3.0])
    assert np.allclose(fr.body_from_world(R, fr.world_from_body(R, v_body)), v_body)


def test_units():
    assert fr.knots_to_m_s(1.0) == pytest.approx(0.514444, rel=1e-5)
    assert fr.m_s_to_knots(fr.knots_to_m_s(3.7)) == pytest.approx(3.7)
    assert fr.depth_from_z(-3.0) == 3.0 and fr.z_from_depth(6.0) == -6.0
