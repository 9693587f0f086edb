"""Frames, navigation angles and their conversions: the one place for them.

Conventions (see ``docs/architecture.md``):

* **World frame** ``world``: x east, y north, z up (ENU; MuJoCo's z is up and gravity is -z).
  The sea surface is z = 0 and depth = -z (positive down).
* **Body frame** ``body``: x forward, y to port, z up (FLU).
* **Navigation angles**: course, heading and the USBL azimuth alpha are measured clockwise from
  north, in radians inside the code, wrapped to [0, 2 pi) by :func:`wrap_2pi` unless a function says
  otherwise. Residuals and differences of angles are wrapped to [-pi, pi) by :func:`wrap_pi`.
  The elevation beta is positive when the target is above the observer.
* **Attitude**: roll positive with the starboard side down, pitch positive nose up, heading as
  above.
* **Quaternions** carry their component order in their name: MuJoCo uses ``quat_wxyz``,
  rerun and scipy ``quat_xyzw``.
* **Seed 004 angles**: theta is measured counter-clockwise from the x (east) axis, gamma up from the
  horizontal; :func:`course_from_theta` and :func:`theta_from_course` convert.

All functions accept numpy arrays and broadcast over leading axes; a trailing axis of size 3 (or 4
for quaternions, or 3x3 for rotation matrices) is the vector axis.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

KNOT_M_S = 1852.0 / 3600.0
"""One knot in metres per second (exact by definition of the nautical mile)."""

TWO_PI = 2.0 * np.pi


def wrap_pi(angle_rad: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to [-pi, pi).

    Args:
        angle_rad: angles, any shape, radians.

    Returns:
        Angles of the same shape in [-pi, pi), radians.
    """
    a = np.asarray(angle_rad, dtype=float)
    return (a + np.pi) % TWO_PI - np.pi


def wrap_2pi(angle_rad: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to [0, 2 pi).

    Args:
        angle_rad: angles, any shape, radians.

    Returns:
        Angles of the same shape in [0, 2 pi), radians.
    """
    a = np.asarray(angle_rad, dtype=float)
    w = a % TWO_PI
    # a tiny negative input can round to exactly 2 pi
    return np.where(w >= TWO_PI, 0.0, w)


def knots_to_m_s(speed_kn: ArrayLike) -> NDArray[np.float64]:
    """Convert knots to metres per second."""
    return np.asarray(speed_kn, dtype=float) * KNOT_M_S


def m_s_to_knots(speed_m_s: ArrayLike) -> NDArray[np.float64]:
    """Convert metres per second to knots."""
    return np.asarray(speed_m_s, dtype=float) / KNOT_M_S


def depth_from_z(z_world_m: ArrayLike) -> NDArray[np.float64]:
    """Depth below the surface (positive down, m) from world z (up, m)."""
    return -np.asarray(z_world_m, dtype=float)


def z_from_depth(depth_m: ArrayLike) -> NDArray[np.float64]:
    """World z (up, m) from depth below the surface (positive down, m)."""
    return -np.asarray(depth_m, dtype=float)


def velocity_from_course_speed(course_rad: ArrayLike, speed_m_s: ArrayLike) -> NDArray[np.float64]:
    """Horizontal world velocity from course and speed.

    Seed 000 eq. 8: ``dx = S sin C``, ``dy = S cos C``.

    Args:
        course_rad: course clockwise from north, shape (...), rad.
        speed_m_s: speed, shape broadcastable with ``course_rad``, m/s.

    Returns:
        Velocity (east, north), shape (..., 2), m/s, world frame.
    """
    c = np.asarray(course_rad, dtype=float)
    s = np.asarray(speed_m_s, dtype=float)
    return np.stack(np.broadcast_arrays(s * np.sin(c), s * np.cos(c)), axis=-1)


def course_speed_from_velocity(
    vel_en_m_s: ArrayLike,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Course and speed of a horizontal world velocity.

    Args:
        vel_en_m_s: velocity (east, north[, up]), shape (..., 2) or (..., 3), m/s, world frame.
            An up component is ignored.

    Returns:
        ``(course_rad, speed_m_s)``, each of shape (...); course in [0, 2 pi) clockwise from
        north (0 for a zero velocity).
    """
    v = np.asarray(vel_en_m_s, dtype=float)
    return wrap_2pi(np.arctan2(v[..., 0], v[..., 1])), np.hypot(v[..., 0], v[..., 1])


def range_azimuth_elevation(rel_world_m: ArrayLike) -> NDArray[np.float64]:
    """Slant range, azimuth and elevation of a relative position.

    Seed 000 eq. 15 (with world z up): ``r = |d|``, ``alpha = atan2(d_e, d_n)`` clockwise from
    north, ``beta = atan2(d_u, sqrt(d_e^2 + d_n^2))`` positive when the target is above.
    Directly above or below the observer the azimuth is returned as 0.

    Args:
        rel_world_m: target minus observer, shape (..., 3), m, world frame.

    Returns:
        ``(r, alpha, beta)`` stacked, shape (..., 3): m, rad in [0, 2 pi), rad in [-pi/2, pi/2].
    """
    d = np.asarray(rel_world_m, dtype=float)
    horiz = np.hypot(d[..., 0], d[..., 1])
    r = np.sqrt(horiz**2 + d[..., 2] ** 2)
    alpha = wrap_2pi(np.arctan2(d[..., 0], d[..., 1]))
    beta = np.arctan2(d[..., 2], horiz)
    return np.stack([r, alpha, beta], axis=-1)


def rel_from_range_azimuth_elevation(rae: ArrayLike) -> NDArray[np.float64]:
    """Relative position from slant range, azimuth and elevation (inverse of
    :func:`range_azimuth_elevation`).

    Args:
        rae: ``(r, alpha, beta)``, shape (..., 3): m, rad clockwise from north, rad up.

    Returns:
        Target minus observer, shape (..., 3), m, world frame.
    """
    a = np.asarray(rae, dtype=float)
    r, alpha, beta = a[..., 0], a[..., 1], a[..., 2]
    horiz = r * np.cos(beta)
    return np.stack([horiz * np.sin(alpha), horiz * np.cos(alpha), r * np.sin(beta)], axis=-1)


def heading_from_yaw(yaw_rad: ArrayLike) -> NDArray[np.float64]:
    """Navigation heading (clockwise from north) from a mathematical yaw about world z (counter-
    clockwise from east). Both in rad; the result is in [0, 2 pi)."""
    return wrap_2pi(np.pi / 2 - np.asarray(yaw_rad, dtype=float))


def yaw_from_heading(heading_rad: ArrayLike) -> NDArray[np.float64]:
    """Mathematical yaw about world z (counter-clockwise from east, in [-pi, pi)) from a navigation
    heading (clockwise from north), both rad."""
    return wrap_pi(np.pi / 2 - np.asarray(heading_rad, dtype=float))


def course_from_theta(theta_rad: ArrayLike) -> NDArray[np.float64]:
    """Seed 004's theta (counter-clockwise from the x/east axis) to a navigation course, rad."""
    return heading_from_yaw(theta_rad)


def theta_from_course(course_rad: ArrayLike) -> NDArray[np.float64]:
    """Navigation course to seed 004's theta (counter-clockwise from x/east, in [-pi, pi)), rad."""
    return yaw_from_heading(course_rad)


def quat_wxyz_to_xyzw(quat_wxyz: ArrayLike) -> NDArray[np.float64]:
    """Reorder quaternions (..., 4) from MuJoCo's (w, x, y, z) to rerun/scipy's (x, y, z, w)."""
    q = np.asarray(quat_wxyz, dtype=float)
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def quat_xyzw_to_wxyz(quat_xyzw: ArrayLike) -> NDArray[np.float64]:
    """Reorder quaternions from (x, y, z, w) to MuJoCo's (w, x, y, z); shape (..., 4)."""
    q = np.asarray(quat_xyzw, dtype=float)
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)


def R_from_quat_wxyz(quat_wxyz: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix from a unit quaternion.

    Args:
        quat_wxyz: quaternion(s) (w, x, y, z), shape (..., 4); normalised here.

    Returns:
        ``R_world_from_body``, shape (..., 3, 3), for a quaternion that rotates body into world.
    """
    q = np.asarray(quat_wxyz, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - w * z)
    R[..., 0, 2] = 2 * (x * z + w * y)
    R[..., 1, 0] = 2 * (x * y + w * z)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - w * x)
    R[..., 2, 0] = 2 * (x * z - w * y)
    R[..., 2, 1] = 2 * (y * z + w * x)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quat_wxyz_from_R(R: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion (w, x, y, z) with w >= 0 from a rotation matrix.

    Args:
        R: rotation matrix ``R_world_from_body``, shape (..., 3, 3).

    Returns:
        Quaternion (w, x, y, z), shape (..., 4).
    """
    M = np.asarray(R, dtype=float)
    flat = Rotation.from_matrix(M.reshape(-1, 3, 3)).as_quat(scalar_first=True)
    flat = np.where(flat[:, :1] < 0, -flat, flat)
    return flat.reshape(M.shape[:-2] + (4,))


def R_from_roll_pitch_heading(
    roll_rad: ArrayLike, pitch_rad: ArrayLike, heading_rad: ArrayLike
) -> NDArray[np.float64]:
    """Rotation ``R_world_from_body`` from navigation attitude angles.

    The body (FLU) is first turned to the heading about world z, then pitched nose up about its
    starboard axis, then rolled starboard down about its forward axis.

    Args:
        roll_rad: roll, starboard down positive, shape (...), rad.
        pitch_rad: pitch, nose up positive, shape (...), rad.
        heading_rad: heading clockwise from north, shape (...), rad.

    Returns:
        ``R_world_from_body``, shape (..., 3, 3).
    """
    roll, pitch, heading = np.broadcast_arrays(
        np.asarray(roll_rad, float), np.asarray(pitch_rad, float), np.asarray(heading_rad, float)
    )
    yaw = np.pi / 2 - heading
    # FLU body: +y is port. Nose up is a negative rotation about +y; starboard down is a
    # positive rotation about +x (port side rises).
    return _rot_z(yaw) @ _rot_y(-pitch) @ _rot_x(roll)


def roll_pitch_heading_from_R(R: ArrayLike) -> NDArray[np.float64]:
    """Navigation attitude angles from ``R_world_from_body`` (inverse of
    :func:`R_from_roll_pitch_heading` for |pitch| < pi/2).

    Args:
        R: rotation matrix, shape (..., 3, 3).

    Returns:
        ``(roll, pitch, heading)`` stacked, shape (..., 3), rad; roll in [-pi, pi), pitch in
        [-pi/2, pi/2], heading in [0, 2 pi).
    """
    M = np.asarray(R, dtype=float)
    fwd = M[..., :, 0]
    pitch = np.arcsin(np.clip(fwd[..., 2], -1.0, 1.0))
    heading = wrap_2pi(np.arctan2(fwd[..., 0], fwd[..., 1]))
    # roll from the body y (port) and z (up) axes' world z components
    roll = np.arctan2(M[..., 2, 1], M[..., 2, 2])
    return np.stack([wrap_pi(roll), pitch, heading], axis=-1)


def roll_pitch_heading_from_quat_wxyz(quat_wxyz: ArrayLike) -> NDArray[np.float64]:
    """Navigation attitude angles straight from a unit quaternion (same result as
    ``roll_pitch_heading_from_R(R_from_quat_wxyz(q))``, without building the matrix).

    Args:
        quat_wxyz: unit quaternion(s) (w, x, y, z), body to world, shape (..., 4).

    Returns:
        ``(roll, pitch, heading)``, shape (..., 3), rad, ranged as in
        :func:`roll_pitch_heading_from_R`.
    """
    q = np.asarray(quat_wxyz, dtype=float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r00 = 1 - 2 * (y * y + z * z)
    r10 = 2 * (x * y + w * z)
    r20 = 2 * (x * z - w * y)
    r21 = 2 * (y * z + w * x)
    r22 = 1 - 2 * (x * x + y * y)
    pitch = np.arcsin(np.clip(r20, -1.0, 1.0))
    heading = wrap_2pi(np.arctan2(r00, r10))
    roll = wrap_pi(np.arctan2(r21, r22))
    return np.stack([roll, pitch, heading], axis=-1)


def quat_wxyz_from_roll_pitch_heading(
    roll_rad: ArrayLike, pitch_rad: ArrayLike, heading_rad: ArrayLike
) -> NDArray[np.float64]:
    """Quaternion (w, x, y, z) of :func:`R_from_roll_pitch_heading`; shape (..., 4)."""
    return quat_wxyz_from_R(R_from_roll_pitch_heading(roll_rad, pitch_rad, heading_rad))


def heading_from_quat_wxyz(quat_wxyz: ArrayLike) -> NDArray[np.float64]:
    """Heading (clockwise from north, [0, 2 pi), rad) of the body x axis; shape (...)."""
    return roll_pitch_heading_from_R(R_from_quat_wxyz(quat_wxyz))[..., 2]


def world_from_body(R_world_from_body: ArrayLike, vec_body: ArrayLike) -> NDArray[np.float64]:
    """Rotate body-frame vectors into the world frame.

    Args:
        R_world_from_body: shape (..., 3, 3).
        vec_body: shape (..., 3), body frame.

    Returns:
        Shape (..., 3), world frame.
    """
    return np.einsum("...ij,...j->...i", np.asarray(R_world_from_body, float), vec_body)


def body_from_world(R_world_from_body: ArrayLike, vec_world: ArrayLike) -> NDArray[np.float64]:
    """Rotate world-frame vectors into the body frame (inverse of :func:`world_from_body`)."""
    return np.einsum("...ji,...j->...i", np.asarray(R_world_from_body, float), vec_world)


def _rot_x(a: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack(
        [np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2
    )


def _rot_y(a: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack(
        [np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2
    )


def _rot_z(a: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    return np.stack(
        [np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2
    )
