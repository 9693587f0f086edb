"""The course to a way-point that compensates the estimated current and the vehicle's systematic
error (seed 001 eq. 22-26, with CP2's three-phase fix).

References:
    Praczyk T., Correction of navigational information supplied to biomimetic autonomous
    underwater vehicle (seed 001), eq. 22-26.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import course_of, unit_vector, wrap_2pi
from nav.errors import NavInputError
from nav.surfacing.estimate import CorrectionEstimate

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CourseSolution:
    """A compensated course for a batch of runs.

    Attributes:
        course_rad: the course to steer ``alpha`` (eq. 25-26), shape (n,), rad in [0, 2 pi).
        speed_along_m_s: the predicted speed over ground along the desired course ``nu``, shape
            (n,), m/s (> 0 when feasible).
        feasible: whether some course makes the predicted track follow ``nu`` with progress
            (False: see :func:`course_through_current` for the fallback), shape (n,).
    """

    course_rad: Array
    speed_along_m_s: Array
    feasible: NDArray[np.bool_]


def course_through_current(
    desired_course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    vs_m_s: ArrayLike,
    beta_rad: ArrayLike,
    current_world_m_s: ArrayLike,
) -> CourseSolution:
    """One solve of eq. 22-26: the course whose predicted ground track follows ``nu``.

    The vehicle's velocity through water on course ``alpha`` is
    ``W = |Va| u(alpha) + vs u(alpha + beta)``: magnitude
    ``R = |(|Va| + vs cos beta, vs sin beta)|`` (eq. 24, printed without the square root)
    at the angle ``delta = atan2(vs sin beta, |Va| + vs cos beta)`` from the course (eq. 26's
    ``getCourse180(U1, U2)``, whose printed ``U2`` omits ``|Va|`` and whose ``U1, U2`` name
    ``|Vc,CP|`` for ``|Vs,CP|``; printed literally it would subtract ``beta`` itself, 15 deg too
    much at ``|Vs| = 0.3``, ``beta = 20``: the exact angle of ``W`` is used).
    Eq. 22-23 ask for ``W`` with ``|W| = R`` and ``W + Vc`` along ``nu``: ``W = lam u(nu) - Vc``,

        ``lam = u(nu).Vc +- sqrt(R^2 - (u(nu) x Vc)^2)``.

    The paper's form, with ``tan(theta(nu))`` folding ``nu`` into [0, 90] deg and both equations
    squared, has four solutions: these two roots on the line along ``nu`` and two on its mirror
    line, whose resulting velocity is not along ``nu``. The paper keeps the one "which leads the
    vehicle along the course nu with the highest resulting velocity": ``lam+``. Then
    ``alpha = getCourse360(W) - delta`` (eq. 25-26). No course is special (the paper's footnote 2
    treats ``nu`` in {0, 90, 180, 270} separately because ``tan`` is 0 or infinite there).

    Fallbacks (``feasible`` False, never NaN): if the current across ``nu`` exceeds ``R``, the
    course that cancels as much of it as possible (``W = -R`` times the unit cross-track current);
    if even ``lam+ <= 0`` (the current against ``nu`` exceeds what the vehicle makes good), ``lam+``
    is kept (the track stays on the line, drifting back); if ``R = 0``, ``alpha = nu``.

    Args:
        desired_course_rad: direct course ``nu`` to the way-point, shape (n,), rad.
        speed_m_s: odometry speed ``|Va|``, shape (n,) or scalar, m/s.
        vs_m_s: signed ``|Vs|`` (eq. 34), shape (n,) or scalar, m/s.
        beta_rad: deviation of ``Vs`` from the course, shape (n,) or scalar, rad.
        current_world_m_s: the current to compensate, shape (n, 2), m/s, world.

    Returns:
        The solution.
    """
    nu = np.asarray(desired_course_rad, dtype=float)
    c = np.asarray(current_world_m_s, dtype=float)
    n = nu.shape[0]
    va = np.broadcast_to(np.asarray(speed_m_s, dtype=float), (n,))
    vs = np.broadcast_to(np.asarray(vs_m_s, dtype=float), (n,))
    beta = np.broadcast_to(np.asarray(beta_rad, dtype=float), (n,))
    along_x = va + vs * np.cos(beta)
    along_y = vs * np.sin(beta)
    R = np.hypot(along_x, along_y)
    delta = np.arctan2(along_y, along_x)
    u = unit_vector(nu)
    c_along = np.sum(u * c, axis=-1)
    c_cross_vec = c - c_along[:, None] * u
    disc = R * R - np.sum(c_cross_vec * c_cross_vec, axis=-1)
    lam = c_along + np.sqrt(np.maximum(disc, 0.0))
    W = lam[:, None] * u - c
    cross_mag = np.hypot(c_cross_vec[:, 0], c_cross_vec[:, 1])
    too_strong = disc < 0.0
    safe = np.where(cross_mag > 0.0, cross_mag, 1.0)
    W_fb = -R[:, None] * c_cross_vec / safe[:, None]
    W = np.where(too_strong[:, None], W_fb, W)
    resulting = W + c
    speed_along = np.sum(resulting * u, axis=-1)
    alpha = wrap_2pi(np.where(R > 0.0, course_of(W) - delta, nu))
    feasible = ~too_strong & (speed_along > 0.0) & (R > 0.0)
    return CourseSolution(alpha, speed_along, feasible)


def compensated_course(
    desired_course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    estimate: CorrectionEstimate,
    *,
    reference_course_rad: ArrayLike | None = None,
) -> CourseSolution:
    """The course to a way-point that compensates an estimate (seed 001, section 3.5).

    Without a hull response (CP1, baseline) one solve of eq. 22-26
    (:func:`course_through_current`). With one (CP2) the current depends on the course it is meant
    to determine, so the paper's three phases: (1) solve with the current estimated for the
    reference course (45 deg); (2) rescale the current to that solution's course with eq. 21;
    (3) solve again with the rescaled current.

    Args:
        desired_course_rad: direct course ``nu`` to the way-point, shape (n,), rad.
        speed_m_s: odometry speed ``|Va|``, shape (n,) or scalar, m/s.
        estimate: the correction estimate for the ``n`` runs.
        reference_course_rad: the course of phase 1's current, shape (n,); default the estimate's
            ``reference_course_rad``.

    Returns:
        The solution.
    """
    nu = np.asarray(desired_course_rad, dtype=float)
    if nu.shape != (estimate.n,):
        raise NavInputError(
            f"desired_course_rad has shape {nu.shape}: expected ({estimate.n},) runs"
        )
    if estimate.response is None:
        return course_through_current(
            nu, speed_m_s, estimate.vs_m_s, estimate.beta_rad, estimate.current_world_m_s
        )
    ref = estimate.reference_course_rad if reference_course_rad is None else reference_course_rad
    phase1 = course_through_current(
        nu, speed_m_s, estimate.vs_m_s, estimate.beta_rad, estimate.current_for_course(ref)
    )
    current = estimate.current_for_course(phase1.course_rad)
    return course_through_current(nu, speed_m_s, estimate.vs_m_s, estimate.beta_rad, current)
