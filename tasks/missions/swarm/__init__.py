"""``mission/swarm``: seed 003 on the physical BAUVs: followers keeping station on a leader from
one acoustic range every 5 s (Naus & Piskur 2022).

The package: :mod:`~tasks.missions.swarm.scenario` (the scenario and its sections),
:mod:`~tasks.missions.swarm.formation` (the leader's pattern, the followers' stations),
:mod:`~tasks.missions.swarm.leader` (the leader's broadcast),
:mod:`~tasks.missions.swarm.follower` (a follower's navigation: the adapter of its rig to
:class:`nav.navigator.BroadcastRangeNavigator`), :mod:`~tasks.missions.swarm.station` (station
keeping), :mod:`~tasks.missions.swarm.design` (the mission's design: the scene, the vehicles and
their parts),
:mod:`~tasks.missions.swarm.network` (the team's acoustic network: its section, the device on
every rig, what each vehicle heard), :mod:`~tasks.missions.swarm.options` (the cooperative
filters' settings), :mod:`~tasks.missions.swarm.coop` (a follower's decentralised navigation),
:mod:`~tasks.missions.swarm.relay` (ranges relayed back to their senders),
:mod:`~tasks.missions.swarm.team` (the team methods compared on a flight's measurements),
:mod:`~tasks.missions.swarm.run` (one run's flights and metrics) and
:mod:`~tasks.missions.swarm.report` (tables, ``metrics.json``) with
:mod:`~tasks.missions.swarm.figures` (figure, recording); this module registers the experiment.

One sea, one MuJoCo model, a leader and up to 12 followers namespaced ``leader``, ``f1``,
``f2`` ... (``followers.count``; the modem's five-second period holds six slots, more need a
longer ``followers.sensors.modem.period_s``):

* **The leader** flies a way-point pattern (a racetrack, :func:`racetrack`: 230 m north, a half
  circle of 50 m radius, 230 m south, about 10 minutes at 1 m/s) on the standard navigation
  part: the EKF with USBL fixes, the log and the compass, with the water current in its state.
  The paper gives its leader a DVL and a FOG and dead-reckons; this simulator has no DVL (the log
  measures speed *through water*), and DR on a log drifts with the current (0.2 m/s: 120 m in 10
  minutes), so the leader's good navigation is the USBL-aided EKF, which estimates the current,
  with a better USBL than the followers could carry (1 deg instead of the MicronNav's 3 deg in
  azimuth and elevation: the paper's leader has the expensive navigation). Each tick
  it states its position, its modem transducer's position, its velocity over ground (its speed
  through water along the measured heading, averaged over ``leader.velocity_window_s``, plus its
  current estimate) and its covariance (:class:`~bauv_sim.sensors.online.Broadcast`).
* **Each follower** has a compass and a log for navigation (seed 003's devices: uniform errors
  of +-2 deg and +-0.3 m/s at every tick, plus the calibrated systematic errors of Test 3 by
  default), an INS (attitude and rates for the autopilot only) and a pressure sensor (depth),
  and the acoustic modem (:mod:`bauv_sim.sensors.modem`): every 5 s in its own TDMA slot it
  receives the range to the leader and the leader's broadcast. Its navigation part
  (:class:`FollowerNavigation`) runs :class:`nav.relative.FollowerNavigator` with the method of
  ``navigation.method`` (``ga1``, ``ga2``, ``ekf``, or ``dr``, which ignores the messages).
  Beyond the paper, it dead-reckons over ground with the current the leader sends
  (``navigation.current = "leader"``, default; ``"none"`` is eq. 1 through water): without it the
  0.2 m/s cross current, which the paper's DR model lacks, drags every method's estimate along
  the track within minutes (measured; see :class:`FollowerNavigation`).
* **Station keeping** (:class:`StationGuidance`): the station is a point at
  ``followers.stations[i]`` (relative bearing clockwise from the leader's course, distance; for
  the followers beyond the list, rings of three stations, abeam to starboard, abeam to port and
  astern, at 10, 20, 30 ... m: :func:`generated_station`, whose first four are the defaults) from
  the leader's position dead-reckoned from its last message with its stated velocity. The
  follower asks for the leader's velocity plus a proportional-integral correction towards the
  station computed from its own estimate (the integral takes up the current the follower cannot
  measure); the along-track part sets the commanded speed (the autopilot's speed loop and the
  model's speed table), the cross-track part the course, which never turns back.

Two readings had to be chosen for the physics:

* the range is the slant range between the transducers (the model's ``modem`` sites); the
  follower turns it into the horizontal range with the depth difference (its own pressure depth,
  the leader's stated depth) and takes the circle around the leader's transducer less its own
  lever arm (rotated by its measured attitude), which is exact for the reference point;
* a range is valid when it is measured and reaches the follower ``travel + processing`` later
  (about 0.5 s); the follower applies it on arrival, about the leader's stated position moved on
  with the leader's stated velocity, so the error is the relative motion during the latency
  (the formation moves together: centimetres).

The followers fly the range EKF by default: it keeps them on station through the racetrack's
turn (seed 0: estimate error 1.4 m mean, 4.9 m largest, against 62 m for dead reckoning), and so
does GA2 (2.5 / 5.1 m), while GA1 as printed (``navigation.jacobian = "printed"``) takes the
wrong candidate on the circle after the turn and never recovers (106 m mean, 415 m largest:
worse than dead reckoning). ``--set navigation.method=ga2`` picks the method; ``--set
'navigation.methods=["ga1","ga2","ekf","dr"]'`` flies each run once per method on the same draws
(the same seed and run: the same start, sensor errors and current) and reports them side by
side. A follower without an accepted range for ``navigation.dr_warning_s`` (leader out of modem
range, messages lost, an outage: ``sensors.modem.outages_s``) is on dead reckoning: the report
says so. An aided estimate (the leader's EKF, a follower's GA1, GA2 or EKF) farther than
``navigation.divergence_m`` from the vehicle's true position has diverged: the report and
``metrics.json`` name it with the time (``divergences``, a ``Diverged runs`` column) and ``bauv
run`` exits with status 1.

**A team that navigates together** (issue 24; ``--set followers.network.enabled=true``): every
vehicle, the leader too, ranges to every other on the acoustic network
(:mod:`bauv_sim.acoustics.network`: one-way travel times in TDMA slots kept by each vehicle's
clock, ``followers.network.clocks``; the sender and the receiver at their own instants; packet
loss by the sonar equation, collisions) in place of the followers' modem; each packet carries
its sender's broadcast with its clock estimate. Only the leader has the USBL. The seed 003
methods use the leader's ranges alone (the clocks' offsets bias them); ``navigation.method =
decentralised`` flies each follower on :class:`nav.cooperative.CoopNavigator` (position and
clock, every range fused with the sender's broadcast by covariance intersection, the ranges it
sent relayed back by their receivers: :mod:`~tasks.missions.swarm.coop`). After each flight the
same measurements go to every team method (:mod:`~tasks.missions.swarm.team`: seed 003's GA2
and range EKF on the leader's ranges, the decentralised filters, the centralised EKF): the
report's team table and ``metrics.json``'s ``team`` give each vehicle's error and NEES per
method. ``sound`` sets the sea's sound-speed profile for every vehicle's acoustic devices.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from bauv_sim import seabed
from bauv_sim.errors import ConfigError
from tasks.closed_loop.experiment import BYTES_PER_TICK, MissionExperiment, check_gridded_current
from tasks.closed_loop.world import check_world
from tasks.core.registry import MemoryTerm, ReportContext, ReportSummary, register
from tasks.missions.swarm.design import SwarmMission
from tasks.missions.swarm.figures import record_swarm, swarm_figure
from tasks.missions.swarm.follower import EN, FOLLOWER_COLUMNS, FollowerNavigation
from tasks.missions.swarm.formation import (
    DEFAULT_STATIONS,
    MIN_STATION_SEPARATION_M,
    StationConfig,
    generated_station,
    racetrack,
    station_point_m,
)
from tasks.missions.swarm.leader import LeaderNavigation
from tasks.missions.swarm.report import FollowerRow, SwarmMetrics, report_swarm
from tasks.missions.swarm.run import (
    SwarmRunResult,
    divergences,
    flight_warnings,
    fly_run,
    follower_metrics,
    leader_course_true,
    leader_metrics,
)
from tasks.missions.swarm.scenario import (
    DEPTH_SIGMA_M,
    FOLLOWERS,
    LEADER,
    MAX_FOLLOWERS,
    METHODS,
    REFUSAL_CODES,
    REFUSALS,
    FollowerNavigationConfig,
    FollowersConfig,
    FollowerSensors,
    LeaderConfig,
    Method,
    StationGuidanceConfig,
    SwarmScenario,
    station_offsets,
)
from tasks.missions.swarm.station import StationGuidance

__all__ = [
    "DEFAULT_STATIONS",
    "DEPTH_SIGMA_M",
    "EN",
    "FOLLOWERS",
    "FOLLOWER_COLUMNS",
    "LEADER",
    "MAX_FOLLOWERS",
    "METHODS",
    "MIN_STATION_SEPARATION_M",
    "REFUSALS",
    "REFUSAL_CODES",
    "FollowerNavigation",
    "FollowerNavigationConfig",
    "FollowerRow",
    "FollowerSensors",
    "FollowersConfig",
    "LeaderConfig",
    "LeaderNavigation",
    "Method",
    "StationConfig",
    "StationGuidance",
    "StationGuidanceConfig",
    "SwarmExperiment",
    "SwarmMetrics",
    "SwarmMission",
    "SwarmRunResult",
    "SwarmScenario",
    "divergences",
    "flight_warnings",
    "fly_run",
    "follower_metrics",
    "generated_station",
    "leader_course_true",
    "leader_metrics",
    "racetrack",
    "record_swarm",
    "report_swarm",
    "station_offsets",
    "station_point_m",
    "swarm_figure",
]


TEAM_BYTES_PER_TICK = 192.0
"""A vehicle's team estimates per control tick on the acoustic network, bytes: the four
methods' positions (east, north) and 2 x 2 covariances in float64
(:func:`tasks.missions.swarm.team.add_track_columns`)."""


@dataclass(frozen=True)
class SwarmExperiment(MissionExperiment):
    """Seed 003 on the physical BAUVs (one flight per method per run)."""

    scenario_type = SwarmScenario
    metrics_type = SwarmMetrics

    def flight(self, scenario: SwarmScenario, seed: int, run: int):
        """The flight of a run with the first method."""
        return SwarmMission(scenario.methods()[0]), scenario

    def check(self, scenario: SwarmScenario, n_runs: int) -> None:
        check_world(self.flight(scenario, 0, 0)[0], scenario)  # several vehicles: full physics
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )
        if scenario.seabed.file is not None:  # read before anything is written
            seabed.generate(scenario.seabed, scenario.frame())
        # issue 25: a gridded current covers the leader's start, way-points and transceiver (the
        # followers keep station within the check's margin); without geo it is refused
        ld = scenario.leader
        wps = ld.guidance.waypoints
        check_gridded_current(
            scenario.current,
            scenario.frame(),
            scenario.timing.max_duration_s,
            [(ld.start.east_m, ld.start.north_m)]
            + [(w.east_m, w.north_m) for w in wps]
            + [(scenario.transceiver_east_m, scenario.transceiver_north_m)],
            [ld.start.depth_m] + [w.depth_m for w in wps],
        )

    def memory(self, scenario: SwarmScenario, n_runs: int) -> list[MemoryTerm]:
        """The mission's estimate (:meth:`MissionExperiment.memory`, one vehicle's per-tick
        columns) with the per-tick terms for every vehicle of every flight of a run: (1 +
        ``followers.count``) vehicles x the methods flown (measured: 2.4 kB per tick for a
        leader and 4 followers, 480 B per vehicle, against 500 B for one); on the acoustic
        network each vehicle also keeps the team methods' estimates and covariances
        (:data:`TEAM_BYTES_PER_TICK` more)."""
        k = (1 + scenario.followers.count) * len(scenario.methods())
        what = f" x {k} vehicles x methods (followers.count, navigation.methods)"
        if scenario.followers.network.enabled:
            k *= 1.0 + TEAM_BYTES_PER_TICK / BYTES_PER_TICK
            what += ", with the team estimates (followers.network.enabled)"
        terms = super().memory(scenario, n_runs)
        scaled = [
            dataclasses.replace(t, bytes=k * t.bytes, fields=t.fields + what) for t in terms[:2]
        ]
        return scaled + terms[2:]

    def run_block(self, scenario: SwarmScenario, seed: int, runs: tuple[int, ...]):
        return [fly_run(scenario, seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_swarm(self, ctx)


register(
    SwarmExperiment(
        name="mission/swarm",
        summary="seed 003 on the BAUVs: followers keep station abeam a leader from one acoustic "
        "range every 5 s (GA1/GA2/EKF/DR), 0.2 m/s cross current",
        preset={},
        default_runs=1,
    )
)
