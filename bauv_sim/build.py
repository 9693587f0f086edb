"""Scene assembly with :mod:`dm_control.mjcf`: one or more BAUVs in the sea.

The environment (seabed, USBL transceiver, acoustic beacons, light, visual settings) is the one of
``models/bauv/scene.xml`` with its ``<include file="bauv.xml"/>`` taken out; each vehicle is a copy
of ``models/bauv/bauv.xml`` attached under its own name, so that every element of vehicle
``leader`` is called ``leader/...`` (``leader/hull``, ``leader/usbl_transponder``, ...). The
vehicle's free joint moves from its hull to the attachment frame and its keyframes are dropped
(initial poses are set on the compiled physics instead).

A :class:`SceneConfig` may replace the seabed (generated in memory, or resampled from the site's
bathymetry file around the scene's geographic origin ``geo``, :mod:`bauv_sim.seabed`), move
the transceiver and replace the beacons; sites are placed on the seabed surface of the scene's own
heightfield.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from pydantic import Field, field_validator, model_validator

from bauv_sim import hydro_native
from bauv_sim import seabed as sb
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.frames import unit_vector_scalar
from bauv_sim.geo import GeoOriginConfig
from bauv_sim.hull import MODEL_DIR
from bauv_sim.physics import DEFAULT_CONTROL_TICK_S, BauvPhysics, mjcf

VEHICLE_XML = MODEL_DIR / "bauv.xml"
"""The vehicle model file."""

SCENE_XML = MODEL_DIR / "scene.xml"
"""The default scene file (environment plus one vehicle by ``<include>``)."""

VEHICLE_CLEARANCE_M = 0.25
"""Smallest allowed height of a vehicle's reference point above the seabed at its initial position,
m (the hull's half-height is 0.17 m)."""


class VehicleSpec(Config):
    """One vehicle of a scene.

    Attributes:
        name: element prefix (``leader`` gives ``leader/hull``); letters, digits, ``_``, ``-``.
        east_m: initial position east, m.
        north_m: initial position north, m.
        depth_m: initial depth of the reference point, m (positive down).
        heading_deg: initial heading, clockwise from north, deg.
        speed_m_s: initial speed along the heading, m/s.
    """

    name: str = "bauv"
    east_m: float = 0.0
    north_m: float = 0.0
    depth_m: float = Field(3.0, ge=0.0)
    heading_deg: float = Field(0.0, ge=0.0, lt=360.0)
    speed_m_s: float = Field(0.0, ge=0.0, le=3.0)

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not v or not all(ch.isalnum() or ch in "_-" for ch in v):
            raise ValueError("must be non-empty letters, digits, '_' or '-'")
        return v


class BeaconSpec(Config):
    """An acoustic beacon, moored above the seabed."""

    name: str
    east_m: float
    north_m: float
    height_above_seabed_m: float = Field(1.0, ge=0.0)


DEFAULT_BEACONS: tuple[BeaconSpec, ...] = tuple(
    BeaconSpec(name=f"beacon_{i}", east_m=e, north_m=n)
    for i, (e, n) in enumerate([(300.0, 300.0), (-300.0, 300.0), (-300.0, -300.0), (300.0, -300.0)])
)
"""The beacons of ``models/bauv/scene.xml``."""


class SceneConfig(Config):
    """A scene: vehicles, seabed, USBL transceiver, beacons.

    Attributes:
        vehicles: the vehicles, at least one, distinct names.
        seabed: the seabed (generated, or from a bathymetry file).
        geo: the scene's origin on the Earth (WGS 84), needed by a bathymetry file
            (``seabed.file``); None: a local frame only.
        transceiver_east_m: USBL transceiver position east, m.
        transceiver_north_m: USBL transceiver position north, m.
        transceiver_height_above_seabed_m: height of the transceiver's transducer, m.
        beacons: the acoustic beacons.
    """

    vehicles: tuple[VehicleSpec, ...] = (VehicleSpec(),)
    seabed: sb.SeabedConfig = sb.SeabedConfig()
    geo: GeoOriginConfig | None = None
    transceiver_east_m: float = 0.0
    transceiver_north_m: float = 0.0
    transceiver_height_above_seabed_m: float = Field(0.0, ge=0.0)
    beacons: tuple[BeaconSpec, ...] = DEFAULT_BEACONS

    @model_validator(mode="after")
    def _names(self) -> SceneConfig:
        names = [v.name for v in self.vehicles]
        if not names:
            raise ValueError("vehicles: need at least one")
        if len(set(names)) != len(names):
            raise ValueError(f"vehicles: names must be distinct, got {names}")
        b = [x.name for x in self.beacons]
        if len(set(b)) != len(b):
            raise ValueError(f"beacons: names must be distinct, got {b}")
        return self


def _environment() -> mjcf.RootElement:
    """The scene file without its vehicle include, as a PyMJCF root."""
    tree = ET.parse(SCENE_XML)
    root = tree.getroot()
    for inc in root.findall("include"):
        root.remove(inc)
    text = ET.tostring(root, encoding="unicode")
    return mjcf.from_xml_string(text, model_dir=str(MODEL_DIR))


def _vehicle(name: str) -> mjcf.RootElement:
    v = mjcf.from_path(str(VEHICLE_XML))
    v.model = name
    hull = v.find("body", "hull")
    if hull is None or hull.freejoint is None:
        raise ConfigError(f"{VEHICLE_XML}: expected body 'hull' with a free joint")
    hull.freejoint.remove()
    hull.pos = [0.0, 0.0, 0.0]
    for key in list(v.keyframe.key):
        key.remove()
    return v


def build_scene(config: SceneConfig | None = None) -> tuple[mjcf.RootElement, sb.Seabed]:
    """Assemble a scene.

    Args:
        config: the scene; the default scene (``models/bauv/scene.xml`` with one vehicle named
            ``bauv``) when None.

    Returns:
        ``(root, seabed)``: the PyMJCF model and the seabed it uses.

    Raises:
        GeometryError: if a site or vehicle would lie outside the seabed grid, or a vehicle below
            or too close to the seabed.
        ConfigError: for a bathymetry file that cannot serve (:func:`bauv_sim.seabed.generate`).
    """
    cfg = config or SceneConfig()
    root = _environment()
    bed = sb.generate(cfg.seabed, None if cfg.geo is None else cfg.geo.frame())
    if cfg.seabed != sb.SeabedConfig():
        hf = root.find("hfield", "seabed")
        hf.file = mjcf.Asset(bed.to_bytes(), ".bin")
        hf.size = list(bed.hfield_size())
    root.find("geom", "seabed").pos = [0.0, 0.0, bed.z_min_m]

    def on_bed(x: float, y: float, above: float) -> list[float]:
        return [x, y, float(bed.height_world(x, y)) + above]

    root.find("site", "usbl_transceiver").pos = on_bed(
        cfg.transceiver_east_m, cfg.transceiver_north_m, cfg.transceiver_height_above_seabed_m
    )
    template = root.find("site", "beacon_0")
    style = {"size": template.size, "type": template.type, "material": template.material}
    for site in [s for s in root.worldbody.site if s.name.startswith("beacon_")]:
        site.remove()
    for b in cfg.beacons:
        root.worldbody.add(
            "site", name=b.name, pos=on_bed(b.east_m, b.north_m, b.height_above_seabed_m), **style
        )
    for spec in cfg.vehicles:
        try:
            floor = float(bed.height_world(spec.east_m, spec.north_m))
        except GeometryError:
            floor = -math.inf
        z = -spec.depth_m
        if z < floor + VEHICLE_CLEARANCE_M:
            raise GeometryError(
                f"vehicle {spec.name!r} at depth {spec.depth_m} m is below or within "
                f"{VEHICLE_CLEARANCE_M} m of the seabed (depth {-floor:.2f} m there)"
            )
        frame = root.worldbody.attach(_vehicle(spec.name))
        frame.add("freejoint", name="root")
        frame.pos = [spec.east_m, spec.north_m, z]
    return root, bed


def initial_velocities(config: SceneConfig) -> dict[str, np.ndarray]:
    """Initial velocity over ground of each vehicle, world ENU, m/s, by vehicle name."""
    out = {}
    for v in config.vehicles:
        east, north = unit_vector_scalar(math.radians(v.heading_deg))
        out[v.name] = np.array([v.speed_m_s * east, v.speed_m_s * north, 0.0])
    return out


def _mujoco_fluid_model(root: mjcf.RootElement) -> None:
    """Give the vehicles' water (numeric ``hydro_water``) back to MuJoCo's fluid model (``option
    density`` and ``viscosity``) and take it from the plugin: the model as before issue 27."""
    water = [n for n in root.find_all("numeric") if n.name == "hydro_water"]
    if not water:
        raise ConfigError("hydrodynamics = 'mujoco-fluid': the vehicles have no 'hydro_water'")
    rho, mu = (float(x) for x in water[0].data)
    for n in water:
        n.remove()
    root.option.density, root.option.viscosity = rho, mu


def build_physics(
    config: SceneConfig | None = None,
    control_tick_s: float = DEFAULT_CONTROL_TICK_S,
    timestep_s: float | None = None,
    hydrodynamics: str | None = None,
) -> BauvPhysics:
    """Assemble, compile and initialise a scene.

    Args:
        config: the scene (default: :class:`SceneConfig` defaults).
        control_tick_s: control tick, s (an integer multiple of the timestep).
        timestep_s: physics timestep, s; None keeps the model file's 2 ms
            (:meth:`BauvPhysics.set_timestep`).
        hydrodynamics: ``"plugin"`` (the engine plugin ``bauv.hydro``), ``"native"`` (MuJoCo's
            own parameters plus one passive callback, :mod:`bauv_sim.hydro_native`) or
            ``"mujoco-fluid"`` (the plugin with MuJoCo's fluid model doing the ellipsoid forces,
            as before issue 27: for validation); None: the current
            :func:`bauv_sim.hydro_native.formulation` (``"plugin"`` by default).

    Returns:
        The physics with every vehicle at its initial pose and speed, all commands zero.
    """
    cfg = config or SceneConfig()
    root, _ = build_scene(cfg)
    kind = hydro_native.check_formulation(hydrodynamics or hydro_native.current_formulation())
    if kind == "mujoco-fluid":
        _mujoco_fluid_model(root)
    with hydro_native.compiling():
        if kind == "native":
            xml = hydro_native.strip_plugin_xml(root.to_xml_string(), len(cfg.vehicles))
            phys = BauvPhysics.from_xml_string(xml, assets=root.get_assets())
        else:
            phys = BauvPhysics.from_mjcf_model(root)
    if kind == "native":
        hydro_native.prepare(phys.model.ptr, phys.data.ptr)
    if timestep_s is not None:
        phys.set_timestep(timestep_s, control_tick_s)
    else:
        phys.set_control_tick(control_tick_s)
    vel = initial_velocities(cfg)
    for v in cfg.vehicles:
        phys.set_pose(
            [v.east_m, v.north_m, -v.depth_m],
            [0.0, 0.0, math.radians(v.heading_deg)],
            vel[v.name],
            vehicle=v.name,
        )
    return phys


def export_scene(config: SceneConfig, out_dir: str | Path) -> Path:
    """Write an assembled scene (XML and its assets) to a folder, for inspection or plain loading.

    Args:
        config: the scene.
        out_dir: target folder.

    Returns:
        Path of the written XML file.
    """
    root, _ = build_scene(config)
    out = Path(out_dir)
    mjcf.export_with_assets(root, str(out), out_file_name="scene.xml")
    return out / "scene.xml"
