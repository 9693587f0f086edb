"""CMNF training at the paper's scale (seed 004: 1e5 paths x 300 steps, the CMNF in the loop), the
batched training against a per-path loop on a subset, and the training's peak memory.

The batched variant is :func:`tasks.paper004.sim.train_gains` (:func:`nav.bearings.cmnf.train` on
:mod:`bauv_sim.kinematic.seed004`: one step at a time over all paths, moments from the current
step only). The per-path loop does the same algorithm path by path: each step it controls,
advances, predicts and observes every path alone (the project's functions on one-row arrays) and
accumulates the moments as running sums, then fits the gains from the sums. Times are per
path-step. Peak memory is the process's maximum RSS after the batched run (the inputs of one
step: ~1e5 x 11 numbers; no path history is kept).

Usage: ``python benchmarks/bench_cmnf.py [--paths 100000] [--steps 300] [--subset 200]
[--repeats 3]``
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np
from harness import machine, measure, table

from bauv_sim.kinematic.seed004 import (
    SECTION6_BEACONS,
    NominalPathConfig,
    Seed004Noise,
    Seed004World,
    TrainingNoise,
    true_bearings,
)
from nav.bearings import SystemPrediction, pinv_floor, velocity
from nav.bearings.cmnf import beta
from nav.bearings.local_control import optimal_control
from tasks.paper004.sim import LoopSetting, train_gains


def per_path_training(s: LoopSetting, seed: int) -> None:
    """The CMNF training as a per-path loop (moments as running sums; same algorithm)."""
    path, noise, b = s.path, s.noise, s.b
    n = s.train_paths
    draws = TrainingNoise(noise, len(b), seed, n)
    world = Seed004World(path, noise, b, draws)
    xn, vn = path.path(), path.velocities()
    pred = SystemPrediction(path.dt_s, noise.s_w)
    x = world.start()
    x_hat = np.broadcast_to(xn[0], (n, 3)).copy()
    for k in range(path.n_steps):
        w = draws.w_at(k)
        eps = draws.eps_at(k + 1)
        alphas = np.empty((n, 3))
        for i in range(n):
            u = optimal_control(x_hat[i : i + 1], xn[k], vn[k], path.dt_s)
            alphas[i] = x_hat[i] + pred(k, x_hat[i : i + 1], u).displacement_m[0]
            x[i] = x[i] + velocity(u)[0] * path.dt_s + w[i]
        sx, sa, sxa, saa = np.zeros(3), np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))
        for i in range(n):
            sx += x[i]
            sa += alphas[i]
            sxa += np.outer(x[i], alphas[i])
            saa += np.outer(alphas[i], alphas[i])
        ma, mx = sa / n, sx / n
        F = (sxa / n - np.outer(mx, ma)) @ pinv_floor(saa / n - np.outer(ma, ma), s.floor)
        f = mx - F @ ma
        x_t = np.empty((n, 3))
        bs = np.empty((n, 2 * len(b)))
        for i in range(n):
            x_t[i] = F @ alphas[i] + f
            h, ok = true_bearings(x[i : i + 1], b, noise.min_rho_m, noise.max_tan)
            y = np.where(ok[..., None], h + eps[i : i + 1], 0.0)
            bs[i] = beta("residual", x_t[i : i + 1], y, ok, b)[0]
        se, sb = np.zeros(3), np.zeros(bs.shape[1])
        seb, sbb = np.zeros((3, bs.shape[1])), np.zeros((bs.shape[1],) * 2)
        for i in range(n):
            e = x[i] - x_t[i]
            se += e
            sb += bs[i]
            seb += np.outer(e, bs[i])
            sbb += np.outer(bs[i], bs[i])
        mb, me = sb / n, se / n
        H = (seb / n - np.outer(me, mb)) @ pinv_floor(sbb / n - np.outer(mb, mb), s.floor)
        for i in range(n):
            x_hat[i] = x_t[i] + H @ (bs[i] - mb)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--paths", type=int, default=100_000)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--subset", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    print(machine())
    path = NominalPathConfig(duration_s=float(a.steps))

    def setting(n: int) -> LoopSetting:
        return LoopSetting(path, Seed004Noise(), SECTION6_BEACONS, train_paths=n)

    full, sub = setting(a.paths), setting(a.subset)
    load0 = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    _, trace = train_gains(full, 1)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"\nCMNF training, {a.paths} paths x {a.steps} steps (batched, CMNF in the loop): "
        f"{wall:.1f} s wall (target < 60 s), {cpu:.1f} s CPU; peak RSS {rss_mb:.0f} MB; "
        f"training J-bar {trace.j.max():.2f} m^2 at k = {int(trace.j.argmax())}\n"
    )
    work = a.subset * a.steps
    res = measure(
        {
            f"batched ({a.subset} paths)": lambda: train_gains(sub, 1),
            f"per-path loop ({a.subset} paths)": lambda: per_path_training(sub, 1),
        },
        repeats=a.repeats,
        warmup=1,
        per={f"batched ({a.subset} paths)": work, f"per-path loop ({a.subset} paths)": work},
    )
    res_full = {"batched full": res[f"batched ({a.subset} paths)"]}
    res_full["batched full"] = type(res_full["batched full"])(
        f"batched ({a.paths} paths, one run)", a.paths * a.steps, [wall], [load0]
    )
    print(
        table(
            {**res, **res_full}, reference=f"per-path loop ({a.subset} paths)", unit="us", scale=1e6
        )
    )


if __name__ == "__main__":
    main()
