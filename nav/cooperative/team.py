"""The centralised EKF over the whole team (the reference of cooperative navigation).

One state stacks every vehicle's block ``[east_m, north_m, clock_offset_s(, clock_drift)]``
(:mod:`nav.cooperative.clock`), batched over n Monte Carlo runs: ``x (n, v s)``, ``P (n, v s,
v s)``. It predicts with each vehicle's dead-reckoned step (``F = I`` on the positions, the clock
transition on the clocks; ``Q`` the DR step's covariance and the clocks' random walks) and
updates with every range of the team (:class:`nav.cooperative.OwttRangeMeasurement` or
:class:`~nav.cooperative.TwttRangeMeasurement`) and every position fix, each through
:mod:`nav.ekf` (seed 000 eq. 17-23, Joseph form). It keeps every cross-covariance between the
vehicles, so a range between two vehicles is never counted twice: the decentralised filters of
:mod:`nav.cooperative.decentralised` are measured against it. The leader (vehicle 0) has its
own clock options: a GPS-disciplined clock, the team's time reference (a small prior).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav import ekf
from nav.cooperative.clock import (
    ClockOptions,
    block_size,
    vehicle_prior,
    vehicle_transition,
)
from nav.cooperative.ranging import OwttRangeMeasurement, PositionFix, TwttRangeMeasurement
from nav.ekf import UpdateInfo
from nav.errors import NavInputError
from nav.relative.adjustment import GaOptions

Array = NDArray[np.float64]

Fusion = Literal["ci", "naive"]

LEADER_CLOCK = ClockOptions(
    offset_sigma_s=1e-6, drift_sigma=1e-9, offset_noise_s2_per_s=1e-16, drift_noise_per_s=1e-22
)
"""The leader's GPS-disciplined clock: a microsecond and 1e-3 ppm (a GPS-disciplined oscillator
holds its time to well under a microsecond while it has a fix)."""


@dataclass(frozen=True)
class CoopOptions:
    """Options of the cooperative filters (centralised and decentralised) and of the leader-only
    baselines of :func:`nav.cooperative.team_tracks`.

    Attributes:
        clock: the followers' clocks.
        leader_clock: the leader's clock (the team's time reference); its ``estimate_drift`` must
            equal ``clock``'s (one block size for the team).
        fusion: the decentralised fusion: ``"ci"`` (covariance intersection, default) or
            ``"naive"`` (the peer's estimate taken as independent: double counting).
        min_range_m: ranges below this are left out (no direction), m.
        gate_probability: chi-square gate of the range updates, or ``None``.
        ci_grid: grid of the CI weight before its golden-section refinement.
        ci_iterations: golden-section iterations of the CI weight.
        ci_criterion: what the CI weight minimises: ``"position"`` (the determinant of the
            receiver's posterior position covariance, default) or ``"state"`` (of its whole
            block, clocks included).
        relay: whether each vehicle's broadcast carries the one-way ranges it received since
            its last transmission with its estimate at each reception (decentralised OWTT): the
            original sender then fuses its own transmission too, and the pair's two directions
            separate the clocks from the distance. Without it a follower's clock is observable
            only through the changing geometry (measured on the synthetic team of the tests,
            600 s: offset error 0.8-0.9 ms against 0.03-0.05 ms with it).
        ga: seed 003's GA readings for the ``ga2`` baseline (its ``sigma_range_m`` is replaced
            by the record's).
    """

    clock: ClockOptions = field(default_factory=ClockOptions)
    leader_clock: ClockOptions = LEADER_CLOCK
    fusion: Fusion = "ci"
    min_range_m: float = 0.5
    gate_probability: float | None = None
    ci_grid: int = 16
    ci_iterations: int = 20
    ci_criterion: str = "position"
    relay: bool = True
    ga: GaOptions = field(default_factory=GaOptions)

    def __post_init__(self) -> None:
        if self.leader_clock.estimate_drift != self.clock.estimate_drift:
            raise NavInputError(
                "CoopOptions.leader_clock.estimate_drift must equal clock.estimate_drift (one "
                f"block size for the team), not {self.leader_clock.estimate_drift!r}"
            )
        if self.fusion not in ("ci", "naive"):
            raise NavInputError(f"CoopOptions.fusion must be 'ci' or 'naive', not {self.fusion!r}")
        if not (np.isfinite(self.min_range_m) and self.min_range_m > 0):
            raise NavInputError(
                f"CoopOptions.min_range_m must be a finite number > 0, not {self.min_range_m!r}"
            )
        if self.gate_probability is not None and not 0 < self.gate_probability < 1:
            raise NavInputError(
                f"CoopOptions.gate_probability must be in (0, 1) or None, not "
                f"{self.gate_probability!r}"
            )
        if self.ci_criterion not in ("position", "state"):
            raise NavInputError(
                f"CoopOptions.ci_criterion must be 'position' or 'state', not {self.ci_criterion!r}"
            )
        if self.ci_grid < 4 or self.ci_iterations < 1:
            raise NavInputError(
                f"CoopOptions.ci_grid must be >= 4 and ci_iterations >= 1, not "
                f"{self.ci_grid!r}, {self.ci_iterations!r}"
            )

    @property
    def estimate_drift(self) -> bool:
        """Whether every block holds a clock drift."""
        return self.clock.estimate_drift

    @property
    def block(self) -> int:
        """Size of a vehicle's block (3 or 4)."""
        return block_size(self.estimate_drift)

    def clock_of(self, vehicle: int) -> ClockOptions:
        """The clock options of a vehicle (0: the leader's)."""
        return self.leader_clock if vehicle == 0 else self.clock


class TeamEkf:
    """The centralised EKF of v vehicles over n runs.

    Args:
        start_m: initial positions, shape (n, v, 2), m.
        start_cov_m2: their covariances, shape (n, v, 2, 2), m^2.
        options: clocks and guards.

    Attributes:
        x: state, shape (n, v s), blocks ``[east, north, offset(, drift)]`` per vehicle.
        P: covariance, shape (n, v s, v s).
        options: the options.
    """

    def __init__(self, start_m: ArrayLike, start_cov_m2: ArrayLike, options: CoopOptions):
        start = np.asarray(start_m, dtype=float)
        cov = np.asarray(start_cov_m2, dtype=float)
        if start.ndim != 3 or start.shape[2] != 2 or cov.shape != (*start.shape, 2):
            raise NavInputError(
                f"start_m (n, v, 2) and start_cov_m2 (n, v, 2, 2) must match, not shapes "
                f"{start.shape} and {cov.shape}"
            )
        n, v, _ = start.shape
        s = options.block
        self.options = options
        self.n_vehicles = v
        self.x = np.zeros((n, v * s))
        self.P = np.zeros((n, v * s, v * s))
        for i in range(v):
            b = slice(i * s, (i + 1) * s)
            self.x[:, i * s : i * s + 2] = start[:, i]
            self.P[:, b, b] = vehicle_prior(cov[:, i], options.clock_of(i))

    def at(self, vehicle: int) -> int:
        """Index of a vehicle's east in the state."""
        if not 0 <= vehicle < self.n_vehicles:
            raise NavInputError(f"vehicle must be in 0..{self.n_vehicles - 1}, not {vehicle!r}")
        return vehicle * self.options.block

    def predict(self, step_m: ArrayLike, step_cov_m2: ArrayLike, dt_s: float) -> None:
        """Advance every vehicle by its dead-reckoned step (seed 000 eq. 17-18 through
        :func:`nav.ekf.predict`): ``p += step``, ``b += d dt``.

        Args:
            step_m: displacements over ground, shape (n, v, 2), m.
            step_cov_m2: their covariances, shape (n, v, 2, 2), m^2.
            dt_s: the step's duration, s (> 0).
        """
        if not dt_s > 0:
            raise NavInputError(f"dt_s must be > 0, not {dt_s!r}")
        step = np.asarray(step_m, dtype=float)
        qs = np.asarray(step_cov_m2, dtype=float)
        n, d = self.x.shape
        s, v = self.options.block, self.n_vehicles
        F = np.eye(d)
        Q = np.zeros((n, d, d))
        fx = self.x.copy()
        for i in range(v):
            Fi, Qi = vehicle_transition(self.options.clock_of(i), dt_s)
            b = slice(i * s, (i + 1) * s)
            F[b, b] = Fi
            Q[:, b, b] = Qi
            Q[:, i * s : i * s + 2, i * s : i * s + 2] = qs[:, i]
            fx[:, i * s : i * s + 2] += step[:, i]
            if self.options.estimate_drift:
                fx[:, i * s + 2] += self.x[:, i * s + 3] * dt_s
        self.x, self.P = ekf.predict(self.x, self.P, fx, F, Q)

    def update_position(
        self,
        vehicle: int,
        z_m: ArrayLike,
        cov_m2: ArrayLike,
        present: ArrayLike | None = None,
    ) -> UpdateInfo:
        """Correct with a horizontal position fix of one vehicle (:func:`nav.ekf.update_with`).

        Args:
            vehicle: the vehicle.
            z_m: the fixes, shape (n, 2), m.
            cov_m2: their covariances, shape (2, 2) or (n, 2, 2), m^2.
            present: runs with a fix, shape (n,).
        """
        model = PositionFix(self.at(vehicle), cov_m2)
        self.x, self.P, info = ekf.update_with(self.x, self.P, model, np.asarray(z_m), present)
        return info

    def update_range(
        self,
        receiver: int,
        sender: int,
        range_m: ArrayLike,
        *,
        kind: str = "owtt",
        sound_speed_m_s: float = 1500.0,
        sigma_m: float,
        dz_m: ArrayLike = 0.0,
        receiver_lag_s: ArrayLike = 0.0,
        sender_lag_s: ArrayLike = 0.0,
        receiver_velocity_m_s: ArrayLike | None = None,
        sender_velocity_m_s: ArrayLike | None = None,
        present: ArrayLike | None = None,
        extra_var_m2: ArrayLike | None = None,
    ) -> UpdateInfo:
        """Correct with one range between two vehicles of the team (:func:`nav.ekf.update_with`
        with :class:`OwttRangeMeasurement` or :class:`TwttRangeMeasurement`).

        Args:
            receiver: the vehicle that received (TWTT: the interrogator).
            sender: the vehicle that transmitted (TWTT: the responder).
            range_m: the ranges, shape (n,), m (anything where not present).
            kind: ``"owtt"`` or ``"twtt"``.
            sound_speed_m_s: the nominal sound speed of the ranges, m/s.
            sigma_m: the ranges' standard deviation, m.
            dz_m: receiver depth minus sender depth, scalar or (n,), m.
            receiver_lag_s, sender_lag_s: the state's time minus the reception / transmission
                (TWTT: minus the exchange's mid-time), scalar or (n,), s.
            receiver_velocity_m_s, sender_velocity_m_s: horizontal velocities, (n, 2), m/s.
            present: runs with the range, shape (n,). Ranges below ``min_range_m`` or not
                finite are left out.
            extra_var_m2: variance added to the range's (the DR noise over the lags), (n,), m^2.

        Returns:
            The update's diagnostics.
        """
        z = np.asarray(range_m, dtype=float).reshape(-1, 1)
        n = self.x.shape[0]
        pres = np.ones(n, dtype=bool) if present is None else np.asarray(present, dtype=bool)
        pres = pres & np.isfinite(z[:, 0]) & (np.nan_to_num(z[:, 0]) >= self.options.min_range_m)
        geometry = dict(
            receiver_at=self.at(receiver),
            sender_at=self.at(sender),
            sigma_m=sigma_m,
            dz_m=dz_m,
            receiver_lag_s=receiver_lag_s,
            sender_lag_s=sender_lag_s,
            receiver_velocity_m_s=receiver_velocity_m_s,
            sender_velocity_m_s=sender_velocity_m_s,
            extra_var_m2=extra_var_m2,
        )
        if kind == "owtt":
            drift = self.options.estimate_drift
            model = OwttRangeMeasurement(
                **geometry,
                sound_speed_m_s=sound_speed_m_s,
                receiver_drift=drift,
                sender_drift=drift,
            )
        elif kind == "twtt":
            model = TwttRangeMeasurement(**geometry)
        else:
            raise NavInputError(f"kind must be 'owtt' or 'twtt', not {kind!r}")
        self.x, self.P, info = ekf.update_with(
            self.x, self.P, model, z, pres, self.options.gate_probability
        )
        return info

    def position(self, vehicle: int) -> Array:
        """A vehicle's position estimate, shape (n, 2), m."""
        a = self.at(vehicle)
        return self.x[:, a : a + 2]

    def covariance(self, vehicle: int) -> Array:
        """Its covariance, shape (n, 2, 2), m^2."""
        a = self.at(vehicle)
        return self.P[:, a : a + 2, a : a + 2]

    def clock_offset(self, vehicle: int) -> Array:
        """A vehicle's clock offset estimate, shape (n,), s."""
        return self.x[:, self.at(vehicle) + 2]

    def clock_variance(self, vehicle: int) -> Array:
        """Its variance, shape (n,), s^2."""
        a = self.at(vehicle) + 2
        return self.P[:, a, a]
