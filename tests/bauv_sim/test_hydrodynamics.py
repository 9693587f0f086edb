"""The run-time hydrodynamics (plugin ``bauv.hydro``) against independent truth: a second
implementation of its equations, Lamb's added mass of a spheroid, the conservation laws of a body
in ideal fluid, and the hydrodynamic balance of a neutrally buoyant body in accelerating water."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from bauv_sim import build, hydro
from bauv_sim.hull import MODEL_DIR

from .hydro_reference import free_body, reference

RHO = 1025.0


def _randomise(m: mujoco.MjModel, d: mujoco.MjData, rng: np.random.Generator) -> None:
    """A random pose, velocity and joint state of every vehicle (kept moderate)."""
    mujoco.mj_resetData(m, d)
    for j in range(m.njnt):
        a, v = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            d.qpos[a : a + 3] += rng.normal(0, 2.0, 3)
            q = rng.normal(size=4)
            d.qpos[a + 3 : a + 7] = q / np.linalg.norm(q)
            d.qvel[v : v + 3] = rng.normal(0, 0.8, 3)
            d.qvel[v + 3 : v + 6] = rng.normal(0, 0.5, 3)
        elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
            lo, hi = m.jnt_range[j] if m.jnt_limited[j] else (-0.3, 0.3)
            d.qpos[a] = rng.uniform(0.5 * lo, 0.5 * hi)
            d.qvel[v] = rng.normal(0, 1.0)


def _plugin_contribution(m, d):
    dofs = np.arange(m.nv)
    return hydro.plugin_force(d, dofs)


def _augmented_block(m, d, dof):
    """(M with the plugin's added mass) - (M as MuJoCo makes it), free joint block, qvel coords."""
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    mujoco.mj_makeM(m, d)
    raw = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, raw)
    return (full - raw)[dof : dof + 6, dof : dof + 6], (full - raw)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_plugin_equals_the_reference_implementation_on_one_vehicle(seed):
    m = hydro.load_model(MODEL_DIR / "scene.xml")
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    _randomise(m, d, rng)
    inst = hydro.plugin_instances(m)[""]
    w = rng.normal(0, 0.4, 3)
    hydro.set_water(m, d, inst, w, rng.normal(0, 0.3, 3), t0_s=-0.05)
    hydro.set_water_velocity(m, w + 0.05 * hydro.water(m, d, inst)[1])  # the first vehicle's
    mujoco.mj_forward(m, d)
    got = _plugin_contribution(m, d)
    want, M_add = reference(m, d)
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    dof = int(m.jnt_dofadr[m.body_jntadr[free_body(m, "")]])
    blk, full = _augmented_block(m, d, dof)
    assert np.allclose(blk, M_add, rtol=0, atol=1e-9)
    full[dof : dof + 6, dof : dof + 6] = 0.0
    assert not np.any(full)  # nothing outside the free joint's block


@pytest.mark.parametrize("jacobian", ["dense", "sparse"])
def test_plugin_equals_the_reference_with_dense_and_sparse_jacobians(jacobian):
    """The plugin adds its per-body wrenches along each body's chain of dofs itself for a model
    with dense Jacobians (MuJoCo's default below 60 dofs) and through ``mj_applyFT`` for one with
    sparse Jacobians (scenes of five vehicles and more): both equal the reference."""
    m = hydro.load_model(MODEL_DIR / "scene.xml")
    m.opt.jacobian = int(getattr(mujoco.mjtJacobian, f"mjJAC_{jacobian.upper()}"))
    d = mujoco.MjData(m)
    assert mujoco.mj_isSparse(m) == (jacobian == "sparse")
    rng = np.random.default_rng(13)
    _randomise(m, d, rng)
    inst = hydro.plugin_instances(m)[""]
    w = rng.normal(0, 0.4, 3)
    hydro.set_water(m, d, inst, w, rng.normal(0, 0.3, 3), t0_s=-0.05)
    hydro.set_water_velocity(m, w)
    mujoco.mj_forward(m, d)
    got = _plugin_contribution(m, d)
    want, _ = reference(m, d)
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_plugin_equals_the_reference_for_vehicles_in_different_water():
    phys = build.build_physics(
        build.SceneConfig(
            vehicles=(
                build.VehicleSpec(name="leader", depth_m=3.0),
                build.VehicleSpec(name="follower", east_m=-30.0, depth_m=3.0),
            )
        )
    )
    m, d = phys.model.ptr, phys.data.ptr
    rng = np.random.default_rng(7)
    _randomise(m, d, rng)
    inst = hydro.plugin_instances(m)
    hydro.set_water(m, d, inst["leader/"], [0.2, 0.1, 0.0])
    hydro.set_water_velocity(m, [0.2, 0.1, 0.0])
    hydro.set_water(m, d, inst["follower/"], [-0.3, 0.4, 0.05], [0.1, -0.2, 0.0])
    mujoco.mj_forward(m, d)
    got = _plugin_contribution(m, d)
    want = reference(m, d, "leader/")[0] + reference(m, d, "follower/")[0]
    assert np.allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_forces_are_evaluated_again_without_adding_the_mass_twice():
    m = hydro.load_model(MODEL_DIR / "scene.xml")
    d = mujoco.MjData(m)
    _randomise(m, d, np.random.default_rng(3))
    mujoco.mj_forward(m, d)
    first = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, first)
    mujoco.mj_fwdVelocity(m, d)  # a second passive evaluation on the same mass matrix
    again = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, again)
    assert np.array_equal(first, again)


# ------------------------------------------------------------------------------------------
# a prolate spheroid in ideal fluid (the analytic case)

A_SPH, B_SPH = 0.5, 0.1  # semi-axes, m (5:1)


def _lamb(a: float, b: float) -> tuple[float, float, float]:
    """Lamb (1932, sec. 114-115) for a prolate spheroid: k1 (axial), k2 (transverse), k' (rotation
    about a transverse axis), from alpha0, beta0 of the eccentricity."""
    e = math.sqrt(1.0 - (b / a) ** 2)
    log = math.log((1.0 + e) / (1.0 - e))
    alpha0 = 2.0 * (1.0 - e * e) / e**3 * (0.5 * log - e)
    beta0 = 1.0 / e**2 - (1.0 - e * e) / (2.0 * e**3) * log
    k1 = alpha0 / (2.0 - alpha0)
    k2 = beta0 / (2.0 - beta0)
    den = (2.0 - e * e) * (2.0 * e * e - (2.0 - e * e) * (beta0 - alpha0))
    kr = e**4 * (beta0 - alpha0) / den
    return k1, k2, kr


def _spheroid_model(tmp_path) -> mujoco.MjModel:
    """The 5:1 spheroid of ``models/bauv/tools/hydro_body.py`` (neutral, ideal fluid, added mass
    through the BAUV's pipeline: ``design.fluid.added_mass_matrix`` and the plugin)."""
    from tests.model_tools import tool

    return tool("hydro_body").spheroid_model(tmp_path, A_SPH, B_SPH)


def test_spheroid_added_mass_is_lambs(tmp_path):
    m = _spheroid_model(tmp_path)
    d = mujoco.MjData(m)
    vol = 4.0 / 3.0 * math.pi * A_SPH * B_SPH * B_SPH
    k1, k2, kr = _lamb(A_SPH, B_SPH)
    assert (k1, k2, kr) == pytest.approx((0.0591, 0.894, 0.700), abs=2e-3)  # the values
    mass = RHO * vol
    # a force step along each axis from rest: the acceleration gives the effective mass
    for axis, k in ((0, k1), (1, k2), (2, k2)):
        mujoco.mj_resetData(m, d)
        d.xfrc_applied[1, :3] = 0.0
        d.xfrc_applied[1, axis] = 10.0
        mujoco.mj_forward(m, d)
        added = 10.0 / d.qacc[axis] - mass
        assert added == pytest.approx(k * mass, rel=0.05)
    mujoco.mj_resetData(m, d)
    d.xfrc_applied[1, 5] = 1.0  # torque about z
    mujoco.mj_forward(m, d)
    i_rigid = mass * (A_SPH**2 + B_SPH**2) / 5.0
    assert 1.0 / d.qacc[5] - i_rigid == pytest.approx(kr * i_rigid, rel=0.05)


def test_spheroid_munk_moment_at_five_degrees(tmp_path):
    m = _spheroid_model(tmp_path)
    d = mujoco.MjData(m)
    vol = 4.0 / 3.0 * math.pi * A_SPH * B_SPH * B_SPH
    k1, k2, _ = _lamb(A_SPH, B_SPH)
    u, v = math.cos(math.radians(5.0)), math.sin(math.radians(5.0))
    d.qvel[:3] = [u, v, 0.0]  # body axes = world axes
    mujoco.mj_forward(m, d)
    yaw = hydro.plugin_force(d, [5])[0]
    munk = (k2 - k1) * RHO * vol * u * v
    # it turns the body broadside: a moment towards -z for flow from +x, +y
    assert yaw == pytest.approx(-munk, rel=0.05)


def test_spheroid_in_ideal_fluid_keeps_energy_and_impulse(tmp_path):
    """Kirchhoff: a body coasting in ideal fluid keeps the kinetic energy of body and fluid,
    1/2 nu^T (M_RB + M_A) nu, and the impulse R (M_RB + M_A)_lin nu in the world frame (Lamb 1932
    sec. 124). Flipping a sign of C_A or leaving out the w x nu term breaks both."""
    m = _spheroid_model(tmp_path)
    d = mujoco.MjData(m)
    d.qpos[3:7] = [0.9, 0.2, -0.3, 0.1]
    d.qpos[3:7] /= np.linalg.norm(d.qpos[3:7])
    d.qvel[:] = [0.6, -0.4, 0.3, 0.4, -0.7, 0.5]
    M_A = np.array(m.numeric_data[:36]).reshape(6, 6)

    def invariants():
        mujoco.mj_forward(m, d)
        full = np.zeros((6, 6))
        mujoco.mj_fullM(m, d, full)  # M_RB + T^T M_A T in qvel coordinates
        energy = 0.5 * d.qvel @ full @ d.qvel
        R = d.xmat[1].reshape(3, 3)
        nu = np.r_[R.T @ d.qvel[:3], d.qvel[3:]]
        mass = m.body_mass[1]
        impulse = R @ (mass * nu[:3] + (M_A @ nu)[:3])
        return energy, impulse

    e0, p0 = invariants()
    for _ in range(4000):  # 2 s
        mujoco.mj_step(m, d)
    e1, p1 = invariants()
    assert e1 == pytest.approx(e0, rel=2e-3)
    assert np.allclose(p1, p0, atol=2e-3 * np.linalg.norm(p0))


def test_neutral_body_follows_accelerating_water(tmp_path):
    """A neutrally buoyant body in water accelerating uniformly moves with it: the Froude-Krylov
    force rho V a and the added mass's reaction M_A a accelerate the body's mass and added mass
    at a (no relative motion builds up)."""
    m = _spheroid_model(tmp_path)
    d = mujoco.MjData(m)
    inst = hydro.plugin_instances(m)[""]
    a = np.array([0.3, -0.2, 0.1])
    hydro.set_water(m, d, inst, [0.0, 0.0, 0.0], a, t0_s=0.0)
    for _ in range(2000):  # 1 s
        mujoco.mj_step(m, d)
    w, _ = hydro.water(m, d, inst)
    assert np.allclose(d.qvel[:3], w, rtol=0, atol=1e-4 * np.linalg.norm(w))
    assert np.allclose(d.qvel[3:], 0.0, atol=1e-9)


# ------------------------------------------------------------------------------------------
# a thin fin is a thin plate (issue 21)


def _plate_model(tmp_path, fin: str = "caudal_fin_fluid") -> tuple[mujoco.MjModel, dict]:
    """One of the vehicle's fins alone: a body ``hull`` (free joint, no fluid forces of its own)
    carrying a plate with the fin's ellipse, lift slope and drag coefficients as the vehicle's
    model file gives them (chord along x, span along z, normal along y); no added mass, no
    gravity, no viscosity."""
    vehicle = hydro.load_model(MODEL_DIR / "bauv.xml")

    def numeric(name):
        i = mujoco.mj_name2id(vehicle, mujoco.mjtObj.mjOBJ_NUMERIC, name)
        a = vehicle.numeric_adr[i]
        return np.array(vehicle.numeric_data[a : a + vehicle.numeric_size[i]])

    t = mujoco.mj_name2id(vehicle, mujoco.mjtObj.mjOBJ_TEXT, "hydro_foils")
    names = bytes(vehicle.text_data[vehicle.text_adr[t] :][: vehicle.text_size[t]]).decode()
    k = names.rstrip("\x00").split().index(fin)
    g = mujoco.mj_name2id(vehicle, mujoco.mjtObj.mjOBJ_GEOM, fin)
    chord, thick, span = vehicle.geom_size[g][0], min(vehicle.geom_size[g]), 0.0
    span = float(sum(vehicle.geom_size[g]) - chord - thick)
    c_la = float(numeric("hydro_foil_cla")[k])
    c_d0, k_i, c_n = (float(x) for x in numeric("hydro_foil_drag").reshape(-1, 3)[k])
    xml = f"""<mujoco model="plate">
  <option timestep="0.001" integrator="implicitfast" gravity="0 0 0" density="{RHO}"
          viscosity="0"/>
  <extension><plugin plugin="bauv.hydro"><instance name="hydro"/></plugin></extension>
  <custom>
    <numeric name="hydro_added_mass" data="{" ".join(["0"] * 36)}"/>
    <text name="hydro_foils" data="plate"/>
    <numeric name="hydro_foil_cla" data="{c_la!r}"/>
    <numeric name="hydro_foil_drag" data="{c_d0!r} {k_i!r} {c_n!r}"/>
  </custom>
  <worldbody>
    <body name="hull">
      <freejoint/>
      <geom type="sphere" size="0.05" mass="1"/>
      <geom name="plate" type="ellipsoid" size="{chord} {thick} {span}" mass="1"
            fluidshape="ellipsoid" fluidcoef="0 0 0 0 0"/>
      <body name="marker"><geom type="sphere" size="0.001" mass="1e-9"/></body>
    </body>
  </worldbody>
</mujoco>"""
    path = tmp_path / "plate.xml"
    path.write_text(xml)
    coefs = dict(S=math.pi * chord * span, a=chord, b=span, c_la=c_la, c_d0=c_d0, k_i=k_i, c_n=c_n)
    return hydro.load_model(path), coefs


@pytest.mark.parametrize("fin", ["caudal_fin_fluid", "dorsal_fin_fluid"])
@pytest.mark.parametrize("alpha_deg", [1.0, 5.0, 20.0, 60.0, 90.0])
def test_a_fin_is_a_thin_plate(tmp_path, fin, alpha_deg):
    """The force on a fin moving at 1.3 m/s at incidence a in its chord-normal plane, against the
    thin plate worked out here with q = 1/2 rho U^2: friction q S C_D0 cos^2 a along the chord,
    induced drag q S C_L^2 / (pi e A) against the flow with C_L = C_La sin a cos a, the normal
    force q S C_N sin^2 a (Hoerner's plate across the flow at 90 deg), the lift q S C_L across
    the flow. MuJoCo's projected-area drag of the fin's flat ellipsoid put nearly the whole plate in
    the flow at a few degrees (3.2 times the true shadow at 1 deg, 6.7 at 5 deg on the caudal fin):
    the caudal fin's drag coefficient on S was 0.044 at 1 deg and 0.124 at 5 deg, 2.3 and 5.4 times
    the plate's 0.019 and 0.023 (0.019 is its friction)."""
    m, c = _plate_model(tmp_path, fin)
    d = mujoco.MjData(m)
    U, al = 1.3, math.radians(alpha_deg)
    flow = np.array([math.cos(al), math.sin(al), 0.0])  # plate x chord, y normal
    d.qvel[:3] = -U * flow  # the plate moves through still water: the water comes along +flow
    mujoco.mj_forward(m, d)
    f = hydro.plugin_force(d, [0, 1, 2])
    q = 0.5 * RHO * U * U
    c_l = c["c_la"] * math.sin(al) * math.cos(al)
    friction = q * c["S"] * c["c_d0"] * math.cos(al) ** 2 * np.array([1.0, 0.0, 0.0])
    induced = q * c["S"] * c["k_i"] * c_l**2 * flow
    normal = q * c["S"] * c["c_n"] * math.sin(al) ** 2 * np.array([0.0, 1.0, 0.0])
    lift_dir = np.array([-math.sin(al), math.cos(al), 0.0])  # perpendicular to the flow
    lift = q * c["S"] * c_l * lift_dir
    # the water pushes along +flow: drag along +flow, friction along +chord
    want = friction + induced + normal + lift
    assert np.allclose(f, want, rtol=1e-9, atol=1e-12)
    if fin == "caudal_fin_fluid" and alpha_deg in (1.0, 5.0):
        drag = f @ flow
        assert drag / (q * c["S"]) < c["c_d0"] + 0.005  # friction and a little induced drag


def test_a_rolling_plate_is_damped_as_strip_theory_says(tmp_path):
    """A plate spinning about its chord (no translation): its panels' normal force gives the
    moment -1/2 rho C_N p|p| int c(s) |s|^3 ds = -1/2 rho C_N p|p| (8/15) a b^4 of the ellipse
    (chord c(s) = 2 a sqrt(1 - s^2/b^2)), to the panels' quadrature (0.5 %)."""
    m, c = _plate_model(tmp_path, "fin_port_fluid")
    d = mujoco.MjData(m)
    p = 2.0
    d.qvel[3] = p  # about the chord (body x)
    mujoco.mj_forward(m, d)
    moment = hydro.plugin_force(d, [3, 4, 5])
    want = -0.5 * RHO * c["c_n"] * p * abs(p) * 8.0 / 15.0 * c["a"] * c["b"] ** 4
    assert moment[0] == pytest.approx(want, rel=0.005)
    assert np.allclose(moment[1:], 0.0, atol=1e-12)
    assert np.allclose(hydro.plugin_force(d, [0, 1, 2]), 0.0, atol=1e-12)


# ------------------------------------------------------------------------------------------
# the peduncle's crossflow drag: strips in its own moving frame


def _c2d(fineness):
    """2-D drag coefficient of an elliptic cylinder across the flow by its fineness (length along
    the flow over width across it), subcritical: 1.6 at 1:2, 1.2 for the circle, 0.6 at 2:1
    (Delany & Sorensen 1953, NACA TN 3038; Hoerner 1965 ch. 3), linear in log fineness, held at
    the ends."""
    return np.interp(np.log2(fineness), np.log2([0.5, 1.0, 2.0]), [1.6, 1.2, 0.6])


ETA = 0.75  # finite-length factor of the body's crossflow, fineness 5.9 (Hoerner 1965 ch. 3)


def _peduncle_model(tmp_path) -> mujoco.MjModel:
    """The peduncle alone: a body ``hull`` (free joint, origin at the tail hinge, no fluid forces)
    carrying the body ``peduncle`` on the tail hinge (z axis), with the vehicle's segment tables
    as its model file gives them; no added mass, no gravity, no viscosity."""
    vehicle = hydro.load_model(MODEL_DIR / "bauv.xml")

    def numeric(name):
        i = mujoco.mj_name2id(vehicle, mujoco.mjtObj.mjOBJ_NUMERIC, name)
        assert i >= 0, name
        a, n = vehicle.numeric_adr[i], vehicle.numeric_size[i]
        return " ".join(repr(float(x)) for x in vehicle.numeric_data[a : a + n])

    xml = f"""<mujoco model="peduncle">
  <option timestep="0.001" integrator="implicitfast" gravity="0 0 0" density="{RHO}"
          viscosity="0"/>
  <extension><plugin plugin="bauv.hydro"><instance name="hydro"/></plugin></extension>
  <custom>
    <numeric name="hydro_added_mass" data="{" ".join(["0"] * 36)}"/>
    <text name="hydro_segments" data="peduncle"/>
    <numeric name="hydro_segment_crossflow" data="{numeric("hydro_segment_crossflow")}"/>
    <numeric name="hydro_segment_roll_damping" data="{numeric("hydro_segment_roll_damping")}"/>
  </custom>
  <worldbody>
    <body name="hull">
      <freejoint/>
      <geom type="sphere" size="0.05" mass="1"/>
      <body name="marker"><geom type="sphere" size="0.001" mass="1e-9"/></body>
      <body name="peduncle">
        <joint name="tail_yaw" type="hinge" axis="0 0 1"/>
        <geom type="sphere" size="0.02" mass="1"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""
    path = tmp_path / "peduncle.xml"
    path.write_text(xml)
    return hydro.load_model(path)


def _peduncle_profile(n: int = 40001):
    """Stations x aft of the tail hinge (m, < 0, the peduncle's frame), half-heights h and
    half-widths w (m) of its elliptic sections, from the stated body profile."""
    from bauv_sim import hull

    h = hull.HULL
    x = np.linspace(h.end_x_m, h.hinge_x_m, n)
    s = h.s_of_x(x)
    return x - h.hinge_x_m, h.half_height(s), h.half_width(s)


def _peduncle_forces(m, qvel, tail_rad=0.0):
    d = mujoco.MjData(m)
    d.qpos[7] = tail_rad
    d.qvel[:] = qvel
    mujoco.mj_forward(m, d)
    return hydro.plugin_force(d, np.arange(m.nv))  # free joint: force (world), moment; tail


@pytest.mark.parametrize("v, w", [(0.4, 0.0), (-0.7, 0.0), (0.0, 0.5), (0.3, -0.4)])
def test_the_peduncle_moving_sideways_and_heaving_takes_strip_theorys_crossflow_drag(
    tmp_path, v, w
):
    """The peduncle translating across its axis at (v, w) (sway, heave; tail straight, hull axes =
    world axes) through still water: strip theory (Allen & Perkins 1951) with elliptic sections
    of the body profile, per unit length ``-1/2 rho eta C_2D 2h |c| v`` across y (C_2D by the
    section's fineness w/h) and ``-1/2 rho eta C_2D 2w |c| w`` across z (fineness h/w), with
    |c| = sqrt(v^2 + w^2), integrated here over the profile; the moment about the tail hinge is
    that of the same distribution. Before the peduncle had strips it took no crossflow drag."""
    m = _peduncle_model(tmp_path)
    x, hh, ww = _peduncle_profile()
    c = math.hypot(v, w)
    fy = -0.5 * RHO * ETA * _c2d(ww / hh) * 2.0 * hh * c * v  # N/m
    fz = -0.5 * RHO * ETA * _c2d(hh / ww) * 2.0 * ww * c * w
    want_f = np.array([0.0, np.trapezoid(fy, x), np.trapezoid(fz, x)])
    want_m = np.array([0.0, -np.trapezoid(x * fz, x), np.trapezoid(x * fy, x)])  # r x f, r = x e_x
    got = _peduncle_forces(m, [0.0, v, w, 0.0, 0.0, 0.0, 0.0])
    assert np.allclose(got[:3], want_f, rtol=0, atol=5e-3 * np.abs(want_f).max())
    assert np.allclose(got[3:6], want_m, rtol=0, atol=1e-2 * np.abs(want_m).max())
    assert got[6] == pytest.approx(want_m[2], rel=1e-2)  # the hinge takes the yaw moment


@pytest.mark.parametrize("rate", [2.0, -1.5])
def test_the_flapping_peduncle_is_damped_as_strip_theory_says(tmp_path, rate):
    """The hull still, the peduncle swinging about the tail hinge at ``rate`` (rad/s): each section
    moves across at c = rate x (x aft of the hinge, < 0), so the moment about the hinge is
    ``-1/2 rho eta rate |rate| int C_2D 2h |x|^3 dx`` and the force ``+1/2 rho eta rate |rate|
    int C_2D 2h x^2 dx`` along y: the rotation is seen in the peduncle's own frame."""
    m = _peduncle_model(tmp_path)
    x, hh, ww = _peduncle_profile()
    k = 0.5 * RHO * ETA * _c2d(ww / hh) * 2.0 * hh
    want_m = -rate * abs(rate) * np.trapezoid(k * np.abs(x) ** 3, x)
    want_f = rate * abs(rate) * np.trapezoid(k * x**2, x)
    got = _peduncle_forces(m, [0.0] * 6 + [rate])
    assert got[6] == pytest.approx(want_m, rel=1e-2)
    assert got[5] == pytest.approx(want_m, rel=1e-2)
    assert got[1] == pytest.approx(want_f, rel=1e-2)
    assert np.allclose(got[[0, 2, 3, 4]], 0.0, atol=1e-12)


def test_the_deflected_peduncle_takes_its_crossflow_in_its_own_frame(tmp_path):
    """The tail deflected by 0.3 rad, the vehicle moving sideways (world y) at 0.5 m/s: the
    peduncle meets the flow at 0.3 rad off its normal, its crossflow is V cos(0.3) along its own
    y axis (-sin 0.3, cos 0.3, 0) and the axial part drives no crossflow drag."""
    m = _peduncle_model(tmp_path)
    x, hh, ww = _peduncle_profile()
    th, V = 0.3, 0.5
    cy = V * math.cos(th)
    fy = np.trapezoid(-0.5 * RHO * ETA * _c2d(ww / hh) * 2.0 * hh * abs(cy) * cy, x)
    got = _peduncle_forces(m, [0.0, V, 0.0, 0.0, 0.0, 0.0, 0.0], tail_rad=th)
    want = fy * np.array([-math.sin(th), math.cos(th), 0.0])
    assert np.allclose(got[:3], want, rtol=0, atol=5e-3 * abs(fy))


def test_the_rolling_peduncle_is_damped_like_the_hulls_sections(tmp_path):
    """The peduncle rolling about its axis at p: its non-circular sections sweep the water outside
    their inscribed circle, ``-1/2 rho C p|p| int (h^4 - w^4) / 4 dx`` with C = 1.2 (Hoerner's
    plate across the flow), as the hull's sections."""
    m = _peduncle_model(tmp_path)
    x, hh, ww = _peduncle_profile()
    p = 3.0
    want = -0.5 * RHO * 1.2 * p * abs(p) * np.trapezoid((hh**4 - ww**4) / 4.0, x)
    got = _peduncle_forces(m, [0.0, 0.0, 0.0, p, 0.0, 0.0, 0.0])
    assert got[3] == pytest.approx(want, rel=1e-3)
    assert np.allclose(got[[0, 1, 2, 4, 5, 6]], 0.0, atol=1e-12)
