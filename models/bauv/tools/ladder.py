"""The fidelity ladder on a mission (issue 27, check 1's second half): ``mission/survey`` over the
same seeds on the full MuJoCo vehicle and on the manoeuvring model (``timing.world``), the
way-point table and the navigation errors of both with their Monte Carlo standard errors, and
whether each difference is within Monte Carlo noise; the speed of each world beside it. Writes
the table into ``models/bauv/README.md`` (section 13, between the ``results:ladder-survey``
markers).

Run from the repository root::

    python models/bauv/tools/ladder.py                # both batches (16 runs, 2 workers), table
    python models/bauv/tools/ladder.py --reuse        # the table from the batches in --out
    python models/bauv/tools/ladder.py --energy       # + the motor energy's difference traced

Each batch is the user's command, ``bauv run mission/survey --runs 16 --workers 2 --seed 0
--set timing.world=<world>`` (its report included), timed by ``benchmarks/harness.py`` (the two
worlds interleaved, the load beside each). ``--flights N`` adds the flight alone: run 0 flown in
this process on each world, interleaved, N repeats after a warm-up.

Statistics: for each quantity the mean over the runs and its standard error ``s / sqrt(n)`` on
each world; the difference (manoeuvring - full) against the standard error of a difference of two
independent means, ``z = d / sqrt(se_f^2 + se_m^2)``: within noise when ``|z| < 2``. The runs of
both batches share their seeds (start scatter, sensor noise, current streams), so the table also
gives the paired difference's ``z`` (mean of the per-run differences over its standard error),
the more sensitive test.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
README = ROOT / "models" / "bauv" / "README.md"
TAG = "ladder-survey"
WORLDS = ("mujoco", "manoeuvring")
MISSION = "mission/survey"

QUANTITIES: tuple[tuple[str, str, float], ...] = (
    ("waypoints_reached_by_truth", "way-points reached (truth, of 5)", 1.0),
    ("max_closest_distance_m", "worst closest approach (m)", 1.0),
    ("ekf_mean_error_m", "EKF mean error (m)", 1.0),
    ("ekf_max_error_m", "EKF max error (m)", 1.0),
    ("ekf_final_error_m", "EKF final error (m)", 1.0),
    ("dr_mean_error_m", "DR mean error (m)", 1.0),
    ("dr_final_error_m", "DR final error (m)", 1.0),
    ("usbl_fixes", "USBL fixes", 1.0),
    ("energy_j", "motor energy (kJ)", 1e-3),
    ("duration_s", "duration (s)", 1.0),
)
"""(summary key, row label, scale) of the navigation table."""


def _sh() -> None:
    sys.path.insert(0, str(ROOT / "benchmarks"))


def run_batches(out: Path, runs: int, workers: int, seed: int, repeats: int) -> dict:
    """Both worlds' batches, interleaved (``repeats`` each), into ``out/<world>``; their times."""
    _sh()
    from harness import machine, measure

    def batch(world: str):
        def call() -> None:
            d = out / world
            if d.exists():
                shutil.rmtree(d)
            subprocess.run(
                [sys.executable, "-m", "tasks.core.cli", "run", MISSION, "--runs", str(runs),
                 "--workers", str(workers), "--seed", str(seed), "--out", str(d), "--quiet",
                 "--set", f"timing.world={world}"],
                check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
            )  # fmt: skip

        return call

    res = measure({w: batch(w) for w in WORLDS}, repeats=repeats, warmup=0)
    info = {
        "machine": machine(),
        "runs": runs,
        "workers": workers,
        "seed": seed,
        "batch_s": {w: r.seconds for w, r in res.items()},
        "batch_load": {w: r.load for w, r in res.items()},
    }
    (out / "timing.json").write_text(json.dumps(info, indent=1))
    return info


def time_flights(seed: int, repeats: int) -> dict:
    """Run 0 of the survey flown in this process on each world, interleaved: seconds, load."""
    _sh()
    from harness import measure

    from tasks.closed_loop.world import fly
    from tasks.core import registry
    from tasks.core.runner import plan_batch

    exp = registry.get(MISSION)
    calls = {}
    for w in WORLDS:
        scn = plan_batch(MISSION, overrides=[f"timing.world={w}"]).scenario
        design, s = exp.flight(scn, seed, 0)
        calls[w] = lambda design=design, s=s: fly(design, s, seed, 0)
    res = measure(calls, repeats=repeats, warmup=1)
    return {w: {"s": r.seconds, "load": r.load} for w, r in res.items()}


def _stats(x: np.ndarray) -> tuple[float, float]:
    return float(np.mean(x)), float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else 0.0


def _row(label: str, f: np.ndarray, m: np.ndarray, paired: bool = True) -> str:
    mf, sf = _stats(f)
    mm, sm = _stats(m)
    d = mm - mf
    se = math.hypot(sf, sm)
    z = d / se if se > 0 else (0.0 if d == 0 else math.inf)
    zp = "-"
    if paired and len(f) == len(m) and len(f) > 1:
        dd = m - f
        sp = float(np.std(dd, ddof=1) / math.sqrt(len(dd)))
        zp = f"{float(np.mean(dd)) / sp:+.2f}" if sp > 0 else "0"
    ok = "yes" if abs(z) < 2 else "NO"
    return (
        f"| {label} | {mf:.4g} +- {sf:.2g} | {mm:.4g} +- {sm:.2g} | {d:+.3g} | {z:+.2f} | {zp} "
        f"| {ok} |"
    )


def load_batch(out: Path, world: str) -> dict:
    """The ``metrics.json`` of a batch; a failed run stops the tool (its runs must all fly)."""
    m = json.loads((out / world / "metrics.json").read_text())
    return m


def ladder_table(out: Path, timing: dict | None, flights: dict | None) -> str:
    """The Markdown block of section 13."""
    met = {w: load_batch(out, w) for w in WORLDS}
    ok = {w: [r for r in met[w]["runs"] if r["failed"] is None] for w in WORLDS}
    # pair the runs that succeeded on both worlds by run index
    common = sorted(set(r["run"] for r in ok["mujoco"]) & set(r["run"] for r in ok["manoeuvring"]))
    by = {w: {r["run"]: r for r in ok[w]} for w in WORLDS}
    n = {w: met[w]["n_runs"] for w in WORLDS}
    lines = [
        f"`{MISSION}`, seed {met['mujoco']['seed']}, runs 0-{n['mujoco'] - 1} on each world "
        f"(failed: full model {met['mujoco']['n_failed']}, manoeuvring "
        f"{met['manoeuvring']['n_failed']}); mean +- its standard error over the {len(common)} "
        "runs that flew on both; z: the difference over the standard error of a difference of "
        "independent means (within noise: |z| < 2); paired z: the per-run differences' mean "
        "over its standard error (same seeds).",
        "",
        "| quantity | full model (4 ms) | manoeuvring model | difference | z | paired z "
        "| within noise |",
        "|---|---|---|---|---|---|---|",
    ]
    for key, label, scale in QUANTITIES:
        f = np.array([by["mujoco"][r]["summary"][key] for r in common]) * scale
        m = np.array([by["manoeuvring"][r]["summary"][key] for r in common]) * scale
        lines.append(_row(label, f, m))
    wps = by["mujoco"][common[0]]["waypoints"]
    for j, w in enumerate(wps):
        f = np.array([by["mujoco"][r]["waypoints"][j]["closest_true_distance_m"] for r in common])
        m = np.array(
            [by["manoeuvring"][r]["waypoints"][j]["closest_true_distance_m"] for r in common]
        )
        lines.append(
            _row(
                f"way-point {j} ({w['east_m']:g}, {w['north_m']:g}): closest true approach (m)",
                f,
                m,
            )
        )
    for j in range(len(wps)):
        f = np.array([float(by["mujoco"][r]["waypoints"][j]["reached_by_truth"]) for r in common])
        m = np.array(
            [float(by["manoeuvring"][r]["waypoints"][j]["reached_by_truth"]) for r in common]
        )
        lines.append(_row(f"way-point {j} reached (truth, fraction)", f, m))
    sim = {w: sum(r["summary"]["duration_s"] for r in ok[w]) for w in WORLDS}  # simulated seconds
    lines.append("")
    if timing is not None:
        lines.append(
            f"Speed, the whole command (`bauv run {MISSION} --runs {timing['runs']} --workers "
            f"{timing['workers']} --set timing.world=...`, report included), {timing['machine']}:"
        )
        lines.append("")
        lines.append(
            "| world | wall (s) | simulated (s, all runs) | x real time | load before | "
            "full / world |"
        )
        lines.append("|---|---|---|---|---|---|")
        ref = min(timing["batch_s"]["mujoco"])
        for w in WORLDS:
            t = min(timing["batch_s"][w])
            load = ", ".join(f"{x:.2f}" for x in timing["batch_load"][w])
            lines.append(
                f"| {w} | {t:.1f} | {sim[w]:.0f} | {sim[w] / t:.0f} | {load} | {ref / t:.2f} |"
            )
    if flights is not None:
        lines.append("")
        lines.append(
            "The flight alone (run 0 in one process: physics, sensors, EKF, guidance, autopilot, "
            "run data; no report), interleaved, min and median of "
            f"{len(flights['mujoco']['s'])} after a warm-up:"
        )
        lines.append("")
        lines.append("| world | min (s) | median (s) | full / world (median) | load |")
        lines.append("|---|---|---|---|---|")
        ref = float(np.median(flights["mujoco"]["s"]))
        for w in WORLDS:
            s = flights[w]["s"]
            lo, hi = min(flights[w]["load"]), max(flights[w]["load"])
            lines.append(
                f"| {w} | {min(s):.2f} | {float(np.median(s)):.2f} | "
                f"{ref / float(np.median(s)):.2f} | {lo:.2f}-{hi:.2f} |"
            )
    return "\n".join(lines)


def _straight_legs(out: Path, world: str, runs: range) -> dict[str, float]:
    """Means over the straight legs (|tail bias command| < 2 deg, 10 s windows) of the first runs
    of a batch: commanded frequency (Hz), progress through the water (m/s: the norm of the
    window's mean velocity through water), the log's body-x speed (m/s), and the logged power
    against the straight-swim table at the commanded frequency (W)."""
    import pyarrow.parquet as pq

    from bauv_sim.manoeuvring.model import load_coefficients

    c = load_coefficients()
    acc: dict[str, list[float]] = {"f": [], "progress": [], "u": [], "power": [], "table": []}
    for r in runs:
        t = pq.read_table(out / world / "data" / "ticks" / f"run-{r:06d}-bauv.parquet").to_pandas()
        vw = t[["truth_vel_water_east", "truth_vel_water_north", "truth_vel_water_up"]].to_numpy()
        h = np.radians(t["truth_rph_deg_heading"].to_numpy())
        p = np.radians(t["truth_rph_deg_pitch"].to_numpy())
        u = np.cos(p) * (np.sin(h) * vw[:, 0] + np.cos(h) * vw[:, 1]) + np.sin(p) * vw[:, 2]
        f = t["cmd_tail_beat_frequency"].to_numpy()
        straight = np.abs(t["cmd_tail_bias_deg"].to_numpy()) < 2.0
        k = 50
        for i in range(0, len(t) - k, k):
            if straight[i : i + k].all():
                acc["f"].append(float(f[i : i + k].mean()))
                acc["progress"].append(float(np.linalg.norm(vw[i : i + k, :2].mean(0))))
                acc["u"].append(float(u[i : i + k].mean()))
        acc["power"].append(float(t["motor_power"].mean()))
        acc["table"].append(float(np.interp(f, c.power_frequency_hz, c.power_w).mean()))
    return {k: float(np.mean(v)) for k, v in acc.items()}


def _swim(world: str, frequency_hz: float, battery_m: float, fins=None) -> float:
    """Progress speed (m/s) over 50-100 s of a swim at 20 m, 0.2 s ticks (the full model at 4 ms):
    fins holding depth (``DepthHold``) or replaying ``fins`` (port, starboard commands per tick,
    rad, 500 each)."""
    from bauv_sim import manoeuvres
    from bauv_sim.manoeuvring import model as mm
    from bauv_sim.manoeuvring import trials

    if world == "manoeuvring":
        w = trials.start(mm.load_coefficients(), tick_s=0.2)
        w.command(tail_beat_frequency_hz=frequency_hz, battery_m=battery_m)
        for k in range(500):
            if fins is None:
                a = float(trials.depth_hold(w, 20.0)[0])
                w.command(fin_port_rad=a, fin_starboard_rad=a)
            else:
                w.command(fin_port_rad=fins[0][k], fin_starboard_rad=fins[1][k])
            w.step()
            if k == 249:
                p0, t0 = w.position_world_m[0].copy(), w.time_s
        return float(np.hypot(*(w.position_world_m[0, :2] - p0[:2])) / (w.time_s - t0))
    ph = manoeuvres.open_water_scene(speed_m_s=1.0)
    ph.set_timestep(0.004, 0.2)
    ph.set_tail_beat_frequency_hz(frequency_hz)
    ph.set_battery_position_m(battery_m)
    hold = manoeuvres.DepthHold(20.0)
    for k in range(500):
        if fins is None:
            a = hold.fins_rad(ph)
            ph.set_lateral_fins_rad(a, a)
        else:
            ph.set_lateral_fins_rad(float(fins[0][k]), float(fins[1][k]))
        ph.advance(0.2)
        if k == 249:
            p0, t0 = ph.position_world().copy(), ph.time_s()
    return float(np.hypot(*(ph.position_world()[:2] - p0[:2])) / (ph.time_s() - t0))


def energy_trace(out: Path) -> str:
    """The motor energy's difference traced (the model README's reading of section 13): power
    against the straight-swim table, the straight legs' frequency and progress, the trim's and
    the fins' unsteady motion's effect on the speed of both models."""
    import pyarrow.parquet as pq

    lines = ["Straight legs of runs 0-7 (10 s windows, |tail bias| < 2 deg):", ""]
    for w in WORLDS:
        s = _straight_legs(out, w, range(8))
        lines.append(
            f"- {w}: frequency {s['f']:.4f} Hz, progress through water {s['progress']:.4f} m/s, "
            f"log body-x speed {s['u']:.4f} m/s; mean power {s['power']:.3f} W against the "
            f"straight-swim table at its commands {s['table']:.3f} W"
        )
    t = pq.read_table(out / "manoeuvring" / "data" / "ticks" / "run-000000-bauv.parquet")
    t = t.to_pandas()
    straight = np.abs(t["cmd_tail_bias_deg"].to_numpy()) < 2.0
    fins = tuple(
        np.radians(t[c].to_numpy()[straight][:500])
        for c in ("cmd_fin_port_deg", "cmd_fin_starboard_deg")
    )
    lines += ["", "Swims at 0.61 Hz, 20 m deep, progress over 50-100 s (m/s):", ""]
    lines.append("| model | fins hold depth, battery 0 | battery 5 mm | survey fins replayed |")
    lines.append("|---|---|---|---|")
    for w in WORLDS:
        a, b, c = _swim(w, 0.61, 0.0), _swim(w, 0.61, 0.005), _swim(w, 0.61, 0.0, fins)
        lines.append(
            f"| {w} | {a:.4f} | {b:.4f} ({100 * (b / a - 1):+.2f} %) | "
            f"{c:.4f} ({100 * (c / a - 1):+.2f} %) |"
        )
    return "\n".join(lines)


def write_readme(block: str) -> None:
    """Replace the block between the ``results:ladder-survey`` markers of the model README."""
    text = README.read_text()
    pat = re.compile(rf"(<!-- BEGIN results:{TAG} -->\n).*?(<!-- END results:{TAG} -->)", re.S)
    if not pat.search(text):
        raise SystemExit(f"{README}: no results:{TAG} markers")
    README.write_text(pat.sub(lambda m: m.group(1) + block + "\n" + m.group(2), text))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "ladder")
    ap.add_argument("--repeats", type=int, default=1, help="batches of each world, interleaved")
    ap.add_argument("--flights", type=int, default=0, help="repeats of the flight alone (0: none)")
    ap.add_argument("--reuse", action="store_true", help="the batches already in --out")
    ap.add_argument("--no-readme", action="store_true", help="print the table only")
    ap.add_argument(
        "--energy", action="store_true", help="trace the motor energy's difference (prints)"
    )
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if a.reuse:
        tj = a.out / "timing.json"
        timing = json.loads(tj.read_text()) if tj.is_file() else None
    else:
        timing = run_batches(a.out, a.runs, a.workers, a.seed, a.repeats)
    flights = time_flights(a.seed, a.flights) if a.flights > 0 else None
    if flights is not None:
        (a.out / "flights.json").write_text(json.dumps(flights, indent=1))
    elif (a.out / "flights.json").is_file() and a.reuse:
        flights = json.loads((a.out / "flights.json").read_text())
    block = ladder_table(a.out, timing, flights)
    print(block)
    if a.energy:
        print(energy_trace(a.out))
    if not a.no_readme:
        write_readme(block)
        print(f"wrote {README} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
