"""``mission/swarm``: seed 003 on the physical BAUVs: followers keeping station on a leader from
one acoustic range every 5 s (Naus & Piskur 2022).

One sea, one MuJoCo model, up to five vehicles namespaced ``leader``, ``f1`` .. ``f4``:

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
  ``followers.stations[i]`` (relative bearing clockwise from the leader's course, distance) from
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
"""

from __future__ import annotations

import collections
import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field, model_validator

from bauv_sim import rng as rng_mod
from bauv_sim.autopilot import AutopilotConfig
from bauv_sim.build import SceneConfig, VehicleSpec
from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.errors import ConfigError
from bauv_sim.frames import (
    R_from_roll_pitch_heading,
    unit_vector_scalar,
    wrap_2pi_scalar,
)
from bauv_sim.seabed import SeabedConfig
from bauv_sim.sensors import (
    AngleErrorConfig,
    CompassConfig,
    LengthErrorConfig,
    LogConfig,
    PressureConfig,
    SpeedErrorConfig,
    UsblConfig,
    check_multiple,
)
from bauv_sim.sensors.ins import InsConfig
from bauv_sim.sensors.modem import ModemConfig, check_slots
from bauv_sim.sensors.online import Broadcast, lever_arm_from_site
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.guidance import GuidanceCommand
from nav.metrics import first_exceedance
from nav.navigator import BroadcastRangeNavigator, FollowerOptions, FollowerReport
from nav.relative import GaOptions
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.navigation import EkfNavigation, FixRecord, NavOutput, report_of
from tasks.closed_loop.parts import MissionParts, VehicleParts
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.scenario import (
    FaultConfig,
    GuidanceConfig,
    MissionReportConfig,
    MissionSensors,
    NavigationConfig,
    StartConfig,
    TimingConfig,
    WaypointConfig,
)
from tasks.closed_loop.world import fly, place_vehicle, scenario_sea, standard_vehicle, streams
from tasks.core import store
from tasks.core.registry import ReportContext, ReportSummary, register

Array = NDArray[np.float64]
Method = Literal["ga1", "ga2", "ekf", "dr"]
METHODS: tuple[str, ...] = ("ga1", "ga2", "ekf", "dr")
FOLLOWERS = ("f1", "f2", "f3", "f4")
LEADER = "leader"
REFUSALS = ("ok", "dr", "no range", "range below minimum", "gate", "no fix", "no direction")
"""Codes of the modem fix table's ``refusal`` column (index = code); ``"degenerate"`` (a slant
range shorter than the depth difference) is the last one."""
REFUSAL_CODES = {r: i for i, r in enumerate((*REFUSALS, "degenerate"))}
DEPTH_SIGMA_M = 0.05
"""Standard deviation of a follower's stated depth (its pressure depth), m."""


def racetrack(
    length_m: float = 230.0,
    radius_m: float = 50.0,
    spacing_m: float = 40.0,
    step_deg: float = 20.0,
    depth_m: float = 3.0,
) -> list[dict[str, float]]:
    """The leader's default pattern from (0, 0): north ``length_m`` (a way-point every
    ``spacing_m``, so that the direct course to the next one keeps the leader near the line in
    the cross current), a clockwise half circle of ``radius_m`` (a way-point every ``step_deg``:
    the turn is wide enough for a follower 10-20 m inside it), then south ``length_m``; about
    620 m, 10 minutes at 1 m/s."""
    legs = np.arange(spacing_m, length_m + 1e-9, spacing_m)
    if legs[-1] < length_m - 1e-9:
        legs = np.append(legs, length_m)
    wps = [(0.0, float(n)) for n in legs]
    for b in np.arange(270.0 + step_deg, 450.0 + 1e-9, step_deg):
        e, n = unit_vector_scalar(math.radians(b % 360))
        wps.append((radius_m + radius_m * e, length_m + radius_m * n))
    wps += [(2 * radius_m, float(n)) for n in legs[::-1][1:]] + [(2 * radius_m, 0.0)]
    return [
        {"east_m": e, "north_m": n, "depth_m": depth_m, "acceptance_radius_m": 5.0} for e, n in wps
    ]


# ---------------------------------------------------------------------------------------------
# Scenario


class StationConfig(Config):
    """A follower's station relative to the leader."""

    relative_bearing_deg: float = Field(
        90.0,
        ge=0,
        lt=360,
        description="bearing of the station from the leader, clockwise from the leader's course "
        "(90: abeam to starboard, 270: to port, 180: astern), deg",
    )
    distance_m: float = Field(10.0, gt=2.5, le=200, description="distance from the leader, m")


DEFAULT_STATIONS = (
    StationConfig(relative_bearing_deg=90.0, distance_m=10.0),
    StationConfig(relative_bearing_deg=270.0, distance_m=10.0),
    StationConfig(relative_bearing_deg=180.0, distance_m=10.0),
    StationConfig(relative_bearing_deg=90.0, distance_m=20.0),
)
"""Four stations: abeam to starboard and to port at 10 m, astern at 10 m, starboard at 20 m."""


class FollowerSensors(Config):
    """A follower's devices (navigation: compass and log; the INS and the pressure sensor serve
    the autopilot and the depth)."""

    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2,
            heading=AngleErrorConfig(
                distribution="uniform",
                uniform_k=1.0,
                sigma_deg=2.0,
                sector_bias_deg=(0.4, 0.8, 0.0, 0.2),
            ),
        ),
        description="VN-100 (seed 003): uniform +-2 deg, Test 3's course-sector bias",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=0.2,
            speed=SpeedErrorConfig(
                distribution="uniform", uniform_k=1.0, sigma_m_s=0.3, bias_m_s=0.005
            ),
            min_speed_m_s=0.15,
        ),
        description="ALIZE log (seed 003): uniform +-0.3 m/s, Test 3's 0.005 m/s bias",
    )
    pressure: PressureConfig = Field(
        default_factory=lambda: PressureConfig(
            period_s=1.0, output="depth", depth=LengthErrorConfig(sigma_m=0.05)
        ),
        description="pressure depth at 1 Hz, 5 cm noise",
    )
    ins: InsConfig = Field(default_factory=InsConfig, description="attitude for the autopilot")
    modem: ModemConfig = Field(
        default_factory=ModemConfig,
        description="HS modem (seed 003): range every 5 s, uniform +-0.1 m, bias 0.025 m",
    )


class FollowersConfig(Config):
    """The followers."""

    count: int = Field(1, ge=1, le=4, description="number of followers (f1 .. f4)")
    stations: tuple[StationConfig, ...] = Field(
        DEFAULT_STATIONS, min_length=1, max_length=4, description="station of f1, f2, ..."
    )
    position_sigma_m: float = Field(
        0.5, ge=0, description="scatter of the true start about the station, per axis, m"
    )
    heading_sigma_deg: float = Field(2.0, ge=0, description="scatter of the start heading, deg")
    sensors: FollowerSensors = Field(default_factory=FollowerSensors)
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)

    @model_validator(mode="after")
    def _count(self) -> FollowersConfig:
        if self.count > len(self.stations):
            raise ValueError(f"count = {self.count}: only {len(self.stations)} stations are given")
        return self


def _leader_sensors() -> MissionSensors:
    usbl = UsblConfig(
        period_s=5.0,
        processing_delay_s=1.0,
        azimuth=AngleErrorConfig(sigma_deg=1.0),
        elevation=AngleErrorConfig(sigma_deg=1.0),
    )
    return MissionSensors(usbl=usbl)


class LeaderConfig(Config):
    """The leader: the standard vehicle's sections (its EKF with USBL)."""

    start: StartConfig = Field(
        default_factory=lambda: StartConfig(position_sigma_m=1.0, heading_sigma_deg=2.0)
    )
    sensors: MissionSensors = Field(
        default_factory=_leader_sensors,
        description="the standard vehicle's, with a 1 deg USBL (0.2 m range, 500 m)",
    )
    navigation: NavigationConfig = Field(
        default_factory=lambda: NavigationConfig(
            initial_sigma_m=1.0, sigma_azimuth_deg=1.0, sigma_elevation_deg=1.0
        )
    )
    guidance: GuidanceConfig = Field(
        default_factory=lambda: GuidanceConfig(
            waypoints=tuple(WaypointConfig(**w) for w in racetrack()), max_leg_time_s=400.0
        )
    )
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)
    velocity_window_s: float = Field(
        2.0, gt=0, description="the broadcast velocity is averaged over this, s"
    )


class FollowerNavigationConfig(Config):
    """The followers' navigation (seed 003's method and its settings)."""

    method: Method = Field(
        "ekf",
        description="ga1, ga2 (eq. 3, 4), the range EKF, or dr (default: the range EKF, the "
        "method that keeps the follower on station in the physics; GA1 as printed loses it "
        "after the leader's turn, models/bauv/README.md and the module docstring)",
    )
    methods: tuple[Method, ...] = Field(
        (),
        description="fly each run once per method on the same draws (comparison); "
        "empty: only `method`",
    )
    sigma_course_deg: float = Field(2.0, gt=0, description="sigma_C of eq. 5, deg")
    sigma_speed_m_s: float = Field(0.3, gt=0, description="sigma_S of eq. 5, m/s")
    ekf_sigma_course_deg: float | None = Field(
        None,
        gt=0,
        description="the range EKF's sigma_C in Q (eq. 5); none: sigma_course_deg (a larger "
        "value covers cross-track drift the model lacks, such as an unknown current)",
    )
    jacobian: Literal["printed", "true"] = Field(
        "printed", description="GA1's A rows as printed or the true Jacobian (nav.relative)"
    )
    restart: bool = Field(True, description="DR restarts from each GA position")
    sigma_range_m: float = Field(0.1, gt=0, description="delta_Dh of P and the EKF's range sigma")
    min_range_m: float = Field(0.5, gt=0, description="ranges below this are refused, m")
    gate_probability: float | None = Field(
        None, gt=0, lt=1, description="the EKF's chi-square gate (none: every range)"
    )
    use_leader_covariance: bool = Field(
        True, description="the EKF adds the leader's stated covariance to the range variance"
    )
    initial_sigma_m: float = Field(1.0, gt=0, description="start position sigma per axis, m")
    current: Literal["leader", "none"] = Field(
        "leader",
        description="beyond the paper: dead-reckon over ground with the current the leader "
        "sends (its EKF's estimate; the same water), or through water as eq. 1 (none)",
    )
    dr_warning_s: float = Field(
        60.0, gt=0, description="warn when a follower goes this long without an accepted range, s"
    )
    hdop_warning: float = Field(
        3.0, gt=0, description="warn when the mean HDOP at a follower's fixes exceeds this"
    )
    divergence_m: float = Field(
        25.0,
        gt=0,
        description="an aided estimate (the leader's EKF; a follower's GA1, GA2 or EKF) farther "
        "than this from the vehicle's true position has diverged: the report names it and "
        "`bauv run` exits with status 1 (dead reckoning is reported by its error), m",
    )


class StationGuidanceConfig(Config):
    """Station keeping (proportional-integral on the follower's estimate of the station)."""

    gain_per_s: float = Field(0.08, ge=0, description="velocity asked per metre of error, 1/s")
    integral_gain_per_s2: float = Field(
        0.003, ge=0, description="velocity added per metre-second of error, 1/s^2"
    )
    max_correction_m_s: float = Field(0.5, gt=0, description="limit of the proportional part")
    max_integral_m_s: float = Field(0.4, ge=0, description="limit of the integral part, m/s")
    min_speed_m_s: float = Field(0.4, gt=0, description="commanded speed limits, m/s")
    max_speed_m_s: float = Field(1.6, gt=0, le=2)
    max_crossing_deg: float = Field(
        60.0, gt=0, lt=90, description="largest angle between the course and the leader's, deg"
    )
    depth_m: float = Field(3.0, ge=0, description="the followers' depth, m")


class SwarmScenario(Config):
    """Scenario of ``mission/swarm``."""

    seabed: SeabedConfig = Field(default_factory=SeabedConfig)
    transceiver_east_m: float = Field(50.0, description="the leader's USBL transceiver, m")
    transceiver_north_m: float = 120.0
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.2, direction_deg=90.0),
        description="0.2 m/s towards east: across the racetrack's legs",
    )
    leader: LeaderConfig = Field(default_factory=LeaderConfig)
    followers: FollowersConfig = Field(default_factory=FollowersConfig)
    navigation: FollowerNavigationConfig = Field(default_factory=FollowerNavigationConfig)
    station: StationGuidanceConfig = Field(default_factory=StationGuidanceConfig)
    timing: TimingConfig = Field(
        default_factory=lambda: TimingConfig(max_duration_s=600.0, physics_timestep_s=0.002),
        description="the physics at 2 ms, not the missions' 4 ms preset: at 4 ms the follower's "
        "track departs from the 1 ms one about 5 times faster than at 2 ms and GA1's largest "
        "error grows 1.5-9x in 4 of 5 seeds (models/bauv/README.md, Timestep presets)",
    )
    faults: FaultConfig = Field(default_factory=FaultConfig)
    report: MissionReportConfig = Field(default_factory=MissionReportConfig)

    @model_validator(mode="after")
    def _check(self) -> SwarmScenario:
        tick = self.timing.control_tick_s
        ls, fs = self.leader.sensors, self.followers.sensors
        for where, s, names in (
            (
                "leader.sensors",
                ls,
                ("compass", "ins", "log", "pressure", "usbl", "gps", "odometry"),
            ),
            ("followers.sensors", fs, ("compass", "ins", "log", "pressure")),
        ):
            for name in names:
                check_multiple(getattr(s, name).period_s, tick, f"{where}.{name}.period_s")
            for name in ("compass", "ins"):
                period = getattr(s, name).period_s
                if abs(period - tick) > 1e-9:
                    raise ValueError(
                        f"{where}.{name}.period_s = {period:g}: the autopilot reads it every "
                        f"control tick ({tick:g} s)"
                    )
        check_slots(fs.modem, tick, self.followers.count, "followers.sensors.modem")
        st = self.station
        if st.min_speed_m_s >= st.max_speed_m_s:
            raise ValueError(
                f"station.min_speed_m_s = {st.min_speed_m_s:g}: must be below "
                f"station.max_speed_m_s = {st.max_speed_m_s:g}"
            )
        return self

    def methods(self) -> tuple[str, ...]:
        """The methods each run is flown with."""
        return tuple(dict.fromkeys(self.navigation.methods)) or (self.navigation.method,)


# ---------------------------------------------------------------------------------------------
# The leader's part: the standard EKF and what it broadcasts


class LeaderNavigation:
    """The standard navigation part, and the leader's broadcast at every tick.

    Args:
        ekf: the standard navigation part.
        transducer_body_m: the leader's modem transducer, body FLU, m.
        window_ticks: the broadcast velocity is averaged over this many ticks.
    """

    def __init__(self, ekf: EkfNavigation, transducer_body_m: Array, window_ticks: int):
        self.ekf = ekf
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self._v: collections.deque[tuple[float, float]] = collections.deque(maxlen=window_ticks)

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        out = self.ekf.step(tick, initial)
        e, n = unit_vector_scalar(out.heading_rad)
        self._v.append((out.speed_m_s * e, out.speed_m_s * n))
        v = np.mean(self._v, axis=0)
        if out.current_m_s is not None:
            v = v + out.current_m_s
        roll, pitch = out.ins[0], out.ins[1]
        x = out.estimate.x
        R = R_from_roll_pitch_heading(roll, pitch, out.heading_rad)
        cur = None if out.current_m_s is None else np.asarray(out.current_m_s, dtype=float).copy()
        P = out.estimate.P[:2, :2].copy()
        b = Broadcast(LEADER, out.t_s, x.copy(), x + R @ self.arm, v, P, cur)
        return dataclasses.replace(out, broadcast=b)

    def outcome(self) -> dict[str, Any]:
        return self.ekf.outcome()


# ---------------------------------------------------------------------------------------------
# A follower's parts


class FollowerNavigation:
    """A follower's navigation part: the rig's compass, log, pressure and modem records fed to
    :class:`nav.navigator.BroadcastRangeNavigator` (seed 003's methods on ranges to the leader's
    broadcast position; see the module docstring).

    Args:
        cfg: the followers' navigation settings.
        method: ``ga1``, ``ga2``, ``ekf`` or ``dr``.
        x0: the initial estimate, shape (3,), m, world (up = -depth).
        transducer_body_m: this follower's modem transducer, body FLU, m.
        plan: the leader's planned start (position, velocity) as a broadcast at t = 0, used
            until the first message.
        period_s: the modem period (the HDOP of the current geometry takes the estimate one
            period ago as the start of the DR segment), s.
        tick_s: control tick, s.

    The output's ``report`` is a :class:`nav.navigator.FollowerReport` (the leader's latest
    message and its position now, its course, the HDOP, the time since the last accepted range,
    whether one was accepted at this tick, the current dead-reckoned with).

    Beyond the paper (``cfg.current = "leader"``): the follower cannot measure the current, and
    the paper's DR (eq. 1) has none. An unmodelled cross current (0.2 m/s: 1 m between two
    ranges) reads, through the anisotropic DR covariance of eq. 5 (sigma_S along the track,
    S sigma_C across), as an along-track error that a range abeam cannot observe, and the fixes
    drag the estimate along the track (measured: the estimates run away within minutes). The
    leader's EKF estimates the current in the same water and sends it with each range; the
    follower dead-reckons over ground with it (course and speed of its through-water velocity
    plus that current). Learning the current from the follower's own corrections was tried and
    fails the same way: in a turn the along-track position error becomes observable and is read
    as current. The ``dr`` method uses no message at all (the paper's DR); the output's
    ``dr_position_m`` is always the pure compass + log track.
    """

    def __init__(
        self,
        cfg: FollowerNavigationConfig,
        method: str,
        x0: Array,
        transducer_body_m: Array,
        plan: Broadcast,
        period_s: float,
        tick_s: float,
    ):
        self.cfg = cfg
        self.method = method
        sigma_c = cfg.sigma_course_deg
        if method == "ekf" and cfg.ekf_sigma_course_deg is not None:
            sigma_c = cfg.ekf_sigma_course_deg
        options = FollowerOptions(
            method=method,  # type: ignore[arg-type]
            sigma_course_rad=math.radians(sigma_c),
            sigma_speed_m_s=cfg.sigma_speed_m_s,
            ga=GaOptions(
                jacobian=cfg.jacobian,
                restart=cfg.restart,
                sigma_range_m=cfg.sigma_range_m,
                min_range_m=cfg.min_range_m,
            ),
            initial_sigma_m=cfg.initial_sigma_m,
            gate_probability=cfg.gate_probability,
            use_leader_covariance=cfg.use_leader_covariance,
            use_leader_current=cfg.current == "leader",
            dr_warning_s=cfg.dr_warning_s,
            depth_sigma_m=DEPTH_SIGMA_M,
        )
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self.nav = BroadcastRangeNavigator(options, x0, plan, max(1, round(period_s / tick_s)))

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        t = tick.t_s
        heading = tick.value("compass")
        log_speed = tick.value("log")
        nav = self.nav
        nav.advance(t, heading, log_speed, tick.value("pressure"), initial)
        fixes, accepted_now = [], False
        for m in tick.arrived:
            if m.device == "modem":
                rec = self._range(t, m)
                fixes.append(rec)
                accepted_now |= rec.accepted
        est, report = nav.end_tick(t, accepted_now)
        return NavOutput(
            t_s=t,
            estimate=est,
            dr_position_m=nav.dr_position,
            current_m_s=None,
            heading_rad=heading,
            speed_m_s=nav.speed,
            speed_from_log=log_speed is not None,
            odometry_speed_m_s=nav.speed,
            depth_m=nav.depth,
            ins=tick.held["ins"],
            fixes=tuple(fixes),
            gps_fix=False,
            report=report,
        )

    def _range(self, t: float, m) -> FixRecord:
        """Apply one modem message (see the module docstring for the geometry)."""
        roll, pitch, heading = m.attitude_rad
        arm = R_from_roll_pitch_heading(roll, pitch, heading) @ self.arm
        res = self.nav.range_fix(t, m.t_valid_s, float(m.value[0]), m.payload, arm)
        h, crit, centre = res.hdop, res.criterion, res.centre_m
        z = np.array(
            [
                res.range_m,
                res.horizontal_m,
                centre[0],
                centre[1],
                min(h, 100.0) if math.isfinite(h) else 100.0,
                crit if math.isfinite(crit) else 0.0,
                float(REFUSAL_CODES.get(res.reason, len(REFUSALS))),
            ]
        )
        return FixRecord("modem", m.t_valid_s, t, z, res.accepted, res.position_m)

    def outcome(self) -> dict[str, Any]:
        """Fix counts by outcome, the mean HDOP of accepted fixes, and the intervals without an
        accepted range longer than ``dr_warning_s`` (the last one still open at the end)."""
        nav = self.nav
        return {
            "method": self.method,
            "fix_counts": dict(nav.counts),
            "mean_fix_hdop": nav.mean_fix_hdop,
            "dr_gaps_s": [list(g) for g in nav.dr_gaps_s()],
        }


@dataclass
class StationGuidance:
    """Station keeping on the follower's estimate (module docstring).

    Args:
        cfg: the gains and limits.
        station: the station relative to the leader.
        tick_s: control tick, s.
        leader_done: whether the leader's pattern is over (the mission ends with it).
    """

    cfg: StationGuidanceConfig
    station: StationConfig
    tick_s: float
    leader_done: Callable[[], bool]

    def __post_init__(self) -> None:
        self._integral = np.zeros(2)
        self.bearing = math.radians(self.station.relative_bearing_deg)

    @property
    def done(self) -> bool:
        return self.leader_done()

    def station_point(self, leader_xy: Array, leader_course: float) -> Array:
        """The station for a leader position (2,) m and course (rad), shape (2,), m."""
        return leader_xy + self.station.distance_m * np.array(
            unit_vector_scalar(leader_course + self.bearing)
        )

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        c = self.cfg
        rep = report_of(nav, FollowerReport)
        course_l = rep.leader_course
        speed_l = float(np.hypot(*rep.leader.velocity_world_m_s))
        s = self.station_point(rep.leader_est, course_l)
        e = s - nav.estimate.x[:2]
        corr = c.gain_per_s * e
        norm = float(np.hypot(*corr))
        if norm > c.max_correction_m_s:
            corr *= c.max_correction_m_s / norm
        self._integral += c.integral_gain_per_s2 * e * self.tick_s
        norm = float(np.hypot(*self._integral))
        if norm > c.max_integral_m_s:
            self._integral *= c.max_integral_m_s / norm
        u = np.array(unit_vector_scalar(course_l))
        n = np.array([u[1], -u[0]])  # to starboard of the leader's course
        w = corr + self._integral
        along = max(speed_l + float(w @ u), c.min_speed_m_s)
        cross = float(w @ n)
        lim = math.tan(math.radians(c.max_crossing_deg))
        cross = max(-lim * along, min(lim * along, cross))
        course = wrap_2pi_scalar(course_l + math.atan2(cross, along))
        speed = min(max(math.hypot(along, cross), c.min_speed_m_s), c.max_speed_m_s)
        mode = "done" if self.done else "transit"
        return GuidanceCommand(course, c.depth_m, speed, mode, 0)

    def waypoints(self) -> list[tuple[float, float, float]]:
        return []

    def legs(self) -> list[dict[str, Any]]:
        return []

    def outcome(self) -> dict[str, Any]:
        return {
            "relative_bearing_deg": self.station.relative_bearing_deg,
            "distance_m": self.station.distance_m,
        }


EN = ("east", "north")
FOLLOWER_COLUMNS = {
    "hdop": (
        "hdop",
        "1",
        "HDOP of the current geometry (seed 003 eq. 7-8; capped at 100)",
        (),
        False,
    ),
    "since_fix": ("since_fix", "s", "time since the last accepted range", (), False),
    "fix_event": ("fix_event", "bool", "a range was accepted at this tick", (), False),
    "leader_est": (
        "leader_est",
        "m",
        "the leader's position as the follower knows it now (last message, dead-reckoned)",
        EN,
        False,
    ),
    "leader_course": ("leader_course", "rad", "the leader's stated course", (), False),
    "current_est": ("current", "m/s", "the follower's current estimate (zero: none)", EN, False),
}
"""The per-tick columns a follower adds (see :class:`~tasks.closed_loop.parts.VehicleParts`)."""


def station_offsets(scn: SwarmScenario) -> list[StationConfig]:
    """The stations of the scenario's followers, in order."""
    return list(scn.followers.stations[: scn.followers.count])


@dataclass(frozen=True)
class SwarmMission:
    """The design of one flight: the leader and its followers, each follower navigating with
    ``method``.

    Attributes:
        method: the followers' method (``ga1``, ``ga2``, ``ekf``, ``dr``).
    """

    method: str = "ga1"

    def vehicle_names(self, scn: SwarmScenario) -> tuple[str, ...]:
        return (LEADER, *FOLLOWERS[: scn.followers.count])

    def _nominal(self, scn: SwarmScenario) -> list[tuple[str, float, float]]:
        st = scn.leader.start
        h = math.radians(st.heading_deg)
        out = [(LEADER, st.east_m, st.north_m)]
        for name, s in zip(FOLLOWERS, station_offsets(scn), strict=False):
            e, n = unit_vector_scalar(h + math.radians(s.relative_bearing_deg))
            out.append((name, st.east_m + s.distance_m * e, st.north_m + s.distance_m * n))
        return out

    def scene(self, scn: SwarmScenario) -> SceneConfig:
        st = scn.leader.start
        vehicles = tuple(
            VehicleSpec(
                name=name,
                east_m=e,
                north_m=n,
                depth_m=st.depth_m if name == LEADER else scn.station.depth_m,
                heading_deg=st.heading_deg,
            )
            for name, e, n in self._nominal(scn)
        )
        return SceneConfig(
            vehicles=vehicles,
            seabed=scn.seabed,
            transceiver_east_m=scn.transceiver_east_m,
            transceiver_north_m=scn.transceiver_north_m,
        )

    def build(self, scn: SwarmScenario, seed: int, run: int, physics) -> MissionParts:
        table = load_speed_table()
        tick = scn.timing.control_tick_s
        lead = standard_vehicle(scn.leader, seed, run, physics, LEADER, LEADER, speed_table=table)
        modem = scn.followers.sensors.modem
        arm_l = (
            np.asarray(modem.transducer_body_m, dtype=float)
            if any(modem.transducer_body_m)
            else np.asarray(lever_arm_from_site(physics, "modem", LEADER), dtype=float)
        )
        lead.navigation = LeaderNavigation(
            lead.navigation, arm_l, max(1, round(scn.leader.velocity_window_s / tick))
        )
        leader_guidance = lead.guidance
        st = scn.leader.start
        h = math.radians(st.heading_deg)
        v_plan = scn.leader.guidance.speed_m_s * np.array(unit_vector_scalar(h))
        p_plan = np.array([st.east_m, st.north_m, -st.depth_m])
        plan = Broadcast(f"{LEADER} (plan)", 0.0, p_plan, p_plan, v_plan, None)
        vehicles: list[VehicleParts] = [lead]
        fc = scn.followers
        names = self.vehicle_names(scn)[1:]
        for i, (name, (_, e, n)) in enumerate(zip(names, self._nominal(scn)[1:], strict=True)):
            start = StartConfig(
                east_m=e,
                north_m=n,
                depth_m=scn.station.depth_m,
                heading_deg=st.heading_deg,
                speed_m_s=st.speed_m_s,
                position_sigma_m=fc.position_sigma_m,
                heading_sigma_deg=fc.heading_sigma_deg,
            )
            pos = place_vehicle(physics, start, seed, run, name, name)
            s = fc.sensors
            rig = SensorRig(
                {
                    "compass": s.compass,
                    "ins": s.ins,
                    "log": s.log,
                    "pressure": s.pressure,
                    "modem": s.modem,
                },
                physics,
                name,
                seed,
                run,
                name,
                extra={"modem": {"sender": LEADER, "slot": i, "slots": len(names)}},
            )
            g = rng_mod.generator(seed, run, *streams(name, "initial"))
            x0 = pos.copy()
            x0[:2] += scn.navigation.initial_sigma_m * g.standard_normal(2)
            nav = FollowerNavigation(
                scn.navigation,
                self.method,
                x0,
                np.asarray(rig.lever_arms_body_m["modem"], dtype=float),
                plan,
                s.modem.period_s,
                tick,
            )
            guidance = StationGuidance(
                scn.station, fc.stations[i], tick, lambda g=leader_guidance: g.done
            )
            vehicles.append(
                VehicleParts(name, rig, nav, guidance, fc.autopilot, table, FOLLOWER_COLUMNS)
            )
        return MissionParts(vehicles, scenario_sea(scn, seed, run))


# ---------------------------------------------------------------------------------------------
# Metrics of one flight


def leader_course_true(leader: VehicleRun, window_ticks: int) -> Array:
    """The leader's true course over ground, rad, shape (T,): of its true velocity averaged over
    the last ``window_ticks`` ticks (the hull swings with the tail beat)."""
    v = leader["truth_vel"][:, :2]
    c = np.cumsum(np.vstack([np.zeros((1, 2)), v]), axis=0)
    k = np.arange(1, len(v) + 1)
    lo = np.maximum(k - window_ticks, 0)
    mean = (c[k] - c[lo]) / (k - lo)[:, None]
    return np.arctan2(mean[:, 0], mean[:, 1]) % (2 * np.pi)


def follower_metrics(
    scn: SwarmScenario, run: MissionRun, name: str, station: StationConfig
) -> dict[str, float]:
    """Errors of a follower's estimate (and of its pure DR) against its truth, and its true
    distance to the true station point (from the leader's true position and true course), m;
    fix counts; ``diverged_at_s``, the first time the estimate was farther than
    ``navigation.divergence_m`` from the truth (only when it was)."""
    lead, f = run.vehicles[LEADER], run.vehicles[name]
    n = min(len(lead["t"]), len(f["t"]))
    tick = scn.timing.control_tick_s
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))[:n]
    b = np.radians(station.relative_bearing_deg)
    station_true = lead["truth_pos"][:n, :2] + station.distance_m * np.column_stack(
        [np.sin(course + b), np.cos(course + b)]
    )
    truth = f["truth_pos"][:n, :2]
    e_est = np.hypot(*(f["ekf_pos"][:n, :2] - truth).T)
    e_dr = np.hypot(*(f["dr_pos"][:n, :2] - truth).T)
    e_st = np.hypot(*(truth - station_true).T)
    rel_true = truth - lead["truth_pos"][:n, :2]
    rel_est = f["ekf_pos"][:n, :2] - f["leader_est"][:n]
    e_rel = np.hypot(*(rel_est - rel_true).T)
    counts = f.outcome.get("fix_counts", {})
    fixes = f.fixes.get("modem", {})
    received = len(fixes["t_valid"].values) if fixes else 0
    gaps = f.outcome.get("dr_gaps_s", [])
    diverged = first_exceedance(f["t"][:n], e_est, scn.navigation.divergence_m)
    return {
        **({} if diverged is None else {"diverged_at_s": diverged}),
        "est_mean_error_m": float(e_est.mean()),
        "est_max_error_m": float(e_est.max()),
        "est_final_error_m": float(e_est[-1]),
        "relative_mean_error_m": float(e_rel.mean()),
        "relative_max_error_m": float(e_rel.max()),
        "dr_mean_error_m": float(e_dr.mean()),
        "dr_max_error_m": float(e_dr.max()),
        "station_mean_error_m": float(e_st.mean()),
        "station_max_error_m": float(e_st.max()),
        "ranges_received": float(received),
        "fixes_accepted": float(counts.get("accepted", 0)),
        "fixes_refused": float(received - counts.get("accepted", 0) - counts.get("dr", 0)),
        "mean_fix_hdop": float(f.outcome.get("mean_fix_hdop", 0.0)),
        "longest_dr_gap_s": float(max((b1 - a1 for a1, b1 in gaps), default=0.0)),
        "duration_s": float(f["t"][n - 1]),
    }


def leader_metrics(scn: SwarmScenario, run: MissionRun) -> dict[str, float]:
    """The leader's own navigation (its broadcast's error) and fix counts; ``diverged_at_s``
    as for a follower (:func:`follower_metrics`)."""
    lead = run.vehicles[LEADER]
    s = lead.summary
    keys = ("ekf_mean_error_m", "ekf_max_error_m", "usbl_fixes", "usbl_rejected", "duration_s")
    err = np.hypot(*(lead["ekf_pos"][:, :2] - lead["truth_pos"][:, :2]).T)
    diverged = first_exceedance(lead["t"], err, scn.navigation.divergence_m)
    out = {k: s[k] for k in keys if k in s}
    return out if diverged is None else {"diverged_at_s": diverged, **out}


def divergences(scn: SwarmScenario, run: int, method: str, metrics) -> list[str]:
    """One line per aided estimate of a flight that diverged (the leader's EKF and, unless the
    method is ``dr``, every follower's), from its metrics."""
    out = []
    for name, m in metrics.items():
        if "diverged_at_s" in m and (name == LEADER or method != "dr"):
            what = "EKF" if name == LEADER else method.upper()
            out.append(
                f"run {run} {method} {name}: {what} estimate diverged: farther than "
                f"{scn.navigation.divergence_m:g} m from the truth from t = "
                f"{m['diverged_at_s']:.1f} s (navigation.divergence_m)"
            )
    return out


def flight_warnings(scn: SwarmScenario, method: str, run: MissionRun) -> list[str]:
    """What a reader must know about a flight: failures, followers on DR for long, bad
    geometry."""
    out = []
    if run.failed:
        out.append(run.failed)
    for name, v in run.vehicles.items():
        if name == LEADER:
            continue
        for a, b in v.outcome.get("dr_gaps_s", []):
            out.append(
                f"run {run.run} {method} {name}: no accepted range for {b - a:.0f} s "
                f"(t = {a:.0f}-{b:.0f} s): navigated on dead reckoning"
            )
        h = v.outcome.get("mean_fix_hdop", 0.0)
        if h > scn.navigation.hdop_warning:
            out.append(
                f"run {run.run} {method} {name}: mean HDOP {h:.1f} at its fixes "
                f"(> {scn.navigation.hdop_warning:g}): poor geometry"
            )
    return out


@store.plain_data("missions.swarm.SwarmRunResult")
@dataclass
class SwarmRunResult:
    """The flights of one run (one per method, same draws), as plain data.

    Attributes:
        run: run index.
        failed: the first flight failure, or ``None``.
        flights: per method, the flight.
        metrics: per method, per follower (and ``leader``), the metrics.
        warnings: what the report must say about these flights.
        diverged: one line per aided estimate that diverged (:func:`divergences`).
    """

    run: int
    failed: str | None
    flights: dict[str, MissionRun]
    metrics: dict[str, dict[str, dict[str, float]]]
    warnings: list[str]
    diverged: list[str]


def fly_run(scn: SwarmScenario, seed: int, run: int) -> SwarmRunResult:
    """Fly one run with every method of the scenario and compute its metrics."""
    flights, metrics, warnings, diverged, failed = {}, {}, [], [], None
    stations = station_offsets(scn)
    for method in scn.methods():
        res = fly(SwarmMission(method), scn, seed, run)
        failed = failed or res.failed
        flights[method] = res
        m: dict[str, dict[str, float]] = {}
        if LEADER in res.vehicles and len(res.vehicles[LEADER]["t"]):
            m[LEADER] = leader_metrics(scn, res)
            for name, st in zip(FOLLOWERS, stations, strict=False):
                if name in res.vehicles:
                    m[name] = follower_metrics(scn, res, name, st)
        metrics[method] = m
        warnings += flight_warnings(scn, method, res)
        diverged += divergences(scn, run, method, m)
    return SwarmRunResult(run, failed, flights, metrics, warnings, diverged)


# ---------------------------------------------------------------------------------------------
# Report


class FollowerRow(BaseModel):
    """One follower with one method, means over the successful runs."""

    method: str
    follower: str
    relative_bearing_deg: float
    distance_m: float
    values: dict[str, float]


class SwarmMetrics(BaseModel):
    """``metrics.json`` of ``mission/swarm``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    failures: list[str]
    n_diverged: int = Field(description="aided estimates that diverged (navigation.divergence_m)")
    divergences: list[str]
    methods: list[str]
    current: str
    followers: list[FollowerRow] = Field(description="per follower and method, means over runs")
    leader: dict[str, dict[str, float]] = Field(description="per method, the leader's means")
    warnings: list[str]
    runs: list[dict[str, Any]] = Field(description="per run: method -> vehicle -> metrics")


@dataclass(frozen=True)
class SwarmExperiment(MissionExperiment):
    """Seed 003 on the physical BAUVs (one flight per method per run)."""

    scenario_type = SwarmScenario
    metrics_type = SwarmMetrics
    report_seabed = False  # its recording draws no seabed mesh

    def flight(self, scenario: SwarmScenario, seed: int, run: int):
        """The flight of a run with the first method."""
        return SwarmMission(scenario.methods()[0]), scenario

    def check(self, scenario: SwarmScenario, n_runs: int) -> None:
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )

    def run_block(self, scenario: SwarmScenario, seed: int, runs: tuple[int, ...]):
        return [fly_run(scenario, seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_swarm(self, ctx)


ROW_KEYS = (
    ("est_mean_error_m", "Estimate mean error (m)"),
    ("est_max_error_m", "Estimate max error (m)"),
    ("relative_mean_error_m", "Relative mean error (m)"),
    ("station_mean_error_m", "Station mean error (m)"),
    ("station_max_error_m", "Station max error (m)"),
    ("dr_mean_error_m", "Pure DR mean error (m)"),
    ("fixes_accepted", "Ranges accepted"),
    ("fixes_refused", "Ranges refused"),
    ("mean_fix_hdop", "Mean HDOP at fixes"),
    ("diverged_runs", "Diverged runs"),
)


COUNT_KEYS = frozenset({"fixes_accepted", "fixes_refused", "usbl_fixes", "diverged_runs"})
"""Row keys that count events: printed as whole numbers when the mean over runs is one."""


def _cell(key: str, value: float | None) -> float | int | None:
    """A table cell: a count that is a whole number as an ``int`` (119, not 119.00)."""
    if key in COUNT_KEYS and value is not None and float(value).is_integer():
        return int(value)
    return value


def report_swarm(exp: SwarmExperiment, ctx: ReportContext) -> ReportSummary:
    """The table per follower and method, the leader's navigation, warnings, figures, the
    recording of one run and the run data."""
    from tasks.closed_loop.report import export_runs
    from tasks.core.report import Table, write_metrics, write_tables

    scn: SwarmScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[SwarmRunResult] = [r for b in ctx.blocks for r in b]
    ok = [r for r in runs if r.failed is None]
    methods = list(scn.methods())
    stations = station_offsets(scn)
    names = FOLLOWERS[: len(stations)]

    def mean(method: str, vehicle: str, key: str) -> float | None:
        if key == "diverged_runs":  # a count over the runs, not a mean
            if method == "dr":
                return None
            return float(sum("diverged_at_s" in r.metrics[method].get(vehicle, {}) for r in ok))
        vals = [r.metrics[method][vehicle][key] for r in ok if vehicle in r.metrics[method]]
        return float(np.mean(vals)) if vals else None

    rows = []
    for name, st in zip(names, stations, strict=True):
        for m in methods:
            vals = {k: mean(m, name, k) for k, _ in ROW_KEYS}
            rows.append(
                FollowerRow(
                    method=m,
                    follower=name,
                    relative_bearing_deg=st.relative_bearing_deg,
                    distance_m=st.distance_m,
                    values={k: v for k, v in vals.items() if v is not None},
                )
            )
    leader = {
        m: {
            k: v
            for k in ("ekf_mean_error_m", "ekf_max_error_m", "usbl_fixes")
            if (v := mean(m, LEADER, k)) is not None
        }
        for m in methods
    }
    diverged = [w for r in ok for w in r.diverged]
    warnings = diverged + [w for r in runs for w in r.warnings]
    failures = [r.failed for r in runs if r.failed]
    metrics = SwarmMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=len(failures),
        failures=failures,
        n_diverged=len(diverged),
        divergences=diverged,
        methods=methods,
        current=f"{scn.current.kind}",
        followers=rows,
        leader=leader,
        warnings=warnings,
        runs=[{"run": r.run, "failed": r.failed, "metrics": r.metrics} for r in runs],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    for m in methods:
        files += export_runs(ctx.out_dir, exp.name, [r.flights[m] for r in runs], f"-{m}")
    cur = scn.current
    cur_text = (
        f"{cur.speed_m_s:g} m/s towards {cur.direction_deg:g} deg"
        if isinstance(cur, UniformCurrentConfig)
        else cur.kind
    )
    t1 = Table(
        f"Followers: navigation and station keeping ({len(ok)} run(s), mean over runs; "
        f"current {cur_text})",
        ["Follower", "Station", "Method", *(label for _, label in ROW_KEYS)],
        [
            [
                row.follower,
                f"{row.relative_bearing_deg:g} deg / {row.distance_m:g} m",
                row.method.upper(),
                *(_cell(k, row.values.get(k)) for k, _ in ROW_KEYS),
            ]
            for row in rows
        ],
        digits=2,
        slug="followers",
        note=(
            "Estimate error: the follower's estimate against its true position (world). "
            "Relative error: the estimated offset from the leader (estimate minus the leader "
            "position it knows) against the true offset. Station error: the true distance to "
            "the true station point (the leader's true position and course). Pure DR: the "
            "compass + log track without any range."
        ),
    )
    t2 = Table(
        "Leader: its own navigation (the position it broadcasts)",
        ["Method flown by the followers", "EKF mean error (m)", "EKF max error (m)", "USBL fixes"],
        [
            [
                m.upper(),
                leader[m].get("ekf_mean_error_m"),
                leader[m].get("ekf_max_error_m"),
                _cell("usbl_fixes", leader[m].get("usbl_fixes")),
            ]
            for m in methods
        ],
        digits=2,
        slug="leader",
    )
    tables = [t1, t2]
    if warnings or failures:
        tables.append(Table("Warnings", ["Warning"], [[w] for w in warnings], slug="warnings"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in runs if r.run == scn.report.record_run), None)
    if rec is not None:
        flight = rec.flights[methods[0]]
        if flight.vehicles and len(flight.vehicles[LEADER]["t"]) > 1:
            if scn.report.figures:
                files += swarm_figure(exp.name, scn, rec, methods, ctx.out_dir)
            if scn.report.recording:
                files.append(record_swarm(exp.name, scn, flight, methods[0], ctx.out_dir))
    text = "".join(t.to_text() + "\n" for t in tables)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files), tuple(failures), tuple(diverged))


COLORS_V = [(0, 0, 0), (0, 114, 178), (213, 94, 0), (0, 158, 115), (230, 159, 0)]
"""Recording colours of the leader and f1 .. f4 (the figure style's Okabe-Ito colours)."""


def swarm_figure(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out) -> list[str]:
    """Tracks of the recorded run (every vehicle's truth and estimate, first method) and each
    follower's true distance to its station over time, per method (PNG and PDF, project
    style)."""
    from tasks.core import style

    with style.context():
        return _draw_swarm(name, scn, rec, methods, out, style)


def _draw_swarm(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out, style):
    pal = style.PALETTE
    vehicle_colors = [pal[k] for k in ("black", "blue", "vermillion", "bluish_green", "orange")]
    method_names = {"ga1": "GA1", "ga2": "GA2", "ekf": "EKF", "dr": "DR"}
    fig, axs = style.subplots("page", 3.8, 1, 2)
    flight = rec.flights[methods[0]]
    ax = axs[0]
    for (vn, v), c in zip(flight.vehicles.items(), vehicle_colors, strict=False):
        ax.plot(v["truth_pos"][:, 0], v["truth_pos"][:, 1], "-", color=c, lw=1.0, label=vn)
        ax.plot(v["ekf_pos"][:, 0], v["ekf_pos"][:, 1], ":", color=c, lw=0.8, label="_")
    ax.plot([], [], "k:", lw=0.8, label="estimates")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"Truth and estimates ({method_names.get(methods[0], methods[0])})")
    ax.legend(loc="best")
    ax = axs[1]
    tick = scn.timing.control_tick_s
    dashes = ["-", "--", "-.", ":"]
    for m in methods:
        f = rec.flights[m]
        if LEADER not in f.vehicles:
            continue
        lead = f.vehicles[LEADER]
        course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
        for j, (vn, st) in enumerate(zip(FOLLOWERS, station_offsets(scn), strict=False)):
            if vn not in f.vehicles:
                continue
            v = f.vehicles[vn]
            n = min(len(v["t"]), len(lead["t"]))
            b = math.radians(st.relative_bearing_deg)
            sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
                [np.sin(course[:n] + b), np.cos(course[:n] + b)]
            )
            ax.plot(
                v["t"][:n],
                np.maximum(np.hypot(*(v["truth_pos"][:n, :2] - sp).T), 1e-2),
                dashes[j % 4],
                color=style.color(method_names.get(m, m)),
                lw=0.8,
                label=f"{vn} {method_names.get(m, m)}",
            )
    ax.set_yscale("log")
    style.log_ticks(ax)
    ax.set_xlabel(style.label("time", "s"))
    ax.set_ylabel(style.label("true distance to the station", "m"))
    style.title(ax, "Station-keeping error")
    ax.legend(ncol=2, loc="best")
    return style.save(fig, out / "swarm.png")


def record_swarm(name: str, scn: SwarmScenario, run: MissionRun, method: str, out) -> str:
    """``recording.rrd`` of a flight: every vehicle (hull, truth, estimate), each follower's
    range circle at each fix (the leader position it used, the horizontal range), its HDOP, its
    station and navigation errors."""
    import rerun as rr

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from tasks.closed_loop.report import circle
    from tasks.core.recording import TIMELINE, Recording

    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}/{method}")
    r = rec.rec
    tick = scn.timing.control_tick_s
    lead = run.vehicles[LEADER]
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, -20.0])
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    stations = dict(zip(FOLLOWERS, station_offsets(scn), strict=False))
    plots = []
    for (vn, v), color in zip(run.vehicles.items(), COLORS_V, strict=False):
        t = v["t"]
        r.send_columns(
            f"world/{vn}/vehicle",
            indexes=[rr.TimeColumn(TIMELINE, duration=t)],
            columns=rr.Transform3D.columns(
                translation=v["truth_pos"], quaternion=quat_wxyz_to_xyzw(v["truth_quat_wxyz"])
            ),
        )
        r.log(
            f"world/{vn}/vehicle/hull",
            rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"),
            static=True,
        )
        rec.track(f"{vn}/truth", t, v["truth_pos"], color)
        light = tuple(int(c + (255 - c) * 0.5) for c in color)
        rec.track(f"{vn}/estimate", t, v["ekf_pos"], light, radius_m=0.4)
        if vn == LEADER:
            continue
        fx = v.fixes.get("modem")
        if fx:
            z = -scn.station.depth_m
            for ta, rng_h, ce, cn, ok in zip(
                fx["t_arrival"].values,
                fx["horizontal_range"].values,
                fx["centre_east"].values,
                fx["centre_north"].values,
                fx["accepted"].values,
                strict=True,
            ):
                r.set_time(TIMELINE, duration=float(ta))
                if rng_h > 0:
                    r.log(
                        f"world/{vn}/range_circle",
                        rr.LineStrips3D(
                            [circle(float(ce), float(cn), float(rng_h), z)],
                            colors=color if ok else (150, 150, 150),
                            radii=0.08,
                        ),
                    )
            r.reset_time()
        rec.scalars(f"hdop/{vn}", t, v["hdop"], color, f"{vn} HDOP")
        st = stations[vn]
        n = min(len(t), len(lead["t"]))
        b = math.radians(st.relative_bearing_deg)
        sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
            [np.sin(course[:n] + b), np.cos(course[:n] + b)]
        )
        rec.track(
            f"{vn}/station",
            t[:n],
            np.column_stack([sp, np.full(n, -scn.station.depth_m)]),
            (255, 127, 14),
            radius_m=0.3,
            strip=False,
        )
        rec.scalars(
            f"station_error/{vn}",
            t[:n],
            np.hypot(*(v["truth_pos"][:n, :2] - sp).T),
            color,
            f"{vn} true distance to station (m)",
        )
        rec.scalars(
            f"errors/{vn}",
            t,
            np.hypot(*(v["ekf_pos"] - v["truth_pos"])[:, :2].T),
            color,
            f"{vn} {method.upper()} position error (m)",
        )
        plots = ["hdop", "station_error", "errors"]
    rec.blueprint(*plots)
    rec.close()
    return "recording.rrd"


register(
    SwarmExperiment(
        name="mission/swarm",
        summary="seed 003 on the BAUVs: followers keep station abeam a leader from one acoustic "
        "range every 5 s (GA1/GA2/EKF/DR), 0.2 m/s cross current",
        preset={},
        default_runs=1,
    )
)
