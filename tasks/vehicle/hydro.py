"""The hydrodynamics checks of issue 11, measured on the physics.

Each ``check_*`` function runs one experiment through the facade and returns its numbers;
:func:`main` runs them, prints them and rewrites the tables of ``models/bauv/README.md`` between
``<!-- BEGIN results:hydro-NAME -->`` and its ``END`` marker, beside the values measured on the
model before the plugin ``bauv.hydro`` (commit 79e14d2, by the same procedures: :data:`BEFORE`).

Run from the repository root::

    python -m tasks.vehicle.hydro                 # everything (a few minutes)
    python -m tasks.vehicle.hydro spheroid turns  # some checks only

References: Lamb (1932) *Hydrodynamics* sec. 114-115, 124; Fossen (2021) *Handbook of Marine Craft
Hydrodynamics and Motion Control* ch. 6-7 (added mass, Coriolis, the linear manoeuvring model);
Hoerner (1965) *Fluid-Dynamic Drag* ch. 3 (crossflow); Munk (1924), NACA Report 184 (slender-body
moment); Newman (1977) *Marine Hydrodynamics* sec. 4.13, 7.? (strip theory of added mass).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from bauv_sim import build, hull, hydro, manoeuvres
from bauv_sim.design import fluid
from bauv_sim.physics import BauvPhysics
from bauv_sim.sea import Sea
from tasks.vehicle.checks import README, rewrite_readme

RHO = hull.SEAWATER_DENSITY_KG_M3
G = hull.GRAVITY_M_S2

BEFORE: dict[str, float] = {
    "sway_mass_kg": 57.52,
    "broadside_cd": 0.0367,
    "hull_side_force_1deg_n": 6.13,
    "hull_side_force_2deg_n": 9.99,
    "hull_side_force_5deg_n": 14.71,
    "yaw_moment_5deg_nm": -7.29,
    "roll_period_s": 0.890,
    "roll_settle_s": 3.66,
    "turn10_rate_deg_s": 7.73,
    "turn10_radius_m": 7.56,
    "turn10_drift_deg": -3.93,
    "turn20_rate_deg_s": 15.91,
    "turn20_radius_m": 3.85,
    "turn20_drift_deg": -8.08,
    "step_along_log_min_m_s": 0.727,
    "step_cross_log_min_m_s": 0.974,
    "idle_step_along_after_20s_m_s": 0.086,
    "plain_speed_10s_m_s": 0.538,
    "plain_pitch_10s_deg": 38.0,
}
"""Figures of the model before the plugin (commit 79e14d2), measured with the same procedures
(a throwaway copy of this module's experiments against the facade of that commit); the issue's
reviewers quote the same within their own set-ups (broadside Cd 0.037, hull side force 6.1 N at
1 deg, roll period 0.89 s and settling 3.7 s, turn 7.7 deg/s and 7.5 m at 10 deg, log 0.75 m/s
after an along-track step, plain MuJoCo 0.52 m/s and 38 deg)."""

BEFORE_21: dict[str, float] = {
    "idle_across_0.2s": 0.089,
    "idle_across_1s": 0.317,
    "idle_along_0.2s": 0.004,
    "idle_along_1s": 0.019,
    "cross_lag_0.3_m": 2.656,
    "cross_lag_2_m": 5.39,
    "log_min_after_switch_m_s": 0.716,
    "tow_mujoco_r0_n": 3.815,
    "tow_mujoco_r0.05_n": 5.913,
    "tow_mujoco_r0.1_n": 7.217,
    "tow_mujoco_r0.2_n": 8.307,
    "tow_total_r0_n": 3.815,
    "tow_total_r0.05_n": 5.754,
    "tow_total_r0.1_n": 6.581,
    "tow_total_r0.2_n": 5.786,
    "speed_at_0.84_hz_m_s": 1.000,
}
"""Figures of issue 21's items on the model before it (commit e4e897f), measured by the same
procedures as :func:`check_set_sea` and :func:`check_fins` (the carry of ``Sea.immerse``, then
``set_sea``, and the thin-plate fins reverted): an idle vehicle's velocity along a 0.3 m/s current
set with ``Sea.immerse``, as a fraction of it, 0.2 s and 1 s after; a swimming vehicle's lag
behind the drifted track after 60 s in a cross current; the log's least reading after an
along-track switch; the towed drag at 1 m/s with a yaw rate (MuJoCo's part: the audit's 7.2 N);
the cruise speed at 0.84 Hz."""

OLD_FIN_FLUIDCOEF = {"caudal_fin_fluid": (0.08, 0.003781), "dorsal_fin_fluid": (0.08, 0.0046943)}
"""MuJoCo's blunt and slender drag coefficients of the fins before issue 21 (commit e4e897f)."""


def _open_water(speed_m_s: float = 0.0, heading_deg: float = 0.0) -> BauvPhysics:
    return manoeuvres.open_water_scene(depth_m=20.0, heading_deg=heading_deg, speed_m_s=speed_m_s)


def tow(
    ph: BauvPhysics,
    vel_body_m_s: NDArray[np.float64] | tuple[float, float, float],
    omega_body_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Hold the vehicle level, heading north at 20 m, with a body-frame velocity and angular
    velocity through still water, joints as they are; the fluid force (N, body) and moment about
    the reference point (N m, body) at that state (quasi-steady: the added mass's acceleration
    terms are not forces)."""
    ph.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    R = ph.R_world_from_body()
    ph.set_pose(
        [0.0, 0.0, -20.0],
        [0.0, 0.0, 0.0],
        R @ np.asarray(vel_body_m_s, dtype=float),
        angular_velocity_body_rad_s=omega_body_rad_s,
    )
    f_w, m_o = ph.fluid_wrench()
    return R.T @ f_w, m_o


def _fmt(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


# ------------------------------------------------------------------------------------------
# 1. the analytic body: a prolate spheroid through the same pipeline


def spheroid_model(folder: Path, a_m: float = 0.5, b_m: float = 0.1) -> mujoco.MjModel:
    """A neutrally buoyant prolate spheroid (semi-axes a, b, b) named ``hull`` in ideal fluid (no
    drag, no lift, no gravity; ``gravcomp`` 1 marks its mass as displaced water), whose added mass
    comes through the BAUV's pipeline: :func:`bauv_sim.design.fluid.added_mass_matrix` from
    MuJoCo's ellipsoid, applied by the plugin ``bauv.hydro``.

    Args:
        folder: where the model file is written.
        a_m: semi-major axis, m.
        b_m: semi-minor axes, m.

    Returns:
        The compiled model (timestep 0.5 ms).
    """
    vol = 4.0 / 3.0 * math.pi * a_m * b_m * b_m
    body = f"""
  <worldbody>
    <body name="hull" pos="0 0 -5" gravcomp="1">
      <freejoint/>
      <geom name="shape" type="ellipsoid" size="{a_m} {b_m} {b_m}" mass="{RHO * vol}"
            fluidshape="ellipsoid" fluidcoef="0 0 0 0 0"/>
      <!-- a welded marker: MuJoCo gives a lone body a diagonal mass-matrix block -->
      <body name="marker"><geom type="sphere" size="0.001" mass="1e-9" contype="0"
            conaffinity="0"/></body>
    </body>
  </worldbody>"""
    head = f"""<mujoco model="spheroid">
  <compiler angle="radian"/>
  <option timestep="0.0005" integrator="implicitfast" gravity="0 0 0" density="{RHO}"
          viscosity="0"/>
  <extension><plugin plugin="bauv.hydro"><instance name="hydro"/></plugin></extension>"""
    path = Path(folder) / "spheroid.xml"
    path.write_text(head + body + "\n</mujoco>\n")
    M_A = fluid.added_mass_matrix(path)
    custom = (
        '\n  <custom><numeric name="hydro_added_mass" data="'
        + " ".join(f"{v:.17g}" for v in M_A.ravel())
        + '"/></custom>'
    )
    path.write_text(head + custom + body + "\n</mujoco>\n")
    return hydro.load_model(path)


def lamb_coefficients(a_m: float, b_m: float) -> tuple[float, float, float]:
    """Lamb's k1 (axial), k2 (transverse), k' (rotation about a transverse axis) of a prolate
    spheroid, from alpha0 and beta0 of its eccentricity (Lamb 1932, sec. 115)."""
    e = math.sqrt(1.0 - (b_m / a_m) ** 2)
    log = math.log((1.0 + e) / (1.0 - e))
    alpha0 = 2.0 * (1.0 - e * e) / e**3 * (0.5 * log - e)
    beta0 = 1.0 / e**2 - (1.0 - e * e) / (2.0 * e**3) * log
    k1 = alpha0 / (2.0 - alpha0)
    k2 = beta0 / (2.0 - beta0)
    den = (2.0 - e * e) * (2.0 * e * e - (2.0 - e * e) * (beta0 - alpha0))
    return k1, k2, e**4 * (beta0 - alpha0) / den


@dataclass(frozen=True)
class SpheroidResult:
    """Measured against Lamb for a 5:1 spheroid: added masses (kg) from force steps, the yaw
    moment (N m) at 1 m/s and 5 deg incidence against (m22 - m11) u v."""

    surge_kg: tuple[float, float]
    sway_kg: tuple[float, float]
    rotation_kg_m2: tuple[float, float]
    munk_nm: tuple[float, float]


def check_spheroid() -> SpheroidResult:
    """Force steps on a 5:1 spheroid (``a = 0.5 m``) from rest give its added masses; towing it at
    5 deg gives the Munk moment."""
    a, b = 0.5, 0.1
    with tempfile.TemporaryDirectory() as tmp:
        m = spheroid_model(Path(tmp), a, b)
    d = mujoco.MjData(m)
    mass = float(m.body_mass[1])
    k1, k2, kr = lamb_coefficients(a, b)

    def accel(row: int, value: float) -> float:
        mujoco.mj_resetData(m, d)
        d.xfrc_applied[1, :] = 0.0
        d.xfrc_applied[1, row] = value
        mujoco.mj_forward(m, d)
        return float(d.qacc[row])

    surge = 10.0 / accel(0, 10.0) - mass
    sway = 10.0 / accel(1, 10.0) - mass
    i_rigid = mass * (a * a + b * b) / 5.0
    rot = 1.0 / accel(5, 1.0) - i_rigid
    mujoco.mj_resetData(m, d)
    u, v = math.cos(math.radians(5.0)), math.sin(math.radians(5.0))
    d.qvel[:3] = [u, v, 0.0]
    mujoco.mj_forward(m, d)
    munk = -float(hydro.plugin_force(d, [5])[0])
    return SpheroidResult(
        (surge, k1 * mass),
        (sway, k2 * mass),
        (rot, kr * i_rigid),
        (munk, (k2 - k1) * mass * u * v),
    )


# ------------------------------------------------------------------------------------------
# 2. the BAUV: sway mass, broadside drag, hull side force, roll


def strip_theory_sway_mass() -> float:
    """Sway added mass of the whole vehicle by strip theory, kg: elliptic sections of the body
    (nose to caudal-fin hinge) ``rho pi h^2`` per unit length, and the dorsal and caudal fins as
    flat plates moving normal to themselves, ``rho pi (c/2)^2`` per unit span (Newman 1977,
    sec. 4.13); no three-dimensional correction (it over-estimates a finite body by about 10 %)."""
    h = hull.HULL
    x = np.linspace(h.end_x_m, h.nose_x_m, 40001)
    body = RHO * math.pi * np.trapezoid(h.half_height(h.s_of_x(x)) ** 2, x)
    r, le, te = hull.DORSAL_FIN.edges(801)
    dorsal = RHO * math.pi * np.trapezoid(((le - te) / 2.0) ** 2, r)
    z, le, te = hull.caudal_fin_edges(hull.TAIL, 801)
    caudal = RHO * math.pi * np.trapezoid(((le - te) / 2.0) ** 2, z)
    return float(body + dorsal + caudal)


@dataclass(frozen=True)
class SwayMassResult:
    """Effective sway mass (kg): from a lateral force step at the CG (the free vehicle), and with
    roll and yaw held (the sway entry of the sway-roll-yaw mass matrix), beside the rigid mass and
    the strip-theory and model added masses."""

    force_at_cg_kg: float
    roll_yaw_held_kg: float
    rigid_kg: float
    strip_added_kg: float
    model_added_kg: float


def check_sway_mass(
    force_n: float = 20.0, moment_nm: float = 5.0, window_s: float = 0.05
) -> SwayMassResult:
    """The idle vehicle at rest takes a lateral force at its CG (body y), a roll moment or a yaw
    moment, for ``window_s``; the changes of the CG's lateral velocity, the roll rate and the yaw
    rate give the 3 x 3 compliance of sway, roll and yaw, whose inverse is the mass matrix (its
    sway entry: the mass with roll and yaw held; with added mass at the hull axis, above the CG, a
    pure roll moment moves the CG sideways too). ``F t / dv`` with the force alone is the
    effective mass of the free vehicle. Drag is negligible at the few mm/s and mrad/s reached."""
    cols = []
    for f, k, n in ((force_n, 0.0, 0.0), (0.0, moment_nm, 0.0), (0.0, 0.0, moment_nm)):
        ph = _open_water()
        ph.set_tail_beat_frequency_hz(0.0)
        ph.advance(0.2)
        R = ph.R_world_from_body()
        v0, w0 = R.T @ ph.com_velocity_world(), ph.angular_velocity_body()
        ph.apply_force_at_cg_world(R @ np.array([0.0, f, 0.0]), moment_body_nm=[k, 0.0, n])
        ph.step(round(window_s / ph.timestep()))
        ph.apply_force_at_cg_world(np.zeros(3))
        dv = R.T @ ph.com_velocity_world() - v0
        dw = ph.angular_velocity_body() - w0
        cols.append(np.array([dv[1], dw[0], dw[2]]) / (window_s * max(f, k, n)))
    mass = np.linalg.inv(np.column_stack(cols))
    return SwayMassResult(
        1.0 / float(cols[0][0]),
        float(mass[0, 0]),
        ph.mass_kg(),
        strip_theory_sway_mass(),
        float(ph.added_mass_matrix()[1, 1]),
    )


def _side_area_m2() -> float:
    """The vehicle's side projected area, m^2: body (nose to caudal-fin hinge), dorsal fin and
    caudal fin (the reference area of the broadside drag coefficient)."""
    h = hull.HULL
    x = np.linspace(h.end_x_m, h.nose_x_m, 40001)
    body = np.trapezoid(2.0 * h.half_height(h.s_of_x(x)), x)
    return float(body + hull.DORSAL_FIN.area_m2() + hull.caudal_fin_area_centroid(hull.TAIL)[0])


@dataclass(frozen=True)
class BroadsideResult:
    """Broadside tow: side force (N) at a speed (m/s), the side area (m^2) and Cd on it."""

    speed_m_s: float
    force_n: float
    side_area_m2: float
    cd: float


def check_broadside(speed_m_s: float = 0.3) -> BroadsideResult:
    """The vehicle held level, tail straight, moving sideways (body y) through still water."""
    f, _ = tow(_open_water(), (0.0, speed_m_s, 0.0))
    area = _side_area_m2()
    return BroadsideResult(speed_m_s, -float(f[1]), area, -f[1] / (0.5 * RHO * speed_m_s**2 * area))


def hull_only() -> BauvPhysics:
    """The vehicle with only its hull in the fluid: the other geoms' fluid coefficients zeroed,
    no lifting plates (their lift and drag), only the hull's crossflow strips (not the peduncle's:
    a model variant, for the hull's forces)."""
    spec = mujoco.MjSpec.from_file(str(hull.MODEL_DIR / "scene.xml"))
    keep = {"hull_fluid"}
    for g in spec.geoms:
        if g.fluid_ellipsoid and g.name not in keep:
            g.fluid_coefs = [0.0, 0.0, 0.0, 0.0, 0.0]
    for t in list(spec.texts):
        if t.name in ("hydro_foils", "hydro_segments"):
            spec.delete(t)
    for n in list(spec.numerics):
        if n.name in (
            "hydro_foil_cla",
            "hydro_foil_drag",
            "hydro_segment_crossflow",
            "hydro_segment_roll_damping",
        ):
            spec.delete(n)
        elif n.name == "hydro_crossflow":
            rows = np.asarray(n.data).reshape(-1, 7)
            rows[fluid.N_HULL_STRIPS :, 3:5] = 0.0
            n.data = rows.ravel().tolist()
    hydro.load_plugin()
    from dm_control.mujoco import wrapper

    return BauvPhysics.from_model(wrapper.MjModel(spec.compile()))


@dataclass(frozen=True)
class SideForceResult:
    """Hull side force (N) at sideslip angles (deg), 1 m/s, against slender-body theory
    ``rho U^2 sin(b) cos(b) pi h_max^2`` (separation at the largest section)."""

    betas_deg: tuple[float, ...]
    hull_n: tuple[float, ...]
    theory_n: tuple[float, ...]
    hull_yaw_moment_cg_nm: tuple[float, ...]
    vehicle_yaw_moment_cg_nm: tuple[float, ...]


def check_side_force(betas_deg: tuple[float, ...] = (1.0, 2.0, 5.0)) -> SideForceResult:
    """Tow the hull alone (:func:`hull_only`) and the whole vehicle at sideslip; the vehicle's
    yaw moment about its CG (positive turns the nose to port) gives the sign of the static
    stability (a vehicle moving to starboard of its heading that turns its nose to starboard is
    stable)."""
    h_max = float(np.max(hull.HULL.half_height(np.linspace(0, 1, 20001))))
    alone = hull_only()
    full = _open_water()
    hulls, theory, hull_moments, moments = [], [], [], []
    tow(full, (0.0, 0.0, 0.0))
    cg_body = full.R_world_from_body().T @ (full.hydrostatics().cg_world_m - full.position_world())
    for beta_deg in betas_deg:
        b = math.radians(beta_deg)
        vel = np.array([math.cos(b), -math.sin(b), 0.0])  # to starboard of the heading
        f_b, m_o = tow(alone, vel)
        hulls.append(float(f_b[1]))
        hull_moments.append(float((m_o - np.cross(cg_body, f_b))[2]))
        f_b, m_o = tow(full, vel)
        moments.append(float((m_o - np.cross(cg_body, f_b))[2]))
        theory.append(RHO * math.sin(b) * math.cos(b) * math.pi * h_max**2)
    return SideForceResult(
        tuple(betas_deg), tuple(hulls), tuple(theory), tuple(hull_moments), tuple(moments)
    )


@dataclass(frozen=True)
class RollResult:
    """Free roll from 20 deg, idle: the measured period and settling time (s), and the period of
    ``2 pi sqrt((I + A) / (m g BG))`` with I and A about the CG."""

    period_s: float
    settle_s: float
    theory_period_s: float
    inertia_kg_m2: float
    added_kg_m2: float
    bg_m: float


def about_point(M: NDArray[np.float64], r_m: NDArray[np.float64]) -> NDArray[np.float64]:
    """A 6 x 6 inertia (order v, w) about the reference point moved to the point ``r`` (body
    frame, m): ``H^T M H`` with ``v_ref = v_r - w x r`` (Fossen 2021, sec. 3.3)."""
    H = np.eye(6)
    x, y, z = r_m
    H[:3, 3:] = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])  # v_ref = v_r + S(r) w
    return H.T @ M @ H


def check_roll() -> RollResult:
    """The idle vehicle released at 20 deg of roll in still water (manoeuvres.roll_recovery)."""
    ph = _open_water()
    ph.set_tail_beat_frequency_hz(0.0)
    hs = ph.hydrostatics()
    r = ph.R_world_from_body().T @ (hs.cg_world_m - ph.position_world())
    inertia = about_point(ph.rigid_inertia_matrix(), r)[3, 3]
    added = about_point(ph.added_mass_matrix(), r)[3, 3]
    bg = hs.metacentric_height_m()
    res = manoeuvres.roll_recovery(ph, duration_s=20.0)
    theory = 2.0 * math.pi * math.sqrt((inertia + added) / (ph.mass_kg() * G * bg))
    return RollResult(res.period_s, res.settle_time_s, theory, inertia, added, bg)


# ------------------------------------------------------------------------------------------
# 3. turning, beside a linear manoeuvring model from the same coefficients


@dataclass(frozen=True)
class TurnRow:
    """One steady turn: measured (open loop, fixed tail bias, depth held by the fins) and the
    linear model's steady state (rate deg/s, radius m, drift angle deg: course minus heading,
    positive to starboard of the heading)."""

    bias_deg: float
    rate_deg_s: float
    radius_m: float
    drift_deg: float
    speed_m_s: float
    linear_rate_deg_s: float
    linear_radius_m: float
    linear_drift_deg: float


@dataclass(frozen=True)
class TurnResult:
    """Turns at tail biases; the linear model's derivatives (about the CG, at the cruise speed,
    N, N m, per m/s and per rad/s): Y_v, Y_r, N_v, N_r, Y_d, N_d; its stability index
    ``C = Y_v (N_r - m x_g U) - N_v (Y_r - m U)`` (> 0: stable in straight motion); and the hull's
    Munk part of N_v, ``-(B22 - B11) U`` reduced by separation (destabilizing, < 0 ...)."""

    rows: tuple[TurnRow, ...]
    derivatives: dict[str, float]
    stability_index: float
    munk_nv: float


def linear_derivatives(ph: BauvPhysics, speed_m_s: float) -> dict[str, float]:
    """Sway-yaw derivatives ``Y_v, N_v, Y_r, N_r`` about the CG by central differences of the
    model's quasi-steady fluid forces (MuJoCo's and the plugin's, less the inertial term
    ``M_A (w x nu)`` that belongs to the acceleration: in a steady turn the mass matrix's
    ``T^T M_A T q_ddot`` cancels it) at straight motion with the tail straight and still (the
    flapping's mean effect on them is left out; the tail's control derivatives come from a
    captive test with the tail beating, :func:`captive_tail_derivatives`)."""
    hs = ph.hydrostatics()
    r_cg = ph.R_world_from_body().T @ (hs.cg_world_m - ph.position_world())
    M_A = ph.added_mass_matrix()

    def yn(v: float, r: float) -> tuple[float, float]:
        nu = np.array([speed_m_s, v, 0.0, 0.0, 0.0, r])
        f, m = tow(ph, nu[:3], (0.0, 0.0, r))
        inertial = M_A[:, :3] @ np.cross(nu[3:], nu[:3])
        f = f - inertial[:3]
        m = m - inertial[3:]
        return float(f[1]), float((m - np.cross(r_cg, f))[2])

    dv, dr = 0.01, 0.01
    yp, np_ = yn(dv, 0.0)
    ym, nm = yn(-dv, 0.0)
    yrp, nrp = yn(0.0, dr)
    yrm, nrm = yn(0.0, -dr)
    return {
        "Y_v": (yp - ym) / (2 * dv),
        "N_v": (np_ - nm) / (2 * dv),
        "Y_r": (yrp - yrm) / (2 * dr),
        "N_r": (nrp - nrm) / (2 * dr),
    }


def captive_physics() -> BauvPhysics:
    """The scene with a mocap carriage (``carriage``) welded to the hull: a captive-model test
    rig (the carriage's motion is prescribed, the weld's force is measured)."""
    spec = mujoco.MjSpec.from_file(str(hull.MODEL_DIR / "scene.xml"))
    spec.worldbody.add_body(name="carriage", mocap=True, pos=[0.0, 0.0, -20.0])
    eq = spec.add_equality(name="carriage_weld", type=mujoco.mjtEq.mjEQ_WELD)
    eq.objtype = mujoco.mjtObj.mjOBJ_BODY
    eq.name1, eq.name2 = "carriage", "hull"
    eq.solref = [0.01, 1.0]
    spec.body("hull").pos = [0.0, 0.0, -20.0]
    spec.body("hull").quat = [1.0, 0.0, 0.0, 0.0]
    hydro.load_plugin()
    from dm_control.mujoco import wrapper

    return BauvPhysics.from_model(wrapper.MjModel(spec.compile()))


def captive_tail_derivatives(
    speed_m_s: float,
    frequency_hz: float,
    bias_deg: float = 5.0,
    settle_s: float = 8.0,
    measure_s: float = 8.0,
) -> tuple[float, float]:
    """``Y_d, N_d`` (N and N m per rad, about the CG) of the flapping tail: the vehicle carried
    straight at the speed by a welded carriage while its tail beats at the frequency with a bias
    of +-``bias_deg``; the mean weld force over whole beats is minus the mean hydrodynamic force
    (central difference in the bias)."""
    out = []
    for sign in (1.0, -1.0):
        ph = captive_physics()
        ph.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        R = ph.R_world_from_body()
        q = ph.quat_wxyz()
        p0 = ph.position_world()
        vel = R @ np.array([speed_m_s, 0.0, 0.0])
        ph.set_pose(p0, [0.0, 0.0, 0.0], vel)
        ph.set_tail_beat_frequency_hz(frequency_hz)
        ph.set_tail_bias_rad(sign * math.radians(bias_deg))
        r_cg = R.T @ (ph.hydrostatics().cg_world_m - p0)
        dt = ph.timestep()
        n_settle = round(settle_s / dt)
        n_beats = max(1, round(measure_s * frequency_hz))
        n_meas = round(n_beats / frequency_hz / dt)
        fy, nz = 0.0, 0.0
        for k in range(n_settle + n_meas):
            ph.set_mocap_pose_world("carriage", p0 + vel * (ph.time_s() + dt), q)
            ph.step(1)
            if k >= n_settle:
                f_w, m_b = ph.constraint_wrench()
                f_b = R.T @ f_w
                fy += f_b[1]
                nz += (m_b - np.cross(r_cg, f_b))[2]
        out.append((-fy / n_meas, -nz / n_meas))
    d = 2.0 * math.radians(bias_deg)
    return (out[0][0] - out[1][0]) / d, (out[0][1] - out[1][1]) / d


def _steady_turn(der: dict[str, float], mass: float, speed: float, bias_rad: float) -> tuple:
    """Steady state of the linear sway-yaw model about the CG:
    ``[Y_v, Y_r - m U; N_v, N_r] [v, r] = -[Y_d, N_d] d`` (Fossen 2021, eq. 7.?; x_g = 0)."""
    A = np.array([[der["Y_v"], der["Y_r"] - mass * speed], [der["N_v"], der["N_r"]]])
    v, r = np.linalg.solve(A, -np.array([der["Y_d"], der["N_d"]]) * bias_rad)
    return v, r


def check_turns(
    biases_deg: tuple[float, ...] = (10.0, 20.0), frequency_hz: float | None = None
) -> TurnResult:
    """Steady turns at tail biases (manoeuvres.heading_change, 30 s straight then 60 s, the last
    30 s fitted) with the drift angle (mean of course minus heading over the last 30 s), beside
    the linear model at the measured straight-swim speed."""
    from tasks.vehicle.checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    rows = []
    der: dict[str, float] = {}
    speed0 = None
    for bias in biases_deg:
        ph = _open_water(speed_m_s=1.0)
        res = manoeuvres.heading_change(ph, f, math.radians(bias))
        drift = math.degrees(res.drift_angle_rad)
        if speed0 is None:
            speed0 = res.speed_through_water_m_s
            lin = _open_water()
            der = linear_derivatives(lin, speed0)
            der["Y_d"], der["N_d"] = captive_tail_derivatives(speed0, f)
            mass = lin.mass_kg()
        v, r = _steady_turn(der, mass, speed0, math.radians(bias))
        rows.append(
            TurnRow(
                bias,
                math.degrees(res.turn_rate_rad_s),
                res.turning_radius_m,
                drift,
                res.speed_through_water_m_s,
                -math.degrees(r),
                abs(speed0 / r) if r else math.inf,
                -math.degrees(math.atan2(v, speed0)),
            )
        )
    lin = _open_water()
    M_B = np.asarray(fluid.added_mass_matrix(geoms=fluid.BODY_GEOMS))
    sl = fluid.slender_lift_stations()
    munk = -(M_B[1, 1] - M_B[0, 0]) * (1.0 - sl[4]) * speed0
    m_ = lin.mass_kg()
    c = der["Y_v"] * der["N_r"] - der["N_v"] * (der["Y_r"] - m_ * speed0)
    return TurnResult(tuple(rows), der, float(c), float(munk))


# ------------------------------------------------------------------------------------------
# 4. a step of the current


class StepCurrent:
    """A uniform current switched on at a time: zero before ``t0``, ``velocity`` after (the sea
    spreads the step over the control tick containing it)."""

    steady_uniform = False

    def __init__(self, t0_s: float, velocity_world_m_s: tuple[float, float, float]) -> None:
        self.t0_s = float(t0_s)
        self.velocity = np.asarray(velocity_world_m_s, dtype=float)

    def velocity_world(self, t_s, pos_world_m):
        t = np.asarray(t_s, dtype=float)
        p = np.asarray(pos_world_m, dtype=float)
        v = np.where((t >= self.t0_s)[..., None], self.velocity, 0.0)
        return np.broadcast_to(v, np.broadcast_shapes(t.shape, p.shape[:-1]) + (3,)).copy()


@dataclass(frozen=True)
class StepRow:
    """A 0.3 m/s current step, along or across the heading: the idle vehicle's time to follow
    the water horizontally within 2 % of the step (s; the water ramps over one 0.1 s tick) and
    its largest vertical velocity after it (m/s: the Froude-Krylov force acts at the centre of
    buoyancy, the inertia at the CG and the hull axis, so it pitches a little); and the swimming
    vehicle's speed through water along the hull (the log's reading, m/s, sampled every 0.1 s):
    its mean and range over the 10 s before, and its least and largest within 10 s after."""

    direction: str
    idle_follow_s: float
    idle_heave_m_s: float
    log_before_m_s: float
    log_range_before_m_s: tuple[float, float]
    log_min_m_s: float
    log_max_m_s: float


def _step_run(vel: tuple[float, float, float], swim: bool, frequency_hz: float) -> NDArray:
    ph = _open_water(speed_m_s=1.0 if swim else 0.0)
    Sea(StepCurrent(20.0, vel)).immerse(ph)
    ph.set_tail_beat_frequency_hz(frequency_hz if swim else 0.0)
    hold = manoeuvres.DepthHold(ph.depth_m())
    tick = ph.control_tick_s
    rows = []
    for _ in range(round(40.0 / tick)):
        a = hold.fins_rad(ph)
        ph.set_lateral_fins_rad(a, a)
        ph.advance(tick)
        R = ph.R_world_from_body()
        through = R.T @ ph.velocity_through_water_world()
        rows.append((ph.time_s(), through[0], *ph.velocity_world()))
    return np.array(rows)


def check_current_step(frequency_hz: float | None = None) -> tuple[StepRow, ...]:
    """Along the heading (north, the vehicle heading north) and across it (east)."""
    from tasks.vehicle.checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    out = []
    for name, vel in (("along", (0.0, 0.3, 0.0)), ("across", (0.3, 0.0, 0.0))):
        idle = _step_run(vel, False, f)
        err = np.linalg.norm(idle[:, 2:4] - np.asarray(vel)[:2], axis=1)
        t = idle[:, 0]
        # time after the step from which the horizontal velocity stays within 2 % of the step
        bad = np.flatnonzero((t > 20.0) & (err > 0.02 * 0.3))
        follow = float(t[bad[-1] + 1] - 20.0) if bad.size else float(t[t > 20.0][0] - 20.0)
        heave = float(np.max(np.abs(idle[t > 20.0, 4])))
        swim = _step_run(vel, True, f)
        pre = swim[(swim[:, 0] > 10.0) & (swim[:, 0] <= 20.0), 1]
        after = swim[(swim[:, 0] > 20.0) & (swim[:, 0] <= 30.0), 1]
        out.append(
            StepRow(
                name,
                follow,
                heave,
                float(pre.mean()),
                (float(pre.min()), float(pre.max())),
                float(after.min()),
                float(after.max()),
            )
        )
    return tuple(out)


@dataclass(frozen=True)
class SetSeaResult:
    """A steady uniform current put in with ``Sea.immerse`` (issue 21): the idle vehicle's
    velocity along a 0.3 m/s current, as a fraction of it, 0.2 s and 1 s after (across and along
    its heading); a vehicle placed at 1 m/s through the water and put in a cross current of 0.3
    and 2 m/s: its offset across the track from the still-water track plus the drift after 60 s
    (m); the log's least reading within 10 s after a 0.3 m/s current is set along the track of a
    vehicle swimming at 1 m/s, and its range over the 10 s before (m/s)."""

    idle: dict[str, tuple[float, float]]
    cross_lag_m: dict[float, float]
    log_min_after_m_s: float
    log_range_before_m_s: tuple[float, float]


def check_set_sea(frequency_hz: float | None = None) -> SetSeaResult:
    """The idle step, the start in a cross current and the along-track switch of issue 21."""
    from bauv_sim.currents import UniformCurrent
    from tasks.vehicle.checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    idle = {}
    for name, direction in (("across", math.pi / 2), ("along", 0.0)):
        ph = _open_water()
        ph.advance(1.0)
        c = UniformCurrent(0.3, direction)
        w = c.velocity_world(0.0, np.zeros(3))
        Sea(c).immerse(ph)
        fr = []
        for _ in range(10):
            ph.advance(0.1)
            fr.append(float(ph.velocity_world() @ w / (w @ w)))
        idle[name] = (fr[1], fr[9])

    def swim(seas: dict[int, Sea], ticks: int, log: list | None = None) -> NDArray:
        ph = _open_water(speed_m_s=1.0)
        hold = manoeuvres.DepthHold(ph.depth_m())
        ph.set_tail_beat_frequency_hz(f)
        p0 = ph.position_world()
        for k in range(ticks):
            if k in seas:
                seas[k].immerse(ph)
            a = hold.fins_rad(ph)
            ph.set_lateral_fins_rad(a, a)
            ph.advance(ph.control_tick_s)
            if log is not None:
                log.append(float(ph.R_world_from_body()[:, 0] @ ph.velocity_through_water_world()))
        return ph.position_world() - p0

    still = swim({}, 600)
    lag = {}
    for speed in (0.3, 2.0):
        moved = swim({0: Sea(UniformCurrent(speed, math.pi / 2))}, 600)
        lag[speed] = float(abs(moved[0] - (still[0] + speed * 60.0)))
    log: list[float] = []
    swim({200: Sea(UniformCurrent(0.3, 0.0))}, 300, log)
    before = log[100:200]
    return SetSeaResult(idle, lag, min(log[200:]), (min(before), max(before)))


@dataclass(frozen=True)
class FinDragResult:
    """The thin fins' drag (issue 21). ``coefficients``: per fin and incidence (deg), the drag
    coefficient on the plate's area of the plate model and of MuJoCo's projected-area formula
    with the fin's former coefficients, and that formula's projected area over the plate's true
    shadow. ``tow``: per yaw rate (rad/s), the towed drag at 1 m/s (N): MuJoCo's part and the total
    fluid force against the motion. ``cruise_speed_m_s``: the straight swim at 0.84 Hz (the
    cruise frequency before)."""

    coefficients: dict[str, dict[float, tuple[float, float, float]]]
    tow: dict[float, tuple[float, float]]
    cruise_speed_m_s: float


def projected_area_m2(semi: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[float, float]:
    """MuJoCo's projected area of an ellipsoid for a flow direction (``engine_passive.c``: a
    weighted mean of the three sections) and the true shadow ``pi abc |(u_x/a, u_y/b, u_z/c)|``,
    m^2."""
    n = np.asarray(u, dtype=float) / np.linalg.norm(u)
    r2 = np.asarray(semi, dtype=float) ** 2
    num = r2[1] ** 2 * r2[2] ** 2 * n[0] ** 2 + r2[2] ** 2 * r2[0] ** 2 * n[1] ** 2
    num += r2[0] ** 2 * r2[1] ** 2 * n[2] ** 2
    den = r2[1] * r2[2] * n[0] ** 2 + r2[2] * r2[0] * n[1] ** 2 + r2[0] * r2[1] * n[2] ** 2
    shadow = math.pi * float(np.prod(semi)) * float(np.linalg.norm(n / np.asarray(semi)))
    return math.pi * math.sqrt(num / den), shadow


def check_fins(alphas_deg: tuple[float, ...] = (1.0, 5.0, 20.0)) -> FinDragResult:
    """The caudal and dorsal fins' drag coefficients against incidence (design tables: the plate
    model the plugin applies, drag = q S (C_D0 cos^3 a + k_i C_L^2 + C_N sin^3 a) with C_L = C_La
    sin a cos a; MuJoCo's 2 (C_b A_proj + C_s (S - A_proj)) / S), the towed drag with a yaw rate,
    and the cruise speed at the former cruise frequency."""
    drag = fluid.foil_drag_coefficients()
    cla = fluid.foil_lift_slopes()
    fins = {f.geom: f for f in fluid.plate_fins()}
    coefs: dict[str, dict[float, tuple[float, float, float]]] = {}
    for geom, (cb, cs) in OLD_FIN_FLUIDCOEF.items():
        semi = np.array(fins[geom].semi_axes_m)  # chord, thickness, span
        area = math.pi * semi[0] * semi[2]
        c_d0, k_i, c_n = drag[geom]
        coefs[geom] = {}
        for a in alphas_deg:
            al = math.radians(a)
            c_l = cla[geom] * math.sin(al) * math.cos(al)
            plate = c_d0 * math.cos(al) ** 3 + k_i * c_l**2 + c_n * math.sin(al) ** 3
            a_proj, shadow = projected_area_m2(semi, np.array([math.cos(al), math.sin(al), 0.0]))
            old = 2.0 * (cb * a_proj + cs * (area - a_proj)) / area
            coefs[geom][a] = (plate, old, a_proj / shadow)
    tow_rows = {}
    for r in (0.0, 0.05, 0.1, 0.2):
        ph = _open_water()
        ph.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], None, [0.0, 0.0, r])
        total = -float(ph.fluid_force_world()[1])
        free = np.arange(6)
        mj = -float(np.asarray(ph.data.qfrc_fluid)[free][1])
        tow_rows[r] = (mj, total)
    swim = manoeuvres.straight_swim(_open_water(speed_m_s=1.0), 0.84)
    return FinDragResult(coefs, tow_rows, swim.speed_through_water_m_s)


# ------------------------------------------------------------------------------------------
# 5. plain MuJoCo, and a vehicle in water of its own


@dataclass(frozen=True)
class PlainResult:
    """``scene.xml`` compiled by plain MuJoCo (no plugin registered): the error it gives; with
    the one-line loader and stepped by plain ``mj_step`` from ``trim`` for 10 s: speed (m/s) and
    pitch (deg), and the largest difference of its state from the facade's run (the same model
    stepped by :class:`BauvPhysics`)."""

    plain_error: str
    loader_speed_m_s: float
    loader_pitch_deg: float
    difference_from_facade: float


def check_plain_mujoco() -> PlainResult:
    """Compile ``models/bauv/scene.xml`` in a fresh interpreter without the plugin; then with
    :func:`bauv_sim.hydro.load_model` step it with plain ``mujoco.mj_step`` from ``trim``."""
    import subprocess
    import sys

    code = (
        "import mujoco\n"
        "try:\n"
        f"    mujoco.MjModel.from_xml_path({str(hull.MODEL_DIR / 'scene.xml')!r})\n"
        "    print('compiled')\n"
        "except ValueError as e:\n"
        "    print(str(e).splitlines()[0])\n"
    )
    plain = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    m = hydro.load_model(hull.MODEL_DIR / "scene.xml")
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "trim"))
    mujoco.mj_step(m, d, round(10.0 / m.opt.timestep))
    qw, qx, qy, qz = d.qpos[3:7]
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, 2.0 * (qw * qy - qz * qx)))))
    ph = BauvPhysics.from_scene_xml()
    ph.reset_to_keyframe("trim")
    ph.step(round(10.0 / ph.timestep()))
    diff = float(np.max(np.abs(np.r_[ph.data.qpos - d.qpos, ph.data.qvel - d.qvel])))
    return PlainResult(plain.stdout.strip(), float(np.linalg.norm(d.qvel[:3])), abs(pitch), diff)


@dataclass(frozen=True)
class OwnWaterResult:
    """A follower swimming in water 0.4 m/s different from the leader's (the leader's water is
    MuJoCo's): its displacement relative to its own water after 60 s against the same vehicle
    alone in that water (m), and the difference."""

    displacement_m: float
    alone_m: float
    difference_m: float


class _TwoWaters:
    """Still water west of x = -15 m, a 0.4 m/s current setting north east of it."""

    steady_uniform = False

    def velocity_world(self, t_s, pos_world_m):
        p = np.asarray(pos_world_m, dtype=float)
        v = np.zeros(p.shape)
        v[..., 1] = np.where(p[..., 0] > -15.0, 0.4, 0.0)
        return v


def check_own_water(frequency_hz: float | None = None, duration_s: float = 60.0) -> OwnWaterResult:
    """The leader (first vehicle) in still water at x = -40 m, the follower at x = 0 in the 0.4
    m/s current; both swim north at the cruise frequency, from 1 m/s through their water. Alone,
    the follower would move relative to its water exactly as in still water; the difference is
    the error of the multi-vehicle coupling (held per tick before: 1.44 m after 60 s)."""
    from tasks.vehicle.checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(name="leader", east_m=-40.0, depth_m=20.0, speed_m_s=1.0),
            build.VehicleSpec(name="follower", east_m=0.0, depth_m=20.0, speed_m_s=1.0),
        ),
        seabed=_flat_bed(),
        beacons=(),
    )
    two = build.build_physics(cfg)
    Sea(_TwoWaters()).immerse(two)
    for name in ("leader", "follower"):
        two.set_tail_beat_frequency_hz(f, name)
    p0 = two.position_world("follower")
    two.advance(duration_s)
    moved = two.position_world("follower") - p0 - np.array([0.0, 0.4, 0.0]) * duration_s
    alone = manoeuvres.open_water_scene(depth_m=20.0, speed_m_s=1.0)
    alone.set_tail_beat_frequency_hz(f)
    q0 = alone.position_world()
    alone.advance(duration_s)
    ref = alone.position_world() - q0
    return OwnWaterResult(
        float(np.linalg.norm(moved[:2])),
        float(np.linalg.norm(ref[:2])),
        float(np.linalg.norm(moved[:2] - ref[:2])),
    )


def _flat_bed():
    from bauv_sim.seabed import SeabedConfig

    return SeabedConfig(
        depth_at_origin_m=200.0,
        slope=0.0,
        relief_std_m=0.0,
        min_depth_m=200.0,
        half_extent_m=2000.0,
        cell_m=500.0,
    )


@dataclass(frozen=True)
class SpringRow:
    """Self-propelled speed (m/s), mean motor power (W) and tail-tip amplitude (m p-p) at one
    tail-beat frequency, with the model's fixed caudal spring and, as an experiment, with the
    spring stiffened as the frequency squared above 1.5 Hz (the fin's natural frequency then
    keeps its ratio to the beat)."""

    frequency_hz: float
    fixed_speed_m_s: float
    fixed_power_w: float
    fixed_amplitude_m: float
    scaled_speed_m_s: float
    scaled_power_w: float
    scaled_amplitude_m: float


def check_spring(frequencies_hz: tuple[float, ...] = (1.5, 2.0, 2.5, 2.75, 3.0)) -> tuple:
    """Why the speed stops rising above 2.5 Hz: the same straight swims with the model's spring
    (30 N m/rad) and with ``30 (f / 1.5)^2`` N m/rad (set in the compiled model for the run)."""
    rows = []
    for f in frequencies_hz:
        out = []
        for scaled in (False, True):
            ph = manoeuvres.open_water_scene(speed_m_s=1.5)
            if scaled:
                ph.set_joint_stiffness("caudal_fin_yaw", 30.0 * max(1.0, (f / 1.5) ** 2))
            r = manoeuvres.straight_swim(ph, f)
            out += [r.speed_through_water_m_s, r.mean_motor_power_w, r.tail_tip_amplitude_m]
        rows.append(SpringRow(f, *out))
    return tuple(rows)


@dataclass(frozen=True)
class ApproximationRow:
    """Cruise (speed m/s, head yaw p-p deg at the cruise frequency) and a 10 deg tail-bias turn
    (rate deg/s, radius m, drift deg) of the model and of a variant without one approximation."""

    variant: str
    speed_m_s: float
    yaw_pp_deg: float
    turn_rate_deg_s: float
    turn_radius_m: float
    drift_deg: float


def _variant(edit) -> BauvPhysics:
    """The open-water scene at 20 m, 1 m/s north, with its compiled model edited before the
    plugin starts (the plugin reads its tables when a data is made)."""
    import copy

    from dm_control.mujoco import wrapper

    base = _open_water(speed_m_s=1.0)
    m = copy.copy(base.model.ptr)
    edit(m)
    ph = BauvPhysics.from_model(wrapper.MjModel(m))
    ph.set_pose(base.position_world(), base.roll_pitch_heading(), base.velocity_world())
    return ph


def _set_numeric(m: mujoco.MjModel, name: str, data: NDArray[np.float64]) -> None:
    """Replace the data of the one vehicle's numeric ``<prefix>name``."""
    ids = [
        i
        for i in range(m.nnumeric)
        if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i) or "").rsplit("/", 1)[-1] == name
    ]
    (i,) = ids
    a, n = int(m.numeric_adr[i]), int(m.numeric_size[i])
    values = np.asarray(data, dtype=float).ravel()
    if values.size != n:
        raise ValueError(f"numeric {name!r} holds {n} numbers, not {values.size}")
    m.numeric_data[a : a + n] = values


def check_approximations(frequency_hz: float | None = None) -> tuple[ApproximationRow, ...]:
    """What five of the model's approximations change: the afterbody's share of the hull's Munk
    couple lost to separation (the variant keeps the whole potential couple: f = 0), the tail's
    share of the rigid-body added mass at zero tail angle (the variant leaves it out: the flapping
    parts' water then only as the hinges' armature), the fins' span efficiency e = 1 of their
    induced drag (the variant: 0.8, real fins' lower bound), their normal force C_N sin^2 a
    (the variant leaves it out) and the peduncle's crossflow strips (the variant leaves them out,
    as the model was before them)."""
    from tasks.vehicle.checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    sl = fluid.slender_lift_stations()
    no_tail = fluid.added_mass_matrix(
        geoms=("hull_fluid", "dorsal_fin_fluid", "fin_port_fluid", "fin_starboard_fluid")
    )
    plates = np.array(list(fluid.foil_drag_coefficients().values()))
    segments = fluid.segment_crossflow()

    def no_peduncle_strips(m: mujoco.MjModel) -> None:
        _set_numeric(m, "hydro_segment_crossflow", segments * [1, 1, 1, 1, 0, 0, 1, 1])
        _set_numeric(m, "hydro_segment_roll_damping", [0.0])

    variants = {
        "the model": lambda m: None,
        "separation off (the hull's whole Munk couple)": lambda m: _set_numeric(
            m, "hydro_slender_lift", np.r_[sl[:4], 0.0, 0.0]
        ),
        "without the tail's added mass": lambda m: _set_numeric(m, "hydro_added_mass", no_tail),
        "fins' span efficiency 0.8 (induced drag x 1.25)": lambda m: _set_numeric(
            m, "hydro_foil_drag", plates * [1.0, 1.0 / 0.8, 1.0]
        ),
        "fins without their normal (crossflow) force": lambda m: _set_numeric(
            m, "hydro_foil_drag", plates * [1.0, 1.0, 0.0]
        ),
        "without the peduncle's crossflow drag": no_peduncle_strips,
    }
    rows = []
    for label, edit in variants.items():
        swim = manoeuvres.straight_swim(_variant(edit), f)
        turn = manoeuvres.heading_change(_variant(edit), f, math.radians(10.0))
        rows.append(
            ApproximationRow(
                label,
                swim.speed_through_water_m_s,
                math.degrees(swim.yaw_amplitude_rad),
                math.degrees(turn.turn_rate_rad_s),
                turn.turning_radius_m,
                math.degrees(turn.drift_angle_rad),
            )
        )
    return tuple(rows)


# ------------------------------------------------------------------------------------------
# README tables


def _pct(a: float, b: float) -> str:
    return f"{100.0 * (a / b - 1.0):+.0f} %"


def render(name: str, res: object) -> str:
    """Markdown of one check for ``models/bauv/README.md``."""
    from tasks.vehicle.checks import _table

    b = BEFORE
    if name == "spheroid":
        r: SpheroidResult = res  # type: ignore[assignment]
        rows = [
            [q, f"{m:.4g}", f"{t:.4g}", _pct(m, t)]
            for q, (m, t) in (
                ("surge added mass (kg)", r.surge_kg),
                ("sway added mass (kg)", r.sway_kg),
                ("added moment of inertia about a minor axis (kg m^2)", r.rotation_kg_m2),
                ("yaw moment at 1 m/s, 5 deg, ideal flow (N m; Munk: (m22 - m11) u v)", r.munk_nm),
            )
        ]
        return _table(["5:1 spheroid (a = 0.5 m)", "measured", "Lamb", "difference"], rows)
    if name == "bauv":
        sm: SwayMassResult = res["sway"]  # type: ignore[index]
        bs: BroadsideResult = res["broadside"]  # type: ignore[index]
        sf: SideForceResult = res["side"]  # type: ignore[index]
        rr: RollResult = res["roll"]  # type: ignore[index]
        ref = sm.rigid_kg + sm.strip_added_kg
        rows = [
            [
                "sway mass, roll and yaw held (kg)",
                f"{sm.roll_yaw_held_kg:.1f}",
                f"{ref:.1f} (rigid {sm.rigid_kg:.1f} + strip {sm.strip_added_kg:.1f}): "
                f"{_pct(sm.roll_yaw_held_kg, ref)}; within 20 %",
                f"{b['sway_mass_kg']:.1f}",
            ],
            [
                "sway mass, force at the CG, free (kg)",
                f"{sm.force_at_cg_kg:.1f}",
                f"model added mass {sm.model_added_kg:.1f} (MuJoCo ellipsoids)",
                f"{b['sway_mass_kg']:.1f}",
            ],
            [
                f"broadside tow at {bs.speed_m_s} m/s: Cd on {bs.side_area_m2:.3f} m^2",
                f"{bs.cd:.2f} ({bs.force_n:.1f} N)",
                "0.8-1.2",
                f"{b['broadside_cd']:.3f}",
            ],
        ]
        for beta, h, t, hm, vm in zip(
            sf.betas_deg,
            sf.hull_n,
            sf.theory_n,
            sf.hull_yaw_moment_cg_nm,
            sf.vehicle_yaw_moment_cg_nm,
            strict=True,
        ):
            rows.append(
                [
                    f"hull side force at {beta:g} deg sideslip (N)",
                    f"{h:.2f}",
                    f"slender body {t:.2f}: {_pct(h, t)}; within 30 %",
                    f"{b[f'hull_side_force_{beta:g}deg_n']:.2f}",
                ]
            )
            if beta == 5.0:
                rows.append(
                    [
                        "yaw moment about the CG at 5 deg, moving to starboard (N m; < 0 turns "
                        "the nose to starboard, into the flow: stable)",
                        f"hull {hm:+.2f}, vehicle {vm:+.2f}",
                        "hull alone: Munk, destabilising (> 0)",
                        f"vehicle {b['yaw_moment_5deg_nm']:+.2f}",
                    ]
                )
        rows += [
            [
                "roll period from 20 deg (s)",
                f"{rr.period_s:.3f}",
                f"2 pi sqrt((I + A) / (m g BG)) = {rr.theory_period_s:.3f} "
                f"(I {rr.inertia_kg_m2:.3f}, A {rr.added_kg_m2:.3f} kg m^2, "
                f"BG {1000 * rr.bg_m:.0f} mm): "
                f"{_pct(rr.period_s, rr.theory_period_s)}; within 10 %",
                f"{b['roll_period_s']:.3f}",
            ],
            ["roll settling to 2 deg (s)", f"{rr.settle_s:.2f}", "-", f"{b['roll_settle_s']:.2f}"],
        ]
        return _table(["quantity", "measured", "reference", "before (79e14d2)"], rows)
    if name == "turns":
        tr: TurnResult = res  # type: ignore[assignment]
        rows = []
        for r in tr.rows:
            k = f"turn{r.bias_deg:g}"
            rows.append(
                [
                    f"{r.bias_deg:+g}",
                    f"{r.rate_deg_s:.2f} / {r.linear_rate_deg_s:.2f} / {b[k + '_rate_deg_s']:.2f}",
                    f"{r.radius_m:.2f} / {r.linear_radius_m:.2f} / {b[k + '_radius_m']:.2f}",
                    f"{r.drift_deg:+.1f} / {r.linear_drift_deg:+.1f} / {b[k + '_drift_deg']:+.1f}",
                    f"{r.speed_m_s:.3f}",
                ]
            )
        d = tr.derivatives
        text = _table(
            [
                "tail bias deg",
                "turn rate deg/s: measured / linear / before",
                "radius m",
                "drift deg (course - heading)",
                "speed m/s",
            ],
            rows,
        )
        return text + (
            "\n\nLinear model (about the CG, at the straight-swim speed): "
            + ", ".join(f"{k} {v:+.1f}" for k, v in d.items())
            + f" (N, N m per m/s, rad/s, rad); stability index {tr.stability_index:+.0f} "
            f"(> 0: stable in straight motion). The hull's Munk part of N_v: "
            f"{tr.munk_nv:+.1f} N m per m/s (destabilising, as theory says; its afterbody share is "
            "lost to separation)."
        )
    if name == "step":
        rows = []
        for r in res:  # type: ignore[attr-defined]
            key = "along" if r.direction == "along" else "cross"
            rows.append(
                [
                    r.direction,
                    f"{r.idle_follow_s:.1f} s (largest heave {r.idle_heave_m_s:.3f} m/s)",
                    f"{r.log_before_m_s:.3f} ({r.log_range_before_m_s[0]:.3f}-"
                    f"{r.log_range_before_m_s[1]:.3f})",
                    f"{r.log_min_m_s:.3f}-{r.log_max_m_s:.3f}",
                    f"{b[f'step_{key}_log_min_m_s']:.3f}",
                ]
            )
        return _table(
            [
                "0.3 m/s step",
                "idle: follows within 2 % after",
                "log before: mean (range) m/s",
                "log 10 s after m/s",
                "log least after, before (79e14d2)",
            ],
            rows,
        )
    if name == "sea":
        q: SetSeaResult = res  # type: ignore[assignment]
        c = BEFORE_21
        rows = []
        for k in ("across", "along"):
            a, b1 = q.idle[k]
            rows.append(
                [
                    f"idle, 0.3 m/s set {k} the heading: fraction reached after 0.2 s / 1 s",
                    f"{a:.3f} / {b1:.3f}",
                    f"{c[f'idle_{k}_0.2s']:.3f} / {c[f'idle_{k}_1s']:.3f}",
                ]
            )
        for speed, lag in q.cross_lag_m.items():
            rows.append(
                [
                    f"placed at 1 m/s, put in a {speed:g} m/s cross current: behind the drifted "
                    "track after 60 s (m)",
                    f"{lag:.3f}",
                    f"{c[f'cross_lag_{speed:g}_m']:.2f}",
                ]
            )
        rows.append(
            [
                "swimming at 1 m/s, 0.3 m/s set along the track: the log's least reading in 10 s "
                "(m/s)",
                f"{q.log_min_after_m_s:.3f} (before the switch "
                f"{q.log_range_before_m_s[0]:.3f}-{q.log_range_before_m_s[1]:.3f})",
                f"{c['log_min_after_switch_m_s']:.3f}",
            ]
        )
        return _table(
            ["steady uniform current set with Sea.immerse", "measured", "before (e4e897f)"], rows
        )
    if name == "fins":
        fr: FinDragResult = res  # type: ignore[assignment]
        c = BEFORE_21
        rows = []
        for geom, by_alpha in fr.coefficients.items():
            for a, (plate, old, ratio) in by_alpha.items():
                rows.append(
                    [
                        f"{geom.removesuffix('_fluid').replace('_', ' ')}, {a:g} deg",
                        f"{plate:.4f}",
                        f"{old:.4f} ({old / plate:.1f} x; projected area {ratio:.1f} x the shadow)",
                    ]
                )
        coef = _table(
            ["fin, incidence", "drag coefficient on S: plate", "before (e4e897f): MuJoCo's"], rows
        )
        tow = _table(
            ["yaw rate rad/s", "towed drag at 1 m/s: MuJoCo's part / total N", "before (e4e897f)"],
            [
                [
                    f"{r:g}",
                    f"{mj:.3f} / {tot:.3f}",
                    f"{c[f'tow_mujoco_r{r:g}_n']:.3f} / {c[f'tow_total_r{r:g}_n']:.3f}",
                ]
                for r, (mj, tot) in fr.tow.items()
            ],
        )
        return (
            coef + "\n\n" + tow + f"\n\nStraight swim at 0.84 Hz (the cruise frequency before): "
            f"{fr.cruise_speed_m_s:.3f} m/s (before {c['speed_at_0.84_hz_m_s']:.3f})."
        )
    if name == "plain":
        p: PlainResult = res  # type: ignore[assignment]
        return _table(
            ["load", "10 s from trim", "before (79e14d2)"],
            [
                [
                    "`mujoco.MjModel.from_xml_path('models/bauv/scene.xml')`",
                    f"refused: `{p.plain_error}`",
                    f"swims {b['plain_speed_10s_m_s']:.2f} m/s, "
                    f"pitch {b['plain_pitch_10s_deg']:.0f} deg",
                ],
                [
                    "`bauv_sim.hydro.load_model('models/bauv/scene.xml')`, plain `mj_step`",
                    f"{p.loader_speed_m_s:.3f} m/s, pitch {p.loader_pitch_deg:.1f} deg; the "
                    f"facade's run differs by {p.difference_from_facade:.1g}",
                    "-",
                ],
            ],
        )
    if name == "spring":
        return _table(
            [
                "f Hz",
                "fixed spring: U m/s / P W / A m",
                "spring x (f / 1.5 Hz)^2: U m/s / P W / A m",
            ],
            [
                [
                    f"{r.frequency_hz:.2f}",
                    f"{r.fixed_speed_m_s:.3f} / {r.fixed_power_w:.0f} / {r.fixed_amplitude_m:.3f}",
                    f"{r.scaled_speed_m_s:.3f} / {r.scaled_power_w:.0f} / "
                    f"{r.scaled_amplitude_m:.3f}",
                ]
                for r in res  # type: ignore[attr-defined]
            ],
        )
    if name == "approximations":
        return _table(
            [
                "variant",
                "cruise speed m/s",
                "yaw p-p deg",
                "turn 10 deg: rate deg/s",
                "radius m",
                "drift deg",
            ],
            [
                [
                    r.variant,
                    f"{r.speed_m_s:.3f}",
                    f"{r.yaw_pp_deg:.1f}",
                    f"{r.turn_rate_deg_s:.2f}",
                    f"{r.turn_radius_m:.2f}",
                    f"{r.drift_deg:+.1f}",
                ]
                for r in res  # type: ignore[attr-defined]
            ],
        )
    if name == "water":
        w: OwnWaterResult = res  # type: ignore[assignment]
        return _table(
            ["vehicle in water 0.4 m/s different, 60 s", "measured", "before (79e14d2)"],
            [
                [
                    "displacement through its water, in the scene / alone (m)",
                    f"{w.displacement_m:.2f} / {w.alone_m:.2f}: {w.difference_m:.3f} apart",
                    "1.44 m apart (issue)",
                ]
            ],
        )
    raise KeyError(name)


def check_bauv() -> dict[str, object]:
    """Sway mass, broadside drag, hull side force and the yaw moment, roll."""
    return {
        "sway": check_sway_mass(),
        "broadside": check_broadside(),
        "side": check_side_force(),
        "roll": check_roll(),
    }


CHECKS = {
    "spheroid": check_spheroid,
    "bauv": check_bauv,
    "turns": check_turns,
    "step": check_current_step,
    "sea": check_set_sea,
    "fins": check_fins,
    "plain": check_plain_mujoco,
    "water": check_own_water,
    "spring": check_spring,
    "approximations": check_approximations,
}
"""The checks by name, in the order :func:`main` runs them."""


def main(argv: list[str] | None = None) -> dict[str, object]:
    """Run the checks, print them and rewrite the README tables (``--no-write``: print only)."""
    parser = argparse.ArgumentParser(description="BAUV hydrodynamics checks (issue 11)")
    parser.add_argument("checks", nargs="*", choices=[*CHECKS, []], default=[])
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    results: dict[str, object] = {}
    sections: dict[str, str] = {}
    for name in args.checks or list(CHECKS):
        t0 = time.perf_counter()
        results[name] = CHECKS[name]()
        sections[f"hydro-{name}"] = render(name, results[name])
        print(f"## {name} ({time.perf_counter() - t0:.1f} s wall)\n{sections[f'hydro-{name}']}\n")
    if not args.no_write:
        rewrite_readme(sections, README)
    return results


if __name__ == "__main__":
    main()
