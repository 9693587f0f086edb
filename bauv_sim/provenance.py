"""Where a run's numbers came from: the package's version and git commit, the versions of Python,
MuJoCo and numpy, and the platform.

:func:`collect` gathers them once per process; every run folder holds them in ``provenance.json``
and under the ``provenance`` key of ``run.json`` (:mod:`tasks.core.run_folder`), never in
``metrics.json`` (whose numbers alone are compared between runs). ``bauv --version`` prints
:func:`version_text`.

The commit is read only from a git checkout whose top holds this package (``.git`` beside the
``bauv_sim`` folder: a clone or a worktree, with ``git`` on the ``PATH``); an installed wheel has
none, even inside someone else's repository, and records ``null``. ``dirty`` is whether tracked
files differ from that commit (untracked files are not counted).
"""

from __future__ import annotations

import functools
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

DISTRIBUTION = "bauv-sim"
"""The distribution name (``pyproject.toml``)."""

GIT_TIMEOUT_S = 10.0
"""Longest wait for one ``git`` command (s); past it the commit is recorded as unknown."""


def package_version() -> str:
    """Version of the installed ``bauv-sim`` distribution (``"0.1.0"``), or ``"unknown"`` when
    the package is imported from a source tree that was never installed."""
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown"


def distribution_version(name: str) -> str | None:
    """Version of an installed distribution (``"mujoco"``, ``"numpy"``), or ``None``; read from
    its metadata, without importing it."""
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def source_root() -> Path | None:
    """The git checkout this package is imported from: the folder above ``bauv_sim`` when it holds
    ``.git`` (a folder in a clone, a file in a worktree), else ``None`` (an installed wheel)."""
    root = Path(__file__).resolve().parents[1]
    return root if (root / ".git").exists() else None


def _git(root: Path, *args: str) -> str | None:
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0"}  # status takes no index lock
    try:
        done = subprocess.run(
            ["git", "-C", str(root), *args],
            capture_output=True,
            text=True,
            timeout=GIT_TIMEOUT_S,
            env=env,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


def git_state(root: Path | None) -> tuple[str | None, bool | None]:
    """``(commit, dirty)`` of a git checkout: the full sha1 of ``HEAD`` and whether tracked files
    differ from it; ``(None, None)`` without a checkout, without ``git``, or when git fails."""
    if root is None:
        return None, None
    head = _git(root, "rev-parse", "--verify", "HEAD")
    if head is None or not head.strip():
        return None, None
    status = _git(root, "status", "--porcelain", "--untracked-files=no")
    return head.strip(), (None if status is None else bool(status.strip()))


@functools.cache
def collect() -> dict[str, Any]:
    """The provenance of this process (gathered once; a plain JSON-ready dict).

    Returns:
        ``package`` (distribution name), ``version`` (:func:`package_version`), ``commit`` (git
        sha1 or ``None``), ``dirty`` (bool or ``None``), ``python`` (``"3.11.7"``),
        ``python_implementation``, ``mujoco`` and ``numpy`` (installed versions), ``platform``
        (:func:`platform.platform`), ``machine`` (``"x86_64"``).
    """
    commit, dirty = git_state(source_root())
    return {
        "package": DISTRIBUTION,
        "version": package_version(),
        "commit": commit,
        "dirty": dirty,
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "mujoco": distribution_version("mujoco"),
        "numpy": distribution_version("numpy"),
        "platform": platform.platform(),
        "machine": platform.machine(),
    }


def version_text() -> str:
    """What ``bauv --version`` prints, four short lines: ``bauv-sim 0.1.0``, with the commit from
    a git checkout (``bauv-sim 0.1.0 (commit 65dac30c1f2e, modified)``); the versions of Python,
    MuJoCo and numpy; the platform; the Python interpreter's path."""
    p = collect()
    text = f"{p['package']} {p['version']}"
    if p["commit"] is not None:
        text += f" (commit {p['commit'][:12]}{', modified' if p['dirty'] else ''})"
    return (
        f"{text}\nPython {p['python']}, mujoco {p['mujoco']}, numpy {p['numpy']}\n"
        f"platform {p['platform']}\ninterpreter {sys.executable}"
    )
