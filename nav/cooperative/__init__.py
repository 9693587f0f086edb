"""Cooperative navigation of a team of vehicles with acoustic ranges and clocks (issue 24).

Seed 003 positions a follower from one range to the leader; at sea the ranges are travel times
between vehicles whose clocks drift, every vehicle can range to every other, and the team can
navigate together. One module per responsibility:

* :mod:`nav.cooperative.clock`: the clock model in a state (offset and drift, their random walks);
* :mod:`nav.cooperative.ranging`: one-way and two-way travel-time ranges as EKF measurement models;
* :mod:`nav.cooperative.record`: what a team measured over a batch of runs (:class:`TeamRecord`);
* :mod:`nav.cooperative.team`: the centralised EKF over the whole team (:class:`TeamEkf`);
* :mod:`nav.cooperative.decentralised`: one vehicle's filter fusing its peers' broadcasts by
  covariance intersection (:class:`CoopNavigator`);
* :mod:`nav.cooperative.tracks`: every method over a :class:`TeamRecord` (:func:`team_tracks`);
* :mod:`nav.cooperative.metrics`: per-vehicle error and consistency (:func:`team_metrics`).

Beyond the design: ``CoopOptions.relay`` (a broadcast carries the one-way ranges its sender
received, so the decentralised filters see both directions of a pair and separate the clocks).

Every Kalman update goes through :mod:`nav.ekf`. Arrays carry a leading run axis n; positions are
(east, north) in m, clock offsets in s (local minus the team's time, the leader's clock).
"""

from nav.cooperative.clock import ClockOptions, true_time_of_local
from nav.cooperative.decentralised import CoopNavigator, PeerEstimate, ci_weight
from nav.cooperative.metrics import VehicleMetrics, horizontal_errors, position_nees, team_metrics
from nav.cooperative.ranging import OwttRangeMeasurement, PositionFix, TwttRangeMeasurement
from nav.cooperative.record import TeamRecord
from nav.cooperative.team import LEADER_CLOCK, CoopOptions, TeamEkf
from nav.cooperative.tracks import METHODS, TeamTracks, team_tracks

__all__ = [
    "LEADER_CLOCK",
    "METHODS",
    "ClockOptions",
    "CoopNavigator",
    "CoopOptions",
    "OwttRangeMeasurement",
    "PeerEstimate",
    "PositionFix",
    "TeamEkf",
    "TeamRecord",
    "TeamTracks",
    "TwttRangeMeasurement",
    "VehicleMetrics",
    "ci_weight",
    "horizontal_errors",
    "position_nees",
    "team_metrics",
    "team_tracks",
    "true_time_of_local",
]
