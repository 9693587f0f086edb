"""``mission/trn``'s report: metrics.json, the tables (errors per method, check 2, check 4, the
DVL's pings and the TRN's updates), every run's data (Parquet) and the figures (package
docstring)."""

from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np

from tasks.closed_loop.result import MissionRun
from tasks.core.registry import ReportContext, ReportSummary
from tasks.missions.trn.figures import error_figure, plan_figure
from tasks.missions.trn.metrics import (
    FLAT_GRADIENT,
    TrnMetrics,
    dvl_vs_log,
    flat_explanation,
    stack_runs,
    summarise_method,
    trn_verdict,
)
from tasks.missions.trn.parts import EXTRA_COLUMNS
from tasks.missions.trn.run import TrnRunResult, summary_of
from tasks.missions.trn.scenario import LABELS, METHODS, TRN_METHODS, TrnScenario, seabed_text
from tasks.missions.trn.terrain import map_nan_fraction

__all__ = ["TrnMetrics", "report_trn"]


class ReportedExperiment(Protocol):
    """What the report reads of the experiment: its name and summary."""

    name: str
    summary: str


def _mean_stat(results: list[TrnRunResult], key: str) -> float:
    vals = [r.stats[key] for r in results if key in r.stats]
    return float(np.mean(vals)) if vals else 0.0


def _warnings(scn: TrnScenario, counts: dict[str, int], nan_fraction: float) -> list[str]:
    out = []
    pings, upd = counts.get("pings", 0), counts.get("updates", 0)
    no_lock = pings - counts.get("bottom", 0)
    if no_lock:
        out.append(
            f"{no_lock} of {pings} DVL pings after the dive without bottom lock "
            f"({counts.get('water', 0)} water track, {counts.get('none', 0)} none; lock between "
            f"sensors.dvl.min_altitude_m = {scn.sensors.dvl.min_altitude_m:g} and "
            f"sensors.dvl.max_altitude_m = {scn.sensors.dvl.max_altitude_m:g} m with >= "
            f"{scn.sensors.dvl.min_beams} beams): DR-DVL and TRN used the water track plus the "
            "current the log EKF learnt before the dive (or held the last velocity) there"
        )
    for key, name in (("unusable_updates", "TRN-PF"), ("pmf_unusable_updates", "TRN-PMF")):
        bad = counts.get(key, 0)
        if bad:
            out.append(
                f"{name}: {bad} of {upd} TRN updates had no usable beam (no bottom lock, or every "
                "beam off the map or on a hole of it): prediction only"
            )
    if nan_fraction > 0:
        out.append(f"the navigator's map has no data on {100 * nan_fraction:.1f} % of its nodes")
    for key, name in (("pf_reinit", "TRN-PF"), ("pmf_reinit", "TRN-PMF")):
        if counts.get(key, 0):
            out.append(f"{name} diverged and was re-initialised {counts[key]} times")
    return out


def symmetrised(flight: MissionRun) -> MissionRun:
    """The flight with its mission's matrix columns (``<method>_P``, ``trn_q``, shape (T, 2, 2))
    made symmetric bit for bit, ``(P + P^T) / 2`` (rounding only), as the run data requires; the
    metrics read the flight as it was flown."""
    vehicles = {}
    for name, v in flight.vehicles.items():
        ticks = dict(v.ticks)
        for k in EXTRA_COLUMNS:
            c = ticks.get(k)
            if c is not None and c.values.ndim == 3:
                sym = 0.5 * (c.values + np.swapaxes(c.values, 1, 2))
                ticks[k] = dataclasses.replace(c, values=sym)
        vehicles[name] = dataclasses.replace(v, ticks=ticks)
    return dataclasses.replace(flight, vehicles=vehicles)


def report_trn(exp: ReportedExperiment, ctx: ReportContext) -> ReportSummary:
    """metrics.json, tables.md (+ CSV), the run data of every run (Parquet, ``data/``) and the
    figures of a finished batch."""
    from tasks.closed_loop.report import export_runs
    from tasks.core.report import Table, write_metrics, write_tables

    scn: TrnScenario = ctx.scenario  # type: ignore[assignment]
    results: list[TrnRunResult] = sorted((r for b in ctx.blocks for r in b), key=lambda r: r.run)
    settle = scn.trn.settle_s
    methods = {m: summarise_method(results, m, settle) for m in METHODS}
    check2 = dvl_vs_log(results)
    grad = _mean_stat(results, "gradient_rms")
    counts = summary_of(results)
    flat = counts.get("updates", 0) > 0 and grad < FLAT_GRADIENT
    trn = {m: trn_verdict(results, m, settle, flat) for m in TRN_METHODS}
    nan_fraction = map_nan_fraction(scn, ctx.seed)
    b = stack_runs(results, None)
    s = np.asarray(results[0].t_s[: b.shape[1]] >= settle) if results else np.zeros(0, bool)
    failures = [r.failed for r in results if r.failed]
    warnings = _warnings(scn, counts, nan_fraction)
    cur = getattr(scn.current, "speed_m_s", None)
    metrics = TrnMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        steer=scn.navigation.steer,
        relief_std_m=scn.seabed.relief_std_m,
        current_m_s=cur,
        gradient_rms=grad,
        altitude_mean_m=_mean_stat(results, "altitude_mean_m"),
        nees_pf_mean=_mean_stat(results, "nees_pf_mean"),
        methods=methods,
        pcrb_start_m=float(b[:, 0].mean()) if b.size else None,
        pcrb_final_m=float(b[:, -1].mean()) if b.size else None,
        pcrb_rms_settled_m=float(np.sqrt(np.mean(b[:, s] ** 2))) if b.size and s.any() else None,
        dr_dvl_vs_log=check2,
        trn=trn,
        flat_seabed=bool(flat),
        flat_explanation=flat_explanation(results, grad, methods) if flat else None,
        counts=counts,
        map_nan_fraction=nan_fraction,
        failures=failures,
        warnings=warnings,
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    tx = [("usbl transceiver", scn.transceiver_east_m, scn.transceiver_north_m)]
    flights = [symmetrised(r.flight) for r in results if r.flight is not None]
    files += export_runs(ctx.out_dir, exp.name, flights, frame=scn.frame(), points=tx)
    dur = results[0].t_s[-1] if results and len(results[0].t_s) else 0.0
    t1 = Table(
        f"Horizontal error after the dive per method ({ctx.n_runs} runs, {dur:.0f} s without "
        f"USBL, {seabed_text(scn)}, current {cur if cur is not None else '-'} "
        f"m/s; steering on {LABELS[scn.navigation.steer]})",
        [
            "Method",
            "Final mean (m)",
            "Final max (m)",
            "Mean (m)",
            "Max mean (m)",
            "Max (m)",
            f"RMS after {settle:g} s (m)",
        ],
        [
            [
                s_.label,
                s_.final_mean_m,
                s_.final_max_m,
                s_.mean_mean_m,
                s_.max_mean_m,
                s_.max_max_m,
                s_.rms_settled_m,
            ]
            for s_ in methods.values()
        ]
        + [["TRN PCRB", metrics.pcrb_final_m, None, None, None, None, metrics.pcrb_rms_settled_m]],
        digits=2,
        slug="errors",
        note="USBL-EKF is the reference (USBL fixes all along, it does not steer); EKF-log is the "
        "vehicle's log EKF after the dive (the current it learnt before, no fix); the PCRB row "
        "is the bound sqrt(trace) from the true track and the true seabed's gradients.",
    )
    t2 = Table(
        "Check 2: dead reckoning on the DVL against dead reckoning on the log",
        [
            "Runs",
            "DR-DVL better",
            "Final DR-DVL (m)",
            "Final DR-log (m)",
            "Ratio",
            "Mean DR-DVL (m)",
            "Mean DR-log (m)",
            "Ratio (mean)",
        ],
        [
            [
                check2.runs,
                check2.runs_dvl_better,
                check2.final_dvl_m,
                check2.final_log_m,
                check2.final_ratio,
                check2.mean_dvl_m,
                check2.mean_log_m,
                check2.mean_ratio,
            ]
        ],
        digits=2,
        slug="dvl-vs-log",
        note=check2.verdict,
    )
    t3 = Table(
        "Check 4: TRN bounded and within 2x the PCRB",
        [
            "Filter",
            "RMS middle (m)",
            "RMS last (m)",
            "Growth",
            "PCRB growth",
            "Bounded",
            "RMS settled (m)",
            "PCRB RMS (m)",
            "Ratio",
            "Within 2x",
            "/ DR-DVL",
        ],
        [
            [
                LABELS[m],
                v.rms_middle_m,
                v.rms_last_m,
                v.growth,
                v.pcrb_growth,
                v.bounded,
                v.rms_settled_m,
                v.pcrb_rms_settled_m,
                v.pcrb_ratio,
                v.within_2x_pcrb,
                v.dr_dvl_ratio,
            ]
            for m, v in trn.items()
        ],
        digits=2,
        slug="trn-vs-pcrb",
        note=" ".join(v.verdict for v in trn.values())
        + (f" {metrics.flat_explanation}" if flat else ""),
    )
    t4 = Table(
        "DVL pings and TRN updates after the dive (all runs)",
        [
            "Pings",
            "Bottom lock",
            "Water track",
            "None",
            "TRN updates",
            "No usable beam (PF)",
            "No usable beam (PMF)",
            "Beams used / update",
            "Re-inits PF",
            "Re-inits PMF",
        ],
        [
            [
                counts.get("pings", 0),
                counts.get("bottom", 0),
                counts.get("water", 0),
                counts.get("none", 0),
                counts.get("updates", 0),
                counts.get("unusable_updates", 0),
                counts.get("pmf_unusable_updates", 0),
                counts.get("beams_used", 0) / max(1, counts.get("updates", 0)),
                counts.get("pf_reinit", 0),
                counts.get("pmf_reinit", 0),
            ]
        ],
        digits=2,
        slug="pings",
        note=f"Mean true altitude {metrics.altitude_mean_m:.1f} m; RMS seabed gradient at the "
        f"footprints {grad:.3f}; TRN-PF mean NEES {metrics.nees_pf_mean:.2f} (2 if "
        f"consistent); map without data on {100 * nan_fraction:.1f} % of its nodes.",
    )
    tables = [t1, t2, t3, t4]
    if failures:
        tables.append(Table("Failed flights", ["Failure"], [[f] for f in failures], slug="failed"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if scn.report.figures and results and all(len(r.t_s) > 1 for r in results):
        files += error_figure(exp.name, scn, results, ctx.out_dir)
        rec = next((r for r in results if r.track and len(r.track["truth"]) > 1), None)
        if rec is not None:
            files += plan_figure(exp.name, scn, rec, ctx.seed, ctx.out_dir)
    flown = next((r.flight for r in results if r.run == scn.report.record_run), None)
    flown = flown if flown is not None and flown.vehicles else None
    if scn.report.recording and flown is not None and len(flown.lead["t"]) > 1:
        from tasks.closed_loop.recording import mission_scene, record_flights

        files.append(record_flights(ctx.out_dir, exp.name, mission_scene(scn), {"": flown}))
    text = "\n".join(t.to_text() for t in (t1, t2, t3)) + "\n"
    text += f"check 2: {check2.verdict}\n"
    text += "".join(f"check 4: {v.verdict}\n" for v in trn.values())
    if flat:
        text += f"flat seabed: {metrics.flat_explanation}\n"
    text += "".join(f"warning: {w}\n" for w in warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))
