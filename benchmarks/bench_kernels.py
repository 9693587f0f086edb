"""The seabed kernels compiled by numba against the C libraries they replaced (issue 26).

Until issue 26 three hot loops were plain C libraries loaded with ctypes: the harmonic seabed's
ray march (``bauv_sim/sensors/harmonic_rays.c``) and the seabed shift's slope fit and eq. 12-15
(``nav/seabed/seabed_shift.c``). They are now numba functions with the same operations in the
same order (:mod:`bauv_sim.sensors.harmonic_march`, :mod:`nav.seabed.kernel`). This script times
each kernel both ways on the same arrays, interleaved (``harness.measure``), and checks that the
two give the same numbers bit for bit.

* ``march``: seed 004's 8 x 8 beams from 10 m below the surface over seabeds ~30 m deep, one
  image per path (``--paths`` of them), per ray.
* ``fit``: Appendix A's harmonic fit (9 functions) of 64 feet per path, per path.
* ``shift``: eq. 12-15 with the residual covariance ("turning" reading), 64 beams, per path.

The C side is loaded from a checkout of the commit before the replacement, built in place
(``--c-checkout DIR``: its ``nav/clib.py``, ``nav/seabed/_seabed_shift*.so`` and
``bauv_sim/sensors/_harmonic_rays*.so``), e.g.::

    git worktree add /tmp/c-kernels <commit before issue 26's kernels>
    (cd /tmp/c-kernels && python setup.py build_ext --inplace)
    python benchmarks/bench_kernels.py --c-checkout /tmp/c-kernels

``--jit`` also measures the first use in a fresh process, with numba's cache empty (compilation)
and filled (the cache loaded), each as the time from before the import to after the first call.

Usage: ``python benchmarks/bench_kernels.py --c-checkout DIR [--paths 2000] [--repeats 15] [--jit]``
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for _p in (str(ROOT), str(ROOT / "benchmarks")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import numpy as np  # noqa: E402
from harness import machine, measure, table  # noqa: E402

from bauv_sim.sensors.multibeam import (  # noqa: E402
    CURVATURE_STEPS,
    HarmonicSeabed,
    MultibeamConfig,
    beam_directions,
)
from nav.seabed.fit import FIT_C_CONDITION  # noqa: E402
from nav.seabed.geometry import BeamGeometry  # noqa: E402
from nav.seabed.shift import SINGULAR_FLOOR  # noqa: E402


def load_c(checkout: Path):
    """The old ``nav.clib`` module of ``checkout`` (under another name) and its two libraries'
    entry points."""
    spec = importlib.util.spec_from_file_location("c_clib", checkout / "nav" / "clib.py")
    clib = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(clib)
    rays = clib.load_library(checkout / "bauv_sim" / "sensors", "_harmonic_rays")
    seabed = clib.load_library(checkout / "nav" / "seabed", "_seabed_shift")
    return (
        clib,
        clib.entry_point(rays, "bauv_harmonic_march", clib.MarchArgs),
        clib.entry_point(seabed, "bauv_seabed_fit", clib.SeabedFitArgs),
        clib.entry_point(seabed, "bauv_seabed_shift", clib.SeabedShiftArgs),
    )


def march_inputs(paths: int) -> dict:
    """The march's arrays for one image per path (as ``HarmonicSeabed._curvature_march``)."""
    rng = np.random.default_rng(0)
    bed = HarmonicSeabed.draw(0, tuple(range(paths)))
    cfg = MultibeamConfig()
    o = np.column_stack(
        [rng.uniform(0, 300, paths), rng.uniform(-20, 20, paths), rng.normal(-10, 1, paths)]
    )
    att = np.column_stack([rng.normal(0, 0.05, paths), rng.uniform(-1.1, 1.1, paths)])
    e = beam_directions(cfg, att).reshape(paths, -1, 3)
    e = e / np.linalg.norm(e, axis=-1, keepdims=True)
    wx, wy = bed._w()
    return {
        "o": np.ascontiguousarray(np.repeat(o, e.shape[1], axis=0)),
        "e": np.ascontiguousarray(e.reshape(-1, 3)),
        "path": np.repeat(np.arange(paths, dtype=np.int64), e.shape[1]),
        **{c: np.ascontiguousarray(getattr(bed, c)) for c in "abcd"},
        "wx": np.ascontiguousarray(wx),
        "wy": np.ascontiguousarray(wy),
        "top": np.ascontiguousarray(-bed.a0_m + bed.relief_bound()),
        "cxx": np.ascontiguousarray((wx**2 * np.hypot(bed.a, bed.b)).sum(-1)),
        "cyy": np.ascontiguousarray((wy**2 * np.hypot(bed.c, bed.d)).sum(-1)),
        "scalars": (bed.a0_m, bed.period_x_m, bed.period_y_m, cfg.max_range_m, cfg.tol_m),
    }


def seabed_inputs(paths: int) -> dict:
    """Feet, ranges and beam vectors of image pairs of 8 x 8 beams over a harmonic seabed."""
    rng = np.random.default_rng(1)
    geo = BeamGeometry.seed004()
    m = geo.shape[0] * geo.shape[1]
    att0 = np.column_stack([rng.normal(0, 0.05, paths), rng.uniform(-1.1, 1.1, paths)])
    att1 = att0 + rng.normal(0, 0.05, (paths, 2))
    e = np.ascontiguousarray(geo.directions(att0).reshape(paths, m, 3))
    de = np.ascontiguousarray(geo.direction_change(att0, att1).reshape(paths, m, 3))
    L0 = rng.uniform(15, 35, (paths, m))
    L1 = L0 + rng.normal(0, 0.5, (paths, m))
    pos = np.column_stack(
        [rng.uniform(0, 300, paths), rng.uniform(-20, 20, paths), rng.normal(-10, 1, paths)]
    )
    points = np.ascontiguousarray(pos[:, None, :] + L0[..., None] * e)
    valid = (rng.random((paths, m)) > 0.1).astype(np.uint8)
    use = valid & (rng.random((paths, m)) > 0.1).astype(np.uint8)
    return {"points": points, "valid": valid, "e": e, "de": de, "L0": L0, "L1": L1, "use": use}


def march_variants(c, inp: dict) -> tuple[dict, dict]:
    """name -> call, and name -> its outputs (filled by the calls)."""
    from bauv_sim.sensors import harmonic_march

    clib, c_march = c[0], c[1]
    n, (P, K) = len(inp["path"]), inp["a"].shape
    a0, px, py, rmax, tol = inp["scalars"]
    arrays = {k: v for k, v in inp.items() if k != "scalars"}
    outs = {
        v: (np.zeros(n), np.zeros(n, np.uint8), np.zeros(n, np.uint8), np.zeros(n))
        for v in ("C", "numba")
    }

    def run_c() -> None:
        r, h, u, s = outs["C"]
        args = clib.pack(
            clib.MarchArgs,
            n=n,
            paths=P,
            harmonics=K,
            steps=CURVATURE_STEPS,
            a0=a0,
            px=px,
            py=py,
            max_range=rmax,
            tol=tol,
            **arrays,
            range=r,
            hit=h,
            unresolved=u,
            s=s,
        )
        assert c_march(args) >= 0

    def run_numba() -> None:
        got = harmonic_march.march(
            *(arrays[k] for k in ("o", "e", "path", "a", "b", "c", "d", "wx", "wy", "top")),
            arrays["cxx"],
            arrays["cyy"],
            a0,
            px,
            py,
            rmax,
            tol,
            CURVATURE_STEPS,
            *outs["numba"],
        )
        assert got >= 0

    return {"C": run_c, "numba": run_numba}, outs


def fit_variants(c, inp: dict) -> tuple[dict, dict]:
    from nav.seabed import kernel

    clib, c_fit = c[0], c[2]
    P, m = inp["valid"].shape
    outs = {
        v: (np.zeros((P, m, 3)), np.zeros(P, np.uint8), np.zeros(P, np.uint8))
        for v in ("C", "numba")
    }
    geo = (0, 3, 20.0, 20.0, FIT_C_CONDITION)  # kind harmonic, K, Px, Py, max condition

    def run_c() -> None:
        g, ok, tn = outs["C"]
        args = clib.pack(
            clib.SeabedFitArgs,
            paths=P,
            feet=m,
            kind=geo[0],
            harmonics=geo[1],
            px=geo[2],
            py=geo[3],
            max_condition=geo[4],
            points=inp["points"],
            valid=inp["valid"],
            grad=g,
            fit_ok=ok,
            to_numpy=tn,
        )
        assert c_fit(args) >= 0

    def run_numba() -> None:
        assert kernel.seabed_fit(inp["points"], inp["valid"], *geo, *outs["numba"]) >= 0

    return {"C": run_c, "numba": run_numba}, outs


def shift_variants(c, inp: dict, grad: np.ndarray, fit_ok: np.ndarray) -> tuple[dict, dict]:
    from nav.seabed import kernel

    clib, c_shift = c[0], c[3]
    P, m = inp["use"].shape
    outs = {
        v: (
            np.zeros((P, 3)),
            np.zeros((P, 3, 3)),
            np.zeros(P, np.int64),
            np.zeros(P, np.int64),
            np.zeros(P, np.uint8),
            np.zeros(P),
        )
        for v in ("C", "numba")
    }
    sc = (0.1, 1e6, 1e-4, SINGULAR_FLOOR)  # sigma, fallback, rcond, floor

    def run_c() -> None:
        sh, cv, b, rk, ok, rms = outs["C"]
        args = clib.pack(
            clib.SeabedShiftArgs,
            paths=P,
            beams=m,
            residual=1,
            sigma=sc[0],
            fallback=sc[1],
            rcond=sc[2],
            singular_floor=sc[3],
            grad=grad,
            e=inp["e"],
            de=inp["de"],
            l0=inp["L0"],
            l1=inp["L1"],
            use=inp["use"],
            fit_ok=fit_ok,
            cmd=None,
            shift=sh,
            cov=cv,
            used=b,
            rank=rk,
            ok=ok,
            rms=rms,
        )
        assert c_shift(args) >= 0

    def run_numba() -> None:
        got = kernel.seabed_shift(
            grad,
            inp["e"],
            inp["de"],
            inp["L0"],
            inp["L1"],
            inp["use"],
            fit_ok,
            True,
            *sc,
            np.empty((0, 3)),
            *outs["numba"],
        )
        assert got >= 0

    return {"C": run_c, "numba": run_numba}, outs


def identical(outs: dict) -> str:
    """Whether the two variants' outputs agree bit for bit (NaN equal to NaN)."""
    same = all(
        np.array_equal(x, y, equal_nan=True) for x, y in zip(outs["C"], outs["numba"], strict=True)
    )
    return "outputs identical bit for bit" if same else "OUTPUTS DIFFER"


JIT_PROBE = """
import sys, time
sys.path[:0] = [".", "benchmarks"]
import numpy as np
from bench_kernels import march_inputs, seabed_inputs
assert "numba" not in sys.modules
inp, sb = march_inputs(1), seabed_inputs(1)
t1 = time.perf_counter()
from bauv_sim.sensors import harmonic_march
from nav.seabed import kernel
a = {k: v for k, v in inp.items() if k != "scalars"}
n = len(a["path"])
harmonic_march.march(*(a[k] for k in ("o", "e", "path", "a", "b", "c", "d", "wx", "wy", "top",
    "cxx", "cyy")), *inp["scalars"], 60, np.zeros(n), np.zeros(n, np.uint8), np.zeros(n, np.uint8),
    np.zeros(n))
g, ok, tn = np.zeros((1, 64, 3)), np.zeros(1, np.uint8), np.zeros(1, np.uint8)
kernel.seabed_fit(sb["points"], sb["valid"], 0, 3, 20.0, 20.0, 1e4, g, ok, tn)
kernel.seabed_shift(g, sb["e"], sb["de"], sb["L0"], sb["L1"], sb["use"], ok, True, 0.1, 1e6,
    1e-4, 1e-9, np.empty((0, 3)), np.zeros((1, 3)), np.zeros((1, 3, 3)), np.zeros(1, np.int64),
    np.zeros(1, np.int64), np.zeros(1, np.uint8), np.zeros(1))
print(time.perf_counter() - t1)
"""


def jit_cost(repeats: int) -> str:
    """First use of the three kernels in a fresh process: numba's import, then the first call
    of each, with the cache empty (compiled) and filled (loaded); seconds, min and median."""
    cold, warm = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            for into in (cold, warm):
                proc = subprocess.run(
                    [sys.executable, "-c", JIT_PROBE],
                    env=env,
                    cwd=ROOT,
                    capture_output=True,
                    text=True,
                    check=True,
                )
                into.append(float(proc.stdout.strip().splitlines()[-1]))
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (
        "| first use (import numba + first call of march, fit, shift) | min (s) | median (s) |\n"
        "|---|---|---|\n"
        f"| cache empty (compiles) | {min(cold):.2f} | {np.median(cold):.2f} |\n"
        f"| cache filled (loads) | {min(warm):.2f} | {np.median(warm):.2f} |\n\n"
        f"{repeats} fresh processes each; load average after: {load}"
    )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--c-checkout", type=Path, required=True, help="a built checkout with the C")
    p.add_argument("--paths", type=int, default=2000)
    p.add_argument("--repeats", type=int, default=15)
    p.add_argument("--jit", action="store_true", help="also the first-use (JIT) cost")
    a = p.parse_args()
    c = load_c(a.c_checkout.resolve())
    print(machine())
    mi = march_inputs(a.paths)
    variants, outs = march_variants(c, mi)
    n = len(mi["path"])
    res = measure(variants, repeats=a.repeats, per={"C": n, "numba": n})
    print(f"\n### march ({n} rays): {identical(outs)}\n")
    print(table(res, reference="C", unit="us per ray", scale=1e6))
    si = seabed_inputs(a.paths)
    variants, outs = fit_variants(c, si)
    res = measure(variants, repeats=a.repeats, per={"C": a.paths, "numba": a.paths})
    print(f"\n### fit ({a.paths} paths): {identical(outs)}\n")
    print(table(res, reference="C", unit="us per path", scale=1e6))
    grad, fit_ok = outs["C"][0], outs["C"][1]
    variants, outs = shift_variants(c, si, grad, fit_ok)
    res = measure(variants, repeats=a.repeats, per={"C": a.paths, "numba": a.paths})
    print(f"\n### shift ({a.paths} paths): {identical(outs)}\n")
    print(table(res, reference="C", unit="us per path", scale=1e6))
    if a.jit:
        print("\n### first use\n")
        print(jit_cost(3))


if __name__ == "__main__":
    main()
