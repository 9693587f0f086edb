"""The hydrodynamics checks of issue 11 on the body: the analytic spheroid through the same
pipeline, the BAUV's sway mass, broadside drag, hull side force and roll, and its turns beside a
linear manoeuvring model from the same coefficients (run by :mod:`hydro`).

References: Lamb (1932) *Hydrodynamics* sec. 114-115, 124; Fossen (2021) *Handbook of Marine Craft
Hydrodynamics and Motion Control* ch. 6-7 (added mass, Coriolis, the linear manoeuvring model);
Hoerner (1965) *Fluid-Dynamic Drag* ch. 3 (crossflow); Munk (1924), NACA Report 184 (slender-body
moment); Newman (1977) *Marine Hydrodynamics* sec. 4.13, 7.? (strip theory of added mass).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from bauv_sim import hull, hydro, manoeuvres
from bauv_sim.design import fluid
from bauv_sim.physics import BauvPhysics

RHO = hull.SEAWATER_DENSITY_KG_M3
G = hull.GRAVITY_M_S2


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
    from checks import cruise_frequency_hz

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
