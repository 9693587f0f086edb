"""Report of a mission batch: ``metrics.json``, tables, figures, the recording of one run and
the run data of every run as Parquet (``data/``, schema in ``docs/run-data.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.frames import velocity_from_course_speed
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


def mission_figures(
    name: str, scn: MissionScenario, run: MissionRun, runs: list[MissionRun], out
) -> list[str]:
    """Route, errors and vehicle state of the recorded run (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a = run.lead
    t = a["t"]
    files = []
    fig, ax = plt.subplots(figsize=(8, 7))
    for other in runs:
        if other is not run and other.vehicles:
            ax.plot(
                other.lead["truth_pos"][:, 0], other.lead["truth_pos"][:, 1], color="0.7", lw=0.6
            )
    ax.plot(a["truth_pos"][:, 0], a["truth_pos"][:, 1], "k-", lw=1.4, label="truth")
    ax.plot(a["ekf_pos"][:, 0], a["ekf_pos"][:, 1], color="tab:blue", lw=1, label="EKF")
    ax.plot(a["dr_pos"][:, 0], a["dr_pos"][:, 1], color="tab:red", lw=1, label="DR")
    us = _fix_positions(a, "usbl")
    if len(us):
        ax.plot(us[:, 0], us[:, 1], ".", color="tab:green", ms=3, alpha=0.6, label="USBL fixes")
    gp = _fix_positions(a, "gps")
    if len(gp):
        ax.plot(gp[:, 0], gp[:, 1], "x", color="tab:orange", ms=6, label="GPS fixes")
    for w in scn.guidance.waypoints:
        c = circle(w.east_m, w.north_m, w.acceptance_radius_m)
        ax.plot(c[:, 0], c[:, 1], color="tab:purple", lw=1)
        ax.plot(w.east_m, w.north_m, "+", color="tab:purple")
    ax.plot(scn.transceiver_east_m, scn.transceiver_north_m, "k^", ms=8, label="transceiver")
    cur = a["truth_current"].mean(axis=0)
    span = max(np.ptp(a["truth_pos"][:, 0]), np.ptp(a["truth_pos"][:, 1]), 1.0)
    x0, y0 = a["truth_pos"][:, 0].min(), a["truth_pos"][:, 1].max()
    ax.annotate(
        "",
        xy=(x0 + 0.3 * span * cur[0], y0 + 0.3 * span * cur[1]),
        xytext=(x0, y0),
        arrowprops={"arrowstyle": "->", "color": "tab:cyan", "lw": 2},
    )
    ax.text(x0, y0, f" mean current {np.hypot(*cur[:2]):.2f} m/s", color="tab:cyan", va="bottom")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{name} run {run.run}: steering on {scn.navigation.steer_on.upper()}")
    fig.tight_layout()
    fig.savefig(out / "route.png", dpi=110)
    plt.close(fig)
    files.append("route.png")

    fig, ax = plt.subplots(figsize=(9, 3.8))
    for key, label, color in [("ekf_pos", "EKF", "tab:blue"), ("dr_pos", "DR", "tab:red")]:
        ax.plot(t, np.hypot(*(a[key] - a["truth_pos"])[:, :2].T), color=color, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(f"{name} run {run.run}: distance of the estimates to the truth")
    fig.tight_layout()
    fig.savefig(out / "errors.png", dpi=110)
    plt.close(fig)
    files.append("errors.png")

    fig, axs = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    axs[0].plot(t, -a["truth_pos"][:, 2], "k", label="true depth")
    axs[0].plot(t, a["guidance_depth"], "--", color="tab:purple", label="commanded")
    axs[0].invert_yaxis()
    axs[0].set_ylabel("depth (m)")
    axs[1].plot(t, np.degrees(a["truth_rph"][:, 2]), "k", label="true heading")
    axs[1].plot(t, np.degrees(a["guidance_course"]), "--", color="tab:purple", label="commanded")
    axs[1].set_ylabel("heading (deg)")
    axs[2].plot(t, np.hypot(*a["truth_vel_water"][:, :2].T), label="through water")
    axs[2].plot(t, np.hypot(*a["truth_vel"][:, :2].T), label="over ground")
    axs[2].set_ylabel("speed (m/s)")
    axs[3].plot(t, a["motor_power"], color="tab:orange", lw=0.5)
    axs[3].set_ylabel("motor power (W)")
    axs[3].set_xlabel("time (s)")
    for x in axs:
        x.grid(alpha=0.3)
        x.legend(fontsize=8, loc="upper right") if x.get_legend_handles_labels()[0] else None
    fig.tight_layout()
    fig.savefig(out / "state.png", dpi=110)
    plt.close(fig)
    files.append("state.png")
    return files


def record_mission(name: str, scn: MissionScenario, run: MissionRun, out) -> str:
    """Write ``recording.rrd`` of a mission run (see the module docstring of
    :mod:`tasks.core.recording`)."""
    import rerun as rr

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
            radii=1.0,
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
            radii=0.15,
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
    rec.track("truth", t, a["truth_pos"], COLORS["truth"])
    rec.track("ekf", t, a["ekf_pos"], COLORS["ekf"])
    rec.track("dr", t, a["dr_pos"], COLORS["dr"])
    every = max(1, round(1.0 / max(float(t[1] - t[0]), 1e-9)))
    rec.ellipsoids("ekf", t[::every], a["ekf_pos"][::every], a["ekf_P"][::every], COLORS["ekf"])
    for kind, color in [("usbl", COLORS["usbl"]), ("gps", COLORS["gps"])]:
        fx = a.fixes.get(kind)
        if fx:
            rec.fixes(kind, fx["t_arrival"].values, fx["position"].values, color)
    # current at the vehicle as arrows (scaled x20 to be visible)
    rec.arrows(
        "current",
        t[::every],
        a["truth_pos"][::every] + [0, 0, 2.0],
        20.0 * a["truth_current"][::every],
        (0, 190, 220),
    )
    err = lambda k: np.hypot(*(a[k] - a["truth_pos"])[:, :2].T)  # noqa: E731
    rec.scalars("errors/ekf", t, err("ekf_pos"), COLORS["ekf"], "EKF horizontal error (m)")
    rec.scalars("errors/dr", t, err("dr_pos"), COLORS["dr"], "DR horizontal error (m)")
    rec.scalars("depth/true", t, -a["truth_pos"][:, 2], (0, 0, 0), "true depth (m)")
    rec.scalars("depth/commanded", t, a["guidance_depth"], (148, 0, 211), "commanded depth (m)")
    rec.scalars(
        "heading/true", t, np.degrees(a["truth_rph"][:, 2]), (0, 0, 0), "true heading (deg)"
    )
    rec.scalars(
        "heading/commanded",
        t,
        np.degrees(a["guidance_course"]),
        (148, 0, 211),
        "commanded course (deg)",
    )
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
    rec.blueprint("errors", "depth", "heading", "speed", "power", "actuators")
    rec.close()
    return "recording.rrd"


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
