"""The BAUV model's acceptance checks that take longer than a unit test (issue 3).

Each ``check_*`` function runs one experiment on the physics and returns its numbers; :func:`main`
runs them all, prints them, writes the speed calibration ``models/bauv/speed_table.csv``,
updates the ``trim`` keyframe of ``models/bauv/bauv.xml`` and rewrites the results tables of
``models/bauv/README.md`` (between ``<!-- BEGIN results:NAME -->`` and ``<!-- END ... -->``).

Run from the repository root (model tooling, outside the installed package)::

    python models/bauv/tools/checks.py            # everything (about 3 minutes on 2 cores)
    python models/bauv/tools/checks.py tow swim   # some checks only

Fast versions of the same checks are the unit tests in ``tests/bauv_sim``.
"""

from __future__ import annotations

import argparse
import math
import re
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bauv_sim import currents, hull, manoeuvres, rng, sea
from bauv_sim.design import fluid, speed_table
from bauv_sim.errors import ConfigError

if TYPE_CHECKING:
    from bauv_sim.physics import BauvPhysics


MODEL_DIR = Path(__file__).resolve().parents[1]
"""``models/bauv`` (this file is ``models/bauv/tools/checks.py``)."""
README = MODEL_DIR / "README.md"
VEHICLE_XML = MODEL_DIR / "bauv.xml"

CD_TARGET_RANGE = (0.08, 0.25)
"""Accepted drag coefficient of the towed vehicle on its frontal area: from a bare streamlined
body of revolution at Re 1e6-1e7 (Hoerner 1965, ch. 6: about 0.08 at this fineness) to torpedo
AUVs with fins and sensors (REMUS 100, Prestero 2001: about 0.2; +25 %)."""

STROUHAL_RANGE = (0.2, 0.5)
"""Accepted Strouhal number at cruise (issue 3); cruising fish and cetaceans 0.2-0.4 (Taylor,
Nudds & Thomas 2003, Nature 425: 707-711)."""

CRUISE_SPEED_M_S = 1.0
"""Seed 000: "assumed optimum cruise speed is around 1 m/s"."""

MOTOR_POWER_W = 250.0
"""Seed 000: "electric motor with nominal power 250 W"."""


def _scene(**kw: float) -> BauvPhysics:
    return manoeuvres.open_water_scene(**kw)


# --------------------------------------------------------------------------------------------
# 1. ten minutes of varied commands


@dataclass(frozen=True)
class LongSwimResult:
    """Ten minutes of varied commands (check 1)."""

    duration_s: float
    command_changes: int
    distance_m: float
    min_depth_m: float
    max_depth_m: float
    max_speed_m_s: float
    max_abs_roll_deg: float
    max_abs_pitch_deg: float
    max_abs_pitch_after_start_deg: float
    mujoco_warnings: int
    wall_s: float


def varied_commands(seed: int, duration_s: float, hold_s: float = 20.0) -> list[dict[str, float]]:
    """A seeded sequence of command sets, one per ``hold_s``: tail-beat frequency uniform on
    [0.3, 2.8] Hz, tail bias uniform on +-18 deg, battery uniform on +-0.06 m, a depth target
    uniform on [20, 60] m (held by the fins' :class:`~bauv_sim.manoeuvres.DepthHold`) and a fin
    offset uniform on +-0.1 rad on top of it."""
    gen = rng.generator(seed, 0, "vehicle_checks", "commands")
    out = []
    for _ in range(math.ceil(duration_s / hold_s)):
        out.append(
            {
                "frequency_hz": float(gen.uniform(0.3, 2.8)),
                "bias_rad": float(gen.uniform(-1.0, 1.0) * math.radians(18.0)),
                "battery_m": float(gen.uniform(-0.06, 0.06)),
                "depth_m": float(gen.uniform(20.0, 60.0)),
                "fin_offset_rad": float(gen.uniform(-0.1, 0.1)),
            }
        )
    return out


def run_commands(
    physics: BauvPhysics, commands: list[dict[str, float]], hold_s: float, record: bool = False
) -> np.ndarray | None:
    """Apply a command sequence (each set for ``hold_s``), the fins holding each depth target.

    Args:
        physics: the physics.
        commands: from :func:`varied_commands`.
        hold_s: time per command set, s.
        record: return the vehicle's position and quaternion at every control tick.

    Returns:
        Shape (ticks, 7) array of (position, quaternion) if ``record``, else None.
    """
    tick = physics.control_tick_s
    rows = []
    for c in commands:
        physics.set_tail_beat_frequency_hz(c["frequency_hz"])
        physics.set_tail_bias_rad(c["bias_rad"])
        physics.set_battery_position_m(c["battery_m"])
        hold = manoeuvres.DepthHold(c["depth_m"], limit_rad=0.4)
        for _ in range(round(hold_s / tick)):
            a = float(np.clip(hold.fins_rad(physics) + c["fin_offset_rad"], -0.5, 0.5))
            physics.set_lateral_fins_rad(a, a)
            physics.advance(tick)
            if record:
                rows.append(np.r_[physics.position_world(), physics.quat_wxyz()])
    return np.asarray(rows) if record else None


def check_ten_minute_swim(
    seed: int = 3, duration_s: float = 600.0, hold_s: float = 20.0
) -> LongSwimResult:
    """Swim for ``duration_s`` under seeded varied commands; any MuJoCo warning or divergence
    raises :class:`~bauv_sim.errors.PhysicsError` from the facade (check 1)."""
    t0 = time.perf_counter()
    phys = _scene(depth_m=40.0)
    cmds = varied_commands(seed, duration_s, hold_s)
    tick = phys.control_tick_s
    dist, depths, speeds, rolls, pitches, late = 0.0, [], [], [], [], [0.0]
    prev = phys.position_world()
    for c in cmds:
        phys.set_tail_beat_frequency_hz(c["frequency_hz"])
        phys.set_tail_bias_rad(c["bias_rad"])
        phys.set_battery_position_m(c["battery_m"])
        hold = manoeuvres.DepthHold(c["depth_m"], limit_rad=0.4)
        for _ in range(round(hold_s / tick)):
            a = float(np.clip(hold.fins_rad(phys) + c["fin_offset_rad"], -0.5, 0.5))
            phys.set_lateral_fins_rad(a, a)
            phys.advance(tick)
            p = phys.position_world()
            dist += float(np.linalg.norm(p - prev))
            prev = p
            depths.append(phys.depth_m())
            speeds.append(phys.speed_through_water_m_s())
            r, pt, _ = phys.roll_pitch_heading()
            rolls.append(abs(r))
            pitches.append(abs(pt))
            if phys.time_s() > 15.0:
                late.append(abs(pt))
    warnings = phys.warning_count()
    return LongSwimResult(
        phys.time_s(),
        len(cmds),
        dist,
        min(depths),
        max(depths),
        max(speeds),
        math.degrees(max(rolls)),
        math.degrees(max(pitches)),
        math.degrees(max(late)),
        warnings,
        time.perf_counter() - t0,
    )


# --------------------------------------------------------------------------------------------
# 2. buoyancy


@dataclass(frozen=True)
class BuoyancyResult:
    """Hydrostatics and the idle checks (check 2)."""

    displaced_volume_mesh_m3: float
    archimedes_n: float
    buoyancy_model_n: float
    weight_n: float
    net_up_n: float
    bg_m: float
    idle_depth_change_m_per_min: float
    idle_duration_s: float
    roll_settle_s: float
    roll_period_s: float
    roll_overshoot_deg: float


def check_buoyancy(idle_s: float = 300.0) -> BuoyancyResult:
    """Archimedes from the meshes, the model's forces, an idle hover and the roll decay."""
    phys = _scene(depth_m=20.0)
    hs = phys.hydrostatics()
    dorsal = hull.dorsal_fin_mesh().volume
    v_mesh = float(hull.hull_mesh(hull.HULL).volume + dorsal)
    g = phys.gravity_m_s2()
    # the self-neutral parts (tail, lateral fins) carry their own displacement: count it too
    ped = hull.peduncle_mesh(hull.HULL).volume
    fin = hull.caudal_fin_mesh(hull.TAIL).volume
    lat = 2 * hull.lateral_fin_mesh().volume
    archimedes = hull.SEAWATER_DENSITY_KG_M3 * g * (v_mesh + ped + fin + lat)
    z0 = phys.depth_m()
    phys.advance(idle_s)
    rate = (phys.depth_m() - z0) / (idle_s / 60.0)
    rr = manoeuvres.roll_recovery(_scene(depth_m=20.0), duration_s=20.0)
    return BuoyancyResult(
        v_mesh,
        archimedes,
        hs.buoyancy_n,
        hs.weight_n,
        hs.net_up_n,
        hs.metacentric_height_m(),
        rate,
        idle_s,
        rr.settle_time_s,
        rr.period_s,
        math.degrees(rr.max_overshoot_rad),
    )


# --------------------------------------------------------------------------------------------
# 3. tow test


@dataclass(frozen=True)
class TowResult:
    """Tow test (check 3)."""

    points: list[manoeuvres.TowPoint]
    target_cd: float
    target_range: tuple[float, float]
    budget: fluid.DragBudget
    same_in_current: bool


def check_tow(speeds: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5)) -> TowResult:
    """Drag vs speed from ``qfrc_fluid``, tail straight; also repeated in a 0.5 m/s current."""
    area = hull.HULL.frontal_area_m2()
    pts = manoeuvres.tow_test(_scene(), list(speeds), area)
    in_current = manoeuvres.tow_test(_scene(), list(speeds), area, current_m_s=0.5)
    same = all(
        abs(a.drag_n - b.drag_n) <= 1e-9 * max(1.0, a.drag_n)
        for a, b in zip(pts, in_current, strict=True)
    )
    budget = fluid.drag_budget(1.0)
    return TowResult(pts, budget.cd, CD_TARGET_RANGE, budget, same)


# --------------------------------------------------------------------------------------------
# 4. speed table and cruise


@dataclass(frozen=True)
class CruiseResult:
    """Self-propelled straight swim (check 4)."""

    table: list[manoeuvres.StraightSwimResult]
    cruise_frequency_hz: float
    cruise: manoeuvres.StraightSwimResult
    trim_fin_rad: float


def check_speed_table(settle_s: float = 30.0, measure_s: float = 20.0) -> CruiseResult:
    """Speed vs frequency (:func:`bauv_sim.design.speed_table.measure_speed_table`, depth held by
    the fins), the frequency that gives 1.0 m/s (rounded to 0.01 Hz) and a separate run at that
    frequency."""
    table = speed_table.measure_speed_table(settle_s, measure_s)
    f = np.array([r.frequency_hz for r in table])
    u = np.array([r.speed_through_water_m_s for r in table])
    f_cruise = round(float(np.interp(CRUISE_SPEED_M_S, u, f)), 2)
    cruise = manoeuvres.straight_swim(_scene(speed_m_s=CRUISE_SPEED_M_S), f_cruise, 40.0, 30.0)
    return CruiseResult(table, f_cruise, cruise, cruise.mean_fin_rad)


def write_trim_keyframe(result: CruiseResult, path: Path = VEHICLE_XML) -> None:
    """Rewrite the ``trim`` keyframe: cruise speed, cruise frequency and the trim fin angle."""
    text = path.read_text()
    w = 2.0 * math.pi * result.cruise_frequency_hz
    a = result.trim_fin_rad
    u = result.cruise.speed_through_water_m_s
    new = (
        f'<key name="trim" qpos="0 0 -3 1 0 0 0  0 0 0 0 0 0 0 0"\n'
        f'         qvel="{u:.4f} 0 0 0 0 0  0 0 0 0 0 0 0 0"\n'
        f'         act="0 0 {a:.4f} {a:.4f} 0" ctrl="{w:.4f} 0 {a:.4f} {a:.4f} 0"/>'
    )
    text, n = re.subn(r'<key name="trim"[^>]*/>', new, text, flags=re.S)
    if n != 1:
        raise RuntimeError(f"{path}: no unique trim keyframe to rewrite")
    path.write_text(text)


# --------------------------------------------------------------------------------------------
# 5. current


@dataclass(frozen=True)
class CurrentResult:
    """Current checks (check 5)."""

    drift: manoeuvres.DriftResult
    drift_expected_error: float
    time_to_3pct_s: float
    swim_uniform: manoeuvres.CurrentSwimResult
    swim_gyre_east: manoeuvres.CurrentSwimResult
    swim_gyre_west: manoeuvres.CurrentSwimResult
    gyre_current_east: np.ndarray
    gyre_current_west: np.ndarray


def cruise_frequency_hz() -> float:
    """The tail-beat frequency for 1.0 m/s from ``models/bauv/speed_table.csv`` (1.2 Hz if there is
    no table yet), Hz, rounded to 0.01 Hz."""
    try:
        return round(float(speed_table.load_speed_table().frequency_for(CRUISE_SPEED_M_S)), 2)
    except ConfigError:
        return 1.2


def check_current(frequency_hz: float | None = None, long_s: float = 1500.0) -> CurrentResult:
    """Idle drift in 0.5 m/s (seed 001's direction 20 deg) from rest: error after 120 s, the
    error predicted by quadratic drag with the tow-test drag, and the time until 3 %; a swim in the
    uniform current; swims in a tidal gyre at two points 600 m apart."""
    frequency_hz = frequency_hz or cruise_frequency_hz()
    field = currents.UniformCurrent(0.5, math.radians(20.0))
    drift = manoeuvres.idle_drift(_scene(), field, 120.0)
    # relative speed decays as dv/dt = -k dv^2 with k = D(1 m/s) / m (quadratic drag, no added
    # mass in MuJoCo): dv(t) = dv0 / (1 + k dv0 t)
    phys = _scene()
    mass = phys.mass_kg()
    k = manoeuvres.tow_test(_scene(), [1.0], 1.0)[0].drag_n / mass
    expected = 1.0 / (1.0 + k * 0.5 * 120.0)
    # time until the drift is within 3 %
    phys = _scene()
    phys.set_tail_beat_frequency_hz(0.0)
    manoeuvres.release_in_current(phys, field)
    tick = phys.control_tick_s
    t3 = math.inf
    prev = phys.position_world()
    for _ in range(round(long_s / tick)):
        phys.advance(tick)
        p = phys.position_world()
        v = (p - prev) / tick
        prev = p
        if np.linalg.norm(v - phys.current_at_vehicle_world()) <= 0.03 * 0.5 and phys.time_s() > 1:
            t3 = phys.time_s()
            break
    swim = manoeuvres.swim_in_current(lambda: _scene(heading_deg=90.0), field, frequency_hz)
    gyre = currents.GyreCurrent((0.0, 0.0), 200.0, 0.3, clockwise=True)
    east = manoeuvres.swim_in_current(lambda: _offset_scene(300.0, 0.0), gyre, frequency_hz)
    west = manoeuvres.swim_in_current(lambda: _offset_scene(-300.0, 0.0), gyre, frequency_hz)
    return CurrentResult(
        drift,
        expected,
        t3,
        swim,
        east,
        west,
        gyre.velocity_world(0.0, np.array([300.0, 0.0, -20.0])),
        gyre.velocity_world(0.0, np.array([-300.0, 0.0, -20.0])),
    )


def _offset_scene(east_m: float, north_m: float) -> BauvPhysics:
    phys = _scene()
    phys.set_pose([east_m, north_m, -20.0], [0.0, 0.0, 0.0])
    return phys


# --------------------------------------------------------------------------------------------
# 6. manoeuvres


@dataclass(frozen=True)
class ManoeuvreResult:
    """Open-loop heading and depth changes (check 6)."""

    turns: list[manoeuvres.TurnResult]
    depth_changes: list[manoeuvres.DepthChangeResult]


def check_manoeuvres(frequency_hz: float | None = None) -> ManoeuvreResult:
    """Turns with tail bias +-10 and +-20 deg (depth held), depth changes with fins +-0.2 rad, at
    the cruise frequency."""
    frequency_hz = frequency_hz or cruise_frequency_hz()
    turns = [
        manoeuvres.heading_change(_scene(), frequency_hz, math.radians(b))
        for b in (10.0, -10.0, 20.0, -20.0)
    ]
    depth = [manoeuvres.depth_change(_scene(), frequency_hz, a) for a in (0.2, -0.2)]
    return ManoeuvreResult(turns, depth)


# --------------------------------------------------------------------------------------------
# 7. determinism


@dataclass(frozen=True)
class DeterminismResult:
    """Same commands and seed, two runs (check 7)."""

    duration_s: float
    ticks: int
    bit_identical: bool
    max_abs_difference: float


def check_determinism(seed: int = 11, duration_s: float = 60.0) -> DeterminismResult:
    """Two runs of the same seeded command sequence in a seed-001 randomised current."""
    runs = []
    for _ in range(2):
        phys = _scene(depth_m=40.0)
        cfg = currents.RandomisedCurrentConfig(speed_m_s=0.3, hold_step_s=0.1)
        sea.Sea(currents.make_current(cfg, rng.generator(seed, 0, "current"))).immerse(phys)
        runs.append(run_commands(phys, varied_commands(seed, duration_s, 10.0), 10.0, record=True))
    a, b = runs
    return DeterminismResult(
        duration_s, a.shape[0], bool(np.array_equal(a, b)), float(np.max(np.abs(a - b)))
    )


# --------------------------------------------------------------------------------------------
# reporting


def _table(header: list[str], rows: list[list[str]]) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def render(name: str, res: object) -> str:
    """Markdown for one check's README section."""
    if name == "swim":
        r: LongSwimResult = res  # type: ignore[assignment]
        return _table(
            ["quantity", "value"],
            [
                [
                    "simulated time",
                    f"{r.duration_s:.0f} s ({r.command_changes} command sets of 20 s)",
                ],
                ["MuJoCo warnings / divergences", f"{r.mujoco_warnings}"],
                ["distance swum", f"{r.distance_m:.0f} m"],
                ["depth range", f"{r.min_depth_m:.1f}-{r.max_depth_m:.1f} m"],
                ["largest speed through water", f"{r.max_speed_m_s:.2f} m/s"],
                ["largest roll", f"{r.max_abs_roll_deg:.1f} deg"],
                [
                    "largest pitch: in the start from rest / after 15 s",
                    f"{r.max_abs_pitch_deg:.1f} deg / {r.max_abs_pitch_after_start_deg:.1f} deg",
                ],
                ["wall time", f"{r.wall_s:.1f} s"],
            ],
        )
    if name == "buoyancy":
        r: BuoyancyResult = res  # type: ignore[no-redef]
        return _table(
            ["quantity", "value"],
            [
                [
                    "displaced volume, hull + dorsal fin (trimesh)",
                    f"{r.displaced_volume_mesh_m3:.6f} m^3",
                ],
                ["Archimedes rho g V, all parts (meshes)", f"{r.archimedes_n:.3f} N"],
                ["buoyancy in the model (gravcomp)", f"{r.buoyancy_model_n:.3f} N"],
                ["weight", f"{r.weight_n:.3f} N"],
                ["net upward force", f"{r.net_up_n:.2e} N"],
                ["BG (CB above CG)", f"{1000 * r.bg_m:.1f} mm"],
                [
                    f"idle depth change ({r.idle_duration_s:.0f} s, still water)",
                    f"{r.idle_depth_change_m_per_min:+.2e} m/min (target < 0.1)",
                ],
                [
                    "roll 20 deg -> below 2 deg",
                    f"{r.roll_settle_s:.2f} s (target <= 15: the roll added inertia about doubles "
                    "the rigid one; 3.7 s without it)",
                ],
                [
                    "roll period, first overshoot",
                    f"{r.roll_period_s:.2f} s, {r.roll_overshoot_deg:.1f} deg",
                ],
            ],
        )
    if name == "tow":
        r: TowResult = res  # type: ignore[no-redef]
        rows = [[f"{p.speed_m_s:.2f}", f"{p.drag_n:.3f}", f"{p.cd:.4f}"] for p in r.points]
        return (
            _table(["speed m/s", "drag N", "Cd (frontal 0.0587 m^2)"], rows)
            + "\n\n"
            + f"Target (first principles, `design.fluid.drag_budget`): Cd = {r.target_cd:.4f} "
            f"(body {r.budget.body_n:.2f} N + fins {r.budget.fins_n:.2f} N at 1 m/s); "
            f"accepted range {r.target_range[0]}-{r.target_range[1]}. "
            "Same drag with the water moving at 0.5 m/s: "
            f"{'yes' if r.same_in_current else 'NO'}."
        )
    if name == "cruise":
        r: CruiseResult = res  # type: ignore[no-redef]
        rows = [
            [
                f"{x.frequency_hz:.2f}",
                f"{x.speed_through_water_m_s:.3f}",
                f"{x.mean_motor_power_w:.1f}",
                f"{x.peak_motor_torque_nm:.1f}",
                f"{x.tail_tip_amplitude_m:.3f}",
                f"{x.strouhal:.3f}",
                f"{math.degrees(x.yaw_amplitude_rad):.1f}",
                f"{math.degrees(x.mean_fin_rad):+.1f}",
            ]
            for x in r.table
        ]
        c = r.cruise
        return (
            _table(
                [
                    "f Hz",
                    "U m/s",
                    "P W",
                    "peak torque N m",
                    "A m",
                    "St",
                    "yaw p-p deg",
                    "trim fin deg",
                ],
                rows,
            )
            + "\n\n"
            + f"**Cruise**: {c.speed_through_water_m_s:.3f} m/s at "
            f"{r.cruise_frequency_hz:.2f} Hz "
            f"(target 1.0 +- 10 %), mean motor power {c.mean_motor_power_w:.1f} W (<= 250 W), "
            f"peak torque {c.peak_motor_torque_nm:.1f} N m, tail-tip amplitude "
            f"{c.tail_tip_amplitude_m:.3f} m p-p, Strouhal {c.strouhal:.3f} (0.2-0.5), "
            f"trim fin angle {math.degrees(r.trim_fin_rad):+.2f} deg."
        )
    if name == "current":
        r: CurrentResult = res  # type: ignore[no-redef]
        d = r.drift

        def v(a: np.ndarray) -> str:
            return "(" + ", ".join(f"{x:+.3f}" for x in a[:2]) + ")"

        return _table(
            ["check", "measured", "target"],
            [
                [
                    "idle drift from rest, 0.5 m/s at 20 deg, after 120 s",
                    f"velocity {v(d.velocity_world_m_s)} vs current {v(d.current_world_m_s)} m/s: "
                    f"error {100 * d.relative_error:.1f} % (quadratic-drag law with the tow drag: "
                    f"{100 * r.drift_expected_error:.1f} %)",
                    "3 %",
                ],
                ["idle drift: time until within 3 %", f"{r.time_to_3pct_s:.0f} s", "-"],
                [
                    "swim east at cruise frequency in the uniform current",
                    f"ground {v(r.swim_uniform.ground_velocity_m_s)} = still-water "
                    f"{v(r.swim_uniform.still_velocity_m_s)} + current "
                    f"{v(r.swim_uniform.mean_current_m_s)}: error "
                    f"{100 * r.swim_uniform.relative_error:.2f} %",
                    "3 %",
                ],
                [
                    "gyre (0.3 m/s, core 200 m), swim north from (+300, 0)",
                    f"current there {v(r.gyre_current_east)}; mean on the path "
                    f"{v(r.swim_gyre_east.mean_current_m_s)}; error "
                    f"{100 * r.swim_gyre_east.relative_error:.2f} %",
                    "3 %",
                ],
                [
                    "gyre, swim north from (-300, 0)",
                    f"current there {v(r.gyre_current_west)}; mean on the path "
                    f"{v(r.swim_gyre_west.mean_current_m_s)}; error "
                    f"{100 * r.swim_gyre_west.relative_error:.2f} %",
                    "3 %",
                ],
            ],
        )
    if name == "manoeuvres":
        r: ManoeuvreResult = res  # type: ignore[no-redef]
        t = _table(
            [
                "tail bias deg",
                "turn rate deg/s",
                "radius m",
                "speed m/s",
                "90 deg after s",
                "roll deg",
            ],
            [
                [
                    f"{math.degrees(x.bias_rad):+.0f}",
                    f"{math.degrees(x.turn_rate_rad_s):+.2f}",
                    f"{x.turning_radius_m:.2f}",
                    f"{x.speed_through_water_m_s:.3f}",
                    f"{x.time_to_90deg_s:.1f}",
                    f"{math.degrees(x.mean_roll_rad):+.1f}",
                ]
                for x in r.turns
            ],
        )
        dd = _table(
            [
                "fin deg",
                "peak pitch rate deg/s",
                "pitch change deg",
                "depth rate m/s",
                "depth change m (20 s)",
            ],
            [
                [
                    f"{math.degrees(x.fin_rad):+.1f}",
                    f"{math.degrees(x.peak_pitch_rate_rad_s):.2f}",
                    f"{math.degrees(x.pitch_change_rad):+.2f}",
                    f"{x.depth_rate_m_s:+.3f}",
                    f"{x.depth_change_m:+.2f}",
                ]
                for x in r.depth_changes
            ],
        )
        return t + "\n\n" + dd
    if name == "determinism":
        r: DeterminismResult = res  # type: ignore[no-redef]
        return (
            f"Two runs of {r.duration_s:.0f} s ({r.ticks} control ticks) with the same seeded "
            f"commands and randomised current: bit-identical = **{r.bit_identical}** "
            f"(largest difference {r.max_abs_difference:g})."
        )
    raise KeyError(name)


def rewrite_readme(sections: dict[str, str], path: Path = README) -> None:
    """Replace the text between ``<!-- BEGIN results:NAME -->`` and its ``END`` marker."""
    text = path.read_text()
    for name, body in sections.items():
        pat = re.compile(rf"(<!-- BEGIN results:{name} -->).*?(<!-- END results:{name} -->)", re.S)
        text, n = pat.subn(lambda m, b=body: m.group(1) + "\n" + b + "\n" + m.group(2), text)
        if n != 1:
            raise RuntimeError(f"{path}: no unique results block {name!r}")
    path.write_text(text)


CHECKS: dict[str, Callable[[], object]] = {
    "swim": check_ten_minute_swim,
    "buoyancy": check_buoyancy,
    "tow": check_tow,
    "cruise": check_speed_table,
    "current": check_current,
    "manoeuvres": check_manoeuvres,
    "determinism": check_determinism,
}
"""The checks by name, in the order :func:`main` runs them."""


def main(argv: list[str] | None = None) -> dict[str, object]:
    """Run the checks, print them, write the calibration files and the README tables.

    Args:
        argv: names of checks to run (all by default); ``--no-write`` only prints.

    Returns:
        The results by check name.
    """
    parser = argparse.ArgumentParser(description="BAUV model acceptance checks (issue 3)")
    parser.add_argument("checks", nargs="*", choices=[*CHECKS, "render", []], default=[])
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    names = args.checks or list(CHECKS)
    results: dict[str, object] = {}
    sections: dict[str, str] = {}
    if "render" in names:
        print(f"wrote {render_png()}")
        names = [n for n in names if n != "render"]
        if not names:
            return results
    for name in names:
        t0 = time.perf_counter()
        res = CHECKS[name]()
        results[name] = res
        sections[name] = render(name, res)
        print(f"## {name} ({time.perf_counter() - t0:.1f} s wall)\n{sections[name]}\n", flush=True)
        if name == "cruise" and not args.no_write:
            speed_table.write_speed_table(res.table)  # type: ignore[attr-defined]
            write_trim_keyframe(res)  # type: ignore[arg-type]
    if not args.no_write:
        rewrite_readme(sections)
    return results


def render_png(
    path: Path = MODEL_DIR / "bauv.png", width: int = 1280, height: int = 720, seconds: float = 2.3
) -> Path:
    """Render the default scene offscreen (``MUJOCO_GL=egl`` or ``osmesa``) with the vehicle
    swimming from the ``trim`` keyframe, seen from port, ahead and above.

    Args:
        path: PNG file to write.
        width: image width, px.
        height: image height, px.
        seconds: simulated time before the picture (the tail mid-stroke), s.

    Returns:
        The path written.
    """
    import mujoco
    from PIL import Image

    from bauv_sim.physics import BauvPhysics

    phys = BauvPhysics.from_scene_xml()
    phys.reset_to_keyframe("trim")
    phys.set_tail_bias_rad(0.0)
    phys.advance(round(seconds / phys.control_tick_s) * phys.control_tick_s)
    m, d = phys.model.ptr, phys.data.ptr
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = phys.position_world() + np.array([-0.15, 0.0, -0.05])
    cam.distance, cam.azimuth, cam.elevation = 2.4, 125.0, -20.0
    opt = mujoco.MjvOption()
    with mujoco.Renderer(m, height, width) as r:
        r.update_scene(d, camera=cam, scene_option=opt)
        r.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = True
        r.scene.flags[mujoco.mjtRndFlag.mjRND_HAZE] = True
        img = r.render()
    Image.fromarray(img).save(path)
    return path


def as_dict(result: object) -> dict:
    """A check's result as plain nested data (for JSON)."""
    return asdict(result)  # type: ignore[call-overload]


if __name__ == "__main__":
    main()
