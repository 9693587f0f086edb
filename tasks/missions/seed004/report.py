"""``mission/seed004``'s report: the per-filter table, the CMNF's surrogate-against-physics gap,
the gains and a figure of the recorded run (package docstring)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.recording import RecordingScene, record_flights
from tasks.core.files import atomic_write_bytes
from tasks.core.registry import ReportContext, ReportSummary
from tasks.missions.seed004.metrics import (
    Seed004Metrics,
    Seed004RunResult,
    summarise_filter,
    surrogate_j,
)
from tasks.missions.seed004.scenario import (
    Seed004Scenario,
    beacons_world,
    flown_filters,
    gains_for,
    path_config,
)

if TYPE_CHECKING:
    pass

Array = NDArray[np.float64]


class ReportedExperiment(Protocol):
    """What the report reads of the experiment: its name and summary."""

    name: str
    summary: str


def report_seed004(exp: ReportedExperiment, ctx: ReportContext) -> ReportSummary:
    """The per-filter table, the CMNF's surrogate-vs-physics gap, the gains and a figure."""
    from tasks.closed_loop.report import export_runs
    from tasks.core.report import Table, write_metrics, write_tables

    scn: Seed004Scenario = ctx.scenario  # type: ignore[assignment]
    results: list[Seed004RunResult] = [r for b in ctx.blocks for r in b]
    names = flown_filters(scn)
    summ = {f: summarise_filter(results, f) for f in names}
    files: list[str] = []
    j_sur = j_phys = gap = m_sur = m_phys = m_gap = None
    sur_shift: dict[str, Any] = {}
    if "cmnf" in names:
        gains = gains_for(scn, ctx.seed)
        atomic_write_bytes(ctx.out_dir / "cmnf-gains.npz", gains.to_bytes())
        files.append("cmnf-gains.npz")
        j_sur, m_sur, sur_shift = surrogate_j(scn, ctx.seed, gains)
        j_phys, m_phys = summ["cmnf"].j_bar_m2, summ["cmnf"].j_mean_m2
        if j_sur is not None and j_phys is not None:
            gap, m_gap = j_phys - j_sur, m_phys - m_sur
    failures = [f"{f}: {m}" for r in results for f, m in r.failed.items() if m]
    warnings = []
    for f in names:
        gaps = [(r.run, r.metrics[f]) for r in results if f in r.metrics]
        absent = sum(m.get("absent_pairs", 0) for _, m in gaps)
        missing = sum(m.get("missing_sets", 0) for _, m in gaps)
        if absent:
            warnings.append(
                f"{f}: {absent} bearing pairs absent (beacon overhead, tangent beyond "
                f"doa.max_tangent, out of range or dropped), {missing} filter steps without any "
                "bearing (prediction only)"
            )
        if summ[f].runs_ok < ctx.n_runs:
            warnings.append(
                f"{f}: {ctx.n_runs - summ[f].runs_ok} of {ctx.n_runs} runs failed or have no "
                "data (see failures)"
            )
        if summ[f].shift_none_steps:
            warnings.append(
                f"{f}: {summ[f].shift_none_steps} filter steps without a seabed shift (too few "
                "beams with an echo in both images): the commanded displacement was predicted"
            )
    metrics = Seed004Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        prediction=scn.navigation.prediction,
        filters=summ,
        cmnf_j_bar_surrogate_m2=j_sur,
        cmnf_j_bar_physics_m2=j_phys,
        cmnf_gap_m2=gap,
        cmnf_j_mean_surrogate_m2=m_sur,
        cmnf_j_mean_physics_m2=m_phys,
        cmnf_j_mean_gap_m2=m_gap,
        surrogate_shift=sur_shift,
        cmnf_train_paths=scn.seed004.train_paths,
        failures=failures,
        warnings=warnings,
    )
    files.append(write_metrics(ctx.out_dir, metrics))
    beacons = [(f"beacon_{i}", float(b[0]), float(b[1])) for i, b in enumerate(beacons_world(scn))]
    for f in names:
        flights = [r.flights[f] for r in results if f in r.flights]
        files += export_runs(ctx.out_dir, exp.name, flights, f, scn.frame(), beacons)
    c = scn.seed004
    t = Table(
        f"Path following and estimation per filter ({ctx.n_runs} runs, {c.duration_s:g} s, "
        f"V° = {c.speed_m_s:g} m/s, box-limited eq. 7)",
        [
            "Filter",
            "Runs ok",
            "Mean dist. to path (m)",
            "Max dist. to path (m)",
            "Mean of run max (m)",
            "Est. RMSE (m)",
            "Est. max (m)",
            "J-bar physics (m^2)",
            "Mean J physics (m^2)",
        ],
        [
            [
                f.upper(),
                s.runs_ok,
                s.path_mean_m,
                s.path_max_m,
                s.path_max_mean_m,
                s.est_rmse_m,
                s.est_max_m,
                s.j_bar_m2,
                s.j_mean_m2,
            ]
            for f, s in summ.items()
        ],
        digits=2,
        slug="filters",
        note=(
            f"CMNF J-bar: surrogate {_fmt(j_sur)} m^2, physics {_fmt(j_phys)} m^2, gap "
            f"{_fmt(gap)} m^2; mean J: surrogate {_fmt(m_sur)}, physics {_fmt(m_phys)}, gap "
            f"{_fmt(m_gap)} m^2 (gains from {c.train_paths} surrogate paths, J on "
            f"{c.surrogate_test_paths} fresh ones)."
            if "cmnf" in names
            else "No CMNF flown."
        ),
    )
    tables = [t]
    if scn.navigation.prediction == "seabed":
        tables.append(
            Table(
                "Seabed-sensing prediction: the shift's own error (norm of the shift less the "
                "true move of the reference point, every filter step with a shift, all runs) and "
                "the flights that diverged",
                [
                    "Filter",
                    "Diverged runs",
                    "Steps with a shift",
                    "Steps without",
                    "Beams used",
                    "Median error (m)",
                    "P90 error (m)",
                    "Bias x (m)",
                    "Bias y (m)",
                    "Bias z (m)",
                ],
                [
                    [
                        f.upper(),
                        v.diverged_runs,
                        v.shift_steps,
                        v.shift_none_steps,
                        v.shift_beams_mean,
                        v.shift_err_median_m,
                        v.shift_err_p90_m,
                        *(v.shift_err_bias_m or [None] * 3),
                    ]
                    for f, v in summ.items()
                ],
                digits=2,
                slug="seabed-shift",
                note=(
                    f"Multibeam {scn.multibeam.beams_elevation} x {scn.multibeam.beams_azimuth} "
                    f"beams, range noise {scn.multibeam.range.sigma_m:g} m, Appendix A basis "
                    f"{c.slope_basis}; the two images of a shift are aimed from the hull's "
                    "attitudes at their pings (reading 'turning', exact beam change). On the "
                    "CMNF's surrogate paths: median "
                    f"{_fmt(sur_shift.get('shift_err_median_m'))} m, p90 "
                    f"{_fmt(sur_shift.get('shift_err_p90_m'))} m, bias "
                    f"{[round(v, 2) for v in sur_shift.get('shift_err_bias_m', [])]} m."
                ),
            )
        )
    if failures:
        tables.append(Table("Failed flights", ["Failure"], [[f] for f in failures], slug="failed"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in results if r.run == scn.report.record_run), None)
    if scn.report.figures and rec is not None:
        files += seed004_figure(exp.name, scn, rec, ctx.out_dir)
    if scn.report.recording and rec is not None:
        flown = {f: fl for f, fl in rec.flights.items() if fl.vehicles and len(fl.lead["t"]) > 1}
        if flown:
            files.append(record_flights(ctx.out_dir, exp.name, recording_scene(scn), flown))
    text = t.to_text() + "\n"
    text += "".join(f"warning: {w}\n" for w in warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def recording_scene(scn: Seed004Scenario) -> RecordingScene:
    """What the recording draws of the scene: the seabed, the four beacons and the nominal
    path (:func:`tasks.closed_loop.recording.record_flights`)."""
    from bauv_sim.seabed import generate

    beacons = [(f"beacon {i}", b, (0, 0, 0)) for i, b in enumerate(beacons_world(scn))]
    return RecordingScene(generate(scn.seabed, scn.frame()), beacons, path=path_config(scn).path())


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f}"


def seed004_figure(name: str, scn: Seed004Scenario, rec: Seed004RunResult, out) -> list[str]:
    """Nominal path, beacons and each filter's true track of the recorded run (plan and depth)."""
    from tasks.core import style

    with style.context():
        fig, (ax, az) = style.subplots("page", 3.2, 1, 2)
        nominal = path_config(scn).path()
        b = beacons_world(scn)
        ax.plot(nominal[:, 0], nominal[:, 1], "k--", lw=1.0, label="nominal")
        az.plot(np.arange(len(nominal)) * scn.seed004.dt_s, -nominal[:, 2], "k--", lw=1.0)
        ax.plot(b[:, 0], b[:, 1], "k^", label="beacons")
        for f, m in rec.metrics.items():
            tr = m.get("track")
            if tr is None:
                continue
            ax.plot(tr[:, 0], tr[:, 1], lw=0.8, label=f.upper())
            az.plot(np.arange(len(tr)) * scn.seed004.dt_s, -tr[:, 2], lw=0.8)
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize="small")
        az.set_xlabel("time (s)")
        az.set_ylabel("depth (m)")
        az.invert_yaxis()
        fig.suptitle(f"{name}: run {rec.run}")
        return style.save(fig, out / "paths.png")
