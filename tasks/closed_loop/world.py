"""The world of a closed-loop mission: N vehicles in one sea, each flying on its own estimate.

In dm_control terms (``control.Task`` + ``control.Environment``, like the suite's domains):

* :class:`MissionWorld` is the task: at the start of an episode it asks the mission's design
  (:class:`~tasks.closed_loop.parts.MissionDesign`) to place the vehicles and assemble the parts
  (the sea among them), and puts the vehicles in that sea; before each physics step it hands
  each vehicle's five actuator settings to the physics and applies the sea (current, free
  surface); after it, for every vehicle in turn,
  the rig samples the truth, the navigation part estimates, guidance commands, and the tick is
  logged;
* the policy (:meth:`MissionWorld.policy`) is every vehicle's autopilot (:class:`~tasks.
  closed_loop.parts.Pilot`): observation -> action;
* the environment steps the physics ``steps_per_tick`` times per action.

Specs are known before ``reset`` (from the design's vehicle names and the scene's command
limits); observation elements are ``"<vehicle>/<element>"`` (:data:`~tasks.closed_loop.parts.
OBSERVATIONS`) and the action is each vehicle's :data:`~tasks.closed_loop.parts.ACTIONS` in turn.

:class:`WaypointMission` is the standard design of one vehicle flying way-points
(``mission/survey``, ``mission/surfacing``, ``mission/short``); :func:`standard_vehicle` builds one
vehicle's parts from the standard scenario sections, for designs of their own.
"""

from __future__ import annotations

import collections
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from dm_control.rl import control
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.build import BeaconSpec, SceneConfig, VehicleSpec, build_physics
from bauv_sim.currents import make_current
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.errors import BauvSimError, PhysicsError
from bauv_sim.frames import unit_vector_scalar
from bauv_sim.sea import Sea
from bauv_sim.sensors.online import Peer
from bauv_sim.sensors.rig import SensorRig
from nav.acoustics import Propagation
from nav.errors import NavError
from nav.guidance import Waypoint, WaypointGuidance
from tasks.closed_loop import parts as P
from tasks.closed_loop.navigation import EkfNavigation, NavOutput, initial_covariance
from tasks.closed_loop.result import MissionRun, TickLog, VehicleRun, fix_columns, summarise
from tasks.closed_loop.scenario import MODES, MissionScenario, StartConfig

Array = NDArray[np.float64]


def streams(prefix: str, name: str) -> tuple[str, ...]:
    """The stream path of a vehicle's component: ``(name,)``, or ``(prefix, name)``."""
    return (prefix, name) if prefix else (name,)


def place_vehicle(
    physics, start: StartConfig, seed: int, run: int, vehicle: str, prefix: str = ""
) -> Array:
    """Place a vehicle at its start: the nominal pose scattered by its ``start`` stream, moving
    at ``start.speed_m_s`` along its heading through the water (placed in the still water of a
    reset physics; :meth:`MissionWorld.initialize_episode` then puts it in the mission's sea,
    which carries it with the water: over ground it starts at that velocity plus the current).

    Returns:
        The true start position, shape (3,), m, world.
    """
    g = rng_mod.generator(seed, run, *streams(prefix, "start"))
    pos = np.array([start.east_m, start.north_m, -start.depth_m])
    pos[:2] += start.position_sigma_m * g.standard_normal(2)
    heading = (
        math.radians(start.heading_deg)
        + math.radians(start.heading_sigma_deg) * g.standard_normal()
    )
    vel = start.speed_m_s * np.array([*unit_vector_scalar(heading), 0.0])
    physics.set_pose(pos, (0.0, 0.0, heading), vel, vehicle=vehicle)
    return pos


def standard_vehicle(
    scn: MissionScenario,
    seed: int,
    run: int,
    physics,
    vehicle: str = "bauv",
    prefix: str = "",
    guidance: P.Guidance | None = None,
    speed_table: Any = None,
    propagation: Propagation | str | None = "scenario",
) -> P.VehicleParts:
    """One vehicle's parts from the standard scenario sections (``start``, ``sensors``,
    ``navigation``, ``guidance``, ``autopilot``): it is placed, its rig reads its lever arms from
    the model's sites, its EKF starts from the GNSS fix (``initial`` stream), and it flies the
    way-points (or ``guidance``).

    Args:
        scn: the scenario sections of this vehicle.
        seed: batch seed.
        run: run index.
        physics: the physics, reset.
        vehicle: the vehicle's name in the scene.
        prefix: its stream prefix ("" for the scene's first vehicle).
        guidance: a guidance part of the mission's own (default: :class:`~tasks.closed_loop.
            parts.WaypointSteering` on ``scn.guidance``).
        speed_table: the speed calibration (default: the model's).
        propagation: the sea's true acoustic medium for the rig's acoustic devices; by default
            (``"scenario"``) the ``sound`` section of a :class:`MissionScenario` (``None`` for
            its default and for other section types: each device's own sound speed).
    """
    if isinstance(propagation, str):
        propagation = scn.sound.propagation() if isinstance(scn, MissionScenario) else None
    table = speed_table if speed_table is not None else load_speed_table()
    pos = place_vehicle(physics, scn.start, seed, run, vehicle, prefix)
    s = scn.sensors
    devices = {"compass": s.compass, "ins": s.ins}
    if s.use_log:
        devices["log"] = s.log
    devices |= {"odometry": s.odometry, "pressure": s.pressure}
    if s.use_usbl:
        devices["usbl"] = s.usbl
    devices["gps"] = s.gps
    if s.use_dvl:
        devices["dvl"] = s.dvl
    # with a geo origin the GPS reports latitude/longitude and the navigation converts it back
    frame = scn.frame() if isinstance(scn, MissionScenario) else None
    rig = SensorRig(
        devices,
        physics,
        vehicle,
        seed,
        run,
        prefix,
        extra={"odometry": {"speed_table": table}, **({"gps": {"frame": frame}} if frame else {})},
        propagation=propagation,  # type: ignore[arg-type]
    )
    n = scn.navigation
    P0 = initial_covariance(n)
    e0 = rng_mod.generator(seed, run, *streams(prefix, "initial")).standard_normal(3) @ np.sqrt(P0)
    navigation = EkfNavigation(
        n, pos + e0, physics.transceiver_world(), rig.lever_arms_body_m, s.use_gps, frame=frame
    )
    if guidance is None:
        guidance = P.WaypointSteering(waypoint_guidance(scn, rig), n.steer_on)
    return P.VehicleParts(vehicle, rig, navigation, guidance, scn.autopilot, table)


def waypoint_guidance(scn: MissionScenario, rig: SensorRig) -> WaypointGuidance:
    """The way-point state machine of ``scn.guidance``; surfaced means the GPS antenna (its lever
    arm in the rig) out of the water with 5 cm to spare, unless configured."""
    gd = scn.guidance
    antenna = rig.lever_arms_body_m.get("gps", (0.0, 0.0, 0.0))
    surface_depth = (
        gd.surface_depth_m if gd.surface_depth_m is not None else max(antenna[2] - 0.05, 0.0)
    )
    return WaypointGuidance(
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


def scenario_sea(scn, seed: int, run: int) -> Sea:
    """The sea of a run: the scenario's current field (its own ``current`` stream; a gridded
    current placed with the scenario's geographic frame, ``scn.frame()``, where the scenario has
    one) and the free surface."""
    frame = scn.frame() if hasattr(scn, "frame") else None
    return Sea(make_current(scn.current, rng_mod.generator(seed, run, "current"), frame))


def single_vehicle_scene(
    scenario: MissionScenario, beacons: tuple[BeaconSpec, ...] | None = None
) -> SceneConfig:
    """The scene of a one-vehicle mission: the BAUV named ``bauv`` at the scenario's start, its
    seabed (from its bathymetry file around its ``geo`` origin, if it has one) and transceiver,
    and the given beacons (default: the scene's own, :data:`bauv_sim.build.DEFAULT_BEACONS`)."""
    st = scenario.start
    extra = {} if beacons is None else {"beacons": tuple(beacons)}
    return SceneConfig(
        vehicles=(
            VehicleSpec(
                name="bauv",
                east_m=st.east_m,
                north_m=st.north_m,
                depth_m=st.depth_m,
                heading_deg=st.heading_deg,
            ),
        ),
        seabed=scenario.seabed,
        geo=scenario.geo,
        transceiver_east_m=scenario.transceiver_east_m,
        transceiver_north_m=scenario.transceiver_north_m,
        **extra,
    )


@dataclass(frozen=True)
class WaypointMission:
    """The standard design: one vehicle (``bauv``) flying the scenario's way-points, steering on
    its EKF (or DR) estimate, in the scenario's current.

    Attributes:
        guidance: a factory ``(scenario, rig) -> guidance part`` replacing way-point steering.
    """

    guidance: Callable[[MissionScenario, SensorRig], P.Guidance] | None = None
    worlds: tuple[str, ...] = ("mujoco", "manoeuvring")
    """The physics this design flies in (``timing.world``): both, one vehicle; a design
    without the attribute flies in ``"mujoco"`` only (:func:`check_world`)."""

    def vehicle_names(self, scenario: MissionScenario) -> tuple[str, ...]:
        return ("bauv",)

    def scene(self, scenario: MissionScenario) -> SceneConfig:
        return single_vehicle_scene(scenario)

    def build(self, scenario: MissionScenario, seed: int, run: int, physics) -> P.MissionParts:
        v = standard_vehicle(scenario, seed, run, physics)
        if self.guidance is not None:
            v.guidance = self.guidance(scenario, v.rig)
        return P.MissionParts([v], scenario_sea(scenario, seed, run))


class MissionWorld(control.Task):
    """The task of a mission run (see the module docstring).

    Args:
        design: the mission's design.
        scenario: its scenario (with ``timing``; ``faults`` if it injects any).
        seed: batch seed.
        run: run index.
    """

    def __init__(self, design: P.MissionDesign, scenario: Any, seed: int, run: int):
        super().__init__()
        self.design, self.scn, self.seed, self.run = design, scenario, seed, run
        self.names = tuple(design.vehicle_names(scenario))
        self.parts: P.MissionParts | None = None

    # -- dm_control interface ------------------------------------------------------------------

    def action_spec(self, physics):
        return P.action_spec(self.names, [physics.command_limits(v) for v in self.names])

    def observation_spec(self, physics) -> collections.OrderedDict:
        return P.observation_spec(self.names)

    def initialize_episode(self, physics) -> None:
        physics.set_control_tick(self.scn.timing.control_tick_s)
        self.parts = self.design.build(self.scn, self.seed, self.run, physics)
        # after the vehicles are placed: the sea carries each with the water at it (Sea.immerse)
        self.parts.sea.immerse(physics)
        got = tuple(v.name for v in self.parts.vehicles)
        if got != self.names:
            raise BauvSimError(f"the design built vehicles {got}, it declared {self.names}")
        self.k = 0
        zero = np.zeros(len(P.ACTIONS))
        self._actions = {v: zero for v in self.names}
        self._logs = {v.name: TickLog(v.extra_columns) for v in self.parts.vehicles}
        self._fixes: dict[str, list] = {v: [] for v in self.names}
        self._nav: dict[str, NavOutput] = {}
        self._cmd: dict[str, Any] = {}
        self._tick_all(physics, initial=True)

    def before_step(self, action, physics) -> None:
        a = np.asarray(action, dtype=float)
        n = len(P.ACTIONS)
        for i, v in enumerate(self.names):
            ai = a[i * n : (i + 1) * n]
            self._actions[v] = ai
            physics.set_tail_beat_frequency_hz(float(ai[0]), vehicle=v)
            physics.set_tail_bias_rad(float(ai[1]), vehicle=v)
            physics.set_lateral_fins_rad(float(ai[2]), float(ai[3]), vehicle=v)
            physics.set_battery_position_m(float(ai[4]), vehicle=v)
        self.parts.sea.apply(physics)
        f = getattr(self.scn, "faults", None)
        if (
            f is not None
            and f.physics_nan_at_s is not None
            and self.run in f.physics_nan_runs
            and physics.time_s() >= f.physics_nan_at_s
        ):
            physics.inject_fault()

    def after_step(self, physics) -> None:
        self.k += 1
        self._tick_all(physics)

    def get_observation(self, physics) -> collections.OrderedDict:
        obs = collections.OrderedDict()
        for v in self.names:
            nav, cmd = self._nav[v], self._cmd[v]
            roll, pitch, roll_rate, pitch_rate, heading_rate = nav.ins
            est = nav.estimate
            values = (
                np.array([nav.heading_rad]),
                np.array([heading_rate]),
                np.array([nav.depth_m]),
                np.array([pitch]),
                np.array([pitch_rate]),
                np.array([roll]),
                np.array([roll_rate]),
                np.array([nav.speed_m_s]),
                est.x,
                np.sqrt(np.diag(est.P)),
                nav.dr_position_m,
                np.array([cmd.course_rad, cmd.depth_m, cmd.speed_m_s]),
                np.array([MODES.index(cmd.mode)]),
            )
            for k, value in zip(P.OBSERVATIONS, values, strict=True):
                obs[f"{v}/{k}"] = value
        return obs

    def get_reward(self, physics) -> float:
        return 0.0

    def get_termination(self, physics) -> float | None:
        return 0.0 if all(v.guidance.done for v in self.parts.vehicles) else None

    # -- the loop of one vehicle ---------------------------------------------------------------

    def _tick_all(self, physics, initial: bool = False) -> None:
        """Every vehicle's tick, in the scene's order. With several vehicles, each rig sees the
        others (:class:`~bauv_sim.sensors.online.Peer`): their truth now and their latest
        broadcast (this tick's for vehicles earlier in the order, else the previous tick's)."""
        if len(self.names) == 1:
            v = self.parts.vehicles[0]
            self._tick(physics, v, physics.truth(v.name), None, initial)
            return
        truths = {name: physics.truth(name) for name in self.names}
        for v in self.parts.vehicles:
            peers = {}
            for name, vt in truths.items():
                if name != v.name:
                    nav = self._nav.get(name)
                    peers[name] = Peer(vt, None if nav is None else nav.broadcast)
            self._tick(physics, v, truths[v.name], peers, initial)

    def _tick(
        self,
        physics,
        v: P.VehicleParts,
        vt,
        peers: dict[str, Peer] | None,
        initial: bool = False,
    ) -> None:
        """Rig, navigation, guidance and the log of one vehicle at this tick (``vt``: its
        truth now; ``peers``: the other vehicles, see :meth:`_tick_all`)."""
        a = self._actions[v.name]
        commands = {"tail_beat_frequency_hz": float(a[0])}
        tick = v.rig.sense(self.k, vt, commands, initial, peers)
        nav = v.navigation.step(tick, initial)
        cmd = v.guidance.step(vt.t_s, nav)
        self._nav[v.name], self._cmd[v.name] = nav, cmd
        self._fixes[v.name] += nav.fixes
        c = physics.commands(v.name)
        log = self._logs[v.name]
        if nav.current_m_s is not None:
            log.current.append(nav.current_m_s)
        row = {
            "t": vt.t_s,
            "truth_pos": vt.position_world_m,
            "truth_quat_wxyz": vt.quat_wxyz,
            "truth_rph": vt.roll_pitch_heading_rad,
            "truth_vel": vt.velocity_world_m_s,
            "truth_vel_water": vt.velocity_through_water_world_m_s,
            "truth_current": vt.current_world_m_s,
            "ekf_pos": nav.estimate.x,
            "ekf_P": nav.estimate.P,
            "dr_pos": nav.dr_position_m,
            "meas_heading": nav.heading_rad,
            "meas_depth": nav.depth_m,
            "meas_speed": nav.speed_m_s,
            "speed_from_log": nav.speed_from_log,
            "truth_tail_angles": physics.tail_angles_rad(v.name),
            "truth_fin_angles": physics.lateral_fin_angles_rad(v.name),
            "motor_power": physics.motor_power_w(v.name),
            "cmd_tail_beat_frequency": c["tail_beat_frequency_hz"],
            "cmd_tail_bias": c["tail_bias_rad"],
            "cmd_fin_port": c["fin_port_rad"],
            "cmd_fin_starboard": c["fin_starboard_rad"],
            "cmd_battery": c["battery_position_m"],
            "guidance_course": cmd.course_rad,
            "guidance_depth": cmd.depth_m,
            "guidance_speed": cmd.speed_m_s,
            "guidance_mode": MODES.index(cmd.mode),
            "guidance_waypoint": cmd.waypoint,
            "usbl_event": any(f.device == "usbl" for f in nav.fixes),
            "gps_event": nav.gps_fix,
        }
        for col, (field_name, *_) in v.extra_columns.items():
            row[col] = getattr(nav.report, field_name)
        log.add(row)

    # -- policy and result ---------------------------------------------------------------------

    def policy(self, action_spec) -> Callable[[collections.OrderedDict], Array]:
        """Every vehicle's autopilot as one policy over the scene's action."""
        n = len(P.ACTIONS)
        lo, hi = action_spec.minimum, action_spec.maximum
        pilots = [
            P.Pilot(
                v.autopilot,
                v.speed_table,
                self.scn.timing.control_tick_s,
                lo[i * n : (i + 1) * n],
                hi[i * n : (i + 1) * n],
                f"{v.name}/",
            )
            for i, v in enumerate(self.parts.vehicles)
        ]
        if len(pilots) == 1:
            return pilots[0]
        return lambda obs: np.concatenate([p(obs) for p in pilots])

    def result(self, failed: str | None) -> MissionRun:
        """The run as plain data (see :mod:`tasks.closed_loop.result`)."""
        out = MissionRun(self.run, self.seed, failed)
        for v in self.parts.vehicles:
            outcome = dict(v.navigation.outcome())
            outcome |= v.guidance.outcome()
            vr = VehicleRun(
                v.name,
                self._logs[v.name].columns(),
                fix_columns(self._fixes[v.name]),
                outcome=outcome,
                estimates=tuple(v.estimates),
            )
            summarise(vr, v.guidance.waypoints(), v.guidance.legs(), v.guidance.done)
            out.vehicles[v.name] = vr
        return out


def world_of(scenario: Any) -> str:
    """The physics a scenario flies in: its ``timing.world`` (``"mujoco"`` where it has none)."""
    return getattr(getattr(scenario, "timing", None), "world", "mujoco")


def check_world(design: Any, scenario: Any) -> None:
    """Refuse a world the mission cannot fly in, with one line naming the field, its value and
    what is allowed: the manoeuvring world (``timing.world = "manoeuvring"``) holds one vehicle
    and has no free surface, and flies designs that declare it in ``worlds``
    (:attr:`WaypointMission.worlds`).

    Raises:
        ConfigError: for a mission the world cannot fly.
    """
    from bauv_sim.errors import ConfigError

    world = world_of(scenario)
    if world == "mujoco":
        return
    what = f"timing.world = {world!r}"
    names = tuple(design.vehicle_names(scenario))
    if len(names) != 1:
        raise ConfigError(
            f"{what}: this mission flies {len(names)} vehicles in one physics and the "
            "manoeuvring world holds one; allowed: 'mujoco'"
        )
    if world not in getattr(design, "worlds", ("mujoco",)):
        raise ConfigError(
            f"{what}: the mission's design ({type(design).__name__}) is flown on the full physics "
            "only (it does not declare the manoeuvring world in its worlds); allowed: 'mujoco'"
        )
    guidance = getattr(scenario, "guidance", None)
    for i, w in enumerate(getattr(guidance, "waypoints", ())):
        if w.surface:
            raise ConfigError(
                f"{what}: guidance.waypoints[{i}].surface = true, and the manoeuvring world has "
                "no free surface; allowed: 'mujoco', or no surfacing way-points"
            )


def build_physics_of(design: P.MissionDesign, scenario: Any) -> Any:
    """The physics of one run: the design's scene in MuJoCo, or (``timing.world =
    "manoeuvring"``) the manoeuvring model behind the same accessors
    (:class:`bauv_sim.manoeuvring.physics.ManoeuvringPhysics`, reading that scene's sites,
    transceiver and seabed).

    Raises:
        ConfigError: a world the mission cannot fly in (:func:`check_world`).
    """
    check_world(design, scenario)
    t = scenario.timing
    physics = build_physics(
        design.scene(scenario), control_tick_s=t.control_tick_s, timestep_s=t.physics_timestep_s
    )
    if world_of(scenario) == "manoeuvring":
        from bauv_sim.manoeuvring.physics import ManoeuvringPhysics

        return ManoeuvringPhysics(physics, t.control_tick_s)
    return physics


def build_environment(
    design: P.MissionDesign, scenario: Any, seed: int, run: int
) -> control.Environment:
    """The physics (:func:`build_physics_of`), the world and the dm_control environment of one
    run."""
    physics = build_physics_of(design, scenario)
    world = MissionWorld(design, scenario, seed, run)
    return control.Environment(
        physics,
        world,
        time_limit=scenario.timing.max_duration_s,
        n_sub_steps=physics.steps_per_tick,
        flat_observation=False,
    )


def check_fly_arguments(design: Any, scenario: Any, seed: Any, run: Any) -> None:
    """Refuse arguments of :func:`fly` of the wrong type with one :class:`ConfigError` naming
    the argument, its type and what is allowed (not an ``AttributeError`` from inside the
    world).

    Raises:
        ConfigError: on the first bad argument.
    """
    import numbers

    from bauv_sim.config import Config
    from bauv_sim.errors import ConfigError
    from bauv_sim.rng import check_seed

    def refuse(arg: str, value: Any, allowed: str) -> None:
        raise ConfigError(f"{arg} = {value!r:.60} ({type(value).__name__}): must be {allowed}")

    missing = [
        m for m in ("vehicle_names", "scene", "build") if not callable(getattr(design, m, None))
    ]
    if isinstance(design, type) or missing:
        refuse(
            "design",
            design,
            "a mission design instance with vehicle_names, scene and build (e.g. "
            "WaypointMission(), or get_experiment(name).design)",
        )
    if not isinstance(scenario, Config) or not isinstance(
        getattr(scenario, "timing", None), Config
    ):
        refuse(
            "scenario",
            scenario,
            "a validated mission scenario with a timing section (load_config("
            "exp.scenario_type, exp.preset, ...))",
        )
    check_seed(seed)
    if isinstance(run, bool) or not isinstance(run, numbers.Integral) or run < 0:
        refuse("run", run, "an integer >= 0 (the run's index in the batch)")


def fly(design: P.MissionDesign, scenario: Any, seed: int, run: int) -> MissionRun:
    """Fly one run to its end, its time limit, or a failure.

    A physics or navigation failure does not raise: it is returned in :attr:`MissionRun.failed`
    with the simulation time, with the data up to it, so that a Monte Carlo batch completes.

    Args:
        design: the mission design (e.g. :class:`WaypointMission`, ``exp.design``).
        scenario: its validated scenario (:func:`bauv_sim.config.load_config`), with a
            ``timing`` section.
        seed: batch seed, an integer in [0, 2**63 - 1].
        run: run index, an integer >= 0.

    Raises:
        ConfigError: for an argument of the wrong type (naming it, its type and what is
            allowed), before anything is built.
    """
    check_fly_arguments(design, scenario, seed, run)
    env = build_environment(design, scenario, seed, run)
    world: MissionWorld = env.task
    ts = env.reset()
    policy = world.policy(env.action_spec())
    failed = None
    try:
        while not ts.last():
            ts = env.step(policy(ts.observation))
    except (PhysicsError, NavError, BauvSimError) as exc:
        t = env.physics.time_s()
        failed = f"run {run} (seed {seed}) failed at t = {t:.2f} s: {type(exc).__name__}: {exc}"
    return world.result(failed)
