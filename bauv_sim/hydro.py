"""Run-time hydrodynamics and hydrostatics of the BAUV's compiled MuJoCo model.

MuJoCo has no buoyancy and applies only part of the added mass (see
``../shared/notes/mujoco-and-rerun.md``). This module holds what a compiled model needs beyond
plain MuJoCo, and what the facade (:mod:`bauv_sim.physics`) uses to measure it:

* **Added mass**: MuJoCo's ellipsoid model drops the acceleration term of added mass but keeps its
  gyroscopic cross terms, which give an oscillating fin a spurious mean force (a fish swam
  backwards). :func:`prepare_model` zeroes the virtual mass and inertia of the geoms that need it;
  ``mj_setConst`` restores them, so call :func:`prepare_model` again after it.
* **Water velocity**: ``option wind`` is the velocity of the medium in MuJoCo's fluid forces, i.e.
  the current. :func:`set_water_velocity` sets it; :mod:`bauv_sim.sea` evaluates the current field
  at every vehicle at every control tick and sets it through the facade.
* **Fluid coefficients** of a compiled model can be read and replaced (calibration experiments);
  the values in the model file are derived in :mod:`bauv_sim.design.fluid`.
* **Buoyancy** is in the model file: the hull's displacement rho V g acts at the centre of buoyancy
  through the gravity compensation (``gravcomp``) of a small welded body placed there; the tail
  segments and lateral fins are neutral by themselves (``gravcomp = 1``). :func:`hydrostatics`
  measures the result (net force, centres, BG) from the bodies' arrays; the ballast that makes it
  neutral and level is :func:`bauv_sim.design.ballast.solve_ballast`.

These functions write into an ``MjModel`` at model preparation (and the water velocity once per
control tick, called by the facade): the one exception to "only :mod:`bauv_sim.physics` indexes
MuJoCo arrays". All vectors are in the world frame (ENU, m, m/s, N) unless the name says otherwise.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

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

KEEP_ADDED_MASS_GEOMS: tuple[str, ...] = ()
"""Geoms (unprefixed names) whose added-mass cross terms are kept. None: with the acceleration
term missing, the cross terms alone are not the physics of added mass on any part of this vehicle
(on the hull they would add a Munk moment without the inertia that goes with it). Measured effect
of keeping them on the hull: README.md, "Added mass"."""


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


def _geom_name(model: mujoco.MjModel, g: int) -> str:
    return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) or ""


def prepare_model(
    model: mujoco.MjModel, keep_added_mass: Iterable[str] = KEEP_ADDED_MASS_GEOMS
) -> NDArray[np.int_]:
    """Remove the added-mass artefact of the ellipsoid fluid model, in place.

    Zeroes the virtual mass and virtual inertia (``geom_fluid[:, 6:12]``) of every fluid geom
    except those whose name, after any ``prefix/`` from :mod:`dm_control.mjcf` attachment, is in
    ``keep_added_mass``. Call again after ``mj_setConst`` (which recomputes them).

    Args:
        model: compiled model (modified in place).
        keep_added_mass: unprefixed geom names to leave untouched.

    Returns:
        Ids of the geoms that were zeroed, shape (n,).

    References:
        MuJoCo ``engine_passive.c``, ``mj_addedMassForces``: the term with the accelerations is
        "disabled due to dependency on qacc"; the cross terms are applied.
    """
    keep = set(keep_added_mass)
    ids = [g for g in fluid_geoms(model) if _geom_name(model, g).rsplit("/", 1)[-1] not in keep]
    idx = np.asarray(ids, dtype=int)
    model.geom_fluid[idx, FLUID_SLICE_VIRTUAL] = 0.0
    return idx


def added_mass_removed(
    model: mujoco.MjModel, keep_added_mass: Iterable[str] = KEEP_ADDED_MASS_GEOMS
) -> bool:
    """Whether :func:`prepare_model` is in effect (non-kept fluid geoms have no virtual mass)."""
    keep = set(keep_added_mass)
    for g in fluid_geoms(model):
        if _geom_name(model, g).rsplit("/", 1)[-1] in keep:
            continue
        if np.any(model.geom_fluid[g, FLUID_SLICE_VIRTUAL] != 0.0):
            return False
    return True


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
