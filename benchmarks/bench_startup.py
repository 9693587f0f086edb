"""Start-up cost of the CLI: ``bauv list`` and a one-run kinematic batch (``paper-000/test-1 --runs
1``, figures and recording off), as whole processes, against a bare interpreter start and
optionally against another checkout (``--reference DIR``, e.g. the code before a change), all
interleaved in one run through the shared harness.

Usage: ``python benchmarks/bench_startup.py [--reference DIR] [--repeats 7]``
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from harness import command, machine, measure, table

ROOT = Path(__file__).resolve().parents[1]


def variants(checkout: Path, label: str, tmp: Path) -> dict:
    env = {"PYTHONPATH": str(checkout)}
    cli = [sys.executable, "-m", "tasks.core.cli"]
    k = iter(range(10**6))

    def run_one() -> None:
        command(
            [*cli, "run", "paper-000/test-1", "--runs", "1", "--quiet"]
            + ["--set", "report.figures=false", "--set", "report.recording=false"]
            + ["--out", str(tmp / f"{label}-{next(k)}")],
            env,
            checkout,
        )()

    return {
        f"bauv list ({label})": command([*cli, "list"], env, checkout),
        f"one run ({label})": run_one,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reference", type=Path, default=None, help="another checkout to compare")
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s)
        v = {"python -c pass": command([sys.executable, "-c", "pass"])}
        v |= variants(ROOT, "this checkout", tmp)
        if a.reference is not None:
            v |= variants(a.reference.resolve(), "reference", tmp)
        res = measure(v, repeats=a.repeats, warmup=1)
        ref = "bauv list (reference)" if a.reference is not None else "python -c pass"
        print(table(res, reference=ref, unit="s"))
        if a.reference is not None:
            for what in ("bauv list", "one run"):
                new, old = res[f"{what} (this checkout)"], res[f"{what} (reference)"]
                print(
                    f"{what}: this checkout / reference = {new.median / old.median:.2f} (median), "
                    f"{new.min / old.min:.2f} (min)"
                )
    os.sync()


if __name__ == "__main__":
    main()
