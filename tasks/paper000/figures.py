"""Figures of a seed 000 test (PNG and PDF): routes, the mean distance to the reference, single
passages, histograms of the distances and the EKF's consistency."""

from __future__ import annotations

from tasks.core import figures


def title_words(exp) -> str:
    """The test's name in words: ``"Seed 000 Test 1"``."""
    n = exp.test.split("-")[-1]
    return f"Seed 000 Test {n}"


def passage_figures(exp, ctx, scn, tot, truth, zeta, fix_tick, mean_nees, band) -> list[str]:
    """The test's figures (PNG and PDF), for any valid batch: one run, no route kept."""
    out = ctx.out_dir
    t = truth.t_s
    ref = truth.pos_world_m[0]
    tx = scn.transceiver.position_world_m()
    words = f"{title_words(exp)}, USBL fix every {scn.sensors.usbl.period_s:g} s"
    n = ctx.n_runs
    passages = f"{n} passage{'s' * (n != 1)}"
    k = 2.0
    files: list[str] = []
    runs = sorted(tot.routes)
    if runs:
        files += figures.routes(
            out / "routes.png",
            ref,
            {
                "DR": [tot.routes[r]["DR"] for r in runs],
                "EKF": [tot.routes[r]["EKF"] for r in runs],
            },
            {"USBL": [tot.routes[r]["USBL"] for r in runs]},
            {"transceiver": tx},
            title=f"{words}: routes of {len(runs)} passage{'s' * (len(runs) != 1)}",
        )
    bounds = {}
    if tot.ekf_sigma_h is not None:
        bounds["EKF"] = (t[1:], k * tot.ekf_sigma_h.mean()[1:], f"EKF {k:g}$\\sigma$ radius")
    files += figures.distances(
        out / "distance.png",
        {
            "EKF": (t[1:], zeta["EKF"][1:]),
            "DR": (t[1:], zeta["DR"][1:]),
            "USBL": (t[fix_tick], zeta["USBL"]),
        },
        title=f"{words}: mean distance to the reference over {passages}",
        bounds=bounds,
    )
    for run in sorted(tot.single):
        d = tot.single[run]
        sb = {}
        if "EKF_sigma_h" in d:
            sb["EKF"] = (t[1:], k * d["EKF_sigma_h"][1:], f"EKF {k:g}$\\sigma$ radius")
        files += figures.distances(
            out / f"distance-passage-{run + 1}.png",
            {
                "EKF": (t[1:], d["EKF"][1:]),
                "DR": (t[1:], d["DR"][1:]),
                "USBL": (t[fix_tick], d["USBL"]),
            },
            title=f"{words}: passage {run + 1}",
            bounds=sb,
        )
    files += figures.histograms(
        out / "histogram.png",
        tot.hist,
        title=f"{words}: distance to the reference, {passages}",
    )
    files += figures.consistency(
        out / "nees.png",
        t[1:],
        mean_nees[1:],
        band,
        3,
        n,
        title=f"{words}: EKF consistency (position NEES)",
        probability=scn.report.consistency_probability,
        method="EKF",
    )
    return files
