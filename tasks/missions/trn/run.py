"""``mission/trn``'s flights: one run flown and reduced to its errors per method, the TRN bound
along it and the counts of the DVL's pings (package docstring)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.world import fly
from tasks.core import store
from tasks.missions.trn.parts import TrnMission
from tasks.missions.trn.scenario import METHODS, TrnScenario
from tasks.missions.trn.terrain import pcrb_track, true_footprints, true_map

Array = NDArray[np.float64]


@store.plain_data("missions.trn.TrnRunResult")
@dataclass
class TrnRunResult:
    """One run, reduced (plain data).

    Attributes:
        run: run index.
        failed: the failure, or ``None``.
        t_s: sample times from the dive on, shape (s,), s (every ``trn.sample_s``).
        errors_m: per method (:data:`~tasks.missions.trn.scenario.METHODS`), the horizontal
            error at the sample times, shape (s,), m.
        pcrb_m: the TRN bound ``sqrt(trace(PCRB))`` at the sample times (the latest update's),
            shape (s,), m.
        counts: the navigation part's counts (pings by DVL mode, TRN updates, updates with no
            usable beam, re-initialisations, beams used).
        stats: ``altitude_mean_m`` (true altitude of the DVL over the seabed, mean over the
            pings), ``nees_pf_mean`` (the particle TRN's mean NEES after the dive: 2 for a
            consistent filter), ``gradient_rms`` (RMS of the true seabed's gradient at the true beam
            footprints of the TRN updates), ``duration_s``, ``reached`` (way-points reached).
        track: the recorded run's true track and every method's, (east, north) at the sample
            times, float32, by name (``truth`` and the methods); empty for other runs.
        flight: the flight (every method's estimate and covariance per tick), exported as the
            run data; ``None`` in blocks written before it was kept.
    """

    run: int
    failed: str | None
    t_s: Array
    errors_m: dict[str, Array]
    pcrb_m: Array
    counts: dict[str, int]
    stats: dict[str, float]
    track: dict[str, Array] = field(default_factory=dict)
    flight: MissionRun | None = None


def _col(v, name: str) -> Array:
    return np.asarray(v.ticks[name].values, float)


def reduce_flight(
    scn: TrnScenario, seed: int, flight: MissionRun, keep_track: bool
) -> TrnRunResult:
    """One flight's errors, bound and counts (:class:`TrnRunResult`); never NaN (a method's
    errors end where the flight ended)."""
    v = flight.lead
    c = scn.trn
    t = _col(v, "t")
    truth = _col(v, "truth_pos")
    every = max(1, round(c.sample_s / scn.timing.control_tick_s))
    start = int(np.searchsorted(t, c.t_dive_s - 1e-9))
    idx = np.arange(start, len(t), every)
    errors = {
        m: np.hypot(*(_col(v, m)[idx, :2] - truth[idx, :2]).T).astype(np.float64) for m in METHODS
    }
    out = dict(v.outcome)
    counts = {k: int(val) for k, val in out.items() if isinstance(val, (int, np.integer))}
    dirs = np.asarray(out.get("beam_directions_body", np.zeros((0, 3))), float).reshape(-1, 3)
    lever = np.asarray(out.get("dvl_lever_arm_body_m", np.zeros(3)), float)
    upd = np.flatnonzero(_col(v, "trn_update") > 0.5)
    rph = _col(v, "truth_rph")
    stats: dict[str, float] = {
        "duration_s": float(t[-1]) if len(t) else 0.0,
        "reached": float(sum(bool(w["reached_by_truth"]) for w in v.waypoints)),
    }
    bound_upd = np.zeros(0)
    if len(dirs) and start < len(t):
        P0 = _col(v, "trn_pf_P")[start].reshape(2, 2)
        q = _col(v, "trn_q")[upd].reshape(-1, 2, 2)
        bound_upd = pcrb_track(scn, seed, P0, q, truth[upd], rph[upd], dirs, lever)
        pings = np.arange(
            start, len(t), max(1, round(scn.sensors.dvl.period_s / scn.timing.control_tick_s))
        )
        pts, _ = true_footprints(scn, truth[pings], rph[pings], dirs, lever)
        bed = true_map(scn.seabed, frame=scn.frame())
        floor, ok = bed.depth(pts[..., 0], pts[..., 1])
        alt = floor + truth[pings, 2][:, None]  # seabed depth less the vehicle's
        stats["altitude_mean_m"] = float(alt[ok].mean()) if ok.any() else 0.0
        if len(upd):
            pu, lu = true_footprints(scn, truth[upd], rph[upd], dirs, lever)
            g, g_ok = bed.gradient(pu[..., 0], pu[..., 1])
            sel = g_ok & lu
            stats["gradient_rms"] = (
                float(np.sqrt(np.mean(np.sum(g[sel] ** 2, -1)))) if sel.any() else 0.0
            )
        P0b = float(np.sqrt(np.trace(P0)))
    else:
        P0b = 0.0
    # the bound at the sample times: the latest update's (the start's before the first)
    pos = np.searchsorted(upd, idx, side="right") - 1
    pcrb = np.where(pos >= 0, bound_upd[np.maximum(pos, 0)] if len(bound_upd) else P0b, P0b)
    if start < len(t):
        e2 = (_col(v, "trn_pf")[idx, :2] - truth[idx, :2])[:, :, None]
        P = _col(v, "trn_pf_P")[idx].reshape(-1, 2, 2)
        nees = (np.swapaxes(e2, 1, 2) @ np.linalg.solve(P, e2))[:, 0, 0]
        stats["nees_pf_mean"] = float(np.mean(nees)) if len(nees) else 0.0
    track = {}
    if keep_track:
        track["truth"] = truth[idx, :2].astype(np.float32)
        for m in METHODS:
            track[m] = _col(v, m)[idx, :2].astype(np.float32)
    return TrnRunResult(
        flight.run,
        flight.failed,
        t[idx] - c.t_dive_s,
        errors,
        np.asarray(pcrb, float),
        counts,
        stats,
        track,
        flight,
    )


def fly_run(scn: TrnScenario, seed: int, run: int) -> TrnRunResult:
    """Fly run ``run`` of the mission and reduce it."""
    flight = fly(TrnMission(), scn, seed, run)
    return reduce_flight(scn, seed, flight, run == scn.report.record_run)


def summary_of(results: list[TrnRunResult]) -> dict[str, Any]:
    """Counts summed over runs."""
    tot: dict[str, int] = {}
    for r in results:
        for k, val in r.counts.items():
            tot[k] = tot.get(k, 0) + val
    return tot
