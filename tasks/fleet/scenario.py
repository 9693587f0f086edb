"""The scenario of ``fleet/survey``: a Monte Carlo batch of way-point missions on the manoeuvring
model, every run steered on its own EKF (issue 27, check 2).

Reading of the experiment where the issue is silent (documented in the fields):

* the plan is the survey's lawn-mower extended to about an hour: ``lanes`` east-west lanes of
  ``lane_length_m`` centred on the transceiver, ``lane_spacing_m`` apart going north, all inside
  the USBL's range;
* the sensors, navigator, guidance and autopilot are those of ``mission/survey`` (the same
  configuration classes and defaults: compass every tick, log and pressure at 1 Hz, USBL every
  5 s with its travel time and 1 s of latency, the EKF with the current in its state, gated);
  the INS is exact as in the missions;
* the manoeuvring model has no sites: the USBL transponder's lever arm is the configured one
  (default at the reference point), and the transceiver sits at ``transceiver_depth_m`` below
  the origin (the survey's seabed there);
* the current is the sea's (:func:`bauv_sim.currents.make_current`) at each vehicle's position,
  uniform by default; the randomised and gridded kinds are refused (a randomised current would
  need one stream per run, a gridded one a geographic origin).
"""

from __future__ import annotations

import itertools
import math

from pydantic import Field, model_validator

from bauv_sim.autopilot import AutopilotConfig
from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig
from tasks.closed_loop.scenario import NavigationConfig, SurveySensors

MAX_WAYPOINTS = 1000
"""The most way-points a plan may have."""


class PlanConfig(Config):
    """The lawn-mower plan (the same for every run)."""

    lanes: int = Field(11, ge=1, le=MAX_WAYPOINTS // 2, description="east-west lanes")
    lane_length_m: float = Field(300.0, gt=0, le=2000, description="length of a lane, m")
    lane_spacing_m: float = Field(30.0, gt=0, le=2000, description="between lanes, m")
    depth_m: float = Field(3.0, ge=0, le=100, description="depth of every leg, m")
    acceptance_radius_m: float = Field(10.0, gt=0, le=100, description="judged horizontally, m")


class StartConfig(Config):
    """Where every run starts (dived, at the first lane's west end, heading east)."""

    depth_m: float = Field(3.0, ge=0, le=100)
    heading_deg: float = Field(90.0, ge=0, lt=360)
    speed_m_s: float = Field(0.8, ge=0, le=2)
    position_sigma_m: float = Field(
        2.0, ge=0, description="scatter of the true start about the nominal one, per axis, m"
    )
    heading_sigma_deg: float = Field(5.0, ge=0, description="scatter of the true heading, deg")


class FleetSensors(SurveySensors):
    """The vehicle's sensors (defaults: ``mission/survey``'s four devices)."""


class FleetGuidance(Config):
    """How the way-points are flown (transit legs of :mod:`nav.guidance`)."""

    speed_m_s: float = Field(1.0, gt=0, le=2, description="cruise speed through water, m/s")
    max_leg_time_s: float = Field(900.0, gt=0, description="a leg taking longer is missed, s")
    reach_probability: float = Field(
        0.95, gt=0, lt=1, description="a way-point is reached when the truth is inside its circle "
        "with this probability given the estimate (see nav.guidance)",
    )  # fmt: skip
    min_reach_m: float = Field(1.0, gt=0, description="else pass within this distance, m")


class FleetTiming(Config):
    """Clocks of the batch."""

    control_tick_s: float = Field(
        0.2, gt=0, le=1, description="autopilot, navigation and model step, s"
    )
    substeps: int = Field(2, ge=1, le=20, description="Runge-Kutta substeps per tick")
    max_duration_s: float = Field(
        4500.0, gt=0, le=86_400, description="every run is stopped after, s"
    )
    record_every_s: float = Field(
        10.0, gt=0, description="period of the decimated tracks in the run data, s"
    )


class FleetRunner(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int = Field(
        500,
        ge=1,
        le=10_000,
        description="runs per block (vectorised together; the blocks go to the workers)",
    )


class FleetReport(Config):
    """What the report writes."""

    tracks: bool = Field(True, description="write the decimated tracks of every run (Parquet)")


class FleetScenario(Config):
    """Scenario of ``fleet/survey`` (module docstring)."""

    transceiver_depth_m: float = Field(
        6.0, ge=0, le=1000, description="depth of the USBL transceiver below the origin, m"
    )
    plan: PlanConfig = Field(default_factory=PlanConfig)
    start: StartConfig = Field(default_factory=StartConfig)
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.25, direction_deg=60.0)
    )
    sensors: FleetSensors = Field(default_factory=FleetSensors)
    navigation: NavigationConfig = Field(default_factory=NavigationConfig)
    guidance: FleetGuidance = Field(default_factory=FleetGuidance)
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)
    timing: FleetTiming = Field(default_factory=FleetTiming)
    runner: FleetRunner = Field(default_factory=FleetRunner)
    report: FleetReport = Field(default_factory=FleetReport)

    @model_validator(mode="after")
    def _check(self) -> FleetScenario:
        tick = self.timing.control_tick_s
        s = self.sensors
        for name in ("compass", "log", "pressure", "usbl"):
            period = getattr(s, name).period_s
            k = period / tick
            if abs(k - round(k)) > 1e-9 or round(k) < 1:
                raise ValueError(
                    f"sensors.{name}.period_s = {period:g}: must be a whole number of control "
                    f"ticks ({tick:g} s)"
                )
        if abs(s.compass.period_s - tick) > 1e-9:
            raise ValueError(
                f"sensors.compass.period_s = {s.compass.period_s:g}: the autopilot reads it "
                f"every control tick ({tick:g} s)"
            )
        r = self.timing.record_every_s / tick
        if abs(r - round(r)) > 1e-9 or round(r) < 1:
            raise ValueError(
                f"timing.record_every_s = {self.timing.record_every_s:g}: must be a whole number "
                f"of control ticks ({tick:g} s)"
            )
        if self.current.kind not in ("uniform", "shear", "gyre"):
            raise ValueError(
                f"current.kind = {self.current.kind!r}: fleet/survey takes 'uniform', 'shear' "
                "or 'gyre' (a randomised current would need a stream per run, a gridded one a "
                "geographic origin)"
            )
        u = s.usbl
        latency = u.max_range_m / u.sound_speed_m_s + u.processing_delay_s
        if latency >= u.period_s:
            raise ValueError(
                f"sensors.usbl.processing_delay_s = {u.processing_delay_s:g}: the latency of a "
                f"fix (up to {latency:g} s at max_range_m) must be shorter than period_s = "
                f"{u.period_s:g} s (one fix in flight at a time)"
            )
        if latency > self.navigation.history_s:
            raise ValueError(
                f"navigation.history_s = {self.navigation.history_s:g}: shorter than the USBL's "
                f"latency (up to {latency:g} s)"
            )
        return self

    def waypoints(self) -> list[tuple[float, float]]:
        """The plan's way-points (east, north), m: lanes alternately east and west, starting
        at the first lane's east end (the start is its west end)."""
        p = self.plan
        half = 0.5 * p.lane_length_m
        north0 = -0.5 * p.lane_spacing_m * (p.lanes - 1)
        out = [(half, north0)]
        for i in range(1, p.lanes):
            north = north0 + i * p.lane_spacing_m
            east = out[-1][0]
            out += [(east, north), (-east, north)]
        return out

    def start_east_north_m(self) -> tuple[float, float]:
        """The nominal start: the first lane's west end, m."""
        p = self.plan
        return -0.5 * p.lane_length_m, -0.5 * p.lane_spacing_m * (p.lanes - 1)

    def plan_length_m(self) -> float:
        """Length of the planned track from the start, m."""
        pts = [self.start_east_north_m(), *self.waypoints()]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(pts))
