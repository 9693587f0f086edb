"""The design-time derivations against the model's files and against independent laws: the
ballast, the derived fluid coefficients and crossflow damper, the drag budget, the speed table."""

from __future__ import annotations

import math
import re

import mujoco
import numpy as np
import pytest

from bauv_sim import hull
from bauv_sim.design import ballast, fluid
from bauv_sim.design.speed_table import (
    SPEED_TABLE_CSV,
    load_speed_table,
    measure_speed_table,
    write_speed_table,
)
from bauv_sim.errors import ConfigError
from bauv_sim.hull import MODEL_DIR, SEAWATER_DENSITY_KG_M3
from bauv_sim.manoeuvres import StraightSwimResult
from bauv_sim.physics import BauvPhysics

VEHICLE = MODEL_DIR / "bauv.xml"


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(VEHICLE))


def test_ballast_in_the_model_is_the_solution():
    spec = mujoco.MjSpec.from_file(str(VEHICLE))
    hm = hull.hull_mesh(hull.HULL)
    dm = hull.dorsal_fin_mesh()
    dm.apply_translation(hull.DORSAL_FIN_ROOT_M)
    v = hm.volume + dm.volume
    cb = (hm.volume * hm.center_mass + dm.volume * dm.center_mass) / v
    sol = ballast.solve_ballast(spec, "hull", "buoyancy", "ballast", v, cb)
    g = spec.geom("ballast")
    assert g.mass == pytest.approx(sol.mass_kg, abs=1e-6)
    assert g.pos[:2] == pytest.approx(sol.pos_hull_m, abs=1e-7)  # the file rounds to 0.1 um
    assert spec.body("buoyancy").gravcomp == pytest.approx(sol.float_gravcomp, abs=1e-6)


def test_fluid_coefficients_in_the_model_are_the_derived_ones():
    text = VEHICLE.read_text()
    for geom, coefs in fluid.derived_fluid_coefficients().items():
        m = re.search(rf'<geom name="{geom}"[^>]*?fluidcoef="([^"]*)"', text, re.S)
        assert m, geom
        assert np.allclose([float(x) for x in m.group(1).split()], coefs, rtol=1e-4, atol=1e-9)


def test_hydro_tables_in_the_model_are_the_derived_ones(model):
    derived = fluid.hydro_numerics()
    for name, data in derived.items():
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, name)
        assert i >= 0, name
        a, n = model.numeric_adr[i], model.numeric_size[i]
        assert np.allclose(model.numeric_data[a : a + n], data, rtol=1e-6, atol=1e-9), name
    texts = (("hydro_foils", fluid.FOIL_GEOMS), ("hydro_segments", fluid.SEGMENT_BODIES))
    for text, names in texts:
        t = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, text)
        a, n = model.text_adr[t], model.text_size[t]
        assert bytes(model.text_data[a : a + n]).decode().rstrip("\x00").split() == list(names)


def test_crossflow_strips_reproduce_the_hull_integrals():
    """The 16 midpoint strips against a fine quadrature of the profile: projected side and top
    areas (m^2) and the yaw/pitch damping integrals of |x|^3 (strip theory's K)."""
    strips = fluid.hull_crossflow_strips()
    h = hull.HULL
    x = np.linspace(h.hinge_x_m, h.nose_x_m, 40001)
    s = h.s_of_x(x)
    side = np.trapezoid(2.0 * h.half_height(s), x)
    top = np.trapezoid(2.0 * h.half_width(s), x)
    assert strips[:, 3].sum() == pytest.approx(side, rel=1e-2)
    assert strips[:, 4].sum() == pytest.approx(top, rel=1e-2)
    k_yaw = np.trapezoid(2.0 * h.half_height(s) * np.abs(x - 0.19) ** 3, x)
    assert (strips[:, 3] * np.abs(strips[:, 0] - 0.19) ** 3).sum() == pytest.approx(k_yaw, rel=0.02)
    # 2-D coefficients by fineness: a laterally compressed section is bluffer across y
    assert fluid.section_drag_coefficient(1.0) == pytest.approx(1.2)
    assert np.all(strips[:, 5] > strips[:, 6])


def test_peduncle_strips_reproduce_its_integrals():
    """The peduncle's strips (its own frame: origin at the tail hinge, x aft < 0) against a fine
    quadrature of the profile from the tail hinge to the body's end: side and top areas (m^2),
    the flapping's damping integral of |x|^3 about the hinge; the coefficients are the body's
    (0.75 x the 2-D elliptic section's by fineness: bluffer across y than across z)."""
    strips = fluid.peduncle_crossflow_strips()
    h = hull.HULL
    x = np.linspace(h.end_x_m, h.hinge_x_m, 40001)
    s = h.s_of_x(x)
    assert np.all((strips[:, 0] < 0.0) & (strips[:, 0] > h.end_x_m - h.hinge_x_m))
    assert np.all(strips[:, 1:3] == 0.0)
    assert strips[:, 3].sum() == pytest.approx(np.trapezoid(2.0 * h.half_height(s), x), rel=2e-3)
    assert strips[:, 4].sum() == pytest.approx(np.trapezoid(2.0 * h.half_width(s), x), rel=2e-3)
    k = np.trapezoid(2.0 * h.half_height(s) * np.abs(x - h.hinge_x_m) ** 3, x)
    assert (strips[:, 3] * np.abs(strips[:, 0]) ** 3).sum() == pytest.approx(k, rel=0.01)
    assert np.all(strips[:, 5] > strips[:, 6])
    assert np.all((strips[:, 5] >= 0.75 * 1.2) & (strips[:, 5] <= 0.75 * 1.6 + 1e-12))
    assert np.all((strips[:, 6] >= 0.75 * 0.6 - 1e-12) & (strips[:, 6] <= 0.75 * 1.2))
    rows = fluid.segment_crossflow()
    assert np.array_equal(rows[:, 0], np.zeros(len(strips))) and np.array_equal(rows[:, 1:], strips)


def test_formula_laws():
    # Theodorsen: 1 when steady, 0.5 for fast oscillation, about 0.62 at k = 0.48
    assert fluid.theodorsen_magnitude(0.0) == 1.0
    assert fluid.theodorsen_magnitude(50.0) == pytest.approx(0.5, abs=0.01)
    assert fluid.theodorsen_magnitude(0.48) == pytest.approx(0.622, abs=0.005)
    # Helmbold: 2 pi for a large aspect ratio, pi A / 2 for a small one
    assert fluid.lift_slope_per_rad(1e4) == pytest.approx(2 * math.pi, rel=1e-3)
    assert fluid.lift_slope_per_rad(1e-3) == pytest.approx(math.pi * 1e-3 / 2, rel=1e-3)
    # ITTC-57 at Re = 1e7: 0.075 / 25
    assert float(fluid.ittc57_friction(1e7)) == pytest.approx(0.003)
    assert fluid.body_form_factor(0.0) == 1.0 and fluid.foil_form_factor(0.0) == 1.0


def test_speed_table_round_trip(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text(
        "# comment\nfrequency_hz,speed_m_s,power_w,strouhal\n"
        "0.5,0.4,1,0.3\n1.0,0.85,8,0.27\n1.5,1.25,28,0.3\n2.0,1.2,60,0.4\n"
    )
    t = load_speed_table(p)
    assert t.speed_at(1.0) == pytest.approx(0.85)
    assert t.speed_at(0.25) == pytest.approx(0.2)  # linear to 0 at 0 Hz
    for u in (0.3, 0.85, 1.1):
        assert t.speed_at(t.frequency_for(u)) == pytest.approx(u)
    assert t.frequency_for(5.0) == pytest.approx(1.5)  # clamped at the fastest row
    with pytest.raises(ConfigError):
        load_speed_table(tmp_path / "missing.csv")


def test_the_models_speed_table_gives_cruise_at_one_metre_per_second():
    t = load_speed_table()
    f = float(t.frequency_for(1.0))
    # 0.61 Hz since the fins are thin plates (issue 21: MuJoCo's projected-area drag on the
    # flapping caudal fin was 42 % of the swimming drag; 0.84 Hz with it)
    assert 0.5 < f < 1.6
    assert np.all(np.diff(t.frequency_hz) > 0)
    assert np.all((t.power_w >= 0) & (t.power_w <= 250.0))


def test_tow_drag_is_the_drag_budget():
    phys = BauvPhysics.from_scene_xml()
    budget = fluid.drag_budget(1.0)
    phys.set_pose([0, 0, -3], [0, 0, 0], [0, 1.0, 0])  # heading north, moving north
    assert -phys.fluid_force_world()[1] == pytest.approx(budget.total_n, rel=0.02)
    area = hull.HULL.frontal_area_m2()
    assert budget.cd == pytest.approx(
        budget.total_n / (0.5 * SEAWATER_DENSITY_KG_M3 * area), rel=1e-12
    )


def test_the_writer_reproduces_the_models_speed_table(tmp_path):
    """Rows written by write_speed_table from the model's table give the model's file back."""
    t = load_speed_table()
    swims = [
        StraightSwimResult(
            frequency_hz=float(f),
            speed_through_water_m_s=float(u),
            speed_over_ground_m_s=float(u),
            mean_motor_power_w=float(p),
            peak_motor_torque_nm=0.0,
            tail_tip_amplitude_m=0.0,
            strouhal=float(st),
            mean_pitch_rad=0.0,
            mean_fin_rad=0.0,
            yaw_amplitude_rad=0.0,
            depth_change_m=0.0,
            window_s=0.0,
        )
        for f, u, p, st in zip(t.frequency_hz, t.speed_m_s, t.power_w, t.strouhal, strict=True)
    ]
    out = tmp_path / "speed_table.csv"
    write_speed_table(swims, out)
    assert out.read_text() == SPEED_TABLE_CSV.read_text()


def test_a_short_measured_speed_table_is_written_and_read_back(tmp_path):
    swims = measure_speed_table(settle_s=2.0, measure_s=2.0, frequencies_hz=(1.0, 2.0))
    assert [s.frequency_hz for s in swims] == [1.0, 2.0]
    assert 0.0 < swims[0].speed_through_water_m_s < swims[1].speed_through_water_m_s
    out = tmp_path / "speed_table.csv"
    write_speed_table(swims, out)
    t = load_speed_table(out)
    assert np.array_equal(t.frequency_hz, [1.0, 2.0])
    assert t.speed_m_s == pytest.approx([s.speed_through_water_m_s for s in swims], abs=5e-5)
    assert t.power_w == pytest.approx([s.mean_motor_power_w for s in swims], abs=5e-4)
