"""The posterior Cramer-Rao bound of terrain-relative navigation (Bergman 1999).

For the TRN model of :mod:`nav.trn` (horizontal position ``x``, random-walk motion
``x_{k+1} = x_k + d_k + w_k``, ``w_k ~ N(0, Q_k)``, soundings ``z_i = h(x + o_i) + e_i``) the
posterior information obeys Tichavsky, Muravchik & Nehorai's (1998) recursion with ``F = I``,
in Bergman's (1999, section 3.4) form for terrain navigation:

    J_k = (J_{k-1}^-1 + Q_k)^-1 + E[ sum_i g_i g_i^T / sigma_i^2 ]

with ``g_i = grad h`` at the beam's footprint on the true seabed; every unbiased estimator's error
covariance at step k is at least ``J_k^-1``. With a common per-ping bias of prior variance
``sigma_b^2`` marginalised (:mod:`nav.trn.likelihood`) the measurement information is
``G^T (D + sigma_b^2 1 1^T)^-1 G`` (Sherman-Morrison):

    sum a_i g_i g_i^T - sigma_b^2 (sum a_i g_i)(sum a_i g_i)^T / (1 + sigma_b^2 sum a_i),
    a_i = 1 / sigma_i^2.

The expectation is over the true paths: pass the gradients of several Monte Carlo paths (a
leading axis) and the information is averaged over them; one path gives the bound conditioned
on it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]


def terrain_information(
    gradients: ArrayLike, sigma_m: ArrayLike, active: ArrayLike, sigma_bias_m: float = 0.0
) -> Array:
    """Fisher information of pings about the horizontal position (module docstring).

    Args:
        gradients: ``d depth / d (x, y)`` at each beam's footprint, shape ``(..., m, 2)``, m/m.
        sigma_m: each beam's depth standard deviation (beam and map), ``(..., m)``, m, > 0 where
            active.
        active: whether each beam is measured, ``(..., m)``.
        sigma_bias_m: prior standard deviation of the ping's common bias, m (0 = none).

    Returns:
        The information, shape ``(..., 2, 2)``, 1/m^2.
    """
    g = np.asarray(gradients, dtype=float)
    act = np.asarray(active, dtype=bool) & np.all(np.isfinite(g), axis=-1)
    s = np.broadcast_to(np.asarray(sigma_m, dtype=float), act.shape)
    safe = np.where(act, s, 1.0)
    a = np.where(act, 1.0 / (safe * safe), 0.0)
    g = np.where(act[..., None], g, 0.0)
    info = np.einsum("...m,...mi,...mj->...ij", a, g, g)
    if sigma_bias_m > 0.0:
        sb2 = sigma_bias_m * sigma_bias_m
        ag = np.einsum("...m,...mi->...i", a, g)
        denom = 1.0 + sb2 * a.sum(axis=-1)
        info = info - sb2 * ag[..., :, None] * ag[..., None, :] / denom[..., None, None]
    return info


def trn_pcrb(
    J0: ArrayLike,
    Q: ArrayLike,
    gradients: ArrayLike,
    sigma_m: ArrayLike,
    active: ArrayLike,
    sigma_bias_m: float = 0.0,
) -> Array:
    """The recursive posterior Cramer-Rao bound of TRN (module docstring).

    Step k (k = 0..K-1) first predicts with ``Q[k]`` and then takes ping k.

    Args:
        J0: initial information ``P0^-1``, shape ``(2, 2)``, 1/m^2.
        Q: process noise of each step, ``(K, 2, 2)``, m^2.
        gradients: terrain gradients at the beams' true footprints, ``(K, m, 2)``, or
            ``(R, K, m, 2)`` for R Monte Carlo paths (the information is averaged over them).
        sigma_m: beam standard deviations (beam and map), ``(K, m)`` or ``(R, K, m)``, m.
        active: beams measured, ``(K, m)`` or ``(R, K, m)``.
        sigma_bias_m: prior standard deviation of a common per-ping bias, m (0 = none).

    Returns:
        The bound on the error covariance after each ping, ``J_k^-1``, shape ``(K, 2, 2)``, m^2.

    Raises:
        NavInputError: shapes that do not match or a non-positive-definite ``J0``.
    """
    j = np.asarray(J0, dtype=float)
    q = np.asarray(Q, dtype=float)
    g = np.asarray(gradients, dtype=float)
    if (
        j.shape != (2, 2)
        or not np.all(np.isfinite(j))
        or np.linalg.eigvalsh(0.5 * (j + j.T))[0] <= 0
    ):
        raise NavInputError(f"J0 = {j.tolist()}: must be a finite positive-definite 2x2, 1/m^2")
    if g.ndim == 3:
        g = g[None]
    if g.ndim != 4 or g.shape[-1] != 2:
        raise NavInputError(f"gradients has shape {g.shape}: must be (K, m, 2) or (R, K, m, 2)")
    k = g.shape[1]
    if q.shape != (k, 2, 2) or not np.all(np.isfinite(q)):
        raise NavInputError(f"Q has shape {q.shape}: must be ({k}, 2, 2) and finite, m^2")
    s = np.broadcast_to(np.asarray(sigma_m, dtype=float), g.shape[:-1])
    act = np.broadcast_to(np.asarray(active, dtype=bool), g.shape[:-1])
    info = terrain_information(g, s, act, sigma_bias_m).mean(axis=0)  # (K, 2, 2)
    out = np.empty((k, 2, 2))
    for i in range(k):
        prior_cov = np.linalg.inv(j) + q[i]
        j = np.linalg.inv(prior_cov) + info[i]
        j = 0.5 * (j + j.T)
        out[i] = np.linalg.inv(j)
    return out
