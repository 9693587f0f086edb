"""The check every experiment's bad-input test makes: ``bauv run`` refuses in one line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path


def assert_refused(tmp_path: Path, name: str, *args: str, pattern: str) -> None:
    """``bauv run NAME --out OUT ARGS`` exits with status 2, one line on stderr holding
    ``pattern`` and no traceback, and writes nothing."""
    out = tmp_path / "refused"
    res = subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", name, "--out", str(out), *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and pattern in lines[0] and "Traceback" not in res.stderr, lines
    assert not out.exists()


def run_in_process(capsys, *args: str) -> tuple[int, str]:
    """``bauv ARGS`` in this process (pytest's ``capsys`` captures it): (exit status, stderr)."""
    from tasks.core import cli

    capsys.readouterr()
    try:
        cli.main(list(args))
        code = 0
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err
