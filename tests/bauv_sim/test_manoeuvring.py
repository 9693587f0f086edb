"""The manoeuvring model (bauv_sim.manoeuvring, issue 27): laws of its equations, its
vectorisation, and its steady states against the full model's measured swims."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bauv_sim.errors import ConfigError
from bauv_sim.manoeuvring import model as mm
from bauv_sim.manoeuvring import trials


@pytest.fixture(scope="module")
def coef() -> mm.ManoeuvringCoefficients:
    return mm.load_coefficients()


def _free_body(c: mm.ManoeuvringCoefficients) -> mm.ManoeuvringCoefficients:
    """The same inertia with no fluid force, no tail, and buoyancy at the CG (no restoring)."""
    z = {
        "hull": np.zeros_like(c.hull),
        "fin_port": np.zeros_like(c.fin_port),
        "fin_starboard": np.zeros_like(c.fin_starboard),
        "tail": np.zeros_like(c.tail),
        "tail_straight": np.zeros_like(c.tail_straight),
        "thrust_speed_slope": 0.0,
        "buoyancy_n": c.weight_n,
        "cb_body_m": c.cg_body_m.copy(),
    }
    return mm.ManoeuvringCoefficients(**{**c.__dict__, **z})


def test_free_rigid_body_conserves_energy_and_momentum(coef):
    """With no external force the kinetic energy 1/2 nu^T M nu is constant (C_RB does no work)
    and so is the world-frame linear momentum of the rigid part without added mass; a tumbling
    body is the case. Independent truth: the conservation laws, not the code's output."""
    c = _free_body(coef)
    c = mm.ManoeuvringCoefficients(
        **{**c.__dict__, "mass_matrix": c.mass_matrix - _added_mass(c)}
    )  # rigid body only: momentum in the world frame is then conserved
    w = mm.ManoeuvringWorld(1, c, tick_s=0.05, substeps=10)
    w.set_pose(np.zeros(3), np.array([0.1, -0.2, 1.0]))
    w.nu_r[:] = [0.8, 0.2, -0.1, 0.6, -0.3, 0.4]
    M = c.mass_matrix

    def energy():
        return 0.5 * float(w.nu_r[0] @ M @ w.nu_r[0])

    def momentum():
        v, om = w.nu_r[0, :3], w.nu_r[0, 3:]
        p_body = c.rigid_mass_kg * (v + np.cross(om, c.cg_body_m))
        return w.R_world_from_body()[0] @ p_body

    e0, p0 = energy(), momentum()
    w.advance(10.0)
    assert energy() == pytest.approx(e0, rel=1e-6)
    np.testing.assert_allclose(momentum(), p0, atol=1e-5 * np.linalg.norm(p0))


def _added_mass(c: mm.ManoeuvringCoefficients) -> np.ndarray:
    m = c.rigid_mass_kg
    S = mm.skew(c.cg_body_m)
    MRB = np.block([[m * np.eye(3), -m * S], [m * S, c.inertia_origin_kg_m2]])
    return c.mass_matrix - MRB


def test_rigid_part_is_a_rigid_body(coef):
    """M_RB recovered from the stored split is symmetric positive definite with the CG the
    hydrostatics report: 57.5 kg (the mass budget), CG below the CB by BG = 48 mm."""
    MA = _added_mass(coef)
    np.testing.assert_allclose(MA, MA.T, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(coef.mass_matrix - MA) > 0)
    assert coef.rigid_mass_kg == pytest.approx(57.51, abs=0.01)
    assert coef.cb_body_m[2] - coef.cg_body_m[2] == pytest.approx(0.048, abs=0.001)
    assert coef.buoyancy_n == pytest.approx(coef.weight_n, rel=1e-6)


def test_uniform_current_moves_the_vehicle_with_the_water(coef):
    """In a uniform current the motion relative to the water is that of still water (bit for
    bit) and the ground track is displaced by current x time."""
    a = trials.start(coef, n=2)
    a.command(tail_beat_frequency_hz=0.61, tail_bias_rad=0.1)
    a.set_current_world(np.array([[0.0, 0.0, 0.0], [0.3, -0.2, 0.0]]))
    a.advance(30.0)
    np.testing.assert_array_equal(a.nu_r[0], a.nu_r[1])
    np.testing.assert_array_equal(a.euler_rad[0], a.euler_rad[1])
    shift = a.position_world_m[1] - a.position_world_m[0]
    np.testing.assert_allclose(shift, [0.3 * 30.0, -0.2 * 30.0, 0.0], atol=1e-9)


def test_batch_equals_single_runs(coef):
    """A batch of runs with different commands equals the same runs flown one at a time."""
    f = np.array([0.45, 0.61, 1.0])
    b = np.array([0.0, 0.2, -0.3])
    fin = np.array([0.1, -0.05, 0.0])
    batch = trials.start(coef, n=3)
    batch.command(f, b, fin, -fin, np.array([0.0, 0.02, -0.02]))
    batch.advance(20.0)
    for i in range(3):
        one = trials.start(coef, n=1)
        one.command(f[i], b[i], fin[i], -fin[i], [0.0, 0.02, -0.02][i])
        one.advance(20.0)
        np.testing.assert_allclose(one.nu_r[0], batch.nu_r[i], rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            one.position_world_m[0], batch.position_world_m[i], rtol=0, atol=1e-9
        )


def test_same_inputs_same_numbers(coef):
    runs = []
    for _ in range(2):
        w = trials.start(coef, n=4)
        w.command(0.7, np.linspace(-0.3, 0.3, 4), 0.05, 0.05)
        w.advance(10.0)
        runs.append(np.c_[w.position_world_m, w.euler_rad, w.nu_r])
    np.testing.assert_array_equal(runs[0], runs[1])


def test_straight_swim_matches_the_full_models_swims(coef):
    """At the identification's frequencies 0.45, 0.61, 0.8 Hz the steady swims of the model (one
    batch, depth held) reach the speed the full model swam (stored beside the tables in
    manoeuvring.json by the identification) within the timestep table's 1 %: the model's
    equilibrium is where the full model's was. (0.3 Hz is left out: its full swim had not
    settled after 30 s.)"""
    f = coef.power_frequency_hz[2:5]
    w = trials.start(coef, n=3, tick_s=0.2)
    w.command(tail_beat_frequency_hz=f)
    for _ in range(round(60.0 / w.tick_s)):
        a = trials.depth_hold(w, 20.0)
        w.command(fin_port_rad=a, fin_starboard_rad=a)
        w.step()
    u = np.linalg.norm(w.velocity_through_water_world(), axis=1)
    np.testing.assert_allclose(u, coef.straight_speed_m_s[2:5], rtol=0.01)


def test_tail_bias_turns_to_starboard_and_the_beat_shows_on_the_compass(coef):
    """Positive bias (tail to port) turns clockwise; the heading read by a compass oscillates at
    the beat frequency with the full model's amplitude, the beat-averaged heading does not."""
    rate, radius = trials.heading_change(coef, 0.61, math.radians(10.0), turn_s=30.0)
    assert rate > 0 and 3.0 < radius < 20.0
    w = trials.start(coef)
    w.command(tail_beat_frequency_hz=0.61)
    w.advance(20.0)
    heads, means = [], []
    for _ in range(round(1 / 0.61 / w.tick_s) * 3):
        w.step()
        heads.append(w.roll_pitch_heading()[0, 2])
        means.append(w.roll_pitch_heading(beat=False)[0, 2])
    amp = np.interp(0.61, coef.power_frequency_hz, coef.yaw_amplitude_rad)
    heads = np.unwrap(heads)
    assert 0.8 * 2 * amp < np.ptp(heads) <= 2 * amp + 1e-9
    assert np.ptp(np.unwrap(means)) < 0.1 * np.ptp(heads)


def test_bad_arguments_name_the_field(coef):
    with pytest.raises(ConfigError, match="n_runs"):
        mm.ManoeuvringWorld(0, coef)
    with pytest.raises(ConfigError, match="tick_s"):
        mm.ManoeuvringWorld(1, coef, tick_s=0.0)
    with pytest.raises(ConfigError, match="not found"):
        mm.load_coefficients("/nonexistent/manoeuvring.json")
