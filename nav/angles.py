"""Navigation angles and their conversions: the one place for them (pure math, no MuJoCo).

Conventions (see ``docs/architecture.md``):

* **World frame**: x east, y north, z up (ENU). A horizontal vector is ``(east, north)``.
* **Navigation angles** (course, heading, the USBL azimuth alpha, a direct course to a way-point)
  are measured clockwise from north in radians and wrapped to [0, 2 pi) by :func:`wrap_2pi`
  unless a function says otherwise; differences and residuals of angles are wrapped to
  [-pi, pi) by :func:`wrap_pi`. The elevation beta is positive when the target is above.
* **Yaw** is the mathematical angle about world z, counter-clockwise from east (MuJoCo's and
  scipy's rotation about z); its rate is positive counter-clockwise, the heading rate clockwise.
* **Seed 004's theta** is measured counter-clockwise from the x (east) axis, like the yaw.

Array forms take anything numpy takes and broadcast over leading axes; a trailing axis of size 2
(``(east, north)``) or 3 (``(east, north, up)``, or ``(r, alpha, beta)``) is the vector axis. The
``*_scalar`` forms take and return Python floats and use :mod:`math`, for the per-tick paths of
the online navigator, guidance and autopilot; numpy's vectorised sine and cosine may differ from
the C library's by an ulp, so a scalar form and its array form agree to an ulp, not bit for bit.

:mod:`bauv_sim.frames` re-exports these functions and adds what belongs to the simulator
(quaternions, rotation matrices, units, depth).

References:
    Seed 000 eq. 8 (course and speed to a displacement) and eq. 15 (range, azimuth, elevation);
    seed 001's ``getCourse360`` and ``diffCourse``; seed 004 (theta).
"""

from __future__ import annotations

import math
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]
Rate = TypeVar("Rate", float, Array)

TWO_PI = 2.0 * math.pi
"""2 pi, rad."""

__all__ = [
    "TWO_PI",
    "course_from_theta",
    "course_of",
    "course_of_scalar",
    "course_speed_from_velocity",
    "diff_course",
    "elevation_angle",
    "heading_from_yaw",
    "heading_rate_from_yaw_rate",
    "range_azimuth_elevation",
    "rel_from_range_azimuth_elevation",
    "rotation_world_from_body",
    "theta_from_course",
    "unit_vector",
    "unit_vector_scalar",
    "velocity_from_course_speed",
    "wrap_2pi",
    "wrap_2pi_scalar",
    "wrap_pi",
    "wrap_pi_scalar",
    "yaw_from_heading",
    "yaw_rate_from_heading_rate",
]


# --------------------------------------------------------------------------------------------
# Wrapping


def wrap_pi(angle_rad: ArrayLike) -> Array:
    """Wrap angles to [-pi, pi).

    Args:
        angle_rad: angles, any shape, rad.

    Returns:
        Angles of the same shape in [-pi, pi), rad (``pi`` itself maps to ``-pi``).
    """
    w = (np.asarray(angle_rad, dtype=float) + np.pi) % TWO_PI
    # a tiny negative a + pi rounds to exactly 2 pi
    return np.where(w >= TWO_PI, 0.0, w) - np.pi


def wrap_2pi(angle_rad: ArrayLike) -> Array:
    """Wrap angles to [0, 2 pi).

    Args:
        angle_rad: angles, any shape, rad.

    Returns:
        Angles of the same shape in [0, 2 pi), rad.
    """
    w = np.asarray(angle_rad, dtype=float) % TWO_PI
    # a tiny negative input rounds to exactly 2 pi
    return np.where(w >= TWO_PI, 0.0, w)


def wrap_pi_scalar(angle_rad: float) -> float:
    """:func:`wrap_pi` of one angle (rad, to [-pi, pi)) with Python floats."""
    w = (angle_rad + math.pi) % TWO_PI
    return (0.0 if w >= TWO_PI else w) - math.pi


def wrap_2pi_scalar(angle_rad: float) -> float:
    """:func:`wrap_2pi` of one angle (rad, to [0, 2 pi)) with Python floats."""
    w = angle_rad % TWO_PI
    return 0.0 if w >= TWO_PI else w


def diff_course(a_rad: ArrayLike, b_rad: ArrayLike) -> Array:
    """The unsigned difference of two courses (seed 001's ``diffCourse``), in [0, pi].

    Args:
        a_rad: courses, rad, any shape broadcastable with ``b_rad``.
        b_rad: courses, rad.

    Returns:
        ``|wrap_pi(a - b)|``, rad.
    """
    return np.abs(wrap_pi(np.asarray(a_rad, dtype=float) - np.asarray(b_rad, dtype=float)))


# --------------------------------------------------------------------------------------------
# Course and speed <-> east/north vectors


def unit_vector(course_rad: ArrayLike) -> Array:
    """Unit vector of a course: ``(sin c, cos c)``.

    Args:
        course_rad: courses clockwise from north, shape (...), rad.

    Returns:
        ``(east, north)``, shape (..., 2), world frame.
    """
    c = np.asarray(course_rad, dtype=float)
    return np.stack([np.sin(c), np.cos(c)], axis=-1)


def unit_vector_scalar(course_rad: float) -> tuple[float, float]:
    """:func:`unit_vector` of one course (rad clockwise from north): ``(east, north)`` floats."""
    return math.sin(course_rad), math.cos(course_rad)


def velocity_from_course_speed(course_rad: ArrayLike, speed_m_s: ArrayLike) -> Array:
    """Horizontal velocity from course and speed (seed 000 eq. 8: ``dx = S sin C, dy = S cos C``).

    Args:
        course_rad: course clockwise from north, shape (...), rad.
        speed_m_s: speed, shape broadcastable with ``course_rad``, m/s (any length unit gives
            a displacement in that unit).

    Returns:
        Velocity ``(east, north)``, shape (..., 2), m/s, world frame.
    """
    return np.asarray(speed_m_s, dtype=float)[..., None] * unit_vector(course_rad)


def course_of(vector_world: ArrayLike) -> Array:
    """Course of a horizontal vector (seed 001's ``getCourse360``), in [0, 2 pi).

    Args:
        vector_world: ``(east, north[, up])``, shape (..., 2) or (..., 3), world frame; an up
            component is ignored.

    Returns:
        Courses clockwise from north, shape (...), rad; 0 for a zero vector.
    """
    v = np.asarray(vector_world, dtype=float)
    return wrap_2pi(np.arctan2(v[..., 0], v[..., 1]))


def course_of_scalar(east: float, north: float) -> float:
    """:func:`course_of` of one vector given by its east and north components: rad in
    [0, 2 pi)."""
    return wrap_2pi_scalar(math.atan2(east, north))


def course_speed_from_velocity(vel_world_m_s: ArrayLike) -> tuple[Array, Array]:
    """Course and speed of a horizontal velocity (inverse of :func:`velocity_from_course_speed`).

    Args:
        vel_world_m_s: ``(east, north[, up])``, shape (..., 2) or (..., 3), m/s, world frame; an
            up component is ignored.

    Returns:
        ``(course_rad, speed_m_s)``, each of shape (...); course in [0, 2 pi) clockwise from
        north (0 for a zero velocity), speed >= 0.
    """
    v = np.asarray(vel_world_m_s, dtype=float)
    return course_of(v), np.hypot(v[..., 0], v[..., 1])


# --------------------------------------------------------------------------------------------
# Heading <-> yaw, and their rates


def heading_from_yaw(yaw_rad: ArrayLike) -> Array:
    """Navigation heading (clockwise from north) from a yaw about world z (counter-clockwise from
    east, e.g. MuJoCo's), both rad; the result is in [0, 2 pi)."""
    return wrap_2pi(np.pi / 2 - np.asarray(yaw_rad, dtype=float))


def yaw_from_heading(heading_rad: ArrayLike) -> Array:
    """Yaw about world z (counter-clockwise from east, in [-pi, pi)) from a navigation heading
    (clockwise from north), both rad."""
    return wrap_pi(np.pi / 2 - np.asarray(heading_rad, dtype=float))


def heading_rate_from_yaw_rate(yaw_rate_rad_s: Rate) -> Rate:
    """Rate of the heading (clockwise +) from the yaw rate about the vertical (counter-clockwise
    +), rad/s; the derivative of :func:`heading_from_yaw`. A float gives a float.

    The body-frame z rate (MuJoCo's ``qvel``) is the yaw rate about the vertical only when the
    vehicle is level; the missions use it as such.
    """
    return -yaw_rate_rad_s


def yaw_rate_from_heading_rate(heading_rate_rad_s: Rate) -> Rate:
    """Yaw rate about the vertical (counter-clockwise +) from the heading rate (clockwise +),
    rad/s (inverse of :func:`heading_rate_from_yaw_rate`)."""
    return -heading_rate_rad_s


def course_from_theta(theta_rad: ArrayLike) -> Array:
    """Seed 004's theta (counter-clockwise from the x/east axis) to a navigation course in
    [0, 2 pi), rad."""
    return heading_from_yaw(theta_rad)


def theta_from_course(course_rad: ArrayLike) -> Array:
    """Navigation course to seed 004's theta (counter-clockwise from x/east, in [-pi, pi)), rad."""
    return yaw_from_heading(course_rad)


# --------------------------------------------------------------------------------------------
# Range, azimuth, elevation <-> relative position


def elevation_angle(up_m: ArrayLike, horizontal_m: ArrayLike) -> Array:
    """Elevation of a vector from its up component and its horizontal length, rad in
    [-pi/2, pi/2], positive up (seed 000 eq. 15's beta with world z up).

    Args:
        up_m: up components, any shape.
        horizontal_m: horizontal lengths (>= 0), broadcastable with ``up_m``, same unit.
    """
    return np.arctan2(up_m, horizontal_m)


def range_azimuth_elevation(rel_world_m: ArrayLike) -> Array:
    """Slant range, azimuth and elevation of a relative position (seed 000 eq. 15, world z up).

    ``r = |d|``, ``alpha = atan2(d_e, d_n)`` clockwise from north, ``beta = atan2(d_u,
    sqrt(d_e^2 + d_n^2))`` positive when the target is above. Directly above or below the
    observer the azimuth is 0.

    Args:
        rel_world_m: target minus observer, shape (..., 3), m, world frame.

    Returns:
        ``(r, alpha, beta)`` stacked, shape (..., 3): m, rad in [0, 2 pi), rad in [-pi/2, pi/2].
    """
    d = np.asarray(rel_world_m, dtype=float)
    horiz = np.hypot(d[..., 0], d[..., 1])
    r = np.sqrt(horiz**2 + d[..., 2] ** 2)
    return np.stack([r, course_of(d), elevation_angle(d[..., 2], horiz)], axis=-1)


def rel_from_range_azimuth_elevation(rae: ArrayLike) -> Array:
    """Relative position from slant range, azimuth and elevation (inverse of
    :func:`range_azimuth_elevation`).

    Args:
        rae: ``(r, alpha, beta)``, shape (..., 3): m, rad clockwise from north, rad up.

    Returns:
        Target minus observer ``(east, north, up)``, shape (..., 3), m, world frame.
    """
    a = np.asarray(rae, dtype=float)
    r, alpha, beta = a[..., 0], a[..., 1], a[..., 2]
    horizontal = velocity_from_course_speed(alpha, r * np.cos(beta))
    return np.concatenate([horizontal, (r * np.sin(beta))[..., None]], axis=-1)


def fold_azimuth_elevation(azimuth_rad: ArrayLike, elevation_rad: ArrayLike) -> tuple[Array, Array]:
    """The same direction with the elevation in [-pi/2, pi/2] and the azimuth in [0, 2 pi).

    An elevation past the zenith (``beta > pi/2``) points over the top, to the azimuth 180 deg
    around: ``(alpha, beta) -> (alpha + pi, pi - beta)``; past the nadir ``(alpha + pi, -pi -
    beta)``. The unit vector ``(cos b sin a, cos b cos a, sin b)`` is unchanged, so a measured
    direction whose error carries it over the pole keeps its geometry (clipping the elevation to
    +-pi/2 would put every such fix straight above the observer).

    Args:
        azimuth_rad: azimuth clockwise from north, any shape, rad.
        elevation_rad: elevation positive up, broadcastable with ``azimuth_rad``, rad, within
            (-3 pi/2, 3 pi/2) (one fold).

    Returns:
        ``(azimuth in [0, 2 pi), elevation in [-pi/2, pi/2])``, broadcast shape, rad.
    """
    a, b = np.broadcast_arrays(
        np.asarray(azimuth_rad, dtype=float), np.asarray(elevation_rad, dtype=float)
    )
    over = b > np.pi / 2
    under = b < -np.pi / 2
    flipped = over | under
    b = np.where(over, np.pi - b, np.where(under, -np.pi - b, b))
    return wrap_2pi(np.where(flipped, a + np.pi, a)), b


def rotation_world_from_body(roll_pitch_heading_rad: ArrayLike) -> Array:
    """Rotation ``R_world_from_body`` (body FLU -> world ENU) from navigation attitude angles.

    The body is turned to the heading about world z, pitched nose up about its starboard axis,
    then rolled starboard down about its forward axis: ``R = Rz(pi/2 - heading) Ry(-pitch)
    Rx(roll)``, written out: the numbers of ``bauv_sim.frames.R_from_roll_pitch_heading`` (which
    takes the three angles apart), tested equal. Its first column is the forward axis
    ``(sin h cos p, cos h cos p, sin p)``. The one attitude rotation of :mod:`nav` (the DVL's
    velocity, the TRN's soundings).

    Args:
        roll_pitch_heading_rad: ``(roll, pitch, heading)``, shape (..., 3), rad; roll starboard
            down +, pitch nose up +, heading clockwise from north.

    Returns:
        ``R_world_from_body``, shape (..., 3, 3).
    """
    a = np.asarray(roll_pitch_heading_rad, dtype=float)
    if a.shape[-1:] != (3,):
        raise NavInputError(
            f"roll_pitch_heading_rad must have a last axis of 3 (roll, pitch, heading), "
            f"not shape {a.shape}"
        )
    sr, cr = np.sin(a[..., 0]), np.cos(a[..., 0])
    sp, cp = np.sin(a[..., 1]), np.cos(a[..., 1])
    # yaw = pi/2 - heading: cos(yaw) = sin(heading), sin(yaw) = cos(heading)
    cy, sy = np.sin(a[..., 2]), np.cos(a[..., 2])
    R = np.empty((*a.shape[:-1], 3, 3))
    R[..., 0, 0] = cy * cp
    R[..., 0, 1] = -cy * sp * sr - sy * cr
    R[..., 0, 2] = -cy * sp * cr + sy * sr
    R[..., 1, 0] = sy * cp
    R[..., 1, 1] = -sy * sp * sr + cy * cr
    R[..., 1, 2] = -sy * sp * cr - cy * sr
    R[..., 2, 0] = sp
    R[..., 2, 1] = cp * sr
    R[..., 2, 2] = cp * cr
    return R
