"""Timestep presets of the BAUV physics, validated against a 1 ms step (issue 13).

A larger MuJoCo step is cheaper in proportion, but the vehicle's motion must not change with it.
Each preset is flown through the same manoeuvres as the reference step of 1 ms, from the same
start, and compared on what the missions depend on:

* **cruise speed** and **motor power**: the steady speed through water at the cruise tail-beat
  frequency and the mean mechanical power (:func:`bauv_sim.manoeuvres.straight_swim`, depth
  held, 30 s to settle, 20 s of whole beats);
* **turn rate**: the steady rate of change of heading with a 10 deg tail bias
  (:func:`bauv_sim.manoeuvres.heading_change`, the second half of a 60 s turn), and the radius;
* **depth response**: the autopilot's 5 m depth step at 1 m/s (``vehicle/autopilot``'s depth
  trial, :func:`tasks.vehicle.autopilot.fly_trial`): the 10-90 % rise time of the tail-beat
  averaged depth, its overshoot, and the open-loop depth rate after a +0.2 rad fin step
  (:func:`bauv_sim.manoeuvres.depth_change`).

A preset holds when every quantity agrees with 1 ms within :data:`THRESHOLDS` (relative, or
absolute where a relative figure is meaningless). The thresholds are set from what the missions
can tell apart, not fitted to the results: 1 % of cruise speed is 10 m in 1 km of dead reckoning,
smaller than the log's scale-factor error; 3 % of turn rate and 5 % of rise time are well inside
the autopilot's own margins (its loops settle within +-2 deg and +-0.1 m).

Run from the repository root (re-run after any change to the hull or its hydrodynamics)::

    python models/bauv/tools/timestep.py                   # 1, 2, 4 ms; rewrites the README tables
    python models/bauv/tools/timestep.py 0.001 0.004 --no-write
"""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REFERENCE_TIMESTEP_S = 0.001
"""The reference step, s."""

PRESETS_S = (0.002, 0.004, 0.005, 0.01)
"""The candidate presets, s."""

THRESHOLDS: dict[str, tuple[str, float]] = {
    "cruise_speed_m_s": ("relative", 0.01),
    "cruise_power_w": ("relative", 0.03),
    "turn_rate_deg_s": ("relative", 0.03),
    "turn_radius_m": ("relative", 0.03),
    "depth_rise_time_s": ("relative", 0.05),
    "depth_overshoot_percent": ("absolute", 2.0),
    "fin_step_depth_rate_m_s": ("relative", 0.05),
}
"""Allowed difference of each quantity from the reference: (kind, bound); relative is
|x - x_ref| / |x_ref|, absolute is |x - x_ref| in the quantity's unit."""

ROOT = Path(__file__).resolve().parents[3]
"""The repository root (this file is ``models/bauv/tools/timestep.py``)."""
README = ROOT / "models" / "bauv" / "README.md"
BENCH_README = ROOT / "benchmarks" / "README.md"


@dataclass(frozen=True)
class TimestepResult:
    """The manoeuvres flown with one timestep.

    Attributes:
        timestep_s: physics timestep, s.
        cruise_speed_m_s: steady speed through water at the cruise frequency, m/s.
        cruise_power_w: mean mechanical motor power in that swim, W.
        turn_rate_deg_s: steady turn rate with a 10 deg tail bias, deg/s (clockwise +).
        turn_radius_m: radius of the circle fitted to the turn, m.
        depth_rise_time_s: 10-90 % rise time of the autopilot's 5 m depth step, s.
        depth_overshoot_percent: its overshoot, % of the step.
        fin_step_depth_rate_m_s: open-loop depth rate after a +0.2 rad fin step, m/s (diving +).
    """

    timestep_s: float
    cruise_speed_m_s: float
    cruise_power_w: float
    turn_rate_deg_s: float
    turn_radius_m: float
    depth_rise_time_s: float
    depth_overshoot_percent: float
    fin_step_depth_rate_m_s: float


def rise_time_s(t_s: np.ndarray, y: np.ndarray, y0: float, y1: float) -> float:
    """Time for a step response to go from 10 % to 90 % of the step, s.

    The crossings are interpolated linearly between samples; the first crossing of each level is
    used.

    Args:
        t_s: sample times, s, shape (n,), increasing.
        y: response, shape (n,).
        y0: value before the step.
        y1: value after it.

    Returns:
        The rise time, s; ``inf`` if the response never reaches 90 %.
    """
    frac = (np.asarray(y, dtype=float) - y0) / (y1 - y0)

    def crossing(level: float) -> float:
        i = np.flatnonzero(frac >= level)
        if i.size == 0:
            return math.inf
        k = int(i[0])
        if k == 0:
            return float(t_s[0])
        a = (level - frac[k - 1]) / (frac[k] - frac[k - 1])
        return float(t_s[k - 1] + a * (t_s[k] - t_s[k - 1]))

    return crossing(0.9) - crossing(0.1)


DEPTH_STEP_AT_S = 10.0
"""When the autopilot's depth step is commanded in the validation trial, s."""


def depth_step_metrics(
    t_s: np.ndarray, depth_m: np.ndarray, sc, frequency_hz: float
) -> tuple[float, float]:
    """Rise time and overshoot of the autopilot's depth step from its depth record.

    The depth is averaged over one tail beat at ``frequency_hz`` (``beat_average``) before the
    10-90 % rise (:func:`rise_time_s`) and the overshoot past the new depth are read after
    :data:`DEPTH_STEP_AT_S`.

    Args:
        t_s: sample times, s, shape (n,).
        depth_m: depth, m, positive down, shape (n,).
        sc: the trial's ``AutopilotTrialsScenario`` (depth, step, control tick).
        frequency_hz: the cruise tail-beat frequency, Hz.

    Returns:
        The rise time, s, and the overshoot, % of the step.
    """
    from tasks.vehicle.autopilot import beat_average

    n = max(1, round(1.0 / (frequency_hz * sc.control_tick_s)))  # one tail beat
    depth = beat_average(np.asarray(depth_m, dtype=float), n)
    t = np.asarray(t_s, dtype=float)
    after = t >= DEPTH_STEP_AT_S
    y0, y1 = sc.depth_m, sc.depth_m + sc.depth_step_m
    rise = rise_time_s(t[after] - DEPTH_STEP_AT_S, depth[after], y0, y1)
    overshoot = max(0.0, float(np.max(depth[after] - y1))) / sc.depth_step_m * 100.0
    return rise, overshoot


def depth_step(timestep_s: float, frequency_hz: float) -> tuple[float, float]:
    """The autopilot's 5 m depth step on the full model (``fly_trial``, 80 s, the step at
    :data:`DEPTH_STEP_AT_S`) with one physics timestep: :func:`depth_step_metrics`.

    Args:
        timestep_s: physics timestep, s.
        frequency_hz: the cruise tail-beat frequency, Hz.

    Returns:
        The rise time, s, and the overshoot, % of the step.
    """
    from tasks.vehicle.autopilot import AutopilotTrialsScenario, fly_trial

    # copied without validation: the scenario field accepts only up to the largest validated
    # preset, and this script is what explores beyond it
    s = AutopilotTrialsScenario().model_copy(update={"physics_timestep_s": timestep_s})
    tr = fly_trial(
        s,
        80.0,
        lambda t: 0.0,
        lambda t: s.depth_m if t < DEPTH_STEP_AT_S else s.depth_m + s.depth_step_m,
        lambda t: s.speed_to_m_s,
    )
    return depth_step_metrics(tr["t"], tr["depth"], s, frequency_hz)


def fly(timestep_s: float, frequency_hz: float | None = None) -> TimestepResult:
    """Fly the validation manoeuvres with one timestep.

    Args:
        timestep_s: physics timestep, s (the 0.1 s and 0.2 s control ticks must be multiples).
        frequency_hz: cruise tail-beat frequency, Hz (default: from the speed table).

    Returns:
        The :class:`TimestepResult`.
    """
    from checks import cruise_frequency_hz

    from bauv_sim import manoeuvres

    f = frequency_hz or cruise_frequency_hz()

    def scene():
        p = manoeuvres.open_water_scene(speed_m_s=1.0)
        p.set_timestep(timestep_s)
        return p

    swim = manoeuvres.straight_swim(scene(), f)
    turn = manoeuvres.heading_change(scene(), f, math.radians(10.0))
    fin = manoeuvres.depth_change(scene(), f, 0.2)
    rise, overshoot = depth_step(timestep_s, f)
    return TimestepResult(
        timestep_s=timestep_s,
        cruise_speed_m_s=swim.speed_through_water_m_s,
        cruise_power_w=float(swim.mean_motor_power_w),
        turn_rate_deg_s=math.degrees(turn.turn_rate_rad_s),
        turn_radius_m=turn.turning_radius_m,
        depth_rise_time_s=rise,
        depth_overshoot_percent=overshoot,
        fin_step_depth_rate_m_s=fin.depth_rate_m_s,
    )


def difference(name: str, x: float, ref: float) -> float:
    """The difference of a quantity from the reference in the kind of :data:`THRESHOLDS`."""
    kind, _ = THRESHOLDS[name]
    return abs(x - ref) / abs(ref) if kind == "relative" else abs(x - ref)


def holds(res: TimestepResult, ref: TimestepResult) -> dict[str, bool]:
    """Whether each quantity of a preset agrees with the reference within its threshold."""
    return {
        k: difference(k, getattr(res, k), getattr(ref, k)) <= bound
        for k, (_, bound) in THRESHOLDS.items()
    }


def render(results: list[TimestepResult]) -> str:
    """The Markdown table of the presets against the first result (the reference)."""
    ref = results[0]
    labels = {
        "cruise_speed_m_s": "cruise speed (m/s)",
        "cruise_power_w": "cruise motor power (W)",
        "turn_rate_deg_s": "turn rate, 10 deg bias (deg/s)",
        "turn_radius_m": "turn radius (m)",
        "depth_rise_time_s": "5 m depth step, 10-90 % rise (s)",
        "depth_overshoot_percent": "depth step overshoot (%)",
        "fin_step_depth_rate_m_s": "fin step +0.2 rad, depth rate (m/s)",
    }
    head = ["quantity", "threshold"] + [f"{r.timestep_s * 1000:g} ms" for r in results]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k, label in labels.items():
        kind, bound = THRESHOLDS[k]
        thr = f"{bound * 100:g} %" if kind == "relative" else f"{bound:g}"
        cells = [label, thr]
        for r in results:
            x = getattr(r, k)
            if r is ref:
                cells.append(f"{x:.4g}")
                continue
            d = difference(k, x, getattr(ref, k))
            signed = x - getattr(ref, k)
            dtxt = (
                f"{signed / abs(getattr(ref, k)) * 100:+.2f} %"
                if kind == "relative"
                else f"{signed:+.2f}"
            )
            ok = "" if d <= bound else " **fails**"
            cells.append(f"{x:.4g} ({dtxt}{ok})")
        lines.append("| " + " | ".join(cells) + " |")
    verdicts = [
        f"{r.timestep_s * 1000:g} ms {'holds' if all(holds(r, ref).values()) else 'does not hold'}"
        for r in results[1:]
    ]
    lines += ["", f"Against {ref.timestep_s * 1000:g} ms: " + "; ".join(verdicts) + "."]
    return "\n".join(lines)


def rewrite(path: Path, name: str, body: str) -> None:
    """Replace the text between ``<!-- BEGIN NAME -->`` and ``<!-- END NAME -->`` in a file."""
    text = path.read_text()
    pat = re.compile(rf"(<!-- BEGIN {name} -->).*?(<!-- END {name} -->)", re.S)
    text, n = pat.subn(lambda m: m.group(1) + "\n" + body + "\n" + m.group(2), text)
    if n != 1:
        raise RuntimeError(f"{path}: no unique block {name!r}")
    path.write_text(text)


MISSIONS: dict[str, list[str]] = {
    "mission/survey": ["mission/survey", "--seed", "0"],
    "mission/correction": ["mission/correction", "--runs", "2", "--seed", "0"],
    "mission/correction, 8 runs": ["mission/correction", "--runs", "8", "--seed", "0"],
}
"""The missions whose outcome is compared across timesteps (the arguments of their golden runs,
``benchmarks/golden.py``)."""

HEADLINES: dict[str, tuple[str, ...]] = {
    "mission/survey": (
        "/runs[0]/summary/duration_s",
        "/runs[0]/summary/energy_j",
        "/runs[0]/summary/ekf_mean_error_m",
        "/runs[0]/summary/ekf_max_error_m",
        "/runs[0]/summary/dr_final_error_m",
        "/runs[0]/summary/max_closest_distance_m",
        "/runs[0]/summary/usbl_fixes",
    ),
    "mission/correction": (
        "/means/compensated.corrected_final_error_m",
        "/means/compensated.uncorrected_final_error_m",
        "/means/compensated.current_error_m_s",
        "/means/compensated.cross_track_m",
        "/means/direct.corrected_final_error_m",
        "/means/direct.cross_track_m",
        "/improvement_factor",
    ),
}
HEADLINES["mission/correction, 8 runs"] = HEADLINES["mission/correction"]
"""The quantities of each mission shown in the table (paths into ``metrics.json``)."""


def flatten(x: object, path: str = "") -> dict[str, float]:
    """Every finite number of a ``metrics.json`` document by its path (``/a/b[0]/c``)."""
    out: dict[str, float] = {}
    if isinstance(x, dict):
        for k, v in x.items():
            out.update(flatten(v, f"{path}/{k}"))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out.update(flatten(v, f"{path}[{i}]"))
    elif isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x):
        out[path] = float(x)
    return out


def mission_metrics(args: list[str], timestep_s: float) -> dict[str, float]:
    """Run ``bauv run ARGS`` at a timestep (figures and recording off) in a fresh process and
    return its ``metrics.json`` flattened (:func:`flatten`)."""
    import json
    import subprocess
    import sys
    import tempfile

    root = ROOT
    with tempfile.TemporaryDirectory(prefix="timestep-") as tmp:
        cmd = [sys.executable, "-m", "tasks.core.cli", "run", *args, "--out", tmp]
        cmd += ["--set", f"timing.physics_timestep_s={timestep_s}"]
        cmd += ["--set", "report.figures=false", "--set", "report.recording=false"]
        subprocess.run(cmd, check=True, cwd=root, stdout=subprocess.DEVNULL)
        return flatten(json.loads((Path(tmp) / "metrics.json").read_text()))


def render_missions(results: dict[str, dict[float, dict[str, float]]]) -> str:
    """The Markdown table of the missions' outcomes per timestep, with the largest relative
    difference of any number from the first timestep (the reference)."""
    lines = []
    for name, by_dt in results.items():
        steps = list(by_dt)
        ref = by_dt[steps[0]]
        head = ["quantity"] + [f"{dt * 1000:g} ms" for dt in steps]
        lines += [f"`{MISSIONS[name][0]}` ({' '.join(MISSIONS[name][1:])}):", ""]
        lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for key in HEADLINES[name]:
            cells = [key.rsplit("/", 1)[-1] if "summary" in key else key.lstrip("/")]
            for dt in steps:
                x = by_dt[dt].get(key, math.nan)
                r = ref.get(key, math.nan)
                if dt == steps[0] or r == 0:
                    cells.append(f"{x:.4g}")
                else:
                    cells.append(f"{x:.4g} ({(x - r) / abs(r) * 100:+.1f} %)")
            lines.append("| " + " | ".join(cells) + " |")
        worst = ["largest relative difference of any number", "-"]
        for dt in steps[1:]:
            d, where = 0.0, ""
            for k, r in ref.items():
                x = by_dt[dt].get(k, math.nan)
                rel = abs(x - r) / max(abs(r), 1e-300) if r != x else 0.0
                if rel > d:
                    d, where = rel, k
            worst.append(f"{d * 100:.1f} % ({where.lstrip('/')})")
        lines += ["| " + " | ".join(worst) + " |", ""]
    return "\n".join(lines).rstrip()


def main(argv: list[str] | None = None) -> list[TimestepResult]:
    """Fly the reference and the presets, print the table and write it into the READMEs."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("timesteps", nargs="*", type=float, help="s; the first is the reference")
    ap.add_argument("--no-write", action="store_true", help="print only")
    ap.add_argument(
        "--missions",
        action="store_true",
        help="instead fly mission/survey and mission/correction at 2 ms (the reference of "
        "their golden outputs), 1 ms and 4 ms and compare their metrics (about 15 minutes)",
    )
    args = ap.parse_args(argv)
    if args.missions:
        res = {
            name: {dt: mission_metrics(a, dt) for dt in (0.002, 0.001, 0.004)}
            for name, a in MISSIONS.items()
        }
        table = render_missions(res)
        print(table)
        if not args.no_write:
            rewrite(README, "results:timestep-missions", table)
        return []
    steps = args.timesteps or [REFERENCE_TIMESTEP_S, *PRESETS_S]
    results = []
    for dt in steps:
        results.append(fly(dt))
        print(results[-1], flush=True)
    table = render(results)
    print(table)
    if not args.no_write:
        for path in (README, BENCH_README):
            rewrite(path, "results:timestep", table)
    return results


if __name__ == "__main__":
    main()
