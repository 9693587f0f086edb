"""Report of a mission batch: ``metrics.json``, tables, the figures
(:mod:`tasks.closed_loop.figures`) and the recording (:mod:`tasks.closed_loop.recording`) of one
run, and the run data of every run as Parquet (``data/``, schema in ``docs/run-data.md``)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field

from bauv_sim.geo import LocalFrame
from tasks.closed_loop.figures import MISSION_FIGURES, circle, current_arrow, mission_figures
from tasks.closed_loop.recording import record_mission
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.scenario import MissionScenario
from tasks.core.registry import Experiment, ReportContext, ReportSummary, ReportWork
from tasks.core.report_pool import offload

__all__ = [
    "MissionMetrics",
    "circle",
    "current_arrow",
    "export_runs",
    "mission_figures",
    "record_mission",
    "report_mission",
]
"""The report's names, and the figures' and recording's that the missions read from here."""


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
    # each block's run data written as the next one arrives (on worker processes, while the
    # later blocks are computed); the last block's by a report process, if any
    blocks: list[list[MissionRun]] = []
    data_files: list[str] = []
    for block in ctx.blocks:
        if blocks:
            data_files += _export_block(scn, blocks, ctx.out_dir, exp.name, len(blocks) - 1)
        blocks.append(block)
    runs: list[MissionRun] = [r for block in blocks for r in block]
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
    rec_run = next((r for r in runs if r.run == scn.report.record_run), None)
    drawn = rec_run is not None and rec_run.failed is None and bool(rec_run.vehicles)
    # the figures and the recording in the report's processes, if any, while this one writes
    # the rest (their files listed in the same order as when drawn here)
    jobs = [
        offload(ctx.pool, _figures_and_recording, scn, blocks, ctx.out_dir, exp.name, job)
        for job in _report_jobs(scn)
        if drawn
    ]
    last = (
        [offload(ctx.pool, _export_block, scn, blocks, ctx.out_dir, exp.name, len(blocks) - 1)]
        if blocks
        else []
    )
    files = [write_metrics(ctx.out_dir, metrics), *data_files]
    files += [f for job in last for f in job.result()]
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
                note=_missed_note(rec_run.waypoints),
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
    done = [job.result() for job in jobs]
    # listed as drawn here: the figures in their order, then the recording
    by_figure = {fig: drawn for figures, _ in done for fig, drawn in figures.items()}
    files += [f for fig in MISSION_FIGURES for f in by_figure.get(fig, [])]
    files += [f for _, rec in done for f in rec]
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


def _report_jobs(scn: MissionScenario) -> list[tuple[tuple[str, ...], bool]]:
    """The figures and recording of a mission report as two jobs of about equal time, measured
    on ``mission/survey`` (CPU s, with their libraries imported: route 0.65, errors 1.0, state
    0.9, recording 0.1, the last block's run data 0.06, handed out after these): the route and
    state figures; the errors figure and the recording. ``(figures, recording?)`` each, the
    empty ones left out."""
    figures = MISSION_FIGURES if scn.report.figures else ()
    first = ("route", "state")
    jobs = [
        (tuple(f for f in figures if f in first), False),
        (tuple(f for f in figures if f not in first), scn.report.recording),
    ]
    return [(f, rec) for f, rec in jobs if f or rec]


def _export_block(
    scn: MissionScenario, blocks: list[list[MissionRun]], out_dir: Path, name: str, index: int
) -> list[str]:
    """The run data of block ``index`` as Parquet (:func:`export_runs`, with the scene's frame
    and the USBL transceiver); a job of the report for the last block
    (:func:`tasks.core.report_pool.offload`).

    Returns:
        The files written, relative to ``out_dir``.
    """
    tx = [("usbl transceiver", scn.transceiver_east_m, scn.transceiver_north_m)]
    points = tx if scn.sensors.use_usbl else ()
    return export_runs(out_dir, name, blocks[index], frame=scn.frame(), points=points)


def _figures_and_recording(
    scn: MissionScenario,
    blocks: list[list[MissionRun]],
    out_dir: Path,
    name: str,
    job: tuple[tuple[str, ...], bool],
) -> tuple[dict[str, list[str]], list[str]]:
    """A job of the report (:func:`tasks.core.report_pool.offload`): figures of the recorded run
    and, if asked, its recording.

    Returns:
        ``({figure: its files}, [recording file] or [])``, the files relative to ``out_dir``.
    """
    figures, recording = job
    runs = [r for block in blocks for r in block]
    run = next(r for r in runs if r.run == scn.report.record_run)
    drawn = {fig: mission_figures(name, scn, run, runs, out_dir, (fig,)) for fig in figures}
    return drawn, [record_mission(name, scn, run, out_dir)] if recording else []


def report_work(scn: MissionScenario) -> ReportWork | None:
    """The report's jobs that its processes may do (:meth:`Experiment.report_work`): the figures
    and recording (:func:`_report_jobs`) and the last block's run data, with the modules they
    need imported beforehand; ``None`` without figures and recording (the run data alone is
    written here)."""
    n = len(_report_jobs(scn))
    if n == 0:
        return None
    return ReportWork(
        n + 1,  # and the last block's run data
        (
            "pyarrow.parquet",
            # pyarrow imports pandas at its first conversion of an array
            "pandas",
            "tasks.closed_loop.report",
            "tasks.core.geojson",
            "matplotlib.pyplot",
            "matplotlib.backends.backend_agg",
            "matplotlib.backends.backend_pdf",
            "fontTools.subset",
            "rerun",
            # the recording's NEES band and covariance ellipsoids
            "scipy.stats",
            "scipy.spatial.transform",
        ),
    )


def export_runs(
    out_dir: Path,
    name: str,
    runs: list[MissionRun],
    variant: str | None = None,
    frame: LocalFrame | None = None,
    points: Sequence[tuple[str, float, float]] = (),
) -> list[str]:
    """Write every run's data as Parquet, one folder per table:
    ``data/ticks/run-NNNNNN[-<variant>]-<vehicle>.parquet`` (the per-tick columns) and
    ``data/<device>/run-...-<vehicle>.parquet`` (the fixes of each device: ``usbl``, ``gps``,
    ``modem``, ``network``), so that each folder reads as one dataset
    (:func:`tasks.core.export.open_dataset`, ``pyarrow.dataset.dataset``).

    Each table starts with the key columns ``run`` (int32), ``vehicle`` and, with a variant,
    ``variant`` (labelled) (:func:`tasks.core.export.key_columns`); angles are written in degrees
    with ``_deg`` in their names (:func:`tasks.core.export.data_columns`); enum columns as their
    labels.

    With the scene's geographic frame, every position column of those tables gets its WGS 84
    latitude/longitude companion (``<name>_geo_deg``; the GPS fixes ``latitude_deg``/
    ``longitude_deg``: :func:`tasks.core.geojson.with_geographic`), and each vehicle's tracks
    (the truth and every estimate), way-points and ``points`` are written as GeoJSON,
    ``data/tracks/run-NNNNNN[-<variant>]-<vehicle>.geojson``
    (:func:`tasks.core.geojson.write_tracks_geojson`). Without one there are no GeoJSON files.

    Args:
        out_dir: the report's folder.
        name: the experiment's name (in the files' metadata).
        runs: the runs.
        variant: the variant flown (a mission flying several per run: ``compensated``,
            ``ga1``, ...), in the files' names and the ``variant`` column; ``None`` for none.
        frame: the scene's frame on the Earth (``scenario.frame()``), or ``None``.
        points: named positions of the scene for the GeoJSON, ``(name, east m, north m)`` (the
            USBL transceiver).

    Returns:
        The files written, relative to ``out_dir``.
    """
    from tasks.core.export import data_columns, data_file, key_columns, write_parquet
    from tasks.core.geojson import with_geographic, write_tracks_geojson

    def table(cols: dict, run: int, vehicle: str) -> dict:
        n = len(next(iter(cols.values())).values) if cols else 0
        if frame is not None:
            cols = with_geographic(cols, frame)
        return {**key_columns(n, run, vehicle, variant), **data_columns(cols)}

    files = []
    for r in runs:
        for v in r.vehicles.values():
            meta = {
                "experiment": name,
                "seed": str(r.seed),
                "run": str(r.run),
                "variant": variant or "",
                "vehicle": v.name,
                "failed": r.failed or "",
            }
            for kind, cols in {"ticks": v.ticks, **v.fixes}.items():
                if not cols:
                    continue
                rel = data_file(kind, r.run, v.name, variant)
                write_parquet(out_dir / rel, table(cols, r.run, v.name), {**meta, "table": kind})
                files.append(rel.as_posix())
            if frame is not None and v.ticks:
                rel = data_file("tracks", r.run, v.name, variant)
                props = {
                    "experiment": name,
                    "seed": r.seed,
                    "run": r.run,
                    "variant": variant or "",
                    "vehicle": v.name,
                    "failed": r.failed or "",
                }
                wps = [(f"waypoint {w['index']}", w["east_m"], w["north_m"]) for w in v.waypoints]
                write_tracks_geojson(out_dir / rel, v.ticks, frame, props, [*wps, *points])
                files.append(rel.as_posix())
    return files


def _missed_note(waypoints: list[dict]) -> str:
    """Why a way-point reads NO by truth but yes by the estimate: the estimate came within the
    radius while the vehicle truly stayed at least its closest distance away, so the navigation
    error then was at least the difference (the guidance steers on the estimate)."""
    missed = [w for w in waypoints if w["reached_by_estimate"] and not w["reached_by_truth"]]
    return "; ".join(
        f"Way-point {w['index']}: NO by truth, yes by the estimate: the estimate came within "
        f"{w['acceptance_radius_m']:g} m of it while the vehicle truly passed "
        f"{w['closest_true_distance_m']:.1f} m away, so the navigation error there was at least "
        f"{w['closest_true_distance_m'] - w['acceptance_radius_m']:.1f} m"
        for w in missed
    ) + ("." if missed else "")
