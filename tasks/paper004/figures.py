"""Figures of seed 004's kinematic experiments (Figures 5-9 equivalents, project style).

* ``nominal-3d``: the nominal path and the beacons (Figure 5);
* ``nominal-components``: X°, Y°, Z° against time (Figure 6);
* ``sample-paths-<case>``: true paths of the sample runs steered by each filter, with the nominal
  path (Figure 7);
* ``error-<case>``: the estimate error's sample mean (dotted) and standard deviation (solid) per
  axis and filter, with the PCRB's standard deviation (Figure 8; Figure 9 for the near-beacon
  case).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nav.bearings.pcrb import pcrb
from tasks.core import style
from tasks.paper004.sim import FILTERS

plt = style.plt


@style.styled
def nominal(out: Path, xn: np.ndarray, beacons: np.ndarray, t: np.ndarray) -> list[str]:
    """Figures 5 and 6: the nominal path with the beacons, and its components."""
    files = []
    fig = plt.figure(figsize=(style.COLUMN_IN, style.COLUMN_IN * 0.8))
    ax = fig.add_subplot(projection="3d")
    ax.plot(xn[:, 0], xn[:, 1], xn[:, 2], **style.line("reference", label="nominal path"))
    ax.scatter(
        beacons[:, 0], beacons[:, 1], beacons[:, 2], color=style.color("EKF"), s=12, label="beacons"
    )
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    style.figure_legend(fig, [ax])  # below the axes: inside, it hid a beacon
    style.title(ax, "Nominal path and beacons")
    files += style.save(fig, out / "nominal-3d.png")
    fig, axes = style.subplots("column", height_in=3.6, nrows=3, sharex=True)
    for ax, i, name in zip(axes, range(3), ("x", "y", "z"), strict=True):
        ax.plot(t, xn[:, i], **style.line("reference", label="nominal"))
        ax.set_ylabel(style.label(name, "m"))
    axes[-1].set_xlabel(style.label("time", "s"))
    style.title(axes[0], "Nominal path, component-wise")
    files += style.save(fig, out / "nominal-components.png")
    return files


@style.styled
def sample_paths(out: Path, name: str, xn: np.ndarray, t: np.ndarray, runs: dict) -> list[str]:
    """Figure 7: true paths of the sample runs under each filter's control.

    The filters' paths of one run lie close together: they are drawn half-transparent, the
    dashed one last, so that none hides another, and the legend goes below the panels."""
    fig, axes = style.subplots("page", height_in=2.9, ncols=2)
    axes[0].plot(xn[:, 0], xn[:, 1], **style.line("reference", label="nominal"), zorder=3)
    axes[1].plot(t, xn[:, 2], **style.line("reference", label="nominal"), zorder=3)
    order = sorted(FILTERS, key=lambda f: style.line(f).get("ls", "-") not in ("-", "solid"))
    for r, (_run, tracks) in enumerate(sorted(runs.items())):
        for f in order:
            if f not in tracks:
                continue
            tr = np.asarray(tracks[f], dtype=float)
            lab = f if r == 0 else "_"
            look = style.line(f, label=lab, lw=0.8, alpha=0.7)
            axes[0].plot(tr[:, 0], tr[:, 1], **look)
            axes[1].plot(t, tr[:, 2], **look)
    axes[0].set_xlabel("x (m)")
    axes[0].set_ylabel("y (m)")
    axes[1].set_xlabel(style.label("time", "s"))
    axes[1].set_ylabel("z (m)")
    style.title(axes[0], f"Sample paths ({len(runs)} runs), plan")
    style.title(axes[1], "Sample paths, depth axis")
    style.figure_legend(fig, axes)  # below the panels: inside, it hid a trough of the paths
    return style.save(fig, out / f"sample-paths-{name}.png")


@style.styled
def errors(
    out: Path, name: str, t: np.ndarray, sums, s_w: np.ndarray, s_0: np.ndarray, title: str
) -> list[str]:
    """Figure 8 (9): error mean (dotted) and standard deviation (solid) per axis and filter."""
    fig, axes = style.subplots("page", height_in=5.0, nrows=3, sharex=True)
    for fi, f in enumerate(FILTERS):
        cnt = np.maximum(sums.count[fi], 1.0)
        mean = sums.err[fi] / cnt[:, None]
        var = np.maximum(sums.err2[fi] / cnt[:, None] - mean**2, 0.0)
        for i in range(3):
            axes[i].plot(t, np.sqrt(var[:, i]), **style.line(f, label=f"{f} std"))
            axes[i].plot(t, mean[:, i], **style.line(f, label=f"{f} mean", ls=":"))
    cnt = np.maximum(sums.count[0], 1.0)
    info = sums.info[0] / cnt[:, None, None]
    bound = pcrb(np.linalg.inv(s_0), s_w, info[1:])
    for i, ax in enumerate(axes):
        ax.plot(t, np.sqrt(bound[:, i, i]), **style.line("PCRB", label="PCRB std"))
        ax.set_ylabel(style.label(f"error {'xyz'[i]}", "m"))
    axes[-1].set_xlabel(style.label("time", "s"))
    style.title(axes[0], title)
    style.figure_legend(fig, axes, ncol=4)
    return style.save(fig, out / f"error-{name}.png")


def draw(out: Path, kind: str, scn, cs, settings, tot, samples: dict) -> list[str]:
    """Every figure of a batch (see the module docstring); ``settings`` are the cases'
    :class:`tasks.paper004.sim.LoopSetting`, in the order of ``cs``."""
    xn = scn.path.path()
    t = np.arange(len(xn)) * scn.path.dt_s
    files = nominal(out, xn, np.asarray(scn.beacons, dtype=float), t)
    for c, st, s in zip(cs, settings, tot, strict=True):
        if c.label in samples:
            files += sample_paths(out, c.label, xn, t, samples[c.label])
        files += errors(
            out,
            c.label,
            t,
            s,
            st.noise.s_w,
            st.noise.s_0,
            f"Estimate error, bearing {c.bearing_sigma_deg:g} deg, "
            f"S0 = {c.initial_variance_m2:g} I",
        )
    return files
