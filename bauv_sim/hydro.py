"""Run-time hydrodynamics and hydrostatics of the BAUV's compiled MuJoCo model.

MuJoCo's ellipsoid fluid model gives each part's drag; it has no buoyancy, applies only the
velocity terms of added mass, no crossflow drag across a streamlined hull, a Kutta lift whose
slope near zero angle grows with the chord/thickness ratio, and no reaction to an accelerating
current (``../shared/notes/hydrodynamics.md``). This module holds what a compiled model needs
beyond plain MuJoCo:

* **The engine plugin** ``bauv.hydro`` (``bauv_sim/plugin/hydro.c``, compiled at install): added
  mass in the mass matrix, the hull's Munk coupling with separation, crossflow drag (the hull's
  strips, and the flapping peduncle's in its own frame), slender-body and thin-plate lift, the
  thin fins' plate drag (profile, induced, normal force), water acceleration, each vehicle's own
  water, and (the model file's numeric ``hydro_water``: :func:`water_properties`) MuJoCo's
  ellipsoid fluid model of the fluid geoms, with MuJoCo's own off (``option density`` and
  ``viscosity`` 0: it and its velocity derivatives were half of a step, issue 27).
  :func:`load_plugin` registers it (at import), :func:`load_model` compiles a model file
  with it (the one line a plain-MuJoCo user needs), :func:`set_water` and :func:`water` hold each
  vehicle's water in the plugin's state, :func:`plugin_force` reads what it applied.
* **Water velocity**: ``option wind`` is the water velocity of MuJoCo's fluid forces;
  :func:`set_water_velocity` sets it (the facade keeps it equal to the first vehicle's water).
* **Fluid coefficients** of a compiled model can be read and replaced (calibration experiments);
  the values in the model file are derived in :mod:`bauv_sim.design.fluid`.
* **Buoyancy** is in the model file: the hull's displacement rho V g acts at the centre of buoyancy
  through the gravity compensation (``gravcomp``) of a small welded body placed there; the tail
  segments and lateral fins are neutral by themselves (``gravcomp = 1``). :func:`hydrostatics`
  measures the result (net force, centres, BG) from the bodies' arrays; the ballast that makes it
  neutral and level is :func:`bauv_sim.design.ballast.solve_ballast`.
* **Added-mass algebra** used by the design-time tables and the tests: the rigid transfer of an
  ellipsoid's added mass (:func:`rigid_added_mass`), Kirchhoff's velocity coupling
  (:func:`coriolis_added_mass`), MuJoCo's ellipsoid drag (:func:`ellipsoid_drag`).

These functions write into an ``MjModel``/``MjData`` only where the facade calls them (the water):
the one exception to "only :mod:`bauv_sim.physics` indexes MuJoCo arrays". All vectors are in
the world frame (ENU, m, m/s, N) unless the name says otherwise.
"""

from __future__ import annotations

import importlib.machinery
import json
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim.errors import ConfigError

FLUID_SLICE_VIRTUAL = slice(6, 12)
"""Columns of ``MjModel.geom_fluid`` holding the virtual mass (3) and virtual inertia (3) of the
ellipsoid model (MuJoCo ``engine_passive.c``, ``readFluidGeomInteraction``)."""

FLUID_SLICE_COEFS = slice(1, 6)
"""Columns of ``MjModel.geom_fluid`` holding ``fluidcoef`` (blunt drag, slender drag, angular
drag, Kutta lift, Magnus lift)."""

FLUID_SLICE_KUTTA = 4
"""Column of ``MjModel.geom_fluid`` holding the Kutta lift coefficient."""


# --------------------------------------------------------------------------------------------
# Model preparation


def fluid_geoms(model: mujoco.MjModel) -> NDArray[np.int_]:
    """Ids of the geoms that take part in the ellipsoid fluid model (``fluidshape="ellipsoid"``).

    Args:
        model: compiled model.

    Returns:
        Geom ids, shape (n,).
    """
    return np.flatnonzero(model.geom_fluid[:, 0] > 0)


def added_mass_removed(model: mujoco.MjModel) -> bool:
    """Whether no fluid geom has MuJoCo virtual mass left (the plugin zeroes them when it starts on
    a data, and again at every step)."""
    return not np.any(model.geom_fluid[fluid_geoms(model), FLUID_SLICE_VIRTUAL] != 0.0)


def water_properties(model: mujoco.MjModel) -> tuple[float, float]:
    """Density (kg/m^3) and dynamic viscosity (Pa s) of the water of a compiled model.

    With a numeric ``<prefix>hydro_water`` (density, viscosity) the plugin applies MuJoCo's
    ellipsoid fluid model itself and ``option density`` and ``viscosity`` are 0 (the model file's
    default since issue 27); without one they are MuJoCo's ``option density`` and ``viscosity``.
    The first vehicle's values are returned (every vehicle of a scene is a copy of one file).

    Args:
        model: compiled model.

    Returns:
        ``(density_kg_m3, viscosity_pa_s)``.
    """
    for i in range(model.nnumeric):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_NUMERIC, i) or ""
        if name.endswith("hydro_water") and int(model.numeric_size[i]) == 2:
            adr = int(model.numeric_adr[i])
            return float(model.numeric_data[adr]), float(model.numeric_data[adr + 1])
    return float(model.opt.density), float(model.opt.viscosity)


def plugin_fluid_model(model: mujoco.MjModel) -> bool:
    """Whether the plugin applies the ellipsoid fluid model (a numeric ``<prefix>hydro_water``),
    so that MuJoCo's own is off and ``qfrc_fluid`` is zero."""
    return any(
        (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_NUMERIC, i) or "").endswith("hydro_water")
        for i in range(model.nnumeric)
    )


# --------------------------------------------------------------------------------------------
# The engine plugin bauv.hydro

PLUGIN_NAME = "bauv.hydro"
"""Name of the engine plugin (``bauv_sim/plugin/hydro.c``) that applies the run-time
hydrodynamics; one instance per vehicle, named ``<prefix>hydro``."""

PLUGIN_RECORD = "_bauv_hydro.build.json"
"""File beside the plugin library, written by ``setup.py`` when it compiles it: the MuJoCo release
whose headers it was compiled against (``{"mujoco": "3.17.0", "mjVERSION_HEADER": 3017000}``)."""

PLUGIN_BUILT_FOR_UNRECORDED = "3.17.0"
"""The release a library without :data:`PLUGIN_RECORD` was compiled against: ``setup.py`` wrote no
record while the build pinned ``mujoco==3.17.0`` exactly."""

WATER_STATE_SIZE = 7
"""Numbers of the plugin's state per instance: water velocity ``w0`` (3, m/s, world), its rate
``a`` (3, m/s^2, world) and the time ``t0`` (s) of ``w0``: ``w(t) = w0 + a (t - t0)``."""

_PLUGIN_LOADED = False


def plugin_path() -> Path:
    """Path of the compiled plugin library (built by ``pip install``, see ``setup.py``).

    The library is the extension module ``bauv_sim.plugin._bauv_hydro``, so its file name ends
    with one of this interpreter's extension suffixes (``importlib.machinery.EXTENSION_SUFFIXES``,
    tried in their order): a library built for another Python beside it is not taken.

    Raises:
        ConfigError: if it was not built.
    """
    directory = Path(__file__).parent / "plugin"
    suffixes = importlib.machinery.EXTENSION_SUFFIXES
    for suffix in suffixes:
        path = directory / ("_bauv_hydro" + suffix)
        if path.is_file():
            return path
    raise ConfigError(
        f"the hydrodynamics plugin bauv_sim/plugin/_bauv_hydro{suffixes[0]} is not built: "
        "reinstall the package (pip install -e .)"
    )


def _version_number(version: str) -> int:
    """``mjVERSION_HEADER`` form of a release string: ``"3.17.0"`` -> 3017000."""
    parts = [int(p) for p in version.split(".")[:3]]
    parts += [0] * (3 - len(parts))
    return parts[0] * 1_000_000 + parts[1] * 1_000 + parts[2]


def _version_text(number: int) -> str:
    """Release string of an ``mjVERSION_HEADER`` number: 3017000 -> ``"3.17.0"``."""
    return f"{number // 1_000_000}.{number // 1_000 % 1_000}.{number % 1_000}"


def plugin_built_for(library: Path | None = None) -> int:
    """The MuJoCo release the plugin library was compiled against, as ``mjVERSION_HEADER``
    (3017000 for 3.17.0), from :data:`PLUGIN_RECORD` beside it.

    Args:
        library: the plugin library (default :func:`plugin_path`).

    Raises:
        ConfigError: if the record cannot be read or holds no version number.
    """
    path = (plugin_path() if library is None else library).parent / PLUGIN_RECORD
    if not path.exists():
        return _version_number(PLUGIN_BUILT_FOR_UNRECORDED)
    try:
        number = json.loads(path.read_text(encoding="utf-8"))["mjVERSION_HEADER"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ConfigError(
            f"{str(path)!r}: unreadable build record of the hydrodynamics plugin ({exc!r}); "
            "reinstall the package"
        ) from None
    if type(number) is not int or number <= 0:
        raise ConfigError(
            f"{str(path)!r}: mjVERSION_HEADER = {number!r}: must be a positive integer; "
            "reinstall the package"
        )
    return number


def check_plugin_abi(runtime: int, built_for: int) -> None:
    """Refuse a MuJoCo other than the release the plugin was compiled against.

    The rule is equality of the whole release number (major, minor and patch): the plugin reads
    ``mjModel``/``mjData`` fields at the offsets of its build's headers, MuJoCo promises no stable
    layout between releases, and a changed one is not detected at load (3.17.0 inserted
    ``mjModel.tex_contenttypeadr``, moving ``text_adr``, ``numeric_*`` and ``plugin_stateadr``,
    all of which the plugin reads): the forces would be computed from the wrong arrays. MuJoCo's
    own Python bindings refuse a library whose ``mj_version()`` is not their
    ``mjVERSION_HEADER`` for the same reason.

    Args:
        runtime: ``mujoco.mj_version()`` of the library loaded (3017000 for 3.17.0).
        built_for: ``mjVERSION_HEADER`` the plugin was compiled against (:func:`plugin_built_for`).

    Raises:
        ConfigError: if they differ.
    """
    if runtime != built_for:
        have, want = _version_text(runtime), _version_text(built_for)
        raise ConfigError(
            f"mujoco {have} is installed, but the hydrodynamics plugin was compiled against "
            f"mujoco {want} (its mjModel/mjData layout); install mujoco=={want}, or rebuild "
            f"bauv-sim against {have} (pip install --no-build-isolation --force-reinstall "
            "--no-deps bauv-sim, or pip install -e . in a checkout)"
        )


def load_plugin() -> None:
    """Register the plugin ``bauv.hydro`` with MuJoCo (once per process), after checking that
    the MuJoCo loaded is the release it was compiled against (:func:`check_plugin_abi`).

    Raises:
        ConfigError: if the installed MuJoCo is not the release the plugin was built for, or the
            library is missing.
    """
    global _PLUGIN_LOADED
    if _PLUGIN_LOADED:
        return
    library = plugin_path()
    check_plugin_abi(int(mujoco.mj_version()), plugin_built_for(library))
    mujoco.mj_loadPluginLibrary(str(library))
    _PLUGIN_LOADED = True


def load_model(path: str | Path) -> mujoco.MjModel:
    """Compile a model file with the plugin registered: the one line a plain-MuJoCo user needs,
    ``m = bauv_sim.hydro.load_model("models/bauv/scene.xml")`` (or
    ``mujoco.mj_loadPluginLibrary(str(bauv_sim.hydro.plugin_path()))`` before their own load).

    Args:
        path: MJCF file.

    Returns:
        The compiled model.
    """
    load_plugin()
    return mujoco.MjModel.from_xml_path(str(path))


def plugin_instances(model: mujoco.MjModel) -> dict[str, int]:
    """The model's ``bauv.hydro`` instances by vehicle prefix (``""`` or ``"leader/"``).

    A model without the plugin (the native formulation, :mod:`bauv_sim.hydro_native`) gives its
    vehicles negative numbers ``-1 - k`` (k-th vehicle in model order): their water is block k of
    ``MjData.userdata`` (:func:`set_water`, :func:`water`).
    """
    out = {}
    for i in range(model.nplugin):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_PLUGIN, i) or ""
        if name.endswith("hydro"):
            out[name[: -len("hydro")]] = i
    if not out and model.nuserdata:
        out = {p: -1 - k for k, p in enumerate(native_prefixes(model))}
    return out


def native_prefixes(model: mujoco.MjModel) -> list[str]:
    """The vehicles' prefixes of a model, in model order: the names of its numerics
    ``<prefix>hydro_added_mass``."""
    out = []
    for i in range(model.nnumeric):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_NUMERIC, i) or ""
        if name.endswith("hydro_added_mass"):
            out.append(name[: -len("hydro_added_mass")])
    return out


def _water_slice(model: mujoco.MjModel, data: mujoco.MjData, instance: int) -> NDArray[np.float64]:
    """The 7 numbers of a vehicle's water: the plugin's state, or (negative instance, native
    model) its block of ``userdata``; a view."""
    if instance < 0:
        a = WATER_STATE_SIZE * (-1 - instance)
        return data.userdata[a : a + WATER_STATE_SIZE]
    a = int(model.plugin_stateadr[instance])
    return data.plugin_state[a : a + WATER_STATE_SIZE]


def set_water(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    instance: int,
    velocity_world_m_s: ArrayLike,
    accel_world_m_s2: ArrayLike = (0.0, 0.0, 0.0),
    t0_s: float | None = None,
) -> None:
    """Set the water the plugin applies to one vehicle: ``w(t) = w0 + a (t - t0)``.

    It drives the plugin's forces (for a vehicle other than the one whose water is MuJoCo's
    ``option wind``, the change of MuJoCo's drag too); MuJoCo's own fluid forces see
    ``option wind`` (:func:`set_water_velocity`), which the caller keeps equal to the first
    vehicle's water.

    Args:
        model: compiled model.
        data: its data.
        instance: plugin instance of the vehicle (:func:`plugin_instances`).
        velocity_world_m_s: ``w0``, shape (3,), m/s, world.
        accel_world_m_s2: ``a``, shape (3,), m/s^2, world.
        t0_s: time of ``w0``, s (default: the data's time).
    """
    st = _water_slice(model, data, instance)
    st[0:3] = velocity_world_m_s
    st[3:6] = accel_world_m_s2
    st[6] = float(data.time) if t0_s is None else float(t0_s)


def water(
    model: mujoco.MjModel, data: mujoco.MjData, instance: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The water at a vehicle now (:func:`set_water`): velocity (m/s) and its rate (m/s^2), world,
    shape (3,) each."""
    st = _water_slice(model, data, instance)
    return st[:3] + st[3:6] * (float(data.time) - st[6]), np.array(st[3:6])


def plugin_force(data: mujoco.MjData, dofs: ArrayLike) -> NDArray[np.float64]:
    """The generalized force the plugin added at the last evaluation of the passive forces, over
    given degrees of freedom: ``qfrc_passive`` less MuJoCo's springs, dampers, gravity
    compensation, fluid forces and adhesion (the model has no other plugin or passive callback).

    Args:
        data: the data.
        dofs: degree-of-freedom indices, (n,).

    Returns:
        Generalized force, (n,) (a free joint: force N world, moment N m body).
    """
    i = np.asarray(dofs, dtype=int)
    d = data
    other = d.qfrc_spring[i] + d.qfrc_damper[i] + d.qfrc_gravcomp[i] + d.qfrc_fluid[i]
    return d.qfrc_passive[i] - other - d.qfrc_adhesion[i]


def set_water_velocity(model: mujoco.MjModel, vel_world_m_s: ArrayLike) -> None:
    """Set the velocity of the water that MuJoCo's fluid forces see (``option wind``).

    Args:
        model: compiled model (modified in place).
        vel_world_m_s: water velocity, shape (3,), m/s, world frame.
    """
    v = np.asarray(vel_world_m_s, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f"water velocity = {v!r}: expected 3 finite numbers (m/s)")
    model.opt.wind[:] = v


def water_velocity(model: mujoco.MjModel) -> NDArray[np.float64]:
    """The water velocity applied by the fluid forces (``option wind``), shape (3,), m/s, world."""
    return np.array(model.opt.wind, dtype=float)


def fluid_coefficients(model: mujoco.MjModel, geom: str) -> NDArray[np.float64]:
    """``fluidcoef`` of one geom: blunt drag, slender drag, angular drag, Kutta lift, Magnus lift.

    Args:
        model: compiled model.
        geom: full geom name.

    Returns:
        Copy of the five coefficients, shape (5,), dimensionless.
    """
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
    if g < 0:
        raise ConfigError(f"geom {geom!r}: not in the model")
    return np.array(model.geom_fluid[g, FLUID_SLICE_COEFS])


def set_fluid_coefficients(model: mujoco.MjModel, geom: str, coefs: ArrayLike) -> None:
    """Replace ``fluidcoef`` of one geom in a compiled model (calibration experiments).

    Args:
        model: compiled model (modified in place).
        geom: full geom name.
        coefs: blunt drag, slender drag, angular drag, Kutta lift, Magnus lift, shape (5,).
    """
    c = np.asarray(coefs, dtype=float)
    if c.shape != (5,) or np.any(c < 0) or not np.all(np.isfinite(c)):
        raise ConfigError(f"fluid coefficients = {c!r}: expected 5 finite numbers >= 0")
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom)
    if g < 0:
        raise ConfigError(f"geom {geom!r}: not in the model")
    model.geom_fluid[g, FLUID_SLICE_COEFS] = c


# --------------------------------------------------------------------------------------------
# Hydrostatics


def subtree_bodies(model: mujoco.MjModel, root_body: int) -> NDArray[np.int_]:
    """Ids of ``root_body`` and all its descendants, shape (n,)."""
    ids = [root_body]
    for b in range(root_body + 1, model.nbody):
        p = int(model.body_parentid[b])
        while p > root_body:
            p = int(model.body_parentid[p])
        if p == root_body:
            ids.append(b)
    return np.asarray(ids, dtype=int)


@dataclass(frozen=True)
class Hydrostatics:
    """Weight and buoyancy of one vehicle in its current configuration.

    Attributes:
        weight_n: total weight, N (> 0).
        buoyancy_n: total upward force of the gravity compensation (the displacement), N.
        net_up_n: ``buoyancy_n - weight_n``, N (> 0: positively buoyant).
        cg_world_m: centre of gravity, shape (3,), m, world frame.
        cb_world_m: centre of buoyancy, shape (3,), m, world frame.
        bg_world_m: the righting arm vector ``sum((gc_i - 1) m_i r_i) / sum(m_i)``, shape (3,), m,
            world frame: equal to CB - CG when the vehicle is neutral; parts that are neutral by
            themselves (gc = 1) drop out.
    """

    weight_n: float
    buoyancy_n: float
    net_up_n: float
    cg_world_m: NDArray[np.float64]
    cb_world_m: NDArray[np.float64]
    bg_world_m: NDArray[np.float64]

    def metacentric_height_m(self) -> float:
        """Vertical component of :attr:`bg_world_m` (BG), m; > 0 means self-righting."""
        return float(self.bg_world_m[2])


def hydrostatics(
    mass_kg: ArrayLike, gravcomp: ArrayLike, com_world_m: ArrayLike, gravity_m_s2: float
) -> Hydrostatics:
    """Weight and buoyancy of a set of bodies from their masses, gravity compensations and centres
    of mass (MuJoCo applies ``gravcomp * m * g`` upwards at each body's centre of mass).

    Args:
        mass_kg: body masses, shape (n,), kg.
        gravcomp: their ``gravcomp`` factors, shape (n,).
        com_world_m: their centres of mass, shape (n, 3), m, world frame.
        gravity_m_s2: magnitude of gravity, m/s^2.

    Returns:
        The :class:`Hydrostatics` of the set.
    """
    m = np.asarray(mass_kg, dtype=float)
    gc = np.asarray(gravcomp, dtype=float)
    r = np.asarray(com_world_m, dtype=float)
    g = float(gravity_m_s2)
    weight = float(m.sum()) * g
    buoy = float((gc * m).sum()) * g
    cg = (m[:, None] * r).sum(axis=0) / m.sum()
    if buoy > 0:
        cb = ((gc * m)[:, None] * r).sum(axis=0) / (gc * m).sum()
    else:
        cb = np.full(3, np.nan)
    bg = (((gc - 1.0) * m)[:, None] * r).sum(axis=0) / m.sum()
    # BG about the CG: the first moment of (gc - 1) m about the CG equals the one about the
    # origin when the vehicle is neutral; subtract the net-force part otherwise
    bg = bg - ((gc - 1.0) * m).sum() / m.sum() * cg
    return Hydrostatics(weight, buoy, buoy - weight, cg, cb, bg)


# --------------------------------------------------------------------------------------------
# Added-mass algebra


def _skew(r: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def rigid_added_mass(
    m_lin: ArrayLike, m_rot: ArrayLike, R_ref_from_geom: ArrayLike, r_ref_m: ArrayLike
) -> NDArray[np.float64]:
    """The added-mass matrix of an ellipsoid with diagonal added mass in its own frame, about
    another reference point and in another frame of the same rigid body.

    With ``H`` the map from the reference frame's velocity ``(v, w)`` at the reference point to the
    ellipsoid frame's ``(v_g, w_g)`` at its centre (``v_g = R^T (v + w x r)``, ``w_g = R^T w``),
    the kinetic energy ``1/2 nu_g^T M_g nu_g`` is ``1/2 nu^T (H^T M_g H) nu`` (Fossen 2021, sec.
    3.3, the system transformation matrix).

    Args:
        m_lin: added masses along the ellipsoid's axes, shape (3,), kg.
        m_rot: added moments of inertia about its axes, shape (3,), kg m^2.
        R_ref_from_geom: rotation, columns are the ellipsoid axes in the reference frame, (3, 3).
        r_ref_m: ellipsoid centre in the reference frame, shape (3,), m.

    Returns:
        6 x 6 added-mass matrix about the reference point, order (v, w), reference frame.
    """
    R = np.asarray(R_ref_from_geom, dtype=float)
    H = np.zeros((6, 6))
    H[:3, :3] = R.T
    H[:3, 3:] = -R.T @ _skew(np.asarray(r_ref_m, dtype=float))
    H[3:, 3:] = R.T
    Mg = np.diag(np.r_[np.asarray(m_lin, dtype=float), np.asarray(m_rot, dtype=float)])
    return H.T @ Mg @ H


def coriolis_added_mass(M_A: ArrayLike, nu: ArrayLike) -> NDArray[np.float64]:
    """The velocity part of the fluid's reaction, ``-C_A(nu) nu``, for any symmetric added-mass
    matrix (Kirchhoff's equations).

    With ``p = A11 v + A12 w`` and ``L = A21 v + A22 w``: force ``p x w``, moment
    ``p x v + L x w`` (Fossen 2021, eq. 6.43; Lamb 1932, sec. 124). Its yaw part for a body moving
    at (u, v) with ``A22 > A11`` is the destabilising Munk moment ``(A22 - A11) u v``.

    Args:
        M_A: added-mass matrix, (6, 6), order (v, w).
        nu: velocity relative to the water, shape (6,): linear (m/s) then angular (rad/s), body
            frame.

    Returns:
        Force (N) then moment (N m), shape (6,), body frame, about the reference point of ``M_A``.
    """
    A = np.asarray(M_A, dtype=float)
    n = np.asarray(nu, dtype=float)
    p = A[:3] @ n
    L = A[3:] @ n
    return np.r_[np.cross(p, n[3:]), np.cross(p, n[:3]) + np.cross(L, n[3:])]


def ellipsoid_drag(
    u_local: NDArray[np.float64],
    semi_axes: NDArray[np.float64],
    blunt: NDArray[np.float64],
    slender: NDArray[np.float64],
    density: float,
    viscosity: float,
) -> NDArray[np.float64]:
    """MuJoCo's translational drag of ellipsoids (``engine_passive.c``, documented in
    ``doc/computation/fluid.rst``): ``-rho (C_b A_proj + C_s (A_max - A_proj)) |u| u`` with the
    projected area of the lemma and ``A_max = pi r_max r_mid``, plus Stokes' ``-6 pi r_D beta u``.

    Args:
        u_local: velocity of each ellipsoid's centre relative to the water, (n, 3), m/s, its frame.
        semi_axes: (n, 3), m.
        blunt: blunt-drag coefficients, (n,).
        slender: slender-drag coefficients, (n,).
        density: fluid density, kg/m^3.
        viscosity: MuJoCo ``option viscosity``, Pa s.

    Returns:
        Forces, (n, 3), N, ellipsoid frames.
    """
    r = semi_axes
    speed = np.sqrt(np.einsum("ij,ij->i", u_local, u_local))
    safe = np.where(speed > 0.0, speed, 1.0)
    uh2 = (u_local / safe[:, None]) ** 2
    r2 = r * r
    r4 = r2 * r2
    num = r4[:, 1] * r4[:, 2] * uh2[:, 0] + r4[:, 2] * r4[:, 0] * uh2[:, 1]
    num = num + r4[:, 0] * r4[:, 1] * uh2[:, 2]
    den = r2[:, 1] * r2[:, 2] * uh2[:, 0] + r2[:, 2] * r2[:, 0] * uh2[:, 1]
    den = den + r2[:, 0] * r2[:, 1] * uh2[:, 2]
    a_proj = np.pi * np.sqrt(num / np.where(den > 0.0, den, 1.0))
    rs = np.sort(r, axis=1)
    a_max = np.pi * rs[:, 2] * rs[:, 1]
    c = -density * (blunt * a_proj + slender * (a_max - a_proj)) * speed
    stokes = -6.0 * np.pi * r.mean(axis=1) * viscosity
    return (c + stokes)[:, None] * u_local


load_plugin()
