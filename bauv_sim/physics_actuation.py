"""Actuation and energy of the facade: what drives the vehicles, and the energy it takes.

:class:`Actuation` is the part of :class:`bauv_sim.physics.BauvPhysics` that writes the
simulation's inputs: each vehicle's five actuators in their own units (tail-beat frequency, tail
bias, the two lateral fins, the battery's position for trim) with their ranges checked, their
state (crank, tail, fins, battery), the motor's torque and power and the motor-energy accounts
kept by :meth:`bauv_sim.physics.BauvPhysics.step`; and the inputs from outside the vehicle that a
task sets: the water around each vehicle and the scale of its buoyancy (what a sea applies,
:mod:`bauv_sim.sea`), a vehicle carried with a change of the water, an external force at the
centre of gravity, a mocap body, a joint's stiffness, a fault on purpose. It stands on the truth
accessors (:class:`bauv_sim.physics_state.VehicleState`).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import hydro
from bauv_sim.errors import ConfigError
from bauv_sim.physics_index import VehicleIndex
from bauv_sim.physics_state import VehicleState


class Actuation(VehicleState):
    """Actuation, energy and external inputs of :class:`bauv_sim.physics.BauvPhysics` (see the
    module docstring)."""

    _track_energy: bool = False
    _energy_j: dict[str, float]
    _energy_window_s: float

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

    def _set_ctrl(self, v: VehicleIndex, name: str, value: float, what: str, unit: str) -> None:
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
    # inputs from outside the vehicle: the water, buoyancy, test inputs

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

    def shift_velocity_world(self, delta_world_m_s: ArrayLike, vehicle: str | None = None) -> None:
        """Add a velocity to a vehicle's velocity over ground, its angular velocity and joints
        kept: the vehicle carried with a change of the water (:meth:`bauv_sim.sea.Sea.immerse`).

        Args:
            delta_world_m_s: the change, shape (3,), m/s, world ENU.
            vehicle: vehicle name or None for the first.

        Raises:
            ConfigError: if the change is not 3 finite numbers.
        """
        v = self._v(vehicle)
        delta = np.asarray(delta_world_m_s, dtype=float)
        if delta.shape != (3,) or not np.all(np.isfinite(delta)):
            raise ConfigError(f"velocity change = {delta!r}: expected 3 finite numbers, m/s, world")
        self.data.qvel[v.dof_adr : v.dof_adr + 3] += delta

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

    def inject_fault(self) -> None:
        """Corrupt the simulation on purpose (a NaN motor command), so that the next step raises
        :class:`~bauv_sim.errors.PhysicsError`: for tests of a mission's error handling."""
        self.data.ctrl[self._v(None).act["motor"]] = np.nan
