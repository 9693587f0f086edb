"""A physics Monte Carlo of 16 seeds: processes against batched stepping (issue 13, check 4).

Each seed is one run of the same physics job: the BAUV (``models/bauv/scene.xml``) flown by
:class:`bauv_sim.autopilot.Autopilot` from its true state (course 090, 3 m depth, 1 m/s) for
``--seconds`` of simulated time in its own uniform current (speed up to 0.3 m/s, any direction,
drawn from the stream ``(seed, run, "bench", "current")``), at the missions' timestep preset. Per
control tick (0.2 s) each seed's autopilot runs in Python and sets the five actuator commands;
between ticks the physics steps ``tick / timestep`` times with nothing from Python. The fluid
forces are MuJoCo's own ellipsoid drag and the ``bauv.hydro`` engine plugin (C), and the sea acts
once per tick (``option wind`` and the plugin's water = the current at the vehicle, buoyancy
scaled by the submerged fraction), so the steps between two ticks need no Python callback:
batched stepping is the same physics, which the script checks (every variant's final states must
equal the reference's bit for bit).

**The plugin's water per seed.** Issue 11's hydrodynamics is the engine plugin ``bauv.hydro``
(C, declared in the model), so every variant applies it inside ``mj_step`` with no Python and no
GIL. The plugin reads the water it acts in from its own state (``plugin_state``: velocity, rate,
epoch; :func:`bauv_sim.hydro.set_water`), which the facade's sea writes each tick; the batched
variants write the same uniform current into each seed's plugin state once (a ``MjData`` each, a
bound ``plugin_state`` row of the batch, the plugin slice of each rollout state), beside
``option wind`` for MuJoCo's own drag. A current that varies along the path would need that
write per tick, as the facade does.

Variants, timed by :mod:`harness` (interleaved, warm-up, repeats, min and median, load):

* ``processes (cold pool)``: the runner's way: a fresh ``spawn`` process pool of ``--workers``, one
  seed per task, each seed its own :class:`~bauv_sim.physics.BauvPhysics` advanced tick by tick
  through the facade (sea, divergence checks); the pool's start-up is in the time;
* ``processes (warm pool)``: the same on a pool started (and imported) before the timing;
* ``MjData loop``: one process, one ``MjModel``, one ``MjData`` per seed, ``mj_step(m, d, n)`` per
  seed per tick with the model's ``opt.wind`` set to that seed's current (1 thread);
* ``mujoco.batch (1 thread)`` / ``(N threads)``: one persistent ``mujoco.batch.Batch`` of the 16
  seeds, ``opt.wind`` and ``body_gravcomp`` expanded per seed, ``Batch.step(nstep=n)`` per tick
  (the GIL released, the seeds spread over the threads);
* ``mujoco.rollout (N threads)``: ``mujoco.rollout.rollout`` per tick, one model copy per seed
  (its current and buoyancy), the state in and out each tick; rollout does not hand back the
  constraint solver's warm start, so its states differ from the others' in the last digits.

Reported per variant: wall time, the aggregate real-time factor (16 x simulated seconds / wall),
the CPU time used per wall second (how many cores it got: the machine is shared), and the
real-time factor per core used (16 x simulated seconds / CPU seconds, each call's CPU paired with
its own wall). Only the physics and the autopilot are batched here: a full mission also runs its
sensors, navigator and guidance per seed per tick (about 10 % over the physics in one process,
``bench_mission.py``), which would have to be vectorised over seeds as well.

Run from the repository root::

    python benchmarks/bench_batched_physics.py               # --seconds 60 --repeats 3
    python benchmarks/bench_batched_physics.py --write       # also into benchmarks/README.md
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import math
import multiprocessing
import os
import re
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (str(ROOT), str(ROOT / "benchmarks")):
    if p not in sys.path:
        sys.path.insert(0, p)

import mujoco  # noqa: E402
import mujoco.batch  # noqa: E402
import numpy as np  # noqa: E402
from harness import machine, measure  # noqa: E402

from bauv_sim import hydro  # noqa: E402

README = ROOT / "benchmarks" / "README.md"
SEED = 0
RUNS = 16
TICK_S = 0.2
COURSE_RAD = math.pi / 2
DEPTH_M = 3.0
SPEED_M_S = 1.0


def current_of(run: int) -> np.ndarray:
    """The uniform current of one run, world ENU, m/s, shape (3,)."""

    speed, direction = speed_direction(run)
    return np.array([speed * math.sin(direction), speed * math.cos(direction), 0.0])


def speed_direction(run: int) -> tuple[float, float]:
    """Speed (m/s) and set direction (towards, clockwise from north, rad) of a run's current."""
    from bauv_sim import rng

    g = rng.generator(SEED, run, "bench", "current")
    return float(g.uniform(0.0, 0.3)), float(g.uniform(0.0, 2 * math.pi))


class Pilot:
    """One seed's autopilot and the encoding of its commands into the model's ``ctrl``.

    The commands are turned into controls by the facade's own setters on a scratch physics (the
    same mapping and range checks as a mission), so every variant applies identical controls.
    """

    def __init__(self, encoder) -> None:
        from bauv_sim.autopilot import Autopilot, AutopilotConfig
        from bauv_sim.design.speed_table import load_speed_table

        table = load_speed_table()
        self.ap = Autopilot(AutopilotConfig(), lambda v: float(table.frequency_for(v)))
        self.enc = encoder
        self.lim = encoder.command_limits()

    def ctrl(self, qpos: np.ndarray, qvel: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Controls for the next tick from the free joint's state.

        Args:
            qpos: the vehicle's free-joint position (x, y, z, qw, qx, qy, qz), world ENU.
            qvel: its velocity (vx, vy, vz world; wx, wy, wz body), m/s and rad/s.
            current: the water velocity at the vehicle, world ENU, m/s, shape (3,).

        Returns:
            The ``ctrl`` vector of the model, shape (nu,).
        """
        from bauv_sim.autopilot import Measured
        from bauv_sim.frames import (
            attitude_from_quat_wxyz_scalar,
            navigation_rates_from_body,
            unit_vector_scalar,
        )

        _, (r, pt, h) = attitude_from_quat_wxyz_scalar(*qpos[3:7].tolist())
        roll_rate, pitch_rate, heading_rate = navigation_rates_from_body(qvel[3:6])
        east, north = unit_vector_scalar(h)
        x_axis = np.array([math.cos(pt) * east, math.cos(pt) * north, math.sin(pt)])
        u = float((qvel[:3] - current) @ x_axis)
        m = Measured(h, heading_rate, -float(qpos[2]), pt, pitch_rate, r, roll_rate, u)
        c = self.ap.step(TICK_S, COURSE_RAD, DEPTH_M, SPEED_M_S, m)
        e, lim = self.enc, self.lim
        e.set_tail_beat_frequency_hz(float(np.clip(c.tail_beat_hz, *lim["tail_beat_frequency_hz"])))
        e.set_tail_bias_rad(float(np.clip(c.tail_bias_rad, *lim["tail_bias_rad"])))
        e.set_lateral_fins_rad(
            float(np.clip(c.fin_port_rad, *lim["fin_port_rad"])),
            float(np.clip(c.fin_starboard_rad, *lim["fin_starboard_rad"])),
        )
        e.set_battery_position_m(float(np.clip(c.battery_m, *lim["battery_position_m"])))
        return np.array(e.data.ctrl)


def _start(timestep_s: float):
    """The facade at the start state (heading east at 1 m/s, 3 m depth, over the origin)."""
    from bauv_sim.physics import BauvPhysics

    p = BauvPhysics.from_scene_xml(control_tick_s=TICK_S, timestep_s=timestep_s)
    p.set_pose([0.0, 0.0, -DEPTH_M], [0.0, 0.0, COURSE_RAD], [SPEED_M_S, 0.0, 0.0])
    return p


def one_seed(run: int, seconds: float, timestep_s: float) -> tuple[np.ndarray, float]:
    """One seed through the facade (what a worker process runs).

    Returns:
        ``(final qpos, CPU seconds of this call)``.
    """
    from bauv_sim.currents import UniformCurrent
    from bauv_sim.sea import Sea

    c0 = time.process_time()
    cur = current_of(run)
    p = _start(timestep_s)
    Sea(UniformCurrent(*speed_direction(run))).immerse(p)
    pilot = Pilot(p)  # its setters write p's own controls
    for _ in range(round(seconds / TICK_S)):
        p.data.ctrl[:] = pilot.ctrl(p.data.qpos[:7], p.data.qvel[:6], cur)
        p.advance(TICK_S)
    return np.array(p.data.qpos), time.process_time() - c0


def _warm(_: int) -> int:
    import bauv_sim.autopilot
    import bauv_sim.physics  # noqa: F401

    return os.getpid()


def processes(pool: cf.ProcessPoolExecutor | None, workers: int, seconds: float, dt: float):
    """All seeds on a process pool (a fresh one if ``pool`` is None).

    Returns:
        The final qpos per seed, shape (16, nq), and the workers' CPU seconds: for a fresh pool
        everything its processes used (start-up and imports included, from the reaped children's
        resource usage), for a warm pool the CPU of the seeds' tasks.
    """
    import resource

    own = pool is None

    def children() -> float:
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        return r.ru_utime + r.ru_stime

    c0 = children()
    ex = pool or cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futs = [ex.submit(one_seed, r, seconds, dt) for r in range(RUNS)]
        out = [f.result() for f in futs]
    finally:
        if own:
            ex.shutdown()
    used = children() - c0 if own else sum(c for _, c in out)
    return np.array([q for q, _ in out]), used


def _model(timestep_s: float):
    p = _start(timestep_s)
    return p, p.model.ptr


def _instance(m) -> int:
    """The plugin instance of the scene's one vehicle."""
    (inst,) = hydro.plugin_instances(m).values()
    return inst


def mjdata_loop(seconds: float, dt: float) -> np.ndarray:
    """All seeds in one process: one model, one MjData per seed, one thread."""
    from bauv_sim.sea import submerged_fraction

    p0, m = _model(dt)
    n = p0.steps_per_tick
    cur = [current_of(r) for r in range(RUNS)]
    inst = _instance(m)
    datas = []
    for i in range(RUNS):
        d = mujoco.MjData(m)
        d.qpos[:] = p0.data.qpos
        d.qvel[:] = p0.data.qvel
        hydro.set_water(m, d, inst, cur[i])
        mujoco.mj_forward(m, d)
        datas.append(d)
    pilots = [Pilot(p0) for _ in range(RUNS)]  # p0: the scratch physics that encodes commands
    floats = np.flatnonzero(m.body_gravcomp > 0)
    g0 = m.body_gravcomp[floats].copy()
    for _ in range(round(seconds / TICK_S)):
        for i, d in enumerate(datas):
            d.ctrl[:] = pilots[i].ctrl(d.qpos[:7], d.qvel[:6], cur[i])
            m.opt.wind[:] = cur[i]
            m.body_gravcomp[floats] = g0 * submerged_fraction(-float(d.qpos[2]))
            mujoco.mj_step(m, d, n)
    for d in datas:
        if any(w.number for w in d.warning) or not np.isfinite(d.qpos).all():
            raise RuntimeError("a simulation of the MjData loop failed")
    return np.array([d.qpos for d in datas])


def batched(seconds: float, dt: float, nthread: int) -> np.ndarray:
    """All seeds in one ``mujoco.batch.Batch`` on ``nthread`` threads."""
    from bauv_sim.sea import submerged_fraction

    p0, m = _model(dt)
    n = p0.steps_per_tick
    b = mujoco.batch.Batch(m, RUNS, nthread, persistent=True)
    b.reset(stage=mujoco.mjtStage.mjSTAGE_NONE)
    qpos, qvel, ctrl = b.bind("qpos"), b.bind("qvel"), b.bind("ctrl")
    qpos[:] = p0.data.qpos
    qvel[:] = p0.data.qvel
    cur = np.array([current_of(r) for r in range(RUNS)])
    a = int(m.plugin_stateadr[_instance(m)])
    ps = b.bind("plugin_state")  # the plugin's water per seed: velocity, rate, epoch
    ps[:, a : a + 3] = cur
    ps[:, a + 3 : a + 7] = 0.0
    b.forward()
    wind = b.expand("opt.wind")
    wind[:] = cur
    grav = b.expand("body_gravcomp")
    floats = np.flatnonzero(m.body_gravcomp > 0)
    g0 = m.body_gravcomp[floats].copy()
    pilots = [Pilot(p0) for _ in range(RUNS)]  # p0: the scratch physics that encodes commands
    for _ in range(round(seconds / TICK_S)):
        for i in range(RUNS):
            ctrl[i] = pilots[i].ctrl(qpos[i, :7], qvel[i, :6], cur[i])
            grav[i, floats] = g0 * submerged_fraction(-float(qpos[i, 2]))
        b.step(nstep=n)
        st = np.asarray(b.status) if hasattr(b, "status") else None
        if st is not None and np.any(st != 0):
            raise RuntimeError(f"batch simulations failed: {[b.error(i) for i in range(RUNS)]}")
    return np.array(qpos)


def rolled_out(seconds: float, dt: float, nthread: int) -> np.ndarray:
    """All seeds through ``mujoco.rollout`` per tick (stateless: the state goes in and out each
    tick; one model copy per seed carries its current; the solver's warm start is not part of
    the state it returns, so every tick starts it from zero)."""
    import copy

    import mujoco.rollout

    from bauv_sim.sea import submerged_fraction

    p0, m = _model(dt)
    n = p0.steps_per_tick
    cur = [current_of(r) for r in range(RUNS)]
    models = []
    for i in range(RUNS):
        mi = copy.copy(m)
        mi.opt.wind[:] = cur[i]
        models.append(mi)
    datas = [mujoco.MjData(m) for _ in range(nthread)]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    x = np.empty((RUNS, mujoco.mj_stateSize(m, spec)))
    inst = _instance(m)
    scratch = mujoco.MjData(m)
    for i in range(RUNS):  # each seed's state carries its water in the plugin's slice
        mujoco.mj_copyData(scratch, m, p0.data.ptr)
        hydro.set_water(m, scratch, inst, cur[i])
        mujoco.mj_getState(m, scratch, x[i], spec)
    nq = m.nq
    qpos, qvel = x[:, 1 : 1 + nq], x[:, 1 + nq : 1 + nq + m.nv]  # after the time
    floats = np.flatnonzero(m.body_gravcomp > 0)
    g0 = m.body_gravcomp[floats].copy()
    pilots = [Pilot(p0) for _ in range(RUNS)]
    ctrl = np.empty((RUNS, 1, m.nu))
    out = np.empty((RUNS, n, x.shape[1]))
    for _ in range(round(seconds / TICK_S)):
        for i in range(RUNS):
            ctrl[i, 0] = pilots[i].ctrl(qpos[i, :7], qvel[i, :6], cur[i])
            models[i].body_gravcomp[floats] = g0 * submerged_fraction(-float(qpos[i, 2]))
        mujoco.rollout.rollout(
            models, datas, x, ctrl, nstep=n, state=out, persistent_pool=nthread > 1
        )
        x[:] = out[:, -1]
    if not np.isfinite(x).all():
        raise RuntimeError("a rollout failed")
    return np.array(qpos)


def main(argv: list[str] | None = None) -> str:
    """Run the variants, print the table and (with ``--write``) put it in the README."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="simulated per seed, s")
    ap.add_argument("--timestep", type=float, default=None, help="s (default: the preset)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--write", action="store_true", help="rewrite benchmarks/README.md's block")
    args = ap.parse_args(argv)
    from tasks.closed_loop.scenario import PHYSICS_TIMESTEP_S

    dt = args.timestep or PHYSICS_TIMESTEP_S
    sec, w = args.seconds, args.workers
    head = machine()
    pool = cf.ProcessPoolExecutor(w, mp_context=multiprocessing.get_context("spawn"))
    list(pool.map(_warm, range(4 * w)))
    finals: dict[str, list[np.ndarray]] = {}
    cpu: dict[str, list[float]] = {}

    def timed(name, fn):
        def run():
            c0 = time.process_time()
            res = fn()
            q, extra = res if isinstance(res, tuple) else (res, 0.0)
            cpu.setdefault(name, []).append(time.process_time() - c0 + extra)
            finals.setdefault(name, []).append(q)

        return run

    variants = {
        "processes (cold pool)": timed(
            "processes (cold pool)", lambda: processes(None, w, sec, dt)
        ),
        "processes (warm pool)": timed(
            "processes (warm pool)", lambda: processes(pool, w, sec, dt)
        ),
        "MjData loop (1 thread)": timed("MjData loop (1 thread)", lambda: mjdata_loop(sec, dt)),
        "mujoco.batch (1 thread)": timed("mujoco.batch (1 thread)", lambda: batched(sec, dt, 1)),
        f"mujoco.batch ({w} threads)": timed(
            f"mujoco.batch ({w} threads)", lambda: batched(sec, dt, w)
        ),
        f"mujoco.rollout ({w} threads)": timed(
            f"mujoco.rollout ({w} threads)", lambda: rolled_out(sec, dt, w)
        ),
    }
    res = measure(variants, repeats=args.repeats, warmup=1)
    pool.shutdown()
    ref_name = "processes (cold pool)"
    ref_q = finals[ref_name][0]
    sim = RUNS * sec
    lines = [
        f"{head}. {RUNS} seeds x {sec:g} s simulated at {dt * 1000:g} ms "
        f"({round(TICK_S / dt)} steps per {TICK_S:g} s tick), {w} workers / threads; "
        f"{args.repeats} interleaved repeats after a warm-up. RTF = real-time factor.",
        "",
        "| variant | wall min (s) | wall median (s) | aggregate RTF (median) | CPU / wall "
        "(median) | RTF per core used (median; min-max) | same states as processes | load |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, r in res.items():
        walls = r.seconds
        cw = [c / s for c, s in zip(cpu[name][1:], walls, strict=True)]
        per_core = [sim / c for c in cpu[name][1:]]
        same = all(np.array_equal(q, ref_q) for q in finals[name])
        worst = max(float(np.max(np.abs(q - ref_q))) for q in finals[name])
        lo, hi = r.load_range
        lines.append(
            f"| {name} | {min(walls):.2f} | {statistics.median(walls):.2f} | "
            f"{sim / statistics.median(walls):.0f}x | {statistics.median(cw):.2f} | "
            f"{statistics.median(per_core):.0f}x ({min(per_core):.0f}-{max(per_core):.0f}) | "
            f"{'bit for bit' if same else f'max |dq| {worst:.2g}'} | {lo:.2f}-{hi:.2f} |"
        )
    ref = res[ref_name]
    lines += [
        "",
        "Wall-time ratio to the cold-pool processes (median): "
        + ", ".join(f"{n} {ref.median / r.median:.2f}x" for n, r in res.items() if n != ref_name)
        + ".",
    ]
    report = "\n".join(lines)
    print(report)
    if args.write:
        text = README.read_text()
        block = f"<!-- BEGIN batched -->\n{report}\n<!-- END batched -->"
        text, k = re.subn(
            r"<!-- BEGIN batched -->.*?<!-- END batched -->", lambda _: block, text, flags=re.S
        )
        if k != 1:
            raise RuntimeError(f"{README}: no unique batched block")
        README.write_text(text)
    return report


if __name__ == "__main__":
    main()
