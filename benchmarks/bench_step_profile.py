"""Where a step of ``mission/survey`` goes: MuJoCo's stages, the tick's Python, the whole command.

Three measurements, each in its own process so that imports and caches start cold where the
command's would:

* **physics step** (``--part step``): the mission's scene (``bauv_sim.build.build_physics``, the
  missions' step ``tasks.closed_loop.scenario.PHYSICS_TIMESTEP_S``, implicitfast) cruising from
  the initial pose, ``mj_step`` with the loop in C; MuJoCo's own stage timers (``mjData.timer``:
  position, velocity = passive forces incl. the fluid model and the ``bauv.hydro`` plugin,
  constraint, advance = implicitfast's velocity derivatives and factorisation), and the cost of
  each part by ablation, interleaved through :mod:`harness`: the fluid model off (density and
  viscosity 0), the zero-coefficient fluid geoms (5 markers and 3 thin fins) dropped from the
  fluid model (their bodies' ``geom_fluid`` interaction set to 0, so those bodies fall back to
  the inertia-box model, which is cheaper but not the same physics: a cost figure only), the
  crank-rocker equality off, contacts off. Ablations are cost measurements, not physics.
* **command** (``--part command``): the whole ``bauv run mission/survey`` in a fresh
  interpreter, its phases timed by wrappers that accumulate wall time: start-up (interpreter
  and the command's imports), the flight and, within it, each part of a control tick (the
  physics ``BauvPhysics.step``, i.e. all MuJoCo steps of a tick; the sensor rig; the navigator,
  EKF and fix adapters; guidance; the autopilot ``Pilot``; the tick log; dm_control's loop is
  the rest), then the report's figures, recording, Parquet export and the rest.

Usage::

    python benchmarks/bench_step_profile.py                 # all three
    python benchmarks/bench_step_profile.py --part step --repeats 5 --nstep 20000
    python benchmarks/bench_step_profile.py --part command --out /tmp/run

The tables are printed in Markdown for ``benchmarks/README.md`` (section "Where a step goes").
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
T0 = time.perf_counter()

ACC: dict[str, float] = defaultdict(float)
"""Accumulated wall time of each wrapped part, s."""
CALLS: dict[str, int] = defaultdict(int)


def _wrap(owner, attr: str, label: str) -> None:
    """Replace ``owner.attr`` by a wrapper that adds its wall time to ``ACC[label]``."""
    f = getattr(owner, attr)

    @functools.wraps(f)
    def timed(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            ACC[label] += time.perf_counter() - t
            CALLS[label] += 1

    setattr(owner, attr, timed)


def _load() -> float:
    return os.getloadavg()[0]


# -- physics step ------------------------------------------------------------------------------


def part_step(repeats: int, nstep: int) -> None:
    import mujoco
    from harness import machine, measure, table

    from bauv_sim.build import build_physics
    from tasks.closed_loop.scenario import PHYSICS_TIMESTEP_S

    def fresh():
        p = build_physics(control_tick_s=0.2, timestep_s=PHYSICS_TIMESTEP_S)
        p.set_tail_beat_frequency_hz(0.61)
        m, d = p.model.ptr, p.data.ptr
        mujoco.mj_step(m, d, 500)
        return p, m, d

    _, m, d = fresh()
    fluid = m.geom_fluid.reshape(m.ngeom, -1)
    active = [g for g in range(m.ngeom) if fluid[g, 0] > 0]
    zero_coef = [g for g in active if not fluid[g, 1:6].any()]
    names = {g: mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom {g}" for g in active}
    print(
        f"fluid geoms: {len(active)} ({len(zero_coef)} with all five coefficients 0: "
        f"{', '.join(names[g] for g in zero_coef)})"
    )
    print(f"nv {m.nv}, neq {m.neq}, nplugin {m.nplugin}, timestep {m.opt.timestep * 1e3:g} ms")

    # MuJoCo's stage timers (their own overhead included)
    for t in d.timer:
        t.duration, t.number = 0.0, 0
    mujoco.mj_step(m, d, nstep)
    stages = [
        ("step (all)", mujoco.mjtTimer.mjTIMER_STEP),
        (
            "position: kinematics, inertia, collision, make constraints",
            mujoco.mjtTimer.mjTIMER_POSITION,
        ),
        ("velocity: passive forces (fluid model, plugin)", mujoco.mjtTimer.mjTIMER_VELOCITY),
        ("actuation", mujoco.mjtTimer.mjTIMER_ACTUATION),
        ("constraint: solver (crank-rocker equality)", mujoco.mjtTimer.mjTIMER_CONSTRAINT),
        ("advance: implicitfast derivatives + factorisation", mujoco.mjtTimer.mjTIMER_ADVANCE),
    ]
    tot = d.timer[int(mujoco.mjtTimer.mjTIMER_STEP)].duration
    print(f"\nMuJoCo stage timers over {nstep} steps (load {_load():.2f}):\n")
    print("| stage | us per step | share |\n|---|---|---|")
    for label, k in stages:
        dur = d.timer[int(k)].duration
        print(f"| {label} | {dur / nstep * 1e6:.2f} | {dur / tot:.0%} |")

    def variant(edit):
        _, mq, dq = fresh()
        edit(mq, dq)
        mujoco.mj_forward(mq, dq)
        return lambda: mujoco.mj_step(mq, dq, nstep)

    def no_fluid(mq, dq):
        mq.opt.density, mq.opt.viscosity = 0.0, 0.0

    def no_zero_coef(mq, dq):
        f = mq.geom_fluid.reshape(mq.ngeom, -1)
        for g in zero_coef:
            f[g, 0] = 0.0

    def no_eq(mq, dq):
        mq.eq_active0[:] = 0
        dq.eq_active[:] = 0

    def no_contact(mq, dq):
        mq.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)

    def as_is(mq, dq):
        pass

    variants = {
        "full scene": variant(as_is),
        "fluid model off (density, viscosity 0)": variant(no_fluid),
        "zero-coefficient fluid geoms dropped": variant(no_zero_coef),
        "crank-rocker equality off": variant(no_eq),
        "contacts off": variant(no_contact),
    }
    res = measure(variants, repeats=repeats, warmup=1, per={k: nstep for k in variants})
    print(f"\n{machine()}\n")
    print(table(res, reference="full scene", unit="us/step", scale=1e6))


# -- the tick's Python -------------------------------------------------------------------------


def _instrument_tick() -> None:
    from bauv_sim.physics import BauvPhysics
    from bauv_sim.sensors.rig import SensorRig
    from tasks.closed_loop import parts, result
    from tasks.closed_loop.navigation import EkfNavigation

    _wrap(BauvPhysics, "step", "physics (mj_step, the tick's steps)")
    _wrap(SensorRig, "sense", "sensor rig")
    _wrap(EkfNavigation, "step", "navigator (EKF, fixes)")
    _wrap(parts.WaypointSteering, "step", "guidance")
    _wrap(parts.Pilot, "__call__", "autopilot")
    _wrap(result.TickLog, "add", "tick log")


def _instrument_report() -> None:
    from tasks.closed_loop import report
    from tasks.core import report_pool

    # drawn in this process only without report processes (one CPU); with them, the wait for
    # their jobs once the rest of the report is written
    _wrap(report, "mission_figures", "report: figures (PNG + PDF)")
    _wrap(report, "record_mission", "report: rerun recording")
    _wrap(report_pool.Offloaded, "result", "report: waiting for the report processes")
    _wrap(report, "export_runs", "report: Parquet run data")
    _wrap(report, "report_mission", "report (all)")


def _run_command(extra: list[str], report: bool = True, out: str | None = None) -> None:
    from tasks.core.cli import main

    t_imports = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = out or str(Path(tmp) / "run")
        t = time.perf_counter()
        try:
            main(["run", "mission/survey", "--out", folder, "--quiet", *extra])
        except SystemExit as e:
            if e.code not in (0, None):
                raise
        t_run = time.perf_counter() - t
    print(
        json.dumps(
            {
                "startup_s": t_imports - T0,
                "run_s": t_run,
                "parts": dict(ACC),
                "calls": dict(CALLS),
                "load": _load(),
            }
        )
    )


def part_command(out: str | None) -> None:
    import tasks.core.cli  # noqa: F401  (the command's own imports)

    _instrument_tick()
    _instrument_report()
    from dm_control.rl import control

    _wrap(control.Environment, "step", "flight (dm_control steps)")
    _run_command([], out=out)


def _child(part: str, args) -> dict:
    """Run a part in a fresh interpreter (cold imports); its last stdout line is JSON."""
    cmd = [sys.executable, __file__, "--part", part, "--child"]
    if args.out:
        cmd += ["--out", args.out]
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t
    data = json.loads(proc.stdout.strip().splitlines()[-1])
    data["wall_s"] = wall
    return data


def summarise(data: dict, title: str) -> None:
    wall, parts = data["wall_s"], data["parts"]
    print(f"\n{title} (load {data['load']:.2f}):\n")
    print("| part | s | share of the command |\n|---|---|---|")
    print(f"| whole command (process wall time) | {wall:.2f} | 100 % |")
    up = data["startup_s"]
    print(f"| start-up: interpreter and imports | {up:.2f} | {up / wall:.0%} |")
    flight = parts.get("flight (dm_control steps)", 0.0)
    tick_parts = [
        "physics (mj_step, the tick's steps)",
        "sensor rig",
        "navigator (EKF, fixes)",
        "guidance",
        "autopilot",
        "tick log",
    ]
    print(f"| flight | {flight:.2f} | {flight / wall:.0%} |")
    inner = 0.0
    for k in tick_parts:
        if k in parts:
            inner += parts[k]
            print(f"| - {k} | {parts[k]:.2f} | {parts[k] / wall:.0%} |")
    rest = flight - inner
    print(f"| - dm_control's loop and the rest | {rest:.2f} | {rest / wall:.0%} |")
    rep = parts.get("report (all)")
    if rep is not None:
        print(f"| report | {rep:.2f} | {rep / wall:.0%} |")
        sub = 0.0
        for k in (
            "report: figures (PNG + PDF)",
            "report: rerun recording",
            "report: waiting for the report processes",
            "report: Parquet run data",
        ):
            sub += parts.get(k, 0.0)
            print(f"| - {k[8:]} | {parts.get(k, 0.0):.2f} | {parts.get(k, 0.0) / wall:.0%} |")
        print(f"| - tables, metrics, the rest | {rep - sub:.2f} | {(rep - sub) / wall:.0%} |")
    other = wall - data["startup_s"] - flight - (rep or 0.0)
    print(
        f"| the rest (scenario, environment, run folder, exit) | {other:.2f} | {other / wall:.0%} |"
    )
    n = data["calls"].get("physics (mj_step, the tick's steps)", 0)
    if n:
        per = {k: parts[k] / n * 1e3 for k in tick_parts if k in parts}
        print(
            f"\nPer control tick ({n} ticks): "
            + ", ".join(f"{k} {v:.3f} ms" for k, v in per.items())
        )


def part_compare(base: str, repeats: int, runs: int, workers_list: list[int]) -> None:
    """Whole ``bauv run`` commands, interleaved through :mod:`harness`, against another checkout.

    ``base`` is a checkout with its own environment (``<base>/.venv/bin/python``), e.g. of the
    commit before this work; each command runs in a fresh process from its checkout's folder.
    Variants: this checkout's ``mission/survey`` (its preset, 10 ms), the same at the 4 ms step
    of the other missions (the cuts that do not change the physics), and the base's.
    """
    from harness import machine, measure, table

    here_py = sys.executable
    base_py = str(Path(base) / ".venv" / "bin" / "python")

    cpu: dict[str, list[float]] = defaultdict(list)

    def command(py: str, cwd: str, extra: list[str], name: str = "mission/survey"):
        key = f"{py} {name} {' '.join(extra)}"

        def run() -> None:
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            with tempfile.TemporaryDirectory() as tmp:
                subprocess.run(
                    [
                        py,
                        "-m",
                        "tasks.core.cli",
                        "run",
                        name,
                        "--out",
                        f"{tmp}/run",
                        "--quiet",
                        *extra,
                    ],
                    cwd=cwd,
                    check=True,
                    stdout=subprocess.DEVNULL,
                )
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[key].append(r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)

        run.key = key  # type: ignore[attr-defined]
        return run

    def cpu_table(variants: dict) -> None:
        print("\nCPU time of the command and its workers (user + system, s; median, min):\n")
        print("| variant | median | min |\n|---|---|---|")
        for label, f in variants.items():
            xs = sorted(cpu[f.key][-repeats:])
            print(f"| {label} | {xs[len(xs) // 2]:.2f} | {xs[0]:.2f} |")

    root = str(HERE.parent)
    if runs <= 1:
        variants = {
            "base": command(base_py, base, []),
            "this branch": command(here_py, root, []),
            "this branch at 4 ms": command(
                here_py, root, ["--set", "timing.physics_timestep_s=0.004"]
            ),
        }
        res = measure(variants, repeats=repeats, warmup=1)
        print(f"\n{machine()}\n\n`bauv run mission/survey`, whole command (s):\n")
        print(table(res, reference="base", unit="s", scale=1))
        cpu_table(variants)
        return
    variants = {}
    for w in workers_list:
        args = ["--runs", str(runs), "--workers", str(w)]
        variants[f"base, {w} worker(s)"] = command(base_py, base, args, "mission/short")
        variants[f"this branch, {w} worker(s)"] = command(here_py, root, args, "mission/short")
    res = measure(variants, repeats=repeats, warmup=0)
    print(f"\n{machine()}\n\n`bauv run mission/short --runs {runs}`, whole command (s):\n")
    print(table(res, reference=f"base, {workers_list[0]} worker(s)", unit="s", scale=1))
    cpu_table(variants)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", choices=("step", "command", "compare", "all"), default="all")
    ap.add_argument("--base", default=None, help="compare: a checkout of the reference commit")
    ap.add_argument("--runs", type=int, default=1, help="compare: runs (>1: mission/short)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="compare: workers")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--nstep", type=int, default=20000)
    ap.add_argument("--out", default=None, help="keep the command's run folder here")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    sys.path.insert(0, str(HERE))
    if args.child:
        part_command(args.out)
        return
    if args.part == "compare":
        if not args.base:
            ap.error("--part compare needs --base (a checkout with its own .venv)")
        part_compare(args.base, args.repeats, args.runs, args.workers)
        return
    if args.part in ("step", "all"):
        part_step(args.repeats, args.nstep)
    if args.part in ("command", "all"):
        summarise(_child("command", args), "`bauv run mission/survey`, phases")


if __name__ == "__main__":
    main()
