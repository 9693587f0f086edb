"""Scenario of a closed-loop way-point mission (one vehicle): the configuration a user sets.

A mission module presets these fields (``mission_preset``); ``--set`` and scenario files override
them. Multi-vehicle missions declare their own scenario types built from the same sections.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_validator

from bauv_sim.acoustics import SoundSpeedConfig
from bauv_sim.autopilot import AutopilotConfig
from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig
from bauv_sim.geo import GeoOriginConfig, LocalFrame
from bauv_sim.seabed import SeabedConfig
from bauv_sim.sensors import (
    AngleErrorConfig,
    CompassConfig,
    DvlConfig,
    GpsConfig,
    LengthErrorConfig,
    LogConfig,
    OdometryConfig,
    PressureConfig,
    SpeedErrorConfig,
    UsblConfig,
    check_multiple,
)
from bauv_sim.sensors.ins import InsConfig
from tasks.closed_loop.geo import resolve_geographic

MODES = ("transit", "ascend", "surface", "dive", "done")

PHYSICS_TIMESTEP_S = 0.004
"""The missions' physics timestep, s: the 4 ms preset, validated against 1 ms by
``python models/bauv/tools/timestep.py`` (models/bauv/README.md, "Timestep presets")."""
"""Guidance modes, in the order of their integer codes in observations and run data."""


class WaypointConfig(Config):
    """A way-point of the mission (in a scenario file it may be given as ``latitude_deg`` and
    ``longitude_deg`` instead of ``east_m`` and ``north_m``, with the scenario's ``geo`` origin;
    :mod:`tasks.closed_loop.geo` converts them before validation)."""

    east_m: float
    north_m: float
    depth_m: float = Field(3.0, ge=0, description="depth of the leg ending here, m")
    acceptance_radius_m: float = Field(8.0, gt=0, description="judged horizontally, m")
    surface: bool = Field(False, description="surface here for a GPS fix")


class StartConfig(Config):
    """Where the vehicle starts (after a GNSS fix at the surface, already dived); in a scenario
    file ``latitude_deg`` and ``longitude_deg``, with the scenario's ``geo`` origin, replace
    ``east_m`` and ``north_m`` (:mod:`tasks.closed_loop.geo`)."""

    east_m: float = 0.0
    north_m: float = 0.0
    depth_m: float = Field(3.0, ge=0)
    heading_deg: float = Field(0.0, ge=0, lt=360)
    speed_m_s: float = Field(0.8, ge=0, le=2)
    position_sigma_m: float = Field(
        2.0, ge=0, description="scatter of the true start about the nominal one, per axis, m"
    )
    heading_sigma_deg: float = Field(5.0, ge=0, description="scatter of the true heading, deg")


class SurveySensors(Config):
    """The survey's four devices (compass, EM log, pressure, USBL), shared by
    :class:`MissionSensors` and the fleet's batches (``tasks.fleet``)."""

    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2, heading=AngleErrorConfig(sigma_deg=2.0, bias_deg=0.0)
        ),
        description="VN-100 class compass/AHRS: 2 deg heading noise in a metal hull",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=1.0,
            speed=SpeedErrorConfig(sigma_m_s=0.05, scale_factor=0.01),
            min_speed_m_s=0.15,
        ),
        description="ALIZE EM log at 1 Hz: speed through water, 1 % scale, blind below 0.15 m/s",
    )
    pressure: PressureConfig = Field(
        default_factory=lambda: PressureConfig(
            period_s=1.0, output="depth", depth=LengthErrorConfig(sigma_m=0.05)
        ),
        description="WIKA S-20 class pressure sensor at 1 Hz, 5 cm noise",
    )
    usbl: UsblConfig = Field(
        default_factory=lambda: UsblConfig(period_s=5.0, processing_delay_s=1.0),
        description="MicronNav: 0.2 m, 3 deg, 500 m; travel time + 1 s modem latency",
    )


class MissionSensors(SurveySensors):
    """The vehicle's sensors (defaults: the seeds' devices, gaussian errors)."""

    ins: InsConfig = Field(
        default_factory=InsConfig,
        description="INS roll, pitch and rates for the autopilot and the lever arms (exact)",
    )
    gps: GpsConfig = Field(default_factory=GpsConfig, description="GPS at the surface")
    odometry: OdometryConfig = Field(
        default_factory=lambda: OdometryConfig(period_s=1.0),
        description="speed from the tail-beat setting; an empty table is the model's speed table",
    )
    use_usbl: bool = Field(True, description="give USBL fixes to the navigator")
    use_gps: bool = Field(True, description="give GPS fixes to the navigator")
    use_log: bool = Field(True, description="the vehicle has a log (else odometry speed)")
    dvl: DvlConfig = Field(
        default_factory=DvlConfig,
        description="Doppler velocity log at 5 Hz on the hull's dvl site (rig only with use_dvl)",
    )
    use_dvl: bool = Field(
        False,
        description="the rig carries the DVL (its pings reach the mission's navigator, which "
        "may ignore them)",
    )


class NavigationConfig(Config):
    """The navigator and what the controller steers on."""

    steer_on: Literal["ekf", "dr"] = Field(
        "ekf", description="estimate guidance uses: the EKF, or dead reckoning alone"
    )
    sigma_heading_deg: float = Field(2.0, gt=0)
    sigma_speed_m_s: float = Field(0.08, gt=0, description="log noise + scale + unmodelled")
    sigma_vertical_m_per_tick: float = Field(0.05, gt=0, description="vertical process noise")
    sigma_depth_m: float = Field(0.05, gt=0)
    sigma_range_m: float = Field(0.2, gt=0)
    sigma_azimuth_deg: float = Field(3.0, gt=0)
    sigma_elevation_deg: float = Field(3.0, gt=0)
    sigma_gps_m: float = Field(2.5, gt=0)
    initial_sigma_m: float = Field(3.0, gt=0, description="per horizontal axis, m (GNSS fix)")
    gate_enabled: bool = Field(True, description="chi-square innovation gate on USBL/GPS fixes")
    gate_probability: float = Field(0.999, gt=0, lt=1, description="gate probability")
    history_s: float = Field(20.0, gt=0, description="history kept for late fixes, s")
    estimate_current: bool = Field(
        True, description="carry the water current in the EKF state (else seed 000's 3 states)"
    )
    current_sigma0_m_s: float = Field(0.3, gt=0, description="initial current sigma, m/s")
    current_walk_m_s_per_sqrt_s: float = Field(
        0.005, ge=0, description="random walk of the current, (m/s)/sqrt(s)"
    )
    max_consecutive_rejections: int = Field(
        5, ge=0, description="after this many gated fixes in a row, apply the next one; 0: never"
    )


class GuidanceConfig(Config):
    """Way-points and how to fly them."""

    waypoints: tuple[WaypointConfig, ...] = Field(min_length=1)
    waypoints_file: str | None = Field(
        None,
        description="a CSV or GeoJSON file of way-points that replace `waypoints` (read when "
        "the scenario is loaded; the resolved scenario holds its way-points, not the file: "
        "formats in tasks.closed_loop.geo)",
    )
    speed_m_s: float = Field(1.0, gt=0, le=2)
    surface_speed_m_s: float = Field(0.5, gt=0, le=2)
    surface_depth_m: float | None = Field(
        None,
        ge=0,
        description="estimated depth counted as surfaced, m (default: the GPS "
        "antenna's height above the reference point minus 5 cm)",
    )
    hold_s: float = Field(10.0, ge=0)
    fixes_needed: int = Field(3, ge=1)
    max_leg_time_s: float = Field(900.0, gt=0)
    reach_probability: float = Field(
        0.95,
        gt=0,
        lt=1,
        description="a way-point is reached when the truth is inside its "
        "circle with this probability given the estimate (see nav.guidance)",
    )
    min_reach_m: float = Field(1.0, gt=0, description="else pass within this distance, m")

    @model_validator(mode="after")
    def _file_read(self) -> GuidanceConfig:
        if self.waypoints_file is not None:
            raise ValueError(
                f"waypoints_file = {self.waypoints_file!r}: read by a mission scenario "
                "(MissionScenario) only; this scenario takes guidance.waypoints"
            )
        return self


class TimingConfig(Config):
    """Clocks of the mission."""

    control_tick_s: float = Field(
        0.2, gt=0, description="autopilot and navigation tick, s (a multiple of the timestep)"
    )
    physics_timestep_s: float = Field(
        PHYSICS_TIMESTEP_S,
        gt=0,
        le=0.01,
        description="MuJoCo timestep, s; every preset up to 10 ms agrees with 1 ms within the "
        "timestep table's thresholds (models/bauv/README.md, Timestep presets): 4 ms within "
        "0.6 %, 10 ms within 2.1 % (motor power; cruise speed 0.3 %); 0.002 or 0.001 for the "
        "finer steps",
    )
    max_duration_s: float = Field(2400.0, gt=0, description="the mission is stopped after, s")
    world: Literal["mujoco", "manoeuvring"] = Field(
        "mujoco",
        description="the physics the vehicle flies in: 'mujoco', the full MuJoCo vehicle at "
        "physics_timestep_s; or 'manoeuvring', the 6-DOF manoeuvring model identified from it "
        "(bauv_sim.manoeuvring), one step per control tick (physics_timestep_s unused); one "
        "vehicle, no free surface (models/bauv/README.md, Results 13)",
    )

    @model_validator(mode="after")
    def _check_tick(self) -> TimingConfig:
        ratio = self.control_tick_s / self.physics_timestep_s
        if round(ratio) < 1 or abs(ratio - round(ratio)) > 1e-9 * max(1.0, ratio):
            raise ValueError(
                f"timing.control_tick_s = {self.control_tick_s:g}: must be a whole multiple "
                f"(>= 1) of timing.physics_timestep_s = {self.physics_timestep_s:g} s"
            )
        return self


class FaultConfig(Config):
    """Injected faults, for testing that failures are reported."""

    physics_nan_at_s: float | None = Field(None, ge=0, description="corrupt the physics at t")
    physics_nan_runs: tuple[int, ...] = Field(
        (), description="runs that get the fault (each 0 <= run < runs, checked with the batch)"
    )


class MissionReportConfig(Config):
    """What the report writes."""

    recording: bool = True
    figures: bool = True
    record_run: int = Field(0, ge=0)


class MissionScenario(Config):
    """Scenario of a closed-loop way-point mission."""

    geo: GeoOriginConfig | None = Field(
        None,
        description="the scene's origin on the Earth (WGS 84); needed by a bathymetry or "
        "current file and by positions given in latitude and longitude (default: none, a "
        "local frame only)",
    )
    seabed: SeabedConfig = Field(default_factory=SeabedConfig)
    transceiver_east_m: float = Field(
        0.0,
        description="the USBL transceiver, m (or transceiver_latitude_deg and "
        "transceiver_longitude_deg with geo)",
    )
    transceiver_north_m: float = 0.0
    start: StartConfig = Field(default_factory=StartConfig)
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.25, direction_deg=60.0)
    )
    sensors: MissionSensors = Field(default_factory=MissionSensors)
    sound: SoundSpeedConfig = Field(
        default_factory=SoundSpeedConfig,
        description="the sea's true sound-speed profile for the acoustic devices (default: "
        "none, each device's own sound_speed_m_s)",
    )
    navigation: NavigationConfig = Field(default_factory=NavigationConfig)
    guidance: GuidanceConfig = Field(
        default_factory=lambda: GuidanceConfig(waypoints=(WaypointConfig(east_m=0, north_m=50),))
    )
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)
    timing: TimingConfig = Field(default_factory=TimingConfig)
    faults: FaultConfig = Field(default_factory=FaultConfig)
    report: MissionReportConfig = Field(default_factory=MissionReportConfig)

    @model_validator(mode="before")
    @classmethod
    def _geographic(cls, data: Any) -> Any:
        """Way-points from ``guidance.waypoints_file`` and positions in latitude/longitude, made
        east/north with the ``geo`` origin (:func:`tasks.closed_loop.geo.resolve_geographic`)."""
        return resolve_geographic(data)

    @model_validator(mode="after")
    def _check(self) -> MissionScenario:
        tick = self.timing.control_tick_s
        s = self.sensors
        for name in ("compass", "ins", "log", "pressure", "usbl", "gps"):
            check_multiple(getattr(s, name).period_s, tick, f"sensors.{name}.period_s")
        check_multiple(s.odometry.period_s, tick, "sensors.odometry.period_s")
        if s.use_dvl:
            check_multiple(s.dvl.period_s, tick, "sensors.dvl.period_s")
        for name in ("compass", "ins"):
            period = getattr(s, name).period_s
            if abs(period - tick) > 1e-9:
                raise ValueError(
                    f"sensors.{name}.period_s = {period:g}: the autopilot reads it every control "
                    f"tick ({tick:g} s)"
                )
        return self

    def frame(self) -> LocalFrame | None:
        """The scene's east/north frame on the Earth, or None without a ``geo`` origin."""
        return None if self.geo is None else self.geo.frame()


def mission_preset(waypoints: list[dict[str, Any]], **sections: Any) -> dict[str, Any]:
    """Build a mission preset from way-points and other scenario sections (helper for the
    :mod:`tasks.missions` modules)."""
    preset: dict[str, Any] = {"guidance": {"waypoints": waypoints}}
    for k, v in sections.items():
        if k == "guidance":
            preset["guidance"].update(v)
        else:
            preset[k] = v
    return preset
