"""One physics step with the ellipsoid fluid model in the plugin against MuJoCo's own (issue 27).

The missions' scene (``bauv_sim.build.build_physics``, the missions' step
``tasks.closed_loop.scenario.PHYSICS_TIMESTEP_S``, implicitfast) cruising from its initial pose,
``mj_step`` with the loop in C, two variants interleaved through :mod:`harness`:

* **plugin fluid model** (the model file since issue 27): MuJoCo's fluid model off (``option
  density`` and ``viscosity`` 0), the plugin ``bauv.hydro`` applies the same ellipsoid forces once
  per body (numeric ``hydro_water``), explicit in the step;
* **MuJoCo fluid model** (the model as before, ``build_physics(hydrodynamics="mujoco-fluid")``):
  the water back in the option and no ``hydro_water``, so that MuJoCo computes ``qfrc_fluid`` per
  geom and its velocity derivatives for implicitfast.

Both vehicles apply the same forces (``tests/bauv_sim/test_hydro_fluid.py``: to 1e-9), and the
plugin's other terms are this checkout's in both, so the ratio is that of the fluid model alone;
the whole command against an older checkout is ``bench_step_profile.py --part compare``. MuJoCo's
stage timers of each are printed too (their own overhead included).

Usage::

    python benchmarks/bench_fluid.py                      # 5 repeats of 20,000 steps
    python benchmarks/bench_fluid.py --repeats 9 --nstep 40000
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import mujoco
from harness import machine, measure, table

from bauv_sim import build, hydro
from tasks.closed_loop.scenario import PHYSICS_TIMESTEP_S

PLUGIN = "plugin fluid model (this model file)"
MUJOCO = "MuJoCo fluid model (as before)"

STAGES = [
    ("step (all)", mujoco.mjtTimer.mjTIMER_STEP),
    ("position", mujoco.mjtTimer.mjTIMER_POSITION),
    ("velocity: passive forces (fluid model, plugin)", mujoco.mjtTimer.mjTIMER_VELOCITY),
    ("actuation", mujoco.mjtTimer.mjTIMER_ACTUATION),
    ("constraint", mujoco.mjtTimer.mjTIMER_CONSTRAINT),
    ("advance: implicitfast derivatives + factorisation", mujoco.mjtTimer.mjTIMER_ADVANCE),
]


def _physics(mujoco_fluid: bool):
    """The missions' scene cruising, with the fluid model in the plugin or in MuJoCo."""
    kind = "mujoco-fluid" if mujoco_fluid else "plugin"
    p = build.build_physics(control_tick_s=0.2, timestep_s=PHYSICS_TIMESTEP_S, hydrodynamics=kind)
    m, d = p.model.ptr, p.data.ptr
    assert hydro.plugin_fluid_model(m) != mujoco_fluid
    assert (m.opt.density > 0) == mujoco_fluid
    p.set_tail_beat_frequency_hz(0.61)
    mujoco.mj_step(m, d, 500)
    return p, m, d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--nstep", type=int, default=20000)
    args = ap.parse_args()
    n = args.nstep

    keep = {}
    for name, mj in ((PLUGIN, False), (MUJOCO, True)):
        keep[name] = _physics(mj)
    print(f"timestep {PHYSICS_TIMESTEP_S * 1e3:g} ms, nv {keep[PLUGIN][1].nv}")

    # the same start: after 500 steps both vehicles are where the other is (forces equal)
    dx = abs(keep[PLUGIN][2].qpos[:3] - keep[MUJOCO][2].qpos[:3]).max()
    print(f"after 500 steps the two vehicles' positions differ by {dx:.2e} m")

    print(f"\nMuJoCo's stage timers, us per step over {n} steps (load {os.getloadavg()[0]:.2f}):\n")
    rows = {}
    for name, (_, m, d) in keep.items():
        for t in d.timer:
            t.duration, t.number = 0.0, 0
        mujoco.mj_step(m, d, n)
        rows[name] = [d.timer[int(k)].duration / n * 1e6 for _, k in STAGES]
    print(f"| stage | {PLUGIN} | {MUJOCO} |\n|---|---|---|")
    for i, (label, _) in enumerate(STAGES):
        print(f"| {label} | {rows[PLUGIN][i]:.2f} | {rows[MUJOCO][i]:.2f} |")

    def variant(name: str):
        _, m, d = _physics(name == MUJOCO)
        return lambda: mujoco.mj_step(m, d, n)

    variants = {name: variant(name) for name in (MUJOCO, PLUGIN)}
    res = measure(variants, repeats=args.repeats, warmup=1, per={k: n for k in variants})
    print(f"\n{machine()}\n")
    print(table(res, reference=MUJOCO, unit="us/step", scale=1e6))


if __name__ == "__main__":
    main()
