"""Speed of the manoeuvring model (issue 27): vehicle-seconds simulated per wall second for
batches of 1, 100 and 1000 runs, against the full MuJoCo model flying the same swim.

Every run flies 60 s at the missions' 0.2 s control tick (2 Runge-Kutta substeps) with its own
tail-beat frequency and bias (a spread of straight swims and turns), fins at a fixed angle. The
reference variant is the full model (one vehicle, 4 ms step, 0.2 s ticks) flying the same 60 s
at the cruise frequency and 10 deg of bias. The manoeuvring model's tick is compiled
(:mod:`bauv_sim.manoeuvring.kernel`); its numpy implementation of the same equations
(``ManoeuvringWorld._step_numpy``, the tests' reference) flies 1 and 1000 runs beside it. Variants
are interleaved by
:func:`harness.measure`; the table gives each variant's time per vehicle-second and the full
model's time over it (> 1: the manoeuvring model is faster per vehicle).

Run from the repository root::

    python benchmarks/bench_manoeuvring.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from harness import machine, measure, table

SECONDS = 60.0


def manoeuvring(n: int, numpy_step: bool = False):
    """A call flying n runs for :data:`SECONDS` (``numpy_step``: the numpy implementation)."""
    from bauv_sim.manoeuvring import model as mm
    from bauv_sim.manoeuvring import trials

    coef = mm.load_coefficients()
    rng = np.random.default_rng(27)
    f = rng.uniform(0.4, 1.2, n)
    b = rng.uniform(-0.3, 0.3, n)

    def run() -> None:
        w = trials.start(coef, n=n, tick_s=0.2)
        w.command(f, b, 0.05, 0.05)
        if numpy_step:
            for _ in range(round(SECONDS / w.tick_s)):
                w._step_numpy()
        else:
            w.advance(SECONDS)

    return run


def full_model():
    """A call flying the full model for :data:`SECONDS`."""
    from bauv_sim import manoeuvres

    def run() -> None:
        p = manoeuvres.open_water_scene(speed_m_s=1.0)
        p.set_timestep(0.004, control_tick_s=0.2)
        p.set_tail_beat_frequency_hz(0.61)
        p.set_tail_bias_rad(math.radians(10.0))
        p.set_lateral_fins_rad(0.05, 0.05)
        p.advance(SECONDS)

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    sizes = (1, 100, 1000)
    variants = {"full model (1 vehicle)": full_model()}
    per = {"full model (1 vehicle)": SECONDS}
    for n in sizes:
        variants[f"manoeuvring, n_runs = {n}"] = manoeuvring(n)
        per[f"manoeuvring, n_runs = {n}"] = n * SECONDS
    for n in (1, 1000):
        variants[f"manoeuvring, numpy step, n_runs = {n}"] = manoeuvring(n, numpy_step=True)
        per[f"manoeuvring, numpy step, n_runs = {n}"] = n * SECONDS
    res = measure(variants, repeats=args.repeats, warmup=1, per=per)
    print(machine())
    print(table(res, reference="full model (1 vehicle)", unit="ms per vehicle-second", scale=1e3))
    for name, r in res.items():
        best = min(r.seconds) / r.per
        print(
            f"{name}: {1.0 / best:,.0f} vehicle-seconds per wall second (best of {len(r.seconds)})"
        )
    for n in (1, 1000):
        a, b = res[f"manoeuvring, numpy step, n_runs = {n}"], res[f"manoeuvring, n_runs = {n}"]
        print(f"n_runs = {n}: numpy step / compiled step {a.min / b.min:.1f} (min), "
              f"{a.median / b.median:.1f} (median)")  # fmt: skip


if __name__ == "__main__":
    main()
