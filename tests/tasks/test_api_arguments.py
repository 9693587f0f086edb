"""The library's entry points (README "Use it as a library") refuse a ``None`` or a wrong type
with the package's own error naming the argument, its type and what is allowed (issue 21: they
raised AttributeError from deep inside, and a string given as the overrides list was read one
character at a time). Nothing is computed or written before the check."""

from pathlib import Path

import pytest

import tasks
from bauv_sim import load_config
from bauv_sim.errors import ConfigError


@pytest.fixture(scope="module")
def short():
    exp = tasks.get_experiment("mission/short")
    return exp, load_config(exp.scenario_type, exp.preset)


def _never(*_a, **_k):
    raise AssertionError("work started before the arguments were checked")


CASES = [
    # (entry point, call, pattern of the one-line message)
    ("get_experiment", lambda s: tasks.get_experiment(None), r"name = None \(NoneType\): must be"),
    ("get_experiment", lambda s: tasks.get_experiment(5), r"name = 5 \(int\): must be an exp"),
    ("register", lambda s: tasks.register(None), r"experiment = None \(NoneType\): must be an"),
    ("register", lambda s: tasks.register("paper-000/x"), r"\(str\): must be an Experiment"),
    ("load_config", lambda s: load_config(None), r"model = None \(NoneType\): must be a Config"),
    ("load_config", lambda s: load_config(s[0].scenario_type, "x"), r"base = 'x' \(str\)"),
    (
        "load_config",
        lambda s: load_config(s[0].scenario_type, s[0].preset, [], "timing.max_duration_s=5"),
        r"overrides = 'timing.max_duration_s=5': a single str; must be a list",
    ),
    (
        "load_config",
        lambda s: load_config(s[0].scenario_type, s[0].preset, "a.toml"),
        r"files = 'a.toml': a single path; must be a list",
    ),
    ("plan_batch", lambda s: tasks.plan_batch(None), r"name = None \(NoneType\)"),
    (
        "plan_batch",
        lambda s: tasks.plan_batch("mission/short", overrides="report.figures=false"),
        r"overrides = 'report.figures=false': a single str",
    ),
    (
        "plan_batch",
        lambda s: tasks.plan_batch("mission/short", overrides=[None]),
        r"overrides\[0\] = None \(NoneType\): must be a KEY=VALUE string",
    ),
    ("run", lambda s: tasks.run(None), r"name = None \(NoneType\): must be an experiment name"),
    ("run", lambda s: tasks.run(["mission/short"]), r"name = \['mission/short'\] \(list\)"),
    (
        "run",
        lambda s: tasks.run("mission/short", overrides="report.figures=false"),
        r"overrides = 'report.figures=false': a single str; must be a list",
    ),
    (
        "run",
        lambda s: tasks.run("mission/short", overrides=None),
        r"overrides = None \(NoneType\): must be a list of KEY=VALUE strings",
    ),
    (
        "run",
        lambda s: tasks.run("mission/short", scenario_files="a.toml"),
        r"scenario_files = 'a.toml': a single path",
    ),
    ("run", lambda s: tasks.run("mission/short", n_runs="2"), r"n_runs = '2' \(str\)"),
    ("run", lambda s: tasks.run("mission/short", seed=1.5), r"seed = 1.5 \(float\)"),
    ("run", lambda s: tasks.run("mission/short", out_dir=5), r"out_dir = 5 \(int\): must be"),
    ("run", lambda s: tasks.run("mission/short", address=5), r"address = 5 \(int\)"),
    ("run", lambda s: tasks.run("mission/short", resume="yes"), r"resume = 'yes' \(str\)"),
    ("run", lambda s: tasks.run("mission/short", progress=None), r"progress = None"),
    ("run", lambda s: tasks.run("mission/short", workers=None), r"workers = None: must be"),
    ("fly", lambda s: tasks.fly(None, s[1], 0, 0), r"design = None \(NoneType\): must be a"),
    (
        "fly",
        lambda s: tasks.fly(tasks.WaypointMission, s[1], 0, 0),
        r"design = <class .*WaypointMission'> \(type\): must be a mission design instance",
    ),
    (
        "fly",
        lambda s: tasks.fly(tasks.WaypointMission(), None, 0, 0),
        r"scenario = None \(NoneType\): must be a validated mission scenario",
    ),
    (
        "fly",
        lambda s: tasks.fly(tasks.WaypointMission(), {}, 0, 0),
        r"scenario = \{\} \(dict\): must be a validated mission scenario",
    ),
    (
        "fly",
        lambda s: tasks.fly(tasks.WaypointMission(), s[0].preset, 0, 0),
        r"\(dict\): must be a validated mission scenario",
    ),
    ("fly", lambda s: tasks.fly(tasks.WaypointMission(), s[1], None, 0), r"seed = None"),
    ("fly", lambda s: tasks.fly(tasks.WaypointMission(), s[1], 0, "a"), r"run = 'a' \(str\)"),
    ("fly", lambda s: tasks.fly(tasks.WaypointMission(), s[1], 0, -1), r"run = -1 \(int\)"),
]


@pytest.mark.parametrize(("entry", "call", "pattern"), CASES, ids=[c[0] for c in CASES])
def test_an_argument_of_the_wrong_type_is_the_packages_own_error(
    entry, call, pattern, short, tmp_path, monkeypatch
):
    from tasks.closed_loop import world
    from tasks.core import runner

    monkeypatch.chdir(tmp_path)  # run() would write runs/... here
    monkeypatch.setattr(world, "build_environment", _never)
    monkeypatch.setattr(runner, "prepare_out_dir", _never)
    with pytest.raises(ConfigError, match=pattern) as info:
        call(short)
    assert "\n" not in str(info.value)
    assert not any(Path(tmp_path).iterdir())


def test_a_list_of_overrides_still_works(short):
    plan = tasks.plan_batch("mission/short", overrides=("report.figures=false",))
    assert plan.scenario.report.figures is False
