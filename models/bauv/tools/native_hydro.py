"""The native (GPU-ready) hydrodynamics against the plugin ``bauv.hydro`` on the manoeuvres
(issue 27, check 5).

Both formulations (:mod:`bauv_sim.hydro_native`) fly the same manoeuvres from the same start at
the missions' 4 ms preset: the cruise swim (speed through water, motor power), turns with a tail
bias of -20, -10, +10, +20 deg (rate, radius), the autopilot's 5 m depth step (rise time,
overshoot), the +0.2 rad fin step (depth rate) and 0.3 m/s current steps along and across the
track (the ground velocity over the 20 s after the step and the lateral offset of the track
20 s after it). The differences are judged with the timestep table's thresholds
(:data:`timestep.THRESHOLDS`, ``models/bauv/README.md`` Results 8); the current steps with
1 % of the ground velocity (the cruise-speed bound) and 0.1 m of offset (the autopilot's own
depth band).

Run from the repository root::

    python models/bauv/tools/native_hydro.py                 # both, writes the README table
    python models/bauv/tools/native_hydro.py --only native --json /tmp/native.json
    python models/bauv/tools/native_hydro.py --from /tmp/plugin.json /tmp/native.json
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from timestep import README, THRESHOLDS, depth_step, rewrite

TIMESTEP_S = 0.004
"""The missions' preset, s."""

EXTRA_THRESHOLDS: dict[str, tuple[str, float]] = {
    "current_along_ground_speed_m_s": ("relative", 0.01),
    "current_across_ground_speed_m_s": ("relative", 0.01),
    "current_along_offset_m": ("absolute", 0.1),
    "current_across_offset_m": ("absolute", 0.1),
}
"""Bounds of the current steps (see the module docstring)."""


def _threshold(name: str) -> tuple[str, float]:
    if name in EXTRA_THRESHOLDS:
        return EXTRA_THRESHOLDS[name]
    base = name.replace("_m20", "").replace("_m10", "").replace("_p10", "").replace("_p20", "")
    return THRESHOLDS[base]


def current_step(
    frequency_hz: float, across: bool, approach_s: float = 20.0, after_s: float = 20.0
) -> tuple[float, float]:
    """Swim north at the cruise frequency with depth held, then step the water to 0.3 m/s along
    (north) or across (east) the track.

    Returns:
        Ground speed over the window after the step (m/s) and the track's offset from the
        start line across the swim direction at its end (m, east +).
    """
    from bauv_sim import manoeuvres

    p = manoeuvres.open_water_scene(speed_m_s=1.0)
    p.set_timestep(TIMESTEP_S)
    hold = manoeuvres.DepthHold(p.depth_m())
    p.set_tail_beat_frequency_hz(frequency_hz)
    tick = p.control_tick_s
    for _ in range(round(approach_s / tick)):
        fin = hold.fins_rad(p)
        p.set_lateral_fins_rad(fin, fin)
        p.advance(tick)
    p.set_water_world([0.3, 0.0, 0.0] if across else [0.0, 0.3, 0.0])
    p0 = p.position_world()
    for _ in range(round(after_s / tick)):
        fin = hold.fins_rad(p)
        p.set_lateral_fins_rad(fin, fin)
        p.advance(tick)
    d = p.position_world() - p0
    return float(np.hypot(d[0], d[1]) / after_s), float(p.position_world()[0])


def fly(kind: str) -> dict[str, float]:
    """Fly every manoeuvre with one formulation; the figures by name."""
    from checks import cruise_frequency_hz

    from bauv_sim import hydro_native, manoeuvres

    f = cruise_frequency_hz()
    out: dict[str, float] = {}
    t0 = time.perf_counter()
    with hydro_native.formulation(kind):

        def scene():
            p = manoeuvres.open_water_scene(speed_m_s=1.0)
            p.set_timestep(TIMESTEP_S)
            return p

        swim = manoeuvres.straight_swim(scene(), f)
        out["cruise_speed_m_s"] = swim.speed_through_water_m_s
        out["cruise_power_w"] = float(swim.mean_motor_power_w)
        for tag, deg in (("m20", -20.0), ("m10", -10.0), ("p10", 10.0), ("p20", 20.0)):
            turn = manoeuvres.heading_change(scene(), f, math.radians(deg))
            out[f"turn_rate_deg_s_{tag}"] = math.degrees(turn.turn_rate_rad_s)
            out[f"turn_radius_m_{tag}"] = turn.turning_radius_m
        out["fin_step_depth_rate_m_s"] = manoeuvres.depth_change(scene(), f, 0.2).depth_rate_m_s
        rise, overshoot = depth_step(TIMESTEP_S, f)
        out["depth_rise_time_s"], out["depth_overshoot_percent"] = rise, overshoot
        for tag, across in (("along", False), ("across", True)):
            speed, offset = current_step(f, across)
            out[f"current_{tag}_ground_speed_m_s"] = speed
            out[f"current_{tag}_offset_m"] = offset
    out["wall_s"] = time.perf_counter() - t0
    return out


def compare(ref: dict[str, float], nat: dict[str, float]) -> tuple[str, bool]:
    """A markdown table of the two and whether every figure holds its bound."""
    rows = [
        "| quantity | plugin | native | difference | bound | holds |",
        "|---|---:|---:|---:|---:|:---:|",
    ]
    ok = True
    for name, x_ref in ref.items():
        if name == "wall_s":
            continue
        x = nat[name]
        kind, bound = _threshold(name)
        if kind == "relative":
            diff = abs(x - x_ref) / abs(x_ref)
            text, btext = f"{100 * diff:.2f} %", f"{100 * bound:g} %"
        else:
            diff = abs(x - x_ref)
            text, btext = f"{diff:.3f}", f"{bound:g}"
        holds = diff <= bound
        ok &= holds
        rows.append(
            f"| {name} | {x_ref:.4g} | {x:.4g} | {text} | {btext} | {'yes' if holds else 'NO'} |"
        )
    return "\n".join(rows), ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=("plugin", "native"), help="fly one formulation")
    ap.add_argument("--json", type=Path, help="write the figures of --only here")
    ap.add_argument("--from", dest="files", nargs=2, type=Path, help="plugin.json native.json")
    ap.add_argument("--no-write", action="store_true", help="do not rewrite the README table")
    a = ap.parse_args(argv)
    if a.only:
        res = fly(a.only)
        print(json.dumps(res, indent=1))
        if a.json:
            a.json.write_text(json.dumps(res, indent=1))
        return 0
    if a.files:
        ref, nat = (json.loads(p.read_text()) for p in a.files)
    else:
        ref, nat = fly("plugin"), fly("native")
    table, ok = compare(ref, nat)
    print(table)
    print("every figure within its bound" if ok else "SOME FIGURE OUTSIDE ITS BOUND")
    if not a.no_write:
        rewrite(README, "results:native-hydro", table)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
