"""Hydrostatics and hydrodynamics of the model against independent truth: Archimedes on the mesh
volumes, MuJoCo's drag formula evaluated by hand, the derivations' laws."""

from __future__ import annotations

import math
import re

import mujoco
import numpy as np
import pytest

from bauv_sim import hull, hydro
from bauv_sim.hull import MODEL_DIR, SEAWATER_DENSITY_KG_M3
from bauv_sim.physics import BauvPhysics

VEHICLE = MODEL_DIR / "bauv.xml"


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    m = mujoco.MjModel.from_xml_path(str(VEHICLE))
    hydro.prepare_model(m)
    return m


def _mesh_volumes() -> dict[str, float]:
    return {
        "hull": float(hull.hull_mesh(hull.HULL).volume),
        "dorsal": float(hull.dorsal_fin_mesh().volume),
        "peduncle": float(hull.peduncle_mesh(hull.HULL).volume),
        "caudal": float(hull.caudal_fin_mesh(hull.TAIL).volume),
        "lateral": float(hull.lateral_fin_mesh().volume),
    }


def test_archimedes_buoyancy_equals_rho_g_v_of_the_meshes(model):
    d = mujoco.MjData(model)
    mujoco.mj_forward(model, d)
    g = float(np.linalg.norm(model.opt.gravity))
    vols = _mesh_volumes()
    total_v = (
        vols["hull"] + vols["dorsal"] + vols["peduncle"] + vols["caudal"] + 2 * vols["lateral"]
    )
    archimedes = SEAWATER_DENSITY_KG_M3 * g * total_v
    # MuJoCo's own upward force from gravity compensation on the free joint's z
    up = float(d.qfrc_gravcomp[2])
    assert up == pytest.approx(archimedes, rel=1e-6)
    # ... and the vehicle is neutral: weight equals it
    weight = float(model.body_subtreemass[1]) * g
    assert abs(up - weight) < 1e-4  # N


def test_centre_of_buoyancy_is_the_mesh_centroid(model):
    d = mujoco.MjData(model)
    mujoco.mj_forward(model, d)
    hm = hull.hull_mesh(hull.HULL)
    dm = hull.dorsal_fin_mesh()
    dm.apply_translation(hull.DORSAL_FIN_ROOT_M)
    v = hm.volume + dm.volume
    cb = (hm.volume * hm.center_mass + dm.volume * dm.center_mass) / v
    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "buoyancy")
    assert np.allclose(d.xipos[b] - d.xpos[1], cb, atol=1e-6)
    assert model.body_gravcomp[b] * model.body_mass[b] == pytest.approx(
        SEAWATER_DENSITY_KG_M3 * v, rel=1e-7
    )


def test_vehicle_is_level_and_self_righting():
    hs = BauvPhysics.from_scene_xml().hydrostatics()
    assert abs(hs.net_up_n) < 1e-4
    assert abs(hs.bg_world_m[0]) < 1e-5 and abs(hs.bg_world_m[1]) < 1e-5  # CG under CB
    assert 0.03 < hs.metacentric_height_m() < 0.07


def test_ballast_in_the_model_is_the_solution():
    spec = mujoco.MjSpec.from_file(str(VEHICLE))
    hm = hull.hull_mesh(hull.HULL)
    dm = hull.dorsal_fin_mesh()
    dm.apply_translation(hull.DORSAL_FIN_ROOT_M)
    v = hm.volume + dm.volume
    cb = (hm.volume * hm.center_mass + dm.volume * dm.center_mass) / v
    sol = hydro.solve_ballast(spec, "hull", "buoyancy", "ballast", v, cb)
    g = spec.geom("ballast")
    assert g.mass == pytest.approx(sol.mass_kg, abs=1e-6)
    assert g.pos[:2] == pytest.approx(sol.pos_hull_m, abs=1e-6)
    assert spec.body("buoyancy").gravcomp == pytest.approx(sol.float_gravcomp, abs=1e-6)


def test_fluid_coefficients_in_the_model_are_the_derived_ones():
    text = VEHICLE.read_text()
    for geom, coefs in hydro.derived_fluid_coefficients().items():
        m = re.search(rf'<geom name="{geom}"[^>]*?fluidcoef="([^"]*)"', text, re.S)
        assert m, geom
        assert np.allclose([float(x) for x in m.group(1).split()], coefs, rtol=1e-4, atol=1e-9)


def test_crossflow_damper_reproduces_the_strip_theory_constants(model):
    phys = BauvPhysics.from_scene_xml()
    hs = phys.hydrostatics()
    k = hydro.crossflow_damping_constants(hs.cg_world_m - phys.position_world())
    g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "crossflow_damper")
    size = model.geom_size[g]
    assert np.allclose(size, hydro.damper_semi_axes(k), rtol=1e-3)
    # MuJoCo's angular drag law, I_i = 8/15 pi d_i max(d_j, d_k)^4, gives the constants back
    c = 8.0 / 15.0 * math.pi
    ii = [c * size[i] * max(size[(i + 1) % 3], size[(i + 2) % 3]) ** 4 for i in range(3)]
    assert np.allclose(SEAWATER_DENSITY_KG_M3 * np.array(ii), k, rtol=3e-3)


def test_prepare_model_removes_virtual_mass_and_set_const_needs_it_again():
    m = mujoco.MjModel.from_xml_path(str(VEHICLE))
    assert not hydro.added_mass_removed(m)
    ids = hydro.prepare_model(m)
    assert ids.size == hydro.fluid_geoms(m).size
    assert hydro.added_mass_removed(m)
    d = mujoco.MjData(m)
    mujoco.mj_setConst(m, d)
    assert not hydro.added_mass_removed(m)  # MuJoCo recomputes them
    phys = BauvPhysics.from_scene_xml()
    mujoco.mj_setConst(phys.model.ptr, phys.data.ptr)
    phys.set_const()
    assert hydro.added_mass_removed(phys.model.ptr)


def _mujoco_drag_by_hand(m: mujoco.MjModel, u: float) -> float:
    """MuJoCo's ellipsoid-model drag for a geom moving along its x axis: rho u^2 (C_b A_proj +
    C_s (A_max - A_proj)) + Stokes, from engine_passive.c, summed over the geoms (all aligned with
    the body x axis at zero joint angles)."""
    rho, mu = m.opt.density, m.opt.viscosity
    total = 0.0
    for g in hydro.fluid_geoms(m):
        a, b, c = m.geom_size[g]
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:  # semi-axes (r, r, r)
            a = b = c = m.geom_size[g][0]
        cb, cs = m.geom_fluid[g, 1], m.geom_fluid[g, 2]
        d = sorted((a, b, c))
        a_proj, a_max = math.pi * b * c, math.pi * d[2] * d[1]
        stokes = mu * 3.0 * math.pi * (2.0 / 3.0 * (a + b + c))
        total += stokes * u + rho * u * u * (cb * a_proj + cs * (a_max - a_proj))
    return total


def test_tow_drag_is_mujocos_formula_and_inside_the_target(model):
    phys = BauvPhysics.from_scene_xml()
    area = hull.HULL.frontal_area_m2()
    for u in (0.5, 1.0, 1.5):
        phys.set_pose([0, 0, -3], [0, 0, 0], [0, u, 0])  # heading north, moving north
        drag = -float(phys.fluid_force_world()[1])
        assert drag == pytest.approx(_mujoco_drag_by_hand(phys.model.ptr, u), rel=1e-9)
        cd = drag / (0.5 * SEAWATER_DENSITY_KG_M3 * u * u * area)
        assert 0.08 < cd < 0.25
    budget = hydro.drag_budget(1.0)
    phys.set_pose([0, 0, -3], [0, 0, 0], [0, 1.0, 0])
    assert -phys.fluid_force_world()[1] == pytest.approx(budget.total_n, rel=0.02)


def test_formula_laws():
    # Theodorsen: 1 when steady, 0.5 for fast oscillation, about 0.62 at k = 0.48
    assert hydro.theodorsen_magnitude(0.0) == 1.0
    assert hydro.theodorsen_magnitude(50.0) == pytest.approx(0.5, abs=0.01)
    assert hydro.theodorsen_magnitude(0.48) == pytest.approx(0.622, abs=0.005)
    # Helmbold: 2 pi for a large aspect ratio, pi A / 2 for a small one
    assert hydro.lift_slope_per_rad(1e4) == pytest.approx(2 * math.pi, rel=1e-3)
    assert hydro.lift_slope_per_rad(1e-3) == pytest.approx(math.pi * 1e-3 / 2, rel=1e-3)
    # ITTC-57 at Re = 1e7: 0.075 / 25
    assert float(hydro.ittc57_friction(1e7)) == pytest.approx(0.003)
    assert hydro.body_form_factor(0.0) == 1.0 and hydro.foil_form_factor(0.0) == 1.0


def test_speed_table_round_trip(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text(
        "# comment\nfrequency_hz,speed_m_s,power_w,strouhal\n"
        "0.5,0.4,1,0.3\n1.0,0.85,8,0.27\n1.5,1.25,28,0.3\n2.0,1.2,60,0.4\n"
    )
    t = hydro.load_speed_table(p)
    assert t.speed_at(1.0) == pytest.approx(0.85)
    assert t.speed_at(0.25) == pytest.approx(0.2)  # linear to 0 at 0 Hz
    for u in (0.3, 0.85, 1.1):
        assert t.speed_at(t.frequency_for(u)) == pytest.approx(u)
    assert t.frequency_for(5.0) == pytest.approx(1.5)  # clamped at the fastest row
    with pytest.raises(hydro.ConfigError):
        hydro.load_speed_table(tmp_path / "missing.csv")


def test_the_models_speed_table_gives_cruise_at_one_metre_per_second():
    t = hydro.load_speed_table()
    f = float(t.frequency_for(1.0))
    assert 0.8 < f < 1.6
    assert np.all(np.diff(t.frequency_hz) > 0)
    assert np.all((t.power_w >= 0) & (t.power_w <= 250.0))
