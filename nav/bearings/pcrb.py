"""The posterior Cramer-Rao bound of the bearing problem (beyond seed 004).

Tichavsky, Muravchik & Nehorai (1998), *Posterior Cramer-Rao bounds for discrete-time nonlinear
filtering*: for ``X_{k+1} = F X_k + c_k + W_k`` with ``W_k ~ N(0, Q)`` and ``Y_k = h(X_k) + E_k``,
``E_k ~ N(0, R)``, the information matrix of the state obeys

    J_{k+1} = D22 - D21 (J_k + D11)^{-1} D12,
    D11 = F^T Q^-1 F,  D12 = D21^T = -F^T Q^-1,  D22 = Q^-1 + E[H_{k+1}^T R^-1 H_{k+1}],

which for a linear motion model is ``J_{k+1} = (Q + F J_k^-1 F^T)^-1 + E[H^T R^-1 H]``, and every
unbiased estimator's error covariance is at least ``J_k^-1``. Seed 004's motion (eq. 1) is linear
in the state with ``F = I`` and the known input ``c_k = V(u_k) dt``; the expectation of the
measurement information is taken over the true positions at step k (Monte Carlo paths). The
control is treated as a known input (it depends on past measurements, which the estimator has).
For Gaussian initial state and linear h the bound is the Kalman filter's covariance.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nav.bearings.model import bearing_jacobian

Array = NDArray[np.float64]


def bearing_information(
    x: Array, beacons: Array, s_eps: Array, present: NDArray[np.bool_] | None = None
) -> Array:
    """Fisher information of one step's bearing tangents, per path (seed 004, eq. 17).

    Args:
        x: true positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.
        s_eps: covariance of one pair's tangent noise, ``(2, 2)``.
        present: ``(n, B)``: pairs measured (default: every observable pair).

    Returns:
        ``sum_b H_b^T S_eps^-1 H_b``, shape ``(n, 3, 3)``, 1/m^2.
    """
    jac = bearing_jacobian(x, beacons)  # (n, B, 2, 3), zero where unobservable
    if present is not None:
        jac = jac * present[..., None, None]
    n, nb = jac.shape[:2]
    r_inv = np.kron(np.eye(nb), np.linalg.inv(np.asarray(s_eps, dtype=float)))
    a = jac.reshape(n, 2 * nb, 3)
    return np.swapaxes(a, -1, -2) @ (r_inv @ a)


def pcrb(j0: Array, q: Array, info: Array, f: Array | None = None) -> Array:
    """The recursive posterior Cramer-Rao bound (Tichavsky et al. 1998, linear motion).

    Args:
        j0: initial information ``S_0^-1``, shape ``(d, d)``.
        q: process noise covariance ``Q``, ``(d, d)``.
        info: expected measurement information at steps 1..N, ``(N, d, d)``.
        f: state transition ``F`` (default identity), ``(d, d)``.

    Returns:
        The bound on the error covariance at steps 0..N, ``(N + 1, d, d)`` (``J_k^-1``).
    """
    d = len(j0)
    f = np.eye(d) if f is None else np.asarray(f, dtype=float)
    q = np.asarray(q, dtype=float)
    J = np.asarray(j0, dtype=float)
    out = [np.linalg.inv(J)]
    for k in range(len(info)):
        prior = q + f @ np.linalg.inv(J) @ f.T
        J = np.linalg.inv(prior) + info[k]
        J = 0.5 * (J + J.T)
        out.append(np.linalg.inv(J))
    return np.array(out)
