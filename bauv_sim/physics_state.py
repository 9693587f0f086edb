"""The truth accessors of the facade: where the vehicles are, how they move, and what acts on
them, read from MuJoCo's state.

:class:`VehicleState` is the part of :class:`bauv_sim.physics.BauvPhysics` that reads and never
writes the simulation (apart from bringing derived quantities up to date: kinematics, forward
dynamics): pose, attitude, depth, velocities over ground and through the water, sensor and scene
sites, rays to the seabed, :meth:`VehicleState.truth` (what sensors may read), hydrostatics, mass
and inertia, fluid and constraint forces. Every accessor takes ``vehicle=None`` (the first vehicle)
or a vehicle name; its name carries its units and frame: world ENU (x east, y north, z up), body
FLU (x forward, y port, z up), heading clockwise from north (:mod:`bauv_sim.frames`); the
vehicle's reference point is the hull body's origin.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import frames, hydro
from bauv_sim.errors import ConfigError
from bauv_sim.physics_index import SENSOR_SITES, VehicleTables


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


class VehicleState(VehicleTables):
    """Truth accessors of :class:`bauv_sim.physics.BauvPhysics` (see the module docstring)."""

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

    def constraint_wrench(
        self, vehicle: str | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The constraint force on the vehicle's free joint at the last step (a carriage's weld:
        the vehicle's internal constraints cancel there): force (3,), N, world ENU, and moment
        about the reference point (3,), N m, body FLU."""
        v = self._v(vehicle)
        q = self.data.qfrc_constraint[v.dof_adr : v.dof_adr + 6]
        return np.array(q[:3]), np.array(q[3:])

    def com_velocity_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Velocity of the vehicle's centre of mass (all its bodies), shape (3,), m/s, world."""
        v = self._v(vehicle)
        m, d = self.model.ptr, self.data.ptr
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        return np.array(d.subtree_linvel[v.free_body])

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
        """Density of the water (the plugin's ``hydro_water``, or MuJoCo's ``option density``
        in a model without it: :func:`bauv_sim.hydro.water_properties`), kg/m^3."""
        return hydro.water_properties(self.model.ptr)[0]

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
    # the water at the vehicles (set by the sea: bauv_sim.physics_actuation.Actuation)

    def current_at_vehicle_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Water velocity at the vehicle now (:meth:`set_water_world`), shape (3,), m/s, world."""
        return hydro.water(self.model.ptr, self.data.ptr, self._v(vehicle).hydro_instance)[0]

    def water_acceleration_world(self, vehicle: str | None = None) -> NDArray[np.float64]:
        """Rate of change of the water velocity at the vehicle over the current tick
        (:meth:`set_water_world`), shape (3,), m/s^2, world."""
        return hydro.water(self.model.ptr, self.data.ptr, self._v(vehicle).hydro_instance)[1]
