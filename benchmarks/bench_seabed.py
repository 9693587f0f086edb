"""Seed 004's seabed sensing (Table 1, row 2): the ray march against the seed's harmonic seabed,
the rays against a physics scene's heightfield, and a row-2 path-step.

* ``rays``: :meth:`bauv_sim.sensors.multibeam.HarmonicSeabed.ray_ranges` (the curvature-bounded
  march, compiled by numba: ``bauv_sim/sensors/harmonic_march.py``, C until issue 26) against the
  same march in numpy (vectorised over the rays, the implementation before the C one, kept as the
  tests' reference in ``tests/bauv_sim/multibeam_reference.py``) and against the first-order march
  (:meth:`HarmonicSeabed._lipschitz_ranges`, the Lipschitz march and safeguarded Newton that was the
  whole method before that), on seed 004's 8 x 8 beams from 10 m below the surface over seabeds ~30
  m deep (section 6), per ray. All give the same first crossings
  (``tests/bauv_sim/test_multibeam.py``).
* ``heightfield``: :meth:`bauv_sim.seabed.Seabed.ray_ranges` on ``mission/seed004``'s seabed
  against MuJoCo's ``mj_multiRay`` (:meth:`bauv_sim.physics.BauvPhysics.seabed_ray_distances`,
  one image per call as the vehicle's device casts it), per ray.
* ``row2``: one block of ``paper-004/table-1-seabed``'s test paths (:func:`tasks.paper004.sim.fly`,
  the three filters, one reading, gains trained beforehand), per path-step (three filters count
  three), an absolute time beside the load, the same block with the numpy march patched in for
  ``HarmonicSeabed.ray_ranges`` (what the compiled march saves in the row), and with the numpy
  seabed shift patched in for :func:`nav.seabed.shift_estimate` (``tests/nav/seabed_reference.py``,
  the implementation before the compiled one in ``nav/seabed/kernel.py``: what that saves in the
  row).

Usage: ``python benchmarks/bench_seabed.py [--paths 2000] [--steps 60] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for _p in (str(ROOT), str(ROOT / "benchmarks")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import numpy as np  # noqa: E402
from harness import machine, measure, table  # noqa: E402

from bauv_sim.sensors.multibeam import (  # noqa: E402
    HarmonicSeabed,
    MultibeamConfig,
    beam_directions,
)
from tests.bauv_sim import multibeam_reference  # noqa: E402
from tests.nav import seabed_reference  # noqa: E402


def rays(paths: int, repeats: int) -> str:
    """The harmonic seabed's march (compiled: numba) against the numpy march and the first-order
    march, per ray."""
    rng = np.random.default_rng(0)
    bed = HarmonicSeabed.draw(0, tuple(range(paths)))
    cfg = MultibeamConfig()
    o = np.column_stack(
        [rng.uniform(0, 300, paths), rng.uniform(-20, 20, paths), rng.normal(-10, 1, paths)]
    )
    att = np.column_stack([rng.normal(0, 0.05, paths), rng.uniform(-1.1, 1.1, paths)])
    e = beam_directions(cfg, att).reshape(paths, -1, 3)
    path = np.repeat(np.arange(paths), e.shape[1])
    oo = np.repeat(o, e.shape[1], axis=0)
    ee = e.reshape(-1, 3)
    rmax = np.full(len(ee), cfg.max_range_m)
    n = len(ee)
    res = measure(
        {
            "curvature march (compiled)": lambda: bed.ray_ranges(o[:, None], e, cfg.max_range_m),
            "curvature march (numpy)": lambda: multibeam_reference.ray_ranges(
                bed, o[:, None], e, cfg.max_range_m
            ),
            "first-order march": lambda: bed._lipschitz_ranges(
                oo, ee, path, rmax, cfg.min_step_m, cfg.tol_m, 10_000
            ),
        },
        repeats=repeats,
        per={"curvature march (compiled)": n, "curvature march (numpy)": n, "first-order march": n},
    )
    return table(res, reference="first-order march", unit="us per ray", scale=1e6)


def heightfield(repeats: int) -> str:
    """The analytic heightfield rays against MuJoCo's, per ray."""
    from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
    from tasks.core.runner import plan_batch
    from tasks.paper004.seabed import heightfield as generated

    scn = plan_batch("mission/seed004", overrides=["navigation.prediction=seabed"]).scenario
    phys = build_physics(SceneConfig(seabed=scn.seabed, beacons=(), vehicles=(VehicleSpec(),)))
    bed = generated(scn.seabed)
    rng = np.random.default_rng(1)
    k = 200
    o = np.column_stack(
        [rng.uniform(-60, 60, k), rng.uniform(-8, 8, k), rng.uniform(-3.5, -1.5, k)]
    )
    att = np.column_stack([rng.normal(0, 0.1, k), rng.uniform(-1.1, 1.1, k)])
    e = beam_directions(scn.multibeam, att).reshape(k, -1, 3)

    def mujoco_rays() -> None:
        for i in range(k):
            phys.seabed_ray_distances(o[i], e[i], scn.multibeam.max_range_m)

    n = k * e.shape[1]
    res = measure(
        {
            "analytic, batched": lambda: bed.ray_ranges(o[:, None], e, scn.multibeam.max_range_m),
            "MuJoCo mj_multiRay": mujoco_rays,
        },
        repeats=repeats,
        per={"analytic, batched": n, "MuJoCo mj_multiRay": n},
    )
    return table(res, reference="MuJoCo mj_multiRay", unit="us per ray", scale=1e6)


def row2(paths: int, steps: int, repeats: int) -> str:
    """A block of row 2's test paths (three filters), per path-step."""
    from tasks.core.runner import plan_batch
    from tasks.paper004 import seabed, table1
    from tasks.paper004.sim import fly, gains_for

    over = [f"path.duration_s={float(steps)}", "filters.train_paths=200"]
    scn = plan_batch("paper-004/table-1-seabed", overrides=over).scenario
    s = table1.setting(scn, table1.cases(scn)[0])
    g = gains_for(s, 0)
    runs = tuple(range(paths))
    c_march = HarmonicSeabed.ray_ranges

    def numpy_march() -> None:
        HarmonicSeabed.ray_ranges = multibeam_reference.ray_ranges  # type: ignore[method-assign]
        try:
            fly(s, 0, runs, g, sample_runs=0)
        finally:
            HarmonicSeabed.ray_ranges = c_march  # type: ignore[method-assign]

    c_shift = seabed.shift_estimate

    def numpy_shift() -> None:
        seabed.shift_estimate = seabed_reference.shift_estimate
        try:
            fly(s, 0, runs, g, sample_runs=0)
        finally:
            seabed.shift_estimate = c_shift

    variants = {
        "row 2 block": lambda: fly(s, 0, runs, g, sample_runs=0),
        "row 2 block, numpy march": numpy_march,
        "row 2 block, numpy shift": numpy_shift,
    }
    res = measure(variants, repeats=repeats, per={k: paths * steps * 3 for k in variants})
    return table(res, reference="row 2 block, numpy march", unit="us per path-step", scale=1e6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=2000)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    print(machine())
    print("\nRays against the harmonic seabed (seed 004, eq. 24):\n")
    print(rays(a.paths, a.repeats))
    print("\nRays against mission/seed004's heightfield:\n")
    print(heightfield(a.repeats))
    print(f"\npaper-004/table-1-seabed, one block of {a.paths} paths x {a.steps} steps:\n")
    print(row2(a.paths, a.steps, a.repeats))


if __name__ == "__main__":
    main()
