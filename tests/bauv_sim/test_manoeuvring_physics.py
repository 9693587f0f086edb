"""The manoeuvring model behind the missions' physics accessors
(bauv_sim.manoeuvring.physics.ManoeuvringPhysics, issue 27): its truth against the model's own
state and against finite differences of itself, its sites against MuJoCo's kinematics, the
current by Galilean invariance, and what it refuses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bauv_sim import frames
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.errors import ConfigError, PhysicsError
from bauv_sim.frames import quat_wxyz_from_roll_pitch_heading_scalar
from bauv_sim.manoeuvring.physics import ManoeuvringPhysics
from bauv_sim.physics_index import SENSOR_SITES


@pytest.fixture(scope="module")
def scene():
    return build_physics(SceneConfig(), control_tick_s=0.2, timestep_s=0.004)


def _flying(scene, tick_s: float = 0.2, seconds: float = 20.0) -> ManoeuvringPhysics:
    """A vehicle at 5 m, heading 30 deg, swimming at 1.6 Hz with some bias, fins and trim."""
    p = ManoeuvringPhysics(scene, tick_s)
    p.set_pose([10.0, -20.0, -5.0], [0.0, 0.0, math.radians(30.0)], [0.5, 0.8, 0.0])
    p.set_tail_beat_frequency_hz(1.6)
    p.set_tail_bias_rad(0.1)
    p.set_lateral_fins_rad(0.05, 0.03)
    p.set_battery_position_m(0.01)
    p.step(round(seconds / tick_s))
    return p


def test_truth_is_the_models_state_with_the_beat(scene):
    """Position, depth, velocities and the water are the model's state; the attitude is the
    beat-averaged Euler angles plus the beat's heading and roll term at its phase, computed here
    from the coefficients' amplitude tables; the quaternion is the same attitude."""
    p = _flying(scene)
    w, c = p.world, p.world.c
    vt = p.truth()
    assert vt.t_s == pytest.approx(20.0)
    np.testing.assert_array_equal(vt.position_world_m, w.position_world_m[0])
    assert vt.depth_m == -w.position_world_m[0, 2]
    roll, theta, yaw = w.euler_rad[0]
    cr, sr, ct, st, cy, sy = (math.cos(roll), math.sin(roll), math.cos(theta),
                              math.sin(theta), math.cos(yaw), math.sin(yaw))  # fmt: skip
    R = np.array(
        [
            [cy * ct, cy * st * sr - sy * cr, cy * st * cr + sy * sr],
            [sy * ct, sy * st * sr + cy * cr, sy * st * cr - cy * sr],
            [-st, ct * sr, ct * cr],
        ]
    )
    np.testing.assert_allclose(vt.velocity_through_water_world_m_s, R @ w.nu_r[0, :3], atol=1e-12)
    np.testing.assert_allclose(vt.velocity_world_m_s, vt.velocity_through_water_world_m_s)
    f, ph = 1.6, w.beat_phase_rad[0]
    ay = np.interp(f, c.power_frequency_hz, c.yaw_amplitude_rad)
    ar = np.interp(f, c.power_frequency_hz, c.roll_amplitude_rad)
    assert ay > 0 and ar > 0  # the beat term is there
    head = (math.pi / 2 - yaw + ay * math.sin(ph)) % (2 * math.pi)
    np.testing.assert_allclose(
        vt.roll_pitch_heading_rad,
        [roll + ar * math.sin(ph + c.roll_phase_rad), -theta, head],
        atol=1e-12,
    )
    np.testing.assert_allclose(
        frames.roll_pitch_heading_from_R(frames.R_from_quat_wxyz(vt.quat_wxyz)),
        vt.roll_pitch_heading_rad,
        atol=1e-9,
    )
    om = 2 * math.pi * f
    np.testing.assert_allclose(
        vt.angular_velocity_body_rad_s,
        w.nu_r[0, 3:] + [ar * om * math.cos(ph + c.roll_phase_rad), 0.0, -ay * om * math.cos(ph)],
        atol=1e-12,
    )


def test_truth_rates_are_the_derivatives_of_its_attitude_and_position(scene):
    """Finite differences over 5 ms ticks: the heading's and roll's change is the angular
    velocity's navigation rates (beat included), the position's change is the velocity over
    ground (in a current)."""
    p = _flying(scene, tick_s=0.005, seconds=5.0)
    p.set_water_world(np.array([0.2, -0.1, 0.0]))
    a = p.truth()
    p.step()
    b = p.truth()
    p.step()
    c = p.truth()
    h = 0.005
    rates = frames.navigation_rates_from_body(b.angular_velocity_body_rad_s)
    d_rph = (c.roll_pitch_heading_rad - a.roll_pitch_heading_rad) / (2 * h)
    np.testing.assert_allclose([d_rph[0], d_rph[2]], [rates[0], rates[2]], rtol=0.02, atol=2e-3)
    np.testing.assert_allclose(
        (c.position_world_m - a.position_world_m) / (2 * h), b.velocity_world_m_s, atol=2e-3
    )


def test_sites_are_the_vehicle_models(scene):
    """Every sensor site of the facade is MuJoCo's own site for the same pose (beat off: tail
    frequency 0), from MuJoCo's kinematics."""
    pos, rph = np.array([3.0, 4.0, -6.0]), np.array([0.05, -0.1, 1.2])
    p = ManoeuvringPhysics(scene, 0.2)
    p.set_pose(pos, rph)
    full = build_physics(SceneConfig(), control_tick_s=0.2, timestep_s=0.004)
    full.set_pose(pos, rph)
    for s in SENSOR_SITES:
        np.testing.assert_allclose(p.site_position_world(s), full.site_position_world(s), atol=1e-9)
    np.testing.assert_allclose(p.transceiver_world(), full.transceiver_world())
    with pytest.raises(ConfigError, match="not a sensor site"):
        p.site_position_world("nose_cone")


def test_a_steady_current_carries_the_vehicle_and_changes_nothing_else(scene):
    """Galilean invariance: the same swim with and without a uniform current differs by the
    current times the time in position, and not at all in attitude or velocity through water."""
    runs = []
    for cur in (np.zeros(3), np.array([0.3, -0.2, 0.0])):
        p = ManoeuvringPhysics(scene, 0.2)
        p.set_pose([0.0, 0.0, -5.0], [0.0, 0.0, 0.3], [0.9, 0.2, 0.0])
        p.set_water_world(cur)
        p.set_pose([0.0, 0.0, -5.0], [0.0, 0.0, 0.3], np.array([0.9, 0.2, 0.0]) + cur)
        p.set_tail_beat_frequency_hz(1.5)
        p.set_tail_bias_rad(-0.15)
        p.step(150)
        runs.append(p.truth())
    still, moving = runs
    np.testing.assert_allclose(
        moving.position_world_m - still.position_world_m, [0.3 * 30, -0.2 * 30, 0.0], atol=1e-9
    )
    np.testing.assert_allclose(moving.roll_pitch_heading_rad, still.roll_pitch_heading_rad)
    np.testing.assert_allclose(
        moving.velocity_through_water_world_m_s, still.velocity_through_water_world_m_s
    )
    np.testing.assert_allclose(moving.current_world_m_s, [0.3, -0.2, 0.0])


def test_bad_commands_and_what_the_model_lacks_are_refused(scene):
    p = ManoeuvringPhysics(scene, 0.2)
    with pytest.raises(ConfigError, match=r"tail-beat frequency = 9 Hz: must be within \[0, "):
        p.set_tail_beat_frequency_hz(9.0)
    with pytest.raises(ConfigError, match="port fin angle = nan rad"):
        p.set_lateral_fins_rad(float("nan"), 0.0)
    with pytest.raises(ConfigError, match="tail bias"):
        p.set_tail_bias_rad(1.2)
    with pytest.raises(ConfigError, match="vehicle 'follower'"):
        p.truth("follower")
    with pytest.raises(ConfigError, match="water velocity"):
        p.set_water_world([0.0, float("inf"), 0.0])
    p.set_pose([0.0, 0.0, -0.05], [0.0, 0.0, 0.0])
    with pytest.raises(PhysicsError, match="no free surface"):
        p.set_buoyancy_scale(0.7)
    p.set_buoyancy_scale(1.0)
    p.inject_fault()
    with pytest.raises(PhysicsError, match="non-finite state"):
        p.step()
    two = build_physics(
        SceneConfig(vehicles=(VehicleSpec(name="leader"), VehicleSpec(name="follower", east_m=5))),
        control_tick_s=0.2,
    )
    with pytest.raises(ConfigError, match="holds one vehicle; the scene has 2"):
        ManoeuvringPhysics(two, 0.2)


def test_scalar_quaternion_is_the_frames_one():
    """The facade's scalar quaternion equals :mod:`bauv_sim.frames`' (through the rotation
    matrix and scipy), w >= 0, over random attitudes, near-vertical pitch included."""
    rng = np.random.default_rng(5)
    for roll, pitch, head in zip(
        rng.uniform(-math.pi, math.pi, 200),
        np.r_[rng.uniform(-1.5, 1.5, 198), 1.5707, -1.5707],
        rng.uniform(0, 2 * math.pi, 200),
        strict=True,
    ):
        np.testing.assert_allclose(
            quat_wxyz_from_roll_pitch_heading_scalar(roll, pitch, head),
            frames.quat_wxyz_from_roll_pitch_heading(roll, pitch, head),
            atol=1e-12,
        )


def test_advance_applies_the_sea_at_every_tick(scene):
    """:meth:`advance` runs the tick hook a sea installs (as the full facade's), so tools that
    drive the full physics by ticks in a sea (e.g. the autopilot trials) fly the model too. A
    current growing linearly in time, w = (0, 0.1 t, 0) m/s, carries a vehicle at rest in the
    water by its integral, 0.1 t^2 / 2 north (the sea's ramp over each tick integrated at its
    mid value: exact), and the truth's water is the one at the start of the last tick."""
    from bauv_sim.sea import Sea

    class Ramp:
        def velocity_world(self, t_s, position_world_m):
            return np.array([0.0, 0.1 * t_s, 0.0])

    p = ManoeuvringPhysics(scene, 0.2)
    p.set_pose([0.0, 0.0, -5.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    Sea(Ramp()).immerse(p)
    p.advance(4.0)
    np.testing.assert_allclose(p.current_at_vehicle_world(), [0.0, 0.1 * 3.8, 0.0], atol=1e-12)
    # at rest in the water: carried with it (it sinks or rises a little: trim only)
    np.testing.assert_allclose(p.position_world()[:2], [0.0, 0.1 * 4.0**2 / 2], atol=0.02)
    with pytest.raises(ConfigError, match="whole number of control ticks"):
        p.advance(0.3)
