"""Eq. 8-16 of seed 004 (:mod:`nav.seabed`): the shift between two acoustic images with its error
covariance (compiled by numba, :func:`nav.seabed.kernel.seabed_shift`; numpy's SVD for tiny
``rcond``) and the dead reckoning on those shifts.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.dead_reckoning import DeadReckoning
from nav.errors import NavError, NavInputError
from nav.seabed.fit import fit_slopes
from nav.seabed.geometry import BeamGeometry, SlopeBasis, _finite

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

BeamAttitude = Literal["one_attitude", "turning"]
"""The two readings of the beam attitude between two images (:mod:`nav.seabed`)."""

CovarianceKind = Literal["residual", "range_noise"]
"""How :func:`shift_estimate` states its error covariance (:mod:`nav.seabed`)."""

SINGULAR_FLOOR = 1e-9
"""Absolute singular-value floor of the shift's least squares (eq. 15): singular values of A
below ``SINGULAR_FLOOR * sqrt(m)`` (``m`` beams, each row of A of order 1: its z component is 1)
count as zero, whatever ``rcond``."""


@dataclass(frozen=True)
class ShiftEstimate:
    """The position shift between two acoustic images (seed 004, eq. 15), per path.

    Attributes:
        shift_m: ``dX-hat_{k+1}``, shape (P, 3), m, world (where not ``ok``: zero, or the
            commanded displacement when one is given).
        covariance_m2: its error covariance, shape (P, 3, 3), m^2 (module docstring;
            ``fallback_var_m2 * I`` where not ``ok``).
        beams: beams used (echo in both images), shape (P,).
        rank: rank of eq. 14's A (3: the whole shift is observed), shape (P,).
        ok: a shift was produced (enough beams for the slope fit and the least squares),
            shape (P,).
        residual_rms: root-mean-square residual of eq. 13, shape (P,), m (0 where not ``ok``).
    """

    shift_m: Array
    covariance_m2: Array
    beams: NDArray[np.int_]
    rank: NDArray[np.int_]
    ok: BoolArray
    residual_rms: Array


def _check_images(name: str, a: Array, shape: tuple[int, ...]) -> Array:
    a = np.asarray(a)
    if a.shape != shape:
        raise NavInputError(f"{name}: shape {a.shape}, expected {shape}")
    return a


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
        covariance: ``"residual"`` or ``"range_noise"`` (:mod:`nav.seabed`).
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
            a non-finite attitude, position, command or slope (at a used beam), a
            ``sigma_range_m``, ``fallback_var_m2`` or ``rcond`` out of range, a basis with at
            least as many functions as the image has beams (:func:`check_basis`), an unknown
            reading, or ``"turning"`` without ``next_attitude_rad``.
        NavError: if the compiled kernel refuses its arguments (a programming error).
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
    _finite("attitude_rad", att0)
    if reading not in ("one_attitude", "turning"):
        raise NavInputError(f"reading = {reading!r}: use 'one_attitude' or 'turning'")
    if reading == "turning":
        if next_attitude_rad is None:
            raise NavInputError("reading = 'turning' needs next_attitude_rad (paths, 2)")
        att1 = _check_images(
            "next_attitude_rad", np.asarray(next_attitude_rad, dtype=float), (P, 2)
        )
        _finite("next_attitude_rad", att1)
    if delta_e not in ("linear", "exact"):
        raise NavInputError(f"delta_e = {delta_e!r}: use 'linear' or 'exact'")
    if covariance not in ("residual", "range_noise"):
        raise NavInputError(f"covariance = {covariance!r}: use 'residual' or 'range_noise'")
    if not (np.isfinite(sigma_range_m) and sigma_range_m >= 0):
        raise NavInputError(f"sigma_range_m = {sigma_range_m}: must be finite and >= 0, m")
    if not (np.isfinite(fallback_var_m2) and fallback_var_m2 > 0):
        raise NavInputError(f"fallback_var_m2 = {fallback_var_m2}: must be finite and > 0, m^2")
    if not (np.isfinite(rcond) and 0 <= rcond < 1):
        raise NavInputError(f"rcond = {rcond}: must be in [0, 1)")
    w0, w1 = w0.astype(bool), w1.astype(bool)
    use = w0 & w1
    if not (np.all(np.isfinite(L0[w0])) and np.all(np.isfinite(L1[w1]))):
        raise NavInputError("ranges_m / next_ranges_m: non-finite range on a beam with an echo")
    m = geometry.shape[0] * geometry.shape[1]
    e = geometry.directions(att0).reshape(P, m, 3)  # eq. 8
    de = None
    if reading == "turning":  # step 2: eq. 10
        de = geometry.direction_change(att0, att1, exact=delta_e == "exact").reshape(P, m, 3)
    usef = use.reshape(P, m)
    if slopes is None:  # step 3: Appendix A on every foot of image k
        origin = np.zeros((P, 3)) if position_m is None else np.asarray(position_m, dtype=float)
        _finite("position_m", _check_images("position_m", origin, (P, 3)))
        w0f = w0.reshape(P, m)
        feet = origin[:, None, :] + np.where(w0f, L0.reshape(P, m), 0.0)[..., None] * e  # eq. 8
        grad, fit_ok = fit_slopes(feet, w0f, basis or SlopeBasis.seed004())
    else:
        grad = _check_images("slopes", np.asarray(slopes, dtype=float), (*L0.shape, 3))
        _finite("slopes (at a beam with an echo in both images)", grad, use[..., None])
        grad = np.where(use[..., None], grad, 0.0).reshape(P, m, 3)
        fit_ok = np.ones(P, bool)
    cmd = None
    if commanded_shift_m is not None:
        cmd = _check_images("commanded_shift_m", np.asarray(commanded_shift_m, dtype=float), (P, 3))
        _finite("commanded_shift_m", cmd)
    if rcond * 1e8 < 1.0:  # a cut-off below what eigenvalues of A^T A resolve: the SVD
        return _shift_svd(
            grad,
            e,
            de,
            L0,
            L1,
            usef,
            fit_ok,
            covariance,
            sigma_range_m,
            fallback_var_m2,
            rcond,
            cmd,
        )
    # steps 4-5 compiled (nav.seabed.kernel.seabed_shift): eq. 12 and 14 over the used beams,
    # eq. 15 by the singular values of A from the eigen-decomposition of the 3 x 3 A^T A with an
    # absolute floor (rank-deficient A: minimum-norm shift), and the stated covariance
    shift = np.empty((P, 3))
    cov = np.empty((P, 3, 3))
    beams = np.empty(P, np.int64)
    rank = np.empty(P, np.int64)
    ok = np.empty(P, np.uint8)
    rms = np.empty(P)
    from nav.seabed import kernel  # numba: imported (and its cache loaded) on the first shift

    status = kernel.seabed_shift(
        np.ascontiguousarray(grad, dtype=float).reshape(P, m, 3),
        np.ascontiguousarray(e, dtype=float).reshape(P, m, 3),
        np.empty((0, 0, 3))
        if de is None
        else np.ascontiguousarray(de, dtype=float).reshape(P, m, 3),
        np.ascontiguousarray(L0, dtype=float).reshape(P, m),
        np.ascontiguousarray(L1, dtype=float).reshape(P, m),
        np.ascontiguousarray(usef, dtype=np.uint8).reshape(P, m),
        np.ascontiguousarray(fit_ok, dtype=np.uint8),
        covariance == "residual",
        float(sigma_range_m),
        float(fallback_var_m2),
        float(rcond),
        SINGULAR_FLOOR,
        np.empty((0, 3)) if cmd is None else np.ascontiguousarray(cmd, dtype=float),
        shift,
        cov,
        beams,
        rank,
        ok,
        rms,
    )
    if status < 0:
        raise NavError(f"shift_estimate: the compiled shift refused: {kernel.STATUS[status]}")
    return ShiftEstimate(shift, cov, beams, rank, ok.view(np.bool_), rms)


def _shift_svd(
    grad: Array,
    e: Array,
    de: Array | None,
    L0: Array,
    L1: Array,
    usef: BoolArray,
    fit_ok: BoolArray,
    covariance: CovarianceKind,
    sigma_range_m: float,
    fallback_var_m2: float,
    rcond: float,
    cmd: Array | None,
) -> ShiftEstimate:
    """Steps 4-5 of :func:`shift_estimate` in numpy with the SVD of A, for ``rcond`` below what
    the eigenvalues of ``A^T A`` resolve (arguments as there, flattened to (P, m, ...))."""
    P, m = usef.shape
    if de is None:
        de = np.zeros_like(e)
    L0f = np.where(usef, L0.reshape(P, m), 0.0)
    dL = np.where(usef, (L1 - L0).reshape(P, m), 0.0)  # step 1: dL = L_{k+1} - L_k
    grad = np.where(usef[..., None], grad, 0.0)
    # step 4: eq. 12 and 14 (masked beams give zero rows)
    A = grad
    B = -np.einsum("pmc,pmc->pm", grad, de * L0f[..., None] + e * dL[..., None])
    beams = usef.sum(axis=1)
    ok = fit_ok & (beams >= 3)
    # step 5: eq. 15 by the SVD of A with an absolute floor (rank-deficient A: minimum-norm shift)
    At = A.transpose(0, 2, 1)
    _, s, Vt = np.linalg.svd(A, full_matrices=False)  # (P,3), (P,3,3)
    floor = np.maximum(SINGULAR_FLOOR * np.sqrt(np.maximum(beams, 1)), rcond * s[:, 0])
    keep = s > floor[:, None]
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
        trace_ok = np.trace(cov, axis1=1, axis2=2) >= np.trace(cov_noise, axis1=1, axis2=2)
        cov = np.where(trace_ok[:, None, None], cov, cov_noise)
    else:
        cov = cov_noise
    unobserved = np.where(keep, 0.0, fallback_var_m2)
    cov = cov + np.einsum("pcd,pc,pce->pde", Vt, unobserved, Vt)
    eye = np.broadcast_to(np.eye(3) * fallback_var_m2, (P, 3, 3))
    shift = np.where(ok[:, None], shift, 0.0 if cmd is None else cmd)
    cov = np.where(ok[:, None, None], cov, eye)
    rms = np.where(ok, np.sqrt(rss / np.maximum(beams, 1)), 0.0)
    return ShiftEstimate(shift, cov, beams, np.where(ok, rank, 0), ok, rms)


def seabed_track(
    start_m: Array,
    ranges_m: Array,
    next_ranges_m: Array,
    geometry: BeamGeometry,
    attitudes_rad: Array,
    *,
    echo: BoolArray | None = None,
    next_echo: BoolArray | None = None,
    reading: BeamAttitude = "one_attitude",
    basis: SlopeBasis | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
    slopes: Array | None = None,
) -> tuple[Array, BoolArray]:
    """Dead reckoning on seabed shifts, ``X-hat_{k+1} = X-hat_k + dX-hat_{k+1}`` (seed 004,
    eq. 16), over N steps.

    Args:
        start_m: ``X-hat_0``, shape (P, 3), m.
        ranges_m: image at the start of each step (at ``X_k``, attitude ``u_k``), shape
            (P, N, Mi, Mj), m.
        next_ranges_m: image at the end of each step (at ``X_{k+1}``; attitude ``u_k`` for
            ``"one_attitude"``, ``u_{k+1}`` for ``"turning"``), shape (P, N, Mi, Mj), m.
        geometry: the beams.
        attitudes_rad: ``(gamma_k, theta_k)``, k = 0..N, shape (P, N + 1, 2), rad.
        echo: echoes of ``ranges_m``, shape (P, N, Mi, Mj) (default: all).
        next_echo: echoes of ``next_ranges_m``.
        reading: :data:`BeamAttitude`.
        basis: Appendix A's basis.
        delta_e: eq. 10 or the exact change.
        slopes: known ``grad psi`` at the feet of ``ranges_m``, shape (P, N, Mi, Mj, 3), instead
            of the Appendix A estimate.

    Returns:
        ``(track, ok)``: positions shape (P, N + 1, 3), m; ``ok`` shape (P, N): the step's shift
        was produced (a step without one adds zero).
    """
    x = np.asarray(start_m, dtype=float)
    L0 = np.asarray(ranges_m, dtype=float)
    P, N = L0.shape[:2]
    att = np.asarray(attitudes_rad, dtype=float)
    if att.shape != (P, N + 1, 2):
        raise NavInputError(f"attitudes_rad: shape {att.shape}, expected ({P}, {N + 1}, 2)")
    track = np.empty((P, N + 1, 3))
    oks = np.empty((P, N), bool)
    track[:, 0] = x
    dr = DeadReckoning(x)
    for k in range(N):
        est = shift_estimate(
            L0[:, k],
            np.asarray(next_ranges_m)[:, k],
            geometry,
            att[:, k],
            att[:, k + 1],
            echo=None if echo is None else np.asarray(echo)[:, k],
            next_echo=None if next_echo is None else np.asarray(next_echo)[:, k],
            reading=reading,
            basis=basis,
            position_m=track[:, k],
            delta_e=delta_e,
            slopes=None if slopes is None else np.asarray(slopes)[:, k],
        )
        dr.advance(est.shift_m)  # eq. 16
        track[:, k + 1] = dr.position
        oks[:, k] = est.ok
    return track, oks
