"""Seed 000 at scale: 10,000 passages of test-1, and the batched EKF against a filterpy loop.

Prints, measured in the same run:

* the wall time and peak resident memory of ``paper-000/test-1`` with 10,000 passages (600 s at
  1 Hz, USBL every 5 s) through the runner, and of 1,000 passages (memory must stay bounded:
  statistics are streamed block by block, not all paths held);
* the EKF cost per path-step of the batched filter (blocks of 1,000 paths) and of filterpy's
  ``ExtendedKalmanFilter`` looped path by path on a subset, on the same inputs, and their ratio
  (target: batched at least 30x faster).

Usage: ``python benchmarks/bench_paper000.py [--passages 10000] [--workers 1] [--subset 20]``
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from tasks.core.runner import plan_batch
from tasks.paper000.passage import measure_passages, run_ekf


def batch_run(passages: int, workers: int) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB, the larger of parent and workers) of a CLI batch."""
    with tempfile.TemporaryDirectory() as tmp:
        code = (
            "import resource, sys;"
            "from tasks.core.cli import main;"
            "\ntry:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    assert not e.code\n"
            "r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss;"
            "c = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss;"
            "print('PEAK_KB', max(r, c))"
        )
        t0 = time.perf_counter()
        res = subprocess.run(
            [
                sys.executable,
                "-c",
                code,
                "run",
                "paper-000/test-1",
                "--runs",
                str(passages),
                "--seed",
                "1",
                "--quiet",
                "--out",
                str(Path(tmp) / "run"),
                "--workers",
                str(workers),
                "--set",
                "runner.block_size=1000",
            ],
            capture_output=True,
            text=True,
            check=True,
        )
        wall = time.perf_counter() - t0
    peak_kb = int(res.stdout.split("PEAK_KB")[-1].split()[0])
    return wall, peak_kb / 1024


def ekf_ratio(subset: int, batch: int = 1000) -> tuple[float, float]:
    """Per-path-step EKF time (s) of the batched filter and of a filterpy loop."""
    scn = plan_batch("paper-000/test-1").scenario
    inp = measure_passages(scn, 1, tuple(range(batch)))
    n, T, _ = inp.u.shape
    t0 = time.perf_counter()
    run_ekf(inp, 1.0)
    batched = (time.perf_counter() - t0) / (n * T)

    fix = {int(k): j for j, k in enumerate(inp.fix_tick)}
    usbl, motion = inp.usbl, inp.motion
    t0 = time.perf_counter()
    for i in range(subset):
        ekf = ExtendedKalmanFilter(dim_x=3, dim_z=3, dim_u=3)
        ekf.x, ekf.P, ekf.F, ekf.B, ekf.R = (
            inp.x0[i].copy(),
            inp.P0.copy(),
            np.eye(3),
            np.eye(3),
            usbl.R(),
        )
        for k in range(T):
            uk = inp.u[i : i + 1, k]
            ekf.Q = motion.Q(uk, 1.0)[0]
            ekf.predict(u=motion.increment(uk, 1.0)[0])
            j = fix.get(k + 1)
            if j is not None and inp.z_produced[i, j]:
                ekf.update(
                    inp.z[i, j],
                    HJacobian=lambda x: usbl.H(x[None])[0],
                    Hx=lambda x: usbl.h(x[None])[0],
                    residual=lambda a, b: usbl.residual(a[None], b[None])[0],
                )
    loop = (time.perf_counter() - t0) / (subset * T)
    return batched, loop


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--passages", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--subset", type=int, default=20)
    a = ap.parse_args()
    batched, loop = ekf_ratio(a.subset)
    print(
        f"EKF per path-step: batched {batched * 1e6:.2f} us, filterpy loop {loop * 1e6:.1f} us, "
        f"ratio {loop / batched:.0f}x (target >= 30x)"
    )
    small = max(a.passages // 10, 1000)
    w_small, m_small = batch_run(small, a.workers)
    print(f"{small} passages: wall {w_small:.1f} s, peak RSS {m_small:.0f} MB")
    wall, mem = batch_run(a.passages, a.workers)
    print(
        f"{a.passages} passages: wall {wall:.1f} s, peak RSS {mem:.0f} MB "
        f"({mem / m_small:.2f}x the peak of {small}; workers {a.workers})"
    )
    print(f"self rss {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
