"""Seed 000 at scale: scaling with workers, memory with the batch, and the batched EKF.

Prints, measured in the same run (issue 13, check 1 and 3):

* ``paper-000/test-1`` (600 s at 1 Hz, USBL every 5 s; figures and recording off) with
  ``--passages`` runs on 1 and on 2 workers: the whole ``bauv run`` command as a user types it
  (``python -m tasks.core.cli run ...``, a fresh process: interpreter, imports, plan, fork server,
  blocks, report, exit), interleaved through :mod:`harness` (warm-up, min and median of
  ``--repeats``, the machine's load beside each), and with ``--reference DIR`` the same two
  commands of another checkout (e.g. the code before a change) in the same rotation;
* one 1-worker ``bauv run`` of ``--big`` runs: its wall time; and the peak resident memory of
  ``bauv`` (which computes the blocks on one worker) at ``--passages / 10``, ``--passages`` and
  ``--big`` runs, with the growth per 100,000 runs between the two largest and the 1e6-run peak
  extrapolated on that line;
* the EKF cost per path-step of the shipped filter (blocks of 1,000 paths), of the kernel before
  it (stacked 3 x 3 updates), of the same filter predicting step by step, and of filterpy's
  ``ExtendedKalmanFilter`` looped path by path on a subset, on the same inputs: interleaved
  repeats after a warm-up, min and median, ratios to the filterpy loop (target: at least 100x).

Usage: ``python benchmarks/bench_paper000.py [--passages 10000] [--big 100000] [--subset 20]
[--repeats 5] [--ekf-only] [--no-scaling] [--scaling-only] [--reference DIR]``
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from harness import command, machine, measure, table

from nav.ekf import BatchEKF
from tasks.core.runner import plan_batch
from tasks.paper000.passage import measure_passages, run_ekf

ROOT = Path(__file__).resolve().parents[1]
FAST = ["report.figures=false", "report.recording=false"]


def batch_run(passages: int, workers: int) -> tuple[float, float]:
    """One ``bauv run`` command in a fresh process (as :func:`cli_batch` runs it): its wall time
    (s) and its peak resident memory (MB; with one worker bauv computes the blocks itself)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1", "--quiet"]
        cmd += ["--runs", str(passages), "--workers", str(workers), "--out", str(Path(tmp) / "r")]
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            cmd + [f"--set={s}" for s in FAST], cwd=ROOT, stdout=subprocess.DEVNULL
        )
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            raise RuntimeError(f"{' '.join(cmd)}: exit status {proc.returncode}")
    return wall, usage.ru_maxrss / 1024


def cli_batch(checkout: Path, passages: int, workers: int, tmp: Path):
    """A variant: ``bauv run paper-000/test-1 --runs passages --workers workers`` (figures and
    recording off) as a whole command in a fresh process, from ``checkout``."""
    env = {"PYTHONPATH": str(checkout)}
    k = iter(range(10**6))

    def run() -> None:
        out = tmp / f"{checkout.name}-{workers}-{next(k)}"
        command(
            [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1", "--quiet"]
            + ["--runs", str(passages), "--workers", str(workers), "--out", str(out)]
            + [f"--set={s}" for s in FAST],
            env,
            checkout,
        )()
        shutil.rmtree(out)

    return run


def scaling(passages: int, repeats: int, reference: Path | None) -> None:
    """1 against 2 workers as whole ``bauv run`` commands, interleaved through the harness
    (optionally with the same commands of another checkout in the same rotation)."""
    checkouts = {"": ROOT} | ({" (reference)": reference.resolve()} if reference else {})
    with tempfile.TemporaryDirectory() as tmp_s:
        variants = {}
        for label, checkout in checkouts.items():
            for w in (1, 2):
                name = f"{w} worker{'s' if w > 1 else ''}{label}"
                variants[name] = cli_batch(checkout, passages, w, Path(tmp_s))
        res = measure(variants, repeats=repeats, warmup=1)
    print(f"paper-000/test-1, {passages:,} passages, figures and recording off, whole command:")
    print(table(res, reference="1 worker", unit="s"))
    for label in checkouts:
        one, two = res[f"1 worker{label}"], res[f"2 workers{label}"]
        lo, hi = min(one.load + two.load), max(one.load + two.load)
        print(
            f"speed-up of 2 workers{label}: {one.median / two.median:.2f}x by the medians, "
            f"{one.min / two.min:.2f}x by the minima (target 1.7x); load {lo:.2f}-{hi:.2f}"
        )


def _block(index: int) -> int:
    """Compute and encode block ``index`` of 1,000 passages (a worker's share of the runner's
    work: no file, no report); returns the encoded size."""
    from tasks.core import store

    exp = plan_batch("paper-000/test-1", overrides=FAST)
    runs = tuple(range(index * 1000, (index + 1) * 1000))
    return len(store.dumps(exp.experiment.run_block(exp.scenario, 1, runs), {}))


def ceiling(passages: int, repeats: int) -> None:
    """The blocks alone, on warm worker processes: ``passages / 1000`` blocks on a pool of one
    worker against a pool of two, interleaved (no interpreter start, imports, plan, files,
    report): how much two workers can gain on this machine at best."""
    from tasks.core import workers
    from tasks.core.runner import make_executor

    workers.prepare_batch_process()  # the workers' settings under bauv run
    blocks = range(max(1, passages // 1000))
    with make_executor("local", 2, None, ("tasks.paper000",)) as pool:

        def on_one() -> None:  # one block at a time: one worker busy
            for i in blocks:
                pool.submit(_block, i).result()

        def on_two() -> None:
            list(pool.map(_block, blocks))

        list(pool.map(_block, range(4)))  # start and warm both workers
        res = measure({"1 worker": on_one, "2 workers": on_two}, repeats=repeats, warmup=1)
    print(f"the blocks alone ({len(blocks)} blocks of 1,000 passages, warm workers):")
    print(table(res, reference="1 worker", unit="s"))
    one, two_ = res["1 worker"], res["2 workers"]
    print(
        f"blocks alone, 2 workers against 1: {one.median / two_.median:.2f}x by the medians, "
        f"{one.min / two_.min:.2f}x by the minima"
    )


def memory(passages: int, big: int) -> None:
    """Peak RSS against the batch size on 1 worker, and the wall time of the big batch."""
    sizes = sorted({max(passages // 10, 1000), passages, big})
    peaks = {}
    for n in sizes:
        load = os.getloadavg()[0]
        wall, mb = batch_run(n, 1)
        peaks[n] = mb
        print(
            f"{n:>9,} passages, 1 worker: wall {wall:.1f} s, peak RSS {mb:.0f} MB, load {load:.2f}"
        )
    # the growth between the two largest batches (the smallest may be a single block)
    (n1, p1), (n2, p2) = [(n, peaks[n]) for n in sizes[-2:]]
    slope = (p2 - p1) / (n2 - n1)
    at_1e6 = p2 + slope * (1e6 - n2)
    print(
        f"peak RSS grows {slope * 1e5:.1f} MB per 100,000 passages ({n1:,} to {n2:,}); "
        f"extrapolated 1e6: {at_1e6:.0f} MB ({at_1e6 / peaks[passages]:.2f}x the peak at "
        f"{passages:,})"
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
    ap.add_argument(
        "--reference", type=Path, default=None, help="another checkout in the workers' rotation"
    )
    ap.add_argument("--scaling-only", action="store_true", help="only 1 against 2 workers")
    a = ap.parse_args()
    print(machine())
    if a.scaling_only:
        ceiling(a.passages, a.repeats)
        scaling(a.passages, a.repeats, a.reference)
        return
    variants, per = ekf_variants(a.subset)
    res = measure(variants, repeats=a.repeats, warmup=1, per=per)
    ref = list(variants)[-1]
    print("EKF per path-step (us):")
    print(table(res, reference=ref, unit="us", scale=1e6))
    if a.ekf_only:
        return
    if not a.no_scaling:
        ceiling(a.passages, a.repeats)
        scaling(a.passages, a.repeats, a.reference)
    memory(a.passages, a.big)


if __name__ == "__main__":
    main()
