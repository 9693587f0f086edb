"""The package as a user gets it: its version, the MuJoCo release its plugin accepts, the
provenance every run folder records, ``python -m bauv_sim``.

The wheel itself (built by ``pip wheel .``, installed into a clean environment, running
``bauv run mission/survey`` outside the source tree) is a step of ``.ci/run``: it needs a fresh
environment and the package index, which a unit test should not.
"""

import json
import platform
import re
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import mujoco
import numpy as np
import pytest

from bauv_sim import ConfigError, hydro, provenance
from tasks.core.runner import run

ROOT = Path(__file__).resolve().parents[1]
HAS_GIT = shutil.which("git") is not None and (ROOT / ".git").exists()


def _git(*args, cwd=ROOT):
    return subprocess.run(
        ["git", *args], cwd=cwd, capture_output=True, text=True, check=True
    ).stdout.strip()


# --------------------------------------------------------------------------------------------
# The MuJoCo release of the plugin


def test_the_plugin_records_the_headers_it_was_compiled_against():
    header = Path(mujoco.__file__).parent / "include" / "mujoco" / "mujoco.h"
    number = int(re.search(r"#define\s+mjVERSION_HEADER\s+(\d+)", header.read_text()).group(1))
    record = json.loads((hydro.plugin_path().parent / hydro.PLUGIN_RECORD).read_text())
    assert record == {"mujoco": mujoco.__version__, "mjVERSION_HEADER": number}
    assert hydro.plugin_built_for() == number == mujoco.mj_version()


@pytest.mark.parametrize(
    ("runtime", "built_for"),
    [(3018000, 3017000), (3016000, 3017000), (3017001, 3017000), (4000000, 3017000)],
)
def test_another_mujoco_release_is_refused_in_one_line(runtime, built_for):
    with pytest.raises(ConfigError) as err:
        hydro.check_plugin_abi(runtime, built_for)
    text = str(err.value)
    have = f"{runtime // 1000000}.{runtime // 1000 % 1000}.{runtime % 1000}"
    assert "\n" not in text
    assert f"mujoco {have} is installed" in text
    assert "compiled against mujoco 3.17.0" in text
    assert "install mujoco==3.17.0" in text


def test_the_same_release_is_accepted():
    hydro.check_plugin_abi(3017000, 3017000)
    hydro.check_plugin_abi(3021004, 3021004)


def test_load_plugin_checks_the_loaded_library(monkeypatch):
    monkeypatch.setattr(hydro, "_PLUGIN_LOADED", False)
    monkeypatch.setattr(hydro.mujoco, "mj_version", lambda: 3018000)
    loaded = []
    monkeypatch.setattr(hydro.mujoco, "mj_loadPluginLibrary", loaded.append)
    with pytest.raises(ConfigError, match=re.escape("mujoco 3.18.0 is installed")):
        hydro.load_plugin()
    assert loaded == [] and hydro._PLUGIN_LOADED is False


def test_plugin_path_takes_this_interpreters_extension_suffix(tmp_path, monkeypatch):
    """The plugin is found by this Python's extension suffixes, in their order: a library built
    for another Python (another ABI tag) beside it is not taken, and none is a ConfigError."""
    import importlib.machinery

    plugin = tmp_path / "plugin"
    plugin.mkdir()
    monkeypatch.setattr(hydro, "__file__", str(tmp_path / "hydro.py"))
    other = plugin / "_bauv_hydro.cpython-399-x86_64-linux-gnu.so"  # sorts after any real tag
    other.write_bytes(b"")
    with pytest.raises(ConfigError, match="is not built"):
        hydro.plugin_path()
    ours = plugin / ("_bauv_hydro" + importlib.machinery.EXTENSION_SUFFIXES[0])
    ours.write_bytes(b"")
    assert hydro.plugin_path() == ours


def test_the_build_record_is_read_and_checked(tmp_path):
    library = tmp_path / "_bauv_hydro.so"
    assert hydro.plugin_built_for(library) == 3017000  # no record: built under the 3.17.0 pin
    record = tmp_path / hydro.PLUGIN_RECORD
    record.write_text('{"mujoco": "3.18.2", "mjVERSION_HEADER": 3018002}')
    assert hydro.plugin_built_for(library) == 3018002
    for bad in ('{"mujoco": "3.18.2"}', "not json", '{"mjVERSION_HEADER": "3018002"}', "[1]"):
        record.write_text(bad)
        with pytest.raises(ConfigError, match="reinstall the package"):
            hydro.plugin_built_for(library)


# --------------------------------------------------------------------------------------------
# Version and provenance


def test_version_is_the_distributions():
    import bauv_sim

    assert provenance.package_version() == metadata.version("bauv-sim")
    assert bauv_sim.__version__ == metadata.version("bauv-sim")


def test_bauv_version_and_python_m_bauv_sim(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "bauv_sim", "--version"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert res.returncode == 0, res.stderr
    first, second, third, fourth = res.stdout.splitlines()
    assert first.startswith(f"bauv-sim {metadata.version('bauv-sim')}")
    if HAS_GIT:
        assert f"(commit {_git('rev-parse', 'HEAD')[:12]}" in first
    assert f"Python {platform.python_version()}" in second
    assert f"mujoco {mujoco.__version__}" in second and f"numpy {np.__version__}" in second
    assert third == f"platform {platform.platform()}"
    assert fourth == f"interpreter {sys.executable}"
    # the terminal's 100 columns (the interpreter's own path excepted: it is as long as it is)
    assert max(len(first), len(second), len(third)) <= 100
    listed = subprocess.run(
        [sys.executable, "-m", "bauv_sim", "list"], capture_output=True, text=True, cwd=tmp_path
    )
    assert listed.returncode == 0 and "mission/survey" in listed.stdout


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_git_state_of_a_checkout(tmp_path):
    repo = tmp_path / "repo"
    repo.mkdir()
    _git("init", "-q", cwd=repo)
    (repo / "a.txt").write_text("one\n")
    _git("add", "a.txt", cwd=repo)
    _git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "c", cwd=repo)
    head = _git("rev-parse", "HEAD", cwd=repo)
    assert provenance.git_state(repo) == (head, False)
    (repo / "b.txt").write_text("untracked\n")
    assert provenance.git_state(repo) == (head, False)
    (repo / "a.txt").write_text("two\n")
    assert provenance.git_state(repo) == (head, True)
    assert provenance.git_state(tmp_path / "not-a-repo") == (None, None)
    assert provenance.git_state(None) == (None, None)


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_an_installed_package_inside_another_repository_names_no_commit(tmp_path, monkeypatch):
    repo = tmp_path / "someone-elses"
    site = repo / ".venv" / "lib" / "site-packages" / "bauv_sim"
    site.mkdir(parents=True)
    _git("init", "-q", cwd=repo)
    monkeypatch.setattr(provenance, "__file__", str(site / "provenance.py"))
    assert provenance.source_root() is None
    monkeypatch.setattr(provenance, "__file__", str(repo / "bauv_sim" / "provenance.py"))
    assert provenance.source_root() == repo


def test_every_run_folder_records_its_provenance(tmp_path):
    out = tmp_path / "run"
    run(
        "paper-000/test-1",
        2,
        7,
        out,
        ["passage.duration_s=100", "passage.closest_approach_time_s=50", "report.figures=false"],
        progress=False,
    )
    prov = json.loads((out / "provenance.json").read_text())
    record = json.loads((out / "run.json").read_text())
    assert record["state"] == "complete" and record["provenance"] == prov
    assert prov["package"] == "bauv-sim" and prov["version"] == metadata.version("bauv-sim")
    assert prov["python"] == platform.python_version()
    assert prov["mujoco"] == mujoco.__version__ and prov["numpy"] == np.__version__
    assert prov["platform"] == platform.platform() and prov["machine"] == platform.machine()
    if HAS_GIT:
        assert prov["commit"] == _git("rev-parse", "HEAD")
        dirty = _git("status", "--porcelain", "--untracked-files=no") != ""
        assert prov["dirty"] is dirty
    metrics = (out / "metrics.json").read_text()
    for word in ("provenance", "mujoco", "numpy", "commit", "platform", "python"):
        assert word not in metrics.lower()


def test_a_batch_completed_elsewhere_keeps_the_provenance_it_started_with(tmp_path):
    from tasks.core import run_folder
    from tasks.core.resume import plan_resume

    out = tmp_path / "run"
    overrides = ["passage.duration_s=100", "passage.closest_approach_time_s=50"]
    run("paper-000/test-1", 2, 7, out, [*overrides, "report.figures=false"], progress=False)
    # as if another version had started it: its provenance.json, then --resume completes it here
    started = {**provenance.collect(), "version": "0.0.9", "commit": "0" * 40}
    (out / "provenance.json").write_text(json.dumps(started))
    plan = plan_resume(out, "paper-000/test-1", None, None, (), ())
    run_folder.write_run_record(out, plan, "complete")
    record = json.loads((out / "run.json").read_text())
    assert record["provenance"] == started
    assert record["provenance_completed"] == provenance.collect()
    assert json.loads((out / "provenance.json").read_text()) == started
    plan_resume(out, "paper-000/test-1", None, None, (), ())  # its record_sha256 still holds
