"""The cooperative filters' settings in ``mission/swarm`` (issue 24), shared by the followers'
decentralised navigation (:mod:`tasks.missions.swarm.coop`) and the team comparison after each
flight (:mod:`tasks.missions.swarm.team`): the ``navigation.coop`` section, the current's
share of a dead-reckoned step's covariance, what the leader states of its clock, and the
scenario's :class:`nav.cooperative.CoopOptions` (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from bauv_sim.config import Config
from nav.cooperative import LEADER_CLOCK, ClockOptions, CoopOptions
from nav.relative import GaOptions

if TYPE_CHECKING:
    from tasks.missions.swarm.scenario import SwarmScenario

Array = NDArray[np.float64]


class CoopNavigationConfig(Config):
    """The decentralised filter's settings (:class:`nav.cooperative.CoopOptions`; the same for
    the team methods compared after each flight, :mod:`tasks.missions.swarm.team`)."""

    fusion: Literal["ci", "naive"] = Field(
        "ci",
        description="covariance intersection (Julier & Uhlmann 1997), or naive: the peer's "
        "estimate taken as independent (double counting, for comparison)",
    )
    clock_offset_sigma_s: float = Field(
        1e-3, gt=0, description="initial standard deviation of a follower's clock offset, s"
    )
    clock_drift_sigma_ppm: float = Field(
        1.0, ge=0, description="initial standard deviation of its drift, ppm (a TCXO: ~1)"
    )
    clock_offset_noise_s2_per_s: float = Field(
        1e-12, ge=0, description="PSD of the offset's random walk, s^2/s"
    )
    clock_drift_noise_per_s: float = Field(
        1e-18, ge=0, description="PSD of the drift's random walk, (s/s)^2/s"
    )
    estimate_drift: bool = Field(True, description="the clock drift is a state")
    ci_criterion: Literal["position", "state"] = Field(
        "position",
        description="what the CI weight minimises: the receiver's posterior position covariance "
        "(determinant) or its whole block's",
    )
    relay: bool = Field(
        True,
        description="the comparison's decentralised filters relay the ranges each vehicle "
        "received in its next broadcast (nav.cooperative.CoopOptions.relay); the vehicles' "
        "online filters cannot (a broadcast carries no ranges)",
    )
    current_sigma_m_s: float = Field(
        0.3,
        ge=0,
        description="uncertainty of the current each vehicle dead-reckons with (the leader's EKF "
        "estimate; none before its first message), per axis, m/s, white over each tick in the "
        "DR step's covariance (current_covariance)",
    )
    gate_probability: float | None = Field(
        None, gt=0, lt=1, description="chi-square gate of the range updates (none: every range)"
    )

    def options(self, min_range_m: float, ga: GaOptions) -> CoopOptions:
        """The filters' options: the followers' clocks as configured, the leader's the
        GPS-disciplined team reference (:data:`nav.cooperative.LEADER_CLOCK`)."""
        clock = ClockOptions(
            offset_sigma_s=self.clock_offset_sigma_s,
            drift_sigma=self.clock_drift_sigma_ppm * 1e-6,
            offset_noise_s2_per_s=self.clock_offset_noise_s2_per_s,
            drift_noise_per_s=self.clock_drift_noise_per_s,
            estimate_drift=self.estimate_drift,
        )
        leader = dataclasses.replace(LEADER_CLOCK, estimate_drift=self.estimate_drift)
        return CoopOptions(
            clock=clock,
            leader_clock=leader,
            fusion=self.fusion,
            min_range_m=min_range_m,
            gate_probability=self.gate_probability,
            ci_criterion=self.ci_criterion,
            relay=self.relay,
            ga=ga,
        )


def current_covariance(dt_s: ArrayLike, current_sigma_m_s: float) -> Array:
    """What the current adds to a dead-reckoned step's covariance: ``(sigma_c dt)^2 I`` per step.

    The cooperative filters hold no current: the vehicles dead-reckon over ground with the
    current the leader's EKF estimates (zero until its first message reaches them), whose error
    is slowly varying. Taken as white velocity noise over each tick it is a random walk of the
    position (``sigma_c sqrt(dt T)`` after T s, against ``sigma_b T`` for a constant error
    ``sigma_b``): the default 0.3 m/s covers a constant 0.06 m/s over the 5 s between two
    cycles of ranges and the USBL fixes (0.3 sqrt(0.2 x 5) = 0.3 m), not the 0.2 m/s of the
    first seconds before the leader's current arrives (measured: the NEES of the first 30 s is
    above the band).

    Args:
        dt_s: the steps' durations, s, scalar or shape (q,).
        current_sigma_m_s: sigma_c, m/s.

    Returns:
        Shape (2, 2) or (q, 2, 2), m^2.
    """
    d = np.asarray(dt_s, dtype=float)
    return (current_sigma_m_s * d)[..., None, None] ** 2 * np.eye(2)


def leader_clock_statement() -> tuple[float, float]:
    """What the leader states of its clock (the team's time reference, GPS-disciplined): offset
    0 with :data:`nav.cooperative.LEADER_CLOCK`'s variance, s and s^2."""
    return 0.0, LEADER_CLOCK.offset_sigma_s**2


def coop_options(scn: SwarmScenario) -> CoopOptions:
    """The cooperative filters' options of the scenario (online and in the comparison): its
    ``navigation.coop`` with the followers' range settings and GA readings."""
    c = scn.navigation
    ga = GaOptions(
        jacobian=c.jacobian,
        restart=c.restart,
        sigma_range_m=c.sigma_range_m,
        min_range_m=c.min_range_m,
    )
    return c.coop.options(c.min_range_m, ga)
