"""The team's kinematic truth (bauv_sim.kinematic.team) against its geometry worked out here:
the racetrack's legs and half circles, the stations in the leader's frame, the current, the
distinct depths and the refusals."""

import math

import numpy as np
import pytest

from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.team import (
    LeaderTrackConfig,
    TeamConfig,
    racetrack,
    team_truth,
)


@pytest.mark.parametrize("turn", ["right", "left"])
@pytest.mark.parametrize("course_deg", [0.0, 30.0])
def test_racetrack_geometry(turn, course_deg):
    """Straight legs along the first course and back, half circles of the radius about centres
    found from the corners (built here with plain trigonometry), one lap back to the start."""
    L, R, V = 200.0, 50.0, 2.0
    tr = LeaderTrackConfig(
        speed_m_s=V,
        leg_m=L,
        turn_radius_m=R,
        initial_course_deg=course_deg,
        turn=turn,
        start_east_m=10.0,
        start_north_m=-5.0,
    )
    lap = 2 * L + 2 * math.pi * R
    t = np.linspace(0.0, lap / V, 2001)
    pos, course = racetrack(tr, t)
    h = math.radians(course_deg)
    fwd = np.array([math.sin(h), math.cos(h)])
    sgn = 1 if turn == "right" else -1
    right = np.array([math.cos(h), -math.sin(h)])  # 90 deg clockwise of fwd
    side = sgn * right
    start = np.array([10.0, -5.0])
    s = V * t
    leg1 = s <= L
    np.testing.assert_allclose(pos[leg1], start + s[leg1, None] * fwd, atol=1e-9)
    turn1 = (s > L) & (s < L + math.pi * R)
    centre1 = start + L * fwd + R * side
    np.testing.assert_allclose(np.linalg.norm(pos[turn1] - centre1, axis=1), R, rtol=1e-12)
    leg2 = (s > L + math.pi * R) & (s < 2 * L + math.pi * R)
    # the return leg: 2 R to the turn's side, heading the other way
    back = start + 2 * R * side + (L - (s[leg2] - L - math.pi * R))[:, None] * fwd
    np.testing.assert_allclose(pos[leg2], back, atol=1e-9)
    np.testing.assert_allclose(np.cos(course[leg2] - h), -1.0, atol=1e-12)
    turn2 = s > 2 * L + math.pi * R
    centre2 = start + R * side
    np.testing.assert_allclose(np.linalg.norm(pos[turn2] - centre2, axis=1), R, rtol=1e-12)
    np.testing.assert_allclose(pos[-1], start, atol=1e-9)
    # the course is the direction of motion (finite differences on a fine grid)
    seg = np.searchsorted([L, L + math.pi * R, 2 * L + math.pi * R], s)
    same = seg[1:] == seg[:-1]  # steps within one leg or one turn
    d = np.diff(pos, axis=0)[same]
    mid = np.arctan2(d[:, 0], d[:, 1])
    cmid = (course[:-1] + 0.5 * np.angle(np.exp(1j * (course[1:] - course[:-1]))))[same]
    assert np.abs(np.angle(np.exp(1j * (mid - cmid)))).max() < 1e-9


def test_stations_in_the_leaders_frame():
    """Each follower's offset from the leader, resolved on the leader's course axes, is its
    station plus the Lissajous wander, at every sample; depths as configured."""
    cfg = TeamConfig()
    truth = team_truth(cfg)
    t = truth.t_s
    p = truth.positions_world_m[:, 0]
    _, course = racetrack(cfg.leader, t)
    fwd = np.stack([np.sin(course), np.cos(course)], axis=-1)
    stbd = np.stack([np.cos(course), -np.sin(course)], axis=-1)
    for i, f in enumerate(cfg.followers, start=1):
        rel = p[i, :, :2] - p[0, :, :2]
        w = 2 * math.pi / f.wander_period_s
        ph = math.radians(f.phase_deg)
        along = f.along_m + f.wander_m * np.sin(w * t + ph)
        across = f.starboard_m + f.wander_m * np.sin(0.5 * w * t + ph)
        np.testing.assert_allclose(np.sum(rel * fwd, axis=1), along, atol=1e-9)
        np.testing.assert_allclose(np.sum(rel * stbd, axis=1), across, atol=1e-9)
        np.testing.assert_array_equal(truth.vehicles[i].depth_m[0], f.depth_m)
    np.testing.assert_array_equal(truth.vehicles[0].depth_m[0], cfg.leader.depth_m)
    assert truth.names == ("leader", "f1", "f2", "f3")


def test_truth_records_are_consistent():
    """Steps over ground integrate the velocity; through the water = over ground minus the
    current; the heading points along the velocity through the water (no sideslip)."""
    cfg = TeamConfig(current_east_m_s=0.1, current_north_m_s=-0.05)
    truth = team_truth(cfg)
    for tr in truth.vehicles:
        step = np.diff(tr.pos_world_m[0], axis=0)
        np.testing.assert_allclose(step, cfg.tick_s * tr.vel_ground_world_m_s[0, :-1], atol=1e-12)
        np.testing.assert_allclose(
            tr.vel_ground_world_m_s - tr.vel_water_world_m_s,
            np.broadcast_to([0.1, -0.05, 0.0], tr.current_world_m_s.shape),
            atol=1e-15,
        )
        vw = tr.vel_water_world_m_s[0, :, :2]
        u = np.stack([np.sin(tr.heading_rad[0]), np.cos(tr.heading_rad[0])], axis=-1)
        cross = u[:, 0] * vw[:, 1] - u[:, 1] * vw[:, 0]
        assert np.abs(cross).max() < 1e-12 and (np.sum(u * vw, axis=1) > 0).all()
    assert truth.positions_world_m.shape == (4, 1, cfg.n_ticks, 3)
    assert truth.min_separation_m() > 20.0


def test_refusals():
    def refused(match, *overrides):
        with pytest.raises(ConfigError, match=match) as e:
            load_config(TeamConfig, overrides=list(overrides))
        assert "\n" not in str(e.value)

    refused(
        r"followers\[1\].depth_m = 10: another vehicle",
        'followers=[{name="a", along_m=0, starboard_m=10, depth_m=10},'
        ' {name="b", along_m=0, starboard_m=-10, depth_m=10}]',
    )
    refused(
        r"followers\[0\].depth_m = 5: another",
        'followers=[{name="a", along_m=0, starboard_m=10, depth_m=5}]',
    )
    refused(
        "'leader' appears twice", 'followers=[{name="leader", along_m=0, starboard_m=5, depth_m=9}]'
    )
    refused("duration_s = 10.1: must be a whole multiple", "duration_s=10.1")
