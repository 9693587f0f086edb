"""The plugin ``bauv.hydro`` against an earlier version of itself, in one process: the same
forces and trajectory bit for bit, and the cost of the mission's physics step, interleaved.

The earlier version is ``bauv_sim/plugin/hydro.c`` at a git revision (``--against``), compiled
with this build's compiler and flags (those of ``setup.py``: the interpreter's ``CFLAGS``, then
``-O2 -std=c11``) under another plugin name, ``bauv.hydro_against``, and loaded beside this
checkout's library. A copy of the mission's compiled model (``bauv_sim.build.build_physics``, the
missions' step ``tasks.closed_loop.scenario.PHYSICS_TIMESTEP_S``) is pointed at it (its
``mjModel.plugin`` slot), so the two libraries run the same model from the same state:

* **forces**: ``qfrc_passive``, the mass matrix with the added mass and ``qacc`` after
  ``mj_forward`` at random states (pose, velocities, joint angles, water and its acceleration);
* **trajectory**: ``--check-steps`` steps of the survey's cruise from one state, the water changed
  every 8 s and the controls every 6 s; ``qpos``, ``qvel``, ``qacc`` compared;
* **time**: ``mj_step`` of ``--nstep`` steps (the loop in C), the two interleaved through
  :mod:`harness` (wall time), and the stepping thread's CPU time of the same calls, which the
  machine's other load moves less.

Both comparisons print ``bit for bit`` or the largest relative difference; the script exits 1 if
they differ by more than ``--rtol`` (default 0: bit for bit).

Usage::

    python benchmarks/bench_plugin.py --against d5b203b
    python benchmarks/bench_plugin.py --against HEAD~1 --repeats 21 --nstep 5000

Needs the C compiler the package was built with (``setup.py``) and git.
"""

from __future__ import annotations

import argparse
import copy
import ctypes
import os
import shlex
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SOURCE = "bauv_sim/plugin/hydro.c"
NAME = "bauv.hydro"
AGAINST_NAME = "bauv.hydro_against"
EXTRA_COMPILE_ARGS = ["-O2", "-std=c11", "-D_POSIX_C_SOURCE=200809L", "-Wall"]
"""The plugin's own flags in ``setup.py`` (``Extension(extra_compile_args=...)``)."""


def build_against(rev: str, out_dir: Path) -> Path:
    """Compile the plugin's source at git revision ``rev`` as ``bauv.hydro_against``.

    Args:
        rev: a git revision of this repository.
        out_dir: folder for the source and the library.

    Returns:
        Path of the shared library.
    """
    src = subprocess.run(
        ["git", "show", f"{rev}:{SOURCE}"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    if f'"{NAME}"' not in src or "mjPLUGIN_LIB_INIT(bauv_hydro)" not in src:
        raise SystemExit(f"{rev}:{SOURCE} does not register {NAME!r} as this script expects")
    src = src.replace(f'"{NAME}"', f'"{AGAINST_NAME}"').replace(
        "mjPLUGIN_LIB_INIT(bauv_hydro)", "mjPLUGIN_LIB_INIT(bauv_hydro_against)"
    )
    c_file, obj, lib = out_dir / "against.c", out_dir / "against.o", out_dir / "against.so"
    c_file.write_text(src, encoding="utf-8")
    root = Path(mujoco.__file__).parent
    libmujoco = sorted(root.glob("libmujoco.so*"))[-1].name

    def var(name: str) -> list[str]:
        return shlex.split(sysconfig.get_config_var(name) or "")

    subprocess.run(
        [*var("CC"), *var("CFLAGS"), *var("CCSHARED"), f"-I{root / 'include'}"]
        + [*EXTRA_COMPILE_ARGS, "-c", str(c_file), "-o", str(obj)],
        check=True,
    )
    subprocess.run(
        [*var("LDSHARED"), str(obj), f"-L{root}", f"-l:{libmujoco}", "-o", str(lib)], check=True
    )
    return lib


def against_slot(lib: Path) -> int:
    """Load ``lib`` and return the slot of its plugin in MuJoCo's plugin table
    (``mjp_getPlugin``, through the MuJoCo library the bindings loaded)."""
    mujoco.mj_loadPluginLibrary(str(lib))
    root = Path(mujoco.__file__).parent
    libmujoco = ctypes.CDLL(str(sorted(root.glob("libmujoco.so*"))[-1]))
    libmujoco.mjp_getPlugin.restype = ctypes.c_void_p
    slot = ctypes.c_int(-1)
    if not libmujoco.mjp_getPlugin(AGAINST_NAME.encode(), ctypes.byref(slot)):
        raise SystemExit(f"{lib}: no plugin {AGAINST_NAME!r} registered")
    return slot.value


def _largest_rel(a: np.ndarray, b: np.ndarray) -> float:
    scale = max(float(np.abs(b).max()), 1e-300)
    return float(np.abs(a - b).max()) / scale


def _report(label: str, got: np.ndarray, want: np.ndarray, rtol: float) -> bool:
    if np.array_equal(got, want):
        print(f"{label}: bit for bit ({got.size} numbers)")
        return True
    rel = _largest_rel(got, want)
    print(f"{label}: largest difference {rel:.3g} of the largest value ({got.size} numbers)")
    return rel <= rtol


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--against", default="HEAD~1", help="git revision of the earlier plugin")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--nstep", type=int, default=5000, help="steps per timed call")
    ap.add_argument("--states", type=int, default=200, help="random states for the forces")
    ap.add_argument("--check-steps", type=int, default=20000, help="steps of the trajectory")
    ap.add_argument("--rtol", type=float, default=0.0, help="largest relative difference allowed")
    args = ap.parse_args(argv)

    sys.path.insert(0, str(HERE))
    from harness import machine, measure, table

    from bauv_sim import hydro
    from bauv_sim.build import build_physics
    from tasks.closed_loop.scenario import PHYSICS_TIMESTEP_S

    with tempfile.TemporaryDirectory() as tmp:
        lib = build_against(args.against, Path(tmp))
        hydro.load_plugin()
        slot = against_slot(lib)

    p = build_physics(control_tick_s=0.2, timestep_s=PHYSICS_TIMESTEP_S)
    p.set_tail_beat_frequency_hz(0.61)
    m, d = p.model.ptr, p.data.ptr
    mujoco.mj_step(m, d, 500)  # cruising
    m_old = copy.copy(m)
    m_old.plugin[:] = slot
    d_old = mujoco.MjData(m_old)
    what = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.zeros(mujoco.mj_stateSize(m, what))
    mujoco.mj_getState(m, d, state, what)
    mujoco.mj_setState(m_old, d_old, state, what)
    inst = next(iter(hydro.plugin_instances(m).values()))
    pair = ((m, d), (m_old, d_old))

    # forces at random states
    rng = np.random.default_rng(27)
    rows: list[list[np.ndarray]] = [[], []]
    full = np.zeros((m.nv, m.nv))
    cruise_q = d.qpos.copy()
    for _ in range(args.states):
        q = cruise_q + rng.normal(0.0, 0.2, m.nq)
        q[3:7] = rng.normal(size=4)
        q[3:7] /= np.linalg.norm(q[3:7])
        v = rng.normal(0.0, 1.0, m.nv)
        w, a = rng.normal(0.0, 0.4, 3), rng.normal(0.0, 0.3, 3) * rng.integers(0, 2)
        for k, (mm, dd) in enumerate(pair):
            dd.qpos[:], dd.qvel[:] = q, v
            hydro.set_water(mm, dd, inst, w, a, t0_s=dd.time - 0.05)
            mujoco.mj_forward(mm, dd)
            mujoco.mj_fullM(mm, dd, full)
            rows[k].append(np.concatenate([dd.qfrc_passive, full.ravel(), dd.qacc]))
    ok = _report("forces at random states", np.array(rows[0]), np.array(rows[1]), args.rtol)

    # a trajectory from one state
    for mm, dd in pair:
        mujoco.mj_setState(mm, dd, state, what)
    rng = np.random.default_rng(5)
    traj: list[list[np.ndarray]] = [[], []]
    for block in range(args.check_steps // 500):
        w, a, c = rng.normal(0.0, 0.3, 3), rng.normal(0.0, 0.05, 3), rng.normal(0.0, 0.05, m.nu)
        for k, (mm, dd) in enumerate(pair):
            if block % 4 == 1:
                hydro.set_water(mm, dd, inst, w, a)
            if block % 3 == 2:
                dd.ctrl[:] = dd.ctrl + c
            mujoco.mj_step(mm, dd, 500)
            traj[k].append(np.concatenate([dd.qpos, dd.qvel, dd.qacc]))
    ok &= _report(
        f"trajectory of {args.check_steps} steps",
        np.array(traj[0]),
        np.array(traj[1]),
        args.rtol,
    )

    n = args.nstep
    ref = f"plugin of {args.against}"
    runs = {"this checkout": (m, d), ref: (m_old, d_old)}
    cpu: dict[str, list[float]] = {k: [] for k in runs}

    def stepper(name: str):
        mm, dd = runs[name]

        def call() -> None:
            c0 = time.thread_time()
            mujoco.mj_step(mm, dd, n)
            cpu[name].append(time.thread_time() - c0)

        return call

    res = measure(
        {k: stepper(k) for k in runs}, repeats=args.repeats, warmup=1, per={k: n for k in runs}
    )
    print(f"\n{machine()}\n")
    print(f"`mj_step` of the survey's scene ({m.opt.timestep * 1e3:g} ms), per step:\n")
    print(table(res, reference=ref, unit="us/step", scale=1e6))
    # the thread's CPU time, which the machine's other load moves less than the wall time
    med = {k: statistics.median(v[-args.repeats :]) / n * 1e6 for k, v in cpu.items()}
    low = {k: min(v[-args.repeats :]) / n * 1e6 for k, v in cpu.items()}
    print("\nCPU time of the stepping thread (us/step):\n")
    print(f"| variant | min | median | {ref} / variant (median) |\n|---|---|---|---|")
    for k in runs:
        print(f"| {k} | {low[k]:.2f} | {med[k]:.2f} | {med[ref] / med[k]:.3g} |")
    # MuJoCo's stage timers (their own overhead included): --repeats runs of --nstep steps each,
    # interleaved, the median of each stage
    stages = [
        ("step (all)", mujoco.mjtTimer.mjTIMER_STEP),
        ("position", mujoco.mjtTimer.mjTIMER_POSITION),
        ("velocity (passive forces: the plugin)", mujoco.mjtTimer.mjTIMER_VELOCITY),
        ("actuation", mujoco.mjtTimer.mjTIMER_ACTUATION),
        ("constraint", mujoco.mjtTimer.mjTIMER_CONSTRAINT),
        ("advance", mujoco.mjtTimer.mjTIMER_ADVANCE),
    ]
    per_stage: dict[str, list[list[float]]] = {k: [] for k in runs}
    load = os.getloadavg()[0]
    for r in range(args.repeats):
        for k in list(runs)[:: 1 if r % 2 else -1]:
            mm, dd = runs[k]
            for t in dd.timer:
                t.duration, t.number = 0.0, 0
            mujoco.mj_step(mm, dd, n)
            per_stage[k].append([dd.timer[int(i)].duration / n * 1e6 for _, i in stages])
    med_stage = {k: np.median(np.array(v), axis=0) for k, v in per_stage.items()}
    print(f"\nMuJoCo's stage timers, us per step (median of {args.repeats} interleaved runs of")
    print(f"{n} steps, load {load:.2f}):\n")
    print(f"| stage | this checkout | {ref} |\n|---|---|---|")
    for j, (label, _) in enumerate(stages):
        print(f"| {label} | {med_stage['this checkout'][j]:.2f} | {med_stage[ref][j]:.2f} |")
    return 0 if ok else 1


if __name__ == "__main__":
    os.chdir(ROOT)
    raise SystemExit(main())
