"""Figures of ``trn/relief`` in the project style (:mod:`tasks.core.style`): TRN error against
the relief (final and over the run) beside the PCRB and DR-DVL, and the RMSE against time."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tasks.core import style
from tasks.trn.run import METHODS, runs

if TYPE_CHECKING:
    from tasks.trn.report import Pooled, TrnReliefMetrics

Array = NDArray[np.float64]

MAP_LINESTYLES = ("--", ":", (0, (5, 1, 1, 1)))
"""Line style of the second, third... map error of the sweep (the first keeps the method's own
look; the colour stays the method's)."""


PCRB_MARKERS = (".", "x", "+", "1")
"""Marker of the PCRB's line for each map error (its line style is the PCRB's own)."""


def _map_ls(i: int) -> dict:
    return {} if i == 0 else {"ls": MAP_LINESTYLES[(i - 1) % len(MAP_LINESTYLES)]}


@style.styled
def relief(path: Path, m: TrnReliefMetrics) -> list[str]:
    """(a) final error and (b) RMSE over the run against the relief's standard deviation, per
    method (DR-DVL, PF, PMF) and map error, with the PCRB's level; error bars: 2 standard errors.

    Returns:
        The files written (PNG and PDF), relative to the PNG's folder.
    """
    fig, axes = style.subplots("page", 3.0, ncols=2)
    sigmas = sorted({s.map_sigma_m for s in m.settings})
    for ax, (key, se_key, bound_key, what) in zip(
        axes,
        (
            ("final_mean_m", "final_se_m", "pcrb_final_m", "Final error"),
            ("rmse_m", "rmse_se_m", "pcrb_rms_m", "RMSE over the run"),
        ),
        strict=True,
    ):
        for i, sig in enumerate(sigmas):
            rows = sorted(
                (s for s in m.settings if s.map_sigma_m == sig), key=lambda s: s.relief_std_m
            )
            x = np.array([s.relief_std_m for s in rows])
            tag = f", map {sig:g} m" if len(sigmas) > 1 else ""
            for meth in METHODS if i == 0 else METHODS[1:]:  # DR does not use the map
                y = [getattr(s.methods[meth], key) for s in rows]
                e = [getattr(s.methods[meth], se_key) for s in rows]
                keep = [j for j, v in enumerate(y) if v is not None]
                if not keep:
                    continue
                ax.errorbar(
                    x[keep],
                    [y[j] for j in keep],
                    yerr=[2 * (e[j] or 0.0) for j in keep],
                    capsize=2,
                    **style.line(meth, label=f"{meth}{tag}", marker="o", **_map_ls(i)),
                )
            b = [getattr(s, bound_key) for s in rows]
            ax.plot(x, b, **style.line("PCRB", label=f"PCRB{tag}", marker=PCRB_MARKERS[i % 4]))
        ax.set_yscale("log")
        if any(s.relief_std_m == 0 for s in m.settings):  # a flat seabed among the settings
            ax.set_xscale("symlog", linthresh=0.1)
        else:
            ax.set_xscale("log")
            style.log_ticks(ax, "x")
        style.log_ticks(ax, "y")
        ax.set_xlabel(style.label("relief standard deviation", "m"))
        ax.set_ylabel(style.label(what, "m"))
        style.title(ax, what)
    style.panel_letters(axes)
    style.figure_legend(fig, axes, ncol=4)
    fig.suptitle(f"Terrain-relative navigation against relief ({runs(m.n_runs)})")
    return style.save(fig, path)


@style.styled
def against_time(path: Path, m: TrnReliefMetrics, p: Pooled, times_s: Array) -> list[str]:
    """RMSE over runs against time, one panel per relief (the first map error of the sweep),
    DR-DVL, PF and PMF beside the PCRB (without and with the filters' per-ping bias).

    Returns:
        The files written (PNG and PDF), relative to the PNG's folder.
    """
    first = m.settings[0].map_sigma_m
    idx = [i for i, s in enumerate(m.settings) if s.map_sigma_m == first]
    fig, axes = style.subplots("page", 2.6, ncols=len(idx), sharey=True, squeeze=False)
    n = p.final_m.shape[0]
    for ax, s in zip(axes[0], idx, strict=True):
        for k, meth in enumerate(METHODS):
            c = p.count[s, k]
            if not c.any():
                continue
            rmse = np.sqrt(np.divide(p.sq_err_sum[s, k], np.maximum(c, 1)))
            ax.plot(times_s[c > 0], rmse[c > 0], **style.line(meth))
        ax.plot(times_s, np.sqrt(p.pcrb_sum[s, 0] / n), **style.line("PCRB"))
        bias = style.line("PCRB", label="PCRB, per-ping bias marginalised", ls="--", alpha=0.6)
        ax.plot(times_s, np.sqrt(p.pcrb_sum[s, 1] / n), **bias)
        ax.set_yscale("log")
        ax.set_xlabel(style.label("time", "s"))
        style.title(ax, f"relief {m.settings[s].relief_std_m:g} m")
    axes[0, 0].set_ylabel(style.label("RMSE", "m"))
    style.panel_letters(axes[0])
    style.figure_legend(fig, axes[0])
    fig.suptitle(f"TRN error against time, map sigma {first:g} m ({runs(m.n_runs)})")
    return style.save(fig, path)
