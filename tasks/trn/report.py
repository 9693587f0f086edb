"""The report of ``trn/relief``: the blocks pooled in run order, ``metrics.json``, the table of
TRN error against relief and map error beside the PCRB and DR-DVL, warnings, the figures.

Statistics per setting and method over the runs: the final error (mean, its standard error,
median, 90th percentile, RMS), the mean over the updates of each run's error (mean over runs),
and the RMSE over runs and updates ``sqrt(mean ||e||^2)``; beside them the PCRB's RMS level
``sqrt(mean trace PCRB)`` over the same runs and updates, and at the end. A run whose error is
not finite (an estimate that ran away to infinity) leaves that method's statistics and is
counted; a method with no finite run says "no data", never NaN.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report import Table, pool_blocks, write_metrics, write_tables
from tasks.trn.run import METHODS, runs, update_times
from tasks.trn.scenario import TrnReliefScenario

Array = NDArray[np.float64]

BELOW_BOUND_SE = 3.0
"""A filter whose RMSE is below the PCRB by more than this many of its standard errors is
flagged (the bound holds for any estimator: a filter below it has a bug or an optimistic
setting)."""


class MethodStats(BaseModel):
    """One method's error over the runs of one setting (no data: every field None)."""

    runs: int = Field(description="runs with a finite error")
    final_mean_m: float | None = Field(None, description="final error, mean over runs, m")
    final_se_m: float | None = Field(None, description="standard error of final_mean_m, m")
    final_median_m: float | None = Field(None, description="final error, median, m")
    final_p90_m: float | None = Field(None, description="final error, 90th percentile, m")
    final_rms_m: float | None = Field(None, description="final error, RMS over runs, m")
    mean_m: float | None = Field(
        None, description="each run's mean error over the updates, averaged over runs, m"
    )
    rmse_m: float | None = Field(None, description="RMS error over runs and updates, m")
    rmse_se_m: float | None = Field(
        None, description="standard error of rmse_m (delta method over the runs), m"
    )


class SettingMetrics(BaseModel):
    """One setting of the sweep."""

    relief_std_m: float
    map_sigma_m: float
    methods: dict[str, MethodStats]
    pcrb_rms_m: float = Field(description="sqrt(mean trace PCRB) over runs and updates, m")
    pcrb_final_m: float = Field(description="sqrt(mean trace PCRB) at the end, m")
    pcrb_bias_rms_m: float = Field(
        description="the same with the filters' per-ping bias prior marginalised (the bound of "
        "their measurement model), m"
    )
    pcrb_bias_final_m: float = Field(description="that bound at the end, m")
    no_lock_pings: int = Field(description="DVL pings without bottom lock, all runs")
    updates_without_soundings: int = Field(description="TRN updates with no sounding, all runs")
    reinitialisations: dict[str, int] = Field(description="per filter, all runs")
    diverged_updates: dict[str, int] = Field(description="updates flagged diverged, all runs")
    non_finite_runs: dict[str, int] = Field(description="runs whose error was not finite")


class TrnReliefMetrics(BaseModel):
    """``metrics.json`` of ``trn/relief``."""

    schema_version: Literal[1] = 1
    experiment: str
    n_runs: int
    seed: int
    duration_s: float
    update_period_s: float
    map_cell_m: float
    map_offset_m: float
    settings: list[SettingMetrics]
    warnings: list[str]


@dataclass(frozen=True)
class Pooled:
    """The blocks pooled in run order (shapes: n runs, S settings, 3 methods, J + 1 times)."""

    sq_err_sum: Array  # (S, 3, J + 1)
    count: NDArray[np.int64]  # (S, 3, J + 1)
    pcrb_sum: Array  # (S, 2, J + 1): without, with the per-ping bias
    final_m: Array  # (n, S, 3)
    mean_m: Array
    rms_m: Array
    reinit: NDArray[np.int64]  # (n, S, 2)
    diverged: NDArray[np.int64]
    no_lock: NDArray[np.int64]  # (n, S)
    no_update: NDArray[np.int64]

    @classmethod
    def of(cls, blocks: Iterator[dict[str, Array]]) -> Pooled:
        """Sum the per-update arrays and stack the per-run ones, one block at a time (the
        per-update arrays of a block are not kept: memory grows with the runs' scalars only)."""
        return cls(**pool_blocks(blocks, SUMMED, PER_RUN))


SUMMED = ("sq_err_sum", "count", "pcrb_sum")
"""The block's arrays summed over its runs (:func:`tasks.trn.run.run_block`)."""
PER_RUN = ("final_m", "mean_m", "rms_m", "reinit", "diverged", "no_lock", "no_update")
"""The block's arrays with one row per run."""


def method_stats(final: Array, mean: Array, rms: Array) -> MethodStats:
    """Statistics of one method over the runs whose three errors are finite."""
    ok = np.isfinite(final) & np.isfinite(mean) & np.isfinite(rms)
    n = int(ok.sum())
    if n == 0:
        return MethodStats(runs=0)
    f, mu, r2 = final[ok], mean[ok], rms[ok] ** 2
    rmse = float(np.sqrt(r2.mean()))
    se = lambda a: float(a.std(ddof=1) / np.sqrt(n)) if n > 1 else 0.0  # noqa: E731
    return MethodStats(
        runs=n,
        final_mean_m=float(f.mean()),
        final_se_m=se(f),
        final_median_m=float(np.median(f)),
        final_p90_m=float(np.percentile(f, 90)),
        final_rms_m=float(np.sqrt((f**2).mean())),
        mean_m=float(mu.mean()),
        rmse_m=rmse,
        rmse_se_m=se(r2) / (2 * rmse) if rmse > 0 else 0.0,
    )


def setting_metrics(p: Pooled, s: int, relief: float, map_sigma: float) -> SettingMetrics:
    """The metrics of setting ``s``."""
    n = p.final_m.shape[0]
    methods = {
        m: method_stats(p.final_m[:, s, i], p.mean_m[:, s, i], p.rms_m[:, s, i])
        for i, m in enumerate(METHODS)
    }
    non_finite = {m: n - methods[m].runs for m in METHODS}
    return SettingMetrics(
        relief_std_m=relief,
        map_sigma_m=map_sigma,
        methods=methods,
        pcrb_rms_m=float(np.sqrt(p.pcrb_sum[s, 0, 1:].mean() / n)),
        pcrb_final_m=float(np.sqrt(p.pcrb_sum[s, 0, -1] / n)),
        pcrb_bias_rms_m=float(np.sqrt(p.pcrb_sum[s, 1, 1:].mean() / n)),
        pcrb_bias_final_m=float(np.sqrt(p.pcrb_sum[s, 1, -1] / n)),
        no_lock_pings=int(p.no_lock[:, s].sum()),
        updates_without_soundings=int(p.no_update[:, s].sum()),
        reinitialisations={m: int(p.reinit[:, s, i].sum()) for i, m in enumerate(METHODS[1:])},
        diverged_updates={m: int(p.diverged[:, s, i].sum()) for i, m in enumerate(METHODS[1:])},
        non_finite_runs=non_finite,
    )


def warnings_of(m: TrnReliefMetrics) -> list[str]:
    """Lines for the reader: lost bottom lock, pings with no sounding, estimates that were not
    finite, re-initialised filters, a filter below the PCRB beyond Monte Carlo tolerance, a flat
    seabed."""
    out = []
    for s in m.settings:
        tag = f"relief {s.relief_std_m:g} m, map sigma {s.map_sigma_m:g} m"
        if s.no_lock_pings:
            out.append(
                f"{tag}: {s.no_lock_pings} DVL pings without bottom lock (DR held the "
                "last velocity; no sounding)"
            )
        if s.updates_without_soundings:
            out.append(
                f"{tag}: {s.updates_without_soundings} TRN updates had no sounding "
                "(prediction only)"
            )
        for meth, k in s.non_finite_runs.items():
            if k and not s.methods[meth].runs:
                out.append(f"{tag}: {meth}: no data (no run with a finite error)")
            elif k:
                out.append(f"{tag}: {meth}: {runs(k)} with a non-finite error left the statistics")
        for meth in METHODS[1:]:
            if s.reinitialisations[meth]:
                times = runs(s.reinitialisations[meth], "time")
                out.append(
                    f"{tag}: {meth} was re-initialised {times} (its divergence test fired; each "
                    "spreads it again, so its error jumps)"
                )
            st = s.methods[meth]
            if st.rmse_m is not None and st.rmse_m + BELOW_BOUND_SE * (st.rmse_se_m or 0.0) < (
                s.pcrb_rms_m
            ):
                out.append(
                    f"{tag}: {meth} RMSE {st.rmse_m:.3g} m is below the PCRB "
                    f"{s.pcrb_rms_m:.3g} m beyond {BELOW_BOUND_SE:g} standard errors"
                )
        if s.relief_std_m == 0:
            out.append(
                f"{tag}: a flat seabed holds no horizontal information: TRN cannot do "
                "better than dead reckoning there"
            )
    return out


def tables(m: TrnReliefMetrics) -> list[Table]:
    """Table 1: final and mean error per method beside the PCRB, one row per setting."""
    rows = []
    for s in m.settings:
        row: list = [s.relief_std_m, s.map_sigma_m]
        for meth in METHODS:
            st = s.methods[meth]
            row += [st.final_mean_m, st.mean_m, st.rmse_m]
        row += [s.pcrb_final_m, s.pcrb_rms_m, s.pcrb_bias_final_m, s.pcrb_bias_rms_m]
        rows.append(row)
    cols = ["relief std (m)", "map sigma (m)"]
    for meth in METHODS:
        cols += [f"{meth} final (m)", f"{meth} mean (m)", f"{meth} RMSE (m)"]
    cols += ["PCRB final (m)", "PCRB RMS (m)", "PCRB-bias final (m)", "PCRB-bias RMS (m)"]
    note = (
        f"{runs(m.n_runs)} of {m.duration_s:g} s, a TRN update every {m.update_period_s:g} s; "
        f"map cell {m.map_cell_m:g} m, offset {m.map_offset_m:g} m. Final: mean over runs of the "
        "error at the end; mean: mean over runs of each run's mean error; RMSE over runs and "
        "updates; PCRB: root of the mean trace of the bound (true track, true seabed's gradients, "
        "beam and map noise); PCRB-bias: the same with the filters' per-ping depth bias "
        "marginalised. A dash: no data."
    )
    return [
        Table(
            f"TRN error against relief and map error ({runs(m.n_runs)}, seed {m.seed})",
            cols,
            rows,
            digits=2,
            note=note,
            slug="trn-relief",
            key=2,  # relief and map sigma name a row (repeated on a narrow screen)
        )
    ]


def report_relief(name: str, summary: str, ctx: ReportContext) -> ReportSummary:
    """Write ``metrics.json``, the tables and the figures of a finished batch."""
    scn: TrnReliefScenario = ctx.scenario  # type: ignore[assignment]
    p = Pooled.of(ctx.blocks)
    times = update_times(scn)
    settings = [setting_metrics(p, s, r, v) for s, (r, v) in enumerate(scn.settings())]
    m = TrnReliefMetrics(
        experiment=name,
        n_runs=ctx.n_runs,
        seed=ctx.seed,
        duration_s=float(times[-1]),
        update_period_s=float(times[1] - times[0]) if len(times) > 1 else 0.0,
        map_cell_m=scn.map.cell_m,
        map_offset_m=scn.map.offset_m,
        settings=settings,
        warnings=[],
    )
    m = m.model_copy(update={"warnings": warnings_of(m)})
    files = [write_metrics(ctx.out_dir, m)]
    tabs = tables(m)
    files += write_tables(ctx.out_dir, tabs, heading=f"{name}: {summary}")
    if scn.report.figures:
        from tasks.trn import figures

        files += figures.relief(ctx.out_dir / "trn-relief.png", m)
        files += figures.against_time(ctx.out_dir / "trn-error-time.png", m, p, times)
    text = "".join(t.to_text() for t in tabs)
    text += "".join(f"warning: {w}\n" for w in m.warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))
