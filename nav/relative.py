"""Positioning relative to a swarm leader from one acoustic range (seed 003, Naus & Piskur 2022).

A follower F dead-reckons from course C and speed S (eq. 1) and accumulates the covariance of its
DR displacement (eq. 5-6). Every few seconds it receives from the leader L the range D_h between
them and L's position, and adjusts its own position by least squares constrained to the circle of
radius D_h around L (eq. 2-4): the candidates are ``X_F0(phi) = X_L + D_h (sin phi, cos phi)``
(the reading notes: the printed ``x_L * D_h * sin(phi)`` means ``x_L + D_h sin(phi)``), ``phi`` the
bearing of the candidate from L, and the fix is the candidate that minimises ``V^T P V`` where the
"measurements" are the bearing B_r and the distance D_r of the DR segment from its start
``X_F(k)`` to its end ``X_DR(k+n)`` and the range D_h:

* **GA1** (eq. 3): ``V = A d + L`` with ``d = X_F0 - X_DR(k+n)``, A the rows of eq. 2 at the
  candidate and ``L = (B_F0 - B_r, D_F0 - D_r, D_L0 - D_h)``;
* **GA2** (eq. 4): ``V = L``.

The weights are ``P = diag(1/delta_Br^2, 1/delta_Dr^2, 1/delta_Dh^2)`` with ``delta_Dr = M_xy``
and ``delta_Br = atan(M_xy / D_r)`` from the DR covariance since the last fix (eq. 6), and
``delta_Dh`` the modem's range error. The geometry's quality is the HDOP of eq. 7-8, computed with
the unweighted A at the fix.

Readings this module had to choose (the printed equations leave them open; ``../shared/seeds/
README.md`` lists them), each an option of :class:`GaOptions` where it is a real choice:

* **A's columns** (``GaOptions.jacobian``). Eq. 2 prints ``a_Br = (dx/D^2, -dy/D^2)``,
  ``a_Dr = (-dy/D, -dx/D)``, ``a_Dh = (-dy_L/D_L, -dx_L/D_L)`` with ``(dx, dy) = X_F(k) - X_F0``
  and ``(dx_L, dy_L) = X_L - X_F0``. The derivatives of the printed B, D with respect to
  ``(x_F0, y_F0)`` (x east) are those rows with their two columns swapped: the rows are the
  Jacobian in geodetic axes (x north, y east) while ``d`` is written in the paper's (x east,
  y north). ``"printed"`` applies the rows as printed to ``d = (dx, dy)``; ``"true"`` uses the
  Jacobian of the printed functions in the paper's own axes. With ``"true"``, ``A d`` is the first-
  order change of the functions from ``X_DR`` to the candidate, so near the circle ``A d ~ L`` and
  GA1 picks (almost) the candidate GA2 picks.
* **Restart** (``GaOptions.restart``): whether DR restarts from the GA position after each fix
  (then ``X_F(k)`` is the previous fix) or runs on undisturbed (then ``X_F(k)`` is the DR position
  at the previous fix and the GA positions are a separate output). The caller applies it
  (:class:`FollowerNavigator`, the paper-003 experiments); :func:`ga_fix` takes ``start`` and
  ``dr_end`` as given.
* **Bearings** use ``atan2`` (the printed ``atan`` loses the quadrant) and bearing residuals are
  wrapped to (-pi, pi].
* **Degenerate rows**: with ``D_r`` below ``min_step_m`` (no displacement since the last fix) the
  bearing row has no meaning and gets weight 0; ``M_xy`` is floored at ``min_sigma_m`` so that
  ``P`` stays finite right after a fix; a range below ``min_range_m`` (or one not received) makes
  no fix (``GaFix.valid`` False, the position stays the DR one).
* **Minimisation over phi**: a grid of ``grid`` candidates on the circle, then golden-section
  search within one grid step either side of each of the (up to four) lowest local minima of the
  grid, keeping the lowest result (to ``_PHI_TOL`` = 1e-9 rad, 1e-8 m on a 10 m circle; GA1's
  criterion can have several narrow basins, and the test compares with a brute-force
  minimisation). The criterion is evaluated fused (``_criterion_sc``: no V or A arrays built)
  with the grid's sines computed once per adjustment: the adjustment's hot path.
* **Stated accuracy** (beyond the paper): ``covariance = delta_0^2 (A^T P A)^-1`` with the true
  Jacobian (a covariance must use the true geometry), ``delta_0^2 = V^T P V`` at the fix (the
  redundancy is 3 - 2 = 1); ``covariance_prior = (A^T P A)^-1``, the same without the a-posteriori
  variance factor.

Beyond the paper: :class:`CourseSpeedMotion` and :class:`RangeMeasurement` make the same problem
an EKF (state: the follower's horizontal position; predict with eq. 1 and Q = eq. 5; update with
the range to the broadcast leader position, whose own covariance may be added to R), run with the
estimators of :mod:`nav.ekf`.

All arrays carry a leading run axis n (n = 1 for one vehicle); positions are (east, north) in m,
angles in rad in the navigation convention (course clockwise from north).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import wrap_pi
from nav.ekf import SingleRunEKF, update, update_one
from nav.errors import NavInputError

Array = NDArray[np.float64]
GaMethod = Literal["ga1", "ga2"]
Jacobian = Literal["printed", "true"]
FollowerMethod = Literal["dr", "ga1", "ga2", "ekf"]
FOLLOWER_METHODS: tuple[str, ...] = ("dr", "ga1", "ga2", "ekf")

_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
_STARTS = 4  # local minima of the grid refined per run
_PHI_TOL = 1e-9  # rad: width of the final golden-section bracket


def dr_step(position: ArrayLike, course_rad: ArrayLike, speed_m_s: ArrayLike, dt_s: float) -> Array:
    """One dead-reckoning step (seed 003, eq. 1, without the random term).

    Args:
        position: positions at k+i-1, shape (n, 2), m (east, north).
        course_rad: measured course C(k+i-1), shape (n,), rad, clockwise from north.
        speed_m_s: measured speed S(k+i-1), shape (n,), m/s.
        dt_s: step Delta t(k+i), s.

    Returns:
        Positions at k+i, shape (n, 2), m.
    """
    p = np.asarray(position, dtype=float)
    c = np.asarray(course_rad, dtype=float)
    s = np.asarray(speed_m_s, dtype=float) * dt_s
    return p + np.stack([s * np.sin(c), s * np.cos(c)], axis=-1)


def dr_increment_covariance(
    course_rad: ArrayLike,
    speed_m_s: ArrayLike,
    dt_s: float,
    sigma_course_rad: float,
    sigma_speed_m_s: float,
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
        sigma_speed_m_s: the speed's mean error sigma_S, m/s.

    Returns:
        Shape (n, 2, 2), m^2.
    """
    c = np.asarray(course_rad, dtype=float)
    a = np.asarray(speed_m_s, dtype=float) * sigma_course_rad
    b = sigma_speed_m_s
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


@dataclass(frozen=True)
class GaOptions:
    """How the adjustment reads the printed equations, and its numerical guards (module
    docstring).

    Attributes:
        jacobian: ``"printed"`` (eq. 2's rows as printed, applied to ``d = (dx, dy)``) or
            ``"true"`` (the Jacobian of the printed B and D in x east, y north).
        restart: whether DR restarts from the GA position after each fix (applied by the caller).
        sigma_range_m: the range's mean error delta_Dh in P, m (seed 003: 0.1).
        min_range_m: ranges below this make no fix, m.
        min_step_m: below this DR displacement D_r the bearing row gets weight 0, m.
        min_sigma_m: floor of M_xy in P, m.
        grid: candidates on the circle before the golden-section refinement.
    """

    jacobian: Jacobian = "printed"
    restart: bool = True
    sigma_range_m: float = 0.1
    min_range_m: float = 0.5
    min_step_m: float = 1e-3
    min_sigma_m: float = 1e-3
    grid: int = 360

    def __post_init__(self) -> None:
        if self.jacobian not in ("printed", "true"):
            raise NavInputError(f"jacobian must be 'printed' or 'true', not {self.jacobian!r}")
        for name in ("sigma_range_m", "min_range_m", "min_step_m", "min_sigma_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise NavInputError(f"{name} must be a finite number > 0, not {v!r}")
        if self.grid < 8:
            raise NavInputError(f"grid must be at least 8 candidates, not {self.grid!r}")


@dataclass(frozen=True)
class GaFix:
    """The result of one adjustment for n runs (seed 003, eq. 3 or 4).

    Attributes:
        position: X_GA(k+n), shape (n, 2), m; the DR end where ``valid`` is False.
        phi_rad: bearing of the fix from the leader, shape (n,), rad (0 where not valid).
        criterion: ``V^T P V`` at the fix (= delta_0^2), shape (n,) (0 where not valid).
        covariance: stated accuracy ``delta_0^2 (A^T P A)^-1``, shape (n, 2, 2), m^2 (the DR
            covariance where not valid).
        covariance_prior: ``(A^T P A)^-1``, shape (n, 2, 2), m^2 (the DR covariance where not
            valid).
        hdop: eq. 7-8 with the unweighted A at the fix, shape (n,) (0 where not valid).
        valid: whether a fix was made, shape (n,).
    """

    position: Array
    phi_rad: Array
    criterion: Array
    covariance: Array
    covariance_prior: Array
    hdop: Array
    valid: NDArray[np.bool_]


@dataclass(frozen=True)
class _Setup:
    """Per-run quantities of one adjustment, broadcast against candidates (n, K)."""

    start: Array  # (n, 1, 2)
    end: Array  # (n, 1, 2)
    leader: Array  # (n, 1, 2)
    radius: Array  # (n, 1)
    bearing: Array  # (n, 1)  B_r
    distance: Array  # (n, 1)  D_r
    weights: Array  # (n, 1, 3) diagonal of P


def _setup(start, dr_end, leader, range_m, dr_cov, opt: GaOptions) -> _Setup:
    s = np.asarray(start, dtype=float)
    e = np.asarray(dr_end, dtype=float)
    d_se = s - e
    d_r = np.hypot(d_se[:, 0], d_se[:, 1])
    b_r = np.arctan2(d_se[:, 0], d_se[:, 1])
    m_xy = np.maximum(mean_position_error(dr_cov), opt.min_sigma_m)
    moved = d_r >= opt.min_step_m
    sigma_b = np.arctan(m_xy / np.where(moved, d_r, 1.0))
    w = np.stack(
        [
            np.where(moved, 1.0 / sigma_b**2, 0.0),
            1.0 / m_xy**2,
            np.full(len(s), 1.0 / opt.sigma_range_m**2),
        ],
        axis=-1,
    )
    return _Setup(
        s[:, None],
        e[:, None],
        np.asarray(leader, dtype=float)[:, None],
        np.asarray(range_m, dtype=float)[:, None],
        b_r[:, None],
        d_r[:, None],
        w[:, None],
    )


def candidates(leader: ArrayLike, range_m: ArrayLike, phi_rad: ArrayLike) -> Array:
    """Candidate follower positions ``X_L + D_h (sin phi, cos phi)`` (eq. 3-4, functional model).

    Args:
        leader: leader positions, shape (n, 1, 2) or broadcastable, m.
        range_m: ranges D_h, shape (n, 1), m.
        phi_rad: bearings of the candidates from the leader, shape (n, K), rad.

    Returns:
        Shape (n, K, 2), m.
    """
    phi = np.asarray(phi_rad, dtype=float)
    r = np.asarray(range_m, dtype=float)
    return np.asarray(leader, dtype=float) + np.stack([r * np.sin(phi), r * np.cos(phi)], axis=-1)


def design_rows(start: Array, candidate: Array, leader: Array, jacobian: Jacobian) -> Array:
    """The rows of A (eq. 2) at candidate positions.

    Args:
        start: X_F(k), shape (..., 2), m.
        candidate: X_F0, shape (..., 2), m.
        leader: X_L(k+m), shape (..., 2), m.
        jacobian: ``"printed"`` or ``"true"`` (module docstring).

    Returns:
        Shape (..., 3, 2): rows a_Br (rad/m), a_Dr, a_Dh (dimensionless); columns act on
        ``d = (dx east, dy north)``.
    """
    dx, dy = start[..., 0] - candidate[..., 0], start[..., 1] - candidate[..., 1]
    lx, ly = leader[..., 0] - candidate[..., 0], leader[..., 1] - candidate[..., 1]
    d2 = dx * dx + dy * dy
    d = np.sqrt(d2)
    dl = np.hypot(lx, ly)
    safe_d2 = np.where(d2 > 0, d2, 1.0)
    safe_d = np.where(d > 0, d, 1.0)
    safe_dl = np.where(dl > 0, dl, 1.0)
    A = np.empty((*dx.shape, 3, 2))
    if jacobian == "printed":
        A[..., 0, 0], A[..., 0, 1] = dx / safe_d2, -dy / safe_d2
        A[..., 1, 0], A[..., 1, 1] = -dy / safe_d, -dx / safe_d
        A[..., 2, 0], A[..., 2, 1] = -ly / safe_dl, -lx / safe_dl
    else:
        A[..., 0, 0], A[..., 0, 1] = -dy / safe_d2, dx / safe_d2
        A[..., 1, 0], A[..., 1, 1] = -dx / safe_d, -dy / safe_d
        A[..., 2, 0], A[..., 2, 1] = -lx / safe_dl, -ly / safe_dl
    return A


def residuals(su: _Setup, candidate: Array, method: GaMethod, jacobian: Jacobian) -> Array:
    """V at candidates: ``L`` (GA2, eq. 4) or ``A d + L`` (GA1, eq. 3), shape (n, K, 3)."""
    dx = su.start[..., 0] - candidate[..., 0]
    dy = su.start[..., 1] - candidate[..., 1]
    b_f0 = np.arctan2(dx, dy)
    d_f0 = np.hypot(dx, dy)
    d_l0 = np.hypot(su.leader[..., 0] - candidate[..., 0], su.leader[..., 1] - candidate[..., 1])
    V = np.stack([wrap_pi(b_f0 - su.bearing), d_f0 - su.distance, d_l0 - su.radius], axis=-1)
    if method == "ga1":
        A = design_rows(su.start, candidate, su.leader, jacobian)
        d = candidate - su.end
        V = V + np.einsum("...ij,...j->...i", A, d)
    return V


def criterion(su: _Setup, phi: Array, method: GaMethod, jacobian: Jacobian) -> Array:
    """``V^T P V`` at candidate bearings ``phi`` (n, K), shape (n, K)."""
    phi = np.asarray(phi, dtype=float)
    return _criterion_sc(su, np.sin(phi), np.cos(phi), method, jacobian)


def _criterion_sc(
    su: _Setup, sin_phi: Array, cos_phi: Array, method: GaMethod, jacobian: Jacobian
) -> Array:
    """:func:`criterion` from ``sin phi``, ``cos phi`` (n, K) or (K,), fused: the numbers of
    :func:`residuals` and :func:`design_rows` component by component, without building V or A
    (the grid's sines are computed once per adjustment; this is the adjustment's hot path)."""
    lead_x, lead_y = su.leader[..., 0], su.leader[..., 1]
    cx = lead_x + su.radius * sin_phi
    cy = lead_y + su.radius * cos_phi
    dx = su.start[..., 0] - cx
    dy = su.start[..., 1] - cy
    lx, ly = lead_x - cx, lead_y - cy
    d2 = dx * dx + dy * dy
    d = np.sqrt(d2)
    dl = np.sqrt(lx * lx + ly * ly)
    w = su.weights
    v1 = np.arctan2(dx, dy) - su.bearing  # in (-2 pi, 2 pi): wrapped by one turn (only v1^2
    v1 = np.where(v1 > np.pi, v1 - 2 * np.pi, np.where(v1 < -np.pi, v1 + 2 * np.pi, v1))  # counts)
    v2 = d - su.distance
    v3 = dl - su.radius
    if method == "ga1":
        ux, uy = cx - su.end[..., 0], cy - su.end[..., 1]
        inv_d2 = 1.0 / np.where(d2 > 0, d2, 1.0)
        inv_d = 1.0 / np.where(d > 0, d, 1.0)
        inv_dl = 1.0 / np.where(dl > 0, dl, 1.0)
        if jacobian == "printed":  # design_rows "printed" times d
            v1 = v1 + (dx * ux - dy * uy) * inv_d2
            v2 = v2 - (dy * ux + dx * uy) * inv_d
            v3 = v3 - (ly * ux + lx * uy) * inv_dl
        else:
            v1 = v1 + (dx * uy - dy * ux) * inv_d2
            v2 = v2 - (dx * ux + dy * uy) * inv_d
            v3 = v3 - (lx * ux + ly * uy) * inv_dl
    return w[..., 0] * v1 * v1 + w[..., 1] * v2 * v2 + w[..., 2] * v3 * v3


def hdop(start: ArrayLike, position: ArrayLike, leader: ArrayLike) -> Array:
    """HDOP of the geometry (seed 003, eq. 7-8): ``sqrt(trace((A^T A)^-1))`` with the unweighted A
    of eq. 2 at ``position`` (the column order does not change the trace).

    Args:
        start: X_F(k), the start of the DR segment, shape (n, 2), m.
        position: the follower's position, shape (n, 2), m.
        leader: the leader's position, shape (n, 2), m.

    Returns:
        Shape (n,); ``inf`` where the geometry is singular.
    """
    A = design_rows(
        np.asarray(start, float), np.asarray(position, float), np.asarray(leader, float), "true"
    )
    N = np.swapaxes(A, -1, -2) @ A
    det = N[..., 0, 0] * N[..., 1, 1] - N[..., 0, 1] * N[..., 1, 0]
    tr = N[..., 0, 0] + N[..., 1, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.sqrt(tr / det)
    return np.where(det > 1e-12 * np.maximum(tr, 1.0) ** 2, out, np.inf)


def ga_fix(
    method: GaMethod,
    start: ArrayLike,
    dr_end: ArrayLike,
    leader: ArrayLike,
    range_m: ArrayLike,
    dr_cov: ArrayLike,
    options: GaOptions = GaOptions(),
    present: ArrayLike | None = None,
) -> GaFix:
    """Adjust the follower's position on the circle of the range (seed 003, GA1 eq. 3, GA2 eq. 4).

    Args:
        method: ``"ga1"`` or ``"ga2"``.
        start: X_F(k), the start of the DR segment (the previous fix when DR restarts), shape
            (n, 2), m.
        dr_end: X_DR(k+n), the dead-reckoned position at the range's time, shape (n, 2), m.
        leader: X_L(k+m), the leader position sent with the range, shape (n, 2), m.
        range_m: D_h, shape (n,), m.
        dr_cov: C_DR(k+n), the covariance accumulated by eq. 5 since ``start``, shape (n, 2, 2).
        options: readings and guards.
        present: runs that received a range, shape (n,) (default all).

    Returns:
        The fix of every run; runs without a usable range keep ``dr_end`` (``valid`` False).

    Raises:
        NavInputError: on an unknown method or mismatched shapes.
    """
    if method not in ("ga1", "ga2"):
        raise NavInputError(f"method must be 'ga1' or 'ga2', not {method!r}")
    e = np.asarray(dr_end, dtype=float)
    n = len(e)
    cov = np.asarray(dr_cov, dtype=float)
    rng = np.asarray(range_m, dtype=float).reshape(n)
    ok = np.ones(n, dtype=bool) if present is None else np.asarray(present, dtype=bool).copy()
    lead = np.asarray(leader, dtype=float)
    ok &= np.isfinite(rng) & (rng >= options.min_range_m)
    ok &= np.isfinite(lead).all(axis=1) & np.isfinite(e).all(axis=1) & np.isfinite(cov).all((1, 2))
    pos = e.copy()
    phi_out = np.zeros(n)
    crit = np.zeros(n)
    cov_out = cov.copy()
    prior_out = cov.copy()
    hd = np.zeros(n)
    idx = np.flatnonzero(ok)
    if idx.size:
        su = _setup(np.asarray(start, float)[idx], e[idx], lead[idx], rng[idx], cov[idx], options)
        step = 2.0 * np.pi / options.grid
        grid = np.arange(options.grid) * step
        J = _criterion_sc(su, np.sin(grid), np.cos(grid), method, options.jacobian)
        # every local minimum of the grid is refined (up to `starts` per run, the lowest first):
        # GA1's criterion can have several narrow basins on the circle
        is_min = (J <= np.roll(J, 1, axis=1)) & (J < np.roll(J, -1, axis=1))
        order = np.argsort(np.where(is_min, J, np.inf), axis=1, kind="stable")[:, :_STARTS]
        best = grid[order]  # (m, S); runs with fewer minima repeat unrefined grid points
        shape = best.shape
        a, b = best - step, best + step
        c = b - _GOLDEN * (b - a)
        d = a + _GOLDEN * (b - a)
        fc = criterion(su, c, method, options.jacobian)
        fd = criterion(su, d, method, options.jacobian)
        for _ in range(80):  # the bracket shrinks by 0.618 a step: 2 deg -> 1e-9 rad in ~37
            left = fc < fd
            b = np.where(left, d, b)
            a = np.where(left, a, c)
            keep = np.where(left, c, d)
            f_keep = np.where(left, fc, fd)
            new = np.where(left, b - _GOLDEN * (b - a), a + _GOLDEN * (b - a))
            f_new = criterion(su, new, method, options.jacobian)
            c, fc = np.where(left, new, keep), np.where(left, f_new, f_keep)
            d, fd = np.where(left, keep, new), np.where(left, f_keep, f_new)
            if np.max(b - a) < _PHI_TOL:
                break
        mids = 0.5 * (a + b)
        f_mid = criterion(su, mids, method, options.jacobian)
        pick = np.argmin(f_mid, axis=1)
        phi = np.mod(mids[np.arange(shape[0]), pick], 2.0 * np.pi)
        p = candidates(su.leader, su.radius, phi[:, None])  # (m, 1, 2)
        crit_i = criterion(su, phi[:, None], method, options.jacobian)[:, 0]
        A = design_rows(su.start, p, su.leader, "true")[:, 0]  # (m, 3, 2)
        W = su.weights[:, 0]
        N = np.einsum("mki,mk,mkj->mij", A, W, A)
        prior = _inv2(N)
        pos[idx] = p[:, 0]
        phi_out[idx] = phi
        crit[idx] = crit_i
        prior_out[idx] = prior
        cov_out[idx] = crit_i[:, None, None] * prior
        hd[idx] = hdop(su.start[:, 0], p[:, 0], su.leader[:, 0])
    return GaFix(pos, phi_out, crit, cov_out, prior_out, hd, ok)


def _inv2(N: Array) -> Array:
    """Inverse of symmetric 2x2 matrices (m, 2, 2); singular ones give ``inf`` variances."""
    det = N[:, 0, 0] * N[:, 1, 1] - N[:, 0, 1] * N[:, 1, 0]
    out = np.empty_like(N)
    with np.errstate(divide="ignore", invalid="ignore"):
        out[:, 0, 0] = N[:, 1, 1] / det
        out[:, 1, 1] = N[:, 0, 0] / det
        out[:, 0, 1] = out[:, 1, 0] = -N[:, 0, 1] / det
    bad = ~(det > 0)
    out[bad] = np.diag([np.inf, np.inf])
    return out


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


@dataclass(frozen=True)
class RangeMeasurement:
    """The range from the follower to the leader's broadcast position (an EKF measurement model
    for :mod:`nav.ekf`; beyond seed 003, which adjusts instead).

    ``h(x) = |x - X_L|``, ``H = (x - X_L)^T / |x - X_L|``, ``R = sigma^2 + H C_L H^T`` when the
    leader's covariance ``C_L`` is given (its position error acts on the range like the range's
    own). The range is inactive where the estimate sits on the leader (no direction).

    Attributes:
        leader: leader positions, shape (n, 2), m.
        sigma_m: the range's standard deviation, m.
        leader_cov: covariance of the leader positions, shape (n, 2, 2), m^2, or ``None``.
    """

    leader: Array
    sigma_m: float
    leader_cov: Array | None = None

    def _d(self, x: Array) -> tuple[Array, Array]:
        d = np.asarray(x, dtype=float)[:, :2] - self.leader
        r = np.hypot(d[:, 0], d[:, 1])
        return d, r

    def h(self, x: Array) -> Array:
        """Predicted ranges, shape (n, 1), m."""
        return self._d(x)[1][:, None]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d)."""
        d, r = self._d(x)
        H = np.zeros((len(d), 1, np.shape(x)[1]))
        safe = np.where(r > 0, r, 1.0)
        H[:, 0, 0], H[:, 0, 1] = d[:, 0] / safe, d[:, 1] / safe
        return H

    def R(self) -> Array:
        """Noise, shape (1, 1) or (n, 1, 1) with the leader's covariance, m^2."""
        if self.leader_cov is None:
            return np.array([[self.sigma_m**2]])
        return np.full((len(self.leader), 1, 1), self.sigma_m**2)

    def R_at(self, x: Array) -> Array:
        """Noise including the leader's covariance projected on the line of sight at ``x``, shape
        (n, 1, 1), m^2."""
        R = np.broadcast_to(self.R(), (len(self.leader), 1, 1)).copy()
        if self.leader_cov is not None:
            h = self.H(x)[:, :, :2]
            R += h @ self.leader_cov @ np.swapaxes(h, -1, -2)
        return R

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``, shape (n, 1)."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Whether the range has a direction, shape (n, 1)."""
        return (self._d(x)[1] > 1e-9)[:, None]


def range_update(
    x: Array,
    P: Array,
    leader: ArrayLike,
    range_m: ArrayLike,
    sigma_m: float,
    leader_cov: ArrayLike | None = None,
    present: ArrayLike | None = None,
    gate_probability: float | None = None,
):
    """The EKF update with one range per run to the leader's broadcast position (batched).

    Args:
        x: states, shape (n, d) (the first two components are east, north, m).
        P: covariances, shape (n, d, d).
        leader: leader positions, shape (n, 2), m.
        range_m: measured ranges, shape (n,), m.
        sigma_m: range standard deviation, m.
        leader_cov: leader position covariances, shape (n, 2, 2), or ``None``.
        present: runs with a range, shape (n,).
        gate_probability: chi-square gate, or ``None``.

    Returns:
        ``(x, P, info)`` as :func:`nav.ekf.update`.
    """
    model = RangeMeasurement(
        np.asarray(leader, float), sigma_m, None if leader_cov is None else np.asarray(leader_cov)
    )
    z = np.asarray(range_m, dtype=float).reshape(-1, 1)
    pres = np.ones(len(x), dtype=bool) if present is None else np.asarray(present, dtype=bool)
    pres = pres & np.isfinite(z[:, 0])
    hx = model.h(x)
    y = model.residual(np.where(pres[:, None], z, hx), hx)
    return update(x, P, y, model.H(x), model.R_at(x), model.active(x), pres, gate_probability)


@dataclass(frozen=True)
class FixOutcome:
    """What one range did to a follower's navigation.

    Attributes:
        accepted: whether the estimate was corrected.
        reason: ``"ok"`` or why not (``"no range"``, ``"range below minimum"``, ``"gate"``,
            ``"dr"`` for the DR method, which ignores ranges).
        position: the estimate after the range, shape (2,), m.
        hdop: eq. 7-8 at the estimate (``inf`` if singular; 0 when not computed).
        criterion: ``V^T P V`` of the adjustment (GA) or the NIS (EKF); 0 otherwise.
    """

    accepted: bool
    reason: str
    position: Array
    hdop: float
    criterion: float


@dataclass
class FollowerNavigator:
    """One follower's online navigation relative to the leader (seed 003): DR (eq. 1, 5-6) and,
    at each range, GA1, GA2 or the range EKF; ``"dr"`` ignores ranges.

    Args:
        method: ``"dr"``, ``"ga1"``, ``"ga2"`` or ``"ekf"``.
        position: initial position, shape (2,), m (east, north).
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.
        options: GA readings and guards (``restart``, ``sigma_range_m`` also used by the EKF).
        initial_cov: initial covariance, shape (2, 2), m^2 (default zero: the start is known).
        gate_probability: the EKF's chi-square gate, or ``None``.
    """

    method: FollowerMethod
    position0: ArrayLike
    sigma_course_rad: float
    sigma_speed_m_s: float
    options: GaOptions = field(default_factory=GaOptions)
    initial_cov: ArrayLike | None = None
    gate_probability: float | None = None

    def __post_init__(self) -> None:
        if self.method not in FOLLOWER_METHODS:
            raise NavInputError(f"method must be one of {FOLLOWER_METHODS}, not {self.method!r}")
        p0 = np.array(self.position0, dtype=float).reshape(2)
        P0 = np.zeros((2, 2)) if self.initial_cov is None else np.array(self.initial_cov, float)
        self._motion = CourseSpeedMotion(self.sigma_course_rad, self.sigma_speed_m_s)
        self._ekf = SingleRunEKF(self._motion)
        self._dr = p0.copy()  # the pure DR track
        self._dr_cov = P0.copy()
        self._seg_start = p0.copy()  # X_F(k): start of the DR segment since the last fix
        self._seg_end = p0.copy()  # X_DR(k+n): the segment's dead-reckoned end
        self._seg_cov = np.zeros((2, 2))  # C_DR(k+n) since the last fix
        self._est = p0.copy()  # the method's estimate
        self._est_cov = P0.copy()

    @property
    def position(self) -> Array:
        """The method's current estimate, shape (2,), m."""
        return self._est.copy()

    @property
    def covariance(self) -> Array:
        """The method's stated covariance, shape (2, 2), m^2 (for GA: the DR covariance since
        the last fix added to the fix's stated covariance)."""
        return self._est_cov.copy()

    @property
    def dr_position(self) -> Array:
        """The pure dead-reckoned track, shape (2,), m."""
        return self._dr.copy()

    def advance(self, course_rad: float, speed_m_s: float, dt_s: float) -> None:
        """One DR step with the measured course and speed (eq. 1, 5).

        Args:
            course_rad: measured course, rad.
            speed_m_s: measured speed (through water, the log), m/s.
            dt_s: step, s.
        """
        c = np.array([course_rad], dtype=float)
        s = np.array([speed_m_s], dtype=float)
        step = dr_step(np.zeros((1, 2)), c, s, dt_s)[0]
        q = dr_increment_covariance(c, s, dt_s, self.sigma_course_rad, self.sigma_speed_m_s)[0]
        self._dr = self._dr + step
        self._dr_cov = self._dr_cov + q
        self._seg_end = self._seg_end + step
        self._seg_cov = self._seg_cov + q
        if self.method == "ekf":
            x, P = self._ekf.predict(
                self._est[None], self._est_cov[None], np.array([[course_rad, speed_m_s]]), dt_s
            )
            self._est, self._est_cov = x[0], P[0]
        elif self.method == "dr":
            self._est, self._est_cov = self._dr.copy(), self._dr_cov.copy()
        else:
            self._est = self._est + step
            self._est_cov = self._est_cov + q

    def fix(
        self, leader_xy: ArrayLike, range_m: float | None, leader_cov: ArrayLike | None = None
    ) -> FixOutcome:
        """Use one range to the leader's broadcast position.

        Args:
            leader_xy: the leader position sent with the range, shape (2,), m.
            range_m: the measured range, m, or ``None`` when none arrived.
            leader_cov: the leader's stated covariance, shape (2, 2), m^2 (EKF only).

        Returns:
            What happened; the estimate is unchanged unless ``accepted``.
        """
        if self.method == "dr":
            return FixOutcome(False, "dr", self.position, 0.0, 0.0)
        lead = np.asarray(leader_xy, dtype=float).reshape(2)
        if range_m is None or not np.isfinite(range_m) or not np.isfinite(lead).all():
            return FixOutcome(False, "no range", self.position, 0.0, 0.0)
        if range_m < self.options.min_range_m:
            return FixOutcome(False, "range below minimum", self.position, 0.0, 0.0)
        if self.method == "ekf":
            model = RangeMeasurement(
                lead[None],
                self.options.sigma_range_m,
                None if leader_cov is None else np.asarray(leader_cov, float)[None],
            )
            x, P = self._est[None], self._est_cov[None]
            hx = model.h(x)
            y = model.residual(np.array([[range_m]]), hx)
            x2, P2, info = update_one(
                x, P, y, model.H(x), model.R_at(x)[0], model.active(x), self.gate_probability
            )
            h = float(hdop(self._seg_start[None], x2, lead[None])[0])
            self._seg_start = x2[0].copy()
            self._seg_cov = np.zeros((2, 2))
            if not info.applied[0]:
                why = "gate" if info.rejected[0] else "no direction"
                return FixOutcome(False, why, self.position, h, float(np.nan_to_num(info.nis[0])))
            self._est, self._est_cov = x2[0], P2[0]
            return FixOutcome(True, "ok", self.position, h, float(info.nis[0]))
        res = ga_fix(
            self.method,  # type: ignore[arg-type]
            self._seg_start[None],
            self._seg_end[None],
            lead[None],
            np.array([range_m]),
            self._seg_cov[None],
            self.options,
        )
        if not res.valid[0]:
            return FixOutcome(False, "no fix", self.position, 0.0, 0.0)
        p = res.position[0]
        self._est = p.copy()
        self._est_cov = res.covariance[0].copy()
        if self.options.restart:
            self._seg_start = p.copy()
            self._seg_end = p.copy()
        else:
            self._seg_start = self._seg_end.copy()
        self._seg_cov = np.zeros((2, 2))
        return FixOutcome(True, "ok", self.position, float(res.hdop[0]), float(res.criterion[0]))
