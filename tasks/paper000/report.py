"""Report of a seed 000 test: the blocks merged, ``metrics.json``, the tables in the paper's layout
with the paper's values beside, the filter's consistency, and the figures and recording."""

from __future__ import annotations

import dataclasses
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.kinematic.passage import straight_passage
from bauv_sim.sensors import periodic_indices
from nav.metrics import nees_band, series_stats
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report import Table, write_metrics, write_tables
from tasks.paper000.figures import passage_figures
from tasks.paper000.paper import PAPER_TABLES, PaperRow
from tasks.paper000.recording import record_passage
from tasks.paper000.run import METHODS, Paper000Block
from tasks.paper000.scenario import Paper000Scenario


class PassageTest(Protocol):
    """What the report reads of the experiment (:class:`tasks.paper000.passage.
    StraightPassageExperiment`): its name, summary, test and the fields off the paper's setting."""

    name: str
    summary: str
    test: str

    def off_paper_fields(self, scenario: Paper000Scenario) -> list[str]: ...


# Metrics file


class MethodStats(BaseModel):
    """Minimum, maximum and mean distance to the reference position, m."""

    min_m: float | None
    max_m: float | None
    mean_m: float | None


class SinglePassage(BaseModel):
    """Statistics of one passage."""

    run: int
    methods: dict[str, MethodStats]
    paper_table: str | None = None
    paper: dict[str, MethodStats] | None = None


class Consistency(BaseModel):
    """EKF consistency: average NEES over the runs against its chi-square band."""

    nees_dim: int
    n_runs: int
    probability: float
    band_low: float
    band_high: float
    fraction_in_band: float = Field(description="fraction of ticks 1..T with the mean NEES in band")
    mean_nees: float
    consistent: bool
    note: str


class ErrorDraw(BaseModel):
    """How a simulated error compares with what the filter assumes."""

    quantity: str
    distribution: str
    simulated_std: float
    filter_sigma: float
    ratio: float


class Paper000Metrics(BaseModel):
    """``metrics.json`` of ``paper-000/test-*`` (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    usbl_period_s: float
    passages: dict[str, MethodStats] = Field(
        description="min / max / mean over ticks 1..T of zeta(k), the mean over runs (eq. 24)"
    )
    paper_table: str | None = Field(
        description="the paper's table of this test, or null when the scenario is not the "
        "paper's setting (see paper_setting)"
    )
    paper: dict[str, MethodStats] | None
    mean_ratio_to_paper: dict[str, float | None] = Field(
        description="mean distance over the paper's; null when the method has no data or the "
        "scenario is not the paper's setting"
    )
    paper_setting: str = Field(
        description="'paper' when the scenario is the paper's setting (report and runner "
        "fields aside), else the fields that differ"
    )
    no_data: dict[str, str] = Field(
        description="methods without a single sample, each with the reason (their statistics "
        "are null)"
    )
    single_passages: list[SinglePassage]
    per_run_mean_m: dict[str, MethodStats] = Field(
        description="min / max / mean over runs of each run's mean distance"
    )
    consistency: Consistency
    error_draws: list[ErrorDraw]
    usbl_fix_availability: float
    gate_rejections: int


def _stats(mn: float, mx: float, mean: float) -> MethodStats:
    def clean(v: float) -> float | None:
        return None if not np.isfinite(v) else float(v)

    return MethodStats(min_m=clean(mn), max_m=clean(mx), mean_m=clean(mean))


def _error_draws(scn: Paper000Scenario) -> list[ErrorDraw]:
    s, f = scn.sensors, scn.filter
    rows = [
        ("COG (deg)", s.ins.heading, f.sigma_course_deg),
        ("SOG (m/s)", s.log.speed, f.sigma_speed_m_s),
        ("dz (m)", s.pressure.depth, f.sigma_depth_change_m),
        ("r (m)", s.usbl.range, f.sigma_range_m),
        ("alpha (deg)", s.usbl.azimuth, f.sigma_azimuth_deg),
        ("beta (deg)", s.usbl.elevation, f.sigma_elevation_deg),
    ]
    out = []
    for name, cfg, sigma in rows:
        std = cfg.to_model().noise_std / cfg.unit_to_si
        out.append(
            ErrorDraw(
                quantity=name,
                distribution=cfg.distribution,
                simulated_std=std,
                filter_sigma=sigma,
                ratio=std / sigma,
            )
        )
    return out


def _paper_stats(rows: dict[str, PaperRow]) -> dict[str, MethodStats]:
    return {k: _stats(*v) for k, v in rows.items()}


def _no_data_reasons(scn: Paper000Scenario, tot: Paper000Block) -> dict[str, str]:
    """Why a method has no sample at all (only the USBL can have none: EKF and DR always have a
    position)."""
    reasons = {}
    if not np.any(tot.zeta["USBL"].count > 0):
        usbl = scn.sensors.usbl
        reasons["USBL"] = (
            f"no USBL fix was produced in {tot.fixes_expected} attempts (the vehicle stays beyond "
            f"sensors.usbl.max_range_m = {usbl.max_range_m:g} m or below "
            f"sensors.usbl.min_elevation_deg = {usbl.min_elevation_deg:g}, or every fix dropped "
            "out)"
        )
    return reasons


def _per_run_stats(values: NDArray[np.float64]) -> MethodStats:
    """Min / max / mean over runs of each run's mean distance, ignoring runs without data."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return MethodStats(min_m=None, max_m=None, mean_m=None)
    return _stats(float(v.min()), float(v.max()), float(v.mean()))


def _merge_blocks(ctx: ReportContext) -> Paper000Block:
    """The blocks summed in block order (so the sums are the same whatever the block layout of a
    resume). Linear in the number of blocks: the per-run arrays are gathered and concatenated
    once, the accumulators of fixed size are summed pairwise."""
    total: Paper000Block | None = None
    runs: list[tuple[int, ...]] = []
    per_run: list[NDArray[np.float64]] = []
    for b in ctx.blocks:
        runs.append(b.runs)
        per_run.append(b.per_run)
        if total is None:
            total = b
            continue
        total = Paper000Block(
            runs=(),
            zeta={k: total.zeta[k].merge(b.zeta[k]) for k in METHODS},
            nees_ekf=total.nees_ekf.merge(b.nees_ekf),
            nis=total.nis.merge(b.nis),
            per_run=per_run[0],
            hist={k: total.hist[k].merge(b.hist[k]) for k in METHODS},
            routes={**total.routes, **b.routes},
            single={**total.single, **b.single},
            fixes_produced=total.fixes_produced + b.fixes_produced,
            fixes_expected=total.fixes_expected + b.fixes_expected,
            gate_rejected=total.gate_rejected + b.gate_rejected,
            ekf_sigma_h=None
            if total.ekf_sigma_h is None or b.ekf_sigma_h is None
            else total.ekf_sigma_h.merge(b.ekf_sigma_h),
        )
    if total is None:
        raise ValueError("no blocks to report")
    return dataclasses.replace(
        total,
        runs=tuple(r for block in runs for r in block),
        per_run=np.concatenate(per_run) if len(per_run) > 1 else per_run[0],
    )


def report_paper000(exp: PassageTest, ctx: ReportContext) -> ReportSummary:
    """Tables, figures, metrics and the recording of a seed 000 test."""
    scn: Paper000Scenario = ctx.scenario  # type: ignore[assignment]
    lo, hi = nees_band(3, ctx.n_runs, scn.report.consistency_probability)
    tot = _merge_blocks(ctx)
    ref = PAPER_TABLES[exp.test]
    truth = straight_passage(scn.passage, scn.transceiver)
    n_ticks = scn.passage.n_ticks
    fix_tick = periodic_indices(n_ticks, round(scn.sensors.usbl.period_s / scn.passage.tick_s))
    zeta = {k: tot.zeta[k].mean() for k in METHODS}
    zeta_window = {"EKF": zeta["EKF"][1:], "DR": zeta["DR"][1:], "USBL": zeta["USBL"]}
    passages = {
        k: _stats(*(lambda s: (s.min, s.max, s.mean))(series_stats(v, np.isfinite(v))))
        for k, v in zeta_window.items()
    }
    no_data = _no_data_reasons(scn, tot)
    off_paper = exp.off_paper_fields(scn)
    on_paper = not off_paper
    paper_name, paper_rows = ref["hundred"]  # type: ignore[misc]
    ratio: dict[str, float | None] = {
        k: float(passages[k].mean_m / paper_rows[k][2])
        if on_paper and passages[k].mean_m is not None
        else None
        for k in METHODS
    }
    singles = []
    for run in sorted(tot.single):
        d = tot.single[run]
        methods = {}
        for k in METHODS:
            v = d[k] if k == "USBL" else d[k][1:]
            st = series_stats(v, np.isfinite(v))
            methods[k] = _stats(st.min, st.max, st.mean)
        tab = (
            ref["single"][run]  # type: ignore[index]
            if on_paper and run < len(ref["single"])  # type: ignore[arg-type]
            else None
        )
        singles.append(
            SinglePassage(
                run=run,
                methods=methods,
                paper_table=tab[0] if tab else None,
                paper=_paper_stats(tab[1]) if tab else None,
            )
        )
    per_run_mean = {k: _per_run_stats(tot.per_run[:, m, 2]) for m, k in enumerate(METHODS)}
    # consistency of the EKF
    mean_nees = tot.nees_ekf.mean()
    window = mean_nees[1:]
    frac = float(np.mean((window >= lo) & (window <= hi)))
    consistent = frac >= scn.report.consistency_min_fraction
    draws = _error_draws(scn)
    mismatched = [d for d in draws if abs(d.ratio - 1.0) > 0.05]
    if consistent:
        note = "consistent: the mean NEES stays inside its chi-square band"
    elif mismatched:
        by_ratio: dict[str, list[str]] = {}
        for d in mismatched:  # "COG (deg)" -> "COG", grouped by their ratio
            by_ratio.setdefault(f"{d.ratio:.2f}", []).append(d.quantity.split(" (")[0])
        what = "; ".join(f"{r}x ({', '.join(q)})" for r, q in by_ratio.items())
        note = (
            f"inconsistent, the filter mis-tuned: the simulated errors' std is {what} its sigma; "
            "seed 000 draws errors uniform on +-3 sigma, whose std is sqrt(3) sigma"
        )
    else:
        note = (
            "inconsistent although the simulated errors match the filter's sigmas: "
            "linearisation or the initial covariance dominate"
        )
    consistency = Consistency(
        nees_dim=3,
        n_runs=ctx.n_runs,
        probability=scn.report.consistency_probability,
        band_low=lo,
        band_high=hi,
        fraction_in_band=frac,
        mean_nees=float(np.mean(window)),
        consistent=consistent,
        note=note,
    )
    metrics = Paper000Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        usbl_period_s=scn.sensors.usbl.period_s,
        passages=passages,
        paper_table=paper_name if on_paper else None,
        paper=_paper_stats(paper_rows) if on_paper else None,
        mean_ratio_to_paper=ratio,
        paper_setting="paper" if on_paper else ", ".join(off_paper),
        no_data=no_data,
        single_passages=singles,
        per_run_mean_m=per_run_mean,
        consistency=consistency,
        error_draws=draws,
        usbl_fix_availability=tot.fixes_produced / max(tot.fixes_expected, 1),
        gate_rejections=tot.gate_rejected,
    )
    files = [write_metrics(ctx.out_dir, metrics)]

    # tables in the paper's layout, with the paper's values beside
    cols = [
        "Positioning method",
        "Minimum distance (m)",
        "Maximum distance (m)",
        "Average distance (m)",
        "Paper min",
        "Paper max",
        "Paper average",
    ]
    if not on_paper:
        cols = cols[:4]
    no_data_note = "".join(f"\n{k}: no data: {why}." for k, why in no_data.items())
    off_note = (
        ""
        if on_paper
        else f"Not the paper's setting (changed: {', '.join(off_paper)}): no comparison with the "
        "paper's tables."
    )
    tables = []
    for sp in singles:
        rows = []
        for k in METHODS:
            paper = sp.paper[k] if sp.paper else MethodStats(min_m=None, max_m=None, mean_m=None)
            rows.append(
                [
                    k,
                    sp.methods[k].min_m,
                    sp.methods[k].max_m,
                    sp.methods[k].mean_m,
                    paper.min_m,
                    paper.max_m,
                    paper.mean_m,
                ][: len(cols)]
            )
        title = f"Single passage {sp.run + 1}" + (
            f" (paper: {sp.paper_table})" if sp.paper_table else ""
        )
        tables.append(
            Table(
                title,
                cols,
                rows,
                slug=f"single-passage-{sp.run + 1}",
                note=(off_note + no_data_note).strip(),
            )
        )
    rows = [
        [k, passages[k].min_m, passages[k].max_m, passages[k].mean_m, *paper_rows[k]][: len(cols)]
        for k in METHODS
    ]
    ratio_note = (
        "Mean ratio to the paper: "
        + ", ".join(f"{k} {ratio[k]:.2f}" for k in METHODS if ratio[k] is not None)
        + "".join(f", {k} none (no data)" for k in METHODS if ratio[k] is None)
        if on_paper
        else off_note
    )
    main = Table(
        f"{ctx.n_runs} passages: statistics of zeta(k)"
        + (f" (paper: {paper_name}, 100 passages)" if on_paper else ""),
        cols,
        rows,
        slug="passages",
        note=ratio_note + no_data_note,
    )
    tables.append(main)
    tables.append(
        Table(
            "Simulated errors against the filter's assumptions",
            ["Quantity", "Draw", "Simulated std", "Filter sigma", "Ratio"],
            [[d.quantity, d.distribution, d.simulated_std, d.filter_sigma, d.ratio] for d in draws],
            digits=3,
            slug="error-draws",
        )
    )
    tables.append(
        Table(
            "EKF consistency (average NEES over runs, 3-D state)",
            ["Runs", "Band low", "Band high", "Fraction of ticks in band", "Mean NEES", "Verdict"],
            [
                [
                    ctx.n_runs,
                    lo,
                    hi,
                    frac,
                    consistency.mean_nees,
                    "consistent" if consistent else "inconsistent",
                ]
            ],
            digits=3,
            slug="consistency",
            note=note,
        )
    )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")

    if scn.report.figures:
        files += passage_figures(exp, ctx, scn, tot, truth, zeta, fix_tick, mean_nees, (lo, hi))
    if scn.report.recording:
        files.append(record_passage(exp, scn, ctx.seed, scn.report.record_run, ctx.out_dir))
    text = main.to_text() + "\n" + tables[-1].to_text()
    text += f"\nwrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))
