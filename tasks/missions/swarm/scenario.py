"""The scenario of ``mission/swarm``: the leader, the followers, their sensors, navigation and
station keeping (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.acoustics.channel import slot_senders
from bauv_sim.acoustics.sound import SoundSpeedConfig
from bauv_sim.autopilot import AutopilotConfig
from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig
from bauv_sim.errors import ConfigError
from bauv_sim.geo import GeoOriginConfig, LocalFrame
from bauv_sim.seabed import SeabedConfig
from bauv_sim.sensors import (
    AngleErrorConfig,
    CompassConfig,
    LengthErrorConfig,
    LogConfig,
    PressureConfig,
    UsblConfig,
    check_multiple,
)
from bauv_sim.sensors.compass import seed003_heading_error
from bauv_sim.sensors.ins import InsConfig
from bauv_sim.sensors.log import seed003_speed_error
from bauv_sim.sensors.modem import ModemConfig, check_slots
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
from tasks.missions.swarm.formation import (
    DEFAULT_STATIONS,
    MIN_STATION_SEPARATION_M,
    StationConfig,
    generated_station,
    racetrack,
    station_point_m,
)
from tasks.missions.swarm.network import SwarmNetworkConfig
from tasks.missions.swarm.options import CoopNavigationConfig

Array = NDArray[np.float64]
Method = Literal["ga1", "ga2", "ekf", "dr", "decentralised"]
METHODS: tuple[str, ...] = ("ga1", "ga2", "ekf", "dr", "decentralised")
LEADER_ONLY_METHODS: tuple[str, ...] = ("ga1", "ga2", "ekf", "dr")
"""Seed 003's methods: a follower navigates on the leader's ranges alone (``dr``: on none)."""
MAX_FOLLOWERS = 12
"""The most followers a scenario may have (``followers.count``)."""
FOLLOWERS = tuple(f"f{i}" for i in range(1, MAX_FOLLOWERS + 1))
"""The followers' names in the scene, in order (``f1`` .. ``f12``; a flight has the first
``followers.count``)."""
LEADER = "leader"
REFUSALS = ("ok", "dr", "no range", "range below minimum", "gate", "no fix", "no direction")
"""Codes of the modem fix table's ``refusal`` column (index = code); ``"degenerate"`` (a slant
range shorter than the depth difference) is the last one."""
REFUSAL_CODES = {r: i for i, r in enumerate((*REFUSALS, "degenerate"))}
DEPTH_SIGMA_M = 0.05
"""Standard deviation of a follower's stated depth (its pressure depth), m."""


# ---------------------------------------------------------------------------------------------
# Scenario


class FollowerSensors(Config):
    """A follower's devices (navigation: compass and log; the INS and the pressure sensor serve
    the autopilot and the depth)."""

    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2,
            heading=seed003_heading_error(),
        ),
        description="VN-100 (seed 003): uniform +-2 deg, Test 3's course-sector bias",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=0.2,
            speed=seed003_speed_error(),
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

    count: int = Field(
        1,
        ge=1,
        le=MAX_FOLLOWERS,
        description=f"number of followers (f1 .. f{MAX_FOLLOWERS}); beyond 6, the modem's "
        "slots need a longer period (followers.sensors.modem.period_s)",
    )
    stations: tuple[StationConfig, ...] = Field(
        DEFAULT_STATIONS,
        min_length=1,
        max_length=MAX_FOLLOWERS,
        description="station of f1, f2, ...; followers beyond the list get generated stations "
        "(rings of starboard, port, astern at 10, 20, 30 ... m: generated_station)",
    )
    position_sigma_m: float = Field(
        0.5, ge=0, description="scatter of the true start about the station, per axis, m"
    )
    heading_sigma_deg: float = Field(2.0, ge=0, description="scatter of the start heading, deg")
    sensors: FollowerSensors = Field(default_factory=FollowerSensors)
    network: SwarmNetworkConfig = Field(
        default_factory=SwarmNetworkConfig,
        description="the team's acoustic network (off by default: the followers' modem)",
    )
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)

    @model_validator(mode="after")
    def _separation(self) -> FollowersConfig:
        pts = [station_point_m(s) for s in self.station_list()]
        for j in range(len(pts)):
            for i in range(j):
                d = float(np.hypot(*(pts[j] - pts[i])))
                if d < MIN_STATION_SEPARATION_M:
                    how = "given" if j < len(self.stations) else "generated"
                    raise ValueError(
                        f"stations: f{j + 1}'s station ({how}) is {d:.2f} m from f{i + 1}'s; "
                        f"stations must be at least {MIN_STATION_SEPARATION_M:g} m apart "
                        "(give a station for every follower)"
                    )
        return self

    def station_list(self) -> list[StationConfig]:
        """The stations of the ``count`` followers, in order: those given, then generated
        (:func:`generated_station`) for the followers beyond the list."""
        given = list(self.stations[: self.count])
        return given + [generated_station(i) for i in range(len(given), self.count)]


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
        "after the leader's turn, models/bauv/README.md and the module docstring); on the "
        "acoustic network also decentralised (every range, clocks in the state, covariance "
        "intersection: navigation.coop)",
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
    coop: CoopNavigationConfig = Field(
        default_factory=CoopNavigationConfig,
        description="the decentralised filter and the team methods compared after each flight",
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

    geo: GeoOriginConfig | None = Field(
        None,
        description="the scene's origin on the Earth (WGS 84); needed by a bathymetry file "
        "(seabed.file); default: none, a local frame only",
    )
    seabed: SeabedConfig = Field(default_factory=SeabedConfig)
    transceiver_east_m: float = Field(50.0, description="the leader's USBL transceiver, m")
    transceiver_north_m: float = 120.0
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.2, direction_deg=90.0),
        description="0.2 m/s towards east: across the racetrack's legs",
    )
    sound: SoundSpeedConfig = Field(
        default_factory=SoundSpeedConfig,
        description="the sea's true sound-speed profile for every vehicle's acoustic devices "
        "(the leader's USBL, the modem, the network); default: none, each device's own "
        "sound_speed_m_s",
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

    def frame(self) -> LocalFrame | None:
        """The scene's east/north frame on the Earth, or None without a ``geo`` origin."""
        return None if self.geo is None else self.geo.frame()

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
        net = self.followers.network
        if not net.enabled:
            check_slots(fs.modem, tick, self.followers.count, "followers.sensors.modem")
            if "decentralised" in self.methods():
                raise ValueError(
                    "navigation.method(s): decentralised needs the acoustic network "
                    "(followers.network.enabled = true)"
                )
        else:
            if net.ranging != "owtt":
                raise ValueError(
                    f"followers.network.ranging = {net.ranging!r}: the vehicles' online device "
                    "ranges by one-way travel time only ('owtt')"
                )
            names = (LEADER, *FOLLOWERS[: self.followers.count])
            try:
                slot_senders(net, names)
            except ConfigError as exc:
                raise ValueError(f"followers.{exc}") from None
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


def station_offsets(scn: SwarmScenario) -> list[StationConfig]:
    """The stations of the scenario's followers, in order (those given, then generated:
    :meth:`FollowersConfig.station_list`)."""
    return scn.followers.station_list()
