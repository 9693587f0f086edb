"""Hostile scenario files and bad way-points on the command line (issue 21): one line, exit
status 2, no traceback, nothing written. A 5,000-deep array gave a 3,001-line RecursionError and
exit status 1; a bad way-point a second line, "Tuple should have at least 1 item"."""

import subprocess
import sys

import pytest


def bauv(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", *args], capture_output=True, text=True, cwd=cwd
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        ("[start]\neast_m = " + "[" * 5000 + "]" * 5000 + "\n", "nested more than 32 deep at"),
        ("x = " + "{a = " * 5000 + "1" + "}" * 5000 + "\n", "nested more than 32 deep at"),
        ("[" + ".".join(["a"] * 5000) + "]\nb = 1\n", "nested more than 32 deep at a.a.a"),
        (
            "[[guidance.waypoints]]\neast_m = 1\n",
            "guidance.waypoints.0.north_m: required field is missing",
        ),
        (
            "[guidance]\nwaypoints = [1]\n",
            "guidance.waypoints.0 = 1: must be a table with east_m, north_m (required)",
        ),
        ("[guidance]\nwaypoints = []\n", "guidance.waypoints = []: must have at least 1 element"),
    ],
    ids=["deep-array", "deep-inline-table", "deep-header", "waypoint", "waypoint-type", "empty"],
)
def test_a_hostile_or_bad_scenario_file_is_one_line_and_exit_2(tmp_path, text, pattern):
    f = tmp_path / "s.toml"
    f.write_text(text)
    out = tmp_path / "out"
    res = bauv("run", "mission/short", "--out", str(out), "--scenario", str(f), cwd=tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and pattern in lines[0], res.stderr[-2000:]
    assert "Traceback" not in res.stderr and "Tuple should" not in res.stderr
    assert not out.exists() and not (tmp_path / "runs").exists()


@pytest.mark.slow
def test_a_bad_waypoint_override_is_one_line(tmp_path):
    res = bauv("show", "mission/short", "--set", 'guidance.waypoints=[{east_m="x", north_m=1}]')
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "guidance.waypoints.0.east_m = 'x': must be a number, not a string" in lines[0]
