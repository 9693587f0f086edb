"""The report of ``fleet/survey``: per-run outcomes over the batch (mean, Monte Carlo standard
error, range), the way-point table's aggregates, ``metrics.json``, and the run data as Parquet:
``data/runs/runs.parquet`` (one row per run: :data:`tasks.fleet.run.OUTCOMES`),
``data/waypoints/waypoints.parquet`` (one row per run and way-point) and, per block,
``data/tracks/block-NNNNNN.parquet`` (the decimated tracks, one row per run and record time,
angles in degrees as all run data),
written as the blocks are read so that the report holds one block's tracks at a time.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from tasks.core import export
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report import Table, write_metrics, write_tables
from tasks.fleet.run import OUTCOMES, TRACK_COLUMNS, FleetBlock
from tasks.fleet.scenario import FleetScenario

Array = NDArray[np.float64]


class Aggregate(BaseModel):
    """One per-run outcome over the batch."""

    mean: float = Field(description="mean over the runs")
    standard_error: float = Field(description="Monte Carlo standard error of the mean")
    min: float = Field(description="smallest")
    max: float = Field(description="largest")


class WaypointAggregate(BaseModel):
    """One way-point over the batch."""

    east_m: float
    north_m: float
    reached_by_estimate: float = Field(description="fraction of runs whose leg ended reached")
    reached_by_truth: float = Field(description="fraction of runs whose truth entered the circle")
    closest_mean_m: float = Field(description="closest true approach, mean over the runs, m")
    closest_max_m: float = Field(description="closest true approach, largest, m")


class FleetMetrics(BaseModel):
    """``metrics.json`` of ``fleet/survey``."""

    runs: int
    failed: int = Field(description="runs that failed")
    plan_length_m: float = Field(description="planned track from the start, m")
    vehicle_hours: float = Field(description="simulated mission time over all runs, h")
    aggregate: dict[str, Aggregate] = Field(description="per-run outcomes over the batch")
    waypoints: list[WaypointAggregate]


def _agg(v: Array) -> Aggregate:
    v = np.asarray(v, dtype=float)
    se = float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else 0.0
    return Aggregate(
        mean=float(v.mean()), standard_error=se, min=float(v.min()), max=float(v.max())
    )


def _track_columns(b: FleetBlock) -> dict[str, export.Column]:
    T, nb = b.t_s.size, b.runs.size
    run = np.repeat(b.runs.astype(np.int32), T)
    cols = {
        "run": export.Column(run, "index", "run index"),
        "t": export.Column(np.tile(b.t_s, nb), "s", "time"),
    }
    for name, (unit, desc, comps) in TRACK_COLUMNS.items():
        v = np.swapaxes(b.tracks[name], 0, 1)  # (b, T, ...)
        v = v.reshape(nb * T, *v.shape[2:])
        cols[name] = export.Column(np.ascontiguousarray(v), unit, desc, comps)
    return cols


def report_fleet(name: str, summary: str, ctx: ReportContext) -> ReportSummary:
    """Write the outputs of a finished batch (module docstring)."""
    scn: FleetScenario = ctx.scenario  # type: ignore[assignment]
    meta = {"experiment": name, "seed": str(ctx.seed), "runs": str(ctx.n_runs)}
    outcomes: dict[str, list[Array]] = {k: [] for k in OUTCOMES}
    runs, reached, closest, leg_end, failed = [], [], [], [], []
    files: list[str] = []
    for i, b in enumerate(ctx.blocks):
        runs.append(b.runs)
        for k in OUTCOMES:
            outcomes[k].append(np.asarray(b.outcomes[k]))
        reached.append(b.reached)
        closest.append(b.closest_m)
        leg_end.append(b.leg_end_s)
        failed += list(b.failed)
        if b.tracks:
            rel = f"data/tracks/block-{i:06d}.parquet"
            cols = export.data_columns(_track_columns(b))  # angles in degrees (heading_deg)
            export.write_parquet(ctx.out_dir / rel, cols, {**meta, "block": str(i)})
            files.append(rel)
    run = np.concatenate(runs)
    out = {k: np.concatenate(v) for k, v in outcomes.items()}
    R, C, L = np.concatenate(reached), np.concatenate(closest), np.concatenate(leg_end)
    cols = {"run": export.Column(run.astype(np.int32), "index", "run index")}
    for k, (unit, desc) in OUTCOMES.items():
        v = out[k]
        cols[k] = export.Column(v.astype(bool) if unit == "bool" else v.astype(float), unit, desc)
    export.write_parquet(ctx.out_dir / "data" / "runs" / "runs.parquet", cols, meta)
    files.insert(0, "data/runs/runs.parquet")
    pts = scn.waypoints()
    n_wp = len(pts)
    wp_index = np.tile(np.arange(n_wp, dtype=np.int32), run.size)
    wcols = {
        "run": export.Column(np.repeat(run.astype(np.int32), n_wp), "index", "run index"),
        "waypoint": export.Column(wp_index, "index", "way-point index"),
        "reached_by_estimate": export.Column(R.ravel(), "bool", "leg ended reached (estimate)"),
        "closest_true_distance": export.Column(C.ravel(), "m", "closest true horizontal approach"),
        "leg_end": export.Column(L.ravel(), "s", "when the leg ended (null: never)", nullable=True),
    }
    export.write_parquet(ctx.out_dir / "data" / "waypoints" / "waypoints.parquet", wcols, meta)
    files.insert(1, "data/waypoints/waypoints.parquet")
    radius = scn.plan.acceptance_radius_m
    wp_aggs = [
        WaypointAggregate(
            east_m=e,
            north_m=nn,
            reached_by_estimate=float(R[:, i].mean()),
            reached_by_truth=float((C[:, i] <= radius).mean()),
            closest_mean_m=float(C[:, i].mean()),
            closest_max_m=float(C[:, i].max()),
        )
        for i, (e, nn) in enumerate(pts)
    ]
    aggs = {k2: _agg(v) for k2, v in out.items()}
    metrics = FleetMetrics(
        runs=int(run.size),
        failed=len(failed),
        plan_length_m=scn.plan_length_m(),
        vehicle_hours=float(out["duration_s"].sum() / 3600.0),
        aggregate=aggs,
        waypoints=wp_aggs,
    )
    files.insert(0, write_metrics(ctx.out_dir, metrics))
    t1 = Table(
        f"Per-run outcomes over {run.size} runs",
        ["outcome", "unit", "mean", "standard error", "min", "max"],
        [[k2, OUTCOMES[k2][0], a.mean, a.standard_error, a.min, a.max] for k2, a in aggs.items()],
        digits=3,
        slug="outcomes",
    )
    t2 = Table(
        "Way-points",
        ["way-point", "east (m)", "north (m)", "reached (estimate)", "reached (truth)",
         "closest mean (m)", "closest max (m)"],
        [[i, w.east_m, w.north_m, w.reached_by_estimate, w.reached_by_truth, w.closest_mean_m,
          w.closest_max_m] for i, w in enumerate(wp_aggs)],
        digits=2,
        slug="waypoints",
    )  # fmt: skip
    files += write_tables(ctx.out_dir, [t1, t2], heading=f"{name}: {summary}")
    text = "".join(t.to_text() for t in (t1, t2)) + (
        f"{name}: {run.size} runs, {metrics.vehicle_hours:.1f} vehicle-hours, "
        f"{aggs['completed'].mean:.3f} completed; EKF mean error "
        f"{aggs['ekf_mean_error_m'].mean:.2f} m, DR final {aggs['dr_final_error_m'].mean:.1f} m, "
        f"NEES mean {aggs['nees_mean'].mean:.2f}\n"
    )
    return ReportSummary(text, tuple(files), tuple(failed))
