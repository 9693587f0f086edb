"""Where a Dask cluster starts to pay: ``paper-000/test-1`` (figures and recording off) through the
CLI on one local worker, on two local workers, and on a loopback cluster (a scheduler and two
single-threaded workers as separate processes, started once and kept warm), for growing batches.

Every variant is a whole ``bauv run`` process, timed by the shared harness (interleaved, warm-up,
repeats, min and median, load beside each); the ratios are to one local worker at the same batch
size. Usage: ``python benchmarks/bench_cluster.py [--runs 500 2000 10000] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import command, machine, measure, table

ROOT = Path(__file__).resolve().parents[1]


def _cluster(tmp: Path) -> tuple[str, list[subprocess.Popen]]:
    """Start a scheduler and two workers on 127.0.0.1; returns the address and the processes."""
    dask = str(Path(sys.executable).with_name("dask"))
    sched_file = tmp / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": ROOT, "env": env}
    procs = [
        subprocess.Popen(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"]
            + ["--scheduler-file", str(sched_file)],
            **quiet,
        )
    ]
    while not sched_file.exists() or sched_file.stat().st_size == 0:
        time.sleep(0.1)
    for _ in range(2):
        procs.append(
            subprocess.Popen(
                [dask, "worker", "--scheduler-file", str(sched_file), "--host", "127.0.0.1"]
                + ["--nthreads", "1", "--nworkers", "1", "--no-dashboard"],
                **quiet,
            )
        )
    from distributed import Client

    with Client(scheduler_file=str(sched_file)) as c:
        c.wait_for_workers(2, timeout=120)
    return json.loads(sched_file.read_text())["address"], procs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, nargs="+", default=[500, 2000, 10000])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--blocks", type=int, default=8, help="blocks per batch (work to share)")
    a = ap.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s)
        address, procs = _cluster(tmp)
        try:
            counter = iter(range(10**6))
            for n in a.runs:
                size = max(1, -(-n // a.blocks))
                base = [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1"]
                base += ["--runs", str(n), "--quiet", "--set", "report.figures=false"]
                base += ["--set", "report.recording=false"]
                base += ["--set", f"runner.block_size={size}"]

                def run(extra: list[str], b: list[str] = base, k=counter) -> None:
                    command([*b, *extra, "--out", str(tmp / f"r{next(k)}")])()

                variants = {
                    "1 local worker": lambda: run([]),
                    "2 local workers": lambda: run(["--workers", "2"]),
                    "loopback cluster, 2 workers": lambda: run(
                        ["--executor", "dask", "--address", address]
                    ),
                }
                res = measure(variants, repeats=a.repeats, warmup=1)
                print(f"\n{n:,} runs (blocks of {size}), wall time per batch:")
                print(table(res, reference="1 local worker", unit="s"))
        finally:
            for p in procs[::-1]:
                p.terminate()
            for p in procs[::-1]:
                p.wait(timeout=30)


if __name__ == "__main__":
    main()
