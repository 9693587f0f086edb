"""The range to the leader's broadcast position as an EKF measurement (beyond seed 003, which
adjusts instead): the measurement model for :mod:`nav.ekf` and its batched update.

Positions are (east, north) in m; arrays carry a leading run axis n.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.ekf import update

Array = NDArray[np.float64]


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
