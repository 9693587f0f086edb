"""Analytic accuracy of USBL fixes and dead reckoning (seed 000 sections 2 and 3).

USBL (eq. 1-7): the position lines of the azimuth and of the range cross at right angles, so the
mean error is ``M_xy = sqrt((sigma_alpha r)^2 + sigma_r^2)`` (eq. 5) and the mean error ellipse has
``a = sigma_alpha r`` across the line of sight and ``b = sigma_r`` along it (eq. 6-7).

Dead reckoning (eq. 8-14): one step of duration dt with course C and speed S adds the covariance
(eq. 10)

    sigma_x^2 = dt^2 ((S sigma_C cos C)^2 + (sigma_S sin C)^2)
    sigma_y^2 = dt^2 ((S sigma_C sin C)^2 + (sigma_S cos C)^2)
    sigma_xy  = dt^2 sin(2C) (sigma_S^2 - (S sigma_C)^2) / 2

Two readings of "the error after travelling t seconds" are offered and named:

* :func:`dr_covariance_single_step` evaluates eq. 10 as one step of length ``dt = t``: the error
  grows linearly with distance (seed 000 Figure 5: 25.54 m per 100 m at sigma_C = 3 deg,
  sigma_S = 0.25 m/s, S = 1 m/s). This is a systematic-error (fully correlated) reading.
* :func:`dr_covariance_random_walk` sums independent 1 s steps (eq. 9 with F = I): the covariance
  grows linearly with time and the mean error with sqrt(t). This is what a filter driven by
  independent per-second measurement errors sees.

x is east and y north (seed 000 eq. 8: ``x += S sin C``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import heading_from_yaw

Array = NDArray[np.float64]


def usbl_position_line_errors(
    r_m: ArrayLike, sigma_range_m: float, sigma_azimuth_rad: float
) -> tuple[Array, Array]:
    """Mean errors of the azimuth and range position lines (eq. 3-4).

    The gradient of alpha = atan(x/y) has norm 1/r and that of r = sqrt(x^2+y^2) has norm 1, so
    ``sigma_l(alpha) = sigma_alpha r`` and ``sigma_l(r) = sigma_r``.

    Returns:
        ``(sigma_l_alpha, sigma_l_r)``, m, shaped like ``r_m``.
    """
    r = np.asarray(r_m, dtype=float)
    return sigma_azimuth_rad * r, np.full_like(r, sigma_range_m)


def usbl_mean_error(r_m: ArrayLike, sigma_range_m: float, sigma_azimuth_rad: float) -> Array:
    """USBL horizontal mean error ``M_xy`` at horizontal distance ``r`` (eq. 5), m."""
    la, lr = usbl_position_line_errors(r_m, sigma_range_m, sigma_azimuth_rad)
    theta = np.pi / 2  # the position lines of a USBL always cross at right angles
    return np.sqrt(la**2 + lr**2) / np.sin(theta)


def usbl_ellipse(
    r_m: ArrayLike, sigma_range_m: float, sigma_azimuth_rad: float
) -> tuple[Array, Array]:
    """Semi-axes of the USBL mean error ellipse (eq. 6-7): ``a`` across, ``b`` along the line of
    sight, m."""
    la, lr = usbl_position_line_errors(r_m, sigma_range_m, sigma_azimuth_rad)
    return la, lr


def dr_step_covariance(
    course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    dt_s: ArrayLike,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
) -> Array:
    """Covariance added by one dead-reckoning step (eq. 10), shape (..., 2, 2), m^2."""
    c = np.asarray(course_rad, dtype=float)
    s = np.asarray(speed_m_s, dtype=float)
    dt = np.asarray(dt_s, dtype=float)
    c, s, dt = np.broadcast_arrays(c, s, dt)
    sx2 = dt**2 * ((s * sigma_course_rad * np.cos(c)) ** 2 + (sigma_speed_m_s * np.sin(c)) ** 2)
    sy2 = dt**2 * ((s * sigma_course_rad * np.sin(c)) ** 2 + (sigma_speed_m_s * np.cos(c)) ** 2)
    sxy = dt**2 * np.sin(2 * c) * (sigma_speed_m_s**2 - (s * sigma_course_rad) ** 2) / 2
    return np.stack([np.stack([sx2, sxy], -1), np.stack([sxy, sy2], -1)], -2)


def dr_covariance_single_step(
    t_s: ArrayLike,
    course_rad: float,
    speed_m_s: float,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
    P0: ArrayLike | None = None,
) -> Array:
    """Seed 000 Figure 5: ``P(t) = P0 + eq. 10 with dt = t`` (linear growth of the mean error).

    Returns:
        Covariances, shape (..., 2, 2), m^2, for each time in ``t_s``.
    """
    P = dr_step_covariance(course_rad, speed_m_s, t_s, sigma_course_rad, sigma_speed_m_s)
    return P + (0.0 if P0 is None else np.asarray(P0, dtype=float))


def dr_covariance_random_walk(
    t_s: ArrayLike,
    course_rad: float,
    speed_m_s: float,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
    step_s: float = 1.0,
    P0: ArrayLike | None = None,
) -> Array:
    """Covariance after ``t / step`` independent steps of ``step_s`` (eq. 9 with F = I, eq. 10),
    m^2, shape (..., 2, 2): the mean error grows with sqrt(t)."""
    steps = np.asarray(t_s, dtype=float) / step_s
    one = dr_step_covariance(course_rad, speed_m_s, step_s, sigma_course_rad, sigma_speed_m_s)
    P = steps[..., None, None] * one
    return P + (0.0 if P0 is None else np.asarray(P0, dtype=float))


def mean_error(P: ArrayLike) -> Array:
    """Mean error of coordinates ``M_xy = sqrt(sigma_x^2 + sigma_y^2)`` (eq. 11), m."""
    P = np.asarray(P, dtype=float)
    return np.sqrt(P[..., 0, 0] + P[..., 1, 1])


@dataclass(frozen=True)
class Ellipse:
    """A mean error ellipse.

    Attributes:
        a: semi-major axis, m.
        b: semi-minor axis, m.
        tau: direction of the major axis, rad, counter-clockwise from the x (east) axis, in
            (-pi/2, pi/2].
    """

    a: Array
    b: Array
    tau: Array

    @property
    def azimuth_rad(self) -> Array:
        """Major-axis direction as a navigation bearing, rad clockwise from north, in [0, pi)."""
        return heading_from_yaw(self.tau) % np.pi


def ellipse_parameters(P: ArrayLike) -> Ellipse:
    """Mean error ellipse of a 2x2 covariance (eq. 12-14).

    ``a, b = sqrt((sx2 + sy2 +- sqrt(p)) / 2)`` with ``p = (sx2 - sy2)^2 + 4 sxy^2`` and
    ``tau = atan2(2 sxy, sx2 - sy2) / 2``: eq. 14 written with the two-argument arctangent, so that
    tau is always the direction of the major axis (eq. 14's one-argument form gives the minor axis
    when sy2 > sx2).

    Args:
        P: covariance(s), shape (..., 2, 2) (a larger matrix uses its leading 2x2 block).

    Returns:
        The ellipse parameters, each of shape (...).
    """
    P = np.asarray(P, dtype=float)
    sx2, sy2, sxy = P[..., 0, 0], P[..., 1, 1], P[..., 0, 1]
    p = (sx2 - sy2) ** 2 + 4 * sxy**2
    a = np.sqrt(0.5 * (sx2 + sy2 + np.sqrt(p)))
    b = np.sqrt(np.maximum(0.5 * (sx2 + sy2 - np.sqrt(p)), 0.0))
    tau = 0.5 * np.arctan2(2 * sxy, sx2 - sy2)
    return Ellipse(a, b, tau)
