"""The scenario of ``coop/team`` and ``coop/sensitivity``: the team's truth, every vehicle's
devices, the acoustic network, the sea's sound speed, what the filters are told, the methods and
the sensitivity settings.

Readings where the issue is silent (documented in the fields):

* every vehicle, the leader too, dead-reckons on a compass and a log sampled every tick with
  seed 003's error models (uniform white noise, a course-sector bias and a speed bias: Test 3's
  values, Naus & Piskur 2022 section 3); a pressure sensor gives each vehicle's depth;
* only the leader has absolute positioning: a USBL from a surface transceiver (a fix every
  ``usbl.period_s``, turned into a horizontal position with its first-order covariance,
  :meth:`nav.models.UsblMeasurement.fix_covariance`) and a GPS fix at the start (before the
  dive); a follower's start is known to ``follower_start_sigma_m`` (launched from a known
  place);
* the filters are told the devices' white noise (the DR steps' covariance, seed 003 eq. 5) plus
  what the white noise does not hold - the current and the biases -, modelled as a velocity error
  of ``filters.unmodelled_speed_m_s`` with correlation time ``filters.correlation_s`` (position
  variance ``2 sigma^2 tau`` per second: the long-time growth of a first-order Gauss-Markov
  velocity error, Gelb 1974 ch. 3).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from bauv_sim.acoustics.clock import ClockConfig
from bauv_sim.acoustics.network import AcousticNetworkConfig
from bauv_sim.acoustics.sonar import SonarConfig
from bauv_sim.acoustics.sound import SoundSpeedConfig
from bauv_sim.config import Config
from bauv_sim.kinematic.team import LEADER, TeamConfig
from bauv_sim.sensors import (
    AngleErrorConfig,
    CompassConfig,
    GpsConfig,
    LengthErrorConfig,
    LogConfig,
    PressureConfig,
    UsblConfig,
    check_multiple,
)
from bauv_sim.sensors.compass import seed003_heading_error
from bauv_sim.sensors.log import seed003_speed_error

METHODS = ("dr", "ga2", "leader-ekf", "decentralised", "central")
"""Every method of :func:`nav.cooperative.team_tracks`, in the report's order."""

LABELS = {
    "dr": "DR",
    "ga2": "GA2",
    "leader-ekf": "EKF",
    "decentralised": "decentralised",
    "central": "central",
}
"""Each method's name in tables and figures (the looks declared by :mod:`tasks.coop`)."""

LEADER_ONLY = ("ga2", "leader-ekf")
"""The methods that position a follower on its ranges to the leader alone (seed 003)."""

CLOCKED = ("decentralised", "central")
"""The methods with the clock offsets in their state."""


class SensorsConfig(Config):
    """Every vehicle's devices (the same on each) and the leader's absolute positioning."""

    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2,
            heading=seed003_heading_error(),
        ),
        description="heading every tick: uniform +-2 deg plus the course-sector bias 0.4, 0.8, "
        "0, 0.2 deg (seed 003, Test 3)",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=0.2,
            speed=seed003_speed_error(),
        ),
        description="speed through water every tick: uniform +-0.3 m/s plus 0.005 m/s bias "
        "(seed 003, Test 3)",
    )
    pressure: PressureConfig = Field(
        default_factory=lambda: PressureConfig(period_s=0.2, depth=LengthErrorConfig(sigma_m=0.1)),
        description="depth every tick, sigma 0.1 m",
    )
    usbl: UsblConfig = Field(
        default_factory=lambda: UsblConfig(
            period_s=5.0,
            azimuth=AngleErrorConfig(sigma_deg=1.0),
            elevation=AngleErrorConfig(sigma_deg=1.0),
        ),
        description="the leader's USBL: a fix every 5 s, range sigma 0.2 m, angles 1 deg",
    )
    usbl_transceiver_m: tuple[float, float, float] = Field(
        (100.0, 100.0, 0.0),
        description="the USBL transceiver (a ship at the surface), east, north, z, m, world",
    )
    gps: GpsConfig = Field(
        default_factory=GpsConfig, description="the leader's GPS fix at the start (its error)"
    )
    follower_start_sigma_m: float = Field(
        5.0, gt=0, le=1000, description="a follower's start error, m, 1 sigma per axis"
    )


def _network() -> AcousticNetworkConfig:
    return AcousticNetworkConfig(
        period_s=8.0,
        slot_s=2.0,
        start_s=2.0,
        travel_time_sigma_s=1e-4,
        max_range_m=1000.0,
        sonar=SonarConfig(fading_sigma_db=3.0),
        clock=ClockConfig(offset_sigma_s=1e-3, drift_sigma_ppm=1.0, jitter_s=2e-5),
        clocks={LEADER: ClockConfig(offset_sigma_s=1e-6, drift_sigma_ppm=1e-3, jitter_s=2e-5)},
    )


class FiltersConfig(Config):
    """What the navigation is told beyond the devices' white noise."""

    unmodelled_speed_m_s: float = Field(
        0.03,
        ge=0,
        le=5,
        description="sigma of the velocity error the white noise does not hold (current, "
        "biases), m/s",
    )
    correlation_s: float = Field(120.0, gt=0, le=36_000, description="its correlation time, s")
    sigma_range_m: float = Field(
        0.3, gt=0, le=100, description="the ranges' standard deviation the filters assume, m"
    )
    clock_offset_sigma_ms: float = Field(
        1.0, gt=0, le=1e4, description="a follower's initial clock offset, ms, 1 sigma"
    )
    clock_drift_sigma_ppm: float = Field(
        1.0, gt=0, le=1e4, description="a follower's initial clock drift, ppm, 1 sigma"
    )
    estimate_drift: bool = Field(True, description="the clock drifts in the state")
    fusion: Literal["ci", "naive"] = Field(
        "ci",
        description="decentralised fusion: covariance intersection, or naive (double counting)",
    )


class SweepConfig(Config):
    """The sensitivity settings: each value changes one thing from the base scenario (same runs,
    same draws); empty lists: the base only (``coop/team``)."""

    drift_ppm: list[float] = Field(
        default_factory=list,
        max_length=20,
        description="clock drift sigma of every vehicle but the leader, ppm (drawn per run)",
    )
    sound_speed_m_s: list[float] = Field(
        default_factory=list,
        max_length=20,
        description="the sea's true (isovelocity) sound speed against the nominal 1500 m/s",
    )
    sound_profile: list[Literal["munk"]] = Field(
        default_factory=list,
        max_length=1,
        description="the sea's true profile (munk: Munk's 1974 thermocline, 1548.5 m/s at the "
        "surface) against the nominal 1500 m/s",
    )
    source_level_db: list[float] = Field(
        default_factory=list,
        max_length=20,
        description="modems' source level with the sonar equation on (packet loss), dB re 1 uPa",
    )

    @model_validator(mode="after")
    def _values(self) -> SweepConfig:
        for name in ("drift_ppm", "sound_speed_m_s", "source_level_db"):
            v = getattr(self, name)
            if len(set(v)) != len(v):
                raise ValueError(f"{name}: a value appears twice")
        bad = [x for x in self.drift_ppm if not 0 <= x <= 1000]
        if bad:
            raise ValueError(f"drift_ppm: {bad[0]} is outside [0, 1000] ppm")
        bad = [x for x in self.sound_speed_m_s if not 1400 <= x <= 1600]
        if bad:
            raise ValueError(f"sound_speed_m_s: {bad[0]} is outside [1400, 1600] m/s")
        bad = [x for x in self.source_level_db if not 100 <= x <= 250]
        if bad:
            raise ValueError(f"source_level_db: {bad[0]} is outside [100, 250] dB")
        return self


class ReportConfig(Config):
    """What the report draws."""

    figures: bool = True
    curve_every_s: float = Field(
        5.0, gt=0, description="time step of the error curves against time, s"
    )


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int = Field(10, ge=1, le=10_000, description="runs per block")


class CoopScenario(Config):
    """Scenario of ``coop/team`` and ``coop/sensitivity`` (module docstring)."""

    team: TeamConfig = Field(default_factory=TeamConfig)
    sensors: SensorsConfig = Field(default_factory=SensorsConfig)
    sound: SoundSpeedConfig = Field(
        default_factory=SoundSpeedConfig,
        description="the sea's true sound speed (default: the devices' nominal 1500 m/s)",
    )
    network: AcousticNetworkConfig = Field(
        default_factory=_network,
        description="OWTT in TDMA slots of 2 s (a cycle of 8 s for the four vehicles), arrival "
        "noise 0.1 ms, followers' clocks: 1 ms and 1 ppm (TCXO) per run, the leader's "
        "GPS-disciplined; the sonar equation off",
    )
    filters: FiltersConfig = Field(default_factory=FiltersConfig)
    methods: list[str] = Field(
        default_factory=lambda: list(METHODS),
        min_length=1,
        description=f"the methods compared, among {', '.join(METHODS)}",
    )
    sweep: SweepConfig = Field(default_factory=SweepConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)

    @model_validator(mode="after")
    def _check(self) -> CoopScenario:
        bad = [m for m in self.methods if m not in METHODS]
        if bad:
            raise ValueError(f"methods: {bad[0]!r} is not one of {', '.join(METHODS)}")
        if len(set(self.methods)) != len(self.methods):
            raise ValueError("methods: a method appears twice")
        tick = self.team.tick_s
        for name in ("compass", "log", "pressure"):
            period = getattr(self.sensors, name).period_s
            if abs(period - tick) > 1e-9 * tick:
                raise ValueError(
                    f"sensors.{name}.period_s = {period:g}: the dead reckoning samples every "
                    f"tick (team.tick_s = {tick:g} s)"
                )
        check_multiple(self.sensors.usbl.period_s, tick, "sensors.usbl.period_s")
        return self

    def settings(self) -> list[tuple[str, str, float | None]]:
        """The batch's settings ``(label, what, value)``: the base first, then one per sweep
        value (``what`` names the sweep list; None and no value for the base)."""
        out: list[tuple[str, str, float | None]] = [("base", "base", None)]
        s = self.sweep
        out += [(f"drift {v:g} ppm", "drift_ppm", v) for v in s.drift_ppm]
        out += [(f"sound {v:g} m/s", "sound_speed_m_s", v) for v in s.sound_speed_m_s]
        out += [(f"sound profile {v}", "sound_profile", None) for v in s.sound_profile]
        out += [(f"source level {v:g} dB", "source_level_db", v) for v in s.source_level_db]
        return out
