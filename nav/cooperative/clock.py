"""A vehicle's clock in a navigation state: its offset (and drift) from the team's time.

A clock reads ``local(t) = t + b(t)``: the offset ``b`` (s, local minus true) changes as
``b(t + dt) = b(t) + d dt`` with the drift ``d`` (s/s), both driven by white noise (the two-state
clock model: Brown & Hwang, *Introduction to Random Signals and Applied Kalman Filtering*, 4th ed.,
section 9.3; the phase and frequency random walks of an oscillator). The leader's clock, disciplined
by GPS, is the team's time reference: its offset has a small prior (its own options).

In a state a vehicle's block is ``[east_m, north_m, clock_offset_s]`` or, with
``ClockOptions.estimate_drift``, ``[east_m, north_m, clock_offset_s, clock_drift]`` (drift in s/s).
Typical drifts: a TCXO ~1 ppm (1e-6 s/s), an OCXO ~1e-2 ppm, a chip-scale atomic clock ~1e-4 ppm
(Eustice, Singh & Whitcomb 2011, "Synchronous-clock one-way-travel-time acoustic navigation for
underwater vehicles", J. Field Robotics 28(1)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]

POSITION = slice(0, 2)
"""Where a vehicle's (east, north) sit in its block."""
OFFSET = 2
"""Where a vehicle's clock offset sits in its block."""
DRIFT = 3
"""Where a vehicle's clock drift sits in its block (when estimated)."""


@dataclass(frozen=True)
class ClockOptions:
    """How a filter models one vehicle's clock.

    Attributes:
        offset_sigma_s: standard deviation of the initial offset, s.
        drift_sigma: standard deviation of the initial drift, s/s (1e-6 = 1 ppm).
        offset_noise_s2_per_s: power spectral density of the offset's random walk, s^2/s.
        drift_noise_per_s: power spectral density of the drift's random walk, (s/s)^2/s.
        estimate_drift: whether the drift is a state (block of 4) or not (block of 3: the drift
            is then taken as zero and its effect must be covered by ``offset_noise_s2_per_s``).
    """

    offset_sigma_s: float = 1e-3
    drift_sigma: float = 1e-6
    offset_noise_s2_per_s: float = 1e-12
    drift_noise_per_s: float = 1e-18
    estimate_drift: bool = True

    def __post_init__(self) -> None:
        for name in ("offset_sigma_s", "drift_sigma", "offset_noise_s2_per_s", "drift_noise_per_s"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v >= 0):
                raise NavInputError(f"ClockOptions.{name} must be a finite number >= 0, not {v!r}")
        if not self.offset_sigma_s > 0:
            raise NavInputError(
                f"ClockOptions.offset_sigma_s must be > 0 (a clock is never known exactly), not "
                f"{self.offset_sigma_s!r}"
            )
        if self.estimate_drift and not self.drift_sigma > 0:
            raise NavInputError(
                f"ClockOptions.drift_sigma must be > 0 when the drift is estimated, not "
                f"{self.drift_sigma!r}"
            )

    @property
    def size(self) -> int:
        """Clock states: 1 (offset) or 2 (offset, drift)."""
        return 2 if self.estimate_drift else 1

    def initial_covariance(self) -> Array:
        """Prior covariance of the clock states, shape (c, c) (c = :attr:`size`), s^2 and
        (s/s)^2."""
        if self.estimate_drift:
            return np.diag([self.offset_sigma_s**2, self.drift_sigma**2])
        return np.array([[self.offset_sigma_s**2]])

    def transition(self, dt_s: float) -> Array:
        """State transition of the clock states over ``dt_s``: ``[[1, dt], [0, 1]]`` (offset
        grows by drift times dt) or ``[[1]]``, shape (c, c)."""
        if self.estimate_drift:
            return np.array([[1.0, dt_s], [0.0, 1.0]])
        return np.array([[1.0]])

    def process_noise(self, dt_s: float) -> Array:
        """Process noise of the clock states over ``dt_s`` (Brown & Hwang eq. 9.3.11): with drift
        ``[[q_b dt + q_d dt^3 / 3, q_d dt^2 / 2], [q_d dt^2 / 2, q_d dt]]``, else ``[[q_b dt]]``;
        ``q_b``, ``q_d`` the PSDs. Shape (c, c)."""
        qb, qd = self.offset_noise_s2_per_s, self.drift_noise_per_s
        if self.estimate_drift:
            return np.array(
                [
                    [qb * dt_s + qd * dt_s**3 / 3.0, qd * dt_s**2 / 2.0],
                    [qd * dt_s**2 / 2.0, qd * dt_s],
                ]
            )
        return np.array([[qb * dt_s]])


def block_size(estimate_drift: bool) -> int:
    """Size of one vehicle's block: 3 (east, north, offset) or 4 (with the drift)."""
    return 4 if estimate_drift else 3


def vehicle_prior(start_cov_m2: ArrayLike, clock: ClockOptions) -> Array:
    """Prior covariance of one vehicle's block: its start's position covariance and the clock's
    prior, uncorrelated.

    Args:
        start_cov_m2: position covariance, shape (n, 2, 2), m^2.
        clock: the clock's options.

    Returns:
        Shape (n, s, s), s = :func:`block_size`.
    """
    c = np.asarray(start_cov_m2, dtype=float)
    s = block_size(clock.estimate_drift)
    P = np.zeros((c.shape[0], s, s))
    P[:, :2, :2] = c
    P[:, 2:, 2:] = clock.initial_covariance()
    return P


def vehicle_transition(clock: ClockOptions, dt_s: float) -> tuple[Array, Array]:
    """Transition and clock process noise of one vehicle's block over ``dt_s`` (the position part
    of the transition is the identity: the DR step is added as an input; its covariance is the
    caller's).

    Returns:
        ``(F, Qc)``, shapes (s, s): ``F`` with the clock's transition, ``Qc`` zero but the clock's
        process noise.
    """
    s = block_size(clock.estimate_drift)
    F = np.eye(s)
    F[2:, 2:] = clock.transition(dt_s)
    Q = np.zeros((s, s))
    Q[2:, 2:] = clock.process_noise(dt_s)
    return F, Q


def true_time_of_local(local_s: ArrayLike, offset_s: ArrayLike) -> Array:
    """The true time of a local time stamp with the clock's offset: ``t = local - b`` (the offset
    at that instant; with a drifting clock use the offset at the stamp, the difference is
    ``d * b``, below a nanosecond for any real clock), s."""
    return np.asarray(local_s, dtype=float) - np.asarray(offset_s, dtype=float)
