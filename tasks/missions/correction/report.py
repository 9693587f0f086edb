"""The report of ``mission/correction``: ``metrics.json``, the tables and the figures."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field

from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.report import export_runs
from tasks.core.registry import ReportContext, ReportSummary
from tasks.missions.correction.figures import correction_figure, current_figure, record_correction
from tasks.missions.correction.run import SPANS, CorrectionRunResult, current_along_track
from tasks.missions.correction.scenario import CorrectionScenario, run_scenario


class CorrectionRunMetrics(BaseModel):
    """One run of ``mission/correction``."""

    run: int
    failed: str | None
    correction_error: str | None
    compensated: dict[str, float]
    direct: dict[str, float]


class CorrectionMetrics(BaseModel):
    """``metrics.json`` of ``mission/correction``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    procedure: str
    current_kind: str
    means: dict[str, float] = Field(
        description="means over successful runs (a quantity no run has is left out)"
    )
    improvement_factor: float | None = Field(
        description="uncorrected / corrected mean DR error on leg 3 (compensated flights); "
        "null without a successful run"
    )
    runs: list[CorrectionRunMetrics]


def _fmt(v: float | None, digits: int) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def report_correction(exp: MissionExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables 1 and 3 analogues, the current estimate, figures and the recording."""
    from tasks.core.report import Table, write_metrics, write_tables

    scn: CorrectionScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[CorrectionRunResult] = [r for b in ctx.blocks for r in b]
    ok = [r for r in runs if r.failed is None and r.metrics["compensated"] and r.metrics["direct"]]

    def mean(law: str, key: str) -> float | None:
        """The mean over the successful runs that have it; ``None`` (a dash) for none."""
        vals = [r.metrics[law][key] for r in ok if key in r.metrics[law]]
        vals = [v for v in vals if math.isfinite(v)]
        return float(np.mean(vals)) if vals else None

    means = {
        f"{law}.{k}": v
        for law in ("compensated", "direct")
        for k in (ok[0].metrics[law] if ok else {})
        if (v := mean(law, k)) is not None
    }
    before = mean("compensated", "uncorrected_mean_error_m")
    after = mean("compensated", "corrected_mean_error_m")
    factor = before / after if before is not None and after else None
    metrics = CorrectionMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=sum(r.failed is not None for r in runs),
        procedure=scn.correction.procedure,
        current_kind=scn.current.kind,
        means=means,
        improvement_factor=factor,
        runs=[
            CorrectionRunMetrics(
                run=r.run,
                failed=r.failed,
                correction_error=r.correction_error,
                compensated=r.metrics.get("compensated", {}),
                direct=r.metrics.get("direct", {}),
            )
            for r in runs
        ],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    for law in ("compensated", "direct"):
        files += export_runs(
            ctx.out_dir, exp.name, [r.flights[law] for r in runs], law, frame=scn.frame()
        )
    p = scn.correction.procedure.upper()
    t1 = Table(
        f"Leg 3 dead-reckoning error after {p} ({len(ok)} runs, {scn.current.kind} current; "
        "seed 001 Table 1-2 analogue)",
        ["DR", "Mean error (m)", "Max error (m)", "Final error (m)"],
        [
            [
                name,
                mean("compensated", f"{k}_mean_error_m"),
                mean("compensated", f"{k}_max_error_m"),
                mean("compensated", f"{k}_final_error_m"),
            ]
            for name, k in [
                ("without CP", "uncorrected"),
                (f"{p}-corrected", "corrected"),
                ("baseline (GPS - DR) / T", "baseline"),
            ]
        ],
        digits=2,
        slug="leg3-errors",
        note=f"Improvement of the mean error by the correction: {_fmt(factor, 1)}x.",
    )
    t3 = Table(
        "Leg 3 deviation from the desired course (seed 001 Table 3 analogue)",
        ["Course law", "Mean deviation (deg)", "Mean cross-track distance (m)"],
        [
            [
                "direct course to the way-point",
                mean("direct", "course_deviation_deg"),
                mean("direct", "cross_track_m"),
            ],
            [
                "compensated (eq. 22-26)",
                mean("compensated", "course_deviation_deg"),
                mean("compensated", "cross_track_m"),
            ],
        ],
        digits=2,
        slug="leg3-course",
    )
    tc = Table(
        f"Current estimated by {p} against the true current at the vehicle (legs 1-2)",
        [
            "Run",
            "True east (m/s)",
            "True north (m/s)",
            "Estimated east (m/s)",
            "Estimated north (m/s)",
            "Error (m/s)",
        ],
        [
            [
                r.run,
                *(
                    r.metrics["compensated"].get(k)
                    for k in (
                        "current_true_east_m_s",
                        "current_true_north_m_s",
                        "current_est_east_m_s",
                        "current_est_north_m_s",
                        "current_error_m_s",
                    )
                ),
            ]
            for r in ok
        ],
        digits=3,
        slug="current",
        note=(
            f"{p}'s current estimate is {_fmt(mean('compensated', 'current_error_m_s'), 3)} m/s "
            "off the true current at the vehicle averaged over legs 1-2 (Error: the size of the "
            "difference; its mean over the runs)."
        ),
    )
    ta = along_track_table(p, ok)
    tables = [t1, t3, tc, ta]
    failures = [r.failed for r in runs if r.failed]
    if failures:
        tables.append(
            Table(
                "Failed runs",
                ["Run", "Reason"],
                [[r.run, r.failed] for r in runs if r.failed],
                slug="failed",
            )
        )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in runs if r.run == scn.report.record_run and r.failed is None), None)
    if rec is not None:
        flight = rec.flights["compensated"]
        if scn.report.figures:
            files += correction_figure(exp.name, scn, rec, ctx.out_dir)
            files += current_figure(exp.name, scn, rec, ctx.out_dir)
        if scn.report.recording and flight.vehicles:
            flown = run_scenario(scn, ctx.seed, rec.run)
            files += record_correction(exp.name, flown, rec.flights, ctx.out_dir)
    text = "".join(t.to_text() + "\n" for t in tables[:2])
    text += tc.note + "\n" + ta.note + "\n" + f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


ALONG_TRACK_COLUMNS = (
    ("mean_error_m_s", "Mean error (m/s)"),
    ("rms_error_m_s", "RMS error (m/s)"),
    ("max_error_m_s", "Max error (m/s)"),
    ("bias_east_m_s", "Mean error east (m/s)"),
    ("bias_north_m_s", "Mean error north (m/s)"),
    ("true_mean_speed_m_s", "True mean speed (m/s)"),
    ("true_rms_variation_m_s", "True RMS variation (m/s)"),
    ("true_max_variation_m_s", "True max variation (m/s)"),
)
"""The along-track comparison's quantities (:func:`~tasks.missions.correction.run.
current_along_track`) and their column headers."""


def along_track_table(procedure: str, ok: list[CorrectionRunResult]):
    """The correction's estimated current against the true current at the vehicle, per tick of
    legs 1-3 of the compensated flights (:func:`~tasks.missions.correction.run.
    current_along_track`), each quantity the mean over the successful runs."""
    from tasks.core.report import Table

    per_run = [current_along_track(r.flights["compensated"].lead) for r in ok]
    rows = []
    for span in SPANS:
        vals = [a[span] for a in per_run if span in a]
        rows.append(
            [span]
            + [
                float(np.mean([v[k] for v in vals])) if vals else None
                for k, _ in ALONG_TRACK_COLUMNS
            ]
        )
    whole = rows[-1][1:]
    note = (
        "Error: the estimate minus the true current at the vehicle (mean, RMS, max: of its "
        f"size). Along the track (legs 1-3, every tick) the estimate is {whole[0]:.3f} m/s off "
        f"on average (RMS {whole[1]:.3f}, max {whole[2]:.3f} m/s); the true current varied by "
        f"{whole[6]:.3f} m/s RMS about its mean."
        if all(isinstance(x, float) for x in whole)
        else "No successful run with a current estimate."
    )
    return Table(
        f"Current estimated by {procedure} against the true current at the vehicle, tick by tick "
        f"along the track ({len(per_run)} runs, compensated flights; means over runs)",
        ["Span", *(h for _, h in ALONG_TRACK_COLUMNS)],
        rows,
        digits=3,
        slug="current-along-track",
        note=note,
    )
