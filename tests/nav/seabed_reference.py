"""The numpy implementation of :func:`nav.seabed.shift_estimate` and :func:`nav.seabed.fit_slopes`
as it was before their per-path arithmetic moved to C (``nav/seabed/seabed_shift.c``, numba's
:mod:`nav.seabed.kernel` since issue 26): the reference the tests compare the compiled path with
(``tests/nav/test_seabed_kernel.py``), and a variant of
``benchmarks/bench_seabed.py``.

The functions are those of ``nav/seabed.py`` at the commit before the C library, unchanged but
for their names' module; they use the library's :class:`~nav.seabed.BeamGeometry`,
:class:`~nav.seabed.SlopeBasis`, :class:`~nav.seabed.ShiftEstimate` and its constants.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError
from nav.seabed import (
    FIT_RCOND,
    GRAM_CONDITION,
    SINGULAR_FLOOR,
    BeamAttitude,
    BeamGeometry,
    CovarianceKind,
    ShiftEstimate,
    SlopeBasis,
)
from nav.seabed.shift import _check_images

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def fit_slopes(points: Array, valid: BoolArray, basis: SlopeBasis) -> tuple[Array, BoolArray]:
    """Seabed gradient at the beam feet from the feet themselves (seed 004, Appendix A, eq. A1).

    Fits ``psi(x) = z + sum_l p_l psi_l(x, y)`` (z coefficient fixed to 1) to the valid points of
    each path in least squares, then returns ``grad psi = (sum p_l dpsi_l/dx, sum p_l dpsi_l/dy,
    1)`` at every point.

    Args:
        points: beam feet, shape (P, m, 3), m, world (z up).
        valid: which points have an echo, shape (P, m).
        basis: the fit's functions.

    Returns:
        ``(grad, ok)``: gradients shape (P, m, 3) (zero where ``ok`` is False), and ``ok``
        shape (P,): the path had more valid points than basis functions.
    """
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


def shift_estimate(
    ranges_m: Array,
    next_ranges_m: Array,
    geometry: BeamGeometry,
    attitude_rad: Array,
    next_attitude_rad: Array | None = None,
    *,
    echo: BoolArray | None = None,
    next_echo: BoolArray | None = None,
    reading: BeamAttitude = "one_attitude",
    basis: SlopeBasis | None = None,
    position_m: Array | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
    slopes: Array | None = None,
    covariance: CovarianceKind = "residual",
    sigma_range_m: float = 0.1,
    fallback_var_m2: float = 1e6,
    rcond: float = 1e-4,
    commanded_shift_m: Array | None = None,
) -> ShiftEstimate:
    """Position shift from two consecutive acoustic images (seed 004, eq. 8-15, Appendix A).

    This is the prediction step of a filter fed by seabed sensing: ``X-tilde_{k+1} = X-hat_k +
    shift`` (seed 004 section 6, second row of Table 1).

    Args:
        ranges_m: image k, ``L_k^ij``, shape (P, Mi, Mj), m (any finite value where no echo).
        next_ranges_m: image k+1, ``L_{k+1}^ij``, shape (P, Mi, Mj), m.
        geometry: the beams' aiming angles.
        attitude_rad: ``(gamma_k, theta_k)`` of image k (from the command ``u_k``), shape
            (P, 2), rad.
        next_attitude_rad: ``(gamma_{k+1}, theta_{k+1})`` of image k+1, shape (P, 2), rad; needed
            for ``reading="turning"``, ignored for ``"one_attitude"`` (image k+1 was taken at
            ``attitude_rad``).
        echo: beams of image k with an echo, shape (P, Mi, Mj) (default: all).
        next_echo: the same for image k+1.
        reading: the beam attitude between the images (:data:`BeamAttitude`).
        basis: Appendix A's basis (default :meth:`SlopeBasis.seed004`).
        position_m: ``X-hat_k``, shape (P, 3), m, for the feet ``X-hat_k + L e`` of the slope fit
            (default zero; the bases are shift-invariant, see the module docstring).
        delta_e: eq. 10 (``"linear"``) or the exact ``e_{k+1} - e_k``.
        slopes: known ``grad psi`` at the feet of image k, shape (P, Mi, Mj, 3), instead of the
            Appendix A estimate (for tests and for a known seabed).
        covariance: ``"residual"`` or ``"range_noise"`` (module docstring).
        sigma_range_m: range noise standard deviation, m (seed 004: 0.1), for the covariance.
        fallback_var_m2: variance stated along unobserved directions and for shifts not
            produced, m^2.
        rcond: singular values of A below ``rcond`` times the largest count as zero (an
            ill-conditioned slope field, e.g. a quadratic fit of a faceted seabed, would
            otherwise give a shift of kilometres); the direction is then unobserved.
        commanded_shift_m: the commanded displacement ``V(u_k) dt``, shape (P, 3), m: the shift
            stated where none is produced (default zero), with ``fallback_var_m2 * I``.

    Returns:
        The :class:`ShiftEstimate`.

    Raises:
        NavInputError: for arrays of the wrong shape, non-finite ranges where there is an echo,
            an unknown reading, or ``"turning"`` without ``next_attitude_rad``.
    """
    L0 = np.asarray(ranges_m, dtype=float)
    if L0.ndim != 3 or L0.shape[1:] != geometry.shape:
        raise NavInputError(
            f"ranges_m: shape {L0.shape}, expected (paths, {geometry.shape[0]}, "
            f"{geometry.shape[1]})"
        )
    P = L0.shape[0]
    L1 = _check_images("next_ranges_m", np.asarray(next_ranges_m, dtype=float), L0.shape)
    w0 = np.ones(L0.shape, bool) if echo is None else _check_images("echo", echo, L0.shape)
    w1 = (
        np.ones(L0.shape, bool)
        if next_echo is None
        else _check_images("next_echo", next_echo, L0.shape)
    )
    att0 = _check_images("attitude_rad", np.asarray(attitude_rad, dtype=float), (P, 2))
    if reading not in ("one_attitude", "turning"):
        raise NavInputError(f"reading = {reading!r}: use 'one_attitude' or 'turning'")
    if reading == "turning":
        if next_attitude_rad is None:
            raise NavInputError("reading = 'turning' needs next_attitude_rad (paths, 2)")
        att1 = _check_images(
            "next_attitude_rad", np.asarray(next_attitude_rad, dtype=float), (P, 2)
        )
    if delta_e not in ("linear", "exact"):
        raise NavInputError(f"delta_e = {delta_e!r}: use 'linear' or 'exact'")
    if covariance not in ("residual", "range_noise"):
        raise NavInputError(f"covariance = {covariance!r}: use 'residual' or 'range_noise'")
    w0, w1 = w0.astype(bool), w1.astype(bool)
    use = w0 & w1
    if not (np.all(np.isfinite(L0[w0])) and np.all(np.isfinite(L1[w1]))):
        raise NavInputError("ranges_m / next_ranges_m: non-finite range on a beam with an echo")
    m = geometry.shape[0] * geometry.shape[1]
    L0f = np.where(use, L0, 0.0).reshape(P, m)
    dL = np.where(use, L1 - L0, 0.0).reshape(P, m)  # step 1: dL = L_{k+1} - L_k
    e = geometry.directions(att0).reshape(P, m, 3)  # eq. 8
    if reading == "turning":  # step 2: eq. 10
        de = geometry.direction_change(att0, att1, exact=delta_e == "exact").reshape(P, m, 3)
    else:
        de = np.zeros_like(e)
    usef = use.reshape(P, m)
    if slopes is None:  # step 3: Appendix A on every foot of image k
        origin = np.zeros((P, 3)) if position_m is None else np.asarray(position_m, dtype=float)
        _check_images("position_m", origin, (P, 3))
        w0f = w0.reshape(P, m)
        feet = origin[:, None, :] + np.where(w0f, L0.reshape(P, m), 0.0)[..., None] * e  # eq. 8
        grad, fit_ok = fit_slopes(feet, w0f, basis or SlopeBasis.seed004())
        grad = np.where(usef[..., None], grad, 0.0)
    else:
        grad = _check_images("slopes", np.asarray(slopes, dtype=float), (*L0.shape, 3))
        grad = np.where(usef[..., None], grad.reshape(P, m, 3), 0.0)
        fit_ok = np.ones(P, bool)
    # step 4: eq. 12 and 14 (masked beams give zero rows)
    A = grad
    B = -np.einsum("pmc,pmc->pm", grad, de * L0f[..., None] + e * dL[..., None])
    beams = usef.sum(axis=1)
    ok = fit_ok & (beams >= 3)
    # step 5: eq. 15 by the singular values of A with an absolute floor (rank-deficient A:
    # minimum-norm shift), from the eigen-decomposition of the 3 x 3 A^T A: A = U S V^T with
    # A^T A = V S^2 V^T and U^T B = S^-1 V^T A^T B
    At = A.transpose(0, 2, 1)
    lam, V = np.linalg.eigh(At @ A)  # ascending
    s = np.sqrt(np.maximum(lam[:, ::-1], 0.0))  # descending, as an SVD's
    Vt = V[:, :, ::-1].transpose(0, 2, 1)
    floor = np.maximum(SINGULAR_FLOOR * np.sqrt(np.maximum(beams, 1)), rcond * s[:, 0])[:, None]
    if rcond * 1e8 < 1.0:  # a cut-off below what eigenvalues of A^T A resolve: the SVD
        _, s, Vt = np.linalg.svd(A, full_matrices=False)  # (P,3), (P,3,3)
        floor = np.maximum(SINGULAR_FLOOR * np.sqrt(np.maximum(beams, 1)), rcond * s[:, 0])
        floor = floor[:, None]
    keep = s > floor
    rank = keep.sum(axis=1)
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    atb = np.einsum("pcm,pm->pc", At, B)
    shift = np.einsum("pcd,pc->pd", Vt, np.einsum("pcd,pd->pc", Vt, atb) * s_inv**2)
    resid = np.where(usef, np.einsum("pmc,pc->pm", A, shift) - B, 0.0)
    rss = (resid**2).sum(axis=1)
    # range-noise propagation: dB/dL_k = -g.(de - e), dB/dL_{k+1} = -g.e
    gb0 = np.einsum("pmc,pmc->pm", grad, de - e)
    gb1 = np.einsum("pmc,pmc->pm", grad, e)
    var_b = sigma_range_m**2 * (gb0**2 + gb1**2) * usef
    # pseudo-inverse rows: dX = V diag(s_inv^2) V^T A^T B
    Apinv = np.einsum("pcd,pc,pce->pde", Vt, s_inv**2, Vt) @ At
    cov_noise = np.einsum("pdm,pm,pem->pde", Apinv, var_b, Apinv)
    if covariance == "residual":
        dof = np.maximum(beams - rank, 1)
        s2 = rss / dof
        cov = np.einsum("pcd,pc,pce->pde", Vt, s2[:, None] * s_inv**2, Vt)
        # never below the range-noise propagation
        cov = np.where(
            (np.trace(cov, axis1=1, axis2=2) >= np.trace(cov_noise, axis1=1, axis2=2))[
                :, None, None
            ],
            cov,
            cov_noise,
        )
    else:
        cov = cov_noise
    unobserved = np.where(keep, 0.0, fallback_var_m2)
    cov = cov + np.einsum("pcd,pc,pce->pde", Vt, unobserved, Vt)
    eye = np.broadcast_to(np.eye(3) * fallback_var_m2, (P, 3, 3))
    if commanded_shift_m is None:
        shift = np.where(ok[:, None], shift, 0.0)
    else:
        cmd = _check_images("commanded_shift_m", np.asarray(commanded_shift_m, dtype=float), (P, 3))
        shift = np.where(ok[:, None], shift, cmd)
    cov = np.where(ok[:, None, None], cov, eye)
    rms = np.where(ok, np.sqrt(rss / np.maximum(beams, 1)), 0.0)
    return ShiftEstimate(shift, cov, beams, np.where(ok, rank, 0), ok, rms)
