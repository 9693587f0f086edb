"""The whole ``bauv run fleet/survey`` command (issue 27, check 2): a thousand one-hour way-point
missions on the manoeuvring model with sensors, EKF, guidance and autopilot, its wall time and
its peak memory, against the full MuJoCo model's ``mission/survey`` per vehicle-hour.

Variants (each a fresh process; interleaved by :func:`harness.measure`):

* ``fleet, W workers``: ``bauv run fleet/survey --runs N --workers W`` with the scenario's
  defaults (N = 1000 by default: the command's default; W from ``--workers``, 1 being the
  command's default);
* ``full model, mission/survey``: ``bauv run mission/survey`` (one run, 18 min simulated), the
  reference per vehicle-hour.

Each variant's peak memory is the largest sum of the resident set sizes of the command's
process tree, sampled every 0.1 s. The table gives wall times per simulated vehicle-hour (the
runs' mission durations from ``metrics.json``) and the full model's time over each variant's.

Run from the repository root (the full check takes about 4 minutes per fleet variant on two
free cores)::

    python benchmarks/bench_fleet.py                       # 1000 runs, workers 1 and 2
    python benchmarks/bench_fleet.py --runs 100 --repeats 3  # under load: a smaller batch
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import machine, measure, table

ROOT = Path(__file__).resolve().parent.parent
BAUV = [sys.executable, "-m", "tasks.core.cli"]


def tree_rss(pid: int) -> int:
    """Resident memory of a process and its descendants, bytes (Linux ``/proc``)."""
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1]) * 1024
            for task in Path(f"/proc/{p}/task").iterdir():
                todo += [int(c) for c in (task / "children").read_text().split()]
        except (OSError, ValueError):
            continue
    return total


def variant(argv: list[str], out: Path, peaks: dict, hours: dict, name: str):
    """A call that runs ``argv`` with ``--out out`` and records its peak memory and the
    vehicle-hours it simulated."""

    def run() -> None:
        if out.exists():
            subprocess.run(["rm", "-rf", str(out)], check=True)
        proc = subprocess.Popen(
            [*argv, "--quiet", "--out", str(out)],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        peak = 0
        while proc.poll() is None:
            peak = max(peak, tree_rss(proc.pid))
            time.sleep(0.1)
        err = proc.stderr.read().decode() if proc.stderr else ""
        if proc.returncode != 0:
            raise RuntimeError(f"{name}: exit {proc.returncode}: {err[-2000:]}")
        peaks.setdefault(name, []).append(peak)
        m = json.loads((out / "metrics.json").read_text())
        if "vehicle_hours" in m:
            hours[name] = float(m["vehicle_hours"])
        else:  # mission/survey: one vehicle
            hours[name] = float(m["aggregate"]["duration_s"]["mean"]) / 3600.0

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=1000, help="fleet runs (the command's default)")
    ap.add_argument("--workers", default="1,2", help="worker counts of the fleet variants")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--no-reference", action="store_true", help="skip the full model's survey")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-fleet-"))
    peaks: dict[str, list[int]] = {}
    hours: dict[str, float] = {}
    variants = {}
    ref = "full model, mission/survey"
    if not args.no_reference:
        variants[ref] = variant([*BAUV, "run", "mission/survey"], tmp / "full", peaks, hours, ref)
    for w in (int(x) for x in args.workers.split(",")):
        name = f"fleet, {args.runs} runs, {w} worker{'s' if w > 1 else ''}"
        argv = [*BAUV, "run", "fleet/survey", "--runs", str(args.runs), "--workers", str(w)]
        variants[name] = variant(argv, tmp / f"fleet{w}", peaks, hours, name)
    # warm-up: one short fleet (imports, the model's data) and nothing else: a full warm-up of
    # every variant would double the benchmark's time for no information
    warm = ["--runs", "2", "--quiet", "--set", "timing.max_duration_s=20"]
    subprocess.run(
        [*BAUV, "run", "fleet/survey", *warm, "--out", str(tmp / "w")], cwd=ROOT, check=True
    )
    res = measure(variants, repeats=args.repeats, warmup=0)
    for name, r in res.items():
        r.per = hours[name]
    print(machine())
    reference = ref if ref in res else next(iter(res))
    print(table(res, reference=reference, unit="s per vehicle-hour"))
    print()
    print(
        "| variant | wall time, min (s) | vehicle-hours | vehicle-hours per wall hour | "
        "peak memory (MB) |"
    )
    print("|---|---|---|---|---|")
    for name, r in res.items():
        best = min(r.seconds)
        print(
            f"| {name} | {best:.1f} | {hours[name]:.1f} | {hours[name] / best * 3600:,.0f} | "
            f"{max(peaks[name]) / 2**20:,.0f} |"
        )
    subprocess.run(["rm", "-rf", str(tmp)], check=False)


if __name__ == "__main__":
    main()
