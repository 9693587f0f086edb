"""Paper-style PNG figures (matplotlib, offscreen Agg backend).

Figures show what the seeds' figures show: routes in the horizontal plane, distance to the
reference over time, histograms of that distance, filter consistency against its chi-square band.
Axes are labelled with units; east is x and north is y.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from numpy.typing import NDArray

from nav.metrics import Histogram

MPL_COLORS = {
    "truth": "black",
    "reference": "black",
    "EKF": "tab:blue",
    "DR": "tab:red",
    "USBL": "tab:green",
    "GPS": "tab:orange",
    "GA1": "tab:green",
    "GA2": "tab:purple",
    "leader": "tab:gray",
}

Array = NDArray[np.float64]


def _save(fig: plt.Figure, path: Path) -> str:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path.name


def routes(
    path: Path,
    reference_en: Array,
    tracks: Mapping[str, Sequence[Array]],
    points: Mapping[str, Sequence[Array]] | None = None,
    landmarks: Mapping[str, Array] | None = None,
    title: str = "",
    extra: Mapping[str, Array] | None = None,
) -> str:
    """Routes in the horizontal plane (seed 000 Figures 8, 19, 24, 30; seed 003 Figures 3, 5, 7).

    Args:
        path: PNG file.
        reference_en: reference route, shape (T, 2+), m (east, north).
        tracks: method -> list of tracks, each (T, 2+), m.
        points: method -> list of point sets, each (k, 2+), m (USBL fixes).
        landmarks: label -> position (2+,), m.
        extra: label -> another reference line (T, 2+), m, drawn dashed (seed 003: the leader).
    """
    fig, ax = plt.subplots(figsize=(7, 6.5))
    for name, pts in (points or {}).items():
        for i, p in enumerate(pts):
            if len(p):
                ax.plot(
                    p[:, 0],
                    p[:, 1],
                    ".",
                    ms=2,
                    alpha=0.35,
                    color=MPL_COLORS.get(name),
                    label=name if i == 0 else None,
                )
    for name, trs in tracks.items():
        color = MPL_COLORS.get(name)
        if len(trs) == 1:
            tr = trs[0]
            ax.plot(tr[:, 0], tr[:, 1], lw=0.8, alpha=0.9, color=color, label=name)
        elif len(trs) > 1:  # many runs: one collection (one draw call) instead of a line each
            alpha = max(0.08, 3.0 / len(trs))
            lines = LineCollection([np.asarray(tr)[:, :2] for tr in trs], lw=0.8, alpha=alpha)
            lines.set_color(color)
            lines.set_label(name)
            ax.add_collection(lines)
            ax.autoscale_view()
    ax.plot(reference_en[:, 0], reference_en[:, 1], "k-", lw=1.6, label="reference")
    for label, line in (extra or {}).items():
        ax.plot(
            line[:, 0], line[:, 1], "--", lw=1.2, color=MPL_COLORS.get(label, "gray"), label=label
        )
    for label, p in (landmarks or {}).items():
        ax.plot(p[0], p[1], "k^", ms=9)
        ax.annotate(label, (p[0], p[1]), textcoords="offset points", xytext=(6, 6))
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    legend = ax.legend(loc="best", fontsize=8)
    for handle in legend.legend_handles:  # faint lines of many runs: full colour in the legend
        if handle is not None:
            handle.set_alpha(1.0)
    ax.set_title(title)
    return _save(fig, path)


def distances(
    path: Path,
    series: Mapping[str, tuple[Array, Array]],
    title: str = "",
    ylabel: str = "distance to the reference position (m)",
) -> str:
    """Distance to the reference over time, one line per method (seed 000 Figures 13, 18...).

    Args:
        series: method -> (t_s (k,), distance_m (k,)).
    """
    fig, ax = plt.subplots(figsize=(8, 4))
    for name, (t, d) in series.items():
        style = "o-" if len(t) < 60 else "-"
        ax.plot(t, d, style, ms=3, lw=1, color=MPL_COLORS.get(name), label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(title)
    return _save(fig, path)


def histograms(path: Path, hists: Mapping[str, Histogram], title: str = "") -> str:
    """Frequency of the distance to the reference (seed 000 Figures 20, 26, 32)."""
    fig, ax = plt.subplots(figsize=(8, 4))
    names = list(hists)
    width = None
    for i, name in enumerate(names):
        h = hists[name]
        w = np.diff(h.edges)
        width = w / (len(names) + 0.5)
        freq = h.counts / max(h.counts.sum(), 1)
        ax.bar(
            h.edges[:-1] + i * width,
            freq,
            width=width,
            align="edge",
            color=MPL_COLORS.get(name),
            label=name,
        )
    ax.set_xlabel("distance to the reference position (m)")
    ax.set_ylabel("relative frequency")
    top = max(
        (h.edges[np.flatnonzero(h.counts)[-1] + 1] if h.counts.any() else h.edges[1])
        for h in hists.values()
    )
    ax.set_xlim(0, top)
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title(title)
    return _save(fig, path)


def consistency(
    path: Path,
    t_s: Array,
    mean_nees: Array,
    band: tuple[float, float],
    dim: int,
    n_runs: int,
    title: str = "",
) -> str:
    """Average NEES over runs against its two-sided chi-square band."""
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t_s, mean_nees, lw=1, color="tab:blue", label=f"mean NEES over {n_runs} runs")
    ax.axhspan(band[0], band[1], color="tab:green", alpha=0.2, label="95% band")
    ax.axhline(dim, color="k", lw=0.8, ls="--", label=f"dim = {dim}")
    ax.set_yscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("NEES")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    ax.set_title(title)
    return _save(fig, path)


def field_map(
    path: Path,
    east_m: Array,
    north_m: Array,
    values: Array,
    title: str = "",
    label: str = "",
    marks: Mapping[str, Array] | None = None,
    arrow: tuple[float, float] | None = None,
    vmax: float | None = None,
) -> str:
    """A scalar field over the horizontal plane (seed 003 Figure 2, the HDOP map).

    Args:
        east_m: grid east coordinates, shape (nx,), m.
        north_m: grid north coordinates, shape (ny,), m.
        values: the field, shape (ny, nx); non-finite cells are drawn at ``vmax``.
        label: colour-bar label.
        marks: label -> position (2,), m, marked with a triangle.
        arrow: ``(course_deg, length_m)`` of an arrow drawn at the centre (the follower's motion).
        vmax: top of the colour scale (values above are clipped).
    """
    v = np.asarray(values, dtype=float)
    top = vmax if vmax is not None else float(np.nanmax(np.where(np.isfinite(v), v, np.nan)))
    v = np.where(np.isfinite(v), np.minimum(v, top), top)
    fig, ax = plt.subplots(figsize=(6.5, 5.5))
    de, dn = (east_m[1] - east_m[0]) / 2, (north_m[1] - north_m[0]) / 2
    extent = (east_m[0] - de, east_m[-1] + de, north_m[0] - dn, north_m[-1] + dn)
    mesh = ax.imshow(v, origin="lower", extent=extent, cmap="viridis_r", vmax=top)
    cs = ax.contour(east_m, north_m, v, levels=[1.5, 2, 3, 5], colors="white", linewidths=0.7)
    ax.clabel(cs, fmt="%g", fontsize=7)
    fig.colorbar(mesh, ax=ax, label=label)
    for name, p in (marks or {}).items():
        ax.plot(p[0], p[1], "k^", ms=9)
        ax.annotate(name, (p[0], p[1]), textcoords="offset points", xytext=(6, 6))
    if arrow is not None:  # the follower's motion, drawn in the upper left corner
        c, length = np.radians(arrow[0]), arrow[1]
        x0 = east_m[0] + 0.08 * (east_m[-1] - east_m[0]) + length / 2
        y0 = north_m[-1] - 0.08 * (north_m[-1] - north_m[0]) - length / 2
        ax.annotate(
            "",
            xy=(x0 + length * np.sin(c) / 2, y0 + length * np.cos(c) / 2),
            xytext=(x0 - length * np.sin(c) / 2, y0 - length * np.cos(c) / 2),
            arrowprops={"arrowstyle": "->", "color": "black", "lw": 1.5},
        )
        ax.annotate(
            "F's DR step", (x0, y0), textcoords="offset points", xytext=(-20, 6), fontsize=8
        )
    ax.set_xlabel("east of the leader (m)")
    ax.set_ylabel("north of the leader (m)")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=10)
    return _save(fig, path)
