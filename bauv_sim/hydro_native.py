"""The plugin ``bauv.hydro``'s forces in a form MuJoCo Warp can run (issue 27, ``docs/gpu.md``).

MuJoCo Warp never calls a model-wide engine plugin and its passive-force hook may write
``qfrc_passive`` only: it cannot add the added mass to the mass matrix as the plugin does. The
*native* formulation splits the plugin's model into

* **MuJoCo-native parameters** (set once on the compiled model, read by every MuJoCo port):
  the free joint's ``dof_armature`` holds the diagonal of the rotational added mass (the free
  joint's angular velocity is in the body frame, so a diagonal there is exact at every attitude)
  and an isotropic translational part ``m_iso I`` (the translational velocity is in the world
  frame: only an isotropic mass is invariant under rotation); the fluid geoms' virtual masses and
  the replaced Kutta lifts are zeroed in ``geom_fluid`` as the plugin zeroes them; MuJoCo's
  ellipsoid fluid model and ``option wind`` are unchanged;
* **one passive-force callback** (:func:`passive`, installed with ``mujoco.set_mjcb_passive`` on
  the CPU, standing for Warp's passive callback) that adds to ``qfrc_passive`` every other term of
  the plugin, equation for equation (``bauv_sim/plugin/hydro.c``'s header), and the remainder of
  the added mass ``dA = M_A - diag(m_iso, m_iso, m_iso, A44, A55, A66)`` as the force
  ``-dA T qacc`` with the *previous* step's acceleration (``T = diag(R^T, I)``, qvel to body
  frame).

The lagged force is a partitioned (explicit) added mass: the acceleration recursion
``a_n = -M^-1 T^T dA T a_(n-1) + ...`` converges only if the spectral radius of
``M^-1 T^T dA T`` is below 1 (Britto et al. 2017 for the UUV simulators' "compensated effort").
:func:`stability_ratio` measures it; ``m_iso`` is chosen to minimise it
(:func:`choose_isotropic_mass`).

Each vehicle's water (velocity, its rate, the time of the velocity: 7 numbers as in the plugin's
state) lives in ``MjData.userdata`` (block k of 7 for the k-th vehicle): the model has no plugin
state. :func:`bauv_sim.hydro.set_water` and :func:`bauv_sim.hydro.water` read and write it through
the negative instance numbers of :func:`bauv_sim.hydro.plugin_instances`.

Build a native scene with ``build_physics(..., hydrodynamics="native")`` or, for code that builds
its own scenes, inside ``with formulation("native"):``. All vectors are in the world frame unless
the name says otherwise; forces in N, moments in N m.

References:
    Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed.,
    eq. 6.43 (Kirchhoff's added-mass coupling).
    Britto, J. et al. (2017), the UUV Simulator's added-mass handling (partitioned added mass is
    stable while the explicit part is smaller than the mass it acts on).
"""

from __future__ import annotations

import contextlib
import contextvars
import re
import weakref
from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from bauv_sim import hydro
from bauv_sim.errors import ConfigError

FORMULATIONS = ("plugin", "native", "mujoco-fluid")
"""The hydrodynamics a scene can be built with: the engine plugin ``bauv.hydro`` (the reference)
or the native parameters plus one passive callback (this module), or the plugin with MuJoCo's own
fluid model doing the ellipsoid forces (the model as before issue 27: the water in ``option
density`` and ``viscosity``, no ``hydro_water``; the same forces, with MuJoCo's velocity
derivatives of them in implicitfast, at twice the cost of a step), for validation."""

WATER_SIZE = hydro.WATER_STATE_SIZE
"""Numbers of one vehicle's water in ``MjData.userdata``: w0 (3), a (3), t0."""

N_SPAN, N_CHORD = 8, 4
"""A plate's normal-force panels: span strips, chordwise panels per strip (as in the plugin)."""

_FORMULATION: contextvars.ContextVar[str] = contextvars.ContextVar(
    "bauv_hydrodynamics", default="plugin"
)


def current_formulation() -> str:
    """The formulation :func:`bauv_sim.build.build_physics` uses when not told (``"plugin"``
    unless inside :func:`formulation`)."""
    return _FORMULATION.get()


@contextlib.contextmanager
def formulation(name: str) -> Iterator[None]:
    """Build scenes with the given hydrodynamics inside the block (for code that builds its own
    scenes, e.g. the manoeuvres and the autopilot's trials).

    Args:
        name: one of :data:`FORMULATIONS`.

    Raises:
        ConfigError: if the name is not one of them.
    """
    check_formulation(name)
    token = _FORMULATION.set(name)
    try:
        yield
    finally:
        _FORMULATION.reset(token)


def check_formulation(name: str) -> str:
    """The name if it is one of :data:`FORMULATIONS`.

    Raises:
        ConfigError: naming the value and the allowed ones.
    """
    if name not in FORMULATIONS:
        raise ConfigError(f"hydrodynamics = {name!r}: must be one of {', '.join(FORMULATIONS)}")
    return name


# --------------------------------------------------------------------------------------------
# the model


def strip_plugin_xml(xml: str, n_vehicles: int) -> str:
    """An assembled scene's MJCF with the ``bauv.hydro`` instances removed and room for each
    vehicle's water in ``userdata``.

    Args:
        xml: the scene's MJCF text (with ``<extension><plugin plugin="bauv.hydro">``).
        n_vehicles: number of vehicles.

    Returns:
        The MJCF text of the native model.
    """
    out = re.sub(r"<extension>.*?</extension>", "", xml, flags=re.S)
    size = f'<size nuserdata="{WATER_SIZE * n_vehicles}"/>'
    return re.sub(r"(<mujoco[^>]*>)", r"\1" + size, out, count=1)


def _numeric(m: mujoco.MjModel, name: str) -> NDArray[np.float64] | None:
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, name)
    if i < 0:
        return None
    a, n = int(m.numeric_adr[i]), int(m.numeric_size[i])
    return np.array(m.numeric_data[a : a + n])


def _text(m: mujoco.MjModel, name: str) -> list[str]:
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXT, name)
    if i < 0:
        return []
    a, n = int(m.text_adr[i]), int(m.text_size[i])
    return bytes(m.text_data[a : a + n]).decode().rstrip("\x00").split()


def _panels(a: float, b: float, span: int) -> NDArray[np.float64]:
    """A plate ellipse's normal-force panels (the plugin's quadrature): rows x, y, z (geom frame,
    m) and area (m^2), shape (N_SPAN * N_CHORD, 4)."""
    th = np.arange(1, N_SPAN + 1) * np.pi / (N_SPAN + 1)
    xi = -1.0 + (2.0 * np.arange(N_CHORD) + 1.0) / N_CHORD
    out = np.zeros((N_SPAN, N_CHORD, 4))
    out[..., 0] = xi[None, :] * np.sin(th)[:, None] * a
    out[..., span] = (np.cos(th) * b)[:, None]
    out[..., 3] = (np.pi * a * b * 2.0 * np.sin(th) ** 2 / (N_SPAN + 1) / N_CHORD)[:, None]
    return out.reshape(-1, 4)


@dataclass
class _Foil:
    geom: int
    body: int
    normal: int
    span: int
    half_chord: float
    k_lift: float  # 1/2 rho S C_La
    drag: NDArray[np.float64]  # 1/2 rho S C_D0, 1/2 rho S k_i C_La^2, 1/2 rho C_N
    panels: NDArray[np.float64]  # (n, 4): position (geom frame), area


@dataclass
class NativeVehicle:
    """One vehicle's tables for :func:`passive` (read once from the model's numerics).

    Attributes:
        prefix: the vehicle's name prefix.
        water_adr: first index of its water in ``MjData.userdata``.
        free_body: body of its free joint.
        dof: first dof of the free joint.
        M_A: added mass, (6, 6), hull origin and frame, order (v, w).
        M_B: the hull's own added mass for its potential coupling, (6, 6).
        dA: the part of ``M_A`` not in the armature (applied with the lagged acceleration), (6, 6).
        m_iso_kg: isotropic translational added mass in the armature, kg.
    """

    prefix: str
    water_adr: int
    free_body: int
    dof: int
    M_A: NDArray[np.float64]
    M_B: NDArray[np.float64]
    dA: NDArray[np.float64]
    m_iso_kg: float
    cross: NDArray[np.float64]
    roll_k: float
    slender: NDArray[np.float64] | None
    seg_bodies: list[int]
    seg_strips: list[NDArray[np.float64]]
    seg_roll: NDArray[np.float64]
    foils: list[_Foil]
    fk_bodies: NDArray[np.int_]
    fk_mass: NDArray[np.float64]
    drag_geoms: NDArray[np.int_]
    drag_semi: NDArray[np.float64]
    drag_coef: NDArray[np.float64]


def _vehicle_tables(m: mujoco.MjModel, prefix: str, k: int) -> NativeVehicle:
    hull = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, prefix + "hull")
    if hull < 0:
        raise ConfigError(f"vehicle prefix {prefix!r}: no body {prefix + 'hull'!r}")
    fb = hull
    while m.body_jntnum[fb] == 0 and m.body_parentid[fb] != 0:
        fb = int(m.body_parentid[fb])
    dof = int(m.jnt_dofadr[m.body_jntadr[fb]])
    rho = float(m.opt.density)
    M_A = _numeric(m, prefix + "hydro_added_mass")
    assert M_A is not None
    M_A = M_A.reshape(6, 6)
    mb = _numeric(m, prefix + "hydro_body_added_mass")
    M_B = M_A if mb is None else mb.reshape(6, 6)
    cross = _numeric(m, prefix + "hydro_crossflow")
    rk = _numeric(m, prefix + "hydro_roll_damping")
    bodies = set(hydro.subtree_bodies(m, fb).tolist())
    seg_names = _text(m, prefix + "hydro_segments")
    strips = _numeric(m, prefix + "hydro_segment_crossflow")
    seg_bodies = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, prefix + s) for s in seg_names]
    seg_strips = []
    for i in range(len(seg_names)):
        rows = strips.reshape(-1, 8) if strips is not None else np.zeros((0, 8))
        seg_strips.append(rows[rows[:, 0] == i, 1:])
    sr = _numeric(m, prefix + "hydro_segment_roll_damping")
    seg_roll = np.zeros(len(seg_names)) if sr is None else sr
    foils = []
    cla = _numeric(m, prefix + "hydro_foil_cla")
    fd = _numeric(m, prefix + "hydro_foil_drag")
    names = _text(m, prefix + "hydro_foils")
    fd = np.zeros((len(names), 3)) if fd is None else fd.reshape(-1, 3)
    for i, name in enumerate(names):
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, prefix + name)
        s = m.geom_size[g]
        n = 1 if s[1] <= s[2] else 2
        span = 3 - n
        area = np.pi * s[0] * s[span]
        assert cla is not None
        drag = np.array(
            [
                0.5 * rho * area * fd[i, 0],
                0.5 * rho * area * fd[i, 1] * cla[i] ** 2,
                0.5 * rho * fd[i, 2],
            ]
        )
        foils.append(
            _Foil(
                g, int(m.geom_bodyid[g]), n, span, float(s[0]), 0.5 * rho * area * float(cla[i]),
                drag, _panels(float(s[0]), float(s[span]), span),
            )
        )  # fmt: skip
    fk = np.array([b for b in sorted(bodies) if m.body_gravcomp[b] > 0], dtype=int)
    drag_geoms = np.array(
        [g for g in range(m.ngeom) if m.geom_fluid[g, 0] > 0 and int(m.geom_bodyid[g]) in bodies],
        dtype=int,
    )
    semi = np.array(m.geom_size[drag_geoms], dtype=float)
    sphere = m.geom_type[drag_geoms] == mujoco.mjtGeom.mjGEOM_SPHERE
    semi[sphere] = semi[sphere, :1]
    return NativeVehicle(
        prefix=prefix,
        water_adr=WATER_SIZE * k,
        free_body=fb,
        dof=dof,
        M_A=M_A,
        M_B=M_B,
        dA=np.zeros((6, 6)),
        m_iso_kg=0.0,
        cross=np.zeros((0, 7)) if cross is None else cross.reshape(-1, 7),
        roll_k=0.0 if rk is None else float(rk[0]),
        slender=_numeric(m, prefix + "hydro_slender_lift"),
        seg_bodies=seg_bodies,
        seg_strips=seg_strips,
        seg_roll=seg_roll,
        foils=foils,
        fk_bodies=fk,
        fk_mass=np.array(m.body_gravcomp[fk] * m.body_mass[fk]),
        drag_geoms=drag_geoms,
        drag_semi=semi,
        drag_coef=np.array(m.geom_fluid[drag_geoms, 1:3]),
    )


def _zero_model_terms(m: mujoco.MjModel, v: NativeVehicle) -> None:
    """Zero what the plugin zeroes: the virtual masses of the vehicle's fluid geoms and the Kutta
    lift of its plates and of the hull's thick geoms (their lift is the slender-body lift)."""
    m.geom_fluid[v.drag_geoms, hydro.FLUID_SLICE_VIRTUAL] = 0.0
    for f in v.foils:
        m.geom_fluid[f.geom, hydro.FLUID_SLICE_KUTTA] = 0.0
    if v.slender is None:
        return
    for g in v.drag_geoms:
        b = int(m.geom_bodyid[g])
        on_hull = b == v.free_body or (m.body_parentid[b] == v.free_body and m.body_jntnum[b] == 0)
        s = np.sort(m.geom_size[g])
        if on_hull and not s[0] < 0.2 * s[1]:
            m.geom_fluid[g, hydro.FLUID_SLICE_KUTTA] = 0.0


def _residual(M_A: NDArray[np.float64], m_iso: float) -> NDArray[np.float64]:
    return M_A - np.diag([m_iso, m_iso, m_iso, M_A[3, 3], M_A[4, 4], M_A[5, 5]])


def stability_ratio(m: mujoco.MjModel, d: mujoco.MjData, v: NativeVehicle) -> float:
    """Spectral radius of the lagged added-mass recursion ``M^-1 T^T dA T`` over the free joint
    (``M`` the model's mass matrix with the armature, at the data's configuration): the
    partitioned added mass is stable when it is below 1.

    Args:
        m: the native model.
        d: data with the kinematics computed (``mj_forward``).
        v: the vehicle.

    Returns:
        The ratio (dimensionless).
    """
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    R = d.xmat[v.free_body].reshape(3, 3)
    T = np.zeros((m.nv, 6))
    T[v.dof : v.dof + 3, :3] = R
    T[v.dof + 3 : v.dof + 6, 3:] = np.eye(3)
    it = np.linalg.solve(M, T @ v.dA @ T.T)
    return float(np.max(np.abs(np.linalg.eigvals(it))))


def choose_isotropic_mass(
    m: mujoco.MjModel, d: mujoco.MjData, v: NativeVehicle, n_grid: int = 41
) -> float:
    """Set the vehicle's armature and residual for the isotropic mass that minimises
    :func:`stability_ratio`, searched on a grid from the smallest to the largest translational
    added mass; returns the ratio reached."""
    base = np.array(m.dof_armature[v.dof : v.dof + 6])
    diag = np.diag(v.M_A)[:3]
    best = (np.inf, 0.0)
    for m_iso in np.linspace(diag.min(), diag.max(), n_grid):
        _set_armature(m, v, base, float(m_iso))
        mujoco.mj_forward(m, d)
        best = min(best, (stability_ratio(m, d, v), float(m_iso)))
    _set_armature(m, v, base, best[1])
    mujoco.mj_forward(m, d)
    return best[0]


def _set_armature(m: mujoco.MjModel, v: NativeVehicle, base: NDArray[np.float64], m_iso: float):
    m.dof_armature[v.dof : v.dof + 6] = base + np.r_[[m_iso] * 3, np.diag(v.M_A)[3:]]
    v.m_iso_kg = m_iso
    v.dA = _residual(v.M_A, m_iso)


@dataclass
class NativeHydro:
    """The native formulation of one compiled model: its vehicles' tables and the ratio of the
    lagged added mass (below 1: stable).

    Attributes:
        vehicles: per vehicle, in model order.
        stability_ratio: the largest :func:`stability_ratio` over the vehicles, at the build
            configuration.
    """

    vehicles: list[NativeVehicle]
    stability_ratio: float


_MODELS: dict[int, tuple[weakref.ref, NativeHydro]] = {}


def prepare(m: mujoco.MjModel, d: mujoco.MjData) -> NativeHydro:
    """Make a compiled model without the plugin native: MuJoCo's fluid model on (``option
    density`` and ``viscosity`` from the plugin's ``hydro_water``), armature and residual added
    mass, zeroed virtual masses and Kutta lifts, the callback installed for it.

    Args:
        m: the model (``strip_plugin_xml``'s), modified in place.
        d: its data (used for the stability ratio at its configuration).

    Returns:
        The :class:`NativeHydro` (also kept for :func:`passive` while the model lives).

    Raises:
        ConfigError: if the model still has a plugin, has no room for the water, or the lagged
            added mass would be unstable (ratio >= 1).
    """
    if m.nplugin:
        raise ConfigError("native hydrodynamics: the model still has an engine plugin")
    prefixes = hydro.native_prefixes(m)
    if m.nuserdata < WATER_SIZE * len(prefixes):
        raise ConfigError(f"nuserdata = {m.nuserdata}: need {WATER_SIZE * len(prefixes)}")
    # MuJoCo's ellipsoid fluid model is native (Warp runs it): a model file whose plugin applied
    # it (numeric hydro_water, option density and viscosity 0) gets it back in the option
    m.opt.density, m.opt.viscosity = hydro.water_properties(m)
    vehicles = [_vehicle_tables(m, p, k) for k, p in enumerate(prefixes)]
    ratio = 0.0
    for v in vehicles:
        _zero_model_terms(m, v)
        ratio = max(ratio, choose_isotropic_mass(m, d, v))
    if not ratio < 1.0:
        raise ConfigError(f"native hydrodynamics: lagged added-mass ratio {ratio:.3f} >= 1")
    out = NativeHydro(vehicles, ratio)
    _MODELS[m._address] = (weakref.ref(m), out)
    weakref.finalize(m, _forget, m._address)
    mujoco.set_mjcb_passive(passive)
    return out


def _forget(address: int) -> None:
    """A native model was freed: drop it, and the callback with the last one (an installed Python
    passive callback makes every compilation of the process fail, :func:`compiling`)."""
    _MODELS.pop(address, None)
    if not _MODELS:
        mujoco.set_mjcb_passive(None)


def uninstall() -> None:
    """Remove the passive callback and forget every native model (their forces stop)."""
    _MODELS.clear()
    mujoco.set_mjcb_passive(None)


@contextlib.contextmanager
def compiling() -> Iterator[None]:
    """Compile models inside this block: MuJoCo's Python bindings fail a compilation while a
    passive callback is installed (the compiler evaluates the model before a Python object wraps
    it), so the callback is removed for the block and put back if a native model is alive. The
    callback is installed while a native model lives (:func:`prepare`) and removed with the last
    one or by :func:`uninstall`; code that compiles models outside ``build_physics`` while a
    native model lives compiles them inside this block."""
    mujoco.set_mjcb_passive(None)
    try:
        yield
    finally:
        if _MODELS:
            mujoco.set_mjcb_passive(passive)


def native_of(m: mujoco.MjModel) -> NativeHydro | None:
    """The native formulation of a model (:func:`prepare`), or None."""
    entry = _MODELS.get(m._address)
    if entry is None or entry[0]() is not m:
        return None
    return entry[1]


# --------------------------------------------------------------------------------------------
# the passive callback


def water(d: mujoco.MjData, v: NativeVehicle) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The vehicle's water now: velocity (m/s) and its rate (m/s^2), world, (3,) each."""
    st = d.userdata[v.water_adr : v.water_adr + WATER_SIZE]
    return st[:3] + st[3:6] * (float(d.time) - st[6]), np.array(st[3:6])


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """a x b of 3-vectors, or row by row of (n, 3) arrays (one may be a 3-vector): ``np.cross``
    without its axis handling, which dominates the callback's cost."""
    return np.stack(
        (
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ),
        axis=-1,
    )


def _coriolis(A: NDArray[np.float64], nu: NDArray[np.float64]) -> NDArray[np.float64]:
    """Kirchhoff's ``-C_A(nu) nu`` (:func:`bauv_sim.hydro.coriolis_added_mass`)."""
    pv = A[:3] @ nu
    L = A[3:] @ nu
    return np.concatenate((_cross(pv, nu[3:]), _cross(pv, nu[:3]) + _cross(L, nu[3:])))


def vehicle_force(m: mujoco.MjModel, d: mujoco.MjData, v: NativeVehicle) -> NDArray[np.float64]:
    """The callback's generalized force for one vehicle (kinematics and velocities computed;
    ``d.qacc`` holds the lagged acceleration).

    Returns:
        Generalized force, shape (nv,).
    """
    qfrc = np.zeros(m.nv)
    rho = float(m.opt.density)
    w, a_w = water(d, v)
    accelerating = bool(np.any(a_w != 0.0))
    R = d.xmat[v.free_body].reshape(3, 3)
    qv = d.qvel[v.dof : v.dof + 6]
    nu = np.concatenate((R.T @ (qv[:3] - w), qv[3:]))
    # Kirchhoff: -C_B(nu) nu + M_A (w x nu_1 + R^T a_water), and the residual added mass
    # -dA T qacc with the previous step's acceleration (-M_A d(nu)/dt = -M_A T qacc
    # + M_A (w x nu_1 + R^T a_water): the armature holds -M_nat T qacc, M_A = M_nat + dA)
    tau = _coriolis(v.M_B, nu)
    ext = _cross(nu[3:], nu[:3]) + (R.T @ a_w if accelerating else 0.0)
    tau += v.M_A[:, :3] @ ext
    qa = d.qacc[v.dof : v.dof + 6]
    tau -= v.dA @ np.concatenate((R.T @ qa[:3], qa[3:]))
    u, p, q, r = nu[0], nu[3], nu[4], nu[5]
    # crossflow strips -1/2 rho C a |c| c
    if len(v.cross):
        x, y, z, ay, az, cy_, cz_ = v.cross.T
        cy = nu[1] + r * x - p * z
        cz = nu[2] + p * y - q * x
        c = np.hypot(cy, cz)
        gy = -0.5 * rho * ay * cy_ * c * cy
        gz = -0.5 * rho * az * cz_ * c * cz
        tau[1] += gy.sum()
        tau[2] += gz.sum()
        tau[3] += np.sum(y * gz - z * gy)
        tau[4] -= np.sum(x * gz)
        tau[5] += np.sum(x * gy)
    tau[3] -= v.roll_k * p * abs(p)
    if v.slender is not None:
        xy, a_y, xz, a_z, f_y, f_z = v.slender
        uu = max(u, 0.0)
        ly = -rho * uu * a_y * (nu[1] + r * xy)
        lz = -rho * uu * a_z * (nu[2] - q * xz)
        tau[1] += ly
        tau[2] += lz
        tau[5] += xy * ly + f_y * (v.M_B[1, 1] - v.M_B[0, 0]) * uu * nu[1]
        tau[4] -= xz * lz + f_z * (v.M_B[2, 2] - v.M_B[0, 0]) * uu * nu[2]
    qfrc[v.dof : v.dof + 3] += R @ tau[:3]
    qfrc[v.dof + 3 : v.dof + 6] += tau[3:]
    zero = np.zeros(3)
    if accelerating:  # Froude-Krylov rho V a_water on every displacing body
        for b, mass in zip(v.fk_bodies, v.fk_mass, strict=True):
            mujoco.mj_applyFT(m, d, mass * a_w, zero, d.xipos[b], int(b), qfrc)
    vel = np.zeros(6)
    for i, b in enumerate(v.seg_bodies):
        Rb = d.xmat[b].reshape(3, 3)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, b, vel, 1)
        ub = vel[3:] - Rb.T @ w
        s = v.seg_strips[i]
        pos = s[:, :3]
        wr = _cross(vel[:3], pos)
        cy = ub[1] + wr[:, 1]
        cz = ub[2] + wr[:, 2]
        c = np.hypot(cy, cz)
        f = np.zeros_like(pos)
        f[:, 1] = -0.5 * rho * s[:, 3] * s[:, 5] * c * cy
        f[:, 2] = -0.5 * rho * s[:, 4] * s[:, 6] * c * cz
        ts = _cross(pos, f).sum(axis=0)
        ts[0] -= v.seg_roll[i] * vel[0] * abs(vel[0])
        mujoco.mj_applyFT(m, d, Rb @ f.sum(axis=0), Rb @ ts, d.xpos[b], b, qfrc)
    for fo in v.foils:
        g = fo.geom
        Rg = d.geom_xmat[g].reshape(3, 3)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 1)
        ul = vel[3:] - Rg.T @ w
        n, span = fo.normal, fo.span
        uc, un = ul[0], ul[n]
        sp = np.hypot(uc, un)
        c_d0, k_i, c_n = fo.drag
        if c_d0 or k_i or c_n:
            fp = np.zeros(3)
            ut = np.hypot(uc, ul[span])
            fp[0] -= c_d0 * ut * uc
            fp[span] -= c_d0 * ut * ul[span]
            if sp > 0:
                di = k_i * uc * uc * un * un / sp**3
                fp[0] -= di * uc
                fp[n] -= di * un
            tp = np.zeros(3)
            if c_n:
                pos = fo.panels[:, :3]
                unp = un + _cross(vel[:3], pos)[:, n]
                fn = -c_n * fo.panels[:, 3] * np.abs(unp) * unp
                fv = np.zeros_like(pos)
                fv[:, n] = fn
                fp[n] += fn.sum()
                tp = _cross(pos, fv).sum(axis=0)
            mujoco.mj_applyFT(m, d, Rg @ fp, Rg @ tp, d.geom_xpos[g], fo.body, qfrc)
        if sp <= 0:
            continue
        k = fo.k_lift * uc * un / sp
        fl = np.zeros(3)
        fl[0], fl[n] = k * un, -k * uc
        quarter = d.geom_xpos[g] + (0.5 if uc > 0 else -0.5) * fo.half_chord * Rg[:, 0]
        mujoco.mj_applyFT(m, d, Rg @ fl, zero, quarter, fo.body, qfrc)
    wind = np.array(m.opt.wind)
    if len(v.drag_geoms) and not np.array_equal(w, wind):  # MuJoCo's drag saw option wind
        args = (v.drag_coef[:, 0], v.drag_coef[:, 1], rho, float(m.opt.viscosity))
        for j, g in enumerate(v.drag_geoms):
            Rg = d.geom_xmat[g].reshape(3, 3)
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, int(g), vel, 1)
            sl = slice(j, j + 1)
            semi = v.drag_semi[sl]
            uo = (vel[3:] - Rg.T @ w)[None]
            ur = (vel[3:] - Rg.T @ wind)[None]
            df = (
                hydro.ellipsoid_drag(uo, semi, args[0][sl], args[1][sl], *args[2:])[0]
                - hydro.ellipsoid_drag(ur, semi, args[0][sl], args[1][sl], *args[2:])[0]
            )
            body = int(m.geom_bodyid[g])
            mujoco.mj_applyFT(m, d, Rg @ df, zero, d.geom_xpos[g], body, qfrc)
    return qfrc


def passive(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """The passive-force callback (``mujoco.set_mjcb_passive``): adds every native vehicle's
    :func:`vehicle_force` to ``d.qfrc_passive``; does nothing for other models."""
    native = native_of(m)
    if native is None:
        return
    for v in native.vehicles:
        d.qfrc_passive[:] += vehicle_force(m, d, v)
