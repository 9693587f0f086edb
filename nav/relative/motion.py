"""Seed 003's motion of the follower: the displacement of a dead-reckoning step from the measured
course and speed (eq. 1), its covariance (eq. 5), the mean position error (eq. 6), the batched DR
track with its covariance, and the same motion as an EKF motion model.

The accumulation (position plus displacement, covariance plus increment) is
:mod:`nav.dead_reckoning`'s, the one dead reckoning; this module only says what a step of seed
003's follower moves and how uncertain that is. Positions are (east, north) in m, courses in rad
clockwise from north; arrays carry a leading run axis n.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav import dead_reckoning
from nav.dead_reckoning import DeadReckonedTrack

Array = NDArray[np.float64]


def dr_increment(course_rad: ArrayLike, speed_m_s: ArrayLike, dt_s: float) -> Array:
    """The displacement of one dead-reckoning step (seed 003, eq. 1, without the random term):
    ``dt S (sin C, cos C)``.

    Args:
        course_rad: measured course C(k+i-1), shape (n,), rad, clockwise from north.
        speed_m_s: measured speed S(k+i-1), shape (n,), m/s.
        dt_s: step Delta t(k+i), s.

    Returns:
        Displacements (east, north), shape (n, 2), m.
    """
    c = np.asarray(course_rad, dtype=float)
    s = np.asarray(speed_m_s, dtype=float) * dt_s
    return np.stack([s * np.sin(c), s * np.cos(c)], axis=-1)


def dr_step(position: ArrayLike, course_rad: ArrayLike, speed_m_s: ArrayLike, dt_s: float) -> Array:
    """One dead-reckoning step (seed 003, eq. 1, without the random term):
    :func:`nav.dead_reckoning.step` with the displacement of :func:`dr_increment`.

    Args:
        position: positions at k+i-1, shape (n, 2), m (east, north).
        course_rad: measured course C(k+i-1), shape (n,), rad, clockwise from north.
        speed_m_s: measured speed S(k+i-1), shape (n,), m/s.
        dt_s: step Delta t(k+i), s.

    Returns:
        Positions at k+i, shape (n, 2), m.
    """
    return dead_reckoning.step(position, dr_increment(course_rad, speed_m_s, dt_s))


def dr_increment_covariance(
    course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    dt_s: float,
    sigma_course_rad: float,
    sigma_speed_m_s: ArrayLike,
) -> Array:
    """Covariance of one DR step's displacement (seed 003, eq. 5).

    ``sigma_x^2 = dt^2 ((S sigma_C cos C)^2 + (sigma_S sin C)^2)``,
    ``sigma_y^2 = dt^2 ((S sigma_C sin C)^2 + (sigma_S cos C)^2)``,
    ``sigma_xy = dt^2 sin(2C) (sigma_S^2 - (S sigma_C)^2) / 2``: the first-order propagation of
    independent course and speed errors through eq. 1.

    Args:
        course_rad: course C(k+i-1), shape (n,), rad.
        speed_m_s: speed S(k+i-1), shape (n,), m/s.
        dt_s: step, s.
        sigma_course_rad: the course's mean error sigma_C, rad.
        sigma_speed_m_s: the speed's mean error sigma_S, m/s: one for every step, or shape (n,).

    Returns:
        Shape (n, 2, 2), m^2.
    """
    c = np.asarray(course_rad, dtype=float)
    a = np.asarray(speed_m_s, dtype=float) * sigma_course_rad
    b = np.asarray(sigma_speed_m_s, dtype=float)
    sin, cos = np.sin(c), np.cos(c)
    out = np.empty((*c.shape, 2, 2))
    dt2 = dt_s * dt_s
    out[..., 0, 0] = dt2 * ((a * cos) ** 2 + (b * sin) ** 2)
    out[..., 1, 1] = dt2 * ((a * sin) ** 2 + (b * cos) ** 2)
    out[..., 0, 1] = out[..., 1, 0] = dt2 * np.sin(2.0 * c) * (b * b - a * a) / 2.0
    return out


def mean_position_error(cov: ArrayLike) -> Array:
    """``M_xy = sqrt(sigma_x^2 + sigma_y^2)`` of a covariance (seed 003, eq. 6).

    Args:
        cov: shape (n, 2, 2), m^2.

    Returns:
        Shape (n,), m.
    """
    c = np.asarray(cov, dtype=float)
    return np.sqrt(np.maximum(c[..., 0, 0] + c[..., 1, 1], 0.0))


def dr_track(
    course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    start_m: ArrayLike,
    dt_s: float,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
) -> DeadReckonedTrack:
    """Dead reckoning of a batch of runs from the measured course and speed (eq. 1) with the
    eq. 5 covariance summed from the start (:func:`nav.dead_reckoning.track_with_covariance`).

    Args:
        course_rad: measured course of each step k -> k + 1, shape (n, T), rad.
        speed_m_s: measured speed of each step, shape (n, T), m/s.
        start_m: the known start, shape (2,) or (n, 2), m (east, north); its covariance is zero.
        dt_s: the step, s.
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.

    Returns:
        Positions (n, T + 1, 2) m and covariances since the start (n, T + 1, 2, 2) m^2.
    """
    course = np.asarray(course_rad, dtype=float)
    n, T = course.shape
    c, s = course.ravel(), np.asarray(speed_m_s, dtype=float).ravel()
    inc = dr_increment(c, s, dt_s).reshape(n, T, 2)
    dc = dr_increment_covariance(c, s, dt_s, sigma_course_rad, sigma_speed_m_s).reshape(n, T, 2, 2)
    start = np.broadcast_to(np.asarray(start_m, dtype=float), (n, 2))
    return dead_reckoning.track_with_covariance(start, inc, dc)


@dataclass(frozen=True)
class CourseSpeedMotion:
    """The follower's horizontal motion for an EKF (seed 003 eq. 1 with Q = eq. 5).

    State ``x = (east, north)`` m; input ``u = (course rad, speed m/s)``; ``f = x + dt S (sin C,
    cos C)``, ``F = I``, ``Q`` = eq. 5.

    Attributes:
        sigma_course_rad: sigma_C, rad.
        sigma_speed_m_s: sigma_S, m/s.
    """

    sigma_course_rad: float
    sigma_speed_m_s: float

    def f(self, x: Array, u: Array, dt_s: float) -> Array:
        """Predicted states, shape (n, 2)."""
        return dr_step(x, u[:, 0], u[:, 1], dt_s)

    def F(self, x: Array, u: Array, dt_s: float) -> Array:
        """State Jacobian (the identity), shape (n, 2, 2)."""
        return np.broadcast_to(np.eye(2), (len(x), 2, 2)).copy()

    def Q(self, u: Array, dt_s: float) -> Array:
        """Process noise (eq. 5), shape (n, 2, 2), m^2."""
        return dr_increment_covariance(
            u[:, 0], u[:, 1], dt_s, self.sigma_course_rad, self.sigma_speed_m_s
        )

    def predict_one(self, x: Array, P: Array, u: Array, dt_s: float) -> tuple[Array, Array]:
        """The prediction of one run (F = I): ``(x + dx, P + Q)``, shapes (1, 2), (1, 2, 2)."""
        return self.f(x, u, dt_s), P + self.Q(u, dt_s)
