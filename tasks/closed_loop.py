"""Closed-loop way-point missions in the physics world: the product's main job.

The BAUV swims in MuJoCo under a modelled current. At every control tick its sensors are sampled
from the true physical motion (with the shared error vocabulary and their own streams), the
navigator predicts its estimate from the measured heading and speed through water and corrects it
with pressure depth, USBL fixes (applied at their time of validity, however late they arrive) and
GPS fixes at the surface; guidance turns the *estimate* (or, for comparison, the dead-reckoned
position) into a desired course, depth and speed; the onboard pilot (the autopilot) turns those
and the measurements into motor, tail-bias, lateral-fin and battery commands.

In dm_control terms (``control.Task`` + ``control.Environment``, like the suite's domains):

* :class:`MissionTask` owns the mission's world side: sensors, navigator, guidance; its
  observation is the vehicle's measurements, the navigation estimate and the guidance command;
* :class:`Pilot` is the policy: observation -> action (the five actuator settings);
* the environment steps the physics ``steps_per_tick`` times per action.

Mission modules (``tasks/mission_*.py``) register :class:`MissionExperiment` instances with their
way-points and settings; everything else is here.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal

import numpy as np
from dm_control.rl import control
from dm_env import specs
from numpy.typing import NDArray
from pydantic import BaseModel, Field, model_validator

from bauv_sim import rng as rng_mod
from bauv_sim.autopilot import Autopilot, AutopilotConfig, Measured
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig, make_current
from bauv_sim.errors import BauvSimError, ConfigError, PhysicsError
from bauv_sim.frames import R_from_roll_pitch_heading
from bauv_sim.hydro import load_speed_table
from bauv_sim.seabed import SeabedConfig
from bauv_sim.sensors import (
    AngleErrorConfig,
    Compass,
    CompassConfig,
    Gps,
    GpsConfig,
    LengthErrorConfig,
    Log,
    LogConfig,
    Odometry,
    OdometryConfig,
    Pressure,
    PressureConfig,
    SpeedErrorConfig,
    Usbl,
    UsblConfig,
    check_multiple,
)
from bauv_sim.truth import Truth
from nav.errors import NavError, NavInputError
from nav.guidance import GuidanceCommand, Waypoint, WaypointGuidance
from nav.models import (
    CourseSpeedDepthMotion,
    DepthMeasurement,
    HorizontalPositionMeasurement,
    UsblMeasurement,
)
from nav.navigator import Navigator
from tasks.core import store
from tasks.registry import Experiment, ReportContext, ReportSummary

MODES = ("transit", "ascend", "surface", "dive", "done")

# ----------------------------------------------------------------------------------------------
# Scenario


class WaypointConfig(Config):
    """A way-point of the mission."""

    east_m: float
    north_m: float
    depth_m: float = Field(3.0, ge=0, description="depth of the leg ending here, m")
    acceptance_radius_m: float = Field(8.0, gt=0, description="judged horizontally, m")
    surface: bool = Field(False, description="surface here for a GPS fix")


class StartConfig(Config):
    """Where the vehicle starts (after a GNSS fix at the surface, already dived)."""

    east_m: float = 0.0
    north_m: float = 0.0
    depth_m: float = Field(3.0, ge=0)
    heading_deg: float = Field(0.0, ge=0, lt=360)
    speed_m_s: float = Field(0.8, ge=0, le=2)
    position_sigma_m: float = Field(
        2.0, ge=0, description="scatter of the true start about the nominal one, per axis, m"
    )
    heading_sigma_deg: float = Field(5.0, ge=0, description="scatter of the true heading, deg")


class MissionSensors(Config):
    """The vehicle's sensors (defaults: the seeds' devices, gaussian errors)."""

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
    gps: GpsConfig = Field(default_factory=GpsConfig, description="GPS at the surface")
    odometry: OdometryConfig = Field(
        default_factory=lambda: OdometryConfig(period_s=1.0),
        description="speed from the tail-beat setting; an empty table is the model's speed table",
    )
    use_usbl: bool = Field(True, description="give USBL fixes to the navigator")
    use_gps: bool = Field(True, description="give GPS fixes to the navigator")
    use_log: bool = Field(True, description="the vehicle has a log (else odometry speed)")


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


class TimingConfig(Config):
    """Clocks of the mission."""

    control_tick_s: float = Field(0.2, gt=0, description="autopilot and navigation tick, s")
    max_duration_s: float = Field(2400.0, gt=0, description="the mission is stopped after, s")


class FaultConfig(Config):
    """Injected faults, for testing that failures are reported."""

    physics_nan_at_s: float | None = Field(None, ge=0, description="corrupt the physics at t")
    physics_nan_runs: tuple[int, ...] = Field((), description="runs that get the fault")


class MissionReportConfig(Config):
    """What the report writes."""

    recording: bool = True
    figures: bool = True
    record_run: int = Field(0, ge=0)


class MissionScenario(Config):
    """Scenario of a closed-loop way-point mission."""

    seabed: SeabedConfig = Field(default_factory=SeabedConfig)
    transceiver_east_m: float = 0.0
    transceiver_north_m: float = 0.0
    start: StartConfig = Field(default_factory=StartConfig)
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.25, direction_deg=60.0)
    )
    sensors: MissionSensors = Field(default_factory=MissionSensors)
    navigation: NavigationConfig = Field(default_factory=NavigationConfig)
    guidance: GuidanceConfig = Field(
        default_factory=lambda: GuidanceConfig(waypoints=(WaypointConfig(east_m=0, north_m=50),))
    )
    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)
    timing: TimingConfig = Field(default_factory=TimingConfig)
    faults: FaultConfig = Field(default_factory=FaultConfig)
    report: MissionReportConfig = Field(default_factory=MissionReportConfig)

    @model_validator(mode="after")
    def _check(self) -> MissionScenario:
        tick = self.timing.control_tick_s
        check_multiple(tick, 0.002, "timing.control_tick_s")
        s = self.sensors
        for name in ("compass", "log", "pressure", "usbl", "gps"):
            check_multiple(getattr(s, name).period_s, tick, f"sensors.{name}.period_s")
        check_multiple(s.odometry.period_s, tick, "sensors.odometry.period_s")
        if abs(s.compass.period_s - tick) > 1e-9:
            raise ValueError(
                f"sensors.compass.period_s = {s.compass.period_s:g}: the heading is sampled "
                f"every control tick ({tick:g} s)"
            )
        return self


# ----------------------------------------------------------------------------------------------
# The task


@dataclass
class _Log:
    """Per-tick record of a mission, turned into arrays at the end."""

    rows: dict[str, list] = field(default_factory=lambda: collections.defaultdict(list))

    def add(self, **kw: Any) -> None:
        for k, v in kw.items():
            self.rows[k].append(v)

    def arrays(self) -> dict[str, NDArray]:
        return {k: np.asarray(v) for k, v in self.rows.items()}


_I0 = np.zeros(1, dtype=np.intp)


def _truth_record(vt, t_s: float) -> Truth:
    """One-sample truth record from the physics (run axis 1)."""
    return Truth(
        t_s=np.array([t_s]),
        pos_world_m=vt.position_world_m[None, None],
        vel_ground_world_m_s=vt.velocity_world_m_s[None, None],
        vel_water_world_m_s=vt.velocity_through_water_world_m_s[None, None],
        heading_rad=np.array([[vt.roll_pitch_heading_rad[2]]]),
        roll_pitch_rad=vt.roll_pitch_heading_rad[None, None, :2],
        current_world_m_s=vt.current_world_m_s[None, None],
    )


class MissionTask(control.Task):
    """The world side of a mission (see the module docstring).

    Args:
        scenario: the mission scenario.
        seed: batch seed.
        run: run index (its streams: start, current, every sensor, initial estimate).
        speed_table: the vehicle's speed calibration (for odometry and the pilot).
    """

    def __init__(self, scenario: MissionScenario, seed: int, run: int, speed_table) -> None:
        super().__init__()
        self.scn = scenario
        self.seed = seed
        self.run = run
        self.speed_table = speed_table
        self.log = _Log()
        self.fixes: list[dict[str, Any]] = []

    # -- dm_control interface ------------------------------------------------------------------

    ACTIONS = (
        "tail_beat_frequency_hz",
        "tail_bias_rad",
        "fin_port_rad",
        "fin_starboard_rad",
        "battery_position_m",
    )
    """The action vector, in the physics setters' units."""

    def action_spec(self, physics) -> specs.BoundedArray:
        lim = physics.command_limits()
        lo = [lim[k][0] for k in self.ACTIONS]
        hi = [lim[k][1] for k in self.ACTIONS]
        return specs.BoundedArray((5,), np.float64, lo, hi, name="actuators")

    def initialize_episode(self, physics) -> None:
        scn, seed, run = self.scn, self.seed, self.run
        tick = scn.timing.control_tick_s
        physics.set_control_tick(tick)
        g = rng_mod.generator(seed, run, "start")
        st = scn.start
        pos = np.array([st.east_m, st.north_m, -st.depth_m])
        pos[:2] += st.position_sigma_m * g.standard_normal(2)
        heading = (
            math.radians(st.heading_deg) + math.radians(st.heading_sigma_deg) * g.standard_normal()
        )
        vel = st.speed_m_s * np.array([math.sin(heading), math.cos(heading), 0.0])
        physics.set_pose(pos, (0.0, 0.0, heading), vel)
        physics.set_current(make_current(scn.current, rng_mod.generator(seed, run, "current")))
        runs = (run,)
        s = scn.sensors
        # lever arms of the antennas from the model's sites (body frame)
        R = physics.R_world_from_body()
        arm = {
            name: tuple(float(c) for c in R.T @ (physics.site_position_world(name) - pos))
            for name in ("gps_antenna", "usbl_transponder")
        }
        if s.gps.antenna_body_m == (0.0, 0.0, 0.0):
            s = s.model_copy(
                update={"gps": s.gps.model_copy(update={"antenna_body_m": arm["gps_antenna"]})}
            )
        if s.usbl.transponder_body_m == (0.0, 0.0, 0.0):
            s = s.model_copy(
                update={
                    "usbl": s.usbl.model_copy(
                        update={"transponder_body_m": arm["usbl_transponder"]}
                    )
                }
            )
        self.sensors_cfg = s
        self.transponder_arm = np.asarray(s.usbl.transponder_body_m, dtype=float)
        self.antenna_arm = np.asarray(s.gps.antenna_body_m, dtype=float)
        self.compass = Compass(s.compass, seed, runs)
        self.compass_needs_course = s.compass.heading.to_model().needs_reference()
        self.log_sensor = Log(s.log, seed, runs)
        self.pressure = Pressure(s.pressure, seed, runs)
        self.gps = Gps(s.gps, seed, runs)
        # deeper than this the antenna is surely under water (its lever arm plus 0.5 m)
        self.gps_depth_limit_m = (
            s.gps.max_antenna_depth_m + 0.5 + float(np.linalg.norm(s.gps.antenna_body_m))
        )
        tx = physics.transceiver_world()
        self.transceiver = tx
        self.usbl = Usbl(s.usbl, tx, seed, runs)
        odo = s.odometry
        if not odo.frequency_hz:
            odo = odo.model_copy(
                update={
                    "frequency_hz": tuple(float(f) for f in self.speed_table.frequency_hz),
                    "speed_m_s": tuple(float(v) for v in self.speed_table.speed_m_s),
                }
            )
        self.odometry = Odometry(odo, seed, runs)
        n = scn.navigation
        self.motion = CourseSpeedDepthMotion(
            math.radians(n.sigma_heading_deg), n.sigma_speed_m_s, n.sigma_vertical_m_per_tick
        )
        self.usbl_model = UsblMeasurement(
            tx,
            n.sigma_range_m,
            math.radians(n.sigma_azimuth_deg),
            math.radians(n.sigma_elevation_deg),
        )
        self.gps_model = HorizontalPositionMeasurement(n.sigma_gps_m)
        self.depth_model = DepthMeasurement(n.sigma_depth_m)
        P0 = np.diag([n.initial_sigma_m**2, n.initial_sigma_m**2, n.sigma_depth_m**2])
        e0 = rng_mod.generator(seed, run, "initial").standard_normal(3) @ np.sqrt(P0)
        self.nav = Navigator(
            0.0,
            pos + e0,
            P0,
            self.motion,
            n.history_s,
            n.gate_probability if n.gate_enabled else None,
            current_sigma0_m_s=n.current_sigma0_m_s if n.estimate_current else None,
            current_walk_m_s_per_sqrt_s=n.current_walk_m_s_per_sqrt_s,
            max_consecutive_rejections=n.max_consecutive_rejections or None,
        )
        gd = scn.guidance
        # surfaced: the GPS antenna out of the water with 5 cm to spare (unless configured)
        antenna_height = s.gps.antenna_body_m[2]
        surface_depth = (
            gd.surface_depth_m
            if gd.surface_depth_m is not None
            else max(antenna_height - 0.05, 0.0)
        )
        self.guidance = WaypointGuidance(
            [
                Waypoint(w.east_m, w.north_m, w.depth_m, w.acceptance_radius_m, w.surface)
                for w in gd.waypoints
            ],
            speed_m_s=gd.speed_m_s,
            surface_speed_m_s=gd.surface_speed_m_s,
            surface_depth_m=surface_depth,
            hold_s=gd.hold_s,
            fixes_needed=gd.fixes_needed,
            max_leg_time_s=gd.max_leg_time_s,
            reach_probability=gd.reach_probability,
            min_reach_m=gd.min_reach_m,
        )
        self.every = {name: round(getattr(s, name).period_s / tick) for name in ("usbl", "gps")}
        self.every["odometry"] = round(odo.period_s / tick)
        self.every["log"] = round(s.log.period_s / tick)
        self.every["pressure"] = round(s.pressure.period_s / tick)
        self.k = 0
        self.pending: list[tuple[float, float, NDArray[np.float64]]] = []
        self.last_action = np.zeros(5)
        self.meas: dict[str, float] = {}
        self._setup(physics)
        self._sense(physics, initial=True)

    def before_step(self, action, physics) -> None:
        a = np.asarray(action, dtype=float)
        self.last_action = a
        physics.set_tail_beat_frequency_hz(float(a[0]))
        physics.set_tail_bias_rad(float(a[1]))
        physics.set_lateral_fins_rad(float(a[2]), float(a[3]))
        physics.set_battery_position_m(float(a[4]))
        physics.apply_environment()
        f = self.scn.faults
        if (
            f.physics_nan_at_s is not None
            and self.run in f.physics_nan_runs
            and physics.time_s() >= f.physics_nan_at_s
        ):
            physics.inject_fault()

    def after_step(self, physics) -> None:
        self.k += 1
        self._sense(physics)

    def get_observation(self, physics) -> collections.OrderedDict:
        est = self.nav.estimate
        cmd = self.command
        m = self.meas
        return collections.OrderedDict(
            heading=np.array([m["heading"]]),
            yaw_rate=np.array([m["yaw_rate"]]),
            depth=np.array([m["depth"]]),
            pitch=np.array([m["pitch"]]),
            pitch_rate=np.array([m["pitch_rate"]]),
            roll=np.array([m["roll"]]),
            roll_rate=np.array([m["roll_rate"]]),
            speed=np.array([m["speed"]]),
            estimate=est.x,
            estimate_std=np.sqrt(np.diag(est.P)),
            dr=self.nav.dr_position,
            command=np.array([cmd.course_rad, cmd.depth_m, cmd.speed_m_s]),
            mode=np.array([MODES.index(cmd.mode)]),
        )

    def get_reward(self, physics) -> float:
        return 0.0

    def get_termination(self, physics) -> float | None:
        return 0.0 if self.guidance.done else None

    # -- the mission's world side --------------------------------------------------------------

    def _sense(self, physics, initial: bool = False) -> None:
        """Sample the sensors due now, run the navigator, ask guidance (see the module)."""
        t = physics.time_s()
        k = self.k
        vt = physics.truth()
        tr = None  # the full truth record, built only when a device needs it
        rph = vt.roll_pitch_heading_rad
        tt = np.array([t])
        course = None
        if self.compass_needs_course:
            v = vt.velocity_world_m_s
            course = np.array([[math.atan2(v[0], v[1]) % (2 * math.pi)]])
        heading = float(self.compass.measure(np.array([[rph[2]]]), tt, course)[0][0, 0])
        # log, odometry and pressure: sampled at their own rates, held in between
        if k % self.every["log"] == 0:
            cp = math.cos(rph[1])
            vw = vt.velocity_through_water_world_m_s
            u_fwd = (
                cp * math.sin(rph[2]) * vw[0]
                + cp * math.cos(rph[2]) * vw[1]
                + math.sin(rph[1]) * vw[2]
            )
            value, ok = self.log_sensor.measure(np.array([[u_fwd]]), tt)
            self.log_speed = float(value[0, 0]) if self.scn.sensors.use_log and ok[0, 0] else None
        if k % self.every["odometry"] == 0:
            odo = self.odometry.sample(tt, np.array([[float(self.last_action[0])]]))
            self.odo_speed = float(odo.values[0, 0])
        speed, speed_src = (
            (self.log_speed, "log") if self.log_speed is not None else (self.odo_speed, "odometry")
        )
        depth_due = k % self.every["pressure"] == 0
        if depth_due:
            self.depth_meas = float(self.pressure.measure(np.array([[vt.depth_m]]), tt)[0][0, 0])
        depth = self.depth_meas
        w = vt.angular_velocity_body_rad_s
        # INS attitude and rates taken as exact (0.1-deg class, negligible for the loops)
        self.meas = {
            "heading": heading,
            "yaw_rate": -float(w[2]),
            "depth": depth,
            "pitch": float(rph[1]),
            "pitch_rate": -float(w[1]),
            "roll": float(rph[0]),
            "roll_rate": float(w[0]),
            "speed": speed,
        }
        nav = self.nav
        if not initial:
            self._predict(t, heading, speed)
        if depth_due:
            nav.update(self.depth_model, np.array([depth]))
        usbl_used = gps_used = False
        if not initial and self.scn.sensors.use_usbl and k % self.every["usbl"] == 0:
            tr = _truth_record(vt, t)
            u = self.usbl.sample(tr, _I0)
            if u.produced[0, 0]:
                # the transponder's lever arm in the world from the vehicle's own attitude
                # (measured heading, INS roll and pitch) at the time of validity
                R = R_from_roll_pitch_heading(rph[0], rph[1], heading)
                model = dataclasses.replace(
                    self.usbl_model, transceiver_world_m=self.transceiver - R @ self.transponder_arm
                )
                self.pending.append((float(u.t_arrival_s[0, 0]), t, u.values[0, 0], model))
        still = []
        for t_arr, t_valid, z, model in self.pending:
            if t_arr > t + 1e-9:
                still.append((t_arr, t_valid, z, model))
                continue
            try:
                info = nav.update(model, z, t_valid)
                accepted = not bool(info.rejected[0])
            except NavInputError:
                accepted = False
            self.fixes.append(
                {
                    "kind": "usbl",
                    "t_valid_s": t_valid,
                    "t_arrival_s": t,
                    "z": z.tolist(),
                    "accepted": accepted,
                    "position": model.invert(z).tolist(),
                }
            )
            usbl_used = True
        self.pending = still
        if not initial and vt.depth_m > self.gps_depth_limit_m:
            self.gps.submerged()  # the antenna cannot be out of the water: skip the sampling
        elif not initial and k % self.every["gps"] == 0:
            tr = tr or _truth_record(vt, t)
            gfix = self.gps.sample(tr, _I0)
            if gfix.produced[0, 0]:
                z = gfix.values[0, 0]
                # the antenna's horizontal lever arm from the vehicle's own attitude
                arm_world = R_from_roll_pitch_heading(rph[0], rph[1], heading) @ self.antenna_arm
                accepted = self._gps_fix(t, z - arm_world[:2])
                self.guidance.gps_fix()
                self.fixes.append(
                    {
                        "kind": "gps",
                        "t_valid_s": t,
                        "t_arrival_s": t,
                        "z": z.tolist(),
                        "accepted": accepted,
                        "position": [float(z[0]), float(z[1]), 0.0],
                    }
                )
                gps_used = True
        est = nav.estimate
        self.command = self._steer(t, est)
        cmds = physics.commands()
        cur = nav.current_estimate
        self.log.add(
            current_est=np.full(2, np.nan) if cur is None else cur[0],
            t=t,
            truth=vt.position_world_m,
            quat=vt.quat_wxyz,
            rph=rph,
            vel=vt.velocity_world_m_s,
            vel_water=vt.velocity_through_water_world_m_s,
            current=vt.current_world_m_s,
            ekf=est.x,
            P=est.P,
            dr=nav.dr_position,
            heading_meas=heading,
            depth_meas=depth,
            speed_meas=speed,
            speed_from_log=speed_src == "log",
            power=physics.motor_power_w(),
            freq=cmds["tail_beat_frequency_hz"],
            bias=cmds["tail_bias_rad"],
            fin_port=cmds["fin_port_rad"],
            fin_stbd=cmds["fin_starboard_rad"],
            battery=cmds["battery_position_m"],
            course_cmd=self.command.course_rad,
            depth_cmd=self.command.depth_m,
            speed_cmd=self.command.speed_m_s,
            mode=MODES.index(self.command.mode),
            waypoint=self.command.waypoint,
            usbl_event=usbl_used,
            gps_event=gps_used,
            **self._extra_log(),
        )

    # -- hooks of the world side (a mission module may override them) ---------------------------

    def _setup(self, physics) -> None:
        """Called at the end of :meth:`initialize_episode`, before the first sensing."""

    def _predict(self, t: float, heading: float, speed: float) -> None:
        """Time update of the navigation from the measured heading and speed."""
        self.nav.predict(t, heading, speed, 0.0)

    def _gps_fix(self, t: float, z_ref: NDArray[np.float64]) -> bool:
        """A GPS fix of the reference point (antenna lever arm removed); returns whether the
        navigator accepted it."""
        if not self.scn.sensors.use_gps:
            return True
        return not bool(self.nav.update(self.gps_model, z_ref).rejected[0])

    def _steer(self, t: float, est) -> GuidanceCommand:
        """Guidance on the estimate the scenario says (EKF with its uncertainty, or DR)."""
        if self.scn.navigation.steer_on == "ekf":
            p_h = est.P[:2, :2]
            tr_h, det_h = p_h[0, 0] + p_h[1, 1], p_h[0, 0] * p_h[1, 1] - p_h[0, 1] ** 2
            sigma = math.sqrt(max(0.5 * tr_h + math.sqrt(max(0.25 * tr_h**2 - det_h, 0.0)), 0.0))
            return self.guidance.step(t, est.x, sigma)
        # dead reckoning carries no covariance here: the bare acceptance circle
        return self.guidance.step(t, self.nav.dr_position)

    def _extra_log(self) -> dict[str, Any]:
        """Additional per-tick columns of a mission module."""
        return {}


class Pilot:
    """The onboard autopilot as a policy: observation -> action (see :class:`MissionTask`).

    Args:
        cfg: autopilot gains.
        speed_table: speed calibration for the speed feed-forward.
        tick_s: control tick, s.
        action_spec: the task's action bounds.
    """

    def __init__(
        self, cfg: AutopilotConfig, speed_table, tick_s: float, action_spec: specs.BoundedArray
    ):
        self.ap = Autopilot(
            cfg, functools.lru_cache(maxsize=128)(lambda v: float(speed_table.frequency_for(v)))
        )
        self.tick_s = tick_s
        self.lo, self.hi = action_spec.minimum, action_spec.maximum

    def __call__(self, obs: collections.OrderedDict) -> NDArray[np.float64]:
        m = Measured(
            float(obs["heading"][0]),
            float(obs["yaw_rate"][0]),
            float(obs["depth"][0]),
            float(obs["pitch"][0]),
            float(obs["pitch_rate"][0]),
            float(obs["roll"][0]),
            float(obs["roll_rate"][0]),
            float(obs["speed"][0]),
        )
        course, depth, speed = (float(v) for v in obs["command"])
        c = self.ap.step(self.tick_s, course, depth, speed, m)
        a = np.array(
            [c.tail_beat_hz, c.tail_bias_rad, c.fin_port_rad, c.fin_starboard_rad, c.battery_m]
        )
        return np.clip(a, self.lo, self.hi)


# ----------------------------------------------------------------------------------------------
# Running a mission


@store.plain_data("closed_loop.MissionRun")
@dataclass
class MissionRun:
    """The outcome of one mission run.

    Attributes:
        run: run index.
        seed: batch seed.
        failed: ``None``, or what failed, when and why (the run's seed is in ``seed``/``run``).
        arrays: per-tick records (``t``, ``truth``, ``ekf``, ``P``, ``dr``, ...), or empty.
        fixes: USBL and GPS fixes as delivered to the navigator.
        waypoints: per way-point: closest true horizontal approach (m), reached by the estimate,
            time the leg ended.
        summary: scalar results (errors, duration, energy, fix counts).
    """

    run: int
    seed: int
    failed: str | None
    arrays: dict[str, NDArray] = field(default_factory=dict)
    fixes: list[dict[str, Any]] = field(default_factory=list)
    waypoints: list[dict[str, Any]] = field(default_factory=list)
    summary: dict[str, float] = field(default_factory=dict)
    task: Any = field(default=None, repr=False, compare=False, metadata=store.NOT_STORED)

    def __getstate__(self) -> dict[str, Any]:
        # the finished task (physics, streams) stays in the worker: only results travel
        return {**self.__dict__, "task": None}


def make_environment(
    scn: MissionScenario, seed: int, run: int, task_type: type[MissionTask] | None = None
) -> control.Environment:
    """Build the physics, the task (``task_type``, default :class:`MissionTask`) and the
    dm_control environment of one mission run."""
    st = scn.start
    scene = SceneConfig(
        vehicles=(
            VehicleSpec(
                name="bauv",
                east_m=st.east_m,
                north_m=st.north_m,
                depth_m=st.depth_m,
                heading_deg=st.heading_deg,
            ),
        ),
        seabed=scn.seabed,
        transceiver_east_m=scn.transceiver_east_m,
        transceiver_north_m=scn.transceiver_north_m,
    )
    physics = build_physics(scene, control_tick_s=scn.timing.control_tick_s)
    task = (task_type or MissionTask)(scn, seed, run, load_speed_table())
    return control.Environment(
        physics,
        task,
        time_limit=scn.timing.max_duration_s,
        n_sub_steps=physics.steps_per_tick,
        flat_observation=False,
    )


def run_mission(
    scn: MissionScenario,
    seed: int,
    run: int,
    keep_arrays: bool = True,
    task_type: type[MissionTask] | None = None,
) -> MissionRun:
    """Fly one mission run to its end, its time limit, or a failure.

    A physics or navigation failure does not raise: it is returned in :attr:`MissionRun.failed`
    with the simulation time, so that a Monte Carlo batch completes.

    Args:
        scn: the scenario.
        seed: batch seed.
        run: run index.
        keep_arrays: keep the per-tick records (for recordings and figures).
        task_type: the task class (a mission module's subclass of :class:`MissionTask`).

    Returns:
        The run's outcome (``task`` holds the finished task for the caller's own metrics; it is
        not stored).
    """
    env = make_environment(scn, seed, run, task_type)
    task: MissionTask = env.task
    ts = env.reset()
    pilot = Pilot(scn.autopilot, task.speed_table, scn.timing.control_tick_s, env.action_spec())
    failed = None
    try:
        while not ts.last():
            ts = env.step(pilot(ts.observation))
    except (PhysicsError, NavError, BauvSimError) as exc:
        t = env.physics.time_s()
        failed = f"run {run} (seed {seed}) failed at t = {t:.2f} s: {type(exc).__name__}: {exc}"
    arrays = task.log.arrays()
    result = _summarise(scn, seed, run, failed, arrays, task, keep_arrays)
    result.task = task
    return result


def _summarise(scn, seed, run, failed, a, task, keep_arrays) -> MissionRun:
    t = a["t"]
    truth, ekf, dr = a["truth"], a["ekf"], a["dr"]
    e_ekf = np.hypot(*(ekf - truth)[:, :2].T)
    e_dr = np.hypot(*(dr - truth)[:, :2].T)
    wps = []
    legs = {leg.waypoint: leg for leg in task.guidance.legs}
    for i, w in enumerate(scn.guidance.waypoints):
        d = np.hypot(truth[:, 0] - w.east_m, truth[:, 1] - w.north_m)
        j = int(np.argmin(d))
        leg = legs.get(i)
        wps.append(
            {
                "index": i,
                "east_m": w.east_m,
                "north_m": w.north_m,
                "acceptance_radius_m": w.acceptance_radius_m,
                "closest_true_distance_m": float(d[j]),
                "closest_at_s": float(t[j]),
                "reached_by_truth": bool(d[j] <= w.acceptance_radius_m),
                "reached_by_estimate": bool(leg.reached) if leg else False,
                "leg_end_s": float(leg.t_s) if leg else None,
            }
        )
    usbl = [f for f in task.fixes if f["kind"] == "usbl"]
    gps = [f for f in task.fixes if f["kind"] == "gps"]
    dt = np.diff(t, prepend=t[0])
    summary = {
        "duration_s": float(t[-1]),
        "completed": float(task.guidance.done),
        "ekf_mean_error_m": float(e_ekf.mean()),
        "ekf_max_error_m": float(e_ekf.max()),
        "ekf_final_error_m": float(e_ekf[-1]),
        "dr_mean_error_m": float(e_dr.mean()),
        "dr_max_error_m": float(e_dr.max()),
        "dr_final_error_m": float(e_dr[-1]),
        "usbl_fixes": float(len(usbl)),
        "usbl_rejected": float(sum(not f["accepted"] for f in usbl)),
        "gps_fixes": float(len(gps)),
        "energy_j": float(np.sum(a["power"] * dt)),
        "mean_power_w": float(np.mean(a["power"])),
        "waypoints_reached_by_truth": float(sum(w["reached_by_truth"] for w in wps)),
        "max_closest_distance_m": float(max(w["closest_true_distance_m"] for w in wps)),
    }
    return MissionRun(run, seed, failed, a if keep_arrays else {}, task.fixes, wps, summary)


# ----------------------------------------------------------------------------------------------
# Metrics, report, figures and recording


class WaypointResult(BaseModel):
    """One way-point of one run."""

    index: int
    east_m: float
    north_m: float
    acceptance_radius_m: float
    closest_true_distance_m: float = Field(description="closest true horizontal approach, m")
    closest_at_s: float
    reached_by_truth: bool = Field(description="the true track entered the acceptance circle")
    reached_by_estimate: bool = Field(description="guidance saw the estimate inside it")
    leg_end_s: float | None


class RunResult(BaseModel):
    """One run of a mission batch."""

    run: int
    failed: str | None
    summary: dict[str, float]
    waypoints: list[WaypointResult]


class Aggregate(BaseModel):
    """A summary value over the successful runs."""

    mean: float
    min: float
    max: float


class MissionMetrics(BaseModel):
    """``metrics.json`` of a ``mission/*`` batch (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    failures: list[str]
    steer_on: str
    all_waypoints_reached_by_truth: bool = Field(
        description="every way-point of every successful run reached, judged by truth"
    )
    aggregate: dict[str, Aggregate]
    runs: list[RunResult]


@dataclass(frozen=True)
class MissionExperiment(Experiment):
    """A registered closed-loop mission (one run per block)."""

    scenario_type = MissionScenario
    metrics_type = MissionMetrics
    task_type: ClassVar[type[MissionTask]] = MissionTask
    """The task class a run flies (a mission module may extend the world side)."""

    def flight_scenario(self, scenario: MissionScenario, seed: int, run: int) -> MissionScenario:
        """The scenario one run flies (a mission module may make it per run)."""
        return scenario

    def check(self, scenario: MissionScenario, n_runs: int) -> None:
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )

    def run_block(self, scenario: MissionScenario, seed: int, runs: tuple[int, ...]):
        out = []
        for r in runs:
            res = run_mission(
                self.flight_scenario(scenario, seed, r),
                seed,
                r,
                keep_arrays=True,
                task_type=self.task_type,
            )
            if r != scenario.report.record_run:
                res.arrays = _thin(res.arrays)
            out.append(res)
        return out

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_mission(self, ctx)


def _thin(a: dict[str, NDArray], every_s: float = 5.0) -> dict[str, NDArray]:
    """Keep the tracks of a run every ``every_s`` seconds (for multi-run route figures)."""
    if not a:
        return {}
    t = a["t"]
    step = max(1, round(every_s / max(float(t[1] - t[0]), 1e-9))) if len(t) > 1 else 1
    return {k: a[k][::step] for k in ("t", "truth", "ekf", "dr")}


def report_mission(exp: MissionExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables, metrics, figures and the recording of a mission batch."""
    from tasks.report import Table, write_metrics, write_tables

    scn: MissionScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[MissionRun] = [r for block in ctx.blocks for r in block]
    ok = [r for r in runs if r.failed is None]
    failures = [r.failed for r in runs if r.failed is not None]
    keys = list(ok[0].summary) if ok else []
    agg = {
        k: Aggregate(
            mean=float(np.mean([r.summary[k] for r in ok])),
            min=float(np.min([r.summary[k] for r in ok])),
            max=float(np.max([r.summary[k] for r in ok])),
        )
        for k in keys
    }
    metrics = MissionMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=len(failures),
        failures=failures,
        steer_on=scn.navigation.steer_on,
        all_waypoints_reached_by_truth=bool(ok)
        and all(w["reached_by_truth"] for r in ok for w in r.waypoints),
        aggregate=agg,
        runs=[
            RunResult(
                run=r.run,
                failed=r.failed,
                summary=r.summary,
                waypoints=[WaypointResult(**w) for w in r.waypoints],
            )
            for r in runs
        ],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    rec_run = next((r for r in runs if r.run == scn.report.record_run), None)
    tables = []
    if rec_run is not None and rec_run.failed is None:
        tables.append(
            Table(
                f"Way-points of run {rec_run.run} (steering on {scn.navigation.steer_on.upper()}), "
                "judged by truth",
                [
                    "Way-point",
                    "East (m)",
                    "North (m)",
                    "Radius (m)",
                    "Closest true distance (m)",
                    "Reached (truth)",
                    "Reached (estimate)",
                ],
                [
                    [
                        w["index"],
                        w["east_m"],
                        w["north_m"],
                        w["acceptance_radius_m"],
                        w["closest_true_distance_m"],
                        "yes" if w["reached_by_truth"] else "NO",
                        "yes" if w["reached_by_estimate"] else "no",
                    ]
                    for w in rec_run.waypoints
                ],
                slug="waypoints",
            )
        )
    rows = []
    for name, key in [("EKF", "ekf"), ("DR", "dr")]:
        rows.append(
            [name]
            + [agg[f"{key}_{s}_error_m"].mean if agg else None for s in ("mean", "max", "final")]
        )
    tables.append(
        Table(
            f"Horizontal navigation error over {len(ok)} successful run(s) (mean over runs)",
            ["Method", "Mean error (m)", "Max error (m)", "Final error (m)"],
            rows,
            slug="errors",
            note=(
                f"Guidance steered on {scn.navigation.steer_on.upper()}. USBL fixes per run: "
                f"{agg['usbl_fixes'].mean:.0f} ({agg['usbl_rejected'].mean:.1f} rejected by the "
                f"gate); GPS fixes: {agg['gps_fixes'].mean:.0f}; mission time "
                f"{agg['duration_s'].mean:.0f} s; motor energy {agg['energy_j'].mean / 1e3:.1f} kJ."
                if agg
                else "No successful run."
            ),
        )
    )
    tables.append(
        Table(
            "Runs",
            [
                "Run",
                "Status",
                "Way-points reached (truth)",
                "Worst closest approach (m)",
                "EKF mean error (m)",
                "DR mean error (m)",
                "Duration (s)",
            ],
            [
                [
                    r.run,
                    "ok" if r.failed is None else "FAILED",
                    f"{int(r.summary['waypoints_reached_by_truth'])}/{len(r.waypoints)}"
                    if r.summary
                    else "-",
                    r.summary.get("max_closest_distance_m"),
                    r.summary.get("ekf_mean_error_m"),
                    r.summary.get("dr_mean_error_m"),
                    r.summary.get("duration_s"),
                ]
                for r in runs
            ],
            slug="runs",
            note="\n".join(failures),
        )
    )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if rec_run is not None and rec_run.failed is None and rec_run.arrays:
        if scn.report.figures:
            files += mission_figures(exp.name, scn, rec_run, runs, ctx.out_dir)
        if scn.report.recording:
            files.append(record_mission(exp.name, scn, rec_run, ctx.out_dir))
    text = "".join(t.to_text() + "\n" for t in tables)
    if failures:
        text += (
            f"{len(failures)} run(s) failed (the others completed):\n  "
            + "\n  ".join(failures)
            + "\n"
        )
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _circle(cx: float, cy: float, r: float, z: float = 0.0, n: int = 48) -> NDArray[np.float64]:
    a = np.linspace(0, 2 * np.pi, n + 1)
    return np.column_stack([cx + r * np.sin(a), cy + r * np.cos(a), np.full(n + 1, z)])


def mission_figures(
    name: str, scn: MissionScenario, run: MissionRun, runs: list[MissionRun], out
) -> list[str]:
    """Route, errors and vehicle state of the recorded run (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a = run.arrays
    t = a["t"]
    files = []
    fig, ax = plt.subplots(figsize=(8, 7))
    for other in runs:
        if other is not run and other.arrays:
            ax.plot(other.arrays["truth"][:, 0], other.arrays["truth"][:, 1], color="0.7", lw=0.6)
    ax.plot(a["truth"][:, 0], a["truth"][:, 1], "k-", lw=1.4, label="truth")
    ax.plot(a["ekf"][:, 0], a["ekf"][:, 1], color="tab:blue", lw=1, label="EKF")
    ax.plot(a["dr"][:, 0], a["dr"][:, 1], color="tab:red", lw=1, label="DR")
    us = np.array([f["position"] for f in run.fixes if f["kind"] == "usbl"]).reshape(-1, 3)
    if len(us):
        ax.plot(us[:, 0], us[:, 1], ".", color="tab:green", ms=3, alpha=0.6, label="USBL fixes")
    gp = np.array([f["position"] for f in run.fixes if f["kind"] == "gps"]).reshape(-1, 3)
    if len(gp):
        ax.plot(gp[:, 0], gp[:, 1], "x", color="tab:orange", ms=6, label="GPS fixes")
    for w in scn.guidance.waypoints:
        c = _circle(w.east_m, w.north_m, w.acceptance_radius_m)
        ax.plot(c[:, 0], c[:, 1], color="tab:purple", lw=1)
        ax.plot(w.east_m, w.north_m, "+", color="tab:purple")
    ax.plot(scn.transceiver_east_m, scn.transceiver_north_m, "k^", ms=8, label="transceiver")
    cur = a["current"].mean(axis=0)
    span = max(np.ptp(a["truth"][:, 0]), np.ptp(a["truth"][:, 1]), 1.0)
    x0, y0 = a["truth"][:, 0].min(), a["truth"][:, 1].max()
    ax.annotate(
        "",
        xy=(x0 + 0.3 * span * cur[0], y0 + 0.3 * span * cur[1]),
        xytext=(x0, y0),
        arrowprops={"arrowstyle": "->", "color": "tab:cyan", "lw": 2},
    )
    ax.text(x0, y0, f" mean current {np.hypot(*cur[:2]):.2f} m/s", color="tab:cyan", va="bottom")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{name} run {run.run}: steering on {scn.navigation.steer_on.upper()}")
    fig.tight_layout()
    fig.savefig(out / "route.png", dpi=110)
    plt.close(fig)
    files.append("route.png")

    fig, ax = plt.subplots(figsize=(9, 3.8))
    for key, label, color in [("ekf", "EKF", "tab:blue"), ("dr", "DR", "tab:red")]:
        ax.plot(t, np.hypot(*(a[key] - a["truth"])[:, :2].T), color=color, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(f"{name} run {run.run}: distance of the estimates to the truth")
    fig.tight_layout()
    fig.savefig(out / "errors.png", dpi=110)
    plt.close(fig)
    files.append("errors.png")

    fig, axs = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    axs[0].plot(t, -a["truth"][:, 2], "k", label="true depth")
    axs[0].plot(t, a["depth_cmd"], "--", color="tab:purple", label="commanded")
    axs[0].invert_yaxis()
    axs[0].set_ylabel("depth (m)")
    axs[1].plot(t, np.degrees(a["rph"][:, 2]), "k", label="true heading")
    axs[1].plot(t, np.degrees(a["course_cmd"]), "--", color="tab:purple", label="commanded")
    axs[1].set_ylabel("heading (deg)")
    axs[2].plot(t, np.hypot(*a["vel_water"][:, :2].T), label="through water")
    axs[2].plot(t, np.hypot(*a["vel"][:, :2].T), label="over ground")
    axs[2].set_ylabel("speed (m/s)")
    axs[3].plot(t, a["power"], color="tab:orange", lw=0.5)
    axs[3].set_ylabel("motor power (W)")
    axs[3].set_xlabel("time (s)")
    for x in axs:
        x.grid(alpha=0.3)
        x.legend(fontsize=8, loc="upper right") if x.get_legend_handles_labels()[0] else None
    fig.tight_layout()
    fig.savefig(out / "state.png", dpi=110)
    plt.close(fig)
    files.append("state.png")
    return files


def record_mission(name: str, scn: MissionScenario, run: MissionRun, out) -> str:
    """Write ``recording.rrd`` of a mission run (see the module docstring of
    :mod:`tasks.recording`)."""
    import rerun as rr

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from bauv_sim.seabed import generate
    from tasks.recording import COLORS, Recording

    a = run.arrays
    t = a["t"]
    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}")
    r = rec.rec
    # seabed mesh around the mission area
    bed = generate(scn.seabed)
    c = bed.config
    pts = np.array(
        [[w.east_m, w.north_m] for w in scn.guidance.waypoints]
        + [[scn.transceiver_east_m, scn.transceiver_north_m]]
    )
    lo = np.minimum(a["truth"][:, :2].min(axis=0), pts.min(axis=0)) - 60.0
    hi = np.maximum(a["truth"][:, :2].max(axis=0), pts.max(axis=0)) + 60.0
    grid = np.arange(c.n) * c.cell_m - c.half_extent_m
    ix = np.flatnonzero((grid >= lo[0]) & (grid <= hi[0]))
    iy = np.flatnonzero((grid >= lo[1]) & (grid <= hi[1]))
    if len(ix) >= 2 and len(iy) >= 2:
        X, Y = np.meshgrid(grid[ix], grid[iy])
        Z = -bed.depth_m[np.ix_(iy, ix)]
        verts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
        nx = len(ix)
        cells = [
            (i * nx + j, i * nx + j + 1, (i + 1) * nx + j + 1, (i + 1) * nx + j)
            for i in range(len(iy) - 1)
            for j in range(nx - 1)
        ]
        tris = np.array([(q[0], q[1], q[2]) for q in cells] + [(q[0], q[2], q[3]) for q in cells])
        r.log(
            "world/seabed",
            rr.Mesh3D(
                vertex_positions=verts, triangle_indices=tris, albedo_factor=[0.76, 0.70, 0.50, 1.0]
            ),
            static=True,
        )
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, 0.0])
    tx[2] = float(bed.height_world(tx[0], tx[1]))
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    wp = scn.guidance.waypoints
    r.log(
        "world/waypoints",
        rr.Points3D(
            [[w.east_m, w.north_m, -w.depth_m] for w in wp],
            radii=1.0,
            colors=(148, 0, 211),
            labels=[f"WP{i}" for i in range(len(wp))],
        ),
        static=True,
    )
    r.log(
        "world/waypoints/acceptance",
        rr.LineStrips3D(
            [_circle(w.east_m, w.north_m, w.acceptance_radius_m, -w.depth_m) for w in wp],
            colors=(148, 0, 211),
            radii=0.15,
        ),
        static=True,
    )
    # the moving hull
    r.send_columns(
        "world/vehicle",
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Transform3D.columns(
            translation=a["truth"], quaternion=quat_wxyz_to_xyzw(a["quat"])
        ),
    )
    r.log("world/vehicle/hull", rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"), static=True)
    rec.track("truth", t, a["truth"], COLORS["truth"])
    rec.track("ekf", t, a["ekf"], COLORS["ekf"])
    rec.track("dr", t, a["dr"], COLORS["dr"])
    every = max(1, round(1.0 / max(float(t[1] - t[0]), 1e-9)))
    rec.ellipsoids("ekf", t[::every], a["ekf"][::every], a["P"][::every], COLORS["ekf"])
    for kind, color in [("usbl", COLORS["usbl"]), ("gps", COLORS["gps"])]:
        fx = [f for f in run.fixes if f["kind"] == kind]
        if fx:
            rec.fixes(
                kind,
                np.array([f["t_arrival_s"] for f in fx]),
                np.array([f["position"] for f in fx]),
                color,
            )
    # current at the vehicle as arrows (scaled x20 to be visible)
    rec.arrows(
        "current",
        t[::every],
        a["truth"][::every] + [0, 0, 2.0],
        20.0 * a["current"][::every],
        (0, 190, 220),
    )
    err = lambda k: np.hypot(*(a[k] - a["truth"])[:, :2].T)  # noqa: E731
    rec.scalars("errors/ekf", t, err("ekf"), COLORS["ekf"], "EKF horizontal error (m)")
    rec.scalars("errors/dr", t, err("dr"), COLORS["dr"], "DR horizontal error (m)")
    rec.scalars("depth/true", t, -a["truth"][:, 2], (0, 0, 0), "true depth (m)")
    rec.scalars("depth/commanded", t, a["depth_cmd"], (148, 0, 211), "commanded depth (m)")
    rec.scalars("heading/true", t, np.degrees(a["rph"][:, 2]), (0, 0, 0), "true heading (deg)")
    rec.scalars(
        "heading/commanded", t, np.degrees(a["course_cmd"]), (148, 0, 211), "commanded course (deg)"
    )
    rec.scalars(
        "speed/through_water",
        t,
        np.hypot(*a["vel_water"][:, :2].T),
        (31, 119, 180),
        "speed through water (m/s)",
    )
    rec.scalars(
        "speed/over_ground",
        t,
        np.hypot(*a["vel"][:, :2].T),
        (214, 39, 40),
        "speed over ground (m/s)",
    )
    rec.scalars("power/motor", t, a["power"], (255, 127, 14), "motor power (W)")
    rec.scalars("actuators/fin_port", t, np.degrees(a["fin_port"]), (44, 160, 44), "port fin (deg)")
    rec.scalars(
        "actuators/fin_starboard",
        t,
        np.degrees(a["fin_stbd"]),
        (23, 190, 207),
        "starboard fin (deg)",
    )
    rec.scalars("actuators/tail_bias", t, np.degrees(a["bias"]), (188, 189, 34), "tail bias (deg)")
    rec.blueprint("errors", "depth", "heading", "speed", "power", "actuators")
    rec.close()
    return "recording.rrd"


def mission_preset(waypoints: list[dict[str, Any]], **sections: Any) -> dict[str, Any]:
    """Build a mission preset from way-points and other scenario sections (helper for the
    ``tasks/mission_*.py`` modules)."""
    preset: dict[str, Any] = {"guidance": {"waypoints": waypoints}}
    for k, v in sections.items():
        if k == "guidance":
            preset["guidance"].update(v)
        else:
            preset[k] = v
    return preset


__all__ = [
    "MissionExperiment",
    "MissionRun",
    "MissionScenario",
    "MissionTask",
    "Pilot",
    "make_environment",
    "mission_preset",
    "run_mission",
]
