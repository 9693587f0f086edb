"""The report of ``coop/team`` and ``coop/sensitivity``: the blocks pooled in run order,
``metrics.json``, the tables per setting (each vehicle and method: mean and final error, NEES
beside its chi-square band, clock-offset error, ranges used), the acceptance check 4 of issue 24
(central <= decentralised <= leader-only positioning, decentralised not over-confident), the
packets lost, warnings and the figures.

The NEES (2 dof, horizontal) is averaged over the runs at each sample of the curves' grid and
compared with the two-sided 95 % band of that average (:func:`nav.metrics.nees_band`: the sum of
n consistent NEES is chi-square with 2n dof, Bar-Shalom, Li & Kirubarajan 2001, section 5.4);
the table gives its mean over every sample and the fraction of the grid's samples inside the band.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from nav.metrics import nees_band
from tasks.coop.run import LOSS_CAUSES, curve_ticks
from tasks.coop.scenario import CLOCKED, LABELS, LEADER_ONLY, CoopScenario
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report import Table, pool_blocks, write_metrics, write_tables

Array = NDArray[np.float64]


class VehicleStats(BaseModel):
    """One method on one vehicle over the runs of one setting."""

    mean_error_m: float = Field(description="each run's mean horizontal error, averaged, m")
    mean_error_se_m: float = Field(description="standard error of mean_error_m, m")
    final_error_m: float = Field(description="the error at the end, mean over runs, m")
    final_error_se_m: float = Field(description="standard error of final_error_m, m")
    rmse_m: float = Field(description="RMS error over runs and the curves' samples, m")
    nees: float | None = Field(
        None, description="NEES (2 dof) averaged over runs and samples (None: no covariance)"
    )
    nees_in_band: float | None = Field(
        None, description="fraction of the curves' samples whose run-averaged NEES is in the band"
    )
    clock_offset_rms_ms: float | None = Field(
        None, description="RMS error of the clock-offset estimate, ms (None: no clock state)"
    )
    ranges_used: float = Field(description="ranges fused per run, mean")


class SettingMetrics(BaseModel):
    """One setting: the base, or one sensitivity value."""

    label: str
    what: str
    value: float | None
    nees_band: tuple[float, float] = Field(description="95 % band of the run-averaged NEES")
    methods: dict[str, dict[str, VehicleStats]] = Field(
        description="method -> vehicle -> statistics"
    )
    ranges_scheduled: int = Field(
        description="range events per run (every receiver of a broadcast)"
    )
    ranges_produced: float = Field(description="ranges received per run, mean")
    lost: dict[str, float] = Field(description="ranges lost per run by cause, mean")
    ordering: dict[str, bool] = Field(
        description="per follower: central <= decentralised <= the better leader-only method "
        "(each run's mean error, paired, within 2 standard errors), and decentralised NEES <= "
        "the band's upper end (acceptance 4); empty without both cooperative methods"
    )


class CoopMetrics(BaseModel):
    """``metrics.json`` of ``coop/team`` and ``coop/sensitivity``."""

    schema_version: Literal[1] = 1
    experiment: str
    n_runs: int
    seed: int
    duration_s: float
    vehicles: list[str]
    methods: list[str]
    settings: list[SettingMetrics]
    warnings: list[str]


PER_RUN = ("mean_m", "final_m", "clock_rms_s", "ranges_used", "produced", "scheduled", "lost")
SUMMED = ("nees_sum", "nees_count", "nees_t_sum", "nees_t_count", "sq_err_sum")


@dataclass(frozen=True)
class Pooled:
    """The blocks pooled in run order (n runs, S settings, M methods, v vehicles, C curve
    samples)."""

    mean_m: Array  # (n, S, M, v)
    final_m: Array
    clock_rms_s: Array
    ranges_used: NDArray[np.int64]
    produced: NDArray[np.int64]  # (n, S)
    scheduled: NDArray[np.int64]
    lost: NDArray[np.int64]  # (n, S, 5)
    nees_sum: Array  # (S, M, v)
    nees_count: NDArray[np.int64]
    nees_t_sum: Array  # (S, M, v, C)
    nees_t_count: NDArray[np.int64]
    sq_err_sum: Array  # (S, M, v, C)

    @classmethod
    def of(cls, blocks: Iterator[dict[str, Array]]) -> Pooled:
        """Sum the pooled arrays and stack the per-run ones, one block at a time."""
        return cls(**pool_blocks(blocks, SUMMED, PER_RUN))


def _se(a: Array) -> float:
    return float(a.std(ddof=1) / np.sqrt(len(a))) if len(a) > 1 else 0.0


def vehicle_stats(
    p: Pooled, s: int, m: int, i: int, has_clock: bool, band: tuple[float, float]
) -> VehicleStats:
    """The statistics of method ``m`` on vehicle ``i`` in setting ``s``."""
    n = p.mean_m.shape[0]
    mean, final = p.mean_m[:, s, m, i], p.final_m[:, s, m, i]
    nees = nees_in = None
    if p.nees_count[s, m, i] > 0:
        nees = float(p.nees_sum[s, m, i] / p.nees_count[s, m, i])
        c = p.nees_t_count[s, m, i, 1:]
        avg = p.nees_t_sum[s, m, i, 1:][c > 0] / c[c > 0]
        nees_in = float(np.mean((avg >= band[0]) & (avg <= band[1]))) if avg.size else None
    clock = None
    if has_clock:
        clock = float(np.sqrt(np.mean(p.clock_rms_s[:, s, m, i] ** 2)) * 1e3)
    return VehicleStats(
        mean_error_m=float(mean.mean()),
        mean_error_se_m=_se(mean),
        final_error_m=float(final.mean()),
        final_error_se_m=_se(final),
        rmse_m=float(np.sqrt(p.sq_err_sum[s, m, i, 1:].mean() / n)),
        nees=nees,
        nees_in_band=nees_in,
        clock_offset_rms_ms=clock,
        ranges_used=float(p.ranges_used[:, s, m, i].mean()),
    )


ORDER_SE = 2.0
"""An inequality of acceptance check 4 holds when the paired difference of the runs' mean errors
is at most this many of its standard errors above zero (Monte Carlo tolerance)."""


def _not_above(a: Array, b: Array) -> bool:
    """Whether ``a <= b`` over paired runs within :data:`ORDER_SE` standard errors."""
    d = a - b
    return bool(d.mean() <= ORDER_SE * _se(d))


def ordering(
    p: Pooled, s: int, methods: list[str], vehicles: list[str], nees: dict, band: tuple
) -> dict[str, bool]:
    """Acceptance check 4 per follower (each run's mean error, paired over the runs): central
    <= decentralised <= the better leader-only method (on average), and the decentralised NEES
    at or below the band's upper end; empty when the methods did not all run."""
    if not {"central", "decentralised"} <= set(methods):
        return {}
    col = {m: i for i, m in enumerate(methods)}
    leader_only = [m for m in LEADER_ONLY if m in methods]
    out: dict[str, bool] = {}
    for i, name in enumerate(vehicles[1:], start=1):
        err = {m: p.mean_m[:, s, col[m], i] for m in methods}
        ok = _not_above(err["central"], err["decentralised"])
        if leader_only:
            best = min(leader_only, key=lambda m: err[m].mean())
            ok &= _not_above(err["decentralised"], err[best])
        d = nees["decentralised"][name]
        out[name] = bool(ok and (d is None or d <= band[1]))
    return out


def warnings_of(m: CoopMetrics) -> list[str]:
    """Lines for the reader: a failed acceptance check 4, over-confident methods, lost packets."""
    out = []
    for s in m.settings:
        bad = [name for name, ok in s.ordering.items() if not ok]
        if bad:
            out.append(
                f"{s.label}: central <= decentralised <= leader-only (paired, {ORDER_SE:g} "
                f"standard errors) or decentralised NEES <= {s.nees_band[1]:.3g} fails on "
                f"{', '.join(bad)}"
            )
        for meth, per in s.methods.items():
            over = [
                f"{name} {st.nees:.3g}"
                for name, st in per.items()
                if st.nees is not None and st.nees > s.nees_band[1]
            ]
            if over:
                out.append(
                    f"{s.label}: {LABELS[meth]} is over-confident (NEES above "
                    f"{s.nees_band[1]:.3g}): {', '.join(over)}"
                )
        lost = sum(s.lost.values())
        if s.ranges_scheduled and lost > 0.5 * s.ranges_scheduled:
            out.append(f"{s.label}: more than half the ranges were lost ({lost:.0f} per run)")
    return out


def tables(m: CoopMetrics) -> list[Table]:
    """One table per setting: a row per vehicle and method."""
    out = []
    for s in m.settings:
        rows = []
        for name in m.vehicles:
            for meth in m.methods:
                st = s.methods[meth][name]
                rows.append(
                    [
                        name,
                        LABELS[meth],
                        st.mean_error_m,
                        st.final_error_m,
                        st.rmse_m,
                        st.nees,
                        st.nees_in_band,
                        st.clock_offset_rms_ms,
                        st.ranges_used,
                    ]
                )
        lost = ", ".join(f"{k} {v:.1f}" for k, v in s.lost.items() if v)
        note = (
            f"{m.n_runs} runs of {m.duration_s:g} s. Mean: each run's mean horizontal error; "
            "final: at the end; RMSE over runs and samples every few seconds; NEES (2 dof) "
            f"averaged over runs and samples, 95 % band of the run average "
            f"[{s.nees_band[0]:.2f}, {s.nees_band[1]:.2f}], in band: fraction of samples whose "
            "run average is inside; clock: RMS error of the clock-offset estimate; ranges: fused "
            f"per run. Ranges per run: {s.ranges_produced:.0f} of {s.ranges_scheduled} received"
            + (f" (lost per run: {lost})" if lost else "")
            + ". A dash: the method has no clock."
        )
        if s.ordering:
            verdict = ", ".join(f"{k} {'holds' if ok else 'FAILS'}" for k, ok in s.ordering.items())
            note += (
                " Acceptance 4 (central <= decentralised <= leader-only, paired within "
                f"{ORDER_SE:g} standard errors; decentralised NEES <= the band's upper end): "
                f"{verdict}."
            )
        out.append(
            Table(
                f"Cooperative navigation, {s.label} ({m.n_runs} runs, seed {m.seed})",
                [
                    "vehicle",
                    "method",
                    "mean (m)",
                    "final (m)",
                    "RMSE (m)",
                    "NEES",
                    "in band",
                    "clock (ms)",
                    "ranges",
                ],
                rows,
                digits=3,
                note=note,
                slug="coop-" + re.sub(r"[^a-z0-9]+", "-", s.label.lower()).strip("-"),
            )
        )
    return out


def report_coop(name: str, summary: str, ctx: ReportContext) -> ReportSummary:
    """Write ``metrics.json``, the tables and the figures of a finished batch."""
    scn: CoopScenario = ctx.scenario  # type: ignore[assignment]
    p = Pooled.of(ctx.blocks)
    n = ctx.n_runs
    band = nees_band(2, n)
    vehicles = list(scn.team.names)
    settings = []
    for s, (label, what, value) in enumerate(scn.settings()):
        methods = {
            meth: {
                veh: vehicle_stats(p, s, m, i, meth in CLOCKED, band)
                for i, veh in enumerate(vehicles)
            }
            for m, meth in enumerate(scn.methods)
        }
        settings.append(
            SettingMetrics(
                label=label,
                what=what,
                value=value,
                nees_band=band,
                methods=methods,
                ranges_scheduled=int(p.scheduled[:, s].max(initial=0)),
                ranges_produced=float(p.produced[:, s].mean()),
                lost={c: float(p.lost[:, s, j].mean()) for j, c in enumerate(LOSS_CAUSES) if j},
                ordering=ordering(
                    p,
                    s,
                    list(scn.methods),
                    vehicles,
                    {k: {x: st.nees for x, st in per.items()} for k, per in methods.items()},
                    band,
                ),
            )
        )
    m = CoopMetrics(
        experiment=name,
        n_runs=n,
        seed=ctx.seed,
        duration_s=scn.team.duration_s,
        vehicles=vehicles,
        methods=list(scn.methods),
        settings=settings,
        warnings=[],
    )
    m = m.model_copy(update={"warnings": warnings_of(m)})
    files = [write_metrics(ctx.out_dir, m)]
    tabs = tables(m)
    files += write_tables(ctx.out_dir, tabs, heading=f"{name}: {summary}")
    if scn.report.figures:
        from tasks.coop import figures

        t = curve_ticks(scn) * scn.team.tick_s
        files += figures.against_time(ctx.out_dir / "coop-error-time.png", m, p, t)
        if len(m.settings) > 1:
            files += figures.sensitivity(ctx.out_dir / "coop-sensitivity.png", m)
    text = "".join(t.to_text() for t in tabs)
    text += "".join(f"warning: {w}\n" for w in m.warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))
