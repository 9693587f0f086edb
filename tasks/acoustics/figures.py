"""Figures of ``acoustics/sound-speed`` in the project style (:mod:`tasks.core.style`): the
systematic cost of the profile (the devices without their errors) for each navigator, along the
USBL passage and against the modem link's range."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tasks.acoustics.run import METHODS, links, passage
from tasks.core import style

if TYPE_CHECKING:
    from tasks.acoustics.report import SoundSpeedMetrics
    from tasks.acoustics.scenario import SoundSpeedScenario

Array = NDArray[np.float64]

DEPTH_MARKERS = ("o", "s", "^", "v", "D", "x", "+", "*")
"""Marker of each receiver depth of the modem panel."""


@style.styled
def systematic(
    path: Path, scn: SoundSpeedScenario, m: SoundSpeedMetrics, exact: dict[str, Array]
) -> list[str]:
    """(a) the USBL's horizontal position error along the passage and (b) the modem's slant-range
    error against the horizontal range (one marker per receiver depth), per navigator, without
    the devices' errors.

    Args:
        path: the PNG file.
        scn: the scenario.
        m: the metrics (for the titles).
        exact: :func:`tasks.acoustics.run.exact`'s arrays.

    Returns:
        The files written (PNG and PDF), relative to the PNG's folder.
    """
    fig, axes = style.subplots("page", 3.0, ncols=2)
    _, pos = passage(scn)
    for i, meth in enumerate(METHODS):
        ok = exact["usbl_present"][:, i]
        axes[0].plot(pos[ok, 0], exact["usbl_horizontal_m"][ok, i], **style.line(meth))
    axes[0].set_xlabel(style.label("transponder east (closest approach at 0)", "m"))
    axes[0].set_ylabel(style.label("horizontal position error", "m"))
    style.title(axes[0], f"USBL, transceiver {m.usbl.transceiver_depth_m:g} m")
    sender, receiver = links(scn)
    depths = sorted(set((-receiver[:, 2]).tolist()))
    for i, meth in enumerate(METHODS):
        for j, depth in enumerate(depths):
            rows = np.flatnonzero((-receiver[:, 2] == depth) & exact["modem_present"][:, i])
            axes[1].plot(
                receiver[rows, 0],
                exact["modem_error_m"][rows, i],
                **style.line(
                    meth,
                    label=meth if j == 0 else "_",
                    marker=DEPTH_MARKERS[j % len(DEPTH_MARKERS)],
                ),
            )
    axes[1].set_xlabel(style.label("horizontal range", "m"))
    axes[1].set_ylabel(style.label("slant-range error", "m"))
    marks = " ".join(DEPTH_MARKERS[j % len(DEPTH_MARKERS)] for j in range(len(depths)))
    receivers = ", ".join(f"{d:g}" for d in depths)
    style.title(axes[1], f"modem, sender {-sender[0, 2]:g} m, receivers {receivers} m ({marks})")
    style.panel_letters(axes)
    style.figure_legend(fig, axes, ncol=3)
    fig.suptitle(f"Systematic cost of the sound-speed profile ({m.profile.kind})")
    return style.save(fig, path)
