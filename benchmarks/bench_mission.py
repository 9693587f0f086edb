"""The default mission's cost, and what sensors, navigation, guidance and recording add to physics.

Measured in one run, on the same model and for the same simulated time, through
:mod:`harness` (interleaved repeats after a warm-up, min and median, the load beside each):

* **raw physics**: the scene of ``mission/survey`` stepped tick by tick through the actuator
  commands the mission gave (current and free surface applied per tick, as in the mission), so
  that MuJoCo does the same work, with no sensing, navigation or guidance in between;
* **mission loop**: ``mission/survey`` through its dm_control environment with sensors, the
  navigator, guidance and the pilot in the loop;
* **overhead** = mission / raw - 1 (target: at most 15 %), and per control tick: the physics'
  time and the Python of the loop (mission - raw), the part that vectorising the sensors,
  navigation and guidance over seeds could shrink (issue 13, batched physics);
* the navigator's EKF per seed and tick, batched over ``--seeds`` seeds (``nav.ekf.BatchEKF``)
  against the single-run filter the mission uses (``nav.ekf.SingleRunEKF``) once per seed: the
  prediction (every tick) and a USBL update (every 5 s), on the mission's motion model with the
  current in the state (what vectorising the navigation over seeds would buy at best);
* the recording's wall time, the wall time of ``bauv run mission/survey`` (report included) and a
  16-seed Monte Carlo of ``mission/survey`` on 2 local workers (its throughput against the one-run
  command's), once each.

Usage: ``python benchmarks/bench_mission.py [--survey-s 300] [--repeats 5] [--seeds 16]
[--workers 2] [--skip-mc] [--loop-only]``
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np
from harness import machine, measure, table

from nav.ekf import BatchEKF, SingleRunEKF
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion, UsblMeasurement
from tasks.closed_loop.report import record_mission
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import WaypointMission, build_environment
from tasks.core.runner import plan_batch, run


def raw_physics(env, actions: list) -> None:
    """Step the mission's scene (a fresh environment, reset) through the same actuator commands,
    tick by tick (current and free surface applied per tick), with no sensing, navigation or
    guidance."""
    p = env.physics
    for a in actions:
        p.set_tail_beat_frequency_hz(float(a[0]))
        p.set_tail_bias_rad(float(a[1]))
        p.set_lateral_fins_rad(float(a[2]), float(a[3]))
        p.set_battery_position_m(float(a[4]))
        env.task.parts.sea.apply(p)
        p.step(p.steps_per_tick)


def mission_loop(env) -> list:
    """One mission run through its environment (fresh, not reset); returns the actions taken."""
    ts = env.reset()
    pilot = env.task.policy(env.action_spec())
    actions = []
    while not ts.last():
        a = pilot(ts.observation)
        actions.append(a)
        ts = env.step(a)
    return actions


def fresh(scn: MissionScenario, calls: int, reset: bool) -> list:
    """Environments built (and reset) before the timing, one per timed or warm-up call: their
    construction (MJCF, compilation) is not part of either variant."""
    envs = [build_environment(WaypointMission(), scn, 0, 0) for _ in range(calls)]
    if reset:
        for env in envs:
            env.reset()
    return envs


def ekf_over_seeds(seeds: int, repeats: int, calls: int = 200) -> None:
    """The navigator's EKF per seed and tick: batched over the seeds against one single-run
    filter per seed (the mission's), prediction and USBL update, interleaved."""
    motion = CurrentAwareMotion(CourseSpeedDepthMotion(math.radians(1.0), 0.05, 0.02), 0.005)
    usbl = UsblMeasurement(np.array([0.0, 0.0, -20.0]), 0.2, math.radians(3), math.radians(3))
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(0.0, 50.0, (seeds, 3)), rng.normal(0.0, 0.1, (seeds, 2))], 1)
    P = np.broadcast_to(np.eye(5), (seeds, 5, 5)).copy()
    u = np.column_stack([rng.uniform(0.0, 2 * math.pi, seeds), np.ones(seeds), np.zeros(seeds)])
    z = usbl.h(x) + 0.01
    batch, single = BatchEKF(motion), SingleRunEKF(motion)
    rows = [slice(i, i + 1) for i in range(seeds)]

    def repeat(f):
        def run() -> None:
            for _ in range(calls):
                f()

        return run

    variants = {
        f"predict, batched ({seeds} seeds)": repeat(lambda: batch.predict(x, P, u, 0.2)),
        "predict, single-run per seed": repeat(
            lambda: [single.predict(x[r], P[r], u[r], 0.2) for r in rows]
        ),
        f"USBL update, batched ({seeds} seeds)": repeat(lambda: batch.update(x, P, usbl, z)),
        "USBL update, single-run per seed": repeat(
            lambda: [single.update(x[r], P[r], usbl, z[r]) for r in rows]
        ),
    }
    res = measure(variants, repeats=repeats, warmup=1, per={k: calls * seeds for k in variants})
    print("the navigator's EKF, per seed and call (us):")
    print(table(res, reference="predict, single-run per seed", unit="us", scale=1e6))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--survey-s", type=float, default=300.0, help="simulated s of the survey")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-mc", action="store_true")
    ap.add_argument(
        "--loop-only", action="store_true", help="only the loop against physics and the EKF"
    )
    a = ap.parse_args()
    print(machine())
    scn = plan_batch("mission/survey", overrides=[f"timing.max_duration_s={a.survey_s}"]).scenario
    first = build_environment(WaypointMission(), scn, 0, 0)
    actions = mission_loop(first)
    task = first.task
    ticks = len(actions)
    loops, raws = fresh(scn, a.repeats + 1, False), fresh(scn, a.repeats + 1, True)
    res = measure(
        {
            "mission loop": lambda: mission_loop(loops.pop()),
            "raw physics": lambda: raw_physics(raws.pop(), actions),
        },
        repeats=a.repeats,
        warmup=1,
    )
    sim = float(task.result(None).lead["t"][-1])
    loop, raw = res["mission loop"], res["raw physics"]
    print(
        f"mission/survey, its first {sim:.0f} s ({ticks} ticks of {scn.timing.control_tick_s:g} s, "
        f"{scn.timing.physics_timestep_s * 1e3:g} ms physics step), wall s:"
    )
    print(table(res, reference="raw physics", unit="s"))
    for what, f in (("median", lambda r: r.median), ("min", lambda r: r.min)):
        print(
            f"by the {what}: overhead of sensors + navigation + guidance + pilot "
            f"{100 * (f(loop) / f(raw) - 1):.1f} % (target <= 15 %); per tick: physics "
            f"{1e3 * f(raw) / ticks:.3f} ms, the loop's Python "
            f"{1e3 * (f(loop) - f(raw)) / ticks:.3f} ms"
        )
    ekf_over_seeds(a.seeds, a.repeats)
    if a.loop_only:
        return
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        record_mission("mission/survey", scn, task.result(None), out)
        print(f"recording of the run above: {time.perf_counter() - t0:.2f} s")
        t0 = time.perf_counter()
        run("mission/survey", out_dir=out / "main", progress=False)
        one = time.perf_counter() - t0
        print(f"bauv run mission/survey (report, figures, recording): {one:.1f} s wall")
        if not a.skip_mc:
            t0 = time.perf_counter()
            run(
                "mission/survey",
                n_runs=a.seeds,
                workers=a.workers,
                out_dir=out / "mc",
                progress=False,
                overrides=["report.recording=false"],
            )
            wall = time.perf_counter() - t0
            print(
                f"{a.seeds} seeds on {a.workers} workers (no recording): {wall:.1f} s wall, "
                f"{a.seeds * one / wall:.2f}x the one-run command's throughput"
            )


if __name__ == "__main__":
    main()
