"""Golden outputs: record the ``metrics.json`` of a fixed set of runs, and compare against them.

A redesign that should not change behaviour is checked by running the same commands before and
after and comparing every number. ``record`` writes the metrics of each run into
``benchmarks/golden/<name>.json``; ``compare`` runs the same commands again and reports, per run,
whether the metrics are identical bit for bit, and otherwise the largest relative difference of
any number with the fields where it occurs (a difference above ``--tolerance`` fails).

Usage::

    .venv/bin/python benchmarks/golden.py record            # before the change
    .venv/bin/python benchmarks/golden.py compare           # after it (exit 1 on a difference)
    .venv/bin/python benchmarks/golden.py compare --only mission/survey paper-000/test-1

Strings (file names, failure messages) must be equal; numbers are compared as floats, NaN equal
to NaN. The commands run through the ``bauv`` CLI of this checkout (``python -m tasks.core.cli``),
with the checkout as working directory.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
GOLDEN_DIR = HERE / "golden"

# name of the golden file -> arguments of `bauv run`
RUNS: dict[str, list[str]] = {
    "paper-000_test-1": ["paper-000/test-1", "--runs", "100", "--seed", "1"],
    "paper-000_test-2": ["paper-000/test-2", "--runs", "100", "--seed", "1"],
    "paper-000_test-3": ["paper-000/test-3", "--runs", "100", "--seed", "1"],
    "paper-000_accuracy": ["paper-000/accuracy"],
    "paper-001_replica": ["paper-001/replica", "--seed", "1"],
    "paper-003_test-1": ["paper-003/test-1", "--runs", "100", "--seed", "1"],
    "paper-003_test-2": ["paper-003/test-2", "--runs", "100", "--seed", "1"],
    "paper-003_test-3": ["paper-003/test-3", "--runs", "100", "--seed", "1"],
    "mission_survey": ["mission/survey", "--seed", "0"],
    "mission_correction": ["mission/correction", "--runs", "2", "--seed", "0"],
    "vehicle_autopilot": ["vehicle/autopilot"],
    # seed 004 and the richer missions at small sizes (recorded after issue 21, before issue 22's
    # redesign of nav and tasks)
    "paper-004_table-1": ["paper-004/table-1", "--runs", "1000", "--seed", "1"]
    + ["--set", "filters.train_paths=2000"],
    "paper-004_near-beacon": ["paper-004/near-beacon", "--runs", "1000", "--seed", "1"]
    + ["--set", "filters.train_paths=2000"],
    "mission_swarm": ["mission/swarm", "--seed", "1", "--set", "timing.max_duration_s=60"]
    + ["--set", 'navigation.methods=["ekf","ga1","ga2","dr"]'],
    "mission_seed004": ["mission/seed004", "--runs", "1", "--seed", "1"]
    + ["--set", "seed004.duration_s=40", "--set", "timing.max_duration_s=40"]
    + ["--set", "seed004.train_paths=500", "--set", "seed004.surrogate_test_paths=200"],
    # issue 23: the DVL and TRN (recorded when they landed)
    "mission_trn": ["mission/trn", "--runs", "2", "--seed", "1"],
    "trn_relief": ["trn/relief", "--runs", "2", "--seed", "1"],
    # issue 24: the kinematic team (recorded when it landed)
    "coop_team": ["coop/team", "--runs", "4", "--seed", "1"],
}


def _bauv() -> list[str]:
    # the CLI of this checkout (run with the checkout as working directory, so that its packages
    # are imported even when another checkout is installed in the environment)
    return [sys.executable, "-m", "tasks.core.cli"]


def run_metrics(args: list[str]) -> dict:
    """Run ``bauv run ARGS`` into a temporary folder and return its ``metrics.json``."""
    tmp = Path(tempfile.mkdtemp(prefix="golden-"))
    try:
        out = tmp / "run"
        cmd = [*_bauv(), "run", *args, "--quiet", "--out", str(out)]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=ROOT)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stderr[-2000:]}")
        return json.loads((out / "metrics.json").read_text())
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def diff(a, b, path: str = "") -> tuple[list[str], float, list[str]]:
    """Compare two JSON values.

    Returns:
        ``(mismatches, largest relative difference, fields at that difference)``; a mismatch is a
        structural or string difference (always a failure).
    """
    if isinstance(a, dict) and isinstance(b, dict):
        only = [f"{path}/{k}: only in {'golden' if k in a else 'new'}" for k in set(a) ^ set(b)]
        pairs = [(f"{path}/{k}", a[k], b[k]) for k in sorted(set(a) & set(b))]
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} vs {len(b)}"], 0.0, []
        only, pairs = (
            [],
            [(f"{path}[{i}]", x, y) for i, (x, y) in enumerate(zip(a, b, strict=True))],
        )
    else:
        pairs = None
    if pairs is not None:
        bad, worst, where = sorted(only), 0.0, []
        for sub, x, y in pairs:
            m, w, f = diff(x, y, sub)
            bad += m
            if w > worst:
                worst, where = w, f
            elif w == worst and w > 0:
                where += f
        return bad, worst, where
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool | str):
        fa, fb = float(a), float(b)
        if fa == fb or (math.isnan(fa) and math.isnan(fb)):
            return [], 0.0, []
        rel = abs(fa - fb) / max(abs(fa), abs(fb), 1e-300)
        return [], rel, [path]
    if a != b:
        return [f"{path}: {a!r} vs {b!r}"], 0.0, []
    return [], 0.0, []


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("action", choices=["record", "compare"])
    p.add_argument("--only", nargs="*", default=None, help="golden names or experiment names")
    p.add_argument("--tolerance", type=float, default=1e-9, help="largest relative difference")
    a = p.parse_args(argv)
    names = list(RUNS)
    if a.only:
        names = [n for n in names if n in a.only or RUNS[n][0] in a.only]
    GOLDEN_DIR.mkdir(exist_ok=True)
    status = 0
    for name in names:
        metrics = run_metrics(RUNS[name])
        path = GOLDEN_DIR / f"{name}.json"
        if a.action == "record":
            path.write_text(json.dumps(metrics, indent=1, sort_keys=True) + "\n")
            print(f"recorded {name}")
            continue
        golden = json.loads(path.read_text())
        bad, worst, where = diff(golden, metrics)
        if bad:
            status = 1
            print(f"{name}: DIFFERENT ({len(bad)} structural/string differences)")
            for line in bad[:10]:
                print(f"    {line}")
        elif worst == 0.0:
            print(f"{name}: identical bit for bit")
        else:
            ok = worst <= a.tolerance
            status = status or (0 if ok else 1)
            shown = ", ".join(where[:6]) + (f" (+{len(where) - 6} more)" if len(where) > 6 else "")
            print(
                f"{name}: {'within' if ok else 'OUTSIDE'} tolerance: largest relative "
                f"difference {worst:.3g} at {shown}"
            )
    return status


if __name__ == "__main__":
    sys.exit(main())
