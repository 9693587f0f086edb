"""Soundings from beam ranges: by hand in simple attitudes, against the project's own rotation
(``bauv_sim.frames``) at arbitrary attitude, and beams without echo."""

from __future__ import annotations

import numpy as np
import pytest

from bauv_sim.frames import R_from_roll_pitch_heading
from nav.errors import NavInputError
from nav.trn import soundings


def test_level_vehicle_beam_straight_down_and_a_forward_beam_heading_east():
    a = np.radians(30.0)
    dirs = np.array([[0.0, 0.0, -1.0], [np.sin(a), 0.0, -np.cos(a)]])
    s = soundings([20.0, 10.0], [True, True], dirs, [0.0, 0.0, np.pi / 2], [1.0, 0.0, 0.5], 30.0)
    # heading east: body forward is east; the lever arm puts the transducer 1 m east, 0.5 m up
    np.testing.assert_allclose(s.offset_m, [[1.0, 0.0], [1.0 + 10.0 * np.sin(a), 0.0]], atol=1e-12)
    np.testing.assert_allclose(s.depth_m, [30.0 - 0.5 + 20.0, 30.0 - 0.5 + 10.0 * np.cos(a)])
    assert s.valid.all() and s.count == 2


def test_arbitrary_attitude_matches_the_projects_rotation():
    rng = np.random.default_rng(3)
    d = rng.normal(size=(6, 3))
    d[:, 2] = -np.abs(d[:, 2]) - 0.5
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rho = rng.uniform(5.0, 40.0, 6)
    att = np.array([0.2, -0.15, 4.0])
    lever = np.array([0.4, -0.1, -0.2])
    s = soundings(rho, np.ones(6, bool), d, att, lever, 12.0)
    rel = (R_from_roll_pitch_heading(*att) @ (lever[None, :] + rho[:, None] * d).T).T
    np.testing.assert_allclose(s.offset_m, rel[:, :2], atol=1e-12)
    np.testing.assert_allclose(s.depth_m, 12.0 - rel[:, 2], atol=1e-12)


def test_beams_without_echo_or_with_bad_ranges_are_invalid_never_nan():
    dirs = np.tile([0.0, 0.0, -1.0], (4, 1))
    s = soundings(
        [10.0, np.nan, 0.0, 12.0], [True, True, True, False], dirs, [0, 0, 0], [0, 0, 0], 5.0
    )
    np.testing.assert_array_equal(s.valid, [True, False, False, False])
    assert np.all(np.isfinite(s.offset_m)) and np.all(np.isfinite(s.depth_m))
    assert s.depth_m[0] == pytest.approx(15.0)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"echo": [True]}, "echo"),
        ({"roll_pitch_heading_rad": [0.0, np.nan, 0.0]}, "roll_pitch"),
        ({"lever_arm_body_m": [0.0, 0.0]}, "lever_arm"),
        ({"vehicle_depth_m": np.inf}, "vehicle_depth"),
    ],
)
def test_bad_input_is_one_clear_error(kwargs, field):
    args = {
        "ranges_m": [10.0, 11.0],
        "echo": [True, True],
        "directions_body": np.tile([0.0, 0.0, -1.0], (2, 1)),
        "roll_pitch_heading_rad": [0.0, 0.0, 0.0],
        "lever_arm_body_m": [0.0, 0.0, 0.0],
        "vehicle_depth_m": 5.0,
    } | kwargs
    with pytest.raises(NavInputError, match=field):
        soundings(**args)
