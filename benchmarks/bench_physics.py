"""Speed of the BAUV physics: raw MuJoCo steps per second, the facade's overhead, a batch of 16
vehicles, and what the time is spent on (issue 3, check 8).

Run from the repository root on an otherwise idle machine::

    python benchmarks/bench_physics.py            # prints and rewrites benchmarks/README.md
    python benchmarks/bench_physics.py --no-write

Every figure is the median of ``--repeats`` timings. Real-time factor = simulated seconds per
wall-clock second. Nothing here is asserted (speed is measured, not tested).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import re
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for _p in (str(ROOT), str(ROOT / "benchmarks")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

import mujoco  # noqa: E402
import mujoco.batch  # noqa: E402
import numpy as np  # noqa: E402

from bauv_sim import hydro  # noqa: E402
from bauv_sim.hull import MODEL_DIR  # noqa: E402
from bauv_sim.physics import BauvPhysics  # noqa: E402

README = ROOT / "benchmarks" / "README.md"


def _cruise_hz() -> float:
    from bauv_sim.design.speed_table import load_speed_table

    return float(load_speed_table().frequency_for(1.0))


CRUISE_HZ = _cruise_hz()


def _model(path: Path = MODEL_DIR / "scene.xml") -> mujoco.MjModel:
    return hydro.load_model(path)


def _cruising(m: mujoco.MjModel) -> mujoco.MjData:
    d = mujoco.MjData(m)
    k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "trim")
    mujoco.mj_resetDataKeyframe(m, d, k)
    mujoco.mj_step(m, d, 500)  # past the start-up transient
    return d


CPU_PER_WALL: dict[str, float] = {}
"""Process CPU time over wall time of the last timing of each measurement (threads in use)."""


RATE_PER_CORE: dict[str, float] = {}
"""Median over repeats of each repeat's steps per CPU second (its rate over its own CPU/wall)."""


def _median_rate(fn: Callable[[], int], repeats: int, label: str = "") -> float:
    """Median of ``steps / seconds`` over repeats of ``fn`` (which returns the steps it took);
    the median CPU/wall and the median of each repeat's steps per CPU second go into
    :data:`CPU_PER_WALL` and :data:`RATE_PER_CORE` (each repeat's CPU paired with its own wall)."""
    rates, cpw, per_core = [], [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        n = fn()
        wall = time.perf_counter() - t0
        cpu = time.process_time() - c0
        rates.append(n / wall)
        cpw.append(cpu / wall)
        per_core.append(n / max(cpu, 1e-9))
    CPU_PER_WALL[label] = statistics.median(cpw)
    RATE_PER_CORE[label] = statistics.median(per_core)
    return statistics.median(rates)


def raw_steps_per_s(m: mujoco.MjModel, nstep: int, repeats: int) -> float:
    """``mj_step(m, d, nstep)``: the stepping loop in C, single thread."""
    d = _cruising(m)

    def run() -> int:
        mujoco.mj_step(m, d, nstep)
        return nstep

    return _median_rate(run, repeats)


def facade_steps_per_s(seconds: float, repeats: int, energy: bool) -> float:
    """``BauvPhysics.advance`` in 0.1 s control ticks (per-tick current and checks; with
    ``energy``, the per-step motor-energy accounts), single thread."""
    phys = BauvPhysics.from_scene_xml()
    phys.set_energy_tracking(energy)
    phys.reset_to_keyframe("trim")
    from bauv_sim.currents import UniformCurrent
    from bauv_sim.sea import Sea

    Sea(UniformCurrent(0.3, 0.5)).immerse(phys)
    n = round(seconds / phys.timestep())

    def run() -> int:
        phys.advance(seconds)
        return n

    return _median_rate(run, repeats)


def batch_steps_per_s(
    m: mujoco.MjModel, nsim: int, nthread: int, nstep: int, repeats: int
) -> float:
    """``mujoco.batch.Batch``: ``nsim`` copies of the vehicle stepped on ``nthread`` threads with
    per-simulation currents (``opt.wind``), aggregate steps per second."""
    b = mujoco.batch.Batch(m, nsim, nthread, persistent=True)
    k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "trim")
    b.reset(keyframe=k)
    wind = b.expand("opt.wind")
    rng = np.random.default_rng(0)
    wind[:] = np.c_[rng.uniform(-0.3, 0.3, (nsim, 2)), np.zeros(nsim)]
    b.step(nstep=500)

    def run() -> int:
        b.step(nstep=nstep)
        return nstep * nsim

    rate = _median_rate(run, repeats, f"batch{nthread}")
    st = np.asarray(b.status) if hasattr(b, "status") else None
    if st is not None and np.any(st != 0):
        raise RuntimeError(f"batch simulations failed: {[b.error(i) for i in range(nsim)]}")
    return rate


def ablations(nstep: int, repeats: int) -> list[tuple[str, float, float]]:
    """Steps per second with one cost removed at a time: where the time goes.

    Returns:
        ``(variant, steps/s, time per step in us)`` rows.
    """
    base = _model()
    rows = []

    def variant(name: str, edit: Callable[[mujoco.MjModel], None]) -> None:
        m = _model()
        edit(m)
        r = raw_steps_per_s(m, nstep, repeats)
        rows.append((name, r, 1e6 / r))

    variant("full scene (vehicle + seabed heightfield)", lambda m: None)
    rows.append(
        (
            "vehicle only (bauv.xml, no seabed)",
            *(lambda r: (r, 1e6 / r))(
                raw_steps_per_s(_model(MODEL_DIR / "bauv.xml"), nstep, repeats)
            ),
        )
    )

    def no_fluid(m: mujoco.MjModel) -> None:
        m.opt.density = 0.0
        m.opt.viscosity = 0.0

    variant("no fluid forces (density 0)", no_fluid)

    def no_contact(m: mujoco.MjModel) -> None:
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT

    variant("no contact detection", no_contact)

    def no_eq(m: mujoco.MjModel) -> None:
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_EQUALITY

    variant("no crank-rocker equality (tail loose)", no_eq)

    def euler(m: mujoco.MjModel) -> None:
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER

    variant("Euler integrator (diverges in long runs)", euler)
    del base
    return rows


def timestep_preset(dt: float, seconds: float = 40.0) -> tuple[float, float]:
    """Raw speed and cruise speed with another timestep (the accuracy it trades).

    Returns:
        ``(real-time factor, mean speed over the last 20 s in m/s)``.
    """
    m = _model()
    m.opt.timestep = dt
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "trim"))
    d.ctrl[2:4] = 0.0
    n = round(seconds / dt)
    t0 = time.perf_counter()
    mujoco.mj_step(m, d, n // 2)
    p0 = d.qpos[:3].copy()
    mujoco.mj_step(m, d, n - n // 2)
    wall = time.perf_counter() - t0
    u = float(np.linalg.norm(d.qpos[:3] - p0) / ((n - n // 2) * dt))
    if any(w.number for w in d.warning) or not np.isfinite(d.qpos).all():
        u = math.nan
    return seconds / wall, u


REMOVED_SENSORS = """  <sensor>
    <framepos name="ins_pos" objtype="site" objname="ins"/>
    <framequat name="ins_quat" objtype="site" objname="ins"/>
    <gyro name="ins_gyro" site="ins"/>
    <accelerometer name="ins_accel" site="ins"/>
    <velocimeter name="ins_velocity" site="ins"/>
    <jointpos name="tail_angle" joint="tail_yaw"/>
    <jointpos name="caudal_fin_angle" joint="caudal_fin_yaw"/>
    <jointvel name="crank_speed" joint="crank"/>
    <actuatorfrc name="motor_torque" actuator="motor"/>
  </sensor>
"""
"""The nine MuJoCo sensors ``models/bauv/bauv.xml`` had until issue 13 (nothing read them)."""


def _vehicle(sensors: bool) -> mujoco.MjModel:
    """``bauv.xml`` as it is, or with :data:`REMOVED_SENSORS` put back; both compiled the same way
    (from the file's text, with the model folder's assets)."""
    xml = (MODEL_DIR / "bauv.xml").read_text()
    if sensors:
        xml = xml.replace("  <keyframe>", REMOVED_SENSORS + "  <keyframe>")
    assets = {
        f"assets/{f.name}": f.read_bytes() for f in (MODEL_DIR / "assets").iterdir() if f.is_file()
    }
    m = mujoco.MjSpec.from_string(xml, assets=assets).compile()
    return m


def harness_presets(repeats: int, nstep: int, survey_s: float, sensors_only: bool = False) -> str:
    """The harness's interleaved timings of what issues 11 and 13 changed in the physics: the
    removed sensors, the raw step at 1, 2 and 4 ms, the hydrodynamics plugin's cost, and
    ``mission/survey`` at 1, 2 and 4 ms.

    Args:
        repeats: interleaved timed repeats of each variant (after one warm-up).
        nstep: physics steps per raw timing.
        survey_s: simulated seconds of ``mission/survey`` per timing (its first part).
        sensors_only: time the sensors alone.

    Returns:
        The Markdown section.
    """
    from harness import machine, measure, table

    from tasks.closed_loop.world import fly
    from tasks.core import registry
    from tasks.core.runner import plan_batch

    out = [f"Measured by `python benchmarks/bench_physics.py --presets` on {machine()}.", ""]
    # 1. the sensors: the vehicle alone (bauv.xml), with and without them, 2 ms; short calls and
    # many repeats, since the difference is a few per cent
    with_s, without = _vehicle(True), _vehicle(False)
    assert with_s.nsensor == 9 and without.nsensor == 0
    datas = {
        "with the 9 sensors": (with_s, _cruising(with_s)),
        "no sensors": (without, _cruising(without)),
    }
    ns, rs = max(1, nstep // 4), 6 * repeats
    res = measure(
        {k: (lambda m=m, d=d: mujoco.mj_step(m, d, ns)) for k, (m, d) in datas.items()},
        repeats=rs,
        per={k: ns for k in datas},
    )
    out += [
        f"The vehicle alone (`bauv.xml`), cruising from `trim`, 2 ms, `mj_step(m, d, {ns})`; "
        "time per step:",
        "",
        table(res, reference="with the 9 sensors", unit="us", scale=1e6),
        "",
    ]
    if sensors_only:
        return "\n".join(out)
    # 2. raw steps at each timestep: time per simulated second
    raw = {}
    for dt in (0.001, 0.002, 0.004):
        m = _model()
        m.opt.timestep = dt
        raw[f"{dt * 1000:g} ms"] = (m, _cruising(m), round(1.0 / dt))
    res = measure(
        {k: (lambda m=m, d=d, n=n: mujoco.mj_step(m, d, 10 * n)) for k, (m, d, n) in raw.items()},
        repeats=repeats,
        per={k: 10.0 for k in raw},
    )
    out += [
        "The scene (`scene.xml`), cruising, 10 s simulated per call; wall seconds per simulated "
        "second (the real-time factor is its inverse):",
        "",
        table(res, reference="1 ms", unit="s per simulated s"),
        "",
        "Real-time factor (median): "
        + ", ".join(f"{k} {1 / r.median:.0f}x" for k, r in res.items())
        + ".",
        "",
    ]
    # 2b. what the hydrodynamics plugin costs: mj_forward at the same cruising state of the scene
    # with and without it (stepping each would compare different motions: without the plugin
    # the vehicle has no lift and MuJoCo's virtual-mass artefact)
    spec = mujoco.MjSpec.from_file(str(MODEL_DIR / "scene.xml"))
    for plugin in list(spec.plugins):
        spec.delete(plugin)
    bare = spec.compile()
    full = _model()
    d_full = _cruising(full)
    d_bare = mujoco.MjData(bare)
    d_bare.qpos[:] = d_full.qpos
    d_bare.qvel[:] = d_full.qvel
    d_bare.act[:] = d_full.act
    pair = {"with bauv.hydro": (full, d_full), "without it": (bare, d_bare)}
    nf = max(1, nstep // 4)

    def forward(m: mujoco.MjModel, d: mujoco.MjData) -> None:
        for _ in range(nf):
            mujoco.mj_forward(m, d)

    res = measure(
        {k: (lambda m=m, d=d: forward(m, d)) for k, (m, d) in pair.items()},
        repeats=repeats,
        per={k: nf for k in pair},
    )
    out += [
        "The plugin `bauv.hydro` (issue 11): `mj_forward` at the same cruising state of the scene "
        f"with and without it, 2 ms, {nf} calls; time per call:",
        "",
        table(res, reference="without it", unit="us", scale=1e6),
        "",
    ]
    # 3. mission/survey, its first survey_s seconds, in process (sensors, navigation, guidance)
    exp = registry.get("mission/survey")
    flights = {}
    for dt in (0.001, 0.002, 0.004):
        scn = plan_batch(
            "mission/survey",
            overrides=[f"timing.physics_timestep_s={dt}", f"timing.max_duration_s={survey_s}"],
        ).scenario
        flights[f"{dt * 1000:g} ms"] = exp.flight(scn, 0, 0)
    res = measure(
        {k: (lambda f=f: fly(f[0], f[1], 0, 0)) for k, f in flights.items()},
        repeats=repeats,
        per={k: survey_s for k in flights},
    )
    out += [
        f"`mission/survey` (seed 0), its first {survey_s:g} s through "
        "`tasks.closed_loop.world.fly` (physics, sea, sensor rig, EKF navigation, guidance, "
        "autopilot; no report): wall seconds per simulated second:",
        "",
        table(res, reference="1 ms", unit="s per simulated s"),
        "",
        "Real-time factor (median): "
        + ", ".join(f"{k} {1 / r.median:.0f}x" for k, r in res.items())
        + ".",
    ]
    return "\n".join(out)


def _write_block(name: str, report: str) -> None:
    text = README.read_text() if README.exists() else "# Benchmarks\n"
    block = f"<!-- BEGIN {name} -->\n{report}\n<!-- END {name} -->"
    if f"<!-- BEGIN {name} -->" in text:
        text = re.sub(
            rf"<!-- BEGIN {name} -->.*?<!-- END {name} -->", lambda _: block, text, flags=re.S
        )
    else:
        text += "\n" + block + "\n"
    README.write_text(text)


def main(argv: list[str] | None = None) -> str:
    """Run the benchmarks, print the report and (unless ``--no-write``) put it in the README."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--nstep", type=int, default=20000)
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument(
        "--presets",
        action="store_true",
        help="only the harness's timings of the removed sensors, the raw step and mission/survey "
        "at 1, 2, 4 ms (block 'physics-presets')",
    )
    ap.add_argument("--survey-s", type=float, default=300.0, help="with --presets, s")
    ap.add_argument(
        "--sensors-only", action="store_true", help="with --presets: the sensor timing alone"
    )
    args = ap.parse_args(argv)
    if args.presets:
        report = harness_presets(args.repeats, args.nstep, args.survey_s, args.sensors_only)
        print(report)
        if not args.no_write:
            _write_block("physics-presets", report)
        return report
    m = _model()
    dt = m.opt.timestep
    load = os.getloadavg()[0]
    raw = raw_steps_per_s(m, args.nstep, args.repeats)
    fac = facade_steps_per_s(20.0, args.repeats, energy=False)
    fac_e = facade_steps_per_s(20.0, args.repeats, energy=True)
    b1 = batch_steps_per_s(m, 16, 1, 2000, args.repeats)
    b2 = batch_steps_per_s(m, 16, 2, 2000, args.repeats)
    b2_per_core = RATE_PER_CORE["batch2"]
    abl = ablations(args.nstep // 2, args.repeats)
    presets = [(x, *timestep_preset(x)) for x in (0.001, 0.002, 0.004)]
    cpu = platform.processor() or platform.machine()
    lines = [
        f"Measured by `python benchmarks/bench_physics.py` on {os.cpu_count()} cores ({cpu}), "
        f"Python {platform.python_version()}, MuJoCo {mujoco.__version__}; median of "
        f"{args.repeats} runs, the vehicle cruising at {CRUISE_HZ} Hz (keyframe `trim`), "
        f"timestep {dt * 1000:.0f} ms, implicitfast. Load average before the run: {load:.2f} "
        "(other jobs share the 2 cores; the batch rows give the process's CPU time per wall "
        "second, i.e. how many cores it actually got).",
        "",
        "| what | steps/s | real-time factor |",
        "|---|---|---|",
        f"| raw `mj_step`, one vehicle in the scene, 1 thread | {raw:,.0f} | {raw * dt:.1f}x |",
        f"| `BauvPhysics.advance` (0.1 s ticks, current, checks) | {fac:,.0f} "
        f"| {fac * dt:.1f}x ({100 * (raw / fac - 1):.0f} % overhead) |",
        f"| the same with motor-energy accounts (steps from Python) | {fac_e:,.0f} "
        f"| {fac_e * dt:.1f}x ({100 * (raw / fac_e - 1):.0f} % overhead) |",
        f"| `mujoco.batch.Batch`, 16 vehicles, 1 thread (aggregate; CPU/wall "
        f"{CPU_PER_WALL['batch1']:.2f}) | {b1:,.0f} | {b1 * dt:.1f}x |",
        f"| `mujoco.batch.Batch`, 16 vehicles, 2 threads (aggregate; CPU/wall "
        f"{CPU_PER_WALL['batch2']:.2f}) | {b2:,.0f} | {b2 * dt:.1f}x "
        f"(= {b2 * dt / 16:.1f}x per vehicle) |",
        "",
        f"With 2 threads the batch got {CPU_PER_WALL['batch2']:.2f} cores: "
        f"{b2_per_core:,.0f} steps/s per core used ({b2_per_core * dt:.0f}x real time per core), "
        "so "
        f"on two free cores about {2 * b2_per_core:,.0f} steps/s aggregate "
        f"({2 * b2_per_core * dt:.0f}x, {2 * b2_per_core * dt / 16:.1f}x per vehicle) "
        "(extrapolated, not measured).",
        "",
        f"Target: one vehicle at 60x real time or better at 2 ms: "
        f"**{'met' if raw * dt >= 60 else 'NOT met'}** ({raw * dt:.1f}x raw, "
        f"{fac * dt:.1f}x through the facade).",
        "",
        "Where the time goes (raw steps/s with one part removed; the difference is its cost):",
        "",
        "| variant | steps/s | us per step |",
        "|---|---|---|",
        *[f"| {name} | {r:,.0f} | {us:.1f} |" for name, r, us in abl],
        "",
        "Timestep presets (40 s of cruise from `trim`, mean speed over the last 20 s):",
        "",
        "| timestep | real-time factor | cruise speed m/s |",
        "|---|---|---|",
        *[f"| {x * 1000:.0f} ms | {rtf:.0f}x | {u:.4f} |" for x, rtf, u in presets],
    ]
    report = "\n".join(lines)
    print(report)
    if not args.no_write:
        _write_block("physics", report)
    return report


if __name__ == "__main__":
    main()
