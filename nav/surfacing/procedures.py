"""Seed 001's correction procedures: sea current and the vehicle's systematic velocity error from
GPS fixes at surfacing.

The vehicle of seed 001 dead-reckons from the odometry speed ``|Va|`` of its drive setting and the
compass course ``alpha`` only (eq. 30-31), so the position error of a leg of duration ``T`` is

    ``delta = S_GPS - S_DR = (Vs + Vc) T``                                      (eq. 5-10)

where ``Vs`` is the vehicle's systematic velocity error (constant magnitude, deviated from the
course by a constant angle ``beta``) and ``Vc`` the sea current's effect. This module estimates
``Vs``, ``beta`` and ``Vc`` from the errors of two legs:

* :func:`cp1` - correction procedure 1 (eq. 7-12): two legs on arbitrary, non-parallel courses;
  the current is assumed the same on both.
* :func:`cp2` - correction procedure 2 (eq. 13-21): two legs on opposite courses (45 and 225 deg
  in the paper); closed form; the current is rescaled to other courses with the hull-response
  model ``xi`` / ``rho`` of eq. 21 (:class:`~nav.surfacing.estimate.CurrentResponse`).
* :func:`baseline` - the simple published estimator: current = (GPS fix - DR position) / time
  since the last fix, no vehicle error (``../shared/notes/navigation.md``).

The estimates (:class:`~nav.surfacing.estimate.CorrectionEstimate`) serve corrected DR
(:func:`~nav.surfacing.drns.dr_velocity`, :func:`~nav.surfacing.drns.dr_track`: eq. 32-33) and
the course that compensates the estimated current and vehicle error
(:func:`~nav.surfacing.course.compensated_course`: eq. 22-26, with CP2's three-phase fix).

Conventions (:mod:`nav.angles`): x east, y north; courses clockwise from north in radians, the
paper's degrees only in names that say so; ``u(c) = (sin c, cos c)`` is the unit vector of course
``c`` (:func:`~nav.angles.unit_vector`), ``getCourse360`` is :func:`~nav.angles.course_of` and
``diffCourse`` :func:`~nav.angles.diff_course`. Arrays carry a leading axis of runs ``n`` (one
run is a batch of one).

Vector formulation (differences from the printed equations, all documented where they occur):

* The paper writes every velocity by its x component and ``tan(psi(.))`` of its course
  (``V^y = V^x tan(psi(alpha))``), which is ``V^y = V^x cot(alpha)``: singular at courses 0 and
  180 deg (``V^x = 0``) and at 90 / 270 deg (``psi`` undefined). Here a velocity with course ``c``
  and signed magnitude ``s`` is ``s u(c)``; no course is special and nothing produces inf or NaN.
* ``Vs`` is one signed magnitude ``vs`` along ``course + beta`` (``beta`` in [-90, 90) deg, the sign
  given by eq. 34) shared by both legs. The paper's eq. 11-12 instead keep two x components tied
  only by ``|Vs,1| = |Vs,2|`` (Error_5), which also admits ``Vs`` reversing between the legs: a
  second zero of eq. 12 that is physically meaningless (eq. 34 exists to repair the sign
  afterwards). With one signed magnitude Error_5 vanishes identically.
* ``Delta S = S_GPS - S_DR`` as in the section "Formulation"; the experiment section's
  ``S_noCP - S_GPS`` is a slip (with it eq. 7 would estimate ``-(Vs + Vc)``).

References:
    Praczyk T., Correction of navigational information supplied to biomimetic autonomous
    underwater vehicle (seed 001), eq. 5-34.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import diff_course, unit_vector
from nav.errors import NavInputError
from nav.surfacing.estimate import CorrectionEstimate, CurrentResponse, _signed_vs

Array = NDArray[np.float64]
OnBad = Literal["raise", "fallback"]


# --------------------------------------------------------------------------------------------
# Input checks shared by the procedures


def _bad_rows(message: str, rows: NDArray[np.bool_], on_bad: OnBad) -> None:
    if np.any(rows) and on_bad == "raise":
        idx = np.flatnonzero(rows)
        shown = ", ".join(str(i) for i in idx[:5]) + (", ..." if idx.size > 5 else "")
        raise NavInputError(f"{message} (run{'s' if idx.size > 1 else ''} {shown})")


def _leg_inputs(
    delta_world_m: ArrayLike | None,
    duration_s: ArrayLike,
    course_rad: ArrayLike,
    on_bad: OnBad,
    procedure: str,
) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """Validate two-leg inputs; return ``(m, T, course, bad)`` with ``m = delta / T`` (n, 2, 2)."""
    if on_bad not in ("raise", "fallback"):
        raise NavInputError(f"on_bad = {on_bad!r}: must be 'raise' or 'fallback'")
    if delta_world_m is None:
        raise NavInputError(
            f"{procedure}: no GPS fix available: the position errors of the two legs "
            "(GPS fix minus DR) are needed"
        )
    d = np.asarray(delta_world_m, dtype=float)
    if d.ndim != 3 or d.shape[1:] != (2, 2):
        raise NavInputError(
            f"{procedure}: delta_world_m has shape {d.shape}: "
            "expected (n runs, 2 legs, 2 east/north)"
        )
    n = d.shape[0]
    try:
        T = np.broadcast_to(np.asarray(duration_s, dtype=float), (n, 2))
        c = np.broadcast_to(np.asarray(course_rad, dtype=float), (n, 2))
    except ValueError:
        raise NavInputError(
            f"{procedure}: duration_s {np.shape(duration_s)} and course_rad {np.shape(course_rad)} "
            f"must broadcast to (n, 2) = ({n}, 2)"
        ) from None
    no_fix = ~np.all(np.isfinite(d), axis=(1, 2))
    _bad_rows(f"{procedure}: no GPS fix available (non-finite position error)", no_fix, on_bad)
    bad_T = ~np.all(np.isfinite(T) & (T > 0.0), axis=1)
    _bad_rows(
        f"{procedure}: leg durations must be finite and > 0 s, got {T[bad_T][:1].tolist()}",
        bad_T,
        on_bad,
    )
    bad_c = ~np.all(np.isfinite(c), axis=1)
    _bad_rows(f"{procedure}: courses must be finite", bad_c, on_bad)
    bad = no_fix | bad_T | bad_c
    safe_T = np.where(bad[:, None], 1.0, T)
    m = np.where(bad[:, None, None], 0.0, d) / safe_T[..., None]
    return m, safe_T, np.where(bad[:, None], 0.0, c), bad


def _fallback(est: CorrectionEstimate, bad: NDArray[np.bool_]) -> CorrectionEstimate:
    """Replace the estimates of bad runs by the no-correction estimate."""
    if not np.any(bad):
        return est
    keep = ~bad
    return CorrectionEstimate(
        est.method,
        np.where(keep, est.vs_m_s, 0.0),
        np.where(keep, est.beta_rad, 0.0),
        np.where(keep[:, None], est.current_world_m_s, 0.0),
        np.where(keep, est.reference_course_rad, 0.0),
        est.response,
        np.where(keep, est.residual_m_s, 0.0),
        keep & est.valid,
    )


# --------------------------------------------------------------------------------------------
# CP1


def cp1_objective(params: ArrayLike, m_world_m_s: ArrayLike, course_rad: ArrayLike) -> Array:
    """Eq. 12: ``F = sum_i Error_i`` in the vector formulation.

    ``F = |vs u(alpha_1 + beta) + Vc - dS_1/T_1|^2 + |vs u(alpha_2 + beta) + Vc - dS_2/T_2|^2``:
    Error_1 + Error_2 (first leg) and Error_3 + Error_4 (second leg); Error_5 (``|Vs,1| = |Vs,2|``)
    is zero by construction because both legs share the signed magnitude ``vs``.

    Args:
        params: ``(vs m/s, beta rad, Vc east m/s, Vc north m/s)``, shape (..., 4).
        m_world_m_s: mean velocity errors ``dS_j / T_j`` of the two legs, shape (..., 2, 2), m/s.
        course_rad: the two legs' courses, shape (..., 2), rad.

    Returns:
        ``F``, shape (...), m^2/s^2.
    """
    p = np.asarray(params, dtype=float)
    r, _ = _cp1_residual_jacobian(
        p, np.asarray(m_world_m_s, dtype=float), np.asarray(course_rad, dtype=float)
    )
    return np.sum(r * r, axis=-1)


def _cp1_residual_jacobian(p: Array, m: Array, course: Array) -> tuple[Array, Array]:
    """Residuals (..., 4) and Jacobian (..., 4, 4) of eq. 12 w.r.t. (vs, beta, cx, cy)."""
    vs, beta, c = p[..., 0], p[..., 1], p[..., 2:]
    a1 = course[..., 0] + beta
    a2 = course[..., 1] + beta
    u1, u2 = unit_vector(a1), unit_vector(a2)
    du1 = np.stack([np.cos(a1), -np.sin(a1)], axis=-1)
    du2 = np.stack([np.cos(a2), -np.sin(a2)], axis=-1)
    r = np.concatenate(
        [vs[..., None] * u1 + c - m[..., 0, :], vs[..., None] * u2 + c - m[..., 1, :]], axis=-1
    )
    J = np.zeros(p.shape[:-1] + (4, 4))
    J[..., 0:2, 0] = u1
    J[..., 2:4, 0] = u2
    J[..., 0:2, 1] = vs[..., None] * du1
    J[..., 2:4, 1] = vs[..., None] * du2
    J[..., 0, 2] = J[..., 2, 2] = 1.0
    J[..., 1, 3] = J[..., 3, 3] = 1.0
    return r, J


def cp1(
    delta_world_m: ArrayLike | None,
    duration_s: ArrayLike,
    course_rad: ArrayLike,
    *,
    beta_max_rad: float = math.radians(20.0),
    beta_step_rad: float = math.radians(1.0),
    min_separation_rad: float = math.radians(5.0),
    max_iter: int = 100,
    on_bad: OnBad = "raise",
) -> CorrectionEstimate:
    """Correction procedure 1 (seed 001, eq. 7-12): two legs on different, non-opposite courses.

    Model of leg ``j`` (``j = 1, 2``): ``dS_j / T_j = vs u(alpha_j + beta) + Vc`` with the same
    current on both legs (CP1 neglects the hull's course-dependent response).

    Phase 1 (eq. 7-10 with ``beta = 0``): the linear system
    ``dS_j / T_j = s_j u(alpha_j) + Vc`` in ``(s_1, s_2, Vc)``, solved exactly. It is singular when
    the courses are the same or opposite, which is why CP1 rejects them (for opposite courses use
    :func:`cp2`). Its ``Vc`` and ``(s_1 + s_2) / 2`` start phase 2.

    Phase 2: a descent on eq. 12 (:func:`cp1_objective`) over ``(vs, beta, Vc)`` from every starting
    ``beta`` in ``-beta_max, -beta_max + step, ..., beta_max`` (41 starts at the paper's 20 deg
    and 1 deg). The descent is a damped Gauss-Newton (Levenberg-Marquardt) iteration implemented
    here in numpy and batched over runs and starts: a gradient method on the same objective that
    does not need a hand-tuned step size (the paper's "simple gradient descent" would need one per
    data scale and thousands of iterations). The start with the lowest ``F`` wins (the first on a
    tie) and ``(vs, beta)`` is normalised with eq. 34.

    With a shared signed ``vs`` the four equations in four unknowns always have an exact solution
    (``F = 0``) when the courses differ: ``beta = course(dS_1/T_1 - dS_2/T_2) - (alpha_1 +
    alpha_2)/2 - 90 deg (mod 180)``, unique with ``beta`` in [-90, 90). On noise-free data it is the
    truth; on real data the model error (the current differs between the legs) goes into the
    estimate.

    Args:
        delta_world_m: position errors ``S_GPS - S_DR`` accumulated over each leg (DR restarted at
            the leg's start fix), shape (n, 2, 2) = (runs, legs, east/north), m, world; ``None``
            when there is no fix.
        duration_s: leg durations ``T_j``, shape (n, 2) or broadcastable, s (> 0).
        course_rad: courses ``alpha_j`` steered on the legs, shape (n, 2) or broadcastable, rad.
        beta_max_rad: half-width of the range of starting ``beta`` (paper: 20 deg).
        beta_step_rad: spacing of the starting ``beta`` (paper: 1 deg).
        min_separation_rad: courses closer than this to each other or to opposite are rejected
            (the phase-1 system's condition number grows as ``1 / |sin(alpha_2 - alpha_1)|``).
        max_iter: iterations of the descent.
        on_bad: ``"raise"`` a :class:`NavInputError` on unusable input, or ``"fallback"`` to give
            those runs the no-correction estimate (``valid`` False).

    Returns:
        The estimate; ``response`` is ``None`` (CP1's current does not depend on the course).

    Raises:
        NavInputError: no fix, a leg duration <= 0, non-finite input, or courses (named in the
            message) the same or opposite within ``min_separation_rad`` (with ``on_bad="raise"``).
    """
    m, _, course, bad = _leg_inputs(delta_world_m, duration_s, course_rad, on_bad, "cp1")
    n = m.shape[0]
    sep = np.abs(np.sin(course[:, 1] - course[:, 0]))
    degenerate = ~bad & (sep < math.sin(min_separation_rad))
    if np.any(degenerate) and on_bad == "raise":
        i = int(np.flatnonzero(degenerate)[0])
        a1, a2 = np.degrees(course[i])
        raise NavInputError(
            f"cp1: courses {a1:.3f} and {a2:.3f} deg (run {i}) are the same or opposite within "
            f"{math.degrees(min_separation_rad):g} deg: CP1 needs two legs on different, "
            "non-opposite courses (use cp2 for opposite courses)"
        )
    bad = bad | degenerate
    course = np.where(bad[:, None], np.array([0.0, np.pi / 2]), course)

    # phase 1: beta = 0, dS_j/T_j = s_j u(alpha_j) + Vc (eq. 7-10)
    u = unit_vector(course)  # (n, 2, 2)
    A = np.stack([u[:, 0], -u[:, 1]], axis=-1)  # columns u1, -u2
    s12 = np.linalg.solve(A, (m[:, 0] - m[:, 1])[..., None])[..., 0]
    c0 = m[:, 0] - s12[:, :1] * u[:, 0]
    vs0 = 0.5 * (s12[:, 0] + s12[:, 1])

    # phase 2: descent on eq. 12 from every starting beta
    n_half = math.floor(beta_max_rad / beta_step_rad + 1e-9)
    starts = beta_step_rad * np.arange(-n_half, n_half + 1)
    k = starts.size
    p = np.empty((n, k, 4))
    p[..., 0] = vs0[:, None]
    p[..., 1] = starts[None, :]
    p[..., 2:] = c0[:, None, :]
    mm = np.broadcast_to(m[:, None], (n, k, 2, 2))
    cc = np.broadcast_to(course[:, None], (n, k, 2))
    p, F = _levenberg_marquardt(p, mm, cc, max_iter)

    best = np.argmin(F, axis=1)
    rows = np.arange(n)
    pb, Fb = p[rows, best], F[rows, best]
    vs_world = pb[:, 0, None] * unit_vector(course[:, 0] + pb[:, 1])
    vs, beta = _signed_vs(vs_world, course[:, 0])
    est = CorrectionEstimate(
        "cp1",
        vs,
        beta,
        pb[:, 2:].copy(),
        course[:, 0].copy(),
        None,
        np.sqrt(Fb),
        np.ones(n, bool),
    )
    return _fallback(est, bad)


def _levenberg_marquardt(p: Array, m: Array, course: Array, max_iter: int) -> tuple[Array, Array]:
    """Batched Levenberg-Marquardt on eq. 12; returns the parameters and ``F`` (...).

    Each element (run, start) stops on its own test (``F`` below 1e-30, a negligible accepted step,
    or saturated damping) and is frozen from then on, so its result never depends on which other
    runs share the batch (results are identical for any block grouping).
    """
    r, J = _cp1_residual_jacobian(p, m, course)
    F = np.sum(r * r, axis=-1)
    lam = np.full(F.shape, 1e-3)
    active = F > 1e-30
    eye = np.eye(4)
    for _ in range(max_iter):
        if not np.any(active):
            break
        g = np.einsum("...ji,...j->...i", J, r)
        H = np.einsum("...ki,...kj->...ij", J, J)
        damp = lam[..., None, None] * (
            eye * (np.diagonal(H, axis1=-2, axis2=-1)[..., None] + 1e-12)
        )
        step = np.linalg.solve(H + damp, -g[..., None])[..., 0]
        p_new = p + step
        r_new, J_new = _cp1_residual_jacobian(p_new, m, course)
        F_new = np.sum(r_new * r_new, axis=-1)
        ok = active & (F_new < F)
        p = np.where(ok[..., None], p_new, p)
        r = np.where(ok[..., None], r_new, r)
        J = np.where(ok[..., None, None], J_new, J)
        F = np.where(ok, F_new, F)
        lam = np.where(active, np.clip(np.where(ok, lam / 3.0, lam * 4.0), 1e-12, 1e12), lam)
        small = np.max(np.abs(step), axis=-1) <= 1e-14 * (1.0 + np.max(np.abs(p), axis=-1))
        active = active & ~((F <= 1e-30) | (ok & small) | (lam >= 1e12))
    return p, F


# --------------------------------------------------------------------------------------------
# CP2


def cp2(
    delta_world_m: ArrayLike | None,
    duration_s: ArrayLike,
    course_rad: ArrayLike,
    *,
    response: CurrentResponse | None = None,
    opposite_tolerance_rad: float = math.radians(0.5),
    on_bad: OnBad = "raise",
) -> CorrectionEstimate:
    """Correction procedure 2 (seed 001, eq. 13-21): two legs on opposite courses, closed form.

    With ``alpha_2 = alpha_1 + 180 deg`` and the same current on both legs (the hull response is
    symmetric about both vehicle axes, eq. 13-16), ``dS_1/T_1 = Vs + Vc`` and ``dS_2/T_2 = -Vs +
    Vc`` with ``Vs = vs u(alpha_1 + beta)``, so

        ``Vs = (dS_1/T_1 - dS_2/T_2) / 2``            (eq. 17, both components)
        ``Vc = (dS_1/T_1 + dS_2/T_2) / 2``            (eq. 18 and 20)
        ``beta = course(Vs) - alpha_1``               (eq. 19; sign of ``vs`` from eq. 34)

    Eq. 19-20 as printed take ``arctan`` of the component ratio, which loses the quadrant and mixes
    an angle from the x axis with a course; the vector form has neither problem. The current
    estimate belongs to ``alpha_1`` (and its opposite);
    :meth:`CorrectionEstimate.current_for_course` carries it to other courses with eq. 21 and
    ``response.rho``.

    Args:
        delta_world_m: position errors ``S_GPS - S_DR`` of the two legs, shape (n, 2, 2), m, world;
            ``None`` when there is no fix.
        duration_s: leg durations, shape (n, 2) or broadcastable, s (> 0).
        course_rad: the legs' courses ``(alpha_1, alpha_2)``, shape (n, 2) or broadcastable, rad
            (paper: 45 and 225 deg).
        response: the hull response for eq. 21; default :class:`CurrentResponse` ``()``.
        opposite_tolerance_rad: how far ``alpha_2`` may be from ``alpha_1 + 180 deg``.
        on_bad: ``"raise"`` or ``"fallback"`` (see :func:`cp1`).

    Returns:
        The estimate (``residual_m_s`` 0: the system is solved exactly).

    Raises:
        NavInputError: no fix, a leg duration <= 0, non-finite input, or courses (named) that are
            not opposite within the tolerance (with ``on_bad="raise"``).
    """
    m, _, course, bad = _leg_inputs(delta_world_m, duration_s, course_rad, on_bad, "cp2")
    n = m.shape[0]
    off = diff_course(course[:, 1], course[:, 0] + np.pi)
    not_opp = ~bad & (off > opposite_tolerance_rad)
    if np.any(not_opp) and on_bad == "raise":
        i = int(np.flatnonzero(not_opp)[0])
        a1, a2 = np.degrees(course[i])
        raise NavInputError(
            f"cp2: courses {a1:.3f} and {a2:.3f} deg (run {i}) are not opposite within "
            f"{math.degrees(opposite_tolerance_rad):g} deg: CP2 needs the second leg on the "
            "reverse of the first (paper: 45 then 225 deg); use cp1 otherwise"
        )
    bad = bad | not_opp
    vs_world = 0.5 * (m[:, 0] - m[:, 1])
    current = 0.5 * (m[:, 0] + m[:, 1])
    vs, beta = _signed_vs(vs_world, course[:, 0])
    est = CorrectionEstimate(
        "cp2",
        vs,
        beta,
        current,
        course[:, 0].copy(),
        response if response is not None else CurrentResponse(),
        np.zeros(n),
        np.ones(n, bool),
    )
    return _fallback(est, bad)


# --------------------------------------------------------------------------------------------
# Baseline


def baseline(
    gps_world_m: ArrayLike | None,
    dr_world_m: ArrayLike,
    elapsed_s: ArrayLike,
    *,
    on_bad: OnBad = "raise",
) -> CorrectionEstimate:
    """The simple published current estimator: ``Vc = (GPS fix - DR position) / time since the
    last fix`` (LSTS DUNE; ``../shared/notes/navigation.md``), with no vehicle error.

    Everything the DR missed over the leg is attributed to the current, so a systematic vehicle
    error is carried into later legs as a current fixed in the world (wrong as soon as the course
    changes); separating the two needs two legs on different courses (CP1, CP2).

    Args:
        gps_world_m: the GPS fix at surfacing, shape (n, 2), m, world; ``None`` when there is none.
        dr_world_m: the DR position at the same moment, DR restarted at the previous fix, shape
            (n, 2), m, world.
        elapsed_s: time since the previous fix, shape (n,) or scalar, s (> 0).
        on_bad: ``"raise"`` or ``"fallback"`` (see :func:`cp1`).

    Returns:
        The estimate (``vs = 0``, ``response`` ``None``).

    Raises:
        NavInputError: no fix, elapsed time <= 0, or non-finite input (with ``on_bad="raise"``).
    """
    if gps_world_m is None:
        raise NavInputError(
            "baseline: no GPS fix available: the current is (GPS fix - DR position) / time since "
            "the last fix"
        )
    g = np.asarray(gps_world_m, dtype=float)
    d = np.asarray(dr_world_m, dtype=float)
    if g.ndim != 2 or g.shape[1] != 2 or d.shape != g.shape:
        raise NavInputError(
            f"baseline: gps_world_m {g.shape} and dr_world_m {d.shape} must both be (n, 2)"
        )
    n = g.shape[0]
    T = np.broadcast_to(np.asarray(elapsed_s, dtype=float), (n,))
    no_fix = ~np.all(np.isfinite(g), axis=1)
    _bad_rows("baseline: no GPS fix available (non-finite fix)", no_fix, on_bad)
    bad_T = ~(np.isfinite(T) & (T > 0.0))
    _bad_rows(
        f"baseline: time since the last fix must be finite and > 0 s, got {T[bad_T][:1].tolist()}",
        bad_T,
        on_bad,
    )
    bad_d = ~np.all(np.isfinite(d), axis=1)
    _bad_rows("baseline: DR position must be finite", bad_d, on_bad)
    bad = no_fix | bad_T | bad_d
    current = np.where(bad[:, None], 0.0, g - d) / np.where(bad, 1.0, T)[:, None]
    z = np.zeros(n)
    est = CorrectionEstimate(
        "baseline", z, z.copy(), current, z.copy(), None, z.copy(), np.ones(n, bool)
    )
    return _fallback(est, bad)
