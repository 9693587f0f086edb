"""Figures of seed 003's tests: the HDOP map of Figure 2, the reference and estimated paths of the
single sample and of up to ``report.routes_max`` runs, and the single sample's distances."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tasks.core import figures
from tasks.core.registry import Experiment, ReportContext
from tasks.paper003.run import hdop_figure2
from tasks.paper003.scenario import Paper003Scenario, scenario_reading, truth_of

Array = NDArray[np.float64]


def _words(exp: Experiment) -> str:
    """The experiment's name in words for figure titles (``paper-003/test-1`` -> ``Seed 003,
    Test 1``)."""
    family, _, test = exp.name.partition("/")
    seed = family.removeprefix("paper-")
    return (
        f"Seed {seed}, Test {test.removeprefix('test-')}" if test.startswith("test-") else exp.name
    )


def write_figures(
    exp: Experiment,
    ctx: ReportContext,
    scn: Paper003Scenario,
    routes: dict[int, dict[str, NDArray[np.float32]]],
    single: dict[int, dict[str, Array]],
) -> list[str]:
    """Write the PNG figures into ``ctx.out_dir`` from the blocks' routes and single sample.

    Args:
        exp: the experiment (its name titles the figures).
        ctx: the report's context.
        scn: the scenario.
        routes: run -> method -> path points (runs below ``report.routes_max``).
        single: run -> the single sample's series (:class:`tasks.paper003.run.Paper003Block`).

    Returns:
        The files written, relative to ``ctx.out_dir``.
    """
    out = ctx.out_dir
    truth = truth_of(scn, scenario_reading(scn).geometry)
    every = max(1, round(scn.report.routes_every_s / scn.path.tick_s))
    ref = truth.follower_m[::every]
    leader = truth.leader_m[::every]
    files = []
    hm = scn.report.hdop_map
    axis = np.linspace(-hm.half_width_m, hm.half_width_m, hm.cells)
    E, N = np.meshgrid(axis, axis)
    files.extend(
        figures.field_map(
            out / "hdop.png",
            axis,
            axis,
            hdop_figure2(hm, E, N),
            title=f"HDOP around the leader\n(F on course {hm.course_deg:g}°, $D_r$ = "
            f"{hm.step_m:g} m)",
            label="HDOP",
            marks={"L": np.zeros(2)},
            arrow=(hm.course_deg, hm.step_m),
            vmax=10.0,
        )
    )
    names = ("DR", "GA1", "GA2", "EKF")
    runs = sorted(routes)
    s = scn.report.single_sample
    if s in routes:
        files.extend(
            figures.routes(
                out / "paths-single.png",
                ref,
                {k: [routes[s][k]] for k in names},
                landmarks=None,
                title=f"{_words(exp)}: reference and estimated paths of F (run {s})",
                extra={"leader": leader},
            )
        )
    if runs:
        files.extend(
            figures.routes(
                out / "paths-all.png",
                ref,
                {k: [routes[r][k] for r in runs] for k in names},
                title=f"{_words(exp)}: reference and estimated paths of F ({len(runs)} samples)",
                extra={"leader": leader},
            )
        )
    if s in single:
        t = truth.t_s
        d = single[s]
        files.extend(
            figures.distances(
                out / "distance-single.png",
                {k: (t[1:], d[f"distance/{k}"][1:]) for k in names},
                title=f"{_words(exp)}: distance to the reference position (run {s})",
                log=False,
            )
        )
    return files
