"""Seed 003's kinematic world: the square and the formation against geometry worked out here, and
the measurement errors against the distributions the paper states (uniform on +-sigma at 10 Hz,
sector bias by the true course, speed and range biases), with bands of the right sample size."""

import math

import numpy as np
import pytest

from bauv_sim.config import ConfigError, load_config
from bauv_sim.kinematic import seed003 as kin


def u(deg):
    c = math.radians(deg)
    return np.array([math.sin(c), math.cos(c)])


def cfg(model, **data):
    return load_config(model, data)


def test_leader_flies_one_square_turning_right_from_45_deg():
    path = cfg(kin.SquarePathConfig)
    tr = kin.square_truth(path, cfg(kin.FormationConfig))
    assert tr.leader_m.shape == (4801, 2) and tr.t_s[-1] == pytest.approx(480.0)
    corners = [np.zeros(2)]
    for c in (45, 135, 225, 315):
        corners.append(corners[-1] + 120.0 * u(c))
    for j, p in enumerate(corners):
        np.testing.assert_allclose(tr.leader_m[1200 * j], p, atol=1e-9)
    np.testing.assert_allclose(corners[-1], 0.0, atol=1e-12)  # the square closes
    np.testing.assert_allclose(np.degrees(path.leg_courses_rad()), [45, 135, 225, 315])
    left = cfg(kin.SquarePathConfig, turn="left")
    np.testing.assert_allclose(np.degrees(left.leg_courses_rad()), [45, 315, 225, 135])


@pytest.mark.parametrize(
    ("bearing", "of", "expected"),
    [
        (90.0, "follower_from_leader", 135.0),  # abeam to starboard on the 45 deg leg
        (180.0, "follower_from_leader", 225.0),  # astern
        (90.0, "leader_from_follower", 315.0),  # L to F's starboard: F on L's port side
        (180.0, "leader_from_follower", 45.0),  # L astern of F: F ahead
    ],
)
def test_world_offset_is_the_first_legs_relative_bearing(bearing, of, expected):
    f = cfg(kin.FormationConfig, relative_bearing_deg=bearing, bearing_of=of)
    tr = kin.square_truth(cfg(kin.SquarePathConfig), f)
    offset = tr.follower_m - tr.leader_m
    np.testing.assert_allclose(offset, np.broadcast_to(10.0 * u(expected), offset.shape), atol=1e-9)
    # same course and speed as the leader
    np.testing.assert_allclose(tr.follower_speed_m_s, 1.0, atol=1e-12)
    np.testing.assert_allclose(tr.follower_course_rad, tr.leader_course_rad, atol=1e-12)


@pytest.mark.parametrize("bearing", [90.0, 180.0])
def test_leg_offset_keeps_the_relative_bearing_on_every_leg(bearing):
    f = cfg(kin.FormationConfig, relative_bearing_deg=bearing, offset="leg")
    tr = kin.square_truth(cfg(kin.SquarePathConfig), f)
    for j, c in enumerate((45, 135, 225, 315)):
        k = 1200 * j + 100  # after the 10 s move to the new station
        np.testing.assert_allclose(
            tr.follower_m[k] - tr.leader_m[k], 10.0 * u(c + bearing), atol=1e-9
        )
    # the default corner move (10 m in 10 s) is sideways at the formation's speed
    np.testing.assert_allclose(tr.follower_speed_m_s, 1.0, atol=1e-9)
    assert np.all(np.diff(tr.follower_m, axis=0) ** 2 < (0.1 + 1e-9) ** 2 * 2)
    with pytest.raises(ConfigError, match=r"formation\.corner_s = 130"):
        kin.corner_ticks(cfg(kin.SquarePathConfig), cfg(kin.FormationConfig, corner_s=130.0))


def _sensors(**over):
    return load_config(kin.Seed003Sensors, over)


def _errors(n=200, seed=5, sensors=None):
    path = cfg(kin.SquarePathConfig)
    tr = kin.square_truth(path, cfg(kin.FormationConfig))
    m = kin.measure(sensors or _sensors(), tr, seed, tuple(range(n)))
    return tr, m


def _uniform_band(err, half, z=5.0):
    """The sample mean and variance of N draws uniform on [-h, h] against 0 and h^2/3, with
    normal bands of z standard errors (var of X = h^2/3; var of X^2 = 4 h^4 / 45)."""
    N = err.size
    assert abs(err.mean()) < z * math.sqrt(half**2 / 3 / N)
    var = np.mean(err**2)
    assert abs(var - half**2 / 3) < z * math.sqrt(4 * half**4 / 45 / N)
    assert np.abs(err).max() <= half * (1 + 1e-12)
    assert np.abs(err).max() > 0.999 * half  # it fills the interval


def test_course_error_is_uniform_on_two_degrees_plus_the_sector_bias():
    tr, m = _errors()
    true = tr.follower_course_rad
    sector = np.floor(np.degrees(true) / 90.0).astype(int)
    bias = np.radians(np.array([4.0, 8.0, 0.0, 2.0]))[sector]
    err = (m.course_rad - true - bias + math.pi) % (2 * math.pi) - math.pi
    _uniform_band(err, math.radians(2.0))
    assert m.course_rad.shape == (200, 4800)


def test_speed_and_range_errors_are_uniform_plus_their_bias():
    tr, m = _errors()
    _uniform_band(m.speed_m_s - 1.0 - 0.05, 0.3)
    true_range = np.hypot(*(tr.leader_m - tr.follower_m)[m.fix_tick].T)
    np.testing.assert_allclose(true_range, 10.0, atol=1e-9)
    _uniform_band(m.range_m - true_range - 0.025, 0.1, z=5.0)
    assert m.fix_tick[0] == 50 and m.fix_tick[-1] == 4800 and len(m.fix_tick) == 96
    np.testing.assert_array_equal(m.leader_m[0], tr.leader_m[m.fix_tick])  # the true position


def test_test3_biases_and_a_noisy_broadcast():
    s = _sensors(
        ins={"heading": {"sector_bias_deg": [0.4, 0.8, 0.0, 0.2]}},
        log={"speed": {"bias_m_s": 0.005}},
        modem={"range": {"bias_m": 0.0025}, "broadcast": {"sigma_m": 0.5}},
    )
    tr, m = _errors(n=100, sensors=s)
    true = tr.follower_course_rad
    sector = np.floor(np.degrees(true) / 90.0).astype(int)
    err = m.course_rad - true - np.radians(np.array([0.4, 0.8, 0.0, 0.2]))[sector]
    _uniform_band((err + math.pi) % (2 * math.pi) - math.pi, math.radians(2.0))
    b = m.leader_m - tr.leader_m[m.fix_tick]
    assert abs(np.std(b) - 0.5) < 5 * 0.5 / math.sqrt(2 * b.size)


def test_runs_draw_the_same_numbers_in_any_block():
    tr = kin.square_truth(cfg(kin.SquarePathConfig), cfg(kin.FormationConfig))
    s = _sensors()
    all5 = kin.measure(s, tr, 9, (0, 1, 2, 3, 4))
    part = kin.measure(s, tr, 9, (3, 4))
    np.testing.assert_array_equal(all5.course_rad[3:], part.course_rad)
    np.testing.assert_array_equal(all5.range_m[3:], part.range_m)
    other = kin.measure(s, tr, 10, (3, 4))
    assert not np.array_equal(other.course_rad, part.course_rad)


def test_modem_limits_zero_range_and_dropout_windows():
    tr = kin.square_truth(cfg(kin.SquarePathConfig), cfg(kin.FormationConfig, distance_m=0.0))
    m = kin.measure(_sensors(), tr, 1, (0, 1))
    assert (m.range_m >= 0).all() and m.range_m.max() <= 0.125 + 1e-12
    tr = kin.square_truth(cfg(kin.SquarePathConfig), cfg(kin.FormationConfig))
    far = kin.measure(_sensors(modem={"max_range_m": 5.0}), tr, 1, (0, 1))
    assert not far.range_produced.any()
    gap = kin.measure(_sensors(modem={"dropout_windows_s": [[60.0, 240.0]]}), tr, 1, (0, 1))
    t = tr.t_s[gap.fix_tick]
    np.testing.assert_array_equal(gap.range_produced[0], (t < 60.0) | (t > 240.0))
    with pytest.raises(ConfigError, match="must end after it starts"):
        _sensors(modem={"dropout_windows_s": [[60.0, 50.0]]})
