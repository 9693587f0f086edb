"""Report of seed 003's tests: merge the blocks, compute Tables 1-3 beside the paper's, the
consistency of the stated accuracy, what the ranges did, the warnings, and write ``metrics.json``,
the tables, the figures, the run data and the recording.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from nav.metrics import nees_band
from nav.relative import pooled_stats
from tasks.core.registry import Experiment, ReportContext, ReportSummary
from tasks.core.report import Table, write_metrics, write_tables
from tasks.paper003.figures import write_figures
from tasks.paper003.paper import PAPER_TABLES, PaperCells
from tasks.paper003.recording import record_sample, write_run_data
from tasks.paper003.run import CONSISTENCY_ROWS, FIXED, METHODS, hdop_figure2
from tasks.paper003.scenario import HdopMapConfig, Paper003Scenario, readings

Array = NDArray[np.float64]

STATS = ("max", "mean", "std")


class CellStats(BaseModel):
    """Maximum, arithmetic mean and standard deviation of the distance to the reference, m."""

    max_m: float | None
    mean_m: float | None
    std_m: float | None


class MethodCells(BaseModel):
    """A row of Tables 1-3: the single test sample and all runs (pooled 10 Hz samples)."""

    single: CellStats
    all_runs: CellStats


class ReadingResult(BaseModel):
    """Every method under one reading of the paper."""

    label: str
    offset: str
    bearing_of: str
    jacobian: str
    restart: bool
    methods: dict[str, MethodCells]
    ratio_to_paper: dict[str, CellStats] = Field(
        description="all-runs cells divided by the paper's 100-sample cells (GA1, GA2, DR)"
    )


class GaConsistency(BaseModel):
    """A method's stated accuracy at its fixes against its actual error."""

    method: str
    n_fixes: int
    mean_nees: float | None
    band_low: float | None
    band_high: float | None
    stated_rms_m: float | None = Field(description="sqrt(mean trace of the stated covariance)")
    actual_rms_m: float | None = Field(description="sqrt(mean squared error at the fixes)")
    stated_to_actual: float | None
    consistent: bool
    note: str


class FixStats(BaseModel):
    """What the ranges did for one method (all runs)."""

    method: str
    ranges_expected: int
    ranges_received: int
    accepted: int
    refused_short: int
    refused_hdop: int
    mean_hdop: float | None
    median_hdop: float | None = Field(description="median over runs of each run's median HDOP")
    longest_gap_s: float


class ErrorDraw(BaseModel):
    """A simulated error against what the navigation assumes."""

    quantity: str
    distribution: str
    half_width: float
    simulated_std: float
    bias: str
    navigation_sigma: float | None


class Paper003Metrics(BaseModel):
    """``metrics.json`` of ``paper-003/test-*`` (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    single_sample_run: int
    paper_table: str
    reading: str
    methods: dict[str, MethodCells]
    paper: dict[str, MethodCells]
    ratio_to_paper: dict[str, CellStats]
    readings: list[ReadingResult] = Field(description="report.readings = all: every reading")
    consistency: list[GaConsistency]
    fixes: list[FixStats]
    hdop_figure2: dict[str, float] = Field(
        description="HDOP of the Figure 2 set-up at relative bearings 0, 90, 180, 270 deg"
    )
    claims: dict[str, bool] = Field(description="the paper's qualitative claims on these runs")
    error_draws: list[ErrorDraw]
    warnings: list[str]


def _clean(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _pooled(stats: Array) -> CellStats:
    """(runs, 4) per-run sums -> pooled max, mean, std (population) over every sample
    (:func:`nav.relative.pooled_stats`)."""
    pooled = pooled_stats(stats)
    if pooled is None:
        return CellStats(max_m=None, mean_m=None, std_m=None)
    mx, mean, std = pooled
    return CellStats(max_m=_clean(mx), mean_m=_clean(mean), std_m=_clean(std))


def _paper_cells(cells: PaperCells) -> dict[str, MethodCells]:
    out = {}
    for k, (single, hundred) in cells.items():
        out[k] = MethodCells(
            single=CellStats(max_m=single[0], mean_m=single[1], std_m=single[2]),
            all_runs=CellStats(max_m=hundred[0], mean_m=hundred[1], std_m=hundred[2]),
        )
    return out


def _ratio(ours: CellStats, paper: CellStats) -> CellStats:
    def r(a: float | None, b: float | None) -> float | None:
        return None if a is None or not b else a / b

    return CellStats(
        max_m=r(ours.max_m, paper.max_m),
        mean_m=r(ours.mean_m, paper.mean_m),
        std_m=r(ours.std_m, paper.std_m),
    )


def _hdop_at_bearings(cfg: HdopMapConfig, distance_m: float) -> dict[str, float]:
    c = math.radians(cfg.course_deg)
    out = {}
    for rb in (0, 90, 180, 270):
        b = c + math.radians(rb)
        h = hdop_figure2(
            cfg, np.array([distance_m * math.sin(b)]), np.array([distance_m * math.cos(b)])
        )
        out[f"{rb}"] = float(h[0])
    return out


def _error_draws(scn: Paper003Scenario) -> list[ErrorDraw]:
    s, n = scn.sensors, scn.navigation
    rows = [
        ("course (deg)", s.ins.heading, n.sigma_course_deg),
        ("speed (m/s)", s.log.speed, n.sigma_speed_m_s),
        ("range (m)", s.modem.range, n.sigma_range_m),
        ("leader broadcast (m)", s.modem.broadcast, None),
    ]
    out = []
    for name, cfg, sigma in rows:
        model = cfg.to_model()
        k = model.uniform_k if model.distribution == "uniform" else float("nan")
        bias = [f"{model.bias / cfg.unit_to_si:g}"]
        if model.sector_bias is not None:
            bias = ["sectors " + ", ".join(f"{b / cfg.unit_to_si:g}" for b in model.sector_bias)]
        out.append(
            ErrorDraw(
                quantity=name,
                distribution=model.distribution,
                half_width=k * model.sigma / cfg.unit_to_si if np.isfinite(k) else 0.0,
                simulated_std=model.noise_std / cfg.unit_to_si,
                bias=bias[0],
                navigation_sigma=sigma,
            )
        )
    return out


@dataclass
class _Totals:
    labels: tuple[str, ...]
    per_run: list[Array] = field(default_factory=list)
    consistency: list[Array] = field(default_factory=list)
    fixes: list[Array] = field(default_factory=list)
    gaps: list[Array] = field(default_factory=list)
    hdop_median: list[Array] = field(default_factory=list)
    routes: dict[int, dict[str, NDArray[np.float32]]] = field(default_factory=dict)
    single: dict[int, dict[str, Array]] = field(default_factory=dict)


def _merge(ctx: ReportContext) -> _Totals:
    tot: _Totals | None = None
    for b in ctx.blocks:
        if tot is None:
            tot = _Totals(b.labels)
        elif b.labels != tot.labels:
            raise ValueError("blocks computed different readings")
        tot.per_run.append(b.per_run)
        tot.consistency.append(b.consistency)
        tot.fixes.append(b.fixes)
        tot.gaps.append(b.longest_gap_s)
        tot.hdop_median.append(b.hdop_median)
        tot.routes.update(b.routes)
        tot.single.update(b.single)
    if tot is None:
        raise ValueError("no blocks to report")
    return tot


def _cells(per_run: Array, single_index: int) -> dict[str, MethodCells]:
    """(runs, 4 methods, 4) -> method -> cells."""
    return {
        name: MethodCells(
            single=_pooled(per_run[single_index : single_index + 1, m]),
            all_runs=_pooled(per_run[:, m]),
        )
        for m, name in enumerate(METHODS)
    }


def report_paper003(exp: Experiment, test: str, ctx: ReportContext) -> ReportSummary:
    """Tables, figures, metrics, run data and the recording of a seed 003 test.

    Args:
        exp: the experiment (its name and summary head the files).
        test: ``"test-1"``, ``"test-2"`` or ``"test-3"``: which of the paper's tables to compare.
        ctx: the blocks, the scenario and the output folder.
    """
    scn: Paper003Scenario = ctx.scenario  # type: ignore[assignment]
    tot = _merge(ctx)
    per_run = np.concatenate(tot.per_run)  # (N, R, M, 4) in run order
    cons = np.concatenate(tot.consistency)
    fixes = np.concatenate(tot.fixes)
    gaps = np.concatenate(tot.gaps)
    hmed = np.concatenate(tot.hdop_median)
    single = scn.report.single_sample
    table_name, paper_cells = PAPER_TABLES[test]
    paper = _paper_cells(paper_cells)
    rds = readings(scn)
    all_cells = [_cells(per_run[:, r], single) for r in range(len(rds))]
    methods = all_cells[0]
    ratio = {k: _ratio(methods[k].all_runs, paper[k].all_runs) for k in paper}
    reading_results = []
    if scn.report.readings == "all":
        for rd, cells in zip(rds, all_cells, strict=True):
            reading_results.append(
                ReadingResult(
                    label=rd.label,
                    offset=rd.offset,
                    bearing_of=rd.bearing_of,
                    jacobian=rd.jacobian,
                    restart=rd.restart,
                    methods=cells,
                    ratio_to_paper={k: _ratio(cells[k].all_runs, paper[k].all_runs) for k in paper},
                )
            )
    # consistency of the stated accuracy (default reading)
    consistency = []
    for m, name in enumerate(CONSISTENCY_ROWS):
        c = cons[:, 0, m].sum(axis=0)
        nf = int(c[0])
        if nf == 0:
            consistency.append(
                GaConsistency(
                    method=name,
                    n_fixes=0,
                    mean_nees=None,
                    band_low=None,
                    band_high=None,
                    stated_rms_m=None,
                    actual_rms_m=None,
                    stated_to_actual=None,
                    consistent=False,
                    note="no fix was accepted: nothing to compare",
                )
            )
            continue
        lo, hi = nees_band(2, nf, scn.report.consistency_probability)
        mean_nees = c[1] / nf
        stated, actual = math.sqrt(c[2] / nf), math.sqrt(c[3] / nf)
        ok = lo <= mean_nees <= hi
        if ok:
            note = "consistent: the mean NEES over the fixes is inside its chi-square band"
        elif mean_nees > hi:
            note = (
                f"over-confident: the actual error is {actual / stated:.1f} x the stated RMS "
                "(the systematic course and speed errors are not in eq. 5)"
            )
        else:
            note = f"pessimistic: the stated RMS is {stated / actual:.1f} x the actual error"
        consistency.append(
            GaConsistency(
                method=name,
                n_fixes=nf,
                mean_nees=mean_nees,
                band_low=lo,
                band_high=hi,
                stated_rms_m=stated,
                actual_rms_m=actual,
                stated_to_actual=stated / actual,
                consistent=ok,
                note=note,
            )
        )
    fix_stats = []
    for m, name in enumerate(FIXED):
        f = fixes[:, 0, m].sum(axis=0)
        med = hmed[:, m]
        fix_stats.append(
            FixStats(
                method=name,
                ranges_expected=int(f[0]),
                ranges_received=int(f[1]),
                accepted=int(f[2]),
                refused_short=int(f[3]),
                refused_hdop=int(f[4]),
                mean_hdop=_clean(f[5] / f[2]) if f[2] else None,
                median_hdop=_clean(float(np.median(med[np.isfinite(med)])))
                if np.isfinite(med).any()
                else None,
                longest_gap_s=float(gaps[:, 0, m].max()),
            )
        )
    warnings = _warnings(scn, fix_stats)
    hd = _hdop_at_bearings(scn.report.hdop_map, scn.formation.distance_m or 10.0)
    mean = {k: methods[k].all_runs.mean_m or 0.0 for k in METHODS}
    claims = {
        "GA1 beats DR (mean, all runs)": mean["GA1"] < mean["DR"],
        "GA2 beats DR (mean, all runs)": mean["GA2"] < mean["DR"],
        "abeam HDOP below astern HDOP (Figure 2 set-up)": hd["90"] < hd["180"],
    }
    metrics = Paper003Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        single_sample_run=single,
        paper_table=table_name,
        reading=rds[0].label,
        methods=methods,
        paper=paper,
        ratio_to_paper=ratio,
        readings=reading_results,
        consistency=consistency,
        fixes=fix_stats,
        hdop_figure2=hd,
        claims=claims,
        error_draws=_error_draws(scn),
        warnings=warnings,
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    tables = _tables(exp, ctx, metrics)
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if scn.report.figures:
        files += write_figures(exp, ctx, scn, tot.routes, tot.single)
    if scn.report.run_data:
        files += write_run_data(exp, ctx, scn, per_run[:, 0])
    if (scn.report.recording or scn.report.run_data) and single in tot.single:
        files += record_sample(exp, scn, ctx.seed, single, tot.single[single], ctx.out_dir)
    text = tables[0].to_text()
    if warnings:
        text += "\n" + "\n".join(f"warning: {w}" for w in warnings) + "\n"
    text += f"\nwrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _warnings(scn: Paper003Scenario, fix_stats: list[FixStats]) -> list[str]:
    out = []
    ga = fix_stats[0]
    if ga.ranges_received < ga.ranges_expected:
        m = scn.sensors.modem
        why = []
        if m.max_range_m is not None:
            why.append(f"sensors.modem.max_range_m = {m.max_range_m:g} m")
        if m.dropout_windows_s:
            why.append(f"sensors.modem.dropout_windows_s = {m.dropout_windows_s}")
        if m.range.dropout_probability > 0:
            why.append(f"dropout probability {m.range.dropout_probability:g}")
        out.append(
            f"ranges missing: {ga.ranges_received} of {ga.ranges_expected} received"
            + (f" ({'; '.join(why)})" if why else "")
            + f"; GA and EKF dead-reckon through the gaps (longest {ga.longest_gap_s:g} s "
            "without a fix)"
        )
    for f in fix_stats:
        if f.refused_short:
            out.append(
                f"{f.method}: {f.refused_short} ranges below navigation.min_range_m = "
                f"{scn.navigation.min_range_m:g} m (zero range: the follower on the leader) "
                "made no fix; it dead-reckons instead"
            )
        if f.refused_hdop:
            out.append(
                f"{f.method}: {f.refused_hdop} fixes refused for HDOP above navigation.max_hdop "
                f"= {scn.navigation.max_hdop:g}; it dead-reckons instead"
            )
    for f in fix_stats[:2]:
        if f.median_hdop is not None and f.median_hdop > scn.report.warn_hdop:
            out.append(
                f"poor geometry: median HDOP {f.median_hdop:.1f} of {f.method}'s fixes "
                f"(above report.warn_hdop = {scn.report.warn_hdop:g}): the follower is near the "
                "leader's course line (bow or stern), where the range and the DR segment cross "
                "at a small angle"
            )
    if ga.accepted == 0 and ga.ranges_expected:
        out.append("no GA fix at all: GA1, GA2 and the EKF are pure DR in these runs")
    return out


def _cell_row(name: str, ours: MethodCells, paper: MethodCells | None) -> list:
    row: list = [name]
    for part in ("single", "all_runs"):
        for st in STATS:
            v = getattr(getattr(ours, part), f"{st}_m")
            p = getattr(getattr(paper, part), f"{st}_m") if paper else None
            row += [v, p, (v / p) if (v is not None and p) else None]
    return row


FAR = (2 / 3, 3 / 2)
"""Ratios to the paper outside this range are explained under the table."""


def _far_from_paper(rows: list[list], reading: str) -> str:
    """Why a GA row is far from the paper (a ratio outside :data:`FAR`), or ``""``: the seed's
    GA tables are ambiguous, no single reading reproduces all of their cells (the seeds' reading
    notes; :mod:`tasks.paper003.square`)."""
    far = []
    for row in rows:
        ratios = [r for r in row[3::3] if r is not None]
        if row[0] in ("GA1", "GA2") and any(not FAR[0] <= r <= FAR[1] for r in ratios):
            far.append(f"{row[0]} at {min(ratios):.2f}-{max(ratios):.2f}x")
    if not far:
        return ""
    return (
        f"\n{' and '.join(far)} the paper: seed 003's GA tables are ambiguous and no one reading "
        f"of its equations gives all their cells (this is {reading}: formation.offset / "
        "formation.bearing_of / navigation.jacobian / navigation.restart); "
        'report.readings = "all" shows every reading.'
    )


def _tables(exp: Experiment, ctx: ReportContext, m: Paper003Metrics) -> list[Table]:
    cols = ["Method"]
    for part in ("1 sample", f"{ctx.n_runs} samples"):
        for st in ("max", "mean", "std"):
            cols += [f"{st} {part} (m)", "paper", "ratio"]
    rows = [_cell_row(k, m.methods[k], m.paper.get(k)) for k in METHODS]
    main = Table(
        f"{m.paper_table}: distance to the reference position (m), reading {m.reading}; "
        f"single sample = run {m.single_sample_run}, {ctx.n_runs} samples pooled at 10 Hz",
        cols,
        rows,
        digits=2,
        slug="table",
        note="Paper columns: the paper's single sample and 100 samples; EKF is beyond the paper."
        + _far_from_paper(rows, m.reading),
    )
    tables = [main]
    if m.readings:
        rc = ["Reading", "Method"]
        for st in ("max", "mean", "std"):
            rc += [f"{st} (m)", "ratio"]
        rows = []
        for r in m.readings:
            for k in ("GA1", "GA2", "DR"):
                c, q = r.methods[k].all_runs, r.ratio_to_paper[k]
                rows.append([r.label, k, c.max_m, q.max_m, c.mean_m, q.mean_m, c.std_m, q.std_m])
        for k in ("GA1", "GA2", "DR"):
            p = m.paper[k].all_runs
            rows.append(["paper (100 samples)", k, p.max_m, 1.0, p.mean_m, 1.0, p.std_m, 1.0])
        tables.append(
            Table(
                f"Every reading, {ctx.n_runs} samples pooled, against {m.paper_table}",
                rc,
                rows,
                digits=2,
                slug="readings",
                note="reading = offset / whose bearing / A of eq. 2 / DR restart after a fix",
            )
        )
    tables.append(
        Table(
            "Stated accuracy at the fixes against the actual error (mean NEES, 2-D)",
            [
                "Method",
                "Fixes",
                "Mean NEES",
                "Band low",
                "Band high",
                "Stated RMS (m)",
                "Actual RMS (m)",
                "Stated / actual",
                "Verdict",
            ],
            [
                [
                    c.method,
                    c.n_fixes,
                    c.mean_nees,
                    c.band_low,
                    c.band_high,
                    c.stated_rms_m,
                    c.actual_rms_m,
                    c.stated_to_actual,
                    "consistent" if c.consistent else "inconsistent",
                ]
                for c in m.consistency
            ],
            digits=3,
            slug="consistency",
            note=" ".join(f"{c.method}: {c.note}." for c in m.consistency),
        )
    )
    tables.append(
        Table(
            "Ranges and fixes",
            [
                "Method",
                "Expected",
                "Received",
                "Accepted",
                "Too short",
                "HDOP refused",
                "Mean HDOP",
                "Median HDOP",
                "Longest gap (s)",
            ],
            [
                [
                    f.method,
                    f.ranges_expected,
                    f.ranges_received,
                    f.accepted,
                    f.refused_short,
                    f.refused_hdop,
                    f.mean_hdop,
                    f.median_hdop,
                    f.longest_gap_s,
                ]
                for f in m.fixes
            ],
            digits=2,
            slug="fixes",
            note="HDOP of the Figure 2 set-up at relative bearings 0/90/180/270 deg: "
            + " / ".join(f"{v:.2f}" for v in m.hdop_figure2.values()),
        )
    )
    tables.append(
        Table(
            "Simulated errors against the navigation's sigmas",
            ["Quantity", "Draw", "Half-width", "Simulated std", "Bias", "Navigation sigma"],
            [
                [
                    d.quantity,
                    d.distribution,
                    d.half_width,
                    d.simulated_std,
                    d.bias,
                    d.navigation_sigma,
                ]
                for d in m.error_draws
            ],
            digits=3,
            slug="error-draws",
        )
    )
    if m.warnings:
        tables.append(Table("Warnings", ["Warning"], [[w] for w in m.warnings], slug="warnings"))
    return tables
