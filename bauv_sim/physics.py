"""The physics facade: the BAUV in MuJoCo, with named accessors and actuation.

:class:`BauvPhysics` is a :class:`dm_control.mjcf.Physics` (so ``dm_control.rl.control``
environments and :mod:`dm_control.mjcf` binding work) and the **only** code in the project that
indexes MuJoCo's state arrays (``qpos``, ``qvel``, ``act``, ``ctrl``, ``actuator_force``,
``site_xpos``, ``qfrc_*``). Everything else calls its accessors, whose names carry units and frames:

* frames: world ENU (x east, y north, z up), body FLU (x forward, y port, z up), heading clockwise
  from north (:mod:`bauv_sim.frames`); the vehicle's reference point is the hull body's origin;
* one scene may hold several vehicles (``leader``, ``follower``): every accessor and setter takes
  ``vehicle=None`` (the first vehicle) or a vehicle name from :meth:`BauvPhysics.vehicle_names`.

The vehicles are in a sea (:class:`bauv_sim.sea.Sea`: current and free surface; still water until
one is injected with :meth:`BauvPhysics.set_sea`). The sea acts through the facade's primitives:
the water velocity of the fluid model, the water velocity recorded at each vehicle, a held
generalized force per vehicle and a scale of each vehicle's buoyancy.

Time advances in control ticks (:meth:`BauvPhysics.advance`): at the start of each tick the sea is
applied (:meth:`BauvPhysics.apply_sea`), then the physics runs the tick's ``n`` steps of
``timestep``. The control tick is an integer multiple of the timestep, checked.
Divergence, non-finite state and any MuJoCo warning raise :class:`~bauv_sim.errors.PhysicsError`
with the simulation time of the step where it happened (auto-reset is disabled in the model).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

with warnings.catch_warnings():
    # dm_control tries GLFW at import; without a display it warns on stderr, although nothing
    # here renders through it (offscreen rendering: MUJOCO_GL=egl or osmesa)
    warnings.filterwarnings("ignore", message=".*DISPLAY environment variable is missing.*")
    from dm_control import mjcf

from bauv_sim import frames, hydro
from bauv_sim.errors import ConfigError, PhysicsError
from bauv_sim.sea import Sea

DEFAULT_CONTROL_TICK_S = 0.1
"""Default control tick, s (50 physics steps of 2 ms)."""

SENSOR_SITES: tuple[str, ...] = (
    "camera",
    "echo_forward",
    "usbl_transponder",
    "modem",
    "echo_up",
    "sonar",
    "echo_down",
    "em_log",
    "pressure",
    "ins",
    "gps_antenna",
    "caudal_tip",
)
"""Named sites of the vehicle (unprefixed), see ``models/bauv/bauv.xml``."""

_JOINTS = (
    "tail_yaw",
    "caudal_fin_yaw",
    "crank",
    "fin_port_pitch",
    "fin_starboard_pitch",
    "battery_slide",
    "tail_bias_slide",
)
_ACTUATORS = ("motor", "tail_bias", "fin_port", "fin_starboard", "battery")
_WARNING_NAMES = {
    int(v): k for k, v in mujoco.mjtWarning.__members__.items() if k.startswith("mjWARN")
}


@dataclass(frozen=True)
class VehicleTruth:
    """The true state of one vehicle at one instant (what sensors may read).

    Attributes:
        t_s: simulation time, s.
        position_world_m: reference point, shape (3,), m, world ENU.
        quat_wxyz: attitude, body to world, shape (4,).
        roll_pitch_heading_rad: shape (3,), rad (roll starboard-down +, pitch nose-up +, heading
            clockwise from north in [0, 2 pi)).
        depth_m: depth of the reference point below the surface z = 0, m (positive down).
        velocity_world_m_s: velocity over ground, shape (3,), m/s, world.
        velocity_through_water_world_m_s: velocity relative to the water, shape (3,), m/s, world.
        current_world_m_s: water velocity at the vehicle, shape (3,), m/s, world.
        angular_velocity_body_rad_s: shape (3,), rad/s, body FLU.
    """

    t_s: float
    position_world_m: NDArray[np.float64]
    quat_wxyz: NDArray[np.float64]
    roll_pitch_heading_rad: NDArray[np.float64]
    depth_m: float
    velocity_world_m_s: NDArray[np.float64]
    velocity_through_water_world_m_s: NDArray[np.float64]
    current_world_m_s: NDArray[np.float64]
    angular_velocity_body_rad_s: NDArray[np.float64]


@dataclass
class _Vehicle:
    """Index tables of one vehicle (built once from names)."""

    name: str
    prefix: str
    hull_body: int
    qpos_adr: int
    dof_adr: int
    dofs: NDArray[np.int_]
    bodies: NDArray[np.int_]
    jnt_qpos: dict[str, int]
    jnt_dof: dict[str, int]
    act: dict[str, int]
    act_state: dict[str, int]
    sites: dict[str, int]
    lever_m: float
    crank_m: float
    free_body: int = -1
    hydro_instance: int = 0
    first: bool = False
    float_bodies: NDArray[np.int_] = field(default_factory=lambda: np.zeros(0, dtype=int))
    float_gravcomp: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    buoyancy_scale: float = 1.0


class BauvPhysics(mjcf.Physics):
    """MuJoCo physics of one or more BAUVs, with named accessors and actuation.

    Build it with :func:`bauv_sim.build.build_physics` (``dm_control.mjcf`` scenes, several
    vehicles) or :meth:`from_scene_xml` (the plain ``models/bauv/scene.xml``). The fluid forces
    beyond MuJoCo's drag are the engine plugin ``bauv.hydro``, one instance per vehicle, declared
    in the model (:mod:`bauv_sim.hydro`); on every (re)load each vehicle is matched to its
    instance, whose water the sea sets each tick (:meth:`set_water_world`).
    """

    _control_tick_s: float = DEFAULT_CONTROL_TICK_S
    _timestep_s: float | None = None
    _sea: Sea = Sea()
    _sea_applied: bool = False
    _track_energy: bool = False

    # ----------------------------------------------------------------------------------------
    # construction

    @classmethod
    def from_scene_xml(
        cls,
        path: str | Path | None = None,
        control_tick_s: float = DEFAULT_CONTROL_TICK_S,
        timestep_s: float | None = None,
    ) -> BauvPhysics:
        """Load a scene file (default ``models/bauv/scene.xml``) with plain MuJoCo.

        Args:
            path: MJCF file.
            control_tick_s: control tick, s (an integer multiple of the timestep).
            timestep_s: physics timestep, s; None keeps the model file's (2 ms).

        Returns:
            The physics, reset to the model's defaults.
        """
        from bauv_sim.hull import MODEL_DIR

        phys = cls.from_xml_path(str(path if path is not None else MODEL_DIR / "scene.xml"))
        if timestep_s is not None:
            phys.set_timestep(timestep_s, control_tick_s)
        else:
            phys.set_control_tick(control_tick_s)
        return phys

    def _reload_from_data(self, data) -> None:
        self._sea_applied = False
        self._vehicles: dict[str, _Vehicle] = {}
        super()._reload_from_data(data)
        self._index_vehicles()
        instances = hydro.plugin_instances(self.model.ptr)
        for k, v in enumerate(self._vehicles.values()):
            if v.prefix not in instances:
                raise ConfigError(
                    f"vehicle {v.name!r}: no {hydro.PLUGIN_NAME} plugin instance "
                    f"{v.prefix + 'hydro'!r} (the vehicle's hydrodynamics)"
                )
            v.hydro_instance = instances[v.prefix]
            v.first = k == 0
        self._check_options()
        self._energy_j = {name: 0.0 for name in self._vehicles}
        self._energy_window_s = 0.0
        self._state_buf = np.empty(
            mujoco.mj_stateSize(self.model.ptr, mujoco.mjtState.mjSTATE_INTEGRATION)
        )
        if self._timestep_s is not None:
            self.model.ptr.opt.timestep = self._timestep_s
        self.set_control_tick(self._control_tick_s)

    def _check_options(self) -> None:
        m = self.model.ptr
        if not m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_AUTORESET:
            raise ConfigError(
                "model option flag autoreset must be disabled "
                "(a divergence would silently restart the simulation)"
            )
        if m.opt.integrator != mujoco.mjtIntegrator.mjINT_IMPLICITFAST:
            raise ConfigError(
                "model integrator must be implicitfast "
                f"(got {mujoco.mjtIntegrator(m.opt.integrator).name})"
            )

    def _index_vehicles(self) -> None:
        m = self.model.ptr
        for b in range(m.nbody):
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or ""
            if name.rsplit("/", 1)[-1] != "hull":
                continue
            prefix = name[: -len("hull")]
            vname = prefix.rstrip("/") or "bauv"
            self._vehicles[vname] = self._index_one(vname, prefix, b)
        if not self._vehicles:
            raise ConfigError("model has no vehicle: no body named 'hull' or '<name>/hull'")

    def _index_one(self, vname: str, prefix: str, hull: int) -> _Vehicle:
        m = self.model.ptr

        def oid(kind: mujoco.mjtObj, name: str) -> int:
            i = mujoco.mj_name2id(m, kind, prefix + name)
            if i < 0:
                raise ConfigError(
                    f"vehicle {vname!r}: {kind.name[6:].lower()} "
                    f"{prefix + name!r} missing from the model"
                )
            return i

        # the free joint: on the hull, or on an attachment frame that carries the hull at identity
        free_body = hull
        while m.body_jntnum[free_body] == 0 and m.body_parentid[free_body] != 0:
            if np.any(m.body_pos[free_body] != 0) or np.any(m.body_quat[free_body] != [1, 0, 0, 0]):
                raise ConfigError(f"vehicle {vname!r}: hull is offset from its free body")
            free_body = int(m.body_parentid[free_body])
        j = int(m.body_jntadr[free_body])
        if j < 0 or m.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE:
            raise ConfigError(f"vehicle {vname!r}: the hull has no free joint")
        bodies = hydro.subtree_bodies(m, free_body)
        dofs = np.flatnonzero(np.isin(m.dof_bodyid, bodies))
        jq = {n: int(m.jnt_qposadr[oid(mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in _JOINTS}
        jd = {n: int(m.jnt_dofadr[oid(mujoco.mjtObj.mjOBJ_JOINT, n)]) for n in _JOINTS}
        act = {n: oid(mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in _ACTUATORS}
        act_state = {n: int(m.actuator_actadr[i]) for n, i in act.items()}
        sites = {n: oid(mujoco.mjtObj.mjOBJ_SITE, n) for n in SENSOR_SITES}
        # crank-rocker geometry from the model: lever = anchor on the peduncle (body2 frame),
        # crank radius = the rod's pin offset on the crank
        eq = oid(mujoco.mjtObj.mjOBJ_EQUALITY, "tail_linkage")
        lever = float(np.linalg.norm(m.eq_data[eq, 3:6]))
        crank = float(np.linalg.norm(m.body_pos[oid(mujoco.mjtObj.mjOBJ_BODY, "rod")]))
        return _Vehicle(
            vname,
            prefix,
            hull,
            int(m.jnt_qposadr[j]),
            int(m.jnt_dofadr[j]),
            dofs,
            bodies,
            jq,
            jd,
            act,
            act_state,
            sites,
            lever,
            crank,
            free_body=int(free_body),
            float_bodies=bodies[m.body_gravcomp[bodies] > 0].copy(),
            float_gravcomp=m.body_gravcomp[bodies][m.body_gravcomp[bodies] > 0].copy(),
        )

    def set_control_tick(self, control_tick_s: float) -> None:
        """Set the control tick.

        Args:
            control_tick_s: tick, s; must be a positive integer multiple of the timestep.

        Raises:
            ConfigError: if it is not.
        """
        dt = float(self.model.opt.timestep)
        n = round(control_tick_s / dt)
        if n < 1 or abs(n * dt - control_tick_s) > 1e-9 * max(1.0, control_tick_s):
            raise ConfigError(
                f"control tick = {control_tick_s} s: must be a positive integer "
                f"multiple of the physics timestep {dt} s"
            )
        self._control_tick_s = float(control_tick_s)
        self._steps_per_tick = int(n)

    def set_timestep(self, timestep_s: float, control_tick_s: float | None = None) -> None:
        """Set the physics timestep (``option timestep``), kept over model reloads.

        The presets validated against 1 ms on cruise speed, turn rate and depth response are in
        ``models/bauv/README.md`` ("Timestep presets", ``python -m tasks.vehicle.timestep``).
        Call it before stepping: it does not rescale anything already integrated.

        Args:
            timestep_s: timestep, s (> 0).
            control_tick_s: control tick, s, to set with it (None keeps the current one); it must
                be a positive integer multiple of the new timestep.

        Raises:
            ConfigError: if the timestep is not finite and positive, or the tick is not a multiple
                of it (the timestep is then left as it was).
        """
        if not (math.isfinite(timestep_s) and timestep_s > 0):
            raise ConfigError(f"timestep = {timestep_s!r} s: must be finite and > 0")
        m = self.model.ptr
        old = float(m.opt.timestep)
        m.opt.timestep = float(timestep_s)
        try:
            self.set_control_tick(
                self._control_tick_s if control_tick_s is None else control_tick_s
            )
        except ConfigError:
            m.opt.timestep = old
            raise
        self._timestep_s = float(timestep_s)

    @property
    def control_tick_s(self) -> float:
        """Control tick, s."""
        return self._control_tick_s

    @property
    def steps_per_tick(self) -> int:
        """Physics steps per control tick."""
        return self._steps_per_tick

    def vehicle_names(self) -> list[str]:
        """Names of the vehicles in the scene (``["bauv"]`` for the plain scene file)."""
        return list(self._vehicles)

    def _v(self, vehicle: str | None) -> _Vehicle:
        if vehicle is None:
            return next(iter(self._vehicles.values()))
        try:
            return self._vehicles[vehicle]
        except KeyError:
            raise ConfigError(
                f"vehicle {vehicle!r}: not in the scene (have {', '.join(self._vehicles)})"
            ) from None

    def set_const(self) -> None:
        """Run ``mj_setConst`` (the plugin zeroes the virtual masses it recomputes again at the next
        step)."""
        mujoco.mj_setConst(self.model.ptr, self.data.ptr)

    # ----------------------------------------------------------------------------------------
    # pose and motion of the vehicle

    def position_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Reference point (hull origin, on the hull axis 0.80 m aft of the nose), shape (3,), m,
        world ENU."""
        v = self._v(vehicle)
        return np.array(self.data.qpos[v.qpos_adr : v.qpos_adr + 3])

    def quat_wxyz(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Attitude quaternion (w, x, y, z), body FLU to world ENU, unit norm, shape (4,)."""
        v = self._v(vehicle)
        q = np.array(self.data.qpos[v.qpos_adr + 3 : v.qpos_adr + 7])
        return q / np.linalg.norm(q)

    def R_world_from_body(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Rotation matrix body FLU -> world ENU, shape (3, 3)."""
        return frames.R_from_quat_wxyz(self.quat_wxyz(vehicle))

    def roll_pitch_heading(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """(roll, pitch, heading), shape (3,), rad: roll starboard-down positive in [-pi, pi),
        pitch nose-up positive, heading clockwise from north in [0, 2 pi)."""
        return frames.roll_pitch_heading_from_R(self.R_world_from_body(vehicle))

    def heading_rad(self, vehicle: str | None = None) -> float:
        """Heading of the body x axis, clockwise from north, in [0, 2 pi), rad."""
        return float(self.roll_pitch_heading(vehicle)[2])

    def depth_m(self, vehicle: str | None = None) -> float:
        """Depth of the reference point below the surface z = 0, m (positive down)."""
        return float(frames.depth_from_z(self.position_world(vehicle)[2]))

    def velocity_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity over ground of the reference point, shape (3,), m/s, world ENU."""
        v = self._v(vehicle)
        return np.array(self.data.qvel[v.dof_adr : v.dof_adr + 3])

    def velocity_body(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity over ground of the reference point, shape (3,), m/s, body FLU."""
        return frames.body_from_world(self.R_world_from_body(vehicle), self.velocity_world(vehicle))

    def velocity_through_water_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity of the reference point relative to the water, shape (3,), m/s, world ENU."""
        return self.velocity_world(vehicle) - self.current_at_vehicle_world(vehicle)

    def speed_through_water_m_s(self, vehicle: str | None = None) -> float:
        """Norm of :meth:`velocity_through_water_world`, m/s."""
        return float(np.linalg.norm(self.velocity_through_water_world(vehicle)))

    def angular_velocity_body(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Angular velocity, shape (3,), rad/s, body FLU (roll rate about x, ...)."""
        v = self._v(vehicle)
        return np.array(self.data.qvel[v.dof_adr + 3 : v.dof_adr + 6])

    def angular_velocity_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Angular velocity, shape (3,), rad/s, world ENU."""
        return frames.world_from_body(
            self.R_world_from_body(vehicle), self.angular_velocity_body(vehicle)
        )

    def site_position_world(self, name: str, vehicle: str | None = None) -> NDArray[np.float64]:
        """Position of a named sensor site (see :data:`SENSOR_SITES`), shape (3,), m, world ENU.

        Args:
            name: unprefixed site name, e.g. ``"usbl_transponder"``.
            vehicle: vehicle name or None for the first.
        """
        v = self._v(vehicle)
        if name not in v.sites:
            raise ConfigError(f"site {name!r}: not a sensor site (have {', '.join(SENSOR_SITES)})")
        self._ensure_kinematics()
        return np.array(self.data.site_xpos[v.sites[name]])

    def site_axis_world(self, name: str, vehicle: str | None = None) -> NDArray[np.float64]:
        """Unit sensing direction (the site's z axis) of a named sensor site, shape (3,), world."""
        v = self._v(vehicle)
        if name not in v.sites:
            raise ConfigError(f"site {name!r}: not a sensor site (have {', '.join(SENSOR_SITES)})")
        self._ensure_kinematics()
        return np.array(self.data.site_xmat[v.sites[name]].reshape(3, 3)[:, 2])

    def scene_site_world(self, name: str) -> NDArray[np.float64]:
        """Position of a site of the scene (not of a vehicle), e.g. ``"usbl_transceiver"`` or
        ``"beacon_0"``, shape (3,), m, world ENU."""
        i = mujoco.mj_name2id(self.model.ptr, mujoco.mjtObj.mjOBJ_SITE, name)
        if i < 0:
            raise ConfigError(f"site {name!r}: not in the scene")
        self._ensure_kinematics()
        return np.array(self.data.site_xpos[i])

    def transceiver_world(self) -> NDArray[np.float64]:
        """Position of the USBL transceiver on the seabed (site ``usbl_transceiver``), shape (3,),
        m, world ENU."""
        return self.scene_site_world("usbl_transceiver")

    def beacons_world(self) -> dict[str, NDArray[np.float64]]:
        """Positions of the acoustic beacons (scene sites ``beacon_*``) by name, each shape (3,),
        m, world ENU."""
        m = self.model.ptr
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, i) or "" for i in range(m.nsite)]
        return {n: self.scene_site_world(n) for n in names if n.startswith("beacon_")}

    def seabed_ray_distances(
        self, origin_world_m: ArrayLike, directions_world: ArrayLike, max_range_m: float
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Distances along rays from one point to the scene's seabed (MuJoCo ``mj_multiRay``).

        The rays see the static geoms of the seabed's geom group (the vehicles' geoms are in
        groups 2-5 and are not seen); a ray that first meets another geom than the seabed
        heightfield, or none within ``max_range_m``, has no hit. MuJoCo intersects the
        heightfield's triangles (each cell split along its lower-left to upper-right diagonal,
        :meth:`bauv_sim.seabed.Seabed.height_world`).

        Args:
            origin_world_m: ray origin, shape (3,), m, world ENU.
            directions_world: ray directions, shape (m, 3), world ENU (normalised here).
            max_range_m: longest distance that counts, m.

        Returns:
            ``(distance_m, hit)``: shape (m,) each; ``distance_m`` is 0 where ``hit`` is False.

        Raises:
            ConfigError: if the scene has no geom named ``seabed``, or a direction is zero or
                not finite.
        """
        m, d = self.model.ptr, self.data.ptr
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "seabed")
        if gid < 0:
            raise ConfigError("seabed ray: the scene has no geom named 'seabed'")
        vec = np.array(directions_world, dtype=float).reshape(-1, 3)
        norm = np.linalg.norm(vec, axis=1)
        if not np.all(np.isfinite(norm) & (norm > 0)):
            raise ConfigError("seabed ray: every direction must be finite and non-zero")
        vec /= norm[:, None]
        n = vec.shape[0]
        group = np.zeros(6, dtype=np.uint8)
        group[int(m.geom_group[gid])] = 1
        ids = np.full(n, -1, dtype=np.int32)
        dist = np.zeros(n)
        self._ensure_kinematics()
        pnt = np.array(origin_world_m, dtype=float).reshape(3)
        mujoco.mj_multiRay(
            m, d, pnt, vec.ravel(), group, 1, -1, ids, dist, None, n, float(max_range_m)
        )
        hit = (ids == gid) & (dist >= 0) & (dist <= max_range_m)
        return np.where(hit, dist, 0.0), hit

    def inject_fault(self) -> None:
        """Corrupt the simulation on purpose (a NaN motor command), so that the next step raises
        :class:`~bauv_sim.errors.PhysicsError`: for tests of a mission's error handling."""
        self.data.ctrl[self._v(None).act["motor"]] = np.nan

    def _ensure_kinematics(self) -> None:
        if self._kinematics_stale:
            mujoco.mj_kinematics(self.model.ptr, self.data.ptr)
            self._kinematics_stale = False

    _kinematics_stale: bool = True

    def truth(self, vehicle: str | None = None) -> VehicleTruth:
        """The true state of a vehicle now (see :class:`VehicleTruth`).

        Called at every control tick, so it reads ``qpos``/``qvel`` once and computes the
        attitude with scalar arithmetic (:func:`bauv_sim.frames.attitude_from_quat_wxyz_scalar`).
        """
        v = self._v(vehicle)
        d = self.data.ptr
        x, y, z, qw, qx, qy, qz = d.qpos[v.qpos_adr : v.qpos_adr + 7].tolist()
        vx, vy, vz, wx, wy, wz = d.qvel[v.dof_adr : v.dof_adr + 6].tolist()
        quat, rph = frames.attitude_from_quat_wxyz_scalar(qw, qx, qy, qz)
        cur = hydro.water(self.model.ptr, d, v.hydro_instance)[0]
        vel = np.array([vx, vy, vz])
        return VehicleTruth(
            float(d.time),
            np.array([x, y, z]),
            np.array(quat),
            np.array(rph),
            -z,
            vel,
            vel - cur,
            cur,
            np.array([wx, wy, wz]),
        )

    def hydrostatics(self, vehicle: str | None = None) -> hydro.Hydrostatics:
        """Weight, buoyancy, centres and BG of a vehicle now (see :func:`hydro.hydrostatics`)."""
        v = self._v(vehicle)
        self._ensure_kinematics()
        m = self.model.ptr
        return hydro.hydrostatics(
            m.body_mass[v.bodies],
            m.body_gravcomp[v.bodies],
            self.data.xipos[v.bodies],
            float(np.linalg.norm(m.opt.gravity)),
        )

    def set_mocap_pose_world(
        self, body: str, position_world_m: ArrayLike, quat_wxyz: ArrayLike
    ) -> None:
        """Place a mocap body of the scene (a captive-test carriage, for example).

        Args:
            body: the mocap body's name.
            position_world_m: shape (3,), m, world ENU.
            quat_wxyz: orientation, shape (4,).
        """
        m = self.model.ptr
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
        if b < 0 or m.body_mocapid[b] < 0:
            raise ConfigError(f"body {body!r}: not a mocap body of the scene")
        k = int(m.body_mocapid[b])
        self.data.mocap_pos[k] = position_world_m
        self.data.mocap_quat[k] = quat_wxyz

    def constraint_wrench(
        self, vehicle: str | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The constraint force on the vehicle's free joint at the last step (a carriage's weld:
        the vehicle's internal constraints cancel there): force (3,), N, world ENU, and moment
        about the reference point (3,), N m, body FLU."""
        v = self._v(vehicle)
        q = self.data.qfrc_constraint[v.dof_adr : v.dof_adr + 6]
        return np.array(q[:3]), np.array(q[3:])

    def set_joint_stiffness(self, joint: str, stiffness: float, vehicle: str | None = None) -> None:
        """Change the stiffness of one of a vehicle's joints in the compiled model (experiments on
        the design, e.g. the passive caudal spring).

        Args:
            joint: unprefixed joint name (``caudal_fin_yaw``).
            stiffness: N m/rad (hinge) or N/m (slide), >= 0.
            vehicle: vehicle name or None for the first.
        """
        v = self._v(vehicle)
        if not (math.isfinite(stiffness) and stiffness >= 0.0):
            raise ConfigError(f"stiffness = {stiffness!r}: must be finite and >= 0")
        m = self.model.ptr
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, v.prefix + joint)
        if j < 0:
            raise ConfigError(f"joint {joint!r}: not a joint of vehicle {v.name!r}")
        m.jnt_stiffness[j] = stiffness

    def com_velocity_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity of the vehicle's centre of mass (all its bodies), shape (3,), m/s, world."""
        v = self._v(vehicle)
        m, d = self.model.ptr, self.data.ptr
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        return np.array(d.subtree_linvel[v.free_body])

    def apply_force_at_cg_world(
        self,
        force_world_n: ArrayLike,
        vehicle: str | None = None,
        moment_body_nm: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        """Apply an external force at the vehicle's centre of gravity, and a moment, until
        replaced (a test input: ``xfrc_applied`` of the hull body, with the moment that moves the
        force to the CG).

        Args:
            force_world_n: force, shape (3,), N, world ENU; zeros to remove it.
            vehicle: vehicle name or None for the first.
            moment_body_nm: moment, shape (3,), N m, body FLU.
        """
        v = self._v(vehicle)
        f = np.asarray(force_world_n, dtype=float)
        n = np.asarray(moment_body_nm, dtype=float)
        if f.shape != (3,) or n.shape != (3,) or not np.all(np.isfinite(np.r_[f, n])):
            raise ConfigError(f"force, moment = {f!r}, {n!r}: expected 3 finite numbers each")
        cg = self.hydrostatics(vehicle).cg_world_m
        d = self.data.ptr
        d.xfrc_applied[v.hull_body, :3] = f
        moment = self.R_world_from_body(vehicle) @ n
        d.xfrc_applied[v.hull_body, 3:] = np.cross(cg - d.xipos[v.hull_body], f) + moment

    def added_mass_matrix(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """The vehicle's added mass (6 x 6, about the reference point, body FLU, order surge, sway,
        heave, roll, pitch, yaw; kg, kg m, kg m^2), the model's ``hydro_added_mass``."""
        v = self._v(vehicle)
        m = self.model.ptr
        i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, v.prefix + "hydro_added_mass")
        a = int(m.numeric_adr[i])
        return np.array(m.numeric_data[a : a + 36]).reshape(6, 6)

    def rigid_inertia_matrix(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """The vehicle's rigid-body inertia with its joints held (6 x 6, about the reference point,
        body FLU, order as :meth:`added_mass_matrix`; kg, kg m, kg m^2), from MuJoCo's mass matrix
        without the added mass."""
        v = self._v(vehicle)
        m, d = self.model.ptr, self.data.ptr
        mujoco.mj_forward(m, d)
        full = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, full)
        blk = full[v.dof_adr : v.dof_adr + 6, v.dof_adr : v.dof_adr + 6]
        T = np.eye(6)
        T[:3, :3] = self.R_world_from_body(vehicle)  # qvel (v_world, w) = T nu
        return T.T @ blk @ T - self.added_mass_matrix(vehicle)

    def mass_kg(self, vehicle: str | None = None) -> float:
        """Total mass of a vehicle (all its bodies), kg."""
        return float(self.model.ptr.body_mass[self._v(vehicle).bodies].sum())

    def water_density_kg_m3(self) -> float:
        """Density of the water (MuJoCo ``option density``), kg/m^3."""
        return float(self.model.ptr.opt.density)

    def gravity_m_s2(self) -> float:
        """Magnitude of gravity, m/s^2."""
        return float(np.linalg.norm(self.model.ptr.opt.gravity))

    def warning_count(self) -> int:
        """Number of MuJoCo warnings raised so far (any would also have raised PhysicsError in
        :meth:`step`)."""
        return int(self.data.ptr.warning.number.sum())

    def fluid_force_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Total fluid force on the vehicle (MuJoCo's ``qfrc_fluid`` and the run-time
        hydrodynamics of :mod:`bauv_sim.hydro` on the free joint's translation, without the
        added mass's acceleration term, which is in the mass matrix), shape (3,), N, world ENU, at
        the current state (forward dynamics are recomputed)."""
        return self.fluid_wrench(vehicle)[0]

    def fluid_wrench(
        self, vehicle: str | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Total fluid force and moment on the vehicle as :meth:`fluid_force_world`: the force,
        shape (3,), N, world ENU, and the moment about the reference point, shape (3,), N m, body
        FLU, at the current state (forward dynamics are recomputed)."""
        v = self._v(vehicle)
        mujoco.mj_forward(self.model.ptr, self.data.ptr)
        dofs = np.arange(v.dof_adr, v.dof_adr + 6)
        gen = self.data.qfrc_fluid[dofs] + hydro.plugin_force(self.data.ptr, dofs)
        return np.array(gen[:3]), np.array(gen[3:])

    # ----------------------------------------------------------------------------------------
    # fins, tail, motor, battery

    def motor_speed_rad_s(self, vehicle: str | None = None) -> float:
        """Crank (gearbox output) speed, rad/s; tail-beat frequency = this / (2 pi)."""
        v = self._v(vehicle)
        return float(self.data.qvel[v.jnt_dof["crank"]])

    def tail_beat_frequency_hz(self, vehicle: str | None = None) -> float:
        """Instantaneous tail-beat frequency from the crank speed, Hz."""
        return self.motor_speed_rad_s(vehicle) / (2.0 * math.pi)

    def motor_torque_nm(self, vehicle: str | None = None) -> float:
        """Torque of the motor on the crank (after the gearbox) during the last physics step
        (MuJoCo evaluates it at the step's start), N m."""
        v = self._v(vehicle)
        return float(self.data.actuator_force[v.act["motor"]])

    def motor_power_w(self, vehicle: str | None = None) -> float:
        """Mechanical power of the motor at the crank during the last physics step: its torque
        times the crank speed at the step's start, W (the energy accounts sum this times dt)."""
        v = self._v(vehicle)
        i = v.act["motor"]
        return float(self.data.actuator_force[i] * self.data.actuator_velocity[i])

    def set_energy_tracking(self, on: bool) -> None:
        """Switch the motor-energy accounts on or off (off by default).

        With the accounts on, :meth:`step` runs the physics one step at a time from Python to add
        torque x speed x dt of every step (about a third slower); off, the steps run in MuJoCo's
        own loop. Switching restarts the accounts.
        """
        self._track_energy = bool(on)
        self.reset_energy()

    def mean_motor_power_w(self, vehicle: str | None = None) -> float:
        """Mean motor power since the last :meth:`reset_energy` (sum of torque x speed x dt over the
        steps taken, divided by their time), W.

        Raises:
            ConfigError: if the energy accounts are off (:meth:`set_energy_tracking`).
        """
        name = self._v(vehicle).name
        if not self._track_energy:
            raise ConfigError("motor energy is not tracked: call set_energy_tracking(True) first")
        if self._energy_window_s <= 0:
            return 0.0
        return self._energy_j[name] / self._energy_window_s

    def motor_energy_j(self, vehicle: str | None = None) -> float:
        """Motor energy since the last :meth:`reset_energy`, J (energy tracking must be on)."""
        if not self._track_energy:
            raise ConfigError("motor energy is not tracked: call set_energy_tracking(True) first")
        return self._energy_j[self._v(vehicle).name]

    def reset_energy(self) -> None:
        """Restart the motor-energy accounting of all vehicles."""
        for k in self._energy_j:
            self._energy_j[k] = 0.0
        self._energy_window_s = 0.0

    def tail_angles_rad(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """(segment 1 angle to the hull, segment 2 angle to segment 1), shape (2,), rad; positive
        swings the tail to port (counter-clockwise seen from above)."""
        v = self._v(vehicle)
        return np.array(
            [self.data.qpos[v.jnt_qpos["tail_yaw"]], self.data.qpos[v.jnt_qpos["caudal_fin_yaw"]]]
        )

    def crank_angle_rad(self, vehicle: str | None = None) -> float:
        """Crank angle (unwrapped), rad."""
        v = self._v(vehicle)
        return float(self.data.qpos[v.jnt_qpos["crank"]])

    def lateral_fin_angles_rad(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """(port, starboard) lateral-fin pitch angles, shape (2,), rad (leading edge up > 0)."""
        v = self._v(vehicle)
        return np.array(
            [
                self.data.qpos[v.jnt_qpos["fin_port_pitch"]],
                self.data.qpos[v.jnt_qpos["fin_starboard_pitch"]],
            ]
        )

    def battery_position_m(self, vehicle: str | None = None) -> float:
        """Battery position along the body x axis from its neutral place, m (positive forward)."""
        v = self._v(vehicle)
        return float(self.data.qpos[v.jnt_qpos["battery_slide"]])

    def tail_bias_rad(self, vehicle: str | None = None) -> float:
        """Tail bias set by the crank carriage's position, -asin(offset / lever), rad (the mean
        segment-1 angle it gives, to first order)."""
        v = self._v(vehicle)
        off = float(self.data.qpos[v.jnt_qpos["tail_bias_slide"]])
        return -math.asin(max(-1.0, min(1.0, off / v.lever_m)))

    def tail_amplitude_rad(self, vehicle: str | None = None) -> float:
        """Design amplitude of segment 1, asin(crank radius / lever), rad."""
        v = self._v(vehicle)
        return math.asin(v.crank_m / v.lever_m)

    def _set_ctrl(self, v: _Vehicle, name: str, value: float, what: str, unit: str) -> None:
        i = v.act[name]
        lo, hi = self.model.ptr.actuator_ctrlrange[i]
        if not (math.isfinite(value) and lo - 1e-12 <= value <= hi + 1e-12):
            raise ConfigError(f"{what} = {value:.6g} {unit}: must be within [{lo:.6g}, {hi:.6g}]")
        self.data.ctrl[i] = value

    def set_tail_beat_frequency_hz(self, frequency_hz: float, vehicle: str | None = None) -> None:
        """Command the tail-beat frequency (the motor's crank speed 2 pi f).

        Args:
            frequency_hz: tail-beat frequency, Hz (0 stops the tail where it is).
            vehicle: vehicle name or None for the first.

        Raises:
            ConfigError: if outside the motor's range.
        """
        v = self._v(vehicle)
        i = v.act["motor"]
        hi = self.model.ptr.actuator_ctrlrange[i][1] / (2.0 * math.pi)
        if not (math.isfinite(frequency_hz) and 0.0 <= frequency_hz <= hi + 1e-12):
            raise ConfigError(
                f"tail-beat frequency = {frequency_hz:.6g} Hz: must be within [0, {hi:.6g}]"
            )
        self.data.ctrl[i] = 2.0 * math.pi * frequency_hz

    def set_tail_bias_rad(self, bias_rad: float, vehicle: str | None = None) -> None:
        """Command the tail bias (the mean segment-1 angle; positive = tail to port, which turns the
        vehicle to starboard), by moving the crank carriage by -lever sin(bias).

        Args:
            bias_rad: bias, rad.
            vehicle: vehicle name or None for the first.
        """
        v = self._v(vehicle)
        if not math.isfinite(bias_rad) or abs(bias_rad) >= math.pi / 2:
            raise ConfigError(f"tail bias = {bias_rad!r} rad: must be finite and within +-pi/2")
        lo, hi = self.model.ptr.actuator_ctrlrange[v.act["tail_bias"]]
        off = -v.lever_m * math.sin(bias_rad)
        if not lo - 1e-12 <= off <= hi + 1e-12:
            lim = math.asin(min(abs(lo), abs(hi)) / v.lever_m)
            raise ConfigError(f"tail bias = {bias_rad:.6g} rad: must be within +-{lim:.6g} rad")
        self.data.ctrl[v.act["tail_bias"]] = off

    def max_tail_bias_rad(self, vehicle: str | None = None) -> float:
        """Largest tail bias the carriage allows, rad."""
        v = self._v(vehicle)
        lo, hi = self.model.ptr.actuator_ctrlrange[v.act["tail_bias"]]
        return math.asin(min(abs(lo), abs(hi)) / v.lever_m)

    def set_lateral_fins_rad(
        self, port_rad: float, starboard_rad: float, vehicle: str | None = None
    ) -> None:
        """Command the lateral-fin pitch angles (positive = leading edge up; together: lift for
        depth and pitch; differentially: roll).

        Args:
            port_rad: port fin, rad.
            starboard_rad: starboard fin, rad.
            vehicle: vehicle name or None for the first.
        """
        v = self._v(vehicle)
        self._set_ctrl(v, "fin_port", float(port_rad), "port fin angle", "rad")
        self._set_ctrl(v, "fin_starboard", float(starboard_rad), "starboard fin angle", "rad")

    def set_battery_position_m(self, position_m: float, vehicle: str | None = None) -> None:
        """Command the battery position along the body x axis (positive forward: nose down), m."""
        self._set_ctrl(self._v(vehicle), "battery", float(position_m), "battery position", "m")

    def commands(self, vehicle: str | None = None) -> dict[str, float]:
        """The current commands of a vehicle, in the setters' units."""
        v = self._v(vehicle)
        c = self.data.ctrl
        return {
            "tail_beat_frequency_hz": float(c[v.act["motor"]]) / (2.0 * math.pi),
            "tail_bias_rad": -math.asin(float(c[v.act["tail_bias"]]) / v.lever_m),
            "fin_port_rad": float(c[v.act["fin_port"]]),
            "fin_starboard_rad": float(c[v.act["fin_starboard"]]),
            "battery_position_m": float(c[v.act["battery"]]),
        }

    def command_limits(self, vehicle: str | None = None) -> dict[str, tuple[float, float]]:
        """The range of every command, in the setters' units (same keys as :meth:`commands`)."""
        v = self._v(vehicle)
        r = self.model.ptr.actuator_ctrlrange
        bias = self.max_tail_bias_rad(vehicle)
        return {
            "tail_beat_frequency_hz": (0.0, float(r[v.act["motor"]][1]) / (2.0 * math.pi)),
            "tail_bias_rad": (-bias, bias),
            "fin_port_rad": (float(r[v.act["fin_port"]][0]), float(r[v.act["fin_port"]][1])),
            "fin_starboard_rad": (
                float(r[v.act["fin_starboard"]][0]),
                float(r[v.act["fin_starboard"]][1]),
            ),
            "battery_position_m": (float(r[v.act["battery"]][0]), float(r[v.act["battery"]][1])),
        }

    # ----------------------------------------------------------------------------------------
    # initial state

    def set_pose(
        self,
        position_world_m: ArrayLike,
        roll_pitch_heading_rad: ArrayLike = (0, 0, 0),
        velocity_world_m_s: ArrayLike = (0, 0, 0),
        vehicle: str | None = None,
        angular_velocity_body_rad_s: ArrayLike = (0, 0, 0),
    ) -> None:
        """Place a vehicle (its joints keep their state).

        Args:
            position_world_m: reference point, shape (3,), m, world ENU.
            roll_pitch_heading_rad: attitude, shape (3,), rad.
            velocity_world_m_s: velocity over ground, shape (3,), m/s, world ENU.
            vehicle: vehicle name or None for the first.
            angular_velocity_body_rad_s: angular velocity, shape (3,), rad/s, body FLU.
        """
        v = self._v(vehicle)
        p = np.asarray(position_world_m, dtype=float)
        a = np.asarray(roll_pitch_heading_rad, dtype=float)
        u = np.asarray(velocity_world_m_s, dtype=float)
        w = np.asarray(angular_velocity_body_rad_s, dtype=float)
        if (
            p.shape != (3,)
            or a.shape != (3,)
            or u.shape != (3,)
            or w.shape != (3,)
            or not np.all(np.isfinite(np.r_[p, a, u, w]))
        ):
            raise ConfigError(
                "set_pose: position, attitude and velocities must be 3 finite numbers each"
            )
        self.data.qpos[v.qpos_adr : v.qpos_adr + 3] = p
        self.data.qpos[v.qpos_adr + 3 : v.qpos_adr + 7] = frames.quat_wxyz_from_roll_pitch_heading(
            *a
        )
        self.data.qvel[v.dof_adr : v.dof_adr + 3] = u
        self.data.qvel[v.dof_adr + 3 : v.dof_adr + 6] = w
        mujoco.mj_forward(self.model.ptr, self.data.ptr)
        self._kinematics_stale = False

    def reset_to_keyframe(self, name: str) -> None:
        """Reset the simulation to a named keyframe (``home`` or ``trim`` of the plain scene).

        Args:
            name: keyframe name.
        """
        k = mujoco.mj_name2id(self.model.ptr, mujoco.mjtObj.mjOBJ_KEY, name)
        if k < 0:
            raise ConfigError(f"keyframe {name!r}: not in the model")
        self.reset(keyframe_id=k)
        self._kinematics_stale = False
        self.reset_energy()

    # ----------------------------------------------------------------------------------------
    # the sea

    @property
    def sea(self) -> Sea:
        """The sea the vehicles are in (still water with the free surface until :meth:`set_sea`)."""
        return self._sea

    def set_sea(self, sea: Sea) -> None:
        """Put the vehicles in a sea. It is applied now and at the start of every control tick of
        :meth:`advance` (or by :meth:`apply_sea`).

        The vehicles are carried by the change of the water: each vehicle's velocity over ground
        changes by the water velocity at it in the new sea minus the water it was in, so that its
        motion relative to the water (and its angular velocity and joints) is what it was. This is
        Galilean invariance, the motion of a neutrally buoyant body in a sea whose velocity changes
        as a whole: the Froude-Krylov force ``rho V a`` and the added mass's reaction ``M_A a``
        accelerate the body's mass and added mass with the water (``models/bauv/README.md``,
        "Current"). A vehicle placed with its speed through the water in still water (the default
        sea) and then put in a current therefore starts moving with the water, and a steady
        uniform current injected during a run carries the vehicle at once. (A current field that
        changes in time during a run is different water accelerating: that acts through the
        plugin's Froude-Krylov and added-mass forces over the tick, :mod:`bauv_sim.sea`.) To
        release a vehicle at rest over ground in a current that was always there, set its pose
        after the sea.

        Args:
            sea: the sea (current and free surface).
        """
        names = self.vehicle_names()
        before = [self.current_at_vehicle_world(n) for n in names]
        self._sea = sea
        self._sea_applied = False
        self.apply_sea()
        carried = False
        for name, w_before in zip(names, before, strict=True):
            change = self.current_at_vehicle_world(name) - w_before
            if np.any(change != 0.0):
                v = self._v(name)
                self.data.qvel[v.dof_adr : v.dof_adr + 3] += change
                carried = True
        if carried:
            # the sea's first tick saw the velocities before the carry (where a vehicle will be at
            # the tick's end): evaluate it again from the carried state
            self._sea.apply(self, again=True)

    def apply_sea(self) -> None:
        """Evaluate the sea at every vehicle now and apply it until the next call
        (:meth:`bauv_sim.sea.Sea.apply`). :meth:`advance` calls it at the start of every tick; a
        ``dm_control`` task that steps the physics itself calls it in ``before_step``."""
        self._sea.apply(self, again=self._sea_applied)
        self._sea_applied = True

    def set_water_world(
        self,
        velocity_world_m_s: ArrayLike,
        accel_world_m_s2: ArrayLike = (0.0, 0.0, 0.0),
        vehicle: str | None = None,
    ) -> None:
        """Set the water around a vehicle from now on: velocity ``w0`` now, changing at the rate
        ``a`` (``w(t) = w0 + a (t - now)``) until the next call. Every fluid force on the vehicle
        sees it (MuJoCo's through ``option wind`` for the first vehicle, set at every step; the
        others through :mod:`bauv_sim.hydro`), and so do :meth:`truth` and
        :meth:`current_at_vehicle_world`; ``a`` also drives the Froude-Krylov force and the added
        mass's reaction to the water's acceleration.

        Args:
            velocity_world_m_s: ``w0``, shape (3,), m/s, world ENU.
            accel_world_m_s2: ``a``, shape (3,), m/s^2, world ENU.
            vehicle: vehicle name or None for the first.

        Raises:
            ConfigError: if either is not 3 finite numbers.
        """
        v = self._v(vehicle)
        w = np.asarray(velocity_world_m_s, dtype=float)
        a = np.asarray(accel_world_m_s2, dtype=float)
        for name, x in (("water velocity", w), ("water acceleration", a)):
            if x.shape != (3,) or not np.all(np.isfinite(x)):
                raise ConfigError(f"{name} = {x!r}: expected 3 finite numbers (SI, world)")
        hydro.set_water(self.model.ptr, self.data.ptr, v.hydro_instance, w, a)
        if v.first:
            hydro.set_water_velocity(self.model.ptr, w)

    def current_at_vehicle_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Water velocity at the vehicle now (:meth:`set_water_world`), shape (3,), m/s, world."""
        return hydro.water(self.model.ptr, self.data.ptr, self._v(vehicle).hydro_instance)[0]

    def water_acceleration_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Rate of change of the water velocity at the vehicle over the current tick
        (:meth:`set_water_world`), shape (3,), m/s^2, world."""
        return hydro.water(self.model.ptr, self.data.ptr, self._v(vehicle).hydro_instance)[1]

    def set_buoyancy_scale(self, scale: float, vehicle: str | None = None) -> None:
        """Scale a vehicle's buoyancy (the gravity compensation of its buoyant bodies) to ``scale``
        times the model's; held until changed.

        Args:
            scale: 1 fully submerged, 0 out of the water.
            vehicle: vehicle name or None for the first.

        Raises:
            ConfigError: if it is not a finite number >= 0.
        """
        v = self._v(vehicle)
        if scale != v.buoyancy_scale:
            if not (math.isfinite(scale) and scale >= 0.0):
                raise ConfigError(f"buoyancy scale = {scale!r}: must be finite and >= 0")
            v.buoyancy_scale = scale
            self.model.ptr.body_gravcomp[v.float_bodies] = v.float_gravcomp * scale

    def buoyancy_scale(self, vehicle: str | None = None) -> float:
        """The scale of a vehicle's buoyancy set by :meth:`set_buoyancy_scale` (the submerged
        fraction the sea applies), 1 at load."""
        return self._v(vehicle).buoyancy_scale

    # ----------------------------------------------------------------------------------------
    # stepping

    def step(self, nstep: int = 1) -> None:
        """Advance ``nstep`` physics steps with the current commands (the sea is not applied),
        keeping the motor-energy accounts if they are on, and checking the state.

        Args:
            nstep: number of steps.

        Raises:
            PhysicsError: on a MuJoCo warning, a non-finite state or a time that did not advance,
                naming the simulation time of the first bad step.
        """
        m, d = self.model.ptr, self.data.ptr
        mujoco.mj_getState(m, d, self._state_buf, mujoco.mjtState.mjSTATE_INTEGRATION)
        warn0 = d.warning.number.copy()
        t0 = float(d.time)
        dt = float(m.opt.timestep)
        force, vel = d.actuator_force, d.actuator_velocity
        acc = [(v.name, v.act["motor"]) for v in self._vehicles.values()]
        w0, a0 = hydro.water(m, d, self._v(None).hydro_instance)
        ramp = bool(np.any(a0 != 0.0))
        if self._track_energy or ramp:
            energy = self._energy_j
            step = mujoco.mj_step
            wind = m.opt.wind
            for _ in range(int(nstep)):
                if ramp:  # MuJoCo's water is the first vehicle's, changing over the tick
                    wind[:] = w0 + a0 * (float(d.time) - t0)
                step(m, d)
                if self._track_energy:
                    for name, i in acc:
                        energy[name] += force[i] * vel[i] * dt
            if self._track_energy:
                self._energy_window_s += nstep * dt
        else:
            mujoco.mj_step(m, d, int(nstep))
        self._kinematics_stale = True
        if (
            np.any(d.warning.number != warn0)
            or not (
                np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all() and np.isfinite(d.act).all()
            )
            or not d.time > t0
        ):
            self._diagnose(t0, int(nstep), warn0.tolist(), (w0, a0) if ramp else None)

    def _diagnose(
        self,
        t0: float,
        nstep: int,
        warn0: list[int],
        ramp: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> None:
        """Replay the failed steps one by one from the saved state (the water ramped as
        :meth:`step` ramped it); raise at the first bad one."""
        m, d = self.model.ptr, self.data.ptr
        ctrl = np.array(d.ctrl)
        mujoco.mj_setState(m, d, self._state_buf, mujoco.mjtState.mjSTATE_INTEGRATION)
        d.ctrl[:] = ctrl
        for w in d.warning:
            w.number = 0
        for k in range(nstep):
            t_before = float(d.time)
            if ramp is not None:
                m.opt.wind[:] = ramp[0] + ramp[1] * (t_before - t0)
            mujoco.mj_step(m, d)
            msgs = []
            for i, w in enumerate(d.warning):
                if w.number > 0:
                    msgs.append(
                        f"MuJoCo warning {_WARNING_NAMES.get(i, i)} "
                        f"({_warning_detail(m, i, int(w.lastinfo))})"
                    )
            if not np.isfinite(d.qpos).all() or not np.isfinite(d.qvel).all():
                bad = np.flatnonzero(~np.isfinite(d.qvel))
                msgs.append(
                    "non-finite state"
                    + (f" at dof {_dof_name(m, int(bad[0]))}" if bad.size else "")
                )
            if not d.time > t_before:
                msgs.append(f"time did not advance (it is {d.time} s)")
            if msgs:
                raise PhysicsError(
                    f"physics failed at t = {t_before + m.opt.timestep:.4f} s "
                    f"(step {k + 1} of {nstep} from t = {t0:.4f} s): " + "; ".join(msgs)
                )
        raise PhysicsError(
            f"physics failed between t = {t0:.4f} s and "
            f"{t0 + nstep * m.opt.timestep:.4f} s, but not on replay "
            f"(warning counters before: {warn0})"
        )

    def advance(self, duration_s: float) -> None:
        """Advance the simulation by whole control ticks, applying the sea (:meth:`apply_sea`) at
        the start of each tick.

        Args:
            duration_s: time to simulate, s; a non-negative integer multiple of the control tick.

        Raises:
            ConfigError: if ``duration_s`` is not a whole number of ticks.
            PhysicsError: as :meth:`step`.
        """
        n = round(duration_s / self._control_tick_s)
        if n < 0 or abs(n * self._control_tick_s - duration_s) > 1e-9 * max(1.0, duration_s):
            raise ConfigError(
                f"duration = {duration_s} s: must be a non-negative whole number of "
                f"control ticks of {self._control_tick_s} s"
            )
        for _ in range(n):
            self.apply_sea()
            self.step(self._steps_per_tick)

    def time_s(self) -> float:
        """Simulation time, s."""
        return float(self.data.time)


def _dof_name(m: mujoco.MjModel, dof: int) -> str:
    j = int(m.dof_jntid[dof])
    return f"{dof} ({mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or 'free joint'})"


def _warning_detail(m: mujoco.MjModel, warning: int, info: int) -> str:
    if (
        warning
        in (
            int(mujoco.mjtWarning.mjWARN_BADQACC),
            int(mujoco.mjtWarning.mjWARN_BADQVEL),
            int(mujoco.mjtWarning.mjWARN_BADQPOS),
        )
        and 0 <= info < m.nv
    ):
        return f"dof {_dof_name(m, info)}"
    return f"info {info}"
