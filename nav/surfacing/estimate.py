"""What seed 001's correction procedures estimate: the vehicle's systematic velocity error ``Vs``
(a signed magnitude along ``course + beta``, eq. 34's sign) and the current ``Vc``, carried to
other courses by the hull's response to the current (eq. 21, 29).

Conventions as in :mod:`nav.surfacing.procedures`: x east, y north; courses clockwise from north
in radians; a leading axis of runs ``n``.

References:
    Praczyk T., Correction of navigational information supplied to biomimetic autonomous
    underwater vehicle (seed 001), eq. 21, 29, 32-34.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import chebyshev
from numpy.typing import ArrayLike, NDArray

from nav.angles import course_of, diff_course, unit_vector, wrap_pi
from nav.errors import NavInputError

Array = NDArray[np.float64]

DEFAULT_RHO_S_COS_COEFFS: tuple[float, ...] = (1.0, 0.2, 0.15)
"""Default hull response ``rho_s(gamma) = 1 + 0.2 cos(gamma) + 0.15 cos(2 gamma)``; see
:class:`CurrentResponse` for the justification."""


# --------------------------------------------------------------------------------------------
# The current's effect versus the angle between the hull and the current


@dataclass(frozen=True)
class CurrentResponse:
    """The hull's response to the current versus the angle ``gamma`` between the vehicle's course
    and the current's set direction: seed 001's ``rho`` (eq. 21) and ``rho_s`` (eq. 29).

    The paper's ``rho`` is a curve measured on the ROV "Gluptak" (1 m/s, current 0.4 m/s) and is not
    printed; only ratios ``rho(gamma_2) / rho(gamma_1)`` are ever used, so its scale is free. Here
    it is a cosine series

        ``rho_s(gamma) = sum_k a_k cos(k gamma)``

    which is even in ``gamma`` - the same for a current from port or from starboard (10 and 350
    deg), the symmetry the paper gives ``rho_s`` ("symmetrical only with respect to axis Y of the
    vehicle", its longitudinal axis) - and ``rho`` keeps only the even ``k``:

        ``rho(gamma) = (rho_s(gamma) + rho_s(pi - gamma)) / 2 = sum_{k even} a_k cos(k gamma)``

    which is in addition the same for a current from ahead or from astern (10 and 170 deg): the
    symmetry about both vehicle axes that CP2 needs (eq. 13-16, Fig. 5). ``rho`` is thus the
    bow-stern average of ``rho_s``: what a CP that can only see the symmetric part would model.

    Default ``(a_0, a_1, a_2) = (1, 0.2, 0.15)``: ``rho_s`` is 1.35 with the current from astern
    (0 deg), 0.85 across (90 deg) and 0.95 from ahead (180 deg); ``rho = 1 + 0.15 cos 2 gamma``
    (35 % more effect along the hull than across). The text gives no curve and no physical model
    that would fix it, so the default is fitted to the paper's own results: a grid search over
    ``a_1, a_2`` in {0, 0.05, ..., 0.25} minimising the RMS log ratio between the replica's means
    and the paper's Tables 1 and 3 (without-CP, CP1 and CP2 rows, 40 values), 30 missions on each of
    seeds 101-103 (never the reported seed), step 0.02 s
    (:func:`tasks.paper001.paper_fit_objective`). The optimum, 0.27 (about 30 % per value, much of
    it the sampling error of a 30-mission mean), is flat over ``a_1`` 0.15-0.25 and ``a_2``
    0.1-0.2; a uniform response ``(1,)`` scores 0.74 and ``(1, 0.1, 0.1)`` 0.41. Through eq. 29's
    normalisation by ``rho_s(20 deg)`` the effective current then ranges from 0.65 to 1.04
    ``|Vc|``. ``(1.0,)`` is a hull on which the current acts the same at every angle.

    Attributes:
        cos_coeffs: ``(a_0, a_1, ...)``, dimensionless; ``rho_s`` must be positive on [0, pi].

    Raises:
        NavInputError: if the coefficients are empty, not finite or ``rho_s`` is not positive.
    """

    cos_coeffs: tuple[float, ...] = DEFAULT_RHO_S_COS_COEFFS
    _even: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        a = np.asarray(self.cos_coeffs, dtype=float)
        if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
            raise NavInputError(
                f"cos_coeffs = {self.cos_coeffs!r}: need at least one finite coefficient"
            )
        g = np.linspace(0.0, np.pi, 3601)
        low = float(np.min(chebyshev.chebval(np.cos(g), a)))
        if low <= 0.0:
            raise NavInputError(
                f"cos_coeffs = {self.cos_coeffs!r}: rho_s must be positive on [0, 180] deg "
                f"(its minimum is {low:.3g})"
            )
        even = np.where(np.arange(a.size) % 2 == 0, a, 0.0)
        object.__setattr__(self, "cos_coeffs", tuple(float(x) for x in a))
        object.__setattr__(self, "_even", tuple(float(x) for x in even))

    def rho_s(self, gamma_rad: ArrayLike) -> Array:
        """``rho_s(gamma)`` of eq. 29 (port-starboard symmetric), any shape, dimensionless."""
        return chebyshev.chebval(np.cos(np.asarray(gamma_rad, dtype=float)), self.cos_coeffs)

    def rho(self, gamma_rad: ArrayLike) -> Array:
        """``rho(gamma)`` of eq. 21 (symmetric about both vehicle axes), any shape."""
        return chebyshev.chebval(np.cos(np.asarray(gamma_rad, dtype=float)), self._even)


# --------------------------------------------------------------------------------------------
# Estimates


def vs_sign(vs_world_m_s: ArrayLike, course_rad: ArrayLike) -> Array:
    """Sign of the systematic error ``Vs`` relative to the course (eq. 34).

    ``+1`` when ``U3 = diffCourse(getCourse360(Vs), alpha) < 90 deg`` (``Vs`` adds to the
    progressive speed), ``-1`` otherwise; ``+1`` for ``Vs = 0``.

    Args:
        vs_world_m_s: ``Vs`` (east, north), shape (..., 2), m/s, world.
        course_rad: the course ``alpha``, shape broadcastable with ``vs_world_m_s[..., 0]``, rad.

    Returns:
        ``+1.0`` or ``-1.0``, shape (...).
    """
    v = np.asarray(vs_world_m_s, dtype=float)
    u3 = diff_course(course_of(v), course_rad)
    zero = np.hypot(v[..., 0], v[..., 1]) == 0.0
    return np.where((u3 < np.pi / 2) | zero, 1.0, -1.0)


def _signed_vs(vs_world: Array, course_rad: Array) -> tuple[Array, Array]:
    """``(vs, beta)`` with ``Vs = vs u(course + beta)``, sign from eq. 34, beta in [-pi/2, pi/2]."""
    sign = vs_sign(vs_world, course_rad)
    mag = np.hypot(vs_world[..., 0], vs_world[..., 1])
    beta = wrap_pi(course_of(vs_world) - course_rad - np.where(sign < 0, np.pi, 0.0))
    return sign * mag, np.where(mag > 0.0, beta, 0.0)


@dataclass(frozen=True)
class CorrectionEstimate:
    """What a correction procedure estimates, for a batch of runs.

    The vehicle's velocity error on course ``alpha`` is ``Vs + Vc(alpha)`` with
    ``Vs = vs u(alpha + beta)`` (eq. 32-33) and ``Vc(alpha)`` from :meth:`current_for_course`.

    Attributes:
        method: ``"cp1"``, ``"cp2"``, ``"baseline"`` or ``"none"``.
        vs_m_s: signed magnitude of ``Vs`` (sign of eq. 34), shape (n,), m/s.
        beta_rad: deviation of ``Vs`` from the course, shape (n,), rad in [-pi/2, pi/2].
        current_world_m_s: estimated current (east, north) on ``reference_course_rad``, shape
            (n, 2), m/s, world.
        reference_course_rad: the course the current estimate belongs to (CP2: the first leg's,
            eq. 21's ``alpha_1``), shape (n,), rad.
        response: the hull response used to carry the current to other courses (eq. 21), or
            ``None`` when the estimate does not depend on the course (CP1, baseline).
        residual_m_s: ``sqrt(F)`` of eq. 12 at the solution (0 for the closed forms), shape (n,),
            m/s.
        valid: False for runs whose input was unusable and that got the no-correction fallback
            (``vs = 0``, current 0: corrected DR equals uncorrected DR), shape (n,).
    """

    method: str
    vs_m_s: Array
    beta_rad: Array
    current_world_m_s: Array
    reference_course_rad: Array
    response: CurrentResponse | None
    residual_m_s: Array
    valid: NDArray[np.bool_]

    @property
    def n(self) -> int:
        """Number of runs."""
        return self.vs_m_s.shape[0]

    @classmethod
    def none(cls, n: int) -> CorrectionEstimate:
        """The no-correction estimate (corrected DR = uncorrected DR) for ``n`` runs."""
        z = np.zeros(n)
        return cls(
            "none", z, z.copy(), np.zeros((n, 2)), z.copy(), None, z.copy(), np.ones(n, bool)
        )

    def _expand(self, a: Array, course: Array) -> Array:
        """Reshape a per-run array (n, ...) to broadcast against courses of shape (n, k...)."""
        return a.reshape((self.n,) + (1,) * (course.ndim - 1) + a.shape[1:])

    def current_for_course(self, course_rad: ArrayLike) -> Array:
        """The estimated current for a vehicle on ``course_rad`` (eq. 21).

        ``|Vc,alpha_2| = |Vc,alpha_1| rho(gamma_2) / rho(gamma_1)`` with ``gamma_i`` the angle
        between the estimated current's direction and ``alpha_i`` (``diffCourse``); the direction is
        unchanged. Without a response the estimate is returned for every course.

        Args:
            course_rad: courses, shape (n,) or (n, k...), rad.

        Returns:
            Current (east, north), shape ``course_rad.shape + (2,)``, m/s, world.
        """
        course = self._course_array(course_rad)
        c = self._expand(self.current_world_m_s, course)
        if self.response is None:
            return np.broadcast_to(c, course.shape + (2,)).copy()
        set_dir = course_of(c)
        g1 = diff_course(set_dir, self._expand(self.reference_course_rad, course))
        g2 = diff_course(set_dir, course)
        ratio = self.response.rho(g2) / self.response.rho(g1)
        return c * ratio[..., None]

    def vs_world(self, course_rad: ArrayLike) -> Array:
        """``Vs = vs u(course + beta)`` on ``course_rad`` (eq. 32-33), shape
        ``course.shape + (2,)``, m/s, world."""
        course = self._course_array(course_rad)
        vs = self._expand(self.vs_m_s, course)
        beta = self._expand(self.beta_rad, course)
        return vs[..., None] * unit_vector(course + beta)

    def velocity_error(self, course_rad: ArrayLike) -> Array:
        """``Vs + Vc(course)``: what corrected DR adds to ``|Va| u(course)``; shape
        ``course.shape + (2,)``, m/s, world."""
        return self.vs_world(course_rad) + self.current_for_course(course_rad)

    def _course_array(self, course_rad: ArrayLike) -> Array:
        course = np.asarray(course_rad, dtype=float)
        if course.ndim == 0 or course.shape[0] != self.n:
            raise NavInputError(
                f"course_rad has shape {course.shape}: expected a leading axis of {self.n} runs"
            )
        return course
