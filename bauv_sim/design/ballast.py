"""The ballast that makes the BAUV neutral and level (design time).

The hull's displacement rho V g acts at the centre of buoyancy through the gravity compensation of
a small welded body placed there (``buoyancy`` in ``models/bauv/bauv.xml``); the tail segments and
lateral fins are neutral by themselves (``gravcomp = 1``). :func:`solve_ballast` gives the ballast
mass and position, and the float's gravity compensation, that make the vehicle neutral with its
centre of gravity under its centre of buoyancy; ``tests/bauv_sim/test_design.py`` checks the model
file against it. It compiles its own copy of the vehicle's specification, never a simulation's.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.hydro import subtree_bodies, water_properties


@dataclass(frozen=True)
class BallastSolution:
    """Ballast that makes a vehicle neutral and level.

    Attributes:
        mass_kg: ballast mass, kg.
        pos_hull_m: ballast centre (x, y) in the hull frame, m; z is given.
        float_gravcomp: gravity compensation of the buoyancy body, rho V / m_float.
    """

    mass_kg: float
    pos_hull_m: NDArray[np.float64]
    float_gravcomp: float


def solve_ballast(
    spec: mujoco.MjSpec,
    hull_body: str,
    float_body: str,
    ballast_geom: str,
    displaced_volume_m3: float,
    cb_hull_m: ArrayLike,
) -> BallastSolution:
    """Ballast mass and (x, y) position that make the vehicle neutral with its CG under its CB at
    zero joint angles (``qpos0``).

    Conditions: the float's gravity compensation carries rho V g; the float's own mass plus every
    other body of the vehicle with ``gravcomp = 0`` weighs rho V g in total; the first moment of
    those masses about the CB is zero in x and y (hull frame). Bodies with ``gravcomp = 1`` (tail
    segments, lateral fins) are neutral by themselves and drop out.

    Args:
        spec: the vehicle's specification (``mujoco.MjSpec.from_file``); not modified.
        hull_body: name of the vehicle's root body.
        float_body: name of the buoyancy body.
        ballast_geom: name of the ballast geom (a child of the hull body, explicit ``mass``).
        displaced_volume_m3: volume whose displacement the float carries, m^3.
        cb_hull_m: its centroid in the hull frame, shape (3,), m.

    Returns:
        The :class:`BallastSolution`.

    Raises:
        GeometryError: if the equipment alone is heavier than the displacement.
    """
    work = spec.copy()
    geom = work.geom(ballast_geom)
    if geom is None:
        raise ConfigError(f"geom {ballast_geom!r}: not in the model")
    geom.mass = 0.0
    model = work.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, hull_body)
    fb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, float_body)
    if min(hb, fb) < 0:
        raise ConfigError(f"body {hull_body!r} or {float_body!r}: not in the model")
    R, p0 = data.xmat[hb].reshape(3, 3), data.xpos[hb]
    m_disp = water_properties(model)[0] * displaced_volume_m3
    total, moment = 0.0, np.zeros(3)
    for b in subtree_bodies(model, hb):
        if b == fb or model.body_gravcomp[b] == 0.0:
            total += float(model.body_mass[b])
            moment += float(model.body_mass[b]) * (R.T @ (data.xipos[b] - p0))
    m_b = m_disp - total
    if m_b <= 0:
        raise GeometryError(
            f"equipment {total:.3f} kg is heavier than the displacement "
            f"{m_disp:.3f} kg: no ballast can make the vehicle neutral"
        )
    cb = np.asarray(cb_hull_m, dtype=float)
    xy = (m_disp * cb[:2] - moment[:2]) / m_b
    return BallastSolution(m_b, xy, m_disp / float(model.body_mass[fb]))
