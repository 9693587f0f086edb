"""The report of seed 004's kinematic experiments: the blocks' sums merged, the metrics (J-bar
beside the paper's Table 1 and the PCRB level), the claims, the tables, the CMNF gains saved and
the figures (:mod:`tasks.paper004.figures`)."""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from nav.bearings.cmnf import CmnfGains
from nav.bearings.pcrb import pcrb
from tasks.core.files import atomic_write_bytes
from tasks.core.registry import (
    ReportContext,
    ReportSummary,
)
from tasks.core.report import Table, write_metrics, write_tables
from tasks.paper004.published import PAPER_ROW1, PAPER_ROW2
from tasks.paper004.scenario import Paper004Scenario, cases, setting, steep_beacons
from tasks.paper004.sim import FILTERS, LoopSums

Array = NDArray[np.float64]


class ReportedExperiment(Protocol):
    """What the report reads of the experiment: its name, summary and kind."""

    name: str
    summary: str
    kind: str


# ----------------------------------------------------------------------------------------------
# Metrics


class FilterResult(BaseModel):
    """One filter in one case."""

    filter: str
    j_bar_m2: float | None = Field(description="max_k E||X°_k - X_k||^2 (J-bar), m^2")
    k_at_max: int | None
    j_final_m2: float | None = Field(description="J at k = N, m^2")
    pcrb_level_m2: float | None = Field(
        description="3 + max_k trace(PCRB_k) on this filter's paths: J-bar's bound, m^2"
    )
    mse_max_m2: float | None = Field(description="max_k E||X_k - X^_k||^2, m^2")
    stated_to_actual: float | None = Field(
        description="max_k of the filter's stated error variance (trace) over the actual one"
    )
    diverged_paths: int
    absent_pairs: int
    worse_than_prediction: list[int] = Field(
        default_factory=list,
        description="steps k where on the test paths E||X_k - X^_k||^2 exceeds the "
        "prediction's E||X_k - X~_k||^2: the correction made the estimate worse (for the "
        "CMNF: gains that do not generalise beyond their training paths)",
    )
    paper_m2: float | None = None
    ratio_to_paper: float | None = None


class ShiftError(BaseModel):
    """The seabed shift estimate's own error ``dX^ - (X_{k+1} - X_k)`` on one filter's paths
    (over the shifts produced), the steps whose shift was not produced (too few beams with an
    echo in both images: the commanded displacement stood in) and the beams used per shift."""

    filter: str
    shifts: int
    median_m: float | None
    p90_m: float | None
    bias_m: list[float] | None
    not_produced: int = 0
    beams_mean: float | None = None


class CaseResult(BaseModel):
    """One case of the batch."""

    label: str
    bearing_sigma_deg: float
    initial_variance_m2: float
    prediction: str = "system"
    paths: int
    filters: list[FilterResult]
    spread: float | None = Field(description="(max - min) / min of the three J-bars")
    shift_error: list[ShiftError] = Field(default_factory=list)
    cmnf_clipped_values: int | None = Field(
        None,
        description="values of the CMNF's basic correction clipped in training, over all steps "
        "and features (filters.clip_sigmas; nav.bearings.cmnf.clip_bounds)",
    )
    cmnf_top_share: float | None = Field(
        None,
        description="largest share one training path had in the sum of squares of one feature "
        "of the (clipped) basic correction at one step: near 1 when one path sets a moment",
    )


class Paper004Metrics(BaseModel):
    """metrics.json of ``paper-004/*``."""

    experiment: str
    seed: int
    n_runs: int
    train_paths: int
    cases: list[CaseResult]
    claims: dict[str, bool]
    ekf_starts_to_lose_m2: float | None = Field(
        None, description="near-beacon: the smallest initial variance where the EKF loses"
    )
    warnings: list[str]


def _f(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def _merge(ctx: ReportContext) -> tuple[tuple[str, ...], list[LoopSums], dict, dict]:
    labels: tuple[str, ...] | None = None
    tot: list[LoopSums] = []
    gains: dict = {}
    samples: dict = {}
    for b in ctx.blocks:
        if labels is None:
            labels = b.labels
            tot = [
                LoopSums(
                    **{
                        k: np.array(getattr(s, k))
                        for k in LoopSums.__dataclass_fields__
                        if k != "samples"
                    }
                )
                for s in b.sums
            ]
        elif b.labels != labels:
            raise ValueError("blocks computed different cases")
        else:
            for t, s in zip(tot, b.sums, strict=True):
                for k in LoopSums.__dataclass_fields__:
                    if k != "samples":
                        setattr(t, k, getattr(t, k) + getattr(s, k))
        for lab, s in zip(labels, b.sums, strict=True):
            for run, d in s.samples.items():
                samples.setdefault(lab, {})[run] = d
        gains.update(b.gains)
    if labels is None:
        raise ValueError("no blocks to report")
    return labels, tot, gains, samples


def filter_result(
    name: str, fi: int, s: LoopSums, s_w: Array, s_0: Array, paper: float | None
) -> FilterResult:
    """Reduce one filter's sums (see :class:`FilterResult`)."""
    cnt = s.count[fi]
    ok = cnt > 0
    safe = np.where(ok, cnt, 1.0)
    J = np.where(ok, s.j[fi] / safe, np.nan)
    mse = np.where(ok, s.err2[fi].sum(1) / safe, np.nan)
    stated = np.where(ok, s.stated[fi].sum(1) / safe, np.nan)
    info = s.info[fi] / safe[:, None, None]
    if ok.all():
        bound = pcrb(np.linalg.inv(s_0), s_w, info[1:])
        level = float(np.trace(s_w) + np.max(np.trace(bound[:-1], axis1=1, axis2=2)))
    else:
        level = float("nan")
    jbar = float(np.nanmax(J)) if ok.any() else float("nan")
    ratio = stated[1:] / mse[1:]
    pred = np.where(ok, s.pred_err2[fi] / safe, np.nan) if s.pred_err2.size else None
    worse = [] if pred is None else [int(k) for k in np.flatnonzero(mse[1:] > pred[1:]) + 1]
    return FilterResult(
        filter=name,
        j_bar_m2=_f(jbar),
        k_at_max=int(np.nanargmax(J)) if ok.any() else None,
        j_final_m2=_f(float(J[-1])),
        pcrb_level_m2=_f(level),
        mse_max_m2=_f(float(np.nanmax(mse))) if ok.any() else None,
        stated_to_actual=_f(float(np.nanmax(ratio))) if ok.any() else None,
        diverged_paths=int(s.diverged[fi]),
        absent_pairs=int(s.absent[fi].sum()),
        worse_than_prediction=worse,
        paper_m2=paper,
        ratio_to_paper=_f(jbar / paper) if paper else None,
    )


def _shift_errors(s: LoopSums) -> list[ShiftError]:
    from tasks.paper004.sim import SHIFT_BIN_M

    out = []
    for fi, name in enumerate(FILTERS):
        n = int(s.shift_n[fi])
        none = int(s.shift_none[fi])
        beams = float(s.shift_beams[fi] / (n + none)) if n + none else None
        if n == 0:
            out.append(
                ShiftError(
                    filter=name,
                    shifts=0,
                    median_m=None,
                    p90_m=None,
                    bias_m=None,
                    not_produced=none,
                    beams_mean=beams,
                )
            )
            continue
        c = np.cumsum(s.shift_hist[fi]) / s.shift_hist[fi].sum()
        med = (np.searchsorted(c, 0.5) + 0.5) * SHIFT_BIN_M
        p90 = (np.searchsorted(c, 0.9) + 0.5) * SHIFT_BIN_M
        out.append(
            ShiftError(
                filter=name,
                shifts=n,
                median_m=float(med),
                p90_m=float(p90),
                bias_m=[float(v) for v in s.shift_err[fi] / n],
                not_produced=none,
                beams_mean=beams,
            )
        )
    return out


def report_paper004(exp: ReportedExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables, figures and metrics of a seed 004 batch."""
    scn: Paper004Scenario = ctx.scenario  # type: ignore[assignment]
    _labels, tot, gains, samples = _merge(ctx)
    cs = cases(scn)
    results = []
    warnings: list[str] = []
    for c, s in zip(cs, tot, strict=True):
        st = setting(scn, c)
        paper_row = PAPER_ROW1 if exp.kind == "table-1" and c.prediction == "system" else {}
        frs = [
            filter_result(
                name,
                fi,
                s,
                st.noise.s_w,
                st.noise.s_0,
                paper_row.get(name) if math.isclose(c.bearing_sigma_deg, 1.0) else None,
            )
            for fi, name in enumerate(FILTERS)
        ]
        if c.prediction != "system" and exp.kind == "seabed":
            for f in frs:
                f.paper_m2 = PAPER_ROW2[f.filter]
                f.ratio_to_paper = (
                    _f(f.j_bar_m2 / f.paper_m2) if f.paper_m2 and f.j_bar_m2 else None
                )
        js = [f.j_bar_m2 for f in frs if f.j_bar_m2 is not None]
        spread = (max(js) - min(js)) / min(js) if len(js) == len(frs) else None
        results.append(
            CaseResult(
                label=c.label,
                bearing_sigma_deg=c.bearing_sigma_deg,
                initial_variance_m2=c.initial_variance_m2,
                paths=ctx.n_runs,
                filters=frs,
                spread=spread,
                prediction=c.prediction,
                shift_error=_shift_errors(s) if c.prediction != "system" else [],
                cmnf_clipped_values=gains.get(c.label, {}).get("clipped"),
                cmnf_top_share=gains.get(c.label, {}).get("top_share"),
            )
        )
        cm = frs[FILTERS.index("CMNF")]
        if cm.worse_than_prediction:
            k = cm.worse_than_prediction[0]
            warnings.append(
                f"{c.label}: CMNF: on the test paths its correction made the estimate worse than "
                f"its own prediction at {len(cm.worse_than_prediction)} step(s) from k = {k}: its "
                f"gains, trained on {st.train_paths} paths (filters.clip_sigmas = "
                f"{scn.filters.clip_sigmas:g}), do not generalise; train on more paths"
            )
        for f in frs:
            if f.diverged_paths:
                warnings.append(
                    f"{c.label}: {f.filter} diverged (non-finite estimate) on {f.diverged_paths} "
                    f"of {ctx.n_runs} paths; they left the statistics"
                )
            if f.absent_pairs:
                warnings.append(
                    f"{c.label}: {f.filter}: {f.absent_pairs} bearing pairs not produced (beacon "
                    "straight above/below the vehicle, or |tan phi| too large)"
                )
        beams = scn.multibeam.beams_elevation * scn.multibeam.beams_azimuth
        for e in results[-1].shift_error:
            if e.not_produced:
                warnings.append(
                    f"{c.label}: {e.filter}: {e.not_produced} of {e.not_produced + e.shifts} "
                    "seabed shifts not produced (too few beams with an echo in both images: "
                    "seabed beyond multibeam.max_range_m, or dropouts); the commanded "
                    "displacement stood in"
                )
            if e.beams_mean is not None and e.beams_mean < 0.9 * beams:
                warnings.append(
                    f"{c.label}: {e.filter}: {e.beams_mean:.1f} of {beams} beams per shift had an "
                    "echo in both images on average"
                )
    for i, el in steep_beacons(scn):
        warnings.append(
            f"beacon {i} comes {el:.1f} deg above the nominal path (> "
            f"{scn.report.steep_elevation_deg:g} deg): its bearings are ill-conditioned there"
        )
    claims, loses = _claims(exp, scn, results)
    metrics = Paper004Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        train_paths=scn.filters.train_paths,
        cases=results,
        claims=claims,
        ekf_starts_to_lose_m2=loses,
        warnings=warnings,
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    tables = _tables(exp, scn, metrics)
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    files += _save_gains(ctx, scn, cs, gains)
    if scn.report.figures:
        from tasks.paper004 import figures

        settings = [setting(scn, c) for c in cs]
        files += figures.draw(ctx.out_dir, exp.kind, scn, cs, settings, tot, samples)
    text = tables[0].to_text()
    if warnings:
        text += "\n" + "\n".join(f"warning: {w}" for w in warnings) + "\n"
    text += f"\nwrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _claims(
    exp: ReportedExperiment, scn: Paper004Scenario, results: list[CaseResult]
) -> tuple[dict[str, bool], float | None]:
    claims: dict[str, bool] = {}
    loses = None
    for r in results:
        j = {f.filter: f.j_bar_m2 for f in r.filters}
        if exp.kind == "table-1":
            claims[f"{r.label}: J-bars within 10 % of each other"] = (
                r.spread is not None and r.spread <= 0.10
            )
            lvl = [f.pcrb_level_m2 for f in r.filters]
            claims[f"{r.label}: every J-bar at or above the PCRB level less 2 %"] = all(
                f.j_bar_m2 is not None
                and f.pcrb_level_m2 is not None
                and f.j_bar_m2 >= 0.98 * f.pcrb_level_m2
                for f in r.filters
            ) and all(v is not None for v in lvl)
            if math.isclose(r.bearing_sigma_deg, 1.0):
                claims[f"{r.label}: every J-bar within 25 % of the paper"] = all(
                    f.ratio_to_paper is not None and abs(f.ratio_to_paper - 1) <= 0.25
                    for f in r.filters
                )
        elif exp.kind == "seabed":
            cm = j["CMNF"]
            claims[f"{r.label}: CMNF J-bar finite"] = cm is not None
            for f in ("UPMF", "EKF"):
                v = j[f]
                claims[f"{r.label}: {f} fails to follow the path (J-bar >= 3 x the CMNF's)"] = (
                    cm is not None and (v is None or v >= 3 * cm)
                )
        else:
            ekf, others = j["EKF"], [j["UPMF"], j["CMNF"]]
            if ekf is None or any(o is None for o in others):
                continue
            if loses is None and ekf > scn.report.loses_ratio * min(others):
                loses = r.initial_variance_m2
            if math.isclose(r.initial_variance_m2, scn.report.documented_variance_m2):
                claims[f"{r.label}: EKF J-bar at least twice the UPMF's and the CMNF's"] = all(
                    ekf >= 2 * o for o in others
                )
    return claims, loses


def _tables(exp: ReportedExperiment, scn: Paper004Scenario, m: Paper004Metrics) -> list[Table]:
    out = []
    if exp.kind == "table-1":
        rows = []
        for r in m.cases:
            for f in r.filters:
                rows.append(
                    [
                        f"{r.bearing_sigma_deg:g} deg",
                        f.filter,
                        f.j_bar_m2,
                        f.pcrb_level_m2,
                        f.k_at_max,
                        f.j_final_m2,
                        f.paper_m2 if math.isclose(r.bearing_sigma_deg, 1.0) else None,
                        f.diverged_paths,
                    ]
                )
        out.append(
            Table(
                f"Table 1, row 1 (prediction by virtue of the system; {m.n_runs} test paths, "
                f"{m.train_paths} CMNF training paths)",
                [
                    "bearing sigma",
                    "filter",
                    "J-bar (m^2)",
                    "PCRB level (m^2)",
                    "k at max",
                    "J at k = N (m^2)",
                    "paper (m^2)",
                    "diverged",
                ],
                rows,
                digits=2,
                note="The paper states tan^2(0.5 deg) bearing noise; its values are beside the "
                "tan(1 deg) rows, which reproduce them (seed README). Row 2 (seabed-sensing "
                "prediction, paper 27.25 / - / -) is paper-004/table-1-seabed.",
            )
        )
    elif exp.kind == "seabed":
        rows = []
        for r in m.cases:
            cm = next(f for f in r.filters if f.filter == "CMNF").j_bar_m2
            for f in r.filters:
                fails = f.filter != "CMNF" and (
                    f.j_bar_m2 is None or (cm is not None and f.j_bar_m2 >= 3 * cm)
                )
                verdict = (
                    f"fails to follow ({f.j_bar_m2 / cm:.0f} x CMNF)"
                    if fails and f.j_bar_m2 is not None and cm
                    else ("diverged" if f.j_bar_m2 is None else "follows")
                )
                rows.append(
                    [
                        r.prediction.removeprefix("seabed-"),
                        f.filter,
                        f.j_bar_m2,
                        f.pcrb_level_m2,
                        f.paper_m2,
                        verdict,
                        f.diverged_paths,
                    ]
                )
        out.append(
            Table(
                f"Table 1, row 2 (prediction from seabed-sensing DR, eq. 15; {m.n_runs} test "
                f"paths, {m.train_paths} CMNF training paths, bearing "
                f"{scn.sweep.bearing_sigma_deg[0]:g} deg)",
                [
                    "beam attitude",
                    "filter",
                    "J-bar (m^2)",
                    "PCRB level (m^2)",
                    "paper (m^2)",
                    "verdict",
                    "diverged",
                ],
                rows,
                digits=2,
                note="The paper's dashes: EKF and UPMF fail. 'Fails to follow': J-bar at least "
                "3 x the CMNF's. The PCRB level is that of the prediction by virtue of the "
                "system (S^W), which the seabed shift does not reach.",
            )
        )
        rows = []
        for r in m.cases:
            for e in r.shift_error:
                rows.append(
                    [
                        r.prediction.removeprefix("seabed-"),
                        e.filter,
                        e.shifts,
                        e.median_m,
                        e.p90_m,
                        *(e.bias_m or [None] * 3),
                    ]
                )
        out.append(
            Table(
                "Seabed shift estimate's own error (dX^ - true move), on each filter's paths",
                [
                    "beam attitude",
                    "paths of",
                    "shifts",
                    "median (m)",
                    "p90 (m)",
                    "bias x (m)",
                    "bias y (m)",
                    "bias z (m)",
                ],
                rows,
                digits=2,
            )
        )
    else:
        rows = []
        for r in m.cases:
            j = {f.filter: f for f in r.filters}
            rows.append(
                [
                    r.initial_variance_m2,
                    j["CMNF"].j_bar_m2,
                    j["UPMF"].j_bar_m2,
                    j["EKF"].j_bar_m2,
                    j["EKF"].pcrb_level_m2,
                    (j["EKF"].j_bar_m2 / min(j["UPMF"].j_bar_m2, j["CMNF"].j_bar_m2))
                    if None not in (j["EKF"].j_bar_m2, j["UPMF"].j_bar_m2, j["CMNF"].j_bar_m2)
                    else None,
                    j["EKF"].diverged_paths,
                ]
            )
        loses = m.ekf_starts_to_lose_m2
        out.append(
            Table(
                f"Near-beacon case (beacon 4 at (-5, -5, 0), {scn.path.duration_s:g} s; "
                f"{m.n_runs} paths): J-bar against the initial spread S_0 = s I",
                ["s (m^2)", "CMNF", "UPMF", "EKF", "PCRB level", "EKF / best", "EKF diverged"],
                rows,
                digits=2,
                note=(
                    f"The EKF starts to lose (J-bar > {scn.report.loses_ratio:g} x the best) at "
                    f"s = {loses:g} m^2."
                    if loses is not None
                    else "The EKF does not lose at any spread of the sweep."
                )
                + f" Documented breakdown case: s = {scn.report.documented_variance_m2:g} m^2.",
            )
        )
    rows = []
    for r in m.cases:
        for f in r.filters:
            rows.append([r.label, f.filter, f.mse_max_m2, f.stated_to_actual, f.absent_pairs])
    out.append(
        Table(
            "Stated against actual accuracy",
            ["case", "filter", "max E|X - X^|^2 (m^2)", "max stated / actual", "absent pairs"],
            rows,
            digits=3,
        )
    )
    return out


def _save_gains(ctx: ReportContext, scn: Paper004Scenario, cs, gains: dict) -> list[str]:
    files = []
    if not gains:
        return files
    for c in cs:
        g = gains.get(c.label)
        if g is None:
            continue
        s = setting(scn, c)
        arrays = {k: v for k, v in g.items() if k not in ("clipped", "top_share")}
        cg = CmnfGains(
            **arrays,
            info={
                "setting": s.key(),
                "seed": ctx.seed,
                "correction": s.correction,
                "floor": s.floor,
                "clip_sigmas": s.clip_sigmas,
                "paths": s.train_paths,
                "clipped": g.get("clipped", 0),
                "top_share": g.get("top_share", 0.0),
            },
        )
        rel = f"gains/gains-{c.label}.npz"
        atomic_write_bytes(ctx.out_dir / rel, cg.to_bytes())
        files.append(rel)
    return files
