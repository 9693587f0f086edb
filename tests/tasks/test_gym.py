"""The missions as Gymnasium environments (tasks.gym): Gymnasium's own checker on every mission,
a random rollout, seeded resets bit for bit, and the environment checked against the mission run
it wraps (the autopilot through the environment flies exactly ``bauv run``'s run; the reward and
the observation recomputed from that run's recorded columns)."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tasks.gym
from bauv_sim.errors import BauvSimError, ConfigError
from tasks.closed_loop.parts import OBSERVATIONS
from tasks.closed_loop.scenario import MODES
from tasks.closed_loop.world import fly
from tasks.core import registry
from tasks.gym import MissionEnv

MISSIONS = [n for n in registry.names() if n.startswith("mission/")]

ADVISORY = (
    # the action is the actuators' commands in their own units (the issue asks for them), not
    # [-1, 1]: gymnasium.wrappers.RescaleAction gives the normalised form
    "we recommend using a symmetric and normalized space",
    # positions, velocities and rates have no bound
    "A Box observation space minimum value is -infinity",
    "A Box observation space maximum value is infinity",
)
"""The checker's advisory warnings the environments answer by design (any other fails)."""


SMALL = {"mission/seed004": ["seabed.cell_m=2"]}
"""Overrides that make a mission's scene quick to build (seed 004's 0.5 m seabed grid takes 0.7 s
to generate at every reset; the checker resets a dozen times)."""


def make(mission: str, seconds: float, overrides=(), **kwargs):
    return gymnasium.make(
        tasks.gym.env_id(mission),
        overrides=[f"timing.max_duration_s={seconds:g}", *overrides],
        **kwargs,
    )


def episode(env, actions, seed=None, options=None):
    """Observations, rewards, flags and infos of an episode with the given actions."""
    obs, info = env.reset(seed=seed, options=options)
    out = {"obs": [obs], "reward": [], "flags": [], "t": [info["t_s"]]}
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out["obs"].append(obs)
        out["reward"].append(r)
        out["flags"].append((term, trunc))
        out["t"].append(info["t_s"])
        if term or trunc:
            break
    return {k: np.array(v) for k, v in out.items()}


def autopilot_episode(env, seed, run):
    """The episode flown by the mission's own autopilot through the environment."""
    u = env.unwrapped
    env.reset(seed=seed, options={"run": run})
    rewards = []
    while True:
        _, r, term, trunc, _ = env.step(u.autopilot_action())
        rewards.append(r)
        if term or trunc:
            return u.result(), np.array(rewards)


def assert_same_run(got, want):
    assert list(got.vehicles) == list(want.vehicles)
    assert got.failed == want.failed
    for v, wv in want.vehicles.items():
        assert list(got.vehicles[v].ticks) == list(wv.ticks)
        for col in wv.ticks:  # NaN-aware, bit for bit
            np.testing.assert_array_equal(got.vehicles[v][col], wv[col], err_msg=f"{v} {col}")
        assert got.vehicles[v].summary == pytest.approx(wv.summary, rel=0, abs=0, nan_ok=True)


def test_every_mission_is_registered_with_gymnasium():
    assert len(MISSIONS) >= 7
    assert sorted(tasks.gym.ENV_IDS.values()) == MISSIONS
    for m in MISSIONS:
        i = tasks.gym.env_id(m)
        assert i == f"bauv/{m.replace('/', '-')}-v0"
        assert i in gymnasium.registry
    assert "bauv/mission-survey-v0" in gymnasium.registry


@pytest.mark.slow
@pytest.mark.parametrize("mission", MISSIONS)
def test_gymnasium_env_checker_passes(mission):
    env = make(mission, 10.0, SMALL.get(mission, ()))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    other = [str(w.message) for w in caught if not any(a in str(w.message) for a in ADVISORY)]
    assert not other, other
    env.close()


def test_a_random_rollout_runs_to_its_time_limit():
    env = make("mission/short", 6.0)
    env.action_space.seed(3)
    actions = [env.action_space.sample() for _ in range(100)]
    ep = episode(env, actions, seed=4)
    ticks = round(6.0 / 0.2)
    assert len(ep["reward"]) == ticks  # truncated after max_duration_s / control_tick_s steps
    assert [tuple(f) for f in ep["flags"]] == [(False, False)] * (ticks - 1) + [(False, True)]
    np.testing.assert_allclose(ep["t"], 0.2 * np.arange(ticks + 1), atol=1e-9)
    assert all(o in env.observation_space for o in ep["obs"])
    assert np.all(np.isfinite(ep["obs"])) and np.all(np.isfinite(ep["reward"]))
    assert len({o.tobytes() for o in ep["obs"]}) == ticks + 1  # the state moves
    with pytest.raises(BauvSimError, match="call reset"):
        env.step(actions[0])


@pytest.mark.slow
def test_seeded_resets_repeat_bit_for_bit():
    env = make("mission/short", 3.0)
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(15)]
    first = episode(env, actions, seed=11)
    episode(env, actions, seed=12)  # another episode in between
    again = episode(env, actions, seed=11)
    fresh = episode(make("mission/short", 3.0), actions, seed=11)
    for other in (again, fresh):
        for k in first:
            assert np.array_equal(first[k], other[k]), k
    assert not np.array_equal(first["obs"], episode(env, actions, seed=12)["obs"])
    # reset() without a seed flies the batch's next run
    episode(env, actions, seed=11)
    nxt = episode(env, actions)
    run1 = episode(env, actions, seed=11, options={"run": 1})
    assert np.array_equal(nxt["obs"], run1["obs"])
    assert not np.array_equal(nxt["obs"][0], first["obs"][0])


@pytest.mark.slow
@pytest.mark.parametrize(
    ("mission", "seconds", "controlled"),
    [
        ("mission/short", 20.0, None),
        ("mission/swarm", 8.0, None),
        ("mission/swarm", 8.0, ["leader"]),
        ("mission/correction", 8.0, None),
    ],
)
def test_the_autopilot_through_the_env_flies_the_mission_run(mission, seconds, controlled):
    """Run ``r`` of seed ``s`` is ``bauv run``'s: the autopilot's actions through the environment
    (the followers on their own autopilot when only the leader is controlled) give the mission's
    run, every recorded column bit for bit."""
    env = make(mission, seconds, controlled=controlled)
    u = env.unwrapped
    assert env.action_space.shape == (5 * len(controlled or u.vehicles),)
    got, _ = autopilot_episode(env, 5, 2)
    assert_same_run(got, fly(*u.experiment.flight(u.scenario, 5, 2), 5, 2))


@pytest.mark.slow
@pytest.mark.parametrize(("mission", "seconds"), [("mission/short", 80.0), ("mission/swarm", 8.0)])
def test_the_reward_is_the_way_point_progress_of_the_run(mission, seconds):
    """Each step's reward recomputed from the run's recorded truth and guidance columns: the
    distance closed towards the way-point approached at the step's start (a change of way-point
    included), or made good along the commanded course for guidance without way-points (the
    swarm's followers)."""
    env = make(mission, seconds)
    run, rewards = autopilot_episode(env, 7, 0)
    want = np.zeros(len(rewards))
    changes = 0
    for v in run.vehicles.values():
        p, mode = v["truth_pos"][:, :2], v["guidance_mode"]
        wp_index, course = v["guidance_waypoint"], v["guidance_course"]
        wps = [(w["east_m"], w["north_m"]) for w in v.waypoints]
        changes += int(np.count_nonzero(np.diff(wp_index)))
        for k in range(1, len(rewards) + 1):
            if mode[k - 1] == MODES.index("done"):
                continue
            if wps:
                e, n = wps[wp_index[k - 1]]
                want[k - 1] += math.hypot(e - p[k - 1, 0], n - p[k - 1, 1]) - math.hypot(
                    e - p[k, 0], n - p[k, 1]
                )
            else:
                d = p[k] - p[k - 1]
                want[k - 1] += d[0] * math.sin(course[k - 1]) + d[1] * math.cos(course[k - 1])
    np.testing.assert_allclose(rewards, want, rtol=1e-12, atol=1e-12)
    assert np.sum(rewards) > 0.5 * seconds  # the autopilot makes way (about 1 m/s)
    if mission == "mission/short":
        assert changes >= 1  # a way-point was reached during the episode


@pytest.mark.slow
def test_the_observation_layouts_are_the_run_columns():
    env = make("mission/short", 2.0, observation="both")
    u = env.unwrapped
    obs = [env.reset(seed=2)[0]]
    for _ in range(5):
        obs.append(env.step(u.autopilot_action())[0])
    v = u.result().vehicles["bauv"]
    sl = u.observation_slices
    pairs = {
        "bauv/estimate": "ekf_pos",
        "bauv/dr": "dr_pos",
        "bauv/true_position": "truth_pos",
        "bauv/true_velocity": "truth_vel",
        "bauv/true_velocity_water": "truth_vel_water",
        "bauv/true_attitude": "truth_rph",
        "bauv/heading": "meas_heading",
        "bauv/depth": "meas_depth",
        "bauv/speed": "meas_speed",
        "bauv/mode": "guidance_mode",
    }
    for tick, o in enumerate(obs):
        for name, col in pairs.items():
            assert np.array_equal(o[sl[name]], np.ravel(v[col][tick])), (tick, name)
        cmd = [v["guidance_course"][tick], v["guidance_depth"][tick], v["guidance_speed"][tick]]
        assert np.array_equal(o[sl["bauv/command"]], cmd)
        std = np.sqrt(np.diag(v["ekf_P"][tick].reshape(3, 3)))
        assert np.array_equal(o[sl["bauv/estimate_std"]], std)
    assert list(sl) == list(u.observation_names)
    assert env.observation_space.shape == (sum(s.stop - s.start for s in sl.values()),)
    truth = make("mission/short", 2.0, observation="truth").unwrapped
    assert [n.split("/")[1] for n in truth.observation_names] == [
        "true_position",
        "true_velocity",
        "true_velocity_water",
        "true_attitude",
        "true_angular_velocity",
        "command",
        "mode",
    ]
    assert truth.observation_space.shape == (5 * 3 + 3 + 1,)
    assert not set(truth.observation_names) & {f"bauv/{k}" for k in OBSERVATIONS} - {
        "bauv/command",
        "bauv/mode",
    }


@pytest.mark.slow
def test_bad_input_is_refused_in_one_line():
    cases = [
        (lambda: MissionEnv("mission/nowhere"), "unknown experiment 'mission/nowhere'"),
        (lambda: MissionEnv("paper-000/test-1"), "not a closed-loop mission"),
        (lambda: make("mission/short", 2.0, observation="pixels"), "observation = 'pixels'"),
        (lambda: make("mission/swarm", 2.0, controlled=["f9"]), "controlled = "),
        (lambda: make("mission/swarm", 2.0, controlled="leader"), "controlled = "),
        (lambda: make("mission/short", -1.0), "timing.max_duration_s"),
    ]
    env = make("mission/short", 2.0).unwrapped
    cases += [
        (lambda: env.reset(seed=-1), "seed = -1"),
        (lambda: env.reset(seed=1, options={"runs": 2}), "options = \\['runs'\\]"),
        (lambda: env.reset(seed=1, options={"run": -2}), "options\\['run'\\] = -2"),
    ]
    for call, match in cases:
        with pytest.raises(ConfigError, match=match) as exc:
            call()
        assert "\n" not in str(exc.value)
    with pytest.raises(BauvSimError, match="before reset"):
        env.step(np.zeros(5))
    env.reset(seed=1)
    for action, match in [
        (np.zeros(4), "shape \\(4,\\)"),
        ([1.0, 0.0, np.nan, 0.0, 0.0], "action\\[2\\] \\(bauv/fin_port_rad \\[rad\\]\\) = nan"),
        ("fast", "action = 'fast'"),
    ]:
        with pytest.raises(ConfigError, match=match):
            env.step(action)


def test_the_gym_package_names_its_extra_when_gymnasium_is_missing():
    code = "import sys; sys.modules['gymnasium'] = None\nimport tasks.gym"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode != 0
    assert "pip install 'bauv-sim[gym]'" in res.stderr


@pytest.mark.slow
def test_make_imports_the_package_from_the_id():
    code = (
        "import gymnasium\n"
        "env = gymnasium.make('tasks.gym:bauv/mission-short-v0',"
        " overrides=['timing.max_duration_s=1'])\n"
        "obs, info = env.reset(seed=0)\n"
        "print(obs.shape, info['run'])"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split("\n")[-2] == "(21,) 0"


def test_a_physics_failure_terminates_the_episode():
    """The scenario's injected fault (a NaN in the physics at 1 s of run 0) ends the episode as
    ``bauv run`` records it: terminated, the failure in the info and the run result, no NaN out."""
    faults = ["faults.physics_nan_at_s=1", "faults.physics_nan_runs=[0]"]
    env = make("mission/short", 5.0, faults)
    u = env.unwrapped
    last, _ = env.reset(seed=3)
    steps = 0
    while True:
        obs, r, term, trunc, info = env.step(u.autopilot_action())
        steps += 1
        if term or trunc:
            break
        last = obs
    assert (term, trunc) == (True, False) and steps < 25
    assert r == 0.0 and np.array_equal(obs, last) and np.all(np.isfinite(obs))
    assert info["failure"].startswith("run 0 (seed 3) failed at t = ")
    assert "PhysicsError" in info["failure"]
    ref = fly(*u.experiment.flight(u.scenario, 3, 0), 3, 0)
    assert u.result().failed == ref.failed == info["failure"]
    with pytest.raises(BauvSimError, match="call reset"):
        env.step(u.autopilot_action())


@pytest.mark.slow
def test_an_action_beyond_the_limits_is_clipped_to_them():
    env = make("mission/short", 2.0)
    high = env.action_space.high
    env.reset(seed=1)
    clipped = env.step(high)[0]
    env.reset(seed=1)
    beyond = env.step(high + np.array([5.0, 1.0, 1.0, 1.0, 0.5]))[0]
    env.reset(seed=1)
    below = env.step(env.action_space.low)[0]
    assert np.array_equal(beyond, clipped) and not np.array_equal(below, clipped)


@pytest.mark.slow
def test_an_unseeded_first_reset_draws_the_batch_seed():
    seeds = [make("mission/short", 1.0).reset()[1]["seed"] for _ in range(2)]
    assert seeds[0] != seeds[1]
    assert all(isinstance(s, int) and 0 <= s <= 2**63 - 1 for s in seeds)


@pytest.mark.slow
def test_a_vector_of_environments_flies_the_single_environments_runs():
    """Gymnasium's vector API seeds sub-environment i with seed + i: each flies the run 0 of its
    seed, as one environment does."""
    kwargs = {"overrides": ["timing.max_duration_s=1"]}
    vec = gymnasium.make_vec("bauv/mission-short-v0", 2, "sync", vector_kwargs={}, **kwargs)
    obs, info = vec.reset(seed=8)
    for i in range(2):
        single, _ = make("mission/short", 1.0).reset(seed=8 + i)
        assert np.array_equal(obs[i], single)
    assert list(info["seed"]) == [8, 9]
    vec.close()
