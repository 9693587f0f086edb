"""The figure and the recordings of ``mission/correction``'s recorded run."""

from __future__ import annotations

import numpy as np

from tasks.closed_loop.report import circle
from tasks.closed_loop.result import MissionRun
from tasks.missions.correction.run import CorrectionRunResult
from tasks.missions.correction.scenario import CorrectionScenario


def correction_figure(
    name: str, scn: CorrectionScenario, rec: CorrectionRunResult, out
) -> list[str]:
    """Tracks of the recorded run: truth, the DR tracks, GPS fixes, numbered way-points, the true
    and the estimated current (PNG and PDF, project style)."""
    from tasks.core import style

    with style.context():
        return _draw_tracks(name, scn, rec, out, style)


def _draw_tracks(name: str, scn: CorrectionScenario, rec: CorrectionRunResult, out, style):
    from tasks.closed_loop.report import current_arrow

    fig, axs = style.subplots("page", 4.0, 1, 2)
    for ax, law in zip(axs, ("direct", "compensated"), strict=True):
        f = rec.flights[law]
        if not f.vehicles:
            continue
        a = f.lead
        ax.plot(a["truth_pos"][:, 0], a["truth_pos"][:, 1], **style.line("truth", lw=1.2))
        ax.plot(
            a["dr_uncorrected"][:, 0],
            a["dr_uncorrected"][:, 1],
            **style.line("DR", label="DR without CP"),
        )
        ax.plot(
            a["dr_corrected"][:, 0],
            a["dr_corrected"][:, 1],
            **style.line(
                scn.correction.procedure.upper(),
                label=f"DR after {scn.correction.procedure.upper()}",
            ),
        )
        gps = a.fixes["gps"]["position"].values if "gps" in a.fixes else np.zeros((0, 3))
        if len(gps):
            ax.plot(gps[:, 0], gps[:, 1], **style.line("GPS", label="GPS fixes", ms=5, zorder=5))
        wcol = style.color("waypoint")
        for i, (e, n, radius) in enumerate(rec.waypoints[law]):
            c = circle(e, n, radius)
            ax.plot(c[:, 0], c[:, 1], color=wcol, lw=0.8, label="way-point" if i == 0 else "_")
            ax.annotate(
                f"WP{i}",
                (e, n),
                ha="center",
                va="center",
                color=wcol,
                fontsize=6.5,
                fontweight="bold",
            )
        true_c = a["truth_current"][:, :2].mean(axis=0)
        est = a["cp_current"][~np.isnan(a["cp_current"][:, 0])]
        current_arrow(ax, true_c, "mean true current", style.color("current"))
        if len(est):
            current_arrow(ax, est.mean(axis=0), "estimated current", style.color("EKF"), "--", 1)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(style.label("east", "m"))
        ax.set_ylabel(style.label("north", "m"))
        style.title(ax, f"leg 3 on the {law} course")
    style.panel_letters(axs)
    fig.suptitle(f"Seed 001 on the vehicle (CP from surfacings), run {rec.run}")
    style.figure_legend(fig, axs, ncol=4)
    return style.save(fig, out / "tracks.png")


def current_figure(name: str, scn: CorrectionScenario, rec: CorrectionRunResult, out) -> list[str]:
    """The current along the recorded run's compensated flight: the true current at the vehicle
    and the correction's estimate (east and north against time; legs 1-2 carry the estimate made
    when leg 2 closed, :func:`~tasks.missions.correction.run.current_along_track`), and their
    difference's magnitude (PNG and PDF, project style)."""
    from tasks.core import style

    with style.context():
        return _draw_current(scn, rec, out, style)


def _draw_current(scn: CorrectionScenario, rec: CorrectionRunResult, out, style):
    v = rec.flights["compensated"].lead
    t = v["t"]
    true = np.asarray(v["truth_current"], dtype=float)[:, :2]
    est = np.array(v["cp_current"], dtype=float)
    t3 = v.outcome["leg3_start_s"]
    c = v.outcome["current_estimate_m_s"]
    if c is not None and t3 is not None:
        est[t < t3] = np.asarray(c, dtype=float)
    p = scn.correction.procedure.upper()
    fig, axs = style.subplots("page", 5.0, 3, 1, sharex=True)
    for ax, i, comp in zip(axs[:2], (0, 1), ("east", "north"), strict=True):
        ax.plot(t, true[:, i], **style.line("truth", label="true current at the vehicle"))
        ax.plot(t, est[:, i], **style.line(p, label=f"{p} estimate"))
        ax.set_ylabel(style.label(f"current {comp}", "m/s"))
    err = np.linalg.norm(est - true, axis=1)
    axs[2].plot(t, err, **style.line(p, label="|estimate - true|", ls="--"))
    axs[2].set_ylabel(style.label("difference", "m/s"))
    axs[2].set_xlabel(style.label("time", "s"))
    if t3 is not None:
        for ax in axs:
            ax.axvline(t3, color="0.5", lw=0.6, ls=":")
        style.title(axs[0], f"{scn.current.kind} current; leg 3 from {t3:.0f} s")
    style.panel_letters(axs)
    fig.suptitle(f"Current along the track, run {rec.run}")
    style.figure_legend(fig, axs, ncol=3)
    return style.save(fig, out / "current-along-track.png")


def record_correction(
    name: str, scn: CorrectionScenario, flights: dict[str, MissionRun], out
) -> list[str]:
    """The recording of the recorded run: both flights (leg 3 on the compensated and on the
    direct course) in one file, each under its own subtree (:func:`tasks.closed_loop.recording.
    record_flights`): the DRNS tracks without and after the correction, the baseline's, the
    EKF's, the GPS fixes, the correction's current estimate beside the true current."""
    from tasks.closed_loop.recording import mission_scene, record_flights

    flown = {law: f for law, f in flights.items() if f.vehicles}
    return [record_flights(out, name, mission_scene(scn), flown)]
