"""Figures of ``paper-001/replica`` (PNG and PDF, project style): the example missions' tracks,
leg-3 courses and the DR error along leg 3."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from tasks.paper001.run import MissionBlock
    from tasks.paper001.scenario import Paper001Scenario


def replica_figures(out_dir: Path, block: MissionBlock, scenario: Paper001Scenario) -> list[str]:
    """Tracks, leg-3 courses and the DR error along leg 3 (PNG and PDF, project style)."""
    from tasks.core import style

    with style.context():
        return _draw(out_dir, block, scenario, style)


def _draw(out_dir: Path, block: MissionBlock, scenario: Paper001Scenario, style) -> list[str]:
    files: list[str] = []
    T = scenario.world.leg_duration_s
    for tr in block.tracks:
        fig, ax = style.subplots("page", 4.2)
        truth = np.concatenate(tr["truth"])
        ax.plot(truth[:, 0], truth[:, 1], "k-", lw=1.8, label="truth")
        fixes = np.array([tr["truth"][0][0], tr["truth"][0][-1], tr["truth"][1][-1]])
        ax.plot(
            fixes[:, 0],
            fixes[:, 1],
            "o",
            ms=8,
            mfc="none",
            mec=style.color("GPS"),
            mew=2,
            label="GPS fixes",
        )
        styles = {
            "nocp": (style.color("DR"), "uncorrected DR (ends at way-point 3)"),
            "cp": (style.color(tr["procedure"].upper()), f"{tr['procedure'].upper()}-corrected DR"),
            "baseline": (style.color("baseline"), "baseline-corrected DR"),
        }
        for kind, (col, lab) in styles.items():
            p = tr["dr"][kind]
            ax.plot(p[:, 0], p[:, 1], "--", color=col, lw=1.5, label=lab)
            ax.plot(p[-1, 0], p[-1, 1], "x", color=col, ms=8)
        ax.plot(tr["truth"][2][-1, 0], tr["truth"][2][-1, 1], "ks", ms=6)
        wp = tr["waypoint3"]
        ax.plot(wp[0], wp[1], "*", color=style.color("waypoint"), ms=9, label="way-point 3")
        # current vectors in an inset (m/s, from a common origin)
        ins = ax.inset_axes((1.06, 0.0, 0.38, 0.38))
        vecs = (
            (tr["current_true"], "k", 6.0, 0.35, "true mean current, leg 3"),
            (tr["current_baseline"], style.color("baseline"), 2.0, 1.0, "baseline estimate"),
            (
                tr["current_est"],
                style.color(tr["procedure"].upper()),
                2.0,
                1.0,
                f"{tr['procedure'].upper()} estimate",
            ),
        )
        lim = 1.25 * max(float(np.hypot(*v)) for v, *_ in vecs) + 1e-3
        for vec, col, lw, alpha, lab in vecs:
            x, y = float(vec[0]), float(vec[1])
            if lw > 3:  # the truth: a wide band with a dot at its tip, under the estimates
                ins.plot([0, x], [0, y], "-", color=col, lw=lw, alpha=alpha, solid_capstyle="butt")
                ins.plot([x], [y], "o", color=col, alpha=alpha, ms=lw)
            else:
                ins.quiver(
                    0, 0, x, y, angles="xy", scale_units="xy", scale=1.0, color=col, width=0.012
                )
            ax.plot([], [], "-", color=col, lw=lw, alpha=alpha, label=f"current: {lab}")
        ins.set_xlim(-lim, lim)
        ins.set_ylim(-lim, lim)
        ins.set_aspect("equal")
        ins.axhline(0, color="0.8", lw=0.5)
        ins.axvline(0, color="0.8", lw=0.5)
        ins.tick_params(labelsize=6)
        ins.set_title("current (m/s)", fontsize=7)
        vg, vc, b = tr["cell"]
        ax.set_title(
            f"Seed 001 {tr['procedure'].upper()} mission {tr['run']}: |Vg|={vg:g} m/s, "
            f"|Vc|={vc:g} m/s, $\\beta$={b:g}°\ncourses "
            f"{', '.join(f'{c:.0f}' for c in tr['nu_deg'])} deg; DR restarted at each fix"
        )
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        name = f"tracks-{tr['procedure']}-mission{tr['run']}.png"
        files += style.save(fig, out_dir / name)

        # Table 3: direct vs compensated leg 3
        fig, ax = style.subplots("column", 3.4)
        start = tr["truth"][2][0]
        ax.plot(
            [start[0], wp[0]],
            [start[1], wp[1]],
            ":",
            color=style.color("waypoint"),
            lw=2,
            label=f"desired track $\\nu$ = {tr['nu_deg'][2]:.0f}°",
        )
        ax.plot(
            tr["truth"][2][:, 0],
            tr["truth"][2][:, 1],
            "-",
            color=style.color("DR"),
            label="steering $\\nu$ (without CP)",
        )
        ax.plot(
            tr["truth_compensated"][:, 0],
            tr["truth_compensated"][:, 1],
            "-",
            color=style.color(tr["procedure"].upper()),
            label=f"steering eq. 22-26 with {tr['procedure'].upper()} "
            f"($\\alpha$ = {tr['alpha3_compensated_deg']:.1f}°)",
        )
        ax.plot(
            tr["truth_compensated_baseline"][:, 0],
            tr["truth_compensated_baseline"][:, 1],
            "-",
            color=style.color("baseline"),
            label="steering eq. 22-26 with baseline current",
        )
        ax.plot(wp[0], wp[1], "*", color=style.color("waypoint"), ms=9)
        ax.set_title(
            f"Seed 001 Table 3, {tr['procedure'].upper()} mission {tr['run']}: true leg-3 tracks\n"
            f"(each leg lasts {T:g} s; a faster track runs past the way-point)"
        )
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        # below the axes, one entry a row: inside, it hid the end of the baseline's track
        style.figure_legend(fig, [ax], ncol=1, fontsize=8)
        name = f"course-{tr['procedure']}-mission{tr['run']}.png"
        files += style.save(fig, out_dir / name)

    # mean DR error along leg 3, figure cell
    fig_cell = tuple(scenario.report.figure_cell)
    if fig_cell in block.cells:
        ci = block.cells.index(fig_cell)
        fig, ax = style.subplots("page", 3.0)
        t = np.linspace(0.0, T, scenario.world.samples_per_leg + 1)
        d = block.data
        for key, procs, col, lab in (
            ("error_curve_nocp_m", [0, 1], style.color("DR"), "uncorrected DR"),
            ("error_curve_baseline_m", [0, 1], style.color("baseline"), "baseline"),
            ("error_curve_cp_m", [0], style.color("CP1"), "CP1"),
            ("error_curve_cp_m", [1], style.color("CP2"), "CP2"),
        ):
            curves = d[key][:, ci, procs].reshape(-1, t.size)[:, 1:]  # t > 0: log axis
            ax.plot(
                t[1:],
                curves.mean(axis=0),
                color=col,
                lw=1.3,
                ls="-." if lab == "baseline" else "-",
                label=f"{lab} (mean)",
            )
            ax.fill_between(
                t[1:],
                np.percentile(curves, 10, axis=0),
                np.percentile(curves, 90, axis=0),
                color=col,
                alpha=0.12,
            )
        vg, vc, b = fig_cell
        ax.set_title(
            f"Seed 001: DR error on leg 3, after the correction\n|Vg| = {vg:g} m/s, "
            f"|Vc| = {vc:g} m/s, $\\beta$ = {b:g}°; {len(block.runs)} missions, mean and "
            "10-90 % band",
            loc="left",
        )
        ax.set_yscale("log")  # the corrected DR's metres beside the uncorrected tens of metres
        style.log_ticks(ax)
        ax.set_xlabel("time since the fix at way-point 2 (s)")
        ax.set_ylabel("|DR - truth| (m)")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
        name = "error-along-leg3.png"
        files += style.save(fig, out_dir / name)
    return files
