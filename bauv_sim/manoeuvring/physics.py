"""The manoeuvring model as a mission's physics: a facade over one
:class:`~bauv_sim.manoeuvring.model.ManoeuvringWorld` run that the missions, the sea, the sensor
rig and the report read as they read :class:`bauv_sim.physics.BauvPhysics` (issue 27).

:class:`ManoeuvringPhysics` provides the part of the full facade that a one-vehicle mission
touches: the clock (``control_tick_s``, ``steps_per_tick``, ``time_s``), placing the vehicle
(``set_pose``), the truth record (:meth:`ManoeuvringPhysics.truth`, the same
:class:`~bauv_sim.physics_state.VehicleTruth`), the five actuator setters with the full model's
ranges and messages, the actuators' state and motor power for the run data, the water at the
vehicle (what a :class:`~bauv_sim.sea.Sea` applies), and the scene: sensor sites (their lever
arms, body FLU, read once from the MuJoCo scene the mission built), the USBL transceiver,
beacons and rays to the seabed (delegated to that scene, whose vehicle never moves: rays see
only the seabed's geom group). One :meth:`step` is one control tick of the model (its own
Runge-Kutta substeps), not a 4 ms MuJoCo step: ``steps_per_tick`` is 1.

What the model does not have, the facade refuses rather than imitates: a single vehicle per
physics (a scene of several is a :class:`~bauv_sim.errors.ConfigError`), no free surface (a
buoyancy scale below 1, which the sea applies when the hull reaches the surface, raises
:class:`~bauv_sim.errors.PhysicsError` with the time and depth), no contact.

Differences from the full facade, each by construction of the model (``models/bauv/README.md``,
Results 12 and 13):

* the attitude and angular velocity carry the tail beat's periodic heading and roll term; the
  position and velocity are beat-averaged;
* ``tail_angles_rad`` is the beat-averaged tail (the bias's filtered angle, 0 for the caudal
  joint), ``motor_power_w`` the straight-swim power at the commanded frequency;
* the water is the sea's velocity at the start of the tick for the truth record (as the full
  facade reports it); the model moves with the water at the middle of the tick, ``w0 + a tick
  / 2`` (exact for the sea's linear ramp); the water's acceleration exerts no force (the model
  moves with the water: a neutrally buoyant body in a uniform current);
* a vehicle carried with a change of the water (:meth:`shift_velocity_world`) needs nothing: the
  model's state is its velocity through the water.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import frames
from bauv_sim.errors import ConfigError, PhysicsError
from bauv_sim.manoeuvring.model import ManoeuvringCoefficients, ManoeuvringWorld
from bauv_sim.physics_index import SENSOR_SITES
from bauv_sim.physics_state import VehicleTruth

WORLDS: tuple[str, ...] = ("mujoco", "manoeuvring")
"""The physics a mission may fly in: the full MuJoCo vehicle, or the manoeuvring model."""


class _Data:
    """What :class:`~bauv_sim.sea.Sea` reads of ``physics.data``: ``ptr``, the identity of the
    simulation it last applied a steady current to."""

    def __init__(self, ptr: object) -> None:
        self.ptr = ptr


class ManoeuvringPhysics:
    """One BAUV under the manoeuvring model, behind the mission-facing accessors of
    :class:`bauv_sim.physics.BauvPhysics` (see the module docstring).

    Args:
        scene: the mission's MuJoCo scene (:func:`bauv_sim.build.build_physics`), one vehicle;
            read for the sensor sites, command ranges, transceiver, beacons and seabed, never
            stepped.
        control_tick_s: control tick, s (> 0): one :meth:`step`.
        coefficients: the identified model (default:
            :func:`~bauv_sim.manoeuvring.model.load_coefficients`).
        substeps: the model's Runge-Kutta substeps per tick (>= 1).

    Raises:
        ConfigError: a scene of more than one vehicle, or a bad tick or substep count.
    """

    legacy_step = False  # dm_control's Environment sets it; nothing to do with it here

    def __init__(
        self,
        scene: Any,
        control_tick_s: float,
        coefficients: ManoeuvringCoefficients | None = None,
        substeps: int = 2,
    ) -> None:
        names = tuple(scene.vehicle_names())
        if len(names) != 1:
            raise ConfigError(
                f"the manoeuvring world holds one vehicle; the scene has {len(names)} "
                f"({', '.join(names)})"
            )
        self.scene = scene
        self._name = names[0]
        self._coefficients = coefficients
        self._substeps = substeps
        self._limits = scene.command_limits(self._name)
        R = scene.R_world_from_body(self._name)
        p = scene.position_world(self._name)
        self._site_arms = {
            s: R.T @ (scene.site_position_world(s, self._name) - p) for s in SENSOR_SITES
        }
        self._tick_hook: Any = None
        self._data = _Data(self)
        self._new_world(control_tick_s)

    def _new_world(self, control_tick_s: float) -> None:
        self.world = ManoeuvringWorld(
            1, self._coefficients, tick_s=control_tick_s, substeps=self._substeps
        )
        self._coefficients = self.world.c
        self._water_w0 = np.zeros(3)
        self._commands = dict.fromkeys(self._limits, 0.0)
        self._buoyancy_scale = 1.0
        self._fault = False

    # ----------------------------------------------------------------------------------------
    # the clock (dm_control's Physics interface where an Environment reads it)

    @property
    def control_tick_s(self) -> float:
        """Control tick, s."""
        return self.world.tick_s

    @property
    def steps_per_tick(self) -> int:
        """Steps per control tick: 1 (a step of the model is a tick)."""
        return 1

    def set_control_tick(self, control_tick_s: float) -> None:
        """Set the control tick, s (finite, > 0).

        Raises:
            ConfigError: if it is not.
        """
        if not (math.isfinite(control_tick_s) and control_tick_s > 0):
            raise ConfigError(f"control tick = {control_tick_s!r} s: must be finite and > 0")
        self.world.tick_s = float(control_tick_s)

    def timestep(self) -> float:
        """The step, s: one control tick (what ``dm_control``'s Environment divides by)."""
        return self.world.tick_s

    def time_s(self) -> float:
        """Simulation time, s."""
        return float(self.world.time_s)

    def time(self) -> float:
        """Simulation time, s (``dm_control``'s name)."""
        return self.time_s()

    @contextlib.contextmanager
    def reset_context(self) -> Iterator[ManoeuvringPhysics]:
        """``dm_control``'s reset: the model starts anew (time 0, at rest, commands zero)."""
        self._new_world(self.world.tick_s)
        yield self

    @property
    def data(self) -> _Data:
        """The simulation's identity for :meth:`bauv_sim.sea.Sea.apply` (``data.ptr``)."""
        return self._data

    def vehicle_names(self) -> tuple[str, ...]:
        """The vehicle's name, a tuple of one."""
        return (self._name,)

    def _check(self, vehicle: str | None) -> None:
        if vehicle is not None and vehicle != self._name:
            raise ConfigError(f"vehicle {vehicle!r}: not in the scene (have {self._name!r})")

    # ----------------------------------------------------------------------------------------
    # placing and stepping

    def set_pose(
        self,
        position_world_m: ArrayLike,
        roll_pitch_heading_rad: ArrayLike = (0, 0, 0),
        velocity_world_m_s: ArrayLike = (0, 0, 0),
        vehicle: str | None = None,
        angular_velocity_body_rad_s: ArrayLike = (0, 0, 0),
    ) -> None:
        """Place the vehicle, as :meth:`bauv_sim.physics.BauvPhysics.set_pose`.

        Args:
            position_world_m: reference point, shape (3,), m, world ENU.
            roll_pitch_heading_rad: attitude, shape (3,), rad.
            velocity_world_m_s: velocity over ground, shape (3,), m/s, world ENU (its velocity
                through the water is this minus the water at the vehicle now).
            vehicle: vehicle name or None.
            angular_velocity_body_rad_s: angular velocity, shape (3,), rad/s, body FLU.

        Raises:
            ConfigError: if an argument is not 3 finite numbers.
        """
        self._check(vehicle)
        p = np.asarray(position_world_m, dtype=float)
        a = np.asarray(roll_pitch_heading_rad, dtype=float)
        u = np.asarray(velocity_world_m_s, dtype=float)
        w = np.asarray(angular_velocity_body_rad_s, dtype=float)
        if any(x.shape != (3,) for x in (p, a, u, w)) or not np.all(np.isfinite(np.r_[p, a, u, w])):
            raise ConfigError(
                "set_pose: position, attitude and velocities must be 3 finite numbers each"
            )
        wm = self.world
        wm.set_pose(p, a)
        R = wm.R_world_from_body()[0]
        wm.nu_r[0, :3] = R.T @ (u - self._water_w0)
        wm.nu_r[0, 3:] = w

    def step(self, nstep: int = 1) -> None:
        """Advance ``nstep`` control ticks with the commands in force.

        Raises:
            PhysicsError: on a non-finite state (or an injected fault), naming the time.
        """
        wm = self.world
        c = self._commands
        for _ in range(int(nstep)):
            t0 = wm.time_s
            wm.command(
                c["tail_beat_frequency_hz"],
                c["tail_bias_rad"],
                c["fin_port_rad"],
                c["fin_starboard_rad"],
                c["battery_position_m"],
            )
            wm.step()
            if self._fault or not (
                np.isfinite(wm.nu_r).all()
                and np.isfinite(wm.position_world_m).all()
                and np.isfinite(wm.euler_rad).all()
            ):
                raise PhysicsError(
                    f"manoeuvring model failed between t = {t0:.4f} s and {wm.time_s:.4f} s: "
                    "non-finite state" + (" (injected fault)" if self._fault else "")
                )

    def advance(self, duration_s: float) -> None:
        """Advance by whole control ticks, running the tick hook (a sea's
        :meth:`~bauv_sim.sea.Sea.apply`) at the start of each, as
        :meth:`bauv_sim.physics.BauvPhysics.advance`.

        Raises:
            ConfigError: if ``duration_s`` is not a whole number of ticks.
            PhysicsError: as :meth:`step`.
        """
        tick = self.world.tick_s
        n = round(duration_s / tick)
        if n < 0 or abs(n * tick - duration_s) > 1e-9 * max(1.0, duration_s):
            raise ConfigError(
                f"duration = {duration_s} s: must be a non-negative whole number of "
                f"control ticks of {tick} s"
            )
        for _ in range(n):
            if self._tick_hook is not None:
                self._tick_hook(self)
            self.step()

    def inject_fault(self) -> None:
        """Corrupt the state on purpose so that the next :meth:`step` raises
        :class:`~bauv_sim.errors.PhysicsError` (for tests of a mission's error handling)."""
        self._fault = True
        self.world.nu_r[:] = np.nan

    # ----------------------------------------------------------------------------------------
    # truth

    def truth(self, vehicle: str | None = None) -> VehicleTruth:
        """The true state now (:class:`~bauv_sim.physics_state.VehicleTruth`): attitude and
        angular velocity with the beat's periodic term, position and velocities beat-averaged;
        the water as the sea set it at the start of the tick."""
        self._check(vehicle)
        wm = self.world
        roll, pitch, head = wm.roll_pitch_heading()[0].tolist()
        quat = frames.quat_wxyz_from_roll_pitch_heading_scalar(roll, pitch, head)
        pos = wm.position_world_m[0].copy()
        vtw = wm.velocity_through_water_world()[0]
        cur = self._water_w0.copy()
        return VehicleTruth(
            float(wm.time_s),
            pos,
            quat,
            np.array([roll, pitch, head]),
            float(-pos[2]),
            vtw + cur,
            vtw,
            cur,
            wm.angular_velocity_body()[0],
        )

    def position_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Reference point (hull origin), shape (3,), m, world ENU."""
        self._check(vehicle)
        return self.world.position_world_m[0].copy()

    def depth_m(self, vehicle: str | None = None) -> float:
        """Depth of the reference point, m (positive down)."""
        self._check(vehicle)
        return float(-self.world.position_world_m[0, 2])

    def roll_pitch_heading(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """(roll, pitch, heading), shape (3,), rad, with the beat's term."""
        self._check(vehicle)
        return self.world.roll_pitch_heading()[0]

    def heading_rad(self, vehicle: str | None = None) -> float:
        """Heading, clockwise from north in [0, 2 pi), rad, with the beat's term."""
        return float(self.roll_pitch_heading(vehicle)[2])

    def quat_wxyz(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Attitude quaternion (w, x, y, z), body FLU to world ENU, shape (4,)."""
        roll, pitch, head = self.roll_pitch_heading(vehicle)
        return frames.quat_wxyz_from_roll_pitch_heading_scalar(
            float(roll), float(pitch), float(head)
        )

    def R_world_from_body(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Rotation body FLU -> world ENU of the attitude with the beat's term, shape (3, 3)."""
        return frames.R_from_quat_wxyz(self.quat_wxyz(vehicle))

    def velocity_through_water_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity relative to the water, shape (3,), m/s, world ENU."""
        self._check(vehicle)
        return self.world.velocity_through_water_world()[0]

    def velocity_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity over ground (through the water plus the water at the vehicle), shape (3,),
        m/s, world ENU."""
        return self.velocity_through_water_world(vehicle) + self._water_w0

    def angular_velocity_body(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Angular velocity with the beat's rates, shape (3,), rad/s, body FLU."""
        self._check(vehicle)
        return self.world.angular_velocity_body()[0]

    def site_position_world(self, name: str, vehicle: str | None = None) -> NDArray[np.float64]:
        """Position of a sensor site (its lever arm in the vehicle model, rotated with the
        attitude), shape (3,), m, world ENU.

        Raises:
            ConfigError: for a name that is not in :data:`~bauv_sim.physics_index.SENSOR_SITES`.
        """
        self._check(vehicle)
        if name not in self._site_arms:
            raise ConfigError(f"site {name!r}: not a sensor site (have {', '.join(SENSOR_SITES)})")
        return self.position_world() + self.R_world_from_body() @ self._site_arms[name]

    def scene_site_world(self, name: str) -> NDArray[np.float64]:
        """A site of the scene (transceiver, beacons), shape (3,), m, world ENU."""
        return self.scene.scene_site_world(name)

    def transceiver_world(self) -> NDArray[np.float64]:
        """The USBL transceiver, shape (3,), m, world ENU."""
        return self.scene.transceiver_world()

    def beacons_world(self) -> dict[str, NDArray[np.float64]]:
        """The acoustic beacons by name, each shape (3,), m, world ENU."""
        return self.scene.beacons_world()

    def seabed_ray_distances(
        self, origin_world_m: ArrayLike, directions_world: ArrayLike, max_range_m: float
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Distances along rays to the scene's seabed
        (:meth:`bauv_sim.physics_state.VehicleState.seabed_ray_distances`)."""
        return self.scene.seabed_ray_distances(origin_world_m, directions_world, max_range_m)

    # ----------------------------------------------------------------------------------------
    # actuators

    def _set(self, key: str, value: float, what: str, unit: str) -> None:
        lo, hi = self._limits[key]
        if not (math.isfinite(value) and lo - 1e-12 <= value <= hi + 1e-12):
            raise ConfigError(f"{what} = {value:.6g} {unit}: must be within [{lo:.6g}, {hi:.6g}]")
        self._commands[key] = float(value)

    def set_tail_beat_frequency_hz(self, frequency_hz: float, vehicle: str | None = None) -> None:
        """Command the tail-beat frequency, Hz (within the motor's range)."""
        self._check(vehicle)
        self._set("tail_beat_frequency_hz", frequency_hz, "tail-beat frequency", "Hz")

    def set_tail_bias_rad(self, bias_rad: float, vehicle: str | None = None) -> None:
        """Command the tail bias, rad (tail to port +, within the carriage's range)."""
        self._check(vehicle)
        self._set("tail_bias_rad", bias_rad, "tail bias", "rad")

    def set_lateral_fins_rad(
        self, port_rad: float, starboard_rad: float, vehicle: str | None = None
    ) -> None:
        """Command the lateral fins, rad (leading edge up +)."""
        self._check(vehicle)
        self._set("fin_port_rad", float(port_rad), "port fin angle", "rad")
        self._set("fin_starboard_rad", float(starboard_rad), "starboard fin angle", "rad")

    def set_battery_position_m(self, position_m: float, vehicle: str | None = None) -> None:
        """Command the battery position along body x, m (forward +)."""
        self._check(vehicle)
        self._set("battery_position_m", float(position_m), "battery position", "m")

    def commands(self, vehicle: str | None = None) -> dict[str, float]:
        """The commands in force, in the setters' units."""
        self._check(vehicle)
        return dict(self._commands)

    def command_limits(self, vehicle: str | None = None) -> dict[str, tuple[float, float]]:
        """The range of every command (the full model's), in the setters' units."""
        self._check(vehicle)
        return dict(self._limits)

    def tail_angles_rad(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """The beat-averaged tail: (the bias's filtered angle, 0), shape (2,), rad."""
        self._check(vehicle)
        return np.array([float(self.world.bias_rad[0]), 0.0])

    def lateral_fin_angles_rad(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """(port, starboard) filtered fin angles, shape (2,), rad."""
        self._check(vehicle)
        return self.world.fins_rad[0].copy()

    def battery_position_m(self, vehicle: str | None = None) -> float:
        """Filtered battery position, m."""
        self._check(vehicle)
        return float(self.world.battery_m[0])

    def motor_power_w(self, vehicle: str | None = None) -> float:
        """Mean motor power at the commanded frequency (the model's straight-swim table), W."""
        self._check(vehicle)
        return float(self.world.motor_power_w()[0])

    # ----------------------------------------------------------------------------------------
    # the sea

    def set_tick_hook(self, hook: Any) -> None:
        """What :meth:`advance` runs at the start of every tick (a sea's ``apply``, installed by
        :meth:`bauv_sim.sea.Sea.immerse`); a mission's task applies its sea itself."""
        self._tick_hook = hook

    def current_at_vehicle_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """The water at the vehicle as last set, shape (3,), m/s, world ENU."""
        self._check(vehicle)
        return self._water_w0.copy()

    def set_water_world(
        self,
        velocity_world_m_s: ArrayLike,
        accel_world_m_s2: ArrayLike = (0.0, 0.0, 0.0),
        vehicle: str | None = None,
    ) -> None:
        """Set the water at the vehicle for the next tick: ``w0`` now, changing at ``a``; the model
        moves with ``w0 + a tick / 2`` over the tick (module docstring).

        Raises:
            ConfigError: if either is not 3 finite numbers.
        """
        self._check(vehicle)
        w = np.asarray(velocity_world_m_s, dtype=float)
        a = np.asarray(accel_world_m_s2, dtype=float)
        for name, x in (("water velocity", w), ("water acceleration", a)):
            if x.shape != (3,) or not np.all(np.isfinite(x)):
                raise ConfigError(f"{name} = {x!r}: expected 3 finite numbers (SI, world)")
        self._water_w0 = w.copy()
        self.world.set_current_world(w + a * (0.5 * self.world.tick_s))

    def shift_velocity_world(self, delta_world_m_s: ArrayLike, vehicle: str | None = None) -> None:
        """The vehicle carried with a change of the water: nothing to do (the model's state is
        the velocity through the water, which the carry keeps).

        Raises:
            ConfigError: if the change is not 3 finite numbers.
        """
        self._check(vehicle)
        delta = np.asarray(delta_world_m_s, dtype=float)
        if delta.shape != (3,) or not np.all(np.isfinite(delta)):
            raise ConfigError(f"velocity change = {delta!r}: expected 3 finite numbers, m/s, world")

    def set_buoyancy_scale(self, scale: float, vehicle: str | None = None) -> None:
        """The sea's free surface: the model has none, so a scale below 1 (the hull at the
        surface) stops the run.

        Raises:
            PhysicsError: for a scale below 1, naming the time and depth.
        """
        self._check(vehicle)
        if scale < 1.0:
            raise PhysicsError(
                f"manoeuvring model at t = {self.time_s():.2f} s: the hull reached the surface "
                f"(depth {self.depth_m():.3f} m, submerged fraction {scale:.3f}); the model has "
                "no free surface (fly timing.world = 'mujoco')"
            )
        self._buoyancy_scale = float(scale)

    def buoyancy_scale(self, vehicle: str | None = None) -> float:
        """1: the model is always fully submerged."""
        self._check(vehicle)
        return self._buoyancy_scale
