"""Seed 004's filters on the bearings: the prediction of the EKF and the UPMF (eq. 21), the EKF
update (the one Kalman update of :mod:`nav.ekf` with the bearing model) and the unbiased
pseudo-measurement filter (UPMF, eq. 19-21).

The UPMF is its own algorithm, not a Kalman update of a measurement model: its gain is built on
the pseudo-measurements of eq. 19-20 (``Psi1`` and ``Psi2`` evaluated at the predicted bearings),
with a pseudo-inverse of the innovation covariance and the covariance update ``(I - K Psi1) P~``
of eq. 21, so it stays here, beside the EKF, as the documented exception to "one Kalman update".

Shapes and conventions: :mod:`nav.bearings.model` (positions ``(n, 3)`` m, world frame; the
measured tangents ``(n, B, 2)``; which pairs were measured ``(n, B)``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nav.bearings.model import Array, BearingTangents, PredictedShift, bearings
from nav.ekf import update_with
from nav.errors import NavInputError


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

    The one Kalman update of the project, :func:`nav.ekf.update` (Joseph form), with the bearing
    measurement model :class:`nav.bearings.model.BearingTangents`: absent pairs (``present``
    False, or unobservable at the prediction) are inactive components, left out exactly.

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
    model = BearingTangents(beacons, np.asarray(s_eps, dtype=float), np.asarray(present, bool))
    z = np.asarray(y, dtype=float).reshape(len(x_tilde), -1)
    x_hat, p_hat, _ = update_with(x_tilde, p_tilde, model, z)
    return x_hat, p_hat


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

    Its own algorithm, not :func:`nav.ekf.update` with a measurement model (the documented
    exception to the one Kalman update): the gain is built on the pseudo-measurements' ``Psi1``
    and ``Psi2`` with a floored pseudo-inverse, and the covariance is eq. 21's ``(I - K Psi1)
    P~``, not the Joseph form.

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
