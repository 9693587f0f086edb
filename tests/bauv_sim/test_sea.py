"""The sea coupled to the physics: the current at every vehicle (the model's water velocity, held
corrections for vehicles in other water), Galilean invariance, the free surface, injection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bauv_sim import build, currents
from bauv_sim.physics import BauvPhysics
from bauv_sim.sea import HULL_HALF_HEIGHT_M, Sea, submerged_fraction


@pytest.fixture
def phys() -> BauvPhysics:
    return BauvPhysics.from_scene_xml()


def test_the_sea_is_held_until_it_is_applied_again(phys):
    """What a dm_control environment that steps the physics itself relies on: the sea applied in
    ``before_step`` holds through the steps."""
    phys.set_sea(Sea(currents.GyreCurrent((0.0, 0.0), 10.0, 0.3)))
    phys.set_pose([10.0, 0.0, -3.0])
    first = phys.current_at_vehicle_world()
    phys.set_pose([0.0, 10.0, -3.0])
    phys.step(5)
    assert np.allclose(phys.current_at_vehicle_world(), first)  # held until applied again
    phys.apply_sea()
    assert np.allclose(phys.current_at_vehicle_world(), [0.3, 0.0, 0.0], atol=1e-12)


def test_current_is_applied_and_velocity_through_water_is_ground_minus_current(phys):
    field = currents.UniformCurrent(0.5, math.radians(30))
    phys.set_sea(Sea(field))
    assert phys.sea.current is field
    cur = field.velocity_world(0.0, np.zeros(3))
    assert np.allclose(phys.current_at_vehicle_world(), cur)
    assert np.allclose(phys.model.opt.wind, cur)
    phys.set_pose([0, 0, -3], [0, 0, 0], cur)  # moving with the water
    phys.advance(1.0)
    assert np.allclose(phys.velocity_world(), cur, atol=1e-6)
    assert np.allclose(
        phys.velocity_through_water_world(), phys.velocity_world() - phys.current_at_vehicle_world()
    )
    assert phys.truth().current_world_m_s == pytest.approx(cur)


def test_a_new_sea_replaces_a_steady_one_at_once(phys):
    """A steady uniform current is written once per injection, not at every tick: injecting another
    sea writes the water anew."""
    a = currents.UniformCurrent(0.5, 0.0)
    phys.set_sea(Sea(a))
    phys.advance(0.2)
    assert np.allclose(phys.model.opt.wind, [0.0, 0.5, 0.0])
    phys.set_sea(Sea(currents.UniformCurrent(0.2, math.pi / 2)))
    assert np.allclose(phys.model.opt.wind, [0.2, 0.0, 0.0])
    assert np.allclose(phys.current_at_vehicle_world(), [0.2, 0.0, 0.0])
    phys.set_sea(Sea())
    phys.advance(0.1)
    assert np.array_equal(phys.model.opt.wind, np.zeros(3))
    assert np.array_equal(phys.truth().current_world_m_s, np.zeros(3))


def test_each_vehicle_feels_the_current_at_its_own_position():
    """Two vehicles in a gyre: the fluid force on each equals the force on a lone vehicle in the
    same state whose water has that vehicle's current (MuJoCo's water is the first vehicle's; the
    plugin applies the change of MuJoCo's drag in the second's own water at every step)."""
    gyre = currents.GyreCurrent((0.0, 0.0), 50.0, 0.4)
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(name="a", east_m=60.0, depth_m=3.0),
            build.VehicleSpec(
                name="b", east_m=-40.0, north_m=10.0, depth_m=3.0, heading_deg=40.0, speed_m_s=0.8
            ),
        )
    )
    two = build.build_physics(cfg)
    two.set_sea(Sea(gyre))
    ca, cb = two.current_at_vehicle_world("a"), two.current_at_vehicle_world("b")
    assert not np.allclose(ca, cb)
    total_b = two.fluid_force_world("b")
    ab = two.water_acceleration_world("b")
    assert np.any(ab != 0.0)  # b moves through the gyre: its water changes over the tick
    lone = BauvPhysics.from_scene_xml()
    lone.set_pose([-40.0, 10.0, -3.0], [0.0, 0.0, math.radians(40.0)], two.velocity_world("b"))
    lone.set_water_world(cb, ab)
    assert np.allclose(lone.fluid_force_world(), total_b, rtol=1e-9, atol=1e-12)


def test_drag_depends_only_on_the_velocity_through_water(phys):
    phys.set_pose([0, 0, -3], [0.1, -0.05, 0.3], [0.3, 0.9, 0.05])
    still = phys.fluid_force_world()
    c = np.array([0.4, -0.2, 0.0])
    phys.set_sea(Sea(currents.UniformCurrent(float(np.hypot(*c[:2])), math.atan2(c[0], c[1]))))
    phys.set_pose([0, 0, -3], [0.1, -0.05, 0.3], [0.3 + c[0], 0.9 + c[1], 0.05])
    assert np.allclose(phys.fluid_force_world(), still, rtol=1e-9, atol=1e-12)


def test_free_surface_buoyancy_fraction_and_motion():
    """Above the surface the hull loses its buoyancy: the submerged fraction follows the area of
    an elliptic section, a vehicle released in the air falls back, and one deep stays put."""
    p = build.build_physics()
    h = HULL_HALF_HEIGHT_M
    for depth, want in [
        (1.0, 1.0),
        (h, 1.0),
        (0.0, 0.5),
        (-h, 0.0),
        (-1.0, 0.0),
        (0.5 * h, 0.5 + (0.5 * math.sqrt(0.75) + math.asin(0.5)) / math.pi),
    ]:
        assert submerged_fraction(depth) == pytest.approx(want, abs=1e-12)
        p.set_pose([0.0, 0.0, -depth])
        p.apply_sea()
        assert p.buoyancy_scale() == pytest.approx(want, abs=1e-12)
    # released 0.5 m above the surface, still water, no commands: it falls into the water
    p.set_pose([0.0, 0.0, 0.5])
    p.advance(2.0)
    assert p.depth_m() > -0.2
    # released at 2 m depth it is neutral: it stays within a few millimetres
    p.set_pose([0.0, 0.0, -2.0])
    p.advance(2.0)
    assert p.depth_m() == pytest.approx(2.0, abs=0.02)
    assert p.buoyancy_scale() == 1.0
