"""Missions flown unchanged in the manoeuvring world (``timing.world = "manoeuvring"``, issue
27): the same sensors, navigation, guidance, autopilot and run data on the manoeuvring model,
and one clear line for what it cannot fly."""

from __future__ import annotations

import numpy as np
import pytest

from bauv_sim.manoeuvring.physics import ManoeuvringPhysics
from tasks.closed_loop.world import WaypointMission, build_environment, fly
from tasks.core.runner import plan_batch
from tests.tasks.refusal import assert_refused

M = "timing.world=manoeuvring"


def _scenario(name: str, *overrides: str):
    return plan_batch(name, overrides=list(overrides)).scenario


@pytest.fixture(scope="module")
def short_pair():
    """mission/short on both worlds, same seed and run."""
    full = fly(WaypointMission(), _scenario("mission/short"), 3, 1)
    man = fly(WaypointMission(), _scenario("mission/short", M), 3, 1)
    return full, man


def test_the_world_is_the_manoeuvring_model_only_when_asked():
    design = WaypointMission()
    env = build_environment(design, _scenario("mission/short", M), 0, 0)
    assert isinstance(env.physics, ManoeuvringPhysics)
    assert env.physics.steps_per_tick == 1  # one model step per control tick
    env = build_environment(design, _scenario("mission/short"), 0, 0)
    assert not isinstance(env.physics, ManoeuvringPhysics)


def test_a_short_mission_flies_to_its_end_as_on_the_full_model(short_pair):
    """Every way-point reached by truth on both worlds; the manoeuvring run's navigation and
    duration within what separates two different physics on a 2-minute mission (the full
    model's own run is the reference: duration within 10 %, EKF mean error within 1 m); run
    data finite, the same columns."""
    full, man = short_pair
    assert man.failed is None, man.failed
    f, m = full.lead, man.lead
    assert m.summary["waypoints_reached_by_truth"] == len(m.waypoints) == 2
    assert f.summary["waypoints_reached_by_truth"] == 2
    assert m.summary["duration_s"] == pytest.approx(f.summary["duration_s"], rel=0.10)
    assert abs(m.summary["ekf_mean_error_m"] - f.summary["ekf_mean_error_m"]) < 1.0
    assert m.summary["energy_j"] == pytest.approx(f.summary["energy_j"], rel=0.15)
    assert set(m.ticks) == set(f.ticks)
    for k, col in m.ticks.items():
        a = np.asarray(col.values)
        if a.dtype.kind == "f":
            assert np.all(np.isfinite(a)), k
    # the compass sees the beat: the heading oscillates about the course at the beat frequency
    head = np.unwrap(m.ticks["truth_rph"].values[:, 2])
    assert np.std(np.diff(head)) > 1e-3


def test_same_seed_same_numbers(short_pair):
    again = fly(WaypointMission(), _scenario("mission/short", M), 3, 1)
    _, man = short_pair
    assert again.lead.summary == man.lead.summary
    np.testing.assert_array_equal(
        again.lead.ticks["ekf_pos"].values, man.lead.ticks["ekf_pos"].values
    )


def test_a_physics_failure_is_reported_not_raised():
    run = fly(
        WaypointMission(),
        _scenario("mission/short", M, "faults.physics_nan_at_s=10", "faults.physics_nan_runs=[0]"),
        0,
        0,
    )
    assert run.failed is not None and "non-finite state" in run.failed and "t = 10.2" in run.failed


@pytest.mark.parametrize(
    ("name", "args", "pattern"),
    [
        ("mission/short", ("--set", "timing.world=gazebo"), "timing.world"),
        ("mission/surfacing", ("--set", M), "no free surface"),
        ("mission/swarm", ("--set", M), "manoeuvring world holds one"),
        ("mission/trn", ("--set", M), "is flown on the full physics only"),
    ],
)
def test_what_the_world_cannot_fly_is_refused_in_one_line(tmp_path, name, args, pattern):
    assert_refused(tmp_path, name, *args, pattern=pattern)


@pytest.mark.slow
def test_the_survey_flies_to_its_end():
    run = fly(WaypointMission(), _scenario("mission/survey", M), 0, 0)
    assert run.failed is None, run.failed
    v = run.lead
    assert v.summary["waypoints_reached_by_truth"] == len(v.waypoints) == 5
    assert v.summary["ekf_mean_error_m"] < 3.0
