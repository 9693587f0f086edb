"""Frames of the simulator: the world and body frames, attitude, quaternions, units and depth.

The navigation angles and their pure conversions (wrapping, course and speed <-> east/north,
heading <-> yaw and their rates, range/azimuth/elevation, seed 004's theta) live in
:mod:`nav.angles`, which the navigation stack uses without importing :mod:`bauv_sim`; this module
re-exports them under their names, so that simulator code has one module to import from, and adds
what belongs to the simulator.

Conventions (see ``docs/architecture.md`` and :mod:`nav.angles`):

* **World frame** ``world``: x east, y north, z up (ENU; MuJoCo's z is up and gravity is -z).
  The sea surface is z = 0 and depth = -z (positive down).
* **Body frame** ``body``: x forward, y to port, z up (FLU).
* **Navigation angles**: clockwise from north, rad, as in :mod:`nav.angles`.
* **Attitude**: roll positive with the starboard side down, pitch positive nose up, heading as
  above.
* **Quaternions** carry their component order in their name: MuJoCo uses ``quat_wxyz``,
  rerun and scipy ``quat_xyzw``.

All functions accept numpy arrays and broadcast over leading axes; a trailing axis of size 3 (or 4
for quaternions, or 3x3 for rotation matrices) is the vector axis.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import (
    TWO_PI,
    course_from_theta,
    course_of,
    course_of_scalar,
    course_speed_from_velocity,
    diff_course,
    elevation_angle,
    fold_azimuth_elevation,
    heading_from_yaw,
    heading_rate_from_yaw_rate,
    range_azimuth_elevation,
    rel_from_range_azimuth_elevation,
    rotation_world_from_body,
    theta_from_course,
    unit_vector,
    unit_vector_scalar,
    velocity_from_course_speed,
    wrap_2pi,
    wrap_2pi_scalar,
    wrap_pi,
    wrap_pi_scalar,
    yaw_from_heading,
    yaw_rate_from_heading_rate,
)

__all__ = [
    "KNOT_M_S",
    "TWO_PI",
    "R_from_quat_wxyz",
    "R_from_roll_pitch_heading",
    "attitude_from_quat_wxyz_scalar",
    "body_from_world",
    "course_from_theta",
    "course_of",
    "course_of_scalar",
    "course_speed_from_velocity",
    "depth_from_z",
    "diff_course",
    "elevation_angle",
    "fold_azimuth_elevation",
    "heading_from_quat_wxyz",
    "heading_from_yaw",
    "heading_rate_from_yaw_rate",
    "knots_to_m_s",
    "m_s_to_knots",
    "navigation_rates_from_body",
    "quat_wxyz_from_R",
    "quat_wxyz_from_roll_pitch_heading",
    "quat_wxyz_from_roll_pitch_heading_scalar",
    "quat_wxyz_to_xyzw",
    "quat_xyzw_to_wxyz",
    "range_azimuth_elevation",
    "rel_from_range_azimuth_elevation",
    "roll_pitch_heading_from_R",
    "roll_pitch_heading_from_quat_wxyz",
    "rotation_world_from_body",
    "theta_from_course",
    "unit_vector",
    "unit_vector_scalar",
    "velocity_from_course_speed",
    "world_from_body",
    "wrap_2pi",
    "wrap_2pi_scalar",
    "wrap_pi",
    "wrap_pi_scalar",
    "yaw_from_heading",
    "yaw_rate_from_heading_rate",
    "z_from_depth",
]

KNOT_M_S = 1852.0 / 3600.0
"""One knot in metres per second (exact by definition of the nautical mile)."""


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
    from scipy.spatial.transform import Rotation  # on first use: scipy.spatial costs ~0.5 s

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
    yaw = np.pi / 2 - heading  # yaw_from_heading unwrapped: no range is needed here
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
    heading = course_of(fwd)
    # roll from the body y (port) and z (up) axes' world z components
    roll = np.arctan2(M[..., 2, 1], M[..., 2, 2])
    return np.stack([wrap_pi(roll), pitch, heading], axis=-1)


def attitude_from_quat_wxyz_scalar(
    qw: float, qx: float, qy: float, qz: float
) -> tuple[tuple[float, float, float, float], tuple[float, float, float]]:
    """The unit quaternion and ``(roll, pitch, heading)`` of one quaternion, with Python floats:
    :func:`roll_pitch_heading_from_quat_wxyz` for per-tick code (the same formulas, tested
    equal).

    Args:
        qw, qx, qy, qz: a quaternion body FLU -> world ENU (any norm > 0).

    Returns:
        ``((w, x, y, z) normalised, (roll in [-pi, pi), pitch, heading in [0, 2 pi)))``, rad.
    """
    n = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    qw, qx, qy, qz = qw / n, qx / n, qy / n, qz / n
    r00 = 1 - 2 * (qy * qy + qz * qz)
    r10 = 2 * (qx * qy + qw * qz)
    r20 = 2 * (qx * qz - qw * qy)
    r21 = 2 * (qy * qz + qw * qx)
    r22 = 1 - 2 * (qx * qx + qy * qy)
    roll = wrap_pi_scalar(math.atan2(r21, r22))
    pitch = math.asin(min(1.0, max(-1.0, r20)))
    heading = course_of_scalar(r00, r10)
    return (qw, qx, qy, qz), (roll, pitch, heading)


def quat_wxyz_from_roll_pitch_heading_scalar(
    roll_rad: float, pitch_rad: float, heading_rad: float
) -> np.ndarray:
    """The quaternion (w, x, y, z), w >= 0, of :func:`R_from_roll_pitch_heading`
    (``Rz(pi/2 - heading) Ry(-pitch) Rx(roll)``, body FLU to world ENU) with Python floats:
    :func:`quat_wxyz_from_roll_pitch_heading` for per-tick code (it goes through a rotation
    matrix and scipy, about 1 ms a call); the inverse of :func:`attitude_from_quat_wxyz_scalar`.

    Args:
        roll_rad, pitch_rad, heading_rad: attitude, rad (pitch nose up +, heading clockwise
            from north).

    Returns:
        The quaternion body FLU -> world ENU, shape (4,).
    """
    hr, hp, hy = 0.5 * roll_rad, -0.5 * pitch_rad, 0.5 * (math.pi / 2 - heading_rad)
    cr, sr, cp, sp, cy, sy = (math.cos(hr), math.sin(hr), math.cos(hp), math.sin(hp),
                              math.cos(hy), math.sin(hy))  # fmt: skip
    w = cr * cp * cy + sr * sp * sy
    x = sr * cp * cy - cr * sp * sy
    y = cr * sp * cy + sr * cp * sy
    z = cr * cp * sy - sr * sp * cy
    return np.array([w, x, y, z]) if w >= 0 else np.array([-w, -x, -y, -z])


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
    heading = course_of(np.stack([r00, r10], axis=-1))
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


def navigation_rates_from_body(
    angular_velocity_body_rad_s: ArrayLike,
) -> tuple[float, float, float]:
    """Roll, pitch and heading rates in the navigation convention from body FLU rates.

    Roll (starboard down +) turns about body x; pitch (nose up +) is minus the rate about body y
    (port); the heading rate (clockwise +) is :func:`~nav.angles.heading_rate_from_yaw_rate` of
    the rate about body z (up). The body rates equal the Euler-angle rates only for a level
    vehicle (small roll and pitch), as the autopilot and the INS model take them.

    Args:
        angular_velocity_body_rad_s: (p, q, r) about body x, y, z, shape (3,), rad/s.

    Returns:
        ``(roll rate, pitch rate, heading rate)``, rad/s, as floats.
    """
    w = angular_velocity_body_rad_s
    return float(w[0]), -float(w[1]), heading_rate_from_yaw_rate(float(w[2]))


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
