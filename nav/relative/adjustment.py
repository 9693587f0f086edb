"""Seed 003's geodetic adjustment on the circle of the range (GA1 eq. 3, GA2 eq. 4) and the HDOP of
its geometry (eq. 7-8): the readings of the printed equations are :mod:`nav.relative`'s docstring
and :class:`GaOptions`.

All arrays carry a leading run axis n; positions are (east, north) in m, angles in rad clockwise
from north.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import wrap_pi
from nav.errors import NavInputError
from nav.relative.motion import mean_position_error

Array = NDArray[np.float64]
GaMethod = Literal["ga1", "ga2"]
Jacobian = Literal["printed", "true"]

_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
_STARTS = 4  # local minima of the grid refined per run
_PHI_TOL = 1e-9  # rad: width of the final golden-section bracket


@dataclass(frozen=True)
class GaOptions:
    """How the adjustment reads the printed equations, and its numerical guards (the readings
    of :mod:`nav.relative`'s docstring).

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
        jacobian: ``"printed"`` or ``"true"`` (:mod:`nav.relative`'s docstring).

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


def hdop_after_step(
    position_m: ArrayLike, leader_m: ArrayLike, course_rad: float, step_m: float
) -> Array:
    """HDOP (eq. 7-8) of followers that have dead-reckoned ``step_m`` on ``course_rad`` since the
    start of their DR segment and receive the range to the leader (seed 003's Figure 2 set-up):
    ``start = position - D_r (sin C, cos C)``, then :func:`hdop`.

    Args:
        position_m: follower positions, shape (n, 2), m.
        leader_m: leader positions, shape (n, 2), m.
        course_rad: the follower's course C, rad.
        step_m: D_r, the DR displacement since the segment's start, m.

    Returns:
        Shape (n,); ``inf`` where the geometry is singular.
    """
    p = np.asarray(position_m, dtype=float)
    start = p - step_m * np.array([math.sin(course_rad), math.cos(course_rad)])
    return hdop(start, p, leader_m)
