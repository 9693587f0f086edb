"""The index tables of the vehicles in a scene, and the base every part of the facade stands on.

A scene (:mod:`bauv_sim.build`, or the plain ``models/bauv/scene.xml``) holds one or more vehicles,
each the bodies under a body named ``hull`` or ``<name>/hull``. :func:`index_vehicles` finds them
and builds, once per model (re)load, each one's addresses in MuJoCo's arrays (free joint, joints,
actuators and their states, sensor sites), its drive's geometry and its instance of the
hydrodynamics plugin (:mod:`bauv_sim.hydro`). :class:`VehicleTables` is the base of the facade's
parts (:mod:`bauv_sim.physics_state`, :mod:`bauv_sim.physics_actuation`,
:class:`bauv_sim.physics.BauvPhysics`): a vehicle looked up by name, and MuJoCo's kinematics
brought up to date before a site or a body position is read.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from bauv_sim import hydro
from bauv_sim.errors import ConfigError

SENSOR_SITES: tuple[str, ...] = (
    "camera",
    "echo_forward",
    "usbl_transponder",
    "modem",
    "echo_up",
    "sonar",
    "echo_down",
    "em_log",
    "dvl",
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


@dataclass
class VehicleIndex:
    """Index tables of one vehicle (built once from names by :func:`index_vehicles`).

    Attributes:
        name: vehicle name (``bauv`` for the plain scene).
        prefix: its names' prefix in the model (``""`` or ``"<name>/"``).
        hull_body: body id of the hull.
        qpos_adr: address of the free joint in ``qpos`` (position, then quaternion w, x, y, z).
        dof_adr: address of the free joint in ``qvel`` (velocity world, angular velocity body).
        dofs: every dof of the vehicle's bodies.
        bodies: the vehicle's bodies (the free body's subtree).
        jnt_qpos: ``qpos`` address of each named joint (``_JOINTS``).
        jnt_dof: ``qvel`` address of each named joint.
        act: actuator id of each named actuator (``_ACTUATORS``).
        act_state: ``act`` address of each named actuator.
        sites: site id of each sensor site (:data:`SENSOR_SITES`).
        lever_m: the tail linkage's lever (the anchor on the peduncle), m.
        crank_m: the crank radius (the rod's pin offset), m.
        free_body: the body that carries the free joint (the hull or its attachment frame).
        hydro_instance: the vehicle's instance of the hydrodynamics plugin.
        first: whether it is the scene's first vehicle (whose water is MuJoCo's ``option wind``).
        float_bodies: the buoyant bodies (gravity compensation > 0).
        float_gravcomp: their gravity compensation in the model.
        buoyancy_scale: the scale of their buoyancy now (1 at load).
    """

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


def index_vehicles(m: mujoco.MjModel) -> dict[str, VehicleIndex]:
    """Find the vehicles of a compiled model and build their index tables.

    Args:
        m: the compiled model.

    Returns:
        The vehicles by name, in the model's body order.

    Raises:
        ConfigError: if the model has no vehicle, a vehicle misses a named joint, actuator, site or
            equality, its hull is offset from its free body or has none, or it has no instance of
            the hydrodynamics plugin.
    """
    vehicles: dict[str, VehicleIndex] = {}
    for b in range(m.nbody):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or ""
        if name.rsplit("/", 1)[-1] != "hull":
            continue
        prefix = name[: -len("hull")]
        vname = prefix.rstrip("/") or "bauv"
        vehicles[vname] = _index_one(m, vname, prefix, b)
    if not vehicles:
        raise ConfigError("model has no vehicle: no body named 'hull' or '<name>/hull'")
    instances = hydro.plugin_instances(m)
    for k, v in enumerate(vehicles.values()):
        if v.prefix not in instances:
            raise ConfigError(
                f"vehicle {v.name!r}: no {hydro.PLUGIN_NAME} plugin instance "
                f"{v.prefix + 'hydro'!r} (the vehicle's hydrodynamics)"
            )
        v.hydro_instance = instances[v.prefix]
        v.first = k == 0
    return vehicles


def _index_one(m: mujoco.MjModel, vname: str, prefix: str, hull: int) -> VehicleIndex:
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
    return VehicleIndex(
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


class VehicleTables:
    """The base of the facade's parts: the scene's vehicles by name and MuJoCo's kinematics kept
    up to date for reads of sites and bodies.

    Mixed into :class:`bauv_sim.physics.BauvPhysics` (a :class:`dm_control.mjcf.Physics`), which
    provides ``model`` and ``data`` and fills ``_vehicles`` on every (re)load
    (:func:`index_vehicles`); the parts above it read and write MuJoCo's arrays only through the
    tables of :meth:`_v`.
    """

    model: Any
    data: Any
    _vehicles: dict[str, VehicleIndex]
    _kinematics_stale: bool = True

    def vehicle_names(self) -> list[str]:
        """Names of the vehicles in the scene (``["bauv"]`` for the plain scene file)."""
        return list(self._vehicles)

    def _v(self, vehicle: str | None) -> VehicleIndex:
        if vehicle is None:
            return next(iter(self._vehicles.values()))
        try:
            return self._vehicles[vehicle]
        except KeyError:
            raise ConfigError(
                f"vehicle {vehicle!r}: not in the scene (have {', '.join(self._vehicles)})"
            ) from None

    def _ensure_kinematics(self) -> None:
        if self._kinematics_stale:
            mujoco.mj_kinematics(self.model.ptr, self.data.ptr)
            self._kinematics_stale = False
