"""Terrain-relative navigation (issue 23, check 5): a particle filter of 10,000 particles over a
one-hour mission must run at 100x real time or more on one core (<= 36 s).

The mission: a DVL of four Janus beams (30 deg, footprints 11.5 m from the vehicle 20 m above the
seabed) pinging at 1 Hz for 3,600 s, the vehicle at (0.5, 0.2) m/s over the tests' analytic toy
terrain (``tests/nav/trn/toy.py``) on a 2 km x 2 km map of 2 m cells; each second one prediction
(dead-reckoned displacement, 0.05 m noise) and one update. The pings are made beforehand
(not timed). Variants, interleaved by :func:`harness.measure`:

* ``nav.trn.ParticleTrn``: the library's filter (bias-marginalised likelihood, windowed-NIS
  divergence test, systematic resampling with roughening);
* ``plain numpy PF``: the straightforward numpy particle filter a reader would write first, the
  reference measured in the same run: per-particle bilinear interpolation with ``np.floor`` and
  2-D fancy indexing, independent-beam Gaussian likelihood, ``rng.choice`` (multinomial)
  resampling when the effective sample size falls below half.

Both are single-threaded numpy (the BLAS thread count is set to 1 before numpy loads). Times are
per mission; ``x real time`` is 3,600 s over the mission's time.

Usage: ``python benchmarks/bench_trn.py [--particles 10000] [--steps 3600] [--repeats 3]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
for _p in (str(ROOT), str(ROOT / "benchmarks")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import numpy as np  # noqa: E402
from harness import machine, measure, table  # noqa: E402

from nav.trn import ParticleTrn, TerrainMap, TrnOptions  # noqa: E402
from tests.nav.trn.toy import dvl_offsets, ping, terrain_depth  # noqa: E402

SIGMA_M = 0.3
STEP_M = np.array([0.5, 0.2])
Q_M2 = 0.05**2 * np.eye(2)
P0_M2 = 4.0 * np.eye(2)
START = np.array([100.0, 300.0])


def mission(steps: int):
    """The map, the true track's pings ``(steps,)`` and the final truth."""
    x = np.arange(0.0, 2001.0, 2.0)
    tmap = TerrainMap(x, x, terrain_depth(x[None, :], x[:, None]))
    rng = np.random.default_rng(1)
    truth = START.copy()
    pings = []
    for _ in range(steps):
        truth = truth + STEP_M + rng.normal(0.0, 0.05, 2)
        pings.append(ping(tmap, truth, rng, SIGMA_M))
    return tmap, pings, truth


def library(tmap, pings, n: int) -> np.ndarray:
    f = ParticleTrn(TrnOptions(particles=n), START, P0_M2, 7)
    for s in pings:
        f.predict(STEP_M, Q_M2)
        f.update(tmap, s, SIGMA_M)
    return f.estimate()[0]


def plain(tmap, pings, n: int) -> np.ndarray:
    """The straightforward numpy particle filter (the reference)."""
    rng = np.random.default_rng(7)
    z = tmap.depth_m
    x0, y0, dx, dy = tmap.x_m[0], tmap.y_m[0], tmap.dx_m, tmap.dy_m
    nx, ny = tmap.x_m.size, tmap.y_m.size
    off = dvl_offsets()
    p = START + rng.normal(size=(n, 2)) * 2.0
    w = np.full(n, 1.0 / n)
    for s in pings:
        p = p + STEP_M + rng.normal(size=(n, 2)) * 0.05
        hx = p[:, 0:1] + off[None, :, 0]
        hy = p[:, 1:2] + off[None, :, 1]
        fx = (hx - x0) / dx
        fy = (hy - y0) / dy
        ix = np.clip(np.floor(fx).astype(int), 0, nx - 2)
        iy = np.clip(np.floor(fy).astype(int), 0, ny - 2)
        u = fx - ix
        v = fy - iy
        pred = (
            z[iy, ix] * (1 - u) * (1 - v)
            + z[iy, ix + 1] * u * (1 - v)
            + z[iy + 1, ix] * (1 - u) * v
            + z[iy + 1, ix + 1] * u * v
        )
        e = s.depth_m[None, :] - pred
        ll = -0.5 * np.sum(e * e, axis=1) / SIGMA_M**2
        w = w * np.exp(ll - ll.max())
        w = w / w.sum()
        if 1.0 / np.sum(w * w) < n / 2:
            idx = rng.choice(n, n, p=w)
            p = p[idx]
            w = np.full(n, 1.0 / n)
    return w @ p


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=3600)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    print(machine())
    tmap, pings, truth = mission(a.steps)
    err_lib = np.hypot(*(library(tmap, pings, a.particles) - truth))
    err_plain = np.hypot(*(plain(tmap, pings, a.particles) - truth))
    print(
        f"\n{a.particles} particles, {a.steps} pings of 4 beams at 1 Hz; final error "
        f"nav.trn {err_lib:.2f} m, plain {err_plain:.2f} m\n"
    )
    res = measure(
        {
            "nav.trn.ParticleTrn": lambda: library(tmap, pings, a.particles),
            "plain numpy PF": lambda: plain(tmap, pings, a.particles),
        },
        repeats=a.repeats,
        warmup=0,  # each ran once above (the final errors): that was the warm-up
    )
    print(table(res, reference="plain numpy PF", unit="s per mission"))
    for r in res.values():
        print(
            f"{r.name}: {a.steps / r.min:.0f}x real time (min), {a.steps / r.median:.0f}x "
            f"(median); target >= 100x"
        )


if __name__ == "__main__":
    main()
