"""Report of a mission batch: ``metrics.json``, tables, figures, the recording of one run and
the run data of every run as Parquet (``data/``, schema in ``docs/run-data.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.frames import velocity_from_course_speed
from nav.metrics import chi2_ppf
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.scenario import MissionScenario
from tasks.core.registry import Experiment, ReportContext, ReportSummary


class WaypointResult(BaseModel):
    """One way-point of one run."""

    index: int
    east_m: float
    north_m: float
    acceptance_radius_m: float
    closest_true_distance_m: float = Field(description="closest true horizontal approach, m")
    closest_at_s: float
    reached_by_truth: bool = Field(description="the true track entered the acceptance circle")
    reached_by_estimate: bool = Field(description="guidance saw the estimate inside it")
    leg_end_s: float | None


class RunResult(BaseModel):
    """One run of a mission batch."""

    run: int
    failed: str | None
    summary: dict[str, float]
    waypoints: list[WaypointResult]


class Aggregate(BaseModel):
    """A summary value over the successful runs."""

    mean: float
    min: float
    max: float


class MissionMetrics(BaseModel):
    """``metrics.json`` of a ``mission/*`` batch (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    failures: list[str]
    steer_on: str
    all_waypoints_reached_by_truth: bool = Field(
        description="every way-point of every successful run reached, judged by truth"
    )
    aggregate: dict[str, Aggregate]
    runs: list[RunResult]


def report_mission(exp: Experiment, ctx: ReportContext) -> ReportSummary:
    """Tables, metrics, figures and the recording of a mission batch."""
    from tasks.core.report import Table, write_metrics, write_tables

    scn: MissionScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[MissionRun] = [r for block in ctx.blocks for r in block]
    ok = [r for r in runs if r.failed is None]
    failures = [r.failed for r in runs if r.failed is not None]
    keys = list(ok[0].summary) if ok else []
    agg = {
        k: Aggregate(
            mean=float(np.mean([r.summary[k] for r in ok])),
            min=float(np.min([r.summary[k] for r in ok])),
            max=float(np.max([r.summary[k] for r in ok])),
        )
        for k in keys
    }
    metrics = MissionMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=len(failures),
        failures=failures,
        steer_on=scn.navigation.steer_on,
        all_waypoints_reached_by_truth=bool(ok)
        and all(w["reached_by_truth"] for r in ok for w in r.waypoints),
        aggregate=agg,
        runs=[
            RunResult(
                run=r.run,
                failed=r.failed,
                summary=r.summary,
                waypoints=[WaypointResult(**w) for w in r.waypoints],
            )
            for r in runs
        ],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    files += export_runs(ctx.out_dir, exp.name, runs)
    rec_run = next((r for r in runs if r.run == scn.report.record_run), None)
    tables = []
    if rec_run is not None and rec_run.failed is None:
        tables.append(
            Table(
                f"Way-points of run {rec_run.run} (steering on {scn.navigation.steer_on.upper()}), "
                "judged by truth",
                [
                    "Way-point",
                    "East (m)",
                    "North (m)",
                    "Radius (m)",
                    "Closest true distance (m)",
                    "Reached (truth)",
                    "Reached (estimate)",
                ],
                [
                    [
                        w["index"],
                        w["east_m"],
                        w["north_m"],
                        w["acceptance_radius_m"],
                        w["closest_true_distance_m"],
                        "yes" if w["reached_by_truth"] else "NO",
                        "yes" if w["reached_by_estimate"] else "no",
                    ]
                    for w in rec_run.waypoints
                ],
                slug="waypoints",
            )
        )
    rows = []
    for name, key in [("EKF", "ekf"), ("DR", "dr")]:
        rows.append(
            [name]
            + [agg[f"{key}_{s}_error_m"].mean if agg else None for s in ("mean", "max", "final")]
        )
    tables.append(
        Table(
            f"Horizontal navigation error over {len(ok)} successful run(s) (mean over runs)",
            ["Method", "Mean error (m)", "Max error (m)", "Final error (m)"],
            rows,
            slug="errors",
            note=(
                f"Guidance steered on {scn.navigation.steer_on.upper()}. USBL fixes per run: "
                f"{agg['usbl_fixes'].mean:.0f} ({agg['usbl_rejected'].mean:.1f} rejected by the "
                f"gate); GPS fixes: {agg['gps_fixes'].mean:.0f}; mission time "
                f"{agg['duration_s'].mean:.0f} s; motor energy {agg['energy_j'].mean / 1e3:.1f} kJ."
                if agg
                else "No successful run."
            ),
        )
    )
    tables.append(
        Table(
            "Runs",
            [
                "Run",
                "Status",
                "Way-points reached (truth)",
                "Worst closest approach (m)",
                "EKF mean error (m)",
                "DR mean error (m)",
                "Duration (s)",
            ],
            [
                [
                    r.run,
                    "ok" if r.failed is None else "FAILED",
                    f"{int(r.summary['waypoints_reached_by_truth'])}/{len(r.waypoints)}"
                    if r.summary
                    else "-",
                    r.summary.get("max_closest_distance_m"),
                    r.summary.get("ekf_mean_error_m"),
                    r.summary.get("dr_mean_error_m"),
                    r.summary.get("duration_s"),
                ]
                for r in runs
            ],
            slug="runs",
            note="\n".join(failures),
        )
    )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if rec_run is not None and rec_run.failed is None and rec_run.vehicles:
        if scn.report.figures:
            files += mission_figures(exp.name, scn, rec_run, runs, ctx.out_dir)
        if scn.report.recording:
            files.append(record_mission(exp.name, scn, rec_run, ctx.out_dir))
    text = "".join(t.to_text() + "\n" for t in tables)
    if failures:
        rest = (
            "none completed"
            if not ok
            else f"the other {len(ok)} completed"
            if len(ok) > 1
            else "the other one completed"
        )
        text += (
            f"{len(failures)} of {len(runs)} run(s) failed ({rest}):\n  "
            + "\n  ".join(failures)
            + "\n"
        )
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files), tuple(failures))


def circle(cx: float, cy: float, r: float, z: float = 0.0, n: int = 48) -> NDArray[np.float64]:
    """A horizontal circle as a closed polyline, shape (n + 1, 3), m, world."""
    ring = (cx, cy) + velocity_from_course_speed(np.linspace(0, 2 * np.pi, n + 1), r)
    return np.column_stack([ring, np.full(n + 1, z)])


def _title_words(name: str) -> str:
    """A mission's registry name in words: ``"mission/survey"`` -> ``"Survey mission"``."""
    return f"{name.split('/')[-1].replace('_', ' ').replace('-', ' ').capitalize()} mission"


def unwrapped_heading_deg(
    heading_rad: NDArray[np.float64], command_rad: NDArray[np.float64] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Heading without the 0/360 jump, and a command drawn beside it.

    Args:
        heading_rad: headings, shape (T,), rad clockwise from north (any wrap).
        command_rad: commanded course, shape (T,), rad, or ``None``.

    Returns:
        ``(heading_deg (T,), command_deg (T,) or None)``: the heading unwrapped (continuous); the
        command placed within 180 deg of it (its wrapped difference added), so both cross north
        without a vertical line.
    """
    h = np.unwrap(np.asarray(heading_rad, dtype=float))
    if command_rad is None:
        return np.degrees(h), None
    d = np.angle(np.exp(1j * (np.asarray(command_rad, dtype=float) - h)))
    return np.degrees(h), np.degrees(h + d)


def moving_mean(values: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Centred moving mean over ``n`` samples (shorter at the ends), shape as ``values``."""
    v = np.asarray(values, dtype=float)
    n = max(1, min(int(n), len(v)))
    c = np.concatenate([[0.0], np.cumsum(v)])
    lo = np.clip(np.arange(len(v)) - n // 2, 0, len(v))
    hi = np.clip(lo + n, 0, len(v))
    return (c[hi] - c[lo]) / np.maximum(hi - lo, 1)


def waypoint_marks(ax, waypoints, z_color: str | None = None) -> None:
    """Draw way-points as acceptance circles labelled with their index (as in the tables)."""
    from tasks.core import style

    col = z_color or style.color("waypoint")
    for i, w in enumerate(waypoints):
        c = circle(w.east_m, w.north_m, w.acceptance_radius_m)
        ax.plot(c[:, 0], c[:, 1], color=col, lw=0.8, zorder=2)
        ax.annotate(
            f"WP{i}",
            (w.east_m + w.acceptance_radius_m * 0.7, w.north_m + w.acceptance_radius_m * 0.7),
            textcoords="offset points",
            xytext=(1, 1),
            ha="left",
            va="bottom",
            color=col,
            fontsize=6.5,
            fontweight="bold",
            zorder=6,
        )
    if len(waypoints):
        ax.plot([], [], color=col, lw=0.8, label="way-point (acceptance circle)")


def current_arrow(
    ax, current_en: NDArray[np.float64], label: str, color: str, ls="-", slot: int = 0
) -> None:
    """An arrow of the mean current in the top left corner of the axes (its length in the
    legend's words: the speed, m/s); drawn in axes coordinates so it never covers the route."""
    speed = float(np.hypot(*current_en[:2]))
    if speed <= 0:
        return
    u = np.asarray(current_en[:2]) / speed
    x0, y0 = 0.09 + 0.17 * slot, 0.9
    ax.annotate(
        "",
        xy=(x0 + 0.07 * u[0], y0 + 0.07 * u[1]),
        xytext=(x0 - 0.07 * u[0], y0 - 0.07 * u[1]),
        xycoords="axes fraction",
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.4, "ls": ls},
        zorder=7,
    )
    ax.plot([], [], color=color, lw=1.4, ls=ls, label=f"{label} {speed:.2f} m/s (arrow: direction)")


def mission_figures(
    name: str, scn: MissionScenario, run: MissionRun, runs: list[MissionRun], out
) -> list[str]:
    """Route, errors and vehicle state of the recorded run (PNG and PDF, project style)."""
    from tasks.core import style  # matplotlib only when figures are drawn

    with style.context():
        return _draw_mission(name, scn, run, runs, out, style)


def _draw_mission(name, scn, run, runs, out, style) -> list[str]:
    a = run.lead
    t = a["t"]
    words = f"{_title_words(name)}, run {run.run}"
    files: list[str] = []
    # the figure as tall as the route (equal scales), the legend below it
    xy = np.concatenate(
        [a["truth_pos"][:, :2], a["ekf_pos"][:, :2], a["dr_pos"][:, :2]]
        + [np.array([[w.east_m, w.north_m]]) for w in scn.guidance.waypoints]
    )
    span = np.ptp(xy, axis=0) + 2.0 * max(
        [w.acceptance_radius_m for w in scn.guidance.waypoints] + [10.0]
    )
    ratio = float(span[1] / span[0])
    axes_h = min(6.5, 0.9 * style.PAGE_IN * ratio)
    width = float(np.clip(axes_h / ratio / 0.85, 5.0, style.PAGE_IN))
    fig, ax = style.subplots(width, axes_h + 1.5)
    others = [o for o in runs if o is not run and o.vehicles]
    for i, other in enumerate(others):
        p = other.lead["truth_pos"]
        ax.plot(
            p[:, 0], p[:, 1], color="0.75", lw=0.5, label="other runs (truth)" if i == 0 else "_"
        )
    fx = a.fixes.get("usbl")
    if fx:
        pos, ok = fx["position"].values, fx["accepted"].values.astype(bool)
        ax.plot(
            pos[ok, 0],
            pos[ok, 1],
            **style.line("USBL", label="USBL fixes (accepted)", ms=2, alpha=0.6, zorder=1),
        )
        if (~ok).any():
            ax.plot(
                pos[~ok, 0],
                pos[~ok, 1],
                "x",
                color=style.color("USBL"),
                ms=4,
                mew=0.8,
                label="USBL fixes (rejected by the gate)",
                zorder=1,
            )
    gp = _fix_positions(a, "gps")
    if len(gp):
        ax.plot(gp[:, 0], gp[:, 1], **style.line("GPS", label="GPS fixes", ms=4, zorder=5))
    ax.plot(a["dr_pos"][:, 0], a["dr_pos"][:, 1], **style.line("DR", zorder=3))
    ax.plot(a["ekf_pos"][:, 0], a["ekf_pos"][:, 1], **style.line("EKF", zorder=4))
    ax.plot(a["truth_pos"][:, 0], a["truth_pos"][:, 1], **style.line("truth", lw=1.2, zorder=3))
    ax.plot(*a["truth_pos"][0, :2], "o", color="k", ms=4, mfc="white", zorder=6, label="start")
    waypoint_marks(ax, scn.guidance.waypoints)
    if scn.sensors.use_usbl:
        ax.plot(scn.transceiver_east_m, scn.transceiver_north_m, "k^", ms=6, label="transceiver")
    current_arrow(ax, a["truth_current"].mean(axis=0), "mean current", style.color("current"))
    if "ekf_current" in a.ticks:
        est = a["ekf_current"]
        current_arrow(ax, est[-1], "EKF current at the end", style.color("EKF"), "--", 1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"{words}: route, steering on the {scn.navigation.steer_on.upper()} estimate")
    style.figure_legend(fig, (ax,), ncol=3 if width > 6.0 else 2)
    files += style.save(fig, out / "route.png")

    # errors: horizontal distance on a log axis, then the EKF's east and north errors with its
    # own +-2 sigma
    k = 2.0
    e_ekf = a["ekf_pos"] - a["truth_pos"]
    e_dr = a["dr_pos"] - a["truth_pos"]
    P = a["ekf_P"]
    sd = np.sqrt(np.maximum(np.stack([P[:, 0, 0], P[:, 1, 1]], axis=1), 0.0))
    fig, axs = style.subplots("page", 5.2, 3, 1, sharex=True)
    for key, e in (("DR", e_dr), ("EKF", e_ekf)):
        d = np.hypot(e[:, 0], e[:, 1])
        keep = d > 0
        axs[0].plot(t[keep], d[keep], **style.line(key))
    radius = k * np.hypot(sd[:, 0], sd[:, 1])
    axs[0].plot(t, radius, **style.line("EKF", label=f"EKF {k:g}$\\sigma$ radius", ls=":"))
    axs[0].set_yscale("log")
    style.log_ticks(axs[0])
    axs[0].set_ylabel(style.label("horizontal error", "m"))
    axs[0].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    for j, (ax, comp) in enumerate(zip(axs[1:], ("east", "north"), strict=True)):
        ax.fill_between(
            t,
            -k * sd[:, j],
            k * sd[:, j],
            color=style.color("EKF"),
            alpha=0.18,
            lw=0,
            label=f"EKF $\\pm${k:g}$\\sigma$",
        )
        ax.plot(t, e_ekf[:, j], **style.line("EKF", label=f"EKF {comp} error"))
        ax.set_ylabel(style.label(f"{comp} error", "m"))
        # the scale of the error and of most of the bound (a bound that is large only before
        # the first fix is drawn past the axis, not squashing the rest)
        lim = 1.25 * max(float(np.max(np.abs(e_ekf[:, j]))), float(np.percentile(k * sd[:, j], 90)))
        ax.set_ylim(-lim, lim)
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    axs[-1].set_xlabel(style.label("time", "s"))
    inside = np.mean(np.all(np.abs(e_ekf[:, :2]) <= k * sd, axis=1))
    fig.suptitle(
        f"{words}: navigation error (EKF inside {k:g}$\\sigma$ on both axes "
        f"{100 * inside:.0f} % of the time)",
    )
    style.panel_letters(axs)
    files += style.save(fig, out / "errors.png")

    # vehicle state
    fig, axs = style.subplots("page", 6.4, 4, 1, sharex=True)
    axs[0].plot(t, -a["truth_pos"][:, 2], **style.line("truth", label="true depth"))
    axs[0].plot(t, a["guidance_depth"], **style.line("command"))
    axs[0].invert_yaxis()
    axs[0].set_ylabel(style.label("depth", "m"))
    h, c = unwrapped_heading_deg(a["truth_rph"][:, 2], a["guidance_course"])
    axs[1].plot(t, h, **style.line("truth", label="true heading (unwrapped)"))
    axs[1].plot(t, c, **style.line("command", label="commanded course"))
    axs[1].set_ylabel(style.label("heading", "deg"))
    axs[2].plot(
        t, np.hypot(*a["truth_vel_water"][:, :2].T), **style.line("EKF", label="through water")
    )
    axs[2].plot(
        t, np.hypot(*a["truth_vel"][:, :2].T), **style.line("DR", label="over ground", ls="-")
    )
    axs[2].plot(t, a["guidance_speed"], **style.line("command"))
    axs[2].set_ylabel(style.label("speed", "m/s"))
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    n5 = max(1, round(5.0 / dt))
    axs[3].plot(t, a["motor_power"], color="0.75", lw=0.4, label="per tick")
    axs[3].plot(
        t,
        moving_mean(a["motor_power"], n5),
        color=style.PALETTE["orange"],
        lw=1.0,
        label="mean over 5 s",
    )
    axs[3].set_ylabel(style.label("motor power", "W"))
    axs[3].set_xlabel(style.label("time", "s"))
    for x in axs:
        if x.get_legend_handles_labels()[0]:
            x.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    fig.suptitle(f"{words}: vehicle state")
    style.panel_letters(axs)
    files += style.save(fig, out / "state.png")
    return files


def record_mission(name: str, scn: MissionScenario, run: MissionRun, out) -> str:
    """Write ``recording.rrd`` of a mission run (see the module docstring of
    :mod:`tasks.core.recording`)."""
    import rerun as rr
    import rerun.blueprint as rrb

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from bauv_sim.seabed import generate
    from tasks.core.recording import COLORS, Recording

    a = run.lead
    t = a["t"]
    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}")
    r = rec.rec
    # seabed mesh around the mission area
    bed = generate(scn.seabed)
    c = bed.config
    pts = np.array(
        [[w.east_m, w.north_m] for w in scn.guidance.waypoints]
        + [[scn.transceiver_east_m, scn.transceiver_north_m]]
    )
    lo = np.minimum(a["truth_pos"][:, :2].min(axis=0), pts.min(axis=0)) - 60.0
    hi = np.maximum(a["truth_pos"][:, :2].max(axis=0), pts.max(axis=0)) + 60.0
    grid = np.arange(c.n) * c.cell_m - c.half_extent_m
    ix = np.flatnonzero((grid >= lo[0]) & (grid <= hi[0]))
    iy = np.flatnonzero((grid >= lo[1]) & (grid <= hi[1]))
    if len(ix) >= 2 and len(iy) >= 2:
        X, Y = np.meshgrid(grid[ix], grid[iy])
        Z = -bed.depth_m[np.ix_(iy, ix)]
        verts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
        nx = len(ix)
        cells = [
            (i * nx + j, i * nx + j + 1, (i + 1) * nx + j + 1, (i + 1) * nx + j)
            for i in range(len(iy) - 1)
            for j in range(nx - 1)
        ]
        tris = np.array([(q[0], q[1], q[2]) for q in cells] + [(q[0], q[2], q[3]) for q in cells])
        r.log(
            "world/seabed",
            rr.Mesh3D(
                vertex_positions=verts, triangle_indices=tris, albedo_factor=[0.76, 0.70, 0.50, 1.0]
            ),
            static=True,
        )
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, 0.0])
    tx[2] = float(bed.height_world(tx[0], tx[1]))
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    wp = scn.guidance.waypoints
    r.log(
        "world/waypoints",
        rr.Points3D(
            [[w.east_m, w.north_m, -w.depth_m] for w in wp],
            radii=-8.0,
            colors=(148, 0, 211),
            labels=[f"WP{i}" for i in range(len(wp))],
        ),
        static=True,
    )
    r.log(
        "world/waypoints/acceptance",
        rr.LineStrips3D(
            [circle(w.east_m, w.north_m, w.acceptance_radius_m, -w.depth_m) for w in wp],
            colors=(148, 0, 211),
            radii=-1.5,
        ),
        static=True,
    )
    # the moving hull
    r.send_columns(
        "world/vehicle",
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Transform3D.columns(
            translation=a["truth_pos"], quaternion=quat_wxyz_to_xyzw(a["truth_quat_wxyz"])
        ),
    )
    r.log("world/vehicle/hull", rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"), static=True)
    record_moving_parts(r, a, t)
    rec.track("truth", t, a["truth_pos"], COLORS["truth"])
    rec.track("ekf", t, a["ekf_pos"], COLORS["ekf"])
    rec.track("dr", t, a["dr_pos"], COLORS["dr"])
    every = max(1, round(1.0 / max(float(t[1] - t[0]), 1e-9))) if len(t) > 1 else 1
    rec.ellipsoids("ekf", t[::every], a["ekf_pos"][::every], a["ekf_P"][::every], COLORS["ekf"])
    record_fixes(rec, a)
    record_current(rec, a, every)
    record_consistency(rec, a)
    record_guidance(rec, a)
    record_events(rec, a)
    err = lambda k: np.hypot(*(a[k] - a["truth_pos"])[:, :2].T)  # noqa: E731
    rec.scalars("errors/ekf", t, err("ekf_pos"), COLORS["ekf"], "EKF horizontal error (m)")
    rec.scalars("errors/dr", t, err("dr_pos"), COLORS["dr"], "DR horizontal error (m)")
    rec.scalars("depth/true", t, -a["truth_pos"][:, 2], (0, 0, 0), "true depth (m)")
    rec.scalars("depth/commanded", t, a["guidance_depth"], (148, 0, 211), "commanded depth (m)")
    h, c = unwrapped_heading_deg(a["truth_rph"][:, 2], a["guidance_course"])
    rec.scalars("heading/true", t, h, (0, 0, 0), "true heading, unwrapped (deg)")
    rec.scalars("heading/commanded", t, c, (148, 0, 211), "commanded course (deg)")
    rec.scalars(
        "speed/through_water",
        t,
        np.hypot(*a["truth_vel_water"][:, :2].T),
        (31, 119, 180),
        "speed through water (m/s)",
    )
    rec.scalars(
        "speed/over_ground",
        t,
        np.hypot(*a["truth_vel"][:, :2].T),
        (214, 39, 40),
        "speed over ground (m/s)",
    )
    rec.scalars("power/motor", t, a["motor_power"], (255, 127, 14), "motor power (W)")
    rec.scalars(
        "actuators/fin_port", t, np.degrees(a["cmd_fin_port"]), (44, 160, 44), "port fin (deg)"
    )
    rec.scalars(
        "actuators/fin_starboard",
        t,
        np.degrees(a["cmd_fin_starboard"]),
        (23, 190, 207),
        "starboard fin (deg)",
    )
    rec.scalars(
        "actuators/tail_bias", t, np.degrees(a["cmd_tail_bias"]), (188, 189, 34), "tail bias (deg)"
    )
    rec.blueprint(
        "errors",
        "consistency",
        "innovation",
        "current",
        "guidance",
        "heading",
        "depth",
        follow="/world/vehicle",
        eye_controls=rrb.EyeControls3D(
            position=[-7.0, 3.5, 3.0], look_target=[0.0, 0.0, 0.0], eye_up=[0.0, 0.0, 1.0]
        ),
        log="events",
        world_name="world (camera follows the vehicle)",
    )
    rec.close()
    return "recording.rrd"


VEHICLE_PARTS: tuple[tuple[str, str, str, tuple[float, float, float], tuple[float, ...]], ...] = (
    # entity under world/vehicle, mesh, (column, component), joint axis (body), pose in parent
    (
        "fin_port",
        "lateral_fin_port.obj",
        "truth_fin_angles:0",
        (0.0, -1.0, 0.0),
        (0.2, 0.105, -0.04),
    ),
    (
        "fin_starboard",
        "lateral_fin_starboard.obj",
        "truth_fin_angles:1",
        (0.0, -1.0, 0.0),
        (0.2, -0.105, -0.04),
    ),
    ("peduncle", "peduncle.obj", "truth_tail_angles:0", (0.0, 0.0, 1.0), (-0.35, 0.0, 0.0)),
    (
        "peduncle/caudal_fin",
        "caudal_fin.obj",
        "truth_tail_angles:1",
        (0.0, 0.0, 1.0),
        (-0.45, 0.0, 0.0),
    ),
)
"""The moving bodies of ``models/bauv/bauv.xml`` (body positions in their parent body, m; hinge
axes, body frame), each drawn with its visual mesh at its true joint angle of every tick."""


def record_moving_parts(r, v: VehicleRun, t: NDArray[np.float64]) -> None:
    """Fins and tail at their true joint angles (``truth_fin_angles``, ``truth_tail_angles``),
    as child transforms of ``world/vehicle``; the dorsal fin, fixed to the hull, once."""
    import rerun as rr

    from bauv_sim.hull import MODEL_DIR

    assets = MODEL_DIR / "assets"
    r.log(
        "world/vehicle/dorsal_fin",
        rr.Transform3D(translation=[0.05, 0.0, 0.15]),
        rr.Asset3D(path=assets / "dorsal_fin.obj"),
        static=True,
    )
    for entity, mesh, source, axis, pos in VEHICLE_PARTS:
        col, comp = source.split(":")
        if col not in v.ticks:
            continue  # run data written before the joint angles were recorded
        angle = v[col][:, int(comp)]
        half = 0.5 * angle
        ax = np.asarray(axis, dtype=float)
        quat_xyzw = np.column_stack([np.sin(half)[:, None] * ax, np.cos(half)])
        r.send_columns(
            f"world/vehicle/{entity}",
            indexes=[rr.TimeColumn("sim_time", duration=t)],
            columns=rr.Transform3D.columns(
                translation=np.tile(pos, (len(t), 1)), quaternion=quat_xyzw
            ),
        )
        r.log(f"world/vehicle/{entity}/mesh", rr.Asset3D(path=assets / mesh), static=True)


GUIDANCE_MODES = ("transit", "ascend", "surface", "dive", "done")
"""Names of the ``guidance_mode`` values (:data:`tasks.closed_loop.result.TICK_COLUMNS`)."""


def position_nees(v: VehicleRun) -> NDArray[np.float64]:
    """The EKF's position NEES at each tick, ``e^T P^-1 e`` with ``e`` the 3-D error, shape (T,)."""
    e = v["ekf_pos"] - v["truth_pos"]
    return np.einsum("ti,ti->t", e, np.linalg.solve(v["ekf_P"], e[..., None])[..., 0])


def record_fixes(rec, v: VehicleRun) -> None:
    """Fixes split into accepted and rejected (gate) entities, their flag as a series, and each
    fix's position innovation: the fix minus the EKF's estimate at its time of validity."""
    from tasks.core.recording import COLORS

    for kind in ("usbl", "gps"):
        fx = v.fixes.get(kind)
        if not fx:
            continue
        ta = fx["t_arrival"].values
        tv = fx["t_valid"].values
        pos = fx["position"].values
        ok = fx["accepted"].values.astype(bool)
        for flag, name, color in ((ok, "accepted", COLORS[kind]), (~ok, "rejected", (230, 0, 0))):
            if flag.any():
                rec.fixes(f"{kind}/{name}", ta[flag], pos[flag], color)
        rec.scalars(
            f"fixes/{kind}_accepted",
            ta,
            ok.astype(float),
            COLORS[kind],
            f"{kind.upper()} fix accepted (1) or rejected by the gate (0)",
        )
        t = v["t"]
        est = np.column_stack([np.interp(tv, t, v["ekf_pos"][:, j]) for j in range(2)])
        innov = pos[:, :2] - est
        for j, axis in enumerate(("east", "north")):
            rec.scalars(
                f"innovation/{kind}_{axis}",
                ta,
                innov[:, j],
                COLORS[kind] if j == 0 else (0, 114, 178),
                f"{kind.upper()} fix - EKF, {axis} (m)",
            )
        if "nis" in fx:
            dof = 3 if kind == "usbl" else 2
            rec.scalars(
                f"consistency/nis_{kind}",
                ta,
                fx["nis"].values,
                COLORS[kind],
                f"{kind.upper()} NIS (dof {dof})",
            )


def record_current(rec, v: VehicleRun, every: int) -> None:
    """The true current at the vehicle and the EKF's estimate beside it: arrows (x20) above the
    vehicle and east/north series."""
    t = v["t"][::every]
    origins = v["truth_pos"][::every] + [0.0, 0.0, 2.0]
    true = v["truth_current"][::every]
    rec.arrows("current/true", t, origins, 20.0 * true, (0, 190, 220))
    rec.scalars("current/true_east", t, true[:, 0], (0, 190, 220), "true current east (m/s)")
    rec.scalars("current/true_north", t, true[:, 1], (0, 120, 140), "true current north (m/s)")
    if "ekf_current" in v.ticks:
        est = v["ekf_current"][::every]
        rec.arrows("current/estimated", t, origins + [0.0, 0.0, 1.0], 20.0 * est, (31, 119, 180))
        rec.scalars("current/ekf_east", t, est[:, 0], (31, 119, 180), "EKF current east (m/s)")
        rec.scalars("current/ekf_north", t, est[:, 1], (20, 60, 140), "EKF current north (m/s)")


def record_consistency(rec, v: VehicleRun, probability: float = 0.95) -> None:
    """The EKF's position NEES at each tick against the chi-square band of one run (dof 3)."""
    t = v["t"]
    rec.scalars(
        "consistency/nees", t, position_nees(v), (31, 119, 180), "EKF position NEES (dof 3)"
    )
    lo, hi = chi2_ppf(np.array([(1 - probability) / 2, (1 + probability) / 2]), 3)
    for name, val in (("band_low", lo), ("band_high", hi)):
        rec.scalars(
            f"consistency/nees_{name}",
            t[[0, -1]],
            np.full(2, val),
            (0, 158, 115),
            f"{100 * probability:g} % chi-square band, one run ({val:.2f})",
        )


def record_guidance(rec, v: VehicleRun) -> None:
    """Guidance mode (0 transit, 1 ascend, 2 surface, 3 dive, 4 done) and way-point index."""
    t = v["t"]
    rec.scalars(
        "guidance/mode",
        t,
        v["guidance_mode"].astype(float),
        (148, 0, 211),
        "mode: " + ", ".join(f"{i} {m}" for i, m in enumerate(GUIDANCE_MODES)),
    )
    rec.scalars(
        "guidance/waypoint", t, v["guidance_waypoint"].astype(float), (0, 0, 0), "way-point index"
    )


def mission_events(v: VehicleRun) -> tuple[list[float], list[str], list[str]]:
    """Events of a run in words: way-points reached (the guidance moves to the next), mode
    changes (surfacing, diving), fixes rejected by the gate.

    Returns:
        ``(t_s, texts, levels)``: k times (s), k strings, k rerun levels.
    """
    t = v["t"]
    ts: list[float] = []
    texts: list[str] = []
    levels: list[str] = []
    wp = np.asarray(v["guidance_waypoint"]).astype(int)
    mode = np.asarray(v["guidance_mode"]).astype(int)
    ts.append(float(t[0]))
    texts.append(f"start: heading for WP{wp[0]}, mode {_mode(mode[0])}")
    levels.append("INFO")
    n_wp = len(v.waypoints)
    for k in np.flatnonzero(np.diff(wp) != 0) + 1:
        ts.append(float(t[k]))
        nxt = f"heading for WP{wp[k]}" if wp[k] < n_wp or not n_wp else "the last way-point"
        texts.append(f"WP{wp[k - 1]} reached (by the estimate); {nxt}")
        levels.append("INFO")
    for k in np.flatnonzero(np.diff(mode) != 0) + 1:
        ts.append(float(t[k]))
        texts.append(f"guidance mode {_mode(mode[k - 1])} -> {_mode(mode[k])}")
        levels.append("INFO")
    for kind in ("usbl", "gps"):
        fx = v.fixes.get(kind)
        if not fx:
            continue
        ok = fx["accepted"].values.astype(bool)
        nis = fx["nis"].values if "nis" in fx else np.full(len(ok), np.nan)
        for k in np.flatnonzero(~ok):
            n = "" if not np.isfinite(nis[k]) else f" (NIS {nis[k]:.1f})"
            ts.append(float(fx["t_arrival"].values[k]))
            texts.append(f"{kind.upper()} fix valid at {fx['t_valid'].values[k]:.1f} s rejected{n}")
            levels.append("WARN")
    for w in v.waypoints:
        if not w["reached_by_truth"]:
            ts.append(float(w["closest_at_s"]))
            texts.append(
                f"WP{w['index']} missed by truth: closest {w['closest_true_distance_m']:.1f} m "
                f"> {w['acceptance_radius_m']:g} m"
            )
            levels.append("WARN")
    ts.append(float(t[-1]))
    texts.append(f"end at {t[-1]:.1f} s")
    levels.append("INFO")
    return ts, texts, levels


def _mode(m: int) -> str:
    return GUIDANCE_MODES[m] if 0 <= m < len(GUIDANCE_MODES) else str(m)


def record_events(rec, v: VehicleRun) -> None:
    """The run's events (:func:`mission_events`) as the text log ``events``."""
    rec.events("events", *mission_events(v))


def _fix_positions(v: VehicleRun, device: str) -> NDArray[np.float64]:
    """The fix positions of a device, shape (k, 3), m, world (k = 0 when there are none)."""
    fx = v.fixes.get(device)
    return fx["position"].values if fx else np.zeros((0, 3))


def export_runs(out_dir: Path, name: str, runs: list[MissionRun], suffix: str = "") -> list[str]:
    """Write every run's data as Parquet: ``data/run-NNNNNN<suffix>/<vehicle>.ticks.parquet``
    (the per-tick columns) and ``<vehicle>.<device>.parquet`` (the fixes of each device).

    Returns:
        The files written, relative to ``out_dir``.
    """
    from tasks.core.export import write_parquet

    files = []
    for r in runs:
        for v in r.vehicles.values():
            meta = {
                "experiment": name,
                "seed": str(r.seed),
                "run": str(r.run),
                "vehicle": v.name,
                "failed": r.failed or "",
            }
            folder = Path("data") / f"run-{r.run:06d}{suffix}"
            rel = folder / f"{v.name}.ticks.parquet"
            write_parquet(out_dir / rel, v.ticks, {**meta, "table": "ticks"})
            files.append(str(rel))
            for device, cols in v.fixes.items():
                rel = folder / f"{v.name}.{device}.parquet"
                write_parquet(out_dir / rel, cols, {**meta, "table": device})
                files.append(str(rel))
    return files
