"""Figures of ``coop/team`` and ``coop/sensitivity`` in the project style
(:mod:`tasks.core.style`): each vehicle's RMS error against time per method, and the followers'
mean error against each sensitivity setting."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tasks.coop.scenario import LABELS
from tasks.core import style

if TYPE_CHECKING:
    from tasks.coop.report import CoopMetrics, Pooled

Array = NDArray[np.float64]

SWEEPS = {
    "drift_ppm": ("clock drift", "drift sigma", "ppm"),
    "sound_speed_m_s": ("sound-speed mismatch", "true speed, nominal 1500", "m/s"),
    "source_level_db": ("packet loss", "source level, sonar equation", "dB re 1 uPa"),
}
"""Each sensitivity list's panel title, axis label and unit."""


@style.styled
def against_time(path: Path, m: CoopMetrics, p: Pooled, times_s: Array) -> list[str]:
    """RMS horizontal error over the runs against time, one panel per vehicle, every method, the
    base setting.

    Returns:
        The files written (PNG and PDF), relative to the PNG's folder.
    """
    v = len(m.vehicles)
    fig, axes = style.subplots("page", 2.6, ncols=v, sharey=True, squeeze=False)
    n = m.n_runs
    for i, (ax, name) in enumerate(zip(axes[0], m.vehicles, strict=True)):
        for j, meth in enumerate(m.methods):
            rmse = np.sqrt(p.sq_err_sum[0, j, i] / n)
            ax.plot(times_s, rmse, **style.line(LABELS[meth]))
        ax.set_yscale("log")
        ax.set_xlabel(style.label("time", "s"))
        style.title(ax, name)
    axes[0, 0].set_ylabel(style.label("RMS horizontal error", "m"))
    style.panel_letters(axes[0])
    style.figure_legend(fig, axes[0])
    fig.suptitle(f"Cooperative navigation error against time ({n} runs)")
    return style.save(fig, path)


PROFILE_SPEED_M_S = 1547.2
"""Where a ``sound_profile`` setting is drawn on the sound-speed axis: Munk's speed at the team's
mean depth (about 12 m), m/s."""


@style.styled
def sensitivity(path: Path, m: CoopMetrics) -> list[str]:
    """The followers' mean error (averaged over the followers) against each sensitivity list,
    every method; the base setting's value drawn as a dotted line per method; Munk's profile as
    open squares at its speed near the team's depths.

    Returns:
        The files written (PNG and PDF), relative to the PNG's folder.
    """
    kinds = [k for k in SWEEPS if any(s.what == k for s in m.settings)]
    profiles = [s for s in m.settings if s.what == "sound_profile"]
    if profiles and "sound_speed_m_s" not in kinds:
        kinds.insert(min(1, len(kinds)), "sound_speed_m_s")
    fig, axes = style.subplots("page", 2.8, ncols=len(kinds), sharey=True, squeeze=False)
    base = m.settings[0]
    followers = m.vehicles[1:]

    def level(s, meth) -> float:
        return float(np.mean([s.methods[meth][f].mean_error_m for f in followers]))

    for ax, kind in zip(axes[0], kinds, strict=True):
        rows = sorted((s for s in m.settings if s.what == kind), key=lambda s: s.value)
        x = [s.value for s in rows]
        for meth in m.methods:
            look = style.line(LABELS[meth], marker="o")
            ax.plot(x, [level(s, meth) for s in rows], **look)
            ax.axhline(level(base, meth), color=look["color"], ls=":", lw=0.8)
        if kind == "sound_speed_m_s":
            for s in profiles:  # a profile at the speed of the team's mean depth
                x0 = [PROFILE_SPEED_M_S]
                for meth in m.methods:
                    look = style.line(LABELS[meth], label="_", marker="s", ls="none")
                    ax.plot(x0, [level(s, meth) for _ in x0], mfc="none", **look)
        title, what, unit = SWEEPS[kind]
        ax.set_yscale("log")
        ax.set_xlabel(style.label(what, unit))
        style.title(ax, title)
    axes[0, 0].set_ylabel(style.label("followers' mean error", "m"))
    style.panel_letters(axes[0])
    style.figure_legend(fig, axes[0])
    fig.suptitle(
        f"Sensitivity of cooperative navigation ({m.n_runs} runs; dotted: base; squares: Munk "
        "profile)"
    )
    return style.save(fig, path)
