"""Seed 000 at scale: 10,000 passages of test-1, and the batched EKF against a filterpy loop.

Prints, measured in the same run:

* the wall time and peak resident memory of ``paper-000/test-1`` with 10,000 passages (600 s at
  1 Hz, USBL every 5 s) through the runner, and of 1,000 passages (memory must stay bounded:
  statistics are streamed block by block, not all paths held);
* the EKF cost per path-step of the batched filter (blocks of 1,000 paths), of the same filter
  predicting step by step (the code before), and of filterpy's ``ExtendedKalmanFilter`` looped
  path by path on a subset, on the same inputs: interleaved repeats after a warm-up, min and
  median, ratios to the filterpy loop (target: batched at least 100x faster), through
  ``benchmarks/harness.py``.

Usage: ``python benchmarks/bench_paper000.py [--passages 10000] [--workers 1] [--subset 20]
[--repeats 7] [--ekf-only]``
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
from harness import machine, measure, table

from nav.ekf import BatchEKF
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


def ekf_variants(subset: int, batch: int = 1000) -> tuple[dict, dict]:
    """The EKF of test-1 three ways on the same measured inputs: the shipped batched filter
    (predictions as running sums between fixes), the batched filter predicting step by step (the
    code before the running sums, kept here as a reference), and filterpy's
    ``ExtendedKalmanFilter`` looped path by path over a subset. The filterpy loop gets the
    process noise and displacement of every step precomputed (they are inputs, not filterpy's
    work); its updates call the same USBL model as the batch.

    Returns:
        ``(variants, per)``: name -> call, name -> path-steps of one call.
    """
    scn = plan_batch("paper-000/test-1").scenario
    tick = scn.passage.tick_s
    inp = measure_passages(scn, 1, tuple(range(batch)))
    n, T, _ = inp.u.shape
    fix = {int(k): j for j, k in enumerate(inp.fix_tick)}
    usbl, motion = inp.usbl, inp.motion
    Q = motion.Q(inp.u[:subset], tick)
    inc = motion.increment(inp.u[:subset], tick)
    R = usbl.R()

    def stepwise() -> None:
        ekf = BatchEKF(motion)
        x, P = np.array(inp.x0, dtype=float), np.broadcast_to(inp.P0, (n, 3, 3)).copy()
        xs, Ps = np.empty((n, T + 1, 3)), np.empty((n, T + 1, 3, 3))
        xs[:, 0], Ps[:, 0] = x, P
        for k in range(T):
            x, P = ekf.predict(x, P, inp.u[:, k], tick)
            j = fix.get(k + 1)
            if j is not None:
                x, P, _ = ekf.update(x, P, usbl, inp.z[:, j], inp.z_produced[:, j], None)
            xs[:, k + 1], Ps[:, k + 1] = x, P

    def stacked() -> None:
        # the shipped kernel before the structure-of-arrays update (time-major tracks, updates
        # through nav.ekf.update on stacked 3 x 3 matrices), kept here as a reference
        ekf = BatchEKF(motion)
        inc_all, Q_all = motion.increment_and_Q(
            np.ascontiguousarray(np.swapaxes(inp.u, 0, 1)), tick
        )
        xs, Ps = np.empty((T + 1, n, 3)), np.empty((T + 1, n, 3, 3))
        xs[0], Ps[0] = inp.x0, inp.P0
        for k in range(T):
            np.add(xs[k], inc_all[k], out=xs[k + 1])
            np.add(Ps[k], Q_all[k], out=Ps[k + 1])
            j = fix.get(k + 1)
            if j is not None:
                xs[k + 1], Ps[k + 1], _ = ekf.update(
                    xs[k + 1], Ps[k + 1], usbl, inp.z[:, j], inp.z_produced[:, j], None
                )

    def filterpy_loop() -> None:
        for i in range(subset):
            ekf = ExtendedKalmanFilter(dim_x=3, dim_z=3, dim_u=3)
            ekf.x, ekf.P, ekf.F, ekf.B, ekf.R = (
                inp.x0[i].copy(),
                inp.P0.copy(),
                np.eye(3),
                np.eye(3),
                R,
            )
            for k in range(T):
                ekf.Q = Q[i, k]
                ekf.predict(u=inc[i, k])
                j = fix.get(k + 1)
                if j is not None and inp.z_produced[i, j]:
                    ekf.update(
                        inp.z[i, j],
                        HJacobian=lambda x: usbl.H(x[None])[0],
                        Hx=lambda x: usbl.h(x[None])[0],
                        residual=lambda a, b: usbl.residual(a[None], b[None])[0],
                    )

    variants = {
        f"batched EKF ({n:,} paths)": lambda: run_ekf(inp, tick),
        f"batched, stacked 3x3 update ({n:,} paths)": stacked,
        f"batched, step-by-step predict ({n:,} paths)": stepwise,
        f"filterpy loop ({subset} paths)": filterpy_loop,
    }
    per = dict(zip(variants, (n * T, n * T, n * T, subset * T), strict=True))
    return variants, per


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--passages", type=int, default=10_000)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--subset", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--ekf-only", action="store_true", help="only the EKF per path-step table")
    a = ap.parse_args()
    print(machine())
    variants, per = ekf_variants(a.subset)
    res = measure(variants, repeats=a.repeats, warmup=1, per=per)
    ref = list(variants)[-1]
    print("EKF per path-step (us):")
    print(table(res, reference=ref, unit="us", scale=1e6))
    if a.ekf_only:
        return
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
