"""The default mission's cost, and what sensors, navigation, guidance and recording add to physics.

Measured in one run, on the same model and for the same simulated time:

* **raw physics**: the scene of ``mission/survey`` stepped tick by tick through the actuator
  commands the mission gave (current and free surface applied per tick, as in the mission), so
  that MuJoCo does the same work, with no sensing, navigation or guidance in between;
* **mission loop**: ``mission/survey`` through its dm_control environment with sensors, the
  navigator, guidance and the pilot in the loop, plus the writing of its rerun recording;
* **overhead** = mission / raw - 1 (target: at most 15 %);
* the wall time of ``bauv run mission/survey`` (the README's main job, report included);
* a 16-seed Monte Carlo of ``mission/survey`` on 2 local workers: aggregate real-time factor.

Usage: ``python benchmarks/bench_mission.py [--seeds 16] [--workers 2] [--skip-mc]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from tasks.closed_loop.report import record_mission
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import WaypointMission, build_environment
from tasks.core.runner import plan_batch, run


def raw_physics(scn: MissionScenario, actions: list) -> float:
    """Wall time of stepping the mission's scene through the same actuator commands, tick by tick
    (current and free surface applied per tick), with no sensing, navigation or guidance, s."""
    env = build_environment(WaypointMission(), scn, 0, 0)
    env.reset()
    p = env.physics
    t0 = time.perf_counter()
    for a in actions:
        p.set_tail_beat_frequency_hz(float(a[0]))
        p.set_tail_bias_rad(float(a[1]))
        p.set_lateral_fins_rad(float(a[2]), float(a[3]))
        p.set_battery_position_m(float(a[4]))
        p.apply_sea()
        p.step(p.steps_per_tick)
    return time.perf_counter() - t0


def mission_loop(scn: MissionScenario, out: Path) -> tuple[float, float, float, list]:
    """``(loop wall s, recording wall s, simulated s, actions)`` of one mission run."""
    env = build_environment(WaypointMission(), scn, 0, 0)
    ts = env.reset()
    pilot = env.task.policy(env.action_spec())
    actions = []
    t0 = time.perf_counter()
    while not ts.last():
        a = pilot(ts.observation)
        actions.append(a)
        ts = env.step(a)
    loop = time.perf_counter() - t0
    res = env.task.result(None)
    t0 = time.perf_counter()
    record_mission("mission/survey", scn, res, out)
    rec = time.perf_counter() - t0
    return loop, rec, float(res.lead["t"][-1]), actions


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-mc", action="store_true")
    a = ap.parse_args()
    scn = plan_batch("mission/survey").scenario
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        loop, rec, sim, actions = mission_loop(scn, out)
        raw = raw_physics(scn, actions)
        print(
            f"simulated {sim:.0f} s: raw physics {raw:.2f} s ({sim / raw:.0f}x real time); "
            f"mission loop {loop:.2f} s + recording {rec:.2f} s"
        )
        print(
            f"overhead of sensors + navigation + guidance: {100 * (loop / raw - 1):.1f} %; "
            f"with the recording: {100 * ((loop + rec) / raw - 1):.1f} % (target <= 15 %)"
        )
        t0 = time.perf_counter()
        run("mission/survey", out_dir=out / "main", progress=False)
        print(
            f"bauv run mission/survey (report, figures, recording): "
            f"{time.perf_counter() - t0:.1f} s wall"
        )
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
                f"{a.seeds} seeds on {a.workers} workers: {wall:.1f} s wall, aggregate "
                f"{a.seeds * sim / wall:.0f}x real time (about {sim:.0f} s simulated each)"
            )


if __name__ == "__main__":
    main()
