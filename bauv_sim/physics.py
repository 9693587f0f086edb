"""The physics facade: the BAUV in MuJoCo, with named accessors and actuation.

:class:`BauvPhysics` is a :class:`dm_control.mjcf.Physics` (so ``dm_control.rl.control``
environments and :mod:`dm_control.mjcf` binding work) and, with its parts, the **only** code in the
project that indexes MuJoCo's state arrays (``qpos``, ``qvel``, ``act``, ``ctrl``,
``actuator_force``, ``site_xpos``, ``qfrc_*``). Everything else calls its accessors, whose names
carry units and frames:

* frames: world ENU (x east, y north, z up), body FLU (x forward, y port, z up), heading clockwise
  from north (:mod:`bauv_sim.frames`); the vehicle's reference point is the hull body's origin;
* one scene may hold several vehicles (``leader``, ``follower``): every accessor and setter takes
  ``vehicle=None`` (the first vehicle) or a vehicle name from :meth:`BauvPhysics.vehicle_names`.

The facade is assembled from parts that read alone, each standing on the one before:

* :mod:`bauv_sim.physics_index`: the vehicles' index tables, built once per model (re)load;
* :mod:`bauv_sim.physics_state`: the truth accessors (pose, attitude, depth, velocities, sites,
  :meth:`~bauv_sim.physics_state.VehicleState.truth`, hydrostatics, fluid forces);
* :mod:`bauv_sim.physics_actuation`: actuation and energy (motor, tail, fins, battery trim, the
  motor-energy accounts) and the inputs from outside the vehicle (the water at each vehicle, its
  buoyancy, test inputs);
* this module: loading, the timestep and the control tick, placing the vehicles, stepping.

The physics owns no sea. Whoever runs it applies one (:class:`bauv_sim.sea.Sea`: current and free
surface) through the primitives of the actuation part: the water at each vehicle and the scale of
its buoyancy. A mission's task applies its sea before every physics step; a loop that advances
the physics by control ticks (:meth:`BauvPhysics.advance`) has it applied at the start of every
tick by the tick hook the sea installs (:meth:`bauv_sim.sea.Sea.immerse`,
:meth:`BauvPhysics.set_tick_hook`). Without a sea nothing is applied: the water and the buoyancy
stay as last set (still water and full buoyancy, at any depth, as loaded).

Time advances in control ticks (:meth:`BauvPhysics.advance`): at the start of each tick the tick
hook runs, then the physics runs the tick's ``n`` steps of ``timestep``. The control tick is an
integer multiple of the timestep, checked. Divergence, non-finite state and any MuJoCo warning
raise :class:`~bauv_sim.errors.PhysicsError` with the simulation time of the step where it
happened (auto-reset is disabled in the model).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
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
from bauv_sim.physics_actuation import Actuation
from bauv_sim.physics_index import SENSOR_SITES, index_vehicles
from bauv_sim.physics_state import VehicleTruth

__all__ = [
    "DEFAULT_CONTROL_TICK_S",
    "SENSOR_SITES",
    "BauvPhysics",
    "TickHook",
    "VehicleTruth",
]

DEFAULT_CONTROL_TICK_S = 0.1
"""Default control tick, s (50 physics steps of 2 ms)."""

_WARNING_NAMES = {
    int(v): k for k, v in mujoco.mjtWarning.__members__.items() if k.startswith("mjWARN")
}


TickHook = Callable[["BauvPhysics"], None]
"""What runs at the start of every control tick of :meth:`BauvPhysics.advance`: a callable of the
physics (a sea's :meth:`~bauv_sim.sea.Sea.apply`)."""


class BauvPhysics(Actuation, mjcf.Physics):
    """MuJoCo physics of one or more BAUVs, with named accessors and actuation.

    Build it with :func:`bauv_sim.build.build_physics` (``dm_control.mjcf`` scenes, several
    vehicles) or :meth:`from_scene_xml` (the plain ``models/bauv/scene.xml``). The fluid forces
    beyond MuJoCo's drag are the engine plugin ``bauv.hydro``, one instance per vehicle, declared
    in the model (:mod:`bauv_sim.hydro`); on every (re)load each vehicle is matched to its
    instance, whose water a sea sets each tick (:meth:`set_water_world`).
    """

    _control_tick_s: float = DEFAULT_CONTROL_TICK_S
    _timestep_s: float | None = None
    _tick_hook: TickHook | None = None

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
        self._vehicles = {}
        super()._reload_from_data(data)
        self._vehicles = index_vehicles(self.model.ptr)
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
        ``models/bauv/README.md`` ("Timestep presets", ``python models/bauv/tools/timestep.py``).
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

    def set_const(self) -> None:
        """Run ``mj_setConst`` (the plugin zeroes the virtual masses it recomputes again at the next
        step)."""
        mujoco.mj_setConst(self.model.ptr, self.data.ptr)

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
    # the tick hook (the sea, applied by whoever runs the physics)

    @property
    def tick_hook(self) -> TickHook | None:
        """What :meth:`advance` runs at the start of every control tick (None: nothing)."""
        return self._tick_hook

    def set_tick_hook(self, hook: TickHook | None) -> None:
        """Set what :meth:`advance` runs at the start of every control tick: a sea puts its
        :meth:`~bauv_sim.sea.Sea.apply` here when it is put around the vehicles
        (:meth:`bauv_sim.sea.Sea.immerse`). Kept over model reloads. A ``dm_control`` task that
        steps the physics itself applies its sea in ``before_step`` instead.

        Args:
            hook: a callable of the physics, or None for nothing.

        Raises:
            ConfigError: if it is neither.
        """
        if hook is not None and not callable(hook):
            raise ConfigError(f"tick hook = {hook!r}: must be a callable of the physics or None")
        self._tick_hook = hook

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
        instance = self._v(None).hydro_instance
        # the water's rate (hydro.water's second part) decides; its velocity only for a ramp
        ramp = bool(hydro._water_slice(m, d, instance)[3:6].any())
        if self._track_energy or ramp:
            w0, a0 = hydro.water(m, d, instance)
            dt = float(m.opt.timestep)
            force, vel = d.actuator_force, d.actuator_velocity
            acc = [(v.name, v.act["motor"]) for v in self._vehicles.values()]
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
            (d.warning.number != warn0).any()
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
        """Advance the simulation by whole control ticks, running the tick hook (a sea's
        :meth:`~bauv_sim.sea.Sea.apply`, :meth:`set_tick_hook`) at the start of each tick.

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
        hook = self._tick_hook
        for _ in range(n):
            if hook is not None:
                hook(self)
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
