"""The extended Kalman filter, batched over Monte Carlo runs (seed 000 eq. 17-23).

Predict: ``x- = f(x, u)`` (eq. 17), ``P- = F P F^T + Q`` (eq. 18).
Update: ``y = z - h(x-)`` with angles wrapped (eq. 19), ``S = H P- H^T + R`` (eq. 20),
``K = P- H^T S^-1`` (eq. 21), ``x = x- + K y`` (eq. 22), and the covariance in Joseph form
``P = (I - K H) P- (I - K H)^T + K R K^T``, which equals eq. 23 for the optimal gain but stays
symmetric and positive definite in floating point.

Robustness (after robot_localization and filterpy): components a model marks inactive (e.g. the
USBL azimuth straight above the transceiver) are left out of the update exactly; runs without a
measurement are left unchanged; an optional chi-square gate on the normalised innovation squared
(NIS) rejects outliers; a non-finite state or covariance raises :class:`FilterDivergedError`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from nav.errors import FilterDivergedError, NavInputError

Array = NDArray[np.float64]


class MotionModel(Protocol):
    """What :meth:`BatchEKF.predict` needs from a motion model."""

    def f(self, x: Array, u: Array, dt_s: float) -> Array: ...
    def F(self, x: Array, u: Array, dt_s: float) -> Array: ...
    def Q(self, u: Array, dt_s: float) -> Array: ...


class MeasurementModel(Protocol):
    """What :meth:`BatchEKF.update` needs from a measurement model."""

    def h(self, x: Array) -> Array: ...
    def H(self, x: Array) -> Array: ...
    def R(self) -> Array: ...
    def residual(self, z: Array, hx: Array) -> Array: ...
    def active(self, x: Array) -> NDArray[np.bool_]: ...


@dataclass(frozen=True)
class UpdateInfo:
    """Diagnostics of one batched update.

    Attributes:
        nis: normalised innovation squared ``y^T S^-1 y`` over the active components, shape (n,);
            NaN for runs that had no measurement.
        dof: number of active components, shape (n,).
        applied: whether the update changed the run's estimate, shape (n,).
        rejected: whether the gate rejected the measurement, shape (n,).
    """

    nis: Array
    dof: NDArray[np.intp]
    applied: NDArray[np.bool_]
    rejected: NDArray[np.bool_]


@functools.lru_cache(maxsize=256)
def gate_limit(probability: float, dof: int) -> float:
    """Chi-square quantile of ``probability`` with ``dof`` degrees of freedom (cached)."""
    return float(chi2.ppf(probability, dof))


def predict(x: Array, P: Array, fx: Array, F: Array, Q: Array) -> tuple[Array, Array]:
    """EKF prediction (eq. 17-18).

    Args:
        x: state, shape (n, d) (unused except for its shape: ``fx`` is ``f(x, u)``).
        P: covariance, shape (n, d, d).
        fx: predicted state ``f(x, u)``, shape (n, d).
        F: state Jacobian, shape (n, d, d).
        Q: process noise, shape (n, d, d).

    Returns:
        ``(x-, P-)``.
    """
    P_pred = F @ P @ np.swapaxes(F, -1, -2) + Q
    return fx, 0.5 * (P_pred + np.swapaxes(P_pred, -1, -2))


def update(
    x: Array,
    P: Array,
    y: Array,
    H: Array,
    R: Array,
    active: NDArray[np.bool_] | None = None,
    present: NDArray[np.bool_] | None = None,
    gate_probability: float | None = None,
) -> tuple[Array, Array, UpdateInfo]:
    """EKF update (eq. 19-23, Joseph form).

    Args:
        x: prior state, shape (n, d).
        P: prior covariance, shape (n, d, d).
        y: innovation ``z - h(x)`` with angles already wrapped, shape (n, m).
        H: measurement Jacobian, shape (n, m, d).
        R: measurement noise, shape (m, m) or (n, m, m).
        active: components to use, shape (n, m) (default all). Inactive components are removed
            exactly: their H rows, innovations and R cross terms are zeroed.
        present: runs that have a measurement, shape (n,) (default all).
        gate_probability: if given, reject runs whose NIS exceeds the chi-square quantile of this
            probability for their number of active components.

    Returns:
        ``(x, P, info)`` with unchanged rows where nothing was applied.
    """
    n, m = y.shape
    act = np.ones((n, m), dtype=bool) if active is None else np.asarray(active, dtype=bool)
    pres = np.ones(n, dtype=bool) if present is None else np.asarray(present, dtype=bool)
    Rb = np.broadcast_to(R, (n, m, m)).copy()
    if np.any(np.diagonal(Rb, axis1=-2, axis2=-1) <= 0):
        raise NavInputError("measurement noise R must have positive variances")
    y = np.where(act & pres[:, None], y, 0.0)
    H = np.where(act[..., None], H, 0.0)
    pair = act[:, :, None] & act[:, None, :]
    Rb = np.where(pair | np.eye(m, dtype=bool), Rb, 0.0)
    Ht = np.swapaxes(H, -1, -2)
    PHt = P @ Ht
    S = H @ PHt + Rb  # eq. 20
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    Sinv_y = np.linalg.solve(S, y[..., None])[..., 0]
    nis = np.einsum("ni,ni->n", y, Sinv_y)
    dof = act.sum(axis=1)
    rejected = np.zeros(n, dtype=bool)
    if gate_probability is not None:
        limit = np.array([gate_limit(gate_probability, int(d)) for d in np.maximum(dof, 1)])
        rejected = pres & (dof > 0) & (nis > limit)
    applied = pres & (dof > 0) & ~rejected
    K = np.swapaxes(np.linalg.solve(S, np.swapaxes(PHt, -1, -2)), -1, -2)  # eq. 21
    x_new = x + np.einsum("nij,nj->ni", K, y)  # eq. 22
    I_KH = np.eye(P.shape[-1]) - K @ H
    P_new = I_KH @ P @ np.swapaxes(I_KH, -1, -2) + K @ Rb @ np.swapaxes(K, -1, -2)  # eq. 23
    P_new = 0.5 * (P_new + np.swapaxes(P_new, -1, -2))
    x_out = np.where(applied[:, None], x_new, x)
    P_out = np.where(applied[:, None, None], P_new, P)
    nis = np.where(pres, nis, np.nan)
    return x_out, P_out, UpdateInfo(nis, dof, applied, rejected)


class BatchEKF:
    """An EKF over n Monte Carlo runs at once.

    Args:
        x0: initial state, shape (n, d).
        P0: initial covariance, shape (n, d, d) or (d, d).
    """

    def __init__(self, x0: Array, P0: Array):
        self.x = np.array(x0, dtype=float)
        n, d = self.x.shape
        self.P = np.broadcast_to(np.asarray(P0, dtype=float), (n, d, d)).copy()

    def predict(self, model: MotionModel, u: Array, dt_s: float) -> None:
        """Propagate with a motion model and input ``u`` (shape (n, p)) over ``dt_s`` seconds."""
        self.x, self.P = predict(
            self.x, self.P, model.f(self.x, u, dt_s), model.F(self.x, u, dt_s), model.Q(u, dt_s)
        )

    def update(
        self,
        model: MeasurementModel,
        z: Array,
        present: NDArray[np.bool_] | None = None,
        gate_probability: float | None = None,
    ) -> UpdateInfo:
        """Correct with measurements ``z`` (shape (n, m)); rows with ``present`` False are skipped
        (their ``z`` may hold anything)."""
        hx = model.h(self.x)
        pres = np.ones(len(self.x), dtype=bool) if present is None else np.asarray(present)
        z_safe = np.where(pres[:, None], z, hx)
        y = model.residual(z_safe, hx)
        self.x, self.P, info = update(
            self.x,
            self.P,
            y,
            model.H(self.x),
            model.R(),
            model.active(self.x),
            pres,
            gate_probability,
        )
        return info

    def check(self, t_s: float) -> None:
        """Raise :class:`FilterDivergedError` if any run's state or covariance is not finite or
        its covariance has a negative variance."""
        bad = ~np.isfinite(self.x).all(axis=1) | ~np.isfinite(self.P).all(axis=(1, 2))
        bad |= (np.diagonal(self.P, axis1=-2, axis2=-1) < 0).any(axis=1)
        if bad.any():
            runs = np.flatnonzero(bad)[:5].tolist()
            raise FilterDivergedError(f"EKF diverged at t = {t_s:g} s in batch rows {runs}")
