"""The report of ``mission/swarm``: the tables, the warnings, the figure and the recording of one
run (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import itertools
import math
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.currents import UniformCurrentConfig
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.result import MissionRun
from tasks.core.registry import ReportContext, ReportSummary
from tasks.missions.swarm.run import SwarmRunResult, leader_course_true
from tasks.missions.swarm.scenario import FOLLOWERS, LEADER, SwarmScenario, station_offsets

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# Report


class FollowerRow(BaseModel):
    """One follower with one method, means over the successful runs."""

    method: str
    follower: str
    relative_bearing_deg: float
    distance_m: float
    values: dict[str, float]


class SwarmMetrics(BaseModel):
    """``metrics.json`` of ``mission/swarm``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    failures: list[str]
    n_diverged: int = Field(description="aided estimates that diverged (navigation.divergence_m)")
    divergences: list[str]
    methods: list[str]
    current: str
    followers: list[FollowerRow] = Field(description="per follower and method, means over runs")
    leader: dict[str, dict[str, float]] = Field(description="per method, the leader's means")
    warnings: list[str]
    runs: list[dict[str, Any]] = Field(description="per run: method -> vehicle -> metrics")


ROW_KEYS = (
    ("est_mean_error_m", "Estimate mean error (m)"),
    ("est_max_error_m", "Estimate max error (m)"),
    ("relative_mean_error_m", "Relative mean error (m)"),
    ("station_mean_error_m", "Station mean error (m)"),
    ("station_max_error_m", "Station max error (m)"),
    ("dr_mean_error_m", "Pure DR mean error (m)"),
    ("fixes_accepted", "Ranges accepted"),
    ("fixes_refused", "Ranges refused"),
    ("mean_fix_hdop", "Mean HDOP at fixes"),
    ("diverged_runs", "Diverged runs"),
)


COUNT_KEYS = frozenset({"fixes_accepted", "fixes_refused", "usbl_fixes", "diverged_runs"})
"""Row keys that count events: printed as whole numbers when the mean over runs is one."""


def _cell(key: str, value: float | None) -> float | int | None:
    """A table cell: a count that is a whole number as an ``int`` (119, not 119.00)."""
    if key in COUNT_KEYS and value is not None and float(value).is_integer():
        return int(value)
    return value


def report_swarm(exp: MissionExperiment, ctx: ReportContext) -> ReportSummary:
    """The table per follower and method, the leader's navigation, warnings, figures, the
    recording of one run and the run data."""
    from tasks.closed_loop.report import export_runs
    from tasks.core.report import Table, write_metrics, write_tables

    scn: SwarmScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[SwarmRunResult] = [r for b in ctx.blocks for r in b]
    ok = [r for r in runs if r.failed is None]
    methods = list(scn.methods())
    stations = station_offsets(scn)
    names = FOLLOWERS[: len(stations)]

    def mean(method: str, vehicle: str, key: str) -> float | None:
        if key == "diverged_runs":  # a count over the runs, not a mean
            if method == "dr":
                return None
            return float(sum("diverged_at_s" in r.metrics[method].get(vehicle, {}) for r in ok))
        vals = [r.metrics[method][vehicle][key] for r in ok if vehicle in r.metrics[method]]
        return float(np.mean(vals)) if vals else None

    rows = []
    for name, st in zip(names, stations, strict=True):
        for m in methods:
            vals = {k: mean(m, name, k) for k, _ in ROW_KEYS}
            rows.append(
                FollowerRow(
                    method=m,
                    follower=name,
                    relative_bearing_deg=st.relative_bearing_deg,
                    distance_m=st.distance_m,
                    values={k: v for k, v in vals.items() if v is not None},
                )
            )
    leader = {
        m: {
            k: v
            for k in ("ekf_mean_error_m", "ekf_max_error_m", "usbl_fixes")
            if (v := mean(m, LEADER, k)) is not None
        }
        for m in methods
    }
    diverged = [w for r in ok for w in r.diverged]
    warnings = diverged + [w for r in runs for w in r.warnings]
    failures = [r.failed for r in runs if r.failed]
    metrics = SwarmMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=len(failures),
        failures=failures,
        n_diverged=len(diverged),
        divergences=diverged,
        methods=methods,
        current=f"{scn.current.kind}",
        followers=rows,
        leader=leader,
        warnings=warnings,
        runs=[{"run": r.run, "failed": r.failed, "metrics": r.metrics} for r in runs],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    for m in methods:
        files += export_runs(ctx.out_dir, exp.name, [r.flights[m] for r in runs], f"-{m}")
    cur = scn.current
    cur_text = (
        f"{cur.speed_m_s:g} m/s towards {cur.direction_deg:g} deg"
        if isinstance(cur, UniformCurrentConfig)
        else cur.kind
    )
    t1 = Table(
        f"Followers: navigation and station keeping ({len(ok)} run(s), mean over runs; "
        f"current {cur_text})",
        ["Follower", "Station", "Method", *(label for _, label in ROW_KEYS)],
        [
            [
                row.follower,
                f"{row.relative_bearing_deg:g} deg / {row.distance_m:g} m",
                row.method.upper(),
                *(_cell(k, row.values.get(k)) for k, _ in ROW_KEYS),
            ]
            for row in rows
        ],
        digits=2,
        slug="followers",
        note=(
            "Estimate error: the follower's estimate against its true position (world). "
            "Relative error: the estimated offset from the leader (estimate minus the leader "
            "position it knows) against the true offset. Station error: the true distance to "
            "the true station point (the leader's true position and course). Pure DR: the "
            "compass + log track without any range."
        ),
    )
    t2 = Table(
        "Leader: its own navigation (the position it broadcasts)",
        ["Method flown by the followers", "EKF mean error (m)", "EKF max error (m)", "USBL fixes"],
        [
            [
                m.upper(),
                leader[m].get("ekf_mean_error_m"),
                leader[m].get("ekf_max_error_m"),
                _cell("usbl_fixes", leader[m].get("usbl_fixes")),
            ]
            for m in methods
        ],
        digits=2,
        slug="leader",
    )
    tables = [t1, t2]
    if warnings or failures:
        tables.append(Table("Warnings", ["Warning"], [[w] for w in warnings], slug="warnings"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in runs if r.run == scn.report.record_run), None)
    if rec is not None:
        flight = rec.flights[methods[0]]
        if flight.vehicles and len(flight.vehicles[LEADER]["t"]) > 1:
            if scn.report.figures:
                files += swarm_figure(exp.name, scn, rec, methods, ctx.out_dir)
            if scn.report.recording:
                files.append(record_swarm(exp.name, scn, flight, methods[0], ctx.out_dir))
    text = "".join(t.to_text() + "\n" for t in tables)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files), tuple(failures), tuple(diverged))


VEHICLE_COLORS = (
    "black",
    "blue",
    "vermillion",
    "bluish_green",
    "orange",
    "sky_blue",
    "reddish_purple",
    "olive",
    "wine",
    "grey",
)
"""The figure style's colours of the leader, f1, f2 ... (repeated beyond ten vehicles)."""
COLORS_V = [
    (0, 0, 0),
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (230, 159, 0),
    (86, 180, 233),
    (204, 121, 167),
    (153, 153, 51),
    (136, 34, 85),
    (127, 127, 127),
]
"""Recording colours of the leader, f1, f2 ... (:data:`VEHICLE_COLORS` as RGB)."""


def swarm_figure(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out) -> list[str]:
    """Tracks of the recorded run (every vehicle's truth and estimate, first method) and each
    follower's true distance to its station over time, per method (PNG and PDF, project
    style)."""
    from tasks.core import style

    with style.context():
        return _draw_swarm(name, scn, rec, methods, out, style)


def _draw_swarm(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out, style):
    pal = style.PALETTE
    vehicle_colors = itertools.cycle([pal[k] for k in VEHICLE_COLORS])
    method_names = {"ga1": "GA1", "ga2": "GA2", "ekf": "EKF", "dr": "DR"}
    fig, axs = style.subplots("page", 3.8, 1, 2)
    flight = rec.flights[methods[0]]
    ax = axs[0]
    for (vn, v), c in zip(flight.vehicles.items(), vehicle_colors, strict=False):
        ax.plot(v["truth_pos"][:, 0], v["truth_pos"][:, 1], "-", color=c, lw=1.0, label=vn)
        ax.plot(v["ekf_pos"][:, 0], v["ekf_pos"][:, 1], ":", color=c, lw=0.8, label="_")
    ax.plot([], [], "k:", lw=0.8, label="estimates")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"Truth and estimates ({method_names.get(methods[0], methods[0])})")
    ax.legend(loc="best")
    ax = axs[1]
    tick = scn.timing.control_tick_s
    dashes = ["-", "--", "-.", ":"]
    for m in methods:
        f = rec.flights[m]
        if LEADER not in f.vehicles:
            continue
        lead = f.vehicles[LEADER]
        course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
        for j, (vn, st) in enumerate(zip(FOLLOWERS, station_offsets(scn), strict=False)):
            if vn not in f.vehicles:
                continue
            v = f.vehicles[vn]
            n = min(len(v["t"]), len(lead["t"]))
            b = math.radians(st.relative_bearing_deg)
            sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
                [np.sin(course[:n] + b), np.cos(course[:n] + b)]
            )
            ax.plot(
                v["t"][:n],
                np.maximum(np.hypot(*(v["truth_pos"][:n, :2] - sp).T), 1e-2),
                dashes[j % 4],
                color=style.color(method_names.get(m, m)),
                lw=0.8,
                label=f"{vn} {method_names.get(m, m)}",
            )
    ax.set_yscale("log")
    style.log_ticks(ax)
    ax.set_xlabel(style.label("time", "s"))
    ax.set_ylabel(style.label("true distance to the station", "m"))
    style.title(ax, "Station-keeping error")
    ax.legend(ncol=2, loc="best")
    return style.save(fig, out / "swarm.png")


def record_swarm(name: str, scn: SwarmScenario, run: MissionRun, method: str, out) -> str:
    """``recording.rrd`` of a flight: every vehicle (hull, truth, estimate), each follower's
    range circle at each fix (the leader position it used, the horizontal range), its HDOP, its
    station and navigation errors."""
    import rerun as rr

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from tasks.closed_loop.report import circle
    from tasks.core.recording import TIMELINE, Recording

    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}/{method}")
    r = rec.rec
    tick = scn.timing.control_tick_s
    lead = run.vehicles[LEADER]
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, -20.0])
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    stations = dict(zip(FOLLOWERS, station_offsets(scn), strict=False))
    plots = []
    for (vn, v), color in zip(run.vehicles.items(), itertools.cycle(COLORS_V)):
        t = v["t"]
        r.send_columns(
            f"world/{vn}/vehicle",
            indexes=[rr.TimeColumn(TIMELINE, duration=t)],
            columns=rr.Transform3D.columns(
                translation=v["truth_pos"], quaternion=quat_wxyz_to_xyzw(v["truth_quat_wxyz"])
            ),
        )
        r.log(
            f"world/{vn}/vehicle/hull",
            rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"),
            static=True,
        )
        rec.track(f"{vn}/truth", t, v["truth_pos"], color)
        light = tuple(int(c + (255 - c) * 0.5) for c in color)
        rec.track(f"{vn}/estimate", t, v["ekf_pos"], light, radius_m=0.4)
        if vn == LEADER:
            continue
        fx = v.fixes.get("modem")
        if fx:
            z = -scn.station.depth_m
            for ta, rng_h, ce, cn, ok in zip(
                fx["t_arrival"].values,
                fx["horizontal_range"].values,
                fx["centre_east"].values,
                fx["centre_north"].values,
                fx["accepted"].values,
                strict=True,
            ):
                r.set_time(TIMELINE, duration=float(ta))
                if rng_h > 0:
                    r.log(
                        f"world/{vn}/range_circle",
                        rr.LineStrips3D(
                            [circle(float(ce), float(cn), float(rng_h), z)],
                            colors=color if ok else (150, 150, 150),
                            radii=0.08,
                        ),
                    )
            r.reset_time()
        rec.scalars(f"hdop/{vn}", t, v["hdop"], color, f"{vn} HDOP")
        st = stations[vn]
        n = min(len(t), len(lead["t"]))
        b = math.radians(st.relative_bearing_deg)
        sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
            [np.sin(course[:n] + b), np.cos(course[:n] + b)]
        )
        rec.track(
            f"{vn}/station",
            t[:n],
            np.column_stack([sp, np.full(n, -scn.station.depth_m)]),
            (255, 127, 14),
            radius_m=0.3,
            strip=False,
        )
        rec.scalars(
            f"station_error/{vn}",
            t[:n],
            np.hypot(*(v["truth_pos"][:n, :2] - sp).T),
            color,
            f"{vn} true distance to station (m)",
        )
        rec.scalars(
            f"errors/{vn}",
            t,
            np.hypot(*(v["ekf_pos"] - v["truth_pos"])[:, :2].T),
            color,
            f"{vn} {method.upper()} position error (m)",
        )
        plots = ["hdop", "station_error", "errors"]
    rec.blueprint(*plots)
    rec.close()
    return "recording.rrd"
