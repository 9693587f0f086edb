"""Seed 000 at scale: scaling with workers, memory with the batch, and the batched EKF.

Prints, measured in the same run (issue 13, check 1 and 3):

* ``paper-000/test-1`` (600 s at 1 Hz, USBL every 5 s; figures and recording off) with
  ``--passages`` runs on 1 and on 2 workers, interleaved: the whole ``bauv run`` command (a fresh
  interpreter, imports, plan, blocks, report) and, from inside the same process, the batch phase
  alone (``tasks.core.runner.run``: plan, blocks, report; the interpreter's start and the CLI's
  imports left out); min and median of ``--repeats``, the machine's load beside each;
* one 1-worker batch of ``--big`` runs: its wall time; and the peak resident memory (the larger of
  bauv and its workers) at ``--passages / 10``, ``--passages`` and ``--big`` runs, with the growth
  per 100,000 runs and the 1e6-run peak extrapolated on that line;
* the EKF cost per path-step of the shipped filter (blocks of 1,000 paths), of the kernel before
  it (stacked 3 x 3 updates), of the same filter predicting step by step, and of filterpy's
  ``ExtendedKalmanFilter`` looped path by path on a subset, on the same inputs: interleaved
  repeats after a warm-up, min and median, ratios to the filterpy loop (target: at least 100x).

Usage: ``python benchmarks/bench_paper000.py [--passages 10000] [--big 100000] [--subset 20]
[--repeats 5] [--ekf-only] [--no-scaling]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from harness import Result, machine, measure, table

from nav.ekf import BatchEKF
from tasks.core.runner import plan_batch
from tasks.paper000.passage import measure_passages, run_ekf

DRIVER = """
import resource, sys, time
t0 = time.perf_counter()
from tasks.core import runner
t1 = time.perf_counter()
runner.run("paper-000/test-1", int(sys.argv[1]), 1, sys.argv[3], FAST, workers=int(sys.argv[2]),
           progress=False)
t2 = time.perf_counter()
r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
c = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print("PHASE", t2 - t1, "PEAK_KB", max(r, c))
"""
FAST = ["report.figures=false", "report.recording=false"]


def batch_run(passages: int, workers: int) -> tuple[float, float, float]:
    """One batch in a fresh interpreter: wall time of the process (s), of its batch phase (s) and
    its peak RSS (MB, the larger of bauv and its workers)."""
    with tempfile.TemporaryDirectory() as tmp:
        code = f"FAST = {FAST!r}\n" + DRIVER
        t0 = time.perf_counter()
        res = subprocess.run(
            [sys.executable, "-c", code, str(passages), str(workers), str(Path(tmp) / "run")],
            capture_output=True,
            text=True,
            check=True,
        )
        wall = time.perf_counter() - t0
    words = res.stdout.split()
    phase = float(words[words.index("PHASE") + 1])
    peak_kb = int(words[words.index("PEAK_KB") + 1])
    return wall, phase, peak_kb / 1024


def scaling(passages: int, repeats: int) -> None:
    """1 against 2 workers, interleaved (A B B A ...), whole process and batch phase."""
    wall: dict[int, Result] = {w: Result(f"{w} worker(s), whole command", 1.0) for w in (1, 2)}
    phase: dict[int, Result] = {w: Result(f"{w} worker(s), batch phase", 1.0) for w in (1, 2)}
    batch_run(min(passages, 1000), 2)  # warm-up: file caches, the fork server's imports
    for r in range(repeats):
        for w in (1, 2) if r % 2 == 0 else (2, 1):
            load = os.getloadavg()[0]
            t_wall, t_phase, _ = batch_run(passages, w)
            for res, t in ((wall[w], t_wall), (phase[w], t_phase)):
                res.load.append(load)
                res.seconds.append(t)
    print(f"paper-000/test-1, {passages:,} passages, figures and recording off:")
    print(table({**{v.name: v for v in wall.values()}}, reference=wall[2].name))
    print(table({**{v.name: v for v in phase.values()}}, reference=phase[2].name))
    print(
        f"speed-up of 2 workers (median): whole command {wall[1].median / wall[2].median:.2f}x, "
        f"batch phase {phase[1].median / phase[2].median:.2f}x (target 1.7x)"
    )


def memory(passages: int, big: int) -> None:
    """Peak RSS against the batch size on 1 worker, and the wall time of the big batch."""
    sizes = sorted({max(passages // 10, 1000), passages, big})
    peaks = {}
    for n in sizes:
        wall, phase, mb = batch_run(n, 1)
        peaks[n] = mb
        print(
            f"{n:>9,} passages, 1 worker: wall {wall:.1f} s (batch phase {phase:.1f} s), "
            f"peak RSS {mb:.0f} MB, load {os.getloadavg()[0]:.2f}"
        )
    n = np.array(sizes, dtype=float)
    slope, icpt = np.polyfit(n, np.array([peaks[s] for s in sizes]), 1)
    print(
        f"peak RSS grows {slope * 1e5:.1f} MB per 100,000 passages; extrapolated 1e6: "
        f"{icpt + slope * 1e6:.0f} MB ({(icpt + slope * 1e6) / peaks[passages]:.2f}x the "
        f"peak at {passages:,})"
    )


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
    ap.add_argument("--big", type=int, default=100_000)
    ap.add_argument("--no-scaling", action="store_true", help="skip the 1 against 2 workers part")
    ap.add_argument("--subset", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=5)
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
    if not a.no_scaling:
        scaling(a.passages, a.repeats)
    memory(a.passages, a.big)


if __name__ == "__main__":
    main()
