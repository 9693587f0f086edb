"""Start-up: a kinematic run imports only what it needs (issue 13: MuJoCo, dm_control, matplotlib
and rerun are not imported by ``bauv run paper-000/test-1`` with figures and recording off), and
``bauv list`` imports no experiment package."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("mujoco", "dm_control", "matplotlib", "rerun", "scipy.stats", "trimesh")


def _modules_after(code: str) -> dict[str, bool]:
    probe = (
        f"import json, sys\n{code}\nprint(json.dumps({{m: m in sys.modules for m in {HEAVY!r}}}))"
    )
    res = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


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
    assert not any(loaded[m] for m in ("mujoco", "dm_control", "matplotlib", "rerun")), loaded


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
        "m.startswith('tasks.missions') or m.startswith('tasks.vehicle'))))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "mission/survey" in res.stdout
    assert json.loads(res.stdout.strip().splitlines()[-1]) == []
