"""``mission/trn``'s figures: error against time per method beside the TRN bound, and the
recorded run's tracks over the navigator's map (package docstring)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tasks.missions.trn.metrics import stack_runs
from tasks.missions.trn.run import TrnRunResult
from tasks.missions.trn.scenario import LABELS, METHODS, TrnScenario, seabed_text
from tasks.missions.trn.terrain import navigator_map


def error_figure(name: str, scn: TrnScenario, results: list[TrnRunResult], out: Path) -> list[str]:
    """RMS over the runs of each method's horizontal error against the time since the dive,
    with the PCRB and twice it (log scale)."""
    from tasks.core import style

    with style.context():
        fig, ax = style.subplots("page", 3.2)
        n = stack_runs(results, METHODS[0]).shape[1]
        t = results[0].t_s[:n]
        for m in METHODS:
            e = stack_runs(results, m)
            ax.plot(t, np.sqrt(np.mean(e**2, axis=0)), **style.line(LABELS[m]))
        b = np.sqrt(np.mean(stack_runs(results, None) ** 2, axis=0))
        ax.plot(t, b, "k-", lw=1.0, label="TRN PCRB")
        ax.plot(t, 2 * b, "k--", lw=0.8, label="2x PCRB")
        ax.set_yscale("log")
        ax.set_xlabel("time since the dive (s)")
        ax.set_ylabel("horizontal error, RMS over runs (m)")
        ax.legend(fontsize="small", ncol=2)
        fig.suptitle(f"{name}: {len(results)} runs, {seabed_text(scn)}")
        return style.save(fig, out / "errors.png")


def plan_figure(name: str, scn: TrnScenario, rec: TrnRunResult, seed: int, out: Path) -> list[str]:
    """The recorded run's true track and every method's, over the navigator's map."""
    from tasks.core import style

    with style.context():
        fig, ax = style.subplots("page", 3.6)
        m = navigator_map(scn, seed)
        tr = rec.track["truth"]
        pad = 30.0
        x0, x1 = tr[:, 0].min() - pad, tr[:, 0].max() + pad
        y0, y1 = tr[:, 1].min() - pad, tr[:, 1].max() + pad
        ix = (m.x_m >= x0) & (m.x_m <= x1)
        iy = (m.y_m >= y0) & (m.y_m <= y1)
        if ix.sum() > 1 and iy.sum() > 1:
            cs = ax.contourf(m.x_m[ix], m.y_m[iy], m.depth_m[np.ix_(iy, ix)], 20, cmap="Greys")
            fig.colorbar(cs, ax=ax, label="map depth (m)")
        ax.plot(tr[:, 0], tr[:, 1], "k-", lw=1.2, label="truth")
        for k in METHODS:
            p = rec.track[k]
            ax.plot(p[:, 0], p[:, 1], **style.line(LABELS[k], lw=0.8))
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize="small", ncol=2)
        fig.suptitle(f"{name}: run {rec.run} after the dive")
        return style.save(fig, out / "plan.png")
