"""Hydrostatics and hydrodynamics of the compiled model against independent truth: Archimedes on
the mesh volumes, the centre of buoyancy, the added-mass fix, MuJoCo's drag formula by hand."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from bauv_sim import hull, hydro
from bauv_sim.hull import MODEL_DIR, SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S
from bauv_sim.physics import BauvPhysics

VEHICLE = MODEL_DIR / "bauv.xml"


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return hydro.load_model(VEHICLE)


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


def test_the_plugin_takes_over_the_virtual_mass_again_after_set_const():
    m = hydro.load_model(VEHICLE)
    d = mujoco.MjData(m)
    assert hydro.added_mass_removed(m)  # zeroed when the plugin starts on a data
    mujoco.mj_setConst(m, d)
    assert not hydro.added_mass_removed(m)  # MuJoCo recomputes them
    mujoco.mj_forward(m, d)
    assert hydro.added_mass_removed(m)  # the plugin zeroes them at every evaluation


def test_without_the_plugin_the_model_does_not_compile(tmp_path):
    """Plain MuJoCo refuses the vehicle rather than simulating a wrong one (in a process that
    never registered the plugin)."""
    import subprocess
    import sys

    code = f"import mujoco; mujoco.MjModel.from_xml_path({str(VEHICLE)!r})"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode != 0
    assert "plugin bauv.hydro not found" in out.stderr


def _mujoco_drag_by_hand(m: mujoco.MjModel, u: float) -> float:
    """MuJoCo's ellipsoid-model drag for a geom moving along its x axis: rho u^2 (C_b A_proj +
    C_s (A_max - A_proj)) + Stokes, from engine_passive.c, summed over the geoms (all aligned with
    the body x axis at zero joint angles)."""
    rho, mu = SEAWATER_DENSITY_KG_M3, SEAWATER_VISCOSITY_PA_S  # the model's water (hydro_water)
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


def _plate_drag_by_hand(m: mujoco.MjModel, u: float) -> float:
    """The thin plates' drag at zero incidence, moving along their chords: the profile drag
    1/2 rho S C_D0 u^2 of each plate's ellipse S = pi a_chord a_span (no lift, so no induced drag;
    no normal velocity, so no normal force)."""
    t = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXT, "hydro_foils")
    names = bytes(m.text_data[m.text_adr[t] : m.text_adr[t] + m.text_size[t]]).decode()
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, "hydro_foil_drag")
    coefs = np.asarray(m.numeric_data[m.numeric_adr[i] : m.numeric_adr[i] + m.numeric_size[i]])
    total = 0.0
    for name, (c_d0, _, _) in zip(names.rstrip("\x00").split(), coefs.reshape(-1, 3), strict=True):
        a, b, c = m.geom_size[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)]
        total += 0.5 * SEAWATER_DENSITY_KG_M3 * math.pi * a * max(b, c) * c_d0 * u * u
    return total


def test_tow_drag_is_mujocos_formula_with_the_plates_and_inside_the_target(model):
    phys = BauvPhysics.from_scene_xml()
    area = hull.HULL.frontal_area_m2()
    m = phys.model.ptr
    for u in (0.5, 1.0, 1.5):
        phys.set_pose([0, 0, -3], [0, 0, 0], [0, u, 0])  # heading north, moving north
        drag = -float(phys.fluid_force_world()[1])
        by_hand = _mujoco_drag_by_hand(m, u) + _plate_drag_by_hand(m, u)
        assert drag == pytest.approx(by_hand, rel=1e-9)
        cd = drag / (0.5 * SEAWATER_DENSITY_KG_M3 * u * u * area)
        assert 0.08 < cd < 0.25
