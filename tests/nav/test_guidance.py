"""Way-point guidance drives a point vehicle through a mission, surfacing where asked."""

import math

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.guidance import Waypoint, WaypointGuidance, direct_course


def _fly(g, start, dt=0.5, t_end=3000.0, speed_gain=1.0):
    """A point vehicle that turns instantly and changes depth at 0.3 m/s."""
    p = np.array(start, dtype=float)
    modes, t = [], 0.0
    closest = [math.inf] * len(g.waypoints)
    while t < t_end and not g.done:
        cmd = g.step(t, p)
        modes.append(cmd.mode)
        if cmd.mode == "surface" and t % 1.0 == 0:
            g.gps_fix()
        v = speed_gain * cmd.speed_m_s
        p[0] += dt * v * math.sin(cmd.course_rad)
        p[1] += dt * v * math.cos(cmd.course_rad)
        dz = np.clip(-cmd.depth_m - p[2], -0.3 * dt, 0.3 * dt)
        p[2] += dz
        for i, wp in enumerate(g.waypoints):
            closest[i] = min(closest[i], math.hypot(wp.east_m - p[0], wp.north_m - p[1]))
        t += dt
    return modes, closest


def test_direct_course_cardinal():
    wp = Waypoint(10.0, 0.0, 5.0)
    assert direct_course(np.zeros(3), wp) == pytest.approx(math.pi / 2)
    assert direct_course(np.array([0.0, 10.0, 0]), Waypoint(0.0, 0.0, 5.0)) == pytest.approx(
        math.pi
    )


def test_mission_with_a_surfacing():
    wps = [Waypoint(100, 0, 5, 3), Waypoint(100, 100, 8, 3, surface=True), Waypoint(0, 100, 5, 3)]
    g = WaypointGuidance(wps, speed_m_s=1.0, hold_s=5.0, fixes_needed=2)
    modes, closest = _fly(g, [0, 0, -5])
    assert g.done and all(leg.reached for leg in g.legs) and len(g.legs) == 3
    assert max(closest) <= 3.0
    order = [m for i, m in enumerate(modes) if i == 0 or modes[i - 1] != m]
    assert order == ["transit", "ascend", "surface", "dive", "transit", "done"]


def test_unreachable_leg_times_out_as_missed():
    g = WaypointGuidance([Waypoint(100, 0, 5, 1.0)], speed_m_s=1.0, max_leg_time_s=20.0)
    _fly(g, [0, 0, -5])
    assert g.done and g.legs[0].reached is False


def test_bad_waypoints():
    with pytest.raises(NavInputError, match="at least one"):
        WaypointGuidance([])
    with pytest.raises(NavInputError, match=r"waypoints\[0\]"):
        WaypointGuidance([Waypoint(0, 0, 5, acceptance_radius_m=0.0)])


def test_reach_test_is_the_probability_that_the_truth_is_inside():
    from scipy.stats import rice

    g = WaypointGuidance([Waypoint(0.0, 0.0, 3.0, acceptance_radius_m=10.0)])
    # by Monte Carlo: estimate 5 m from the way-point, sigma 2 m
    rng = np.random.default_rng(0)
    truth = np.array([5.0, 0.0]) + 2.0 * rng.standard_normal((200_000, 2))
    p_in = np.mean(np.hypot(truth[:, 0], truth[:, 1]) <= 10.0)
    assert rice.cdf(10.0, 5.0 / 2.0, scale=2.0) == pytest.approx(p_in, abs=0.003)
    assert g.reached(5.0, 10.0, 2.0) == (p_in >= 0.95)
    assert not g.reached(8.0, 10.0, 2.0) and g.reached(4.0, 10.0, 2.0)
    assert g.reached(9.9, 10.0, 0.0) and not g.reached(10.1, 10.0, 0.0)
    # sigma so large that even d = 0 gives less than 95 %: pass within min_reach_m
    assert not g.reached(2.0, 10.0, 5.0) and g.reached(0.9, 10.0, 5.0)
