"""Acoustic ranges between two vehicles as EKF measurement models (for :mod:`nav.ekf`).

**One-way travel time** (OWTT; Eustice, Singh & Whitcomb 2011, J. Field Robotics 28(1), eq. 1-3):
the sender j transmits at its scheduled local time ``T`` (its true time ``t_tx = T - b_j``), the
receiver i stamps the arrival with its clock, ``L = t_rx + b_i``, and the range is what the nominal
sound speed makes of the difference,

    ``z = c_nom (L - T) = c_nom (t_rx - t_tx) + c_nom (b_i(t_rx) - b_j(t_tx))``,

so with the straight ray at ``c_nom`` (the filter's assumption)

    ``h = sqrt(|p_i(t_rx) - p_j(t_tx)|^2 + dz^2) + c_nom (b_i(t_rx) - b_j(t_tx))``.

The state holds each vehicle at the filter's time ``t_k`` (at or after the reception): the
positions at the two instants are the state's moved back by the vehicle's velocity over its lag,
``p(t_k - lag) = p(t_k) - v lag`` (the vehicle moves while the sound travels), and a drifting
clock's offset likewise, ``b(t_k - lag) = b(t_k) - d lag``. The lags and velocities are inputs
(from the time stamps and the dead reckoning), not states. ``dz`` (receiver depth minus sender
depth) comes from the pressure sensors.

**Two-way travel time** (TWTT): the interrogator's own clock times both legs, the offsets cancel
(a drift leaves ``d * turnaround``, below a microsecond for 1 ppm and a second's turnaround), and
``h = sqrt(|p_i - p_j|^2 + dz^2)`` with the two positions moved to the exchange's mid-time.

A state is any stack of vehicle blocks ``[east_m, north_m, clock_offset_s(, clock_drift)]``: the
models address the receiver and the sender by the index of their ``east`` in the state (offset
at +2, drift at +3), so the same model serves the team's centralised state and a vehicle's joint
state with one peer's broadcast (:mod:`nav.cooperative.decentralised`). Arrays carry a leading
run axis n.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]

MIN_DISTANCE_M = 1e-9
"""Below this slant distance a range has no direction and is left out (inactive)."""


def _per_run(value: ArrayLike | None, n: int, tail: tuple[int, ...], name: str) -> Array:
    if value is None:
        return np.zeros((n, *tail))
    a = np.asarray(value, dtype=float)
    try:
        return np.broadcast_to(a, (n, *tail))
    except ValueError:
        raise NavInputError(f"{name} must broadcast to shape {(n, *tail)}, not {a.shape}") from None


@dataclass(frozen=True)
class _Geometry:
    """The slant geometry shared by the OWTT and TWTT models."""

    receiver_at: int
    sender_at: int
    sigma_m: float
    dz_m: ArrayLike = 0.0
    receiver_lag_s: ArrayLike = 0.0
    sender_lag_s: ArrayLike = 0.0
    receiver_velocity_m_s: ArrayLike | None = None
    sender_velocity_m_s: ArrayLike | None = None
    extra_var_m2: ArrayLike | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.sigma_m) and self.sigma_m > 0):
            raise NavInputError(f"sigma_m must be a finite number > 0, not {self.sigma_m!r}")
        if self.receiver_at == self.sender_at:
            raise NavInputError(
                f"receiver_at and sender_at must differ (a vehicle does not range to itself), "
                f"both are {self.receiver_at}"
            )

    def _slant(self, x: Array) -> tuple[Array, Array]:
        """``(d (n, 2), r (n,))``: horizontal difference receiver - sender at their instants and
        the slant distance."""
        n = x.shape[0]
        ra, sa = self.receiver_at, self.sender_at
        rl = _per_run(self.receiver_lag_s, n, (), "receiver_lag_s")
        sl = _per_run(self.sender_lag_s, n, (), "sender_lag_s")
        rv = _per_run(self.receiver_velocity_m_s, n, (2,), "receiver_velocity_m_s")
        sv = _per_run(self.sender_velocity_m_s, n, (2,), "sender_velocity_m_s")
        pr = x[:, ra : ra + 2] - rv * rl[:, None]
        ps = x[:, sa : sa + 2] - sv * sl[:, None]
        d = pr - ps
        dz = _per_run(self.dz_m, n, (), "dz_m")
        return d, np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2 + dz**2)

    def _geometry_jacobian(self, x: Array) -> Array:
        d, r = self._slant(x)
        H = np.zeros((x.shape[0], 1, x.shape[1]))
        u = d / np.where(r > MIN_DISTANCE_M, r, 1.0)[:, None]
        ra, sa = self.receiver_at, self.sender_at
        H[:, 0, ra : ra + 2] = u
        H[:, 0, sa : sa + 2] = -u
        return H

    def R(self) -> Array:
        """Noise ``sigma_m^2`` (+ ``extra_var_m2`` per run), shape (1, 1) or (n, 1, 1), m^2."""
        if self.extra_var_m2 is None:
            return np.array([[self.sigma_m**2]])
        extra = np.asarray(self.extra_var_m2, dtype=float)
        return (self.sigma_m**2 + extra)[:, None, None]

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``, shape (n, 1), m."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Whether the range has a direction (slant distance above :data:`MIN_DISTANCE_M`),
        shape (n, 1)."""
        return (self._slant(x)[1] > MIN_DISTANCE_M)[:, None]


@dataclass(frozen=True)
class OwttRangeMeasurement(_Geometry):
    """A one-way-travel-time range with both clocks (a :class:`nav.ekf.MeasurementModel`).

    ``h = sqrt(|(p_i - v_i lag_i) - (p_j - v_j lag_j)|^2 + dz^2)
    + c_nom ((b_i - d_i lag_i) - (b_j - d_j lag_j))`` (the module's equation; the drift terms
    only where the block holds a drift). Jacobian analytic: ``+-u`` on the positions (``u`` the
    horizontal unit difference scaled by ``|d| / r``), ``+-c_nom`` on the offsets,
    ``-+c_nom lag`` on the drifts. ``R = sigma_m^2``.

    Attributes:
        receiver_at: index of the receiver's east in the state (offset at +2, drift at +3).
        sender_at: index of the sender's east in the state.
        sigma_m: standard deviation of the range (detection and time-stamp noise), m.
        dz_m: receiver depth minus sender depth, scalar or shape (n,), m.
        receiver_lag_s: ``t_k - t_rx``, scalar or (n,), s.
        sender_lag_s: ``t_k - t_tx``, scalar or (n,), s (0 when the state holds the sender at
            its transmission, e.g. its broadcast).
        receiver_velocity_m_s: receiver's horizontal velocity, shape (n, 2) or None (zero), m/s.
        sender_velocity_m_s: sender's horizontal velocity, shape (n, 2) or None, m/s.
        extra_var_m2: variance added to the range's, shape (n,), m^2, or ``None``: the dead
            reckoning's noise over the lags (the positions moved back by the DR displacement
            are not the state's: the DR error since the instant is in the state but not in the
            range), an approximation of the delayed measurement without augmenting the state.
        sound_speed_m_s: the nominal sound speed ``c_nom`` that made the range, m/s.
        receiver_drift: whether the receiver's block holds a drift (at ``receiver_at + 3``).
        sender_drift: whether the sender's block holds a drift.
    """

    sound_speed_m_s: float = 1500.0
    receiver_drift: bool = False
    sender_drift: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        c = self.sound_speed_m_s
        if not (np.isfinite(c) and c > 0):
            raise NavInputError(f"sound_speed_m_s must be a finite number > 0, not {c!r}")

    def _clock(self, x: Array) -> Array:
        """``b_i(t_rx) - b_j(t_tx)``, shape (n,), s."""
        n = x.shape[0]
        ra, sa = self.receiver_at, self.sender_at
        out = x[:, ra + 2] - x[:, sa + 2]
        if self.receiver_drift:
            out = out - x[:, ra + 3] * _per_run(self.receiver_lag_s, n, (), "receiver_lag_s")
        if self.sender_drift:
            out = out + x[:, sa + 3] * _per_run(self.sender_lag_s, n, (), "sender_lag_s")
        return out

    def h(self, x: Array) -> Array:
        """Predicted ranges, shape (n, 1), m."""
        x = np.asarray(x, dtype=float)
        return (self._slant(x)[1] + self.sound_speed_m_s * self._clock(x))[:, None]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d)."""
        x = np.asarray(x, dtype=float)
        H = self._geometry_jacobian(x)
        n, c = x.shape[0], self.sound_speed_m_s
        ra, sa = self.receiver_at, self.sender_at
        H[:, 0, ra + 2] = c
        H[:, 0, sa + 2] = -c
        if self.receiver_drift:
            H[:, 0, ra + 3] = -c * _per_run(self.receiver_lag_s, n, (), "receiver_lag_s")
        if self.sender_drift:
            H[:, 0, sa + 3] = c * _per_run(self.sender_lag_s, n, (), "sender_lag_s")
        return H


@dataclass(frozen=True)
class TwttRangeMeasurement(_Geometry):
    """A two-way-travel-time range (a :class:`nav.ekf.MeasurementModel`): the offsets cancel.

    ``h = sqrt(|(p_i - v_i lag_i) - (p_j - v_j lag_j)|^2 + dz^2)``; Jacobian ``+-u`` on the two
    positions, zero on the clocks; ``R = sigma_m^2``. The lags move both vehicles to the
    exchange's mid-time.

    Attributes:
        receiver_at: index of the interrogator's east in the state.
        sender_at: index of the responder's east in the state.
        sigma_m: standard deviation of the range, m.
        dz_m: interrogator depth minus responder depth, m.
        receiver_lag_s, sender_lag_s: ``t_k`` minus the exchange's mid-time, s.
        receiver_velocity_m_s, sender_velocity_m_s: horizontal velocities, (n, 2), m/s.
        extra_var_m2: variance added to the range's, (n,), m^2, or ``None``.
    """

    def h(self, x: Array) -> Array:
        """Predicted ranges, shape (n, 1), m."""
        return self._slant(np.asarray(x, dtype=float))[1][:, None]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d)."""
        return self._geometry_jacobian(np.asarray(x, dtype=float))


@dataclass(frozen=True)
class PositionFix:
    """A horizontal position fix of one vehicle in a stacked state (a
    :class:`nav.ekf.MeasurementModel`): ``h = (east, north)`` of the block at ``at``, linear.

    Attributes:
        at: index of the vehicle's east in the state.
        cov_m2: the fix's covariance, shape (2, 2) or (n, 2, 2), m^2.
    """

    at: int
    cov_m2: ArrayLike

    def h(self, x: Array) -> Array:
        """Predicted fix, shape (n, 2), m."""
        return np.asarray(x, dtype=float)[:, self.at : self.at + 2]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 2, d)."""
        H = np.zeros((np.shape(x)[0], 2, np.shape(x)[1]))
        H[:, 0, self.at] = H[:, 1, self.at + 1] = 1.0
        return H

    def R(self) -> Array:
        """Noise, shape (2, 2) or (n, 2, 2), m^2."""
        return np.asarray(self.cov_m2, dtype=float)

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``, shape (n, 2), m."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Both components, shape (n, 2)."""
        return np.ones((np.shape(x)[0], 2), dtype=bool)
