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
    sea = Sea(currents.GyreCurrent((0.0, 0.0), 10.0, 0.3))
    sea.immerse(phys)
    phys.set_pose([10.0, 0.0, -3.0])
    first = phys.current_at_vehicle_world()
    phys.set_pose([0.0, 10.0, -3.0])
    phys.step(5)
    assert np.allclose(phys.current_at_vehicle_world(), first)  # held until applied again
    sea.apply(phys)
    assert np.allclose(phys.current_at_vehicle_world(), [0.3, 0.0, 0.0], atol=1e-12)


def test_current_is_applied_and_velocity_through_water_is_ground_minus_current(phys):
    field = currents.UniformCurrent(0.5, math.radians(30))
    sea = Sea(field)
    sea.immerse(phys)
    assert sea.current is field
    assert phys.tick_hook == sea.apply  # advance applies it at every tick
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
    Sea(a).immerse(phys)
    phys.advance(0.2)
    assert np.allclose(phys.model.opt.wind, [0.0, 0.5, 0.0])
    Sea(currents.UniformCurrent(0.2, math.pi / 2)).immerse(phys)
    assert np.allclose(phys.model.opt.wind, [0.2, 0.0, 0.0])
    assert np.allclose(phys.current_at_vehicle_world(), [0.2, 0.0, 0.0])
    Sea().immerse(phys)
    phys.advance(0.1)
    assert np.array_equal(phys.model.opt.wind, np.zeros(3))
    assert np.array_equal(phys.truth().current_world_m_s, np.zeros(3))


def test_a_steady_sea_is_written_once_per_immersion_and_again_after_a_reload(phys):
    """A steady uniform current is written when the sea is put around the vehicles and left as
    it is at the following ticks; a reload of the model (the plugin's water back to still) has
    it written again at the next tick."""
    sea = Sea(currents.UniformCurrent(0.5, 0.0))
    sea.immerse(phys)
    assert np.allclose(phys.current_at_vehicle_world(), [0.0, 0.5, 0.0], atol=1e-15)
    phys.set_water_world([0.25, 0.0, 0.0])  # by hand: a steady sea leaves it at its ticks
    phys.advance(0.1)
    assert np.array_equal(phys.current_at_vehicle_world(), [0.25, 0.0, 0.0])
    from bauv_sim.hull import MODEL_DIR

    phys.reload_from_xml_path(str(MODEL_DIR / "scene.xml"))
    assert np.array_equal(phys.current_at_vehicle_world(), np.zeros(3))
    phys.advance(0.1)
    assert np.allclose(phys.current_at_vehicle_world(), [0.0, 0.5, 0.0], atol=1e-15)
    assert np.allclose(phys.model.opt.wind, [0.0, 0.5, 0.0], atol=1e-15)
    sea.immerse(phys)  # a new immersion writes it anew
    assert np.allclose(phys.current_at_vehicle_world(), [0.0, 0.5, 0.0], atol=1e-15)


def test_without_a_sea_the_physics_keeps_the_water_and_the_buoyancy_it_was_given():
    """The physics owns no sea (issue 22): a fresh physics advanced with no sea put around it
    keeps still water and full buoyancy, even above the surface, until a sea is applied."""
    p = build.build_physics()
    p.set_pose([0.0, 0.0, 0.5])
    p.advance(0.1)
    assert p.buoyancy_scale() == 1.0
    assert np.array_equal(p.current_at_vehicle_world(), np.zeros(3))
    Sea().apply(p)
    assert p.buoyancy_scale() == 0.0


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
    Sea(gyre).immerse(two)
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
    Sea(currents.UniformCurrent(float(np.hypot(*c[:2])), math.atan2(c[0], c[1]))).immerse(phys)
    phys.set_pose([0, 0, -3], [0.1, -0.05, 0.3], [0.3 + c[0], 0.9 + c[1], 0.05])
    assert np.allclose(phys.fluid_force_world(), still, rtol=1e-9, atol=1e-12)


def test_free_surface_buoyancy_fraction_and_motion():
    """Above the surface the hull loses its buoyancy: the submerged fraction follows the area of
    an elliptic section, a vehicle released in the air falls back, and one deep stays put."""
    p = build.build_physics()
    sea = Sea()
    sea.immerse(p)
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
        sea.apply(p)
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


# ------------------------------------------------------------------------------------------
# a sea put around the vehicles (Sea.immerse) carries them with the water (issue 21)


def _swim(sea_at: dict[float, Sea], seconds: float, heading_deg: float = 0.0, f: float = 0.84):
    """A vehicle swimming at a fixed tail-beat frequency from 1 m/s through the water (depth held
    by the fins), seas injected at given times; its position over ground and its velocity through
    the water at every tick."""
    from bauv_sim import manoeuvres

    p = manoeuvres.open_water_scene(heading_deg=heading_deg, speed_m_s=1.0)
    hold = manoeuvres.DepthHold(p.depth_m())
    p.set_tail_beat_frequency_hz(f)
    pos, through = [], []
    for k in range(round(seconds / p.control_tick_s)):
        if k * p.control_tick_s in sea_at:
            sea_at[k * p.control_tick_s].immerse(p)
        a = hold.fins_rad(p)
        p.set_lateral_fins_rad(a, a)
        p.advance(p.control_tick_s)
        pos.append(p.position_world())
        through.append(p.velocity_through_water_world())
    return np.array(pos), np.array(through), p


@pytest.mark.slow
@pytest.mark.parametrize("direction_deg", [0.0, 90.0])
def test_an_idle_vehicle_follows_a_step_of_a_steady_uniform_current(direction_deg):
    """Galilean invariance: a neutrally buoyant vehicle at rest in water whose velocity changes as
    a whole moves with the water (Froude-Krylov and added-mass reaction): seen from the water it
    stays exactly as the same vehicle in still water does. Before issue 21 the step gave no push:
    0.004 (along the heading) and 0.089 (across) of a 0.3 m/s step after 0.2 s, 0.019 and 0.317
    after 1 s."""
    from bauv_sim import manoeuvres

    c = currents.UniformCurrent(0.3, math.radians(direction_deg))
    w = c.velocity_world(0.0, np.zeros(3))
    idle, still = manoeuvres.open_water_scene(), manoeuvres.open_water_scene()
    for p in (idle, still):
        p.advance(0.5)
    Sea(c).immerse(idle)
    for k in range(10):
        idle.advance(0.1)
        still.advance(0.1)
        assert np.allclose(idle.velocity_through_water_world(), still.velocity_world(), atol=1e-9)
        if k == 1:  # 0.2 s after the step: the fraction of the step reached
            assert idle.velocity_world() @ w / (w @ w) == pytest.approx(1.0, abs=1e-3)
    assert np.allclose(idle.position_world() - w * 1.0, still.position_world(), atol=1e-9)


@pytest.mark.slow
def test_a_vehicle_put_in_a_current_starts_moving_with_the_water():
    """A vehicle placed at 1 m/s along its heading and put in a 0.3 m/s cross current swims, over
    ground, the still-water track plus the drift (issue 21: it lagged 2.66 m behind the drifted
    track after 60 s, 5.38 m in 2 m/s)."""
    w = np.array([0.3, 0.0, 0.0])
    still, _, _ = _swim({}, 60.0)
    cur, _, p = _swim({0.0: Sea(currents.UniformCurrent(0.3, math.pi / 2))}, 60.0)
    assert np.allclose(p.current_at_vehicle_world(), w)
    t = p.control_tick_s * np.arange(1, len(still) + 1)
    assert np.allclose(cur, still + t[:, None] * w, atol=1e-6)


@pytest.mark.slow
def test_the_log_keeps_reading_speed_through_water_after_an_along_track_switch():
    """A steady uniform current injected along the track during a swim changes nothing relative
    to the water (the log read 0.72 m/s at 1 m/s before issue 21, recovering over 5 s)."""
    _, through_still, _ = _swim({}, 15.0)
    _, through, _ = _swim({10.0: Sea(currents.UniformCurrent(0.3, 0.0))}, 15.0)
    assert np.allclose(through, through_still, atol=1e-9)


def test_immerse_carries_each_vehicle_by_the_water_at_it():
    """Two vehicles in a gyre: each one's velocity over ground changes by its own water's velocity
    (its velocity through the water, angular velocity and joints are kept)."""
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(name="a", east_m=60.0, depth_m=3.0, speed_m_s=0.5),
            build.VehicleSpec(name="b", east_m=-40.0, north_m=10.0, depth_m=3.0, heading_deg=40.0),
        )
    )
    two = build.build_physics(cfg)
    before = {n: two.velocity_world(n) for n in "ab"}
    joints = np.array(two.data.qvel[6:]), np.array(two.data.qpos)
    gyre = currents.GyreCurrent((0.0, 0.0), 50.0, 0.4)
    Sea(gyre).immerse(two)
    for n in "ab":
        w = gyre.velocity_world(0.0, two.position_world(n))
        assert np.allclose(two.current_at_vehicle_world(n), w)
        assert np.allclose(two.velocity_world(n), before[n] + w, atol=1e-12)
        assert np.allclose(two.velocity_through_water_world(n), before[n], atol=1e-12)
    assert np.array_equal(two.data.qpos, joints[1])
    # a second injection of the same sea carries nothing
    again = {n: two.velocity_world(n) for n in "ab"}
    Sea(gyre).immerse(two)
    for n in "ab":
        assert np.array_equal(two.velocity_world(n), again[n])


def test_a_mission_vehicle_starts_at_its_speed_through_the_water_plus_the_current():
    """The mission world places the vehicle at its start speed along its heading and then puts it
    in the mission's sea: over ground it starts with the current added."""
    from tasks.closed_loop.world import WaypointMission, build_environment
    from tasks.core.runner import plan_batch

    scn = plan_batch(
        "mission/short",
        overrides=["current.speed_m_s=0.3", "current.direction_deg=90", "start.heading_deg=0"],
    ).scenario
    env = build_environment(WaypointMission(), scn, 0, 0)
    env.reset()
    p = env.physics
    heading = p.heading_rad()
    want = scn.start.speed_m_s * np.array([math.sin(heading), math.cos(heading), 0.0])
    assert np.allclose(p.current_at_vehicle_world(), [0.3, 0.0, 0.0], atol=1e-12)
    assert np.allclose(p.velocity_world(), want + [0.3, 0.0, 0.0], atol=1e-12)
    assert np.allclose(p.velocity_through_water_world(), want, atol=1e-12)
