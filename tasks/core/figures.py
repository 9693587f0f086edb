"""Paper-style figures in the project style (:mod:`tasks.core.style`): PNG and PDF.

Figures show what the seeds' figures show: routes in the horizontal plane, distance to the
reference over time, the distribution of that distance, filter consistency against its
chi-square band. Axes carry units; east is x and north is y. Every function accepts any valid
batch (one run, no route kept, a method with no data) and draws what there is.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from nav.metrics import Histogram
from tasks.core import style
from tasks.core.lazy import LazyModule

collections = LazyModule("matplotlib.collections", after=(style.matplotlib,))

__all__ = ["consistency", "distances", "field_map", "histograms", "route_alpha", "routes"]

Array = NDArray[np.float64]


def route_alpha(n_tracks: int) -> float:
    """Opacity of one of ``n_tracks`` overlaid tracks: 0.9 alone, fading to 0.15 for many.

    Always inside [0.25, 0.9] (matplotlib refuses an alpha outside [0, 1]), for any count.
    """
    return float(np.clip(3.0 / max(n_tracks, 1), 0.25, 0.9))


def _frame(reference_en: Array) -> tuple[Array, Array, Array] | None:
    """Origin, along-track and cross-track unit vectors of a straight reference, else None."""
    ref = np.asarray(reference_en, dtype=float)[:, :2]
    if len(ref) < 2:
        return None
    chord = ref[-1] - ref[0]
    length = float(np.hypot(*chord))
    if length <= 0:
        return None
    u = chord / length
    n = np.array([u[1], -u[0]])  # to starboard of the direction of travel
    off = (ref - ref[0]) @ n
    if np.max(np.abs(off)) > 0.01 * length:
        return None
    return ref[0], u, n


@style.styled
def routes(
    path: Path,
    reference_en: Array,
    tracks: Mapping[str, Sequence[Array]],
    points: Mapping[str, Sequence[Array]] | None = None,
    landmarks: Mapping[str, Array] | None = None,
    title: str = "",
    extra: Mapping[str, Array] | None = None,
) -> list[str]:
    """Routes in the horizontal plane (seed 000 Figures 8, 19, 24, 30; seed 003 Figures 3, 5, 7).

    Panel (a) is the plan view (east, north, equal scales); when the reference is a straight line
    panel (b) shows each method's offset across it against the distance along it, where metres of
    error are visible on a route hundreds of metres long. Fixes are drawn faint and beneath the
    tracks, so the tracks never vanish under a cloud of fixes.

    Args:
        path: PNG file (a PDF is written beside it).
        reference_en: reference route, shape (T, 2+), m (east, north).
        tracks: method -> list of tracks, each (T, 2+), m (an empty list draws nothing).
        points: method -> list of point sets, each (k, 2+), m (USBL fixes).
        landmarks: label -> position (2+,), m.
        title: the figure's title, in words.
        extra: label -> another reference line (T, 2+), m, drawn dashed in the label's style
            (seed 003: the leader).

    Returns:
        The files written (PNG, PDF).
    """
    frame = _frame(reference_en)
    ncols = 2 if frame is not None else 1
    fig, axes = style.subplots("page" if ncols == 2 else "column", 3.4, 1, ncols, squeeze=False)
    axes = axes[0]
    ref = np.asarray(reference_en, dtype=float)

    def draw(ax, xy):
        for name, pts in (points or {}).items():
            pts = [p for p in pts if len(p)]
            for i, p in enumerate(pts):
                q = xy(np.asarray(p, dtype=float))
                ax.plot(
                    q[:, 0],
                    q[:, 1],
                    **style.line(
                        name,
                        label=f"{name} fixes" if i == 0 else "_",
                        ms=1.5,
                        alpha=0.35,
                        zorder=1,
                    ),
                )
        for name, trs in tracks.items():
            alpha = route_alpha(len(trs))
            if len(trs) > 8:  # many runs: one collection (one draw call) instead of a line each
                look = style.line(name, lw=0.8, alpha=alpha, zorder=3)
                lines = collections.LineCollection(
                    [xy(np.asarray(tr, dtype=float)) for tr in trs],
                    colors=look["color"],
                    linestyles="-" if look.get("ls") in (None, "none") else look["ls"],
                    linewidths=0.8,
                    alpha=alpha,
                    zorder=3,
                )
                ax.add_collection(lines)
                ax.autoscale_view()
                ax.plot([], [], **style.line(name, lw=0.8))  # the legend entry, opaque
                continue
            for i, tr in enumerate(trs):
                q = xy(np.asarray(tr, dtype=float))
                ax.plot(
                    q[:, 0],
                    q[:, 1],
                    **style.line(
                        name, label=name if i == 0 else "_", lw=0.8, alpha=alpha, zorder=3
                    ),
                )
        q = xy(ref)
        ax.plot(q[:, 0], q[:, 1], **style.line("reference", lw=1.2, zorder=4))
        for lab, line_en in (extra or {}).items():
            q = xy(np.asarray(line_en, dtype=float))
            ax.plot(q[:, 0], q[:, 1], **style.line(lab, lw=1.0, ls="--", zorder=4))

    draw(axes[0], lambda p: p[:, :2])
    for lab, p in (landmarks or {}).items():
        axes[0].plot(p[0], p[1], "^", color="k", ms=6, zorder=5)
        axes[0].annotate(lab, (p[0], p[1]), textcoords="offset points", xytext=(5, -9))
    axes[0].set_xlabel(style.label("east", "m"))
    axes[0].set_ylabel(style.label("north", "m"))
    axes[0].set_aspect("equal", adjustable="datalim")
    if frame is not None:
        o, u, n = frame

        def along_across(p):
            d = p[:, :2] - o
            return np.column_stack([d @ u, d @ n])

        draw(axes[1], along_across)
        offsets = [
            np.abs(along_across(np.asarray(tr, dtype=float))[:, 1])
            for trs in tracks.values()
            for tr in trs
        ]
        if offsets:
            # the panel is about the tracks: fixes farther out are in panel (a)
            lim = 1.4 * float(np.percentile(np.concatenate(offsets), 99.5)) + 1.0
            axes[1].set_ylim(-lim, lim)
        for p in (landmarks or {}).values():
            q = along_across(np.asarray(p, dtype=float)[None, :2])[0]
            axes[1].axvline(q[0], color="k", lw=0.6, ls=":", zorder=0)
            axes[1].annotate(
                "closest to the transceiver",
                (q[0], 1.0),
                xycoords=("data", "axes fraction"),
                xytext=(3, -3),
                textcoords="offset points",
                va="top",
                fontsize=6.5,
            )
        axes[1].set_xlabel(style.label("distance along the reference", "m"))
        axes[1].set_ylabel(style.label("offset to starboard of it", "m"))
        style.panel_letters(axes)
    if title:
        fig.suptitle(title)
    style.figure_legend(fig, axes)
    return style.save(fig, path)


@style.styled
def distances(
    path: Path,
    series: Mapping[str, tuple[Array, Array]],
    title: str = "",
    ylabel: str = "distance to the reference position",
    bounds: Mapping[str, tuple[Array, Array, str]] | None = None,
    log: bool = True,
) -> list[str]:
    """Distance to the reference over time, one line per method (seed 000 Figures 13, 18...).

    On a log axis (default) an EKF of a metre and a DR of hundreds of metres are both readable.

    Args:
        path: PNG file (a PDF is written beside it).
        series: method -> (t_s (k,), distance_m (k,)); NaN samples and zeros (not on a log
            axis) are left out; fewer than 60 samples are drawn with markers.
        title: the figure's title, in words.
        ylabel: the quantity on the y axis (its unit, m, is added).
        bounds: method -> (t_s (k,), bound_m (k,), label): the filter's own bound drawn
            dotted in the method's colour (e.g. its 2-sigma radius).
        log: log y axis.

    Returns:
        The files written (PNG, PDF).
    """
    fig, ax = style.subplots("page", 2.8)
    for name, (t, d) in series.items():
        t = np.asarray(t, dtype=float)
        d = np.asarray(d, dtype=float)
        keep = np.isfinite(d) & ((d > 0) if log else True)
        if not keep.any():
            continue
        kw = style.line(name)
        if kw.get("ls") == "none" or keep.sum() < 60:
            kw.update(ls="-" if keep.sum() < 60 else "none", marker=kw.get("marker", "o"), ms=3)
            kw["lw"] = 0.6
        ax.plot(t[keep], d[keep], **kw)
    for name, (t, b, lab) in (bounds or {}).items():
        b = np.asarray(b, dtype=float)
        keep = np.isfinite(b) & ((b > 0) if log else True)
        if keep.any():
            ax.plot(np.asarray(t)[keep], b[keep], **style.line(name, label=lab, ls=":", lw=1.0))
    if log:
        ax.set_yscale("log")
        style.log_ticks(ax)
    ax.set_xlabel(style.label("time", "s"))
    ax.set_ylabel(style.label(ylabel, "m"))
    if title:
        style.title(ax, title)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    else:
        ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center")
    return style.save(fig, path)


@style.styled
def histograms(path: Path, hists: Mapping[str, Histogram], title: str = "") -> list[str]:
    """Distribution of the distance to the reference (seed 000 Figures 20, 26, 32).

    Panel (a): relative frequency per bin as step outlines (one per method, never grouped bars
    that hide each other); panel (b): the empirical cumulative distribution, with the median
    and the 95th percentile readable off it.

    Args:
        path: PNG file (a PDF is written beside it).
        hists: method -> histogram of its distances, m (the last bin counts overflow).
        title: the figure's title, in words.

    Returns:
        The files written (PNG, PDF).
    """
    fig, (a1, a2) = style.subplots("page", 2.7, 1, 2)
    top = 0.0
    for name, h in hists.items():
        total = int(h.counts.sum())
        if total == 0:
            continue
        freq = h.counts / total
        kw = style.line(name, lw=1.1)
        kw.update(ls="-", marker=None)
        a1.stairs(freq, h.edges, **{k: kw[k] for k in ("color", "label", "lw")})
        cdf = np.concatenate([[0.0], np.cumsum(h.counts) / total])
        a2.plot(h.edges, cdf, color=kw["color"], lw=1.1, label=kw["label"])
        top = max(top, float(h.edges[np.flatnonzero(h.counts)[-1] + 1]))
    for ax in (a1, a2):
        ax.set_xlabel(style.label("distance to the reference position", "m"))
        if top > 0:
            ax.set_xlim(0, top)
    a2.axhline(0.5, color="0.5", lw=0.5, ls="--")
    a2.axhline(0.95, color="0.5", lw=0.5, ls="--")
    a2.set_ylim(0, 1.0)
    a1.set_ylabel("relative frequency per bin")
    a2.set_ylabel("fraction at or below")
    style.panel_letters((a1, a2))
    if title:
        fig.suptitle(title)
    if a1.get_legend_handles_labels()[0]:
        style.figure_legend(fig, (a1,))
    else:
        a1.text(0.5, 0.5, "no data", transform=a1.transAxes, ha="center")
    return style.save(fig, path)


@style.styled
def consistency(
    path: Path,
    t_s: Array,
    mean_nees: Array,
    band: tuple[float, float],
    dim: int,
    n_runs: int,
    title: str = "",
    probability: float = 0.95,
    *,
    method: str,
) -> list[str]:
    """Average NEES over runs against its two-sided chi-square band.

    Args:
        path: PNG file (a PDF is written beside it).
        t_s: times, shape (T,), s.
        mean_nees: mean NEES over the runs at each time, shape (T,); NaN left out.
        band: the band's (low, high) for ``n_runs`` runs.
        dim: the state dimension of the NEES.
        n_runs: the number of runs averaged.
        title: the figure's title, in words.
        probability: the band's probability.
        method: the estimator whose NEES it is (its look and legend label, :mod:`style`).

    Returns:
        The files written (PNG, PDF).
    """
    fig, ax = style.subplots("page", 2.8)
    v = np.asarray(mean_nees, dtype=float)
    keep = np.isfinite(v) & (v > 0)
    ax.axhspan(
        band[0],
        band[1],
        color=style.PALETTE["bluish_green"],
        alpha=0.2,
        lw=0,
        label=f"{100 * probability:g} % chi-square band, {n_runs} run{'s' * (n_runs != 1)}",
    )
    ax.axhline(dim, color="k", lw=0.7, ls="--", label=f"expected value = {dim} (state dimension)")
    ax.plot(
        np.asarray(t_s)[keep],
        v[keep],
        **style.line(method, label=f"{method} mean NEES over {n_runs} run{'s' * (n_runs != 1)}"),
    )
    ax.set_yscale("log")
    style.log_ticks(ax)
    ax.set_xlabel(style.label("time", "s"))
    ax.set_ylabel("mean NEES")
    if title:
        fig.suptitle(title)
    style.figure_legend(fig, (ax,), ncol=3)
    return style.save(fig, path)


@style.styled
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
) -> list[str]:
    """A scalar field over the horizontal plane (seed 003 Figure 2, the HDOP map).

    Args:
        east_m: grid east coordinates, shape (nx,), m.
        north_m: grid north coordinates, shape (ny,), m.
        values: the field, shape (ny, nx); non-finite cells are drawn at ``vmax``.
        label: colour-bar label.
        marks: label -> position (2,), m, marked with a triangle.
        arrow: ``(course_deg, length_m)`` of an arrow drawn at the centre (the follower's motion).
        vmax: top of the colour scale (values above are clipped).

    Returns:
        The files written (PNG, PDF).
    """
    v = np.asarray(values, dtype=float)
    top = vmax if vmax is not None else float(np.nanmax(np.where(np.isfinite(v), v, np.nan)))
    v = np.where(np.isfinite(v), np.minimum(v, top), top)
    fig, ax = style.subplots("column", 3.2)
    de, dn = (east_m[1] - east_m[0]) / 2, (north_m[1] - north_m[0]) / 2
    extent = (east_m[0] - de, east_m[-1] + de, north_m[0] - dn, north_m[-1] + dn)
    mesh = ax.imshow(v, origin="lower", extent=extent, cmap="viridis_r", vmax=top)
    cs = ax.contour(east_m, north_m, v, levels=[1.5, 2, 3, 5], colors="white", linewidths=0.7)
    ax.clabel(cs, fmt="%g", fontsize=7)
    fig.colorbar(mesh, ax=ax, label=label)
    for name, p in (marks or {}).items():
        ax.plot(p[0], p[1], "k^", ms=6)
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
            "F's DR step", (x0, y0), textcoords="offset points", xytext=(-20, 6), fontsize=6.5
        )
    ax.set_xlabel(style.label("east of the leader", "m"))
    ax.set_ylabel(style.label("north of the leader", "m"))
    ax.set_aspect("equal")
    ax.grid(False)
    if title:
        ax.set_title(title)
    return style.save(fig, path)
