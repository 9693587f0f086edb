"""Start-up: a kinematic run imports only what it needs (issue 13: MuJoCo, dm_control, matplotlib
and rerun are not imported by ``bauv run paper-000/test-1`` with figures and recording off; scipy's
statistics are, for the chi-square quantiles of its gates and NEES band, since issue 26 replaced
the hand-written quantile with ``scipy.stats.chi2.ppf``), and
``bauv list`` imports no experiment package."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = (
    "mujoco",
    "dm_control",
    "matplotlib",
    "rerun",
    "scipy.stats",
    "scipy.spatial",
    "scipy.special",
    "trimesh",
    "numpy",
    "pydantic",
)


def _modules_after(code: str) -> dict[str, bool]:
    probe = (
        f"import json, sys\n{code}\nprint(json.dumps({{m: m in sys.modules for m in {HEAVY!r}}}))"
    )
    res = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_a_kinematic_run_without_figures_and_recording_imports_nothing_heavy(tmp_path):
    out = tmp_path / "run"
    code = (
        "from tasks.core.cli import main\n"
        "try:\n"
        f"    main(['run', 'paper-000/test-1', '--runs', '1', '--quiet', '--out', {str(out)!r},"
        " '--set', 'report.figures=false', '--set', 'report.recording=false'])\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
    )
    loaded = _modules_after(code)
    assert (out / "metrics.json").is_file()
    heavy = ("mujoco", "dm_control", "matplotlib", "rerun", "trimesh")
    assert not any(loaded[m] for m in heavy), loaded
    # scipy.stats (with scipy.special and scipy.spatial, which it imports) is: the report's NEES
    # band and the EKF's gate take their chi-square quantiles from scipy.stats.chi2.ppf, imported
    # where they are first needed (issue 26: a kept library instead of a hand-written quantile)
    assert loaded["scipy.stats"], loaded


@pytest.mark.slow
def test_figures_import_matplotlib_when_drawn(tmp_path):
    out = tmp_path / "run"
    code = (
        "from tasks.core.cli import main\n"
        "try:\n"
        f"    main(['run', 'paper-000/test-1', '--runs', '2', '--quiet', '--out', {str(out)!r}])\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
    )
    loaded = _modules_after(code)
    assert loaded["matplotlib"] and loaded["rerun"]
    assert not loaded["mujoco"] and not loaded["dm_control"]
    assert (out / "routes.png").is_file() and (out / "recording.rrd").is_file()


def test_bauv_list_imports_no_experiment():
    code = (
        "import json, sys\n"
        "from tasks.core.cli import main\n"
        "try:\n"
        "    main(['list'])\n"
        "except SystemExit as e:\n"
        "    assert not e.code\n"
        "print(json.dumps(sorted(m for m in sys.modules if m.startswith('tasks.paper') or "
        "m.startswith('tasks.missions') or m.startswith('tasks.vehicle') or "
        "m == 'importlib.metadata')))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "mission/survey" in res.stdout
    # nor the installed metadata, where the families are declared (a third of its start-up)
    assert json.loads(res.stdout.strip().splitlines()[-1]) == []


def test_the_command_line_and_the_workers_module_import_nothing_heavy():
    """``bauv`` starts its workers' fork server before the project's imports (issue 13): the CLI
    module and :mod:`tasks.core.workers` import neither numpy nor pydantic."""
    loaded = _modules_after("import tasks.core.cli, tasks.core.workers, tasks.core.errors")
    assert not any(loaded.values()), loaded


@pytest.mark.slow
def test_bauv_run_forks_its_workers_after_its_imports_and_before_its_threads(tmp_path):
    """With ``--workers 2`` on Linux the workers are forked from ``bauv`` itself (issue 13: a
    fork server's own start and imports were on the critical path of a 2-worker batch): when it
    forks it has imported the experiment (the workers start with it), runs no other thread (a
    forked child would keep the locks another thread held; the progress bar's monitor and the
    report's thread start after), and has numpy's huge pages turned off for them to inherit; no
    fork server is started, and the batch completes."""
    out = tmp_path / "run"
    code = (
        "import json, os, sys, threading\n"
        "os.environ.pop('NUMPY_MADVISE_HUGEPAGE', None)\n"
        "seen = []\n"
        "def probe():\n"
        "    seen.append([threading.active_count(), 'tasks.paper000.passage' in sys.modules, "
        "os.environ.get('NUMPY_MADVISE_HUGEPAGE')])\n"
        "os.register_at_fork(before=probe)\n"
        "from multiprocessing import forkserver\n"
        "from tasks.core.cli import main\n"
        "try:\n"
        f"    main(['run', 'paper-000/test-1', '--runs', '4', '--workers', '2', '--quiet', "
        f"'--out', {str(out)!r}, '--set', 'runner.block_size=2', '--set', "
        "'report.figures=false', '--set', 'report.recording=false'])\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
        "print(json.dumps([seen, forkserver._forkserver._forkserver_pid]))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    seen, server = json.loads(res.stdout.strip().splitlines()[-1])
    assert seen == [[1, True, "0"], [1, True, "0"]], seen  # two workers, as described
    assert server is None
    assert (out / "metrics.json").is_file()


def test_bauv_spares_the_final_garbage_collections_at_exit():
    """At exit ``bauv`` freezes the objects it holds (``gc.freeze``), so the interpreter's final
    collections do not scan the whole project (~0.1 s of a kinematic batch): the freeze runs after
    every other exit handler registered by then, and before one registered earlier."""
    code = (
        "import atexit, gc\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count()))\n"
        "from tasks.core.cli import main\n"
        "try:\n"
        "    main(['list'])\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
        "print('frozen before exit', gc.get_freeze_count())\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = res.stdout.strip().splitlines()
    assert lines[-2] == "frozen before exit 0", lines[-2:]
    assert lines[-1].startswith("frozen ") and int(lines[-1].split()[-1]) > 1000, lines[-1]


@pytest.mark.slow
def test_bauv_run_looks_for_no_opengl_backend_unless_asked(tmp_path):
    """``bauv run`` renders nothing through OpenGL: it sets MUJOCO_GL=disable (unless the user
    set it) before MuJoCo is imported, so that MuJoCo does not load GLFW's library at import; a
    user's choice is kept."""
    import os

    def run(env_gl: str | None) -> tuple[str | None, bool]:
        code = (
            "import json, os, sys\n"
            "from tasks.core.cli import main\n"
            "try:\n"
            f"    main(['run', 'paper-000/test-1', '--runs', '1', '--quiet', '--out', "
            f"{str(tmp_path / str(env_gl))!r}, '--set', 'report.figures=false', '--set', "
            "'report.recording=false'])\n"
            "except SystemExit as e:\n"
            "    assert not e.code, e.code\n"
            "import mujoco\n"
            "print(json.dumps([os.environ.get('MUJOCO_GL'), 'glfw' in sys.modules]))\n"
        )
        env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
        if env_gl is not None:
            env["MUJOCO_GL"] = env_gl
        res = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
        )
        gl, glfw = json.loads(res.stdout.strip().splitlines()[-1])
        return gl, glfw

    assert run(None) == ("disable", False)
    assert run("glfw")[0] == "glfw"
