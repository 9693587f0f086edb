"""Appendix A of seed 004 (:mod:`nav.seabed`): the seabed's slopes at the beam feet fitted from
one acoustic image, compiled by numba (:func:`nav.seabed.kernel.seabed_fit`) with numpy for the
rare ill-conditioned paths.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavError, NavInputError
from nav.seabed.geometry import SlopeBasis, _finite, check_basis

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def fit_slopes(points: Array, valid: BoolArray, basis: SlopeBasis) -> tuple[Array, BoolArray]:
    """Seabed gradient at the beam feet from the feet themselves (seed 004, Appendix A, eq. A1).

    Fits ``psi(x) = z + sum_l p_l psi_l(x, y)`` (z coefficient fixed to 1) to the valid points of
    each path in least squares, then returns ``grad psi = (sum p_l dpsi_l/dx, sum p_l dpsi_l/dy,
    1)`` at every point.

    The per-path arithmetic is compiled by numba (:func:`nav.seabed.kernel.seabed_fit`: the
    basis, the normal equations scaled to a unit diagonal, solved by Cholesky); paths whose
    scaled Gram matrix may have a condition number above :data:`FIT_C_CONDITION` are fitted in numpy
    (:func:`_least_squares`: LAPACK's eigen-decomposition or the SVD), as are bases of more
    than :data:`FIT_MAX_FUNCTIONS` functions.

    Args:
        points: beam feet, shape (P, m, 3), m, world (z up).
        valid: which points have an echo, shape (P, m).
        basis: the fit's functions.

    Returns:
        ``(grad, ok)``: gradients shape (P, m, 3) (zero where ``ok`` is False), and ``ok``
        shape (P,): the path had more valid points than basis functions.

    Raises:
        NavInputError: if ``points`` and ``valid`` do not match, a valid foot is not finite, or
            the basis has at least as many functions as an image has feet (no path could be
            fitted; :func:`check_basis`).
        NavError: if the compiled fit refuses its arguments (a programming error).
    """
    pts = np.ascontiguousarray(points, dtype=float)
    w = np.asarray(valid, dtype=bool)
    if w.ndim != 2 or pts.shape != (*w.shape, 3):
        raise NavInputError(
            f"fit_slopes: points of shape {pts.shape} and valid of shape {w.shape}, expected "
            "(P, m, 3) and (P, m)"
        )
    P, m = w.shape
    check_basis(basis, m)
    _finite("fit_slopes: points (at a valid foot)", pts, np.broadcast_to(w[..., None], pts.shape))
    if not np.isfinite(pts).all():  # feet without echo take no part: keep their NaN out
        pts = np.where(w[..., None], pts, 0.0)
    if basis.size > FIT_MAX_FUNCTIONS:
        return _fit_slopes_numpy(pts, w, basis)
    grad = np.empty((P, m, 3))
    ok = np.empty(P, np.uint8)
    to_numpy = np.empty(P, np.uint8)
    kind = {"harmonic": 0, "plane": 1, "quadratic": 2}[basis.kind]
    from nav.seabed import kernel  # numba: imported (and its cache loaded) on the first fit

    flagged = kernel.seabed_fit(
        pts,
        np.ascontiguousarray(w, dtype=np.uint8),
        kind,
        int(basis.harmonics),
        float(basis.period_x_m),
        float(basis.period_y_m),
        FIT_C_CONDITION,
        grad,
        ok,
        to_numpy,
    )
    if flagged < 0:
        raise NavError(f"fit_slopes: the compiled fit refused: {kernel.STATUS[flagged]}")
    if flagged:  # less well conditioned: numpy (LAPACK) on those paths
        bad = np.flatnonzero(to_numpy)
        grad[bad] = _fit_slopes_numpy(pts[bad], w[bad], basis)[0]
    return grad, ok.view(np.bool_)


def _fit_slopes_numpy(
    points: Array, valid: BoolArray, basis: SlopeBasis
) -> tuple[Array, BoolArray]:
    """:func:`fit_slopes` in numpy (the ill-conditioned paths and the large bases)."""
    pts = np.asarray(points, dtype=float)
    w = np.asarray(valid, dtype=bool)
    n_valid = w.sum(axis=1)
    ok = n_valid > basis.size
    x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
    if basis.kind != "harmonic":  # centre the polynomial bases on the valid feet
        cnt = np.maximum(n_valid, 1)[:, None]
        x = x - np.where(w, x, 0.0).sum(1, keepdims=True) / cnt
        y = y - np.where(w, y, 0.0).sum(1, keepdims=True) / cnt
    phi, dphi_dx, dphi_dy = basis.rows(x, y)  # (P, size, m)
    at = phi * w[:, None, :]  # A^T; masked points are zero columns
    rhs = -np.where(w, z, 0.0)[..., None]  # eq. A1 with the z coefficient fixed to 1
    p = _least_squares(at, rhs).transpose(0, 2, 1)  # (P, 1, size)
    gx = (p @ dphi_dx)[:, 0]
    gy = (p @ dphi_dy)[:, 0]
    grad = np.stack([gx, gy, np.ones_like(gx)], axis=-1)
    grad = np.where((ok[:, None] & w)[..., None], grad, 0.0)
    return grad, ok


FIT_RCOND = 1e-10
"""Relative singular-value cut-off of Appendix A's fit (:func:`fit_slopes`)."""

FIT_C_CONDITION = 1e4
"""Largest condition number of the scaled Gram matrix of Appendix A's fit solved by the compiled
kernel (:func:`fit_slopes`, by the bound ``max_row_sum(G) trace(G^-1)``); its solution (Cholesky)
and numpy's (LAPACK's eigen-decomposition) differ by about the condition number times the
rounding error, so up to here they agree to ~1e-11, and the paths beyond it (about 5 per cent
of seed 004's) keep numpy's numbers."""

FIT_MAX_FUNCTIONS = 64
"""Most basis functions of Appendix A's compiled fit (:data:`nav.seabed.kernel.FIT_MAX`); a
larger basis (a harmonic one with more than 15 harmonics) is fitted in numpy."""

GRAM_CONDITION = 1e12
"""Largest condition number of the Jacobi-scaled Gram matrix ``A^T A`` that
:func:`_least_squares` solves by its eigen-decomposition; beyond it, the SVD of ``A``."""


def _least_squares(at: Array, rhs: Array) -> Array:
    """``pinv(A, rcond=FIT_RCOND) @ rhs`` per path, through the Gram matrix where it is safe.

    The normal equations ``(A^T A) p = A^T b``, scaled to a unit diagonal and solved by the
    eigen-decomposition of the small Gram matrix, cost a fraction of a batched SVD of the tall
    ``A``. They square the condition number, so paths whose scaled Gram matrix has a condition
    number above :data:`GRAM_CONDITION` (singular values of ``A`` spread by more than 1e6; a
    rank-deficient fit among them) take the SVD pseudo-inverse instead, with its minimum-norm
    solution.

    Args:
        at: ``A^T``, shape (P, n, m).
        rhs: shape (P, m, 1).

    Returns:
        Shape (P, n, 1).
    """
    a = at.transpose(0, 2, 1)
    g = at @ a
    d = np.sqrt(np.einsum("pii->pi", g))
    dinv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    gs = g * dinv[:, :, None] * dinv[:, None, :]
    lam, v = np.linalg.eigh(gs)  # ascending
    good = lam[:, 0] > lam[:, -1] / GRAM_CONDITION
    ys = dinv[..., None] * (at @ rhs)
    lam = np.where(good[:, None], lam, 1.0)
    p = dinv[..., None] * (v @ ((v.transpose(0, 2, 1) @ ys) / lam[..., None]))
    bad = np.flatnonzero(~good)
    if bad.size:
        p[bad] = np.linalg.pinv(a[bad], rcond=FIT_RCOND) @ rhs[bad]
    return p
