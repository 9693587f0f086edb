"""Laws of the simulator's frame conversions (attitude, quaternions, units, depth): round trips,
inverses, known directions. The navigation angles are tested in ``tests/nav/test_angles.py``."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bauv_sim import frames as fr
from nav import angles as nav_angles

RNG = np.random.default_rng(12345)


def test_the_navigation_angles_are_nav_angles_not_a_copy():
    for name in nav_angles.__all__:
        assert getattr(fr, name) is getattr(nav_angles, name), name
        assert name in fr.__all__


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
    # the heading of the forward axis and from the quaternion agree with the attitude given
    h = np.array([0.0, 1.0, 3.5, 6.2])
    q = fr.quat_wxyz_from_roll_pitch_heading(0.1, -0.2, h)
    assert np.allclose(fr.wrap_pi(fr.heading_from_quat_wxyz(q) - h), 0, atol=1e-12)
    assert np.allclose(fr.wrap_pi(fr.roll_pitch_heading_from_quat_wxyz(q)[:, 2] - h), 0, atol=1e-12)


def test_units():
    assert fr.knots_to_m_s(1.0) == pytest.approx(0.514444, rel=1e-5)
    assert fr.m_s_to_knots(fr.knots_to_m_s(3.7)) == pytest.approx(3.7)
    assert fr.depth_from_z(-3.0) == 3.0 and fr.z_from_depth(6.0) == -6.0


def test_scalar_attitude_equals_the_array_form():
    rng = np.random.default_rng(11)
    q = rng.normal(size=(500, 4)) * rng.uniform(0.5, 2.0, size=(500, 1))  # any norm
    want = fr.roll_pitch_heading_from_quat_wxyz(q / np.linalg.norm(q, axis=1, keepdims=True))
    for qi, wi in zip(q, want, strict=True):
        unit, rph = fr.attitude_from_quat_wxyz_scalar(*qi.tolist())
        assert np.allclose(unit, qi / np.linalg.norm(qi), atol=1e-15)
        assert np.allclose(fr.wrap_pi(np.array(rph) - wi + 1.0) - 1.0, 0.0, atol=1e-12)
