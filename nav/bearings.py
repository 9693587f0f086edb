"""Seed 004: the 3-D motion model, bearings to beacons and the EKF and UPMF on them.

Seed 004 (Miller, Miller & Miller 2019) measures its angles in the mathematical convention: theta
is the azimuth of the velocity from the x axis, counter-clockwise, and gamma its elevation up from
the horizontal plane (z up); the navigation angles of the other seeds are in :mod:`nav.angles`.
Every array carries a leading axis of Monte Carlo paths: positions ``(n, 3)`` m in the world frame
(x, y, z up), covariances ``(n, 3, 3)`` m^2, controls ``(n, 3)`` = (gamma rad, theta rad, V m/s).

Bearings (eq. 17). For each beacon at ``X_B`` the observation is the pair of tangents
``(tan phi, tan lambda)`` with ``tan phi = (Y_B - Y) / (X_B - X)`` and ``tan lambda = (Z_B - Z) cos
phi / (X_B - X)``. This module reads phi as the full bearing of the beacon (its quadrant given by
the sign of ``X_B - X``), so ``cos phi / (X_B - X) = 1 / rho`` with ``rho`` the horizontal
distance, and ``tan lambda = (Z_B - Z) / rho`` is the tangent of the beacon's elevation, the form
eq. 24 writes for the CMNF. A pair is *absent* (no observation) when the beacon is (almost)
straight above or below the vehicle (``rho < min_rho_m``) or when ``|tan phi|`` exceeds ``max_tan``
(the beacon almost abeam of the x axis); the filters leave absent pairs out, so no NaN is made.

The prediction step is pluggable (:class:`Prediction`): "by virtue of the system" (eq. 1,
:class:`SystemPrediction`) or a dead-reckoning shift with its own error covariance (seed 004,
section 4; supplied by another module with the same call signature).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]

MIN_RHO_M = 1e-3
"""Default horizontal distance below which a beacon counts as straight above/below, m."""
MAX_TAN = 1e3
"""Default largest |tan phi| that makes an observation (about 89.94 deg off the x axis)."""


# ----------------------------------------------------------------------------------------------
# Motion (eq. 1-2)


def velocity(u: Array) -> Array:
    """Velocity vector of a control (seed 004, eq. 2).

    Args:
        u: controls, shape ``(..., 3)``: gamma (elevation up from horizontal, rad), theta (from
            the x axis counter-clockwise, rad), V (speed, m/s).

    Returns:
        ``V (cos gamma cos theta, cos gamma sin theta, sin gamma)``, shape ``(..., 3)``, m/s,
        world frame.
    """
    u = np.asarray(u, dtype=float)
    g, th, v = u[..., 0], u[..., 1], u[..., 2]
    cg = np.cos(g)
    return np.stack([v * cg * np.cos(th), v * cg * np.sin(th), v * np.sin(g)], axis=-1)


def step(x: Array, u: Array, dt: float, w: Array | None = None) -> Array:
    """One step of the motion model ``X_{k+1} = X_k + V_k(u_k) dt + W_k`` (seed 004, eq. 1).

    Args:
        x: positions, shape ``(n, 3)``, m.
        u: controls, shape ``(n, 3)`` or ``(3,)`` (see :func:`velocity`).
        dt: step, s.
        w: the disturbance ``W_k``, shape ``(n, 3)``, m (none: the noise-free step).

    Returns:
        The positions at the next step, shape ``(n, 3)``, m.
    """
    out = np.asarray(x, dtype=float) + velocity(u) * dt
    return out if w is None else out + w


def nominal_path(gamma: Array, theta: Array, speed: Array, x0: Array, dt: float) -> Array:
    """The noise-free path of a control sequence (seed 004, eq. 3).

    Args:
        gamma, theta, speed: the nominal controls at t_0 .. t_{N-1}, shape ``(N,)`` (rad, rad,
            m/s).
        x0: the start, shape ``(3,)``, m.
        dt: step, s.

    Returns:
        Positions at t_0 .. t_N, shape ``(N + 1, 3)``, m.
    """
    u = np.stack([np.asarray(gamma), np.asarray(theta), np.asarray(speed)], axis=-1)
    steps = velocity(u) * dt
    return np.concatenate([np.asarray(x0, float)[None], x0 + np.cumsum(steps, axis=0)])


# ----------------------------------------------------------------------------------------------
# Prediction (pluggable)


@dataclass(frozen=True)
class PredictedShift:
    """The prediction of one step: the displacement the filter adds to its estimate.

    Attributes:
        displacement_m: shape ``(n, 3)``, m, world frame: ``X~_{k+1} - X^_k``.
        covariance_m2: error covariance of the displacement, shape ``(3, 3)`` or ``(n, 3, 3)``,
            m^2 (eq. 1's ``S^W`` for the prediction by virtue of the system).
    """

    displacement_m: Array
    covariance_m2: Array


class Prediction(Protocol):
    """A prediction step: ``(k, estimate (n, 3) m, control (n, 3)) -> PredictedShift``.

    ``k`` is the index of the step the estimate belongs to (the prediction is for ``k + 1``).
    The closed loops call it after the truth has moved to ``t_{k+1}``, so an implementation that
    senses the shift (the seabed-sensing dead reckoning of eq. 15-16, which needs the acoustic
    images of ``t_k`` and ``t_{k+1}``) can read its sensor's data of ``t_{k+1}`` through its own
    reference to that sensor; it never sees the truth. Implementations:
    :class:`SystemPrediction` (seed 004, eq. 1, "by virtue of the system"); the seabed DR returns
    its shift estimate (eq. 15) and the covariance of its error.
    """

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift: ...


@dataclass(frozen=True)
class SystemPrediction:
    """Prediction by virtue of the system: displacement ``V_k(u_k) dt``, covariance ``S^W``
    (seed 004, eq. 1 and section 6).

    Attributes:
        dt: step, s.
        s_w: ``S^W``, shape ``(3, 3)``, m^2.
    """

    dt: float
    s_w: Array

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift:
        return PredictedShift(velocity(u) * self.dt, np.asarray(self.s_w, dtype=float))


# ----------------------------------------------------------------------------------------------
# Bearings (eq. 17)


def check_beacons(beacons: Array) -> Array:
    """Beacon positions as a ``(B, 3)`` float array, m.

    Raises:
        NavInputError: if the shape is not ``(B, 3)`` with ``B >= 1`` or a value is not finite.
    """
    b = np.asarray(beacons, dtype=float)
    if b.ndim != 2 or b.shape[1] != 3 or len(b) == 0 or not np.isfinite(b).all():
        raise NavInputError(f"beacons: shape {b.shape} must be (B >= 1, 3), finite, m")
    return b


def _offsets(x: Array, beacons: Array) -> tuple[Array, Array, Array, Array]:
    x = np.asarray(x, dtype=float)
    dx = beacons[:, 0] - x[:, 0:1]  # (n, B), contiguous
    dy = beacons[:, 1] - x[:, 1:2]
    dz = beacons[:, 2] - x[:, 2:3]
    rho = np.sqrt(dx * dx + dy * dy)
    return dx, dy, dz, rho


def observable(
    x: Array, beacons: Array, min_rho_m: float = MIN_RHO_M, max_tan: float = MAX_TAN
) -> NDArray[np.bool_]:
    """Which beacon pairs make an observation at these positions.

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.
        min_rho_m: a beacon closer than this horizontally is straight above/below: absent, m.
        max_tan: ``|tan phi|`` above this is absent.

    Returns:
        Shape ``(n, B)``: True where the pair exists.
    """
    dx, dy, _, rho = _offsets(x, beacons)
    return (rho >= min_rho_m) & (np.abs(dy) <= max_tan * np.abs(dx))


def bearings(x: Array, beacons: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Noise-free bearing tangents (seed 004, eq. 17, phi the full bearing; module docstring).

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.

    Returns:
        ``(h, present)``: h of shape ``(n, B, 2)`` = (tan phi, tan lambda) per beacon (0 where
        absent) and ``present`` of shape ``(n, B)`` (:func:`observable` with its defaults).
    """
    dx, dy, dz, rho = _offsets(x, beacons)
    ok = (rho >= MIN_RHO_M) & (np.abs(dy) <= MAX_TAN * np.abs(dx))
    h = np.empty((*dx.shape, 2))
    if ok.all():
        np.divide(dy, dx, out=h[..., 0])
        np.divide(dz, rho, out=h[..., 1])
        return h, ok
    h[..., 0] = np.where(ok, dy / np.where(ok, dx, 1.0), 0.0)
    h[..., 1] = np.where(ok, dz / np.where(ok, rho, 1.0), 0.0)
    return h, ok


def bearing_jacobian(x: Array, beacons: Array) -> Array:
    """Jacobian of :func:`bearings` with respect to the position.

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.

    Returns:
        Shape ``(n, B, 2, 3)``, 1/m: rows d(tan phi)/dX and d(tan lambda)/dX per beacon (0 where
        the pair is absent).
    """
    dx, dy, dz, rho = _offsets(x, beacons)
    ok = (rho >= MIN_RHO_M) & (np.abs(dy) <= MAX_TAN * np.abs(dx))
    sdx = np.where(ok, dx, 1.0)
    srho = np.where(ok, rho, 1.0)
    zero = np.zeros_like(dx)
    r1 = np.stack([dy / sdx**2, -1.0 / sdx, zero], axis=-1)
    r3 = srho**3
    r2 = np.stack([dz * dx / r3, dz * dy / r3, -1.0 / srho], axis=-1)
    jac = np.stack([r1, r2], axis=-2)
    return np.where(ok[..., None, None], jac, 0.0)


# ----------------------------------------------------------------------------------------------
# Filters


def _check_state(x: Array, p: Array) -> tuple[Array, Array]:
    x = np.asarray(x, dtype=float)
    p = np.asarray(p, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3:
        raise NavInputError(f"state: shape {x.shape} must be (n, 3)")
    if p.shape != (len(x), 3, 3):
        raise NavInputError(f"covariance: shape {p.shape} must be ({len(x)}, 3, 3)")
    return x, p


def predict(x_hat: Array, p_hat: Array, shift: PredictedShift) -> tuple[Array, Array]:
    """Prediction of the EKF and the UPMF (seed 004, eq. 21 first two lines).

    Args:
        x_hat: estimates, shape ``(n, 3)``, m.
        p_hat: their covariances, shape ``(n, 3, 3)``, m^2.
        shift: the step's :class:`PredictedShift`.

    Returns:
        ``(x_tilde, p_tilde)``: ``x_hat + displacement`` and ``p_hat + covariance``.
    """
    x_hat, p_hat = _check_state(x_hat, p_hat)
    return x_hat + shift.displacement_m, p_hat + shift.covariance_m2


def _joseph(p: Array, k: Array, h: Array, r: Array) -> Array:
    n = p.shape[-1]
    a = np.eye(n) - k @ h
    return a @ p @ np.swapaxes(a, -1, -2) + k @ r @ np.swapaxes(k, -1, -2)


def _symmetric(p: Array) -> Array:
    return 0.5 * (p + np.swapaxes(p, -1, -2))


def ekf_update(
    x_tilde: Array,
    p_tilde: Array,
    y: Array,
    present: NDArray[np.bool_],
    beacons: Array,
    s_eps: Array,
) -> tuple[Array, Array]:
    """EKF update on the bearing tangents of every beacon (seed 004, eq. 17-18; [18]).

    Joseph form; absent pairs (``present`` False, or unobservable at the prediction) are left out
    by giving them zero rows in H and a zero residual.

    Args:
        x_tilde: predictions, shape ``(n, 3)``, m.
        p_tilde: their covariances, shape ``(n, 3, 3)``, m^2.
        y: measured tangents, shape ``(n, B, 2)``.
        present: shape ``(n, B)``: which pairs were measured.
        beacons: shape ``(B, 3)``, m.
        s_eps: ``S^eps``, shape ``(2, 2)``: covariance of one pair's tangent noise.

    Returns:
        ``(x_hat, p_hat)``, shapes ``(n, 3)`` and ``(n, 3, 3)``.
    """
    x_tilde, p_tilde = _check_state(x_tilde, p_tilde)
    n, nb = len(x_tilde), len(beacons)
    h0, ok = bearings(x_tilde, beacons)
    use = ok & present
    jac = bearing_jacobian(x_tilde, beacons) * use[..., None, None]
    resid = np.where(use[..., None], y - h0, 0.0).reshape(n, 2 * nb)
    H = jac.reshape(n, 2 * nb, 3)
    R = np.kron(np.eye(nb), np.asarray(s_eps, dtype=float))
    S = H @ p_tilde @ np.swapaxes(H, -1, -2) + R
    PHt = p_tilde @ np.swapaxes(H, -1, -2)
    K = np.swapaxes(np.linalg.solve(S, np.swapaxes(PHt, -1, -2)), -1, -2)
    x_hat = x_tilde + np.einsum("nij,nj->ni", K, resid)
    return x_hat, _symmetric(_joseph(p_tilde, K, H, np.broadcast_to(R, (n, *R.shape))))


def pseudo_measurements(y: Array, x_ref: Array, beacons: Array) -> tuple[Array, Array, Array]:
    """Pseudo-measurements of the bearing tangents (seed 004, eq. 19-20).

    ``Y' = Psi1(Y) X + Psi2(X, Y) E``: with phi = atan(tan phi) put in the quadrant of the beacon
    seen from ``x_ref`` (the sign of ``X_B - X``, module docstring) and lambda = atan(tan lambda).

    Args:
        y: measured tangents, shape ``(n, B, 2)``.
        x_ref: where Psi2 is evaluated and the quadrant of phi taken (the prediction), ``(n, 3)``.
        beacons: shape ``(B, 3)``, m.

    Returns:
        ``(y_pseudo (n, B, 2) m, psi1 (n, B, 2, 3), psi2 (n, B, 2) m)``: the diagonal of Psi2.
    """
    dx = beacons[None, :, 0] - x_ref[:, None, 0]
    phi = np.arctan(y[..., 0]) + np.where(dx < 0, np.pi, 0.0)
    lam = np.arctan(y[..., 1])
    sp, cp, sl, cl = np.sin(phi), np.cos(phi), np.sin(lam), np.cos(lam)
    xb, yb, zb = beacons[None, :, 0], beacons[None, :, 1], beacons[None, :, 2]
    y1 = xb * sp - yb * cp
    y2 = xb * sl - zb * cp * cl
    zero = np.zeros_like(sp)
    psi1 = np.stack(
        [np.stack([sp, -cp, zero], axis=-1), np.stack([sl, zero, -cp * cl], axis=-1)], axis=-2
    )
    psi2 = np.stack([dx * cp, dx * cl], axis=-1)
    return np.stack([y1, y2], axis=-1), psi1, psi2


UPMF_FORMS: tuple[str, ...] = ("unbiased", "printed")


def upmf_update(
    x_tilde: Array,
    p_tilde: Array,
    y: Array,
    present: NDArray[np.bool_],
    beacons: Array,
    s_eps: Array,
    floor: float = 1e-12,
    form: str = "unbiased",
) -> tuple[Array, Array]:
    """Update of the unbiased pseudo-measurement filter (seed 004, eq. 19-21).

    ``K = P~ Psi1^T (Psi1 P~ Psi1^T + Psi2 S^eps Psi2^T)^+``, ``X^ = X~ + K (Y' - Psi1(Y) X~)``
    (the printed ``Psi1 X_k`` is a typo for the prediction, seed README), ``P^ = (I - K Psi1)
    P~``. Absent pairs get zero rows; singular values below ``floor`` count as zero.

    ``form = "printed"`` evaluates Psi1 and Psi2 of the gain at the *measured* angles, as eq. 21
    prints. The gain then depends on the current noise, and with the noise on the tangents (eq.
    17) eq. 20's noise ``Psi2 E`` has a mean that is not zero (the measured cos phi, cos lambda
    depend on E): the estimate is biased by ~sigma^2 |X_B - X| (about 0.02 m in x on section 6's
    setting, 2.6 standard errors of the mean over 1e4 paths, averaged over time). ``form =
    "unbiased"`` (default) keeps the estimate unbiased, the property the filter is named for
    ([26], derived from the unbiasedness of the previous estimate; its derivation is not in the
    seed, so this is the project's reading): the gain's Psi1 and Psi2 are evaluated at the
    predicted bearings, which do not depend on the current noise, and the noise's mean
    (:func:`pseudo_noise_mean`, at the prediction) is taken off ``Y'``; the innovation keeps the
    measured ``Psi1(Y)`` of eq. 20.

    Args:
        x_tilde: predictions, shape ``(n, 3)``, m.
        p_tilde: their covariances, shape ``(n, 3, 3)``, m^2.
        y: measured tangents, shape ``(n, B, 2)``.
        present: shape ``(n, B)``.
        beacons: shape ``(B, 3)``, m.
        s_eps: ``S^eps``, shape ``(2, 2)``.
        floor: absolute singular-value floor of the pseudo-inverse, m^2.
        form: ``"unbiased"`` or ``"printed"`` (see above).

    Returns:
        ``(x_hat, p_hat)``, shapes ``(n, 3)`` and ``(n, 3, 3)``.
    """
    if form not in UPMF_FORMS:
        raise NavInputError(f"form = {form!r}: must be one of {', '.join(UPMF_FORMS)}")
    x_tilde, p_tilde = _check_state(x_tilde, p_tilde)
    n, nb = len(x_tilde), len(beacons)
    h0, ok = bearings(x_tilde, beacons)
    use = (ok & present).astype(float)
    yp, psi1, psi2 = pseudo_measurements(np.where(present[..., None], y, 0.0), x_tilde, beacons)
    if form == "unbiased":
        yp = yp - pseudo_noise_mean(x_tilde, h0, beacons, s_eps)
        _, g1, g2 = pseudo_measurements(h0, x_tilde, beacons)
    else:
        g1, g2 = psi1, psi2
    psi1 = (psi1 * use[..., None, None]).reshape(n, 2 * nb, 3)
    g1 = (g1 * use[..., None, None]).reshape(n, 2 * nb, 3)
    g2 = (g2 * use[..., None]).reshape(n, 2 * nb)
    yp = (yp * use[..., None]).reshape(n, 2 * nb)
    R2 = np.kron(np.eye(nb), np.asarray(s_eps, dtype=float))
    noise = g2[:, :, None] * R2[None] * g2[:, None, :]
    S = g1 @ p_tilde @ np.swapaxes(g1, -1, -2) + noise
    PHt = p_tilde @ np.swapaxes(g1, -1, -2)
    # Absent pairs have zero rows and columns in S; a unit diagonal there makes S invertible
    # without changing K (their columns of P Psi1^T are zero), so K = P Psi1^T S^+ whenever the
    # present block is regular; otherwise the floored pseudo-inverse is used.
    gap = np.repeat(1.0 - use, 2, axis=1)
    S_reg = S + gap[:, :, None] * np.eye(2 * nb)
    try:
        K = np.swapaxes(np.linalg.solve(S_reg, np.swapaxes(PHt, -1, -2)), -1, -2)
    except np.linalg.LinAlgError:
        K = PHt @ pinv_floor(S, floor)
    resid = yp - np.einsum("nij,nj->ni", psi1, x_tilde)
    x_hat = x_tilde + np.einsum("nij,nj->ni", K, resid)
    p_hat = (np.eye(3) - K @ g1) @ p_tilde
    return x_hat, _symmetric(p_hat)


def pseudo_noise_mean(x: Array, h: Array, beacons: Array, s_eps: Array) -> Array:
    """Mean of eq. 20's noise term ``Psi2(X, Y) E`` given the position, to second order in E.

    Row 1 is ``eps_phi (X_B - X) cos phi_m`` with ``cos phi_m = s / sqrt(1 + (t + eps)^2)`` (s the
    sign of ``X_B - X``), so by Stein's lemma ``E = sigma_phi^2 (X_B - X) g'(t)``, ``g(t) = s /
    sqrt(1 + t^2)``. Row 2 is ``cos lambda_m [eps_lambda (X_B - X) + (Z_B - Z)(cos phi - cos
    phi_m)]``, whose mean is ``sigma_lambda^2 (X_B - X) c'(t_lambda) - c(t_lambda) (Z_B - Z)
    sigma_phi^2 g''(t) / 2`` with ``c(t) = 1 / sqrt(1 + t^2)``.

    Args:
        x: positions where it is evaluated (the prediction), ``(n, 3)`` m.
        h: the noise-free tangents there, ``(n, B, 2)`` (:func:`bearings`).
        beacons: ``(B, 3)`` m.
        s_eps: ``(2, 2)``; its diagonal is used.

    Returns:
        Shape ``(n, B, 2)``, m.
    """
    dx = beacons[None, :, 0] - x[:, None, 0]
    dz = beacons[None, :, 2] - x[:, None, 2]
    sgn = np.where(dx < 0, -1.0, 1.0)
    t, tl = h[..., 0], h[..., 1]
    q, ql = 1.0 + t * t, 1.0 + tl * tl
    g1 = -sgn * t / q**1.5
    g2 = sgn * (2 * t * t - 1) / q**2.5
    c, c1 = 1 / np.sqrt(ql), -tl / ql**1.5
    vp, vl = s_eps[0, 0], s_eps[1, 1]
    return np.stack([vp * dx * g1, vl * dx * c1 - c * dz * vp * g2 / 2], axis=-1)


def pinv_floor(a: Array, floor: float) -> Array:
    """Moore-Penrose pseudo-inverse with an absolute singular-value floor (seed README, CMNF).

    Singular values below ``floor`` count as zero; numpy's default relative cut-off would keep
    rounding noise of a numerically zero matrix (seed 004's cov(alpha, alpha)) and amplify it.

    Args:
        a: matrices, shape ``(..., m, n)``.
        floor: absolute floor, in the units of ``a``.

    Returns:
        Shape ``(..., n, m)``.
    """
    u, s, vt = np.linalg.svd(a, full_matrices=False)
    inv = np.where(s > floor, 1.0 / np.where(s > floor, s, 1.0), 0.0)
    return np.swapaxes(vt, -1, -2) @ (inv[..., :, None] * np.swapaxes(u, -1, -2))
