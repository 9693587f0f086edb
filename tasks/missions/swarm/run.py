"""One run of ``mission/swarm``: the flights (one per method, the same draws) and their metrics
(:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from nav.metrics import first_exceedance
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.world import fly
from tasks.core import store
from tasks.missions.swarm.design import SwarmMission
from tasks.missions.swarm.network import NETWORK, network_table
from tasks.missions.swarm.scenario import (
    FOLLOWERS,
    LEADER,
    StationConfig,
    SwarmScenario,
    station_offsets,
)
from tasks.missions.swarm.team import team_comparison

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# Metrics of one flight


def leader_course_true(leader: VehicleRun, window_ticks: int) -> Array:
    """The leader's true course over ground, rad, shape (T,): of its true velocity averaged over
    the last ``window_ticks`` ticks (the hull swings with the tail beat)."""
    v = leader["truth_vel"][:, :2]
    c = np.cumsum(np.vstack([np.zeros((1, 2)), v]), axis=0)
    k = np.arange(1, len(v) + 1)
    lo = np.maximum(k - window_ticks, 0)
    mean = (c[k] - c[lo]) / (k - lo)[:, None]
    return np.arctan2(mean[:, 0], mean[:, 1]) % (2 * np.pi)


def follower_metrics(
    scn: SwarmScenario, run: MissionRun, name: str, station: StationConfig
) -> dict[str, float]:
    """Errors of a follower's estimate (and of its pure DR) against its truth, and its true
    distance to the true station point (from the leader's true position and true course), m;
    fix counts; ``diverged_at_s``, the first time the estimate was farther than
    ``navigation.divergence_m`` from the truth (only when it was)."""
    lead, f = run.vehicles[LEADER], run.vehicles[name]
    n = min(len(lead["t"]), len(f["t"]))
    tick = scn.timing.control_tick_s
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))[:n]
    b = np.radians(station.relative_bearing_deg)
    station_true = lead["truth_pos"][:n, :2] + station.distance_m * np.column_stack(
        [np.sin(course + b), np.cos(course + b)]
    )
    truth = f["truth_pos"][:n, :2]
    e_est = np.hypot(*(f["ekf_pos"][:n, :2] - truth).T)
    e_dr = np.hypot(*(f["dr_pos"][:n, :2] - truth).T)
    e_st = np.hypot(*(truth - station_true).T)
    rel_true = truth - lead["truth_pos"][:n, :2]
    rel_est = f["ekf_pos"][:n, :2] - f["leader_est"][:n]
    e_rel = np.hypot(*(rel_est - rel_true).T)
    counts = f.outcome.get("fix_counts", {})
    fixes = f.fixes.get("modem", {})
    received = len(fixes["t_valid"].values) if fixes else 0
    gaps = f.outcome.get("dr_gaps_s", [])
    diverged = first_exceedance(f["t"][:n], e_est, scn.navigation.divergence_m)
    return {
        **({} if diverged is None else {"diverged_at_s": diverged}),
        "est_mean_error_m": float(e_est.mean()),
        "est_max_error_m": float(e_est.max()),
        "est_final_error_m": float(e_est[-1]),
        "relative_mean_error_m": float(e_rel.mean()),
        "relative_max_error_m": float(e_rel.max()),
        "dr_mean_error_m": float(e_dr.mean()),
        "dr_max_error_m": float(e_dr.max()),
        "station_mean_error_m": float(e_st.mean()),
        "station_max_error_m": float(e_st.max()),
        "ranges_received": float(received),
        "fixes_accepted": float(counts.get("accepted", 0)),
        "fixes_refused": float(received - counts.get("accepted", 0) - counts.get("dr", 0)),
        "mean_fix_hdop": float(f.outcome.get("mean_fix_hdop", 0.0)),
        "longest_dr_gap_s": float(max((b1 - a1 for a1, b1 in gaps), default=0.0)),
        "duration_s": float(f["t"][n - 1]),
    }


def leader_metrics(scn: SwarmScenario, run: MissionRun) -> dict[str, float]:
    """The leader's own navigation (its broadcast's error) and fix counts; ``diverged_at_s``
    as for a follower (:func:`follower_metrics`)."""
    lead = run.vehicles[LEADER]
    s = lead.summary
    keys = ("ekf_mean_error_m", "ekf_max_error_m", "usbl_fixes", "usbl_rejected", "duration_s")
    err = np.hypot(*(lead["ekf_pos"][:, :2] - lead["truth_pos"][:, :2]).T)
    diverged = first_exceedance(lead["t"], err, scn.navigation.divergence_m)
    out = {k: s[k] for k in keys if k in s}
    return out if diverged is None else {"diverged_at_s": diverged, **out}


def divergences(scn: SwarmScenario, run: int, method: str, metrics) -> list[str]:
    """One line per aided estimate of a flight that diverged (the leader's EKF and, unless the
    method is ``dr``, every follower's), from its metrics."""
    out = []
    for name, m in metrics.items():
        if "diverged_at_s" in m and (name == LEADER or method != "dr"):
            what = "EKF" if name == LEADER else method.upper()
            out.append(
                f"run {run} {method} {name}: {what} estimate diverged: farther than "
                f"{scn.navigation.divergence_m:g} m from the truth from t = "
                f"{m['diverged_at_s']:.1f} s (navigation.divergence_m)"
            )
    return out


def flight_warnings(scn: SwarmScenario, method: str, run: MissionRun) -> list[str]:
    """What a reader must know about a flight: failures, followers on DR for long, bad
    geometry."""
    out = []
    if run.failed:
        out.append(run.failed)
    for name, v in run.vehicles.items():
        if name == LEADER:
            continue
        for a, b in v.outcome.get("dr_gaps_s", []):
            out.append(
                f"run {run.run} {method} {name}: no accepted range for {b - a:.0f} s "
                f"(t = {a:.0f}-{b:.0f} s): navigated on dead reckoning"
            )
        h = v.outcome.get("mean_fix_hdop", 0.0)
        if h > scn.navigation.hdop_warning:
            out.append(
                f"run {run.run} {method} {name}: mean HDOP {h:.1f} at its fixes "
                f"(> {scn.navigation.hdop_warning:g}): poor geometry"
            )
    return out


@store.plain_data("missions.swarm.SwarmRunResult")
@dataclass
class SwarmRunResult:
    """The flights of one run (one per method, same draws), as plain data.

    Attributes:
        run: run index.
        failed: the first flight failure, or ``None``.
        flights: per method, the flight.
        metrics: per method, per follower (and ``leader``), the metrics.
        warnings: what the report must say about these flights.
        diverged: one line per aided estimate that diverged (:func:`divergences`).
        team: on the acoustic network, per method flown, the team comparison on that flight's
            measurements (:func:`tasks.missions.swarm.team.team_comparison`: team method ->
            vehicle -> metrics); empty off the network.
    """

    run: int
    failed: str | None
    flights: dict[str, MissionRun]
    metrics: dict[str, dict[str, dict[str, float]]]
    warnings: list[str]
    diverged: list[str]
    team: dict[str, dict[str, dict[str, dict[str, float]]]] = field(default_factory=dict)


def fly_run(scn: SwarmScenario, seed: int, run: int) -> SwarmRunResult:
    """Fly one run with every method of the scenario and compute its metrics (on the acoustic
    network: each vehicle's ``network`` table from what it received, and the team comparison
    on each flight's measurements)."""
    flights, metrics, warnings, diverged, failed = {}, {}, [], [], None
    team: dict[str, dict[str, dict[str, dict[str, float]]]] = {}
    stations = station_offsets(scn)
    for method in scn.methods():
        res = fly(SwarmMission(method), scn, seed, run)
        failed = failed or res.failed
        flights[method] = res
        for v in res.vehicles.values():
            rows = v.outcome.pop(NETWORK, None)
            if rows is not None:
                v.fixes[NETWORK] = network_table(rows)
        m: dict[str, dict[str, float]] = {}
        if LEADER in res.vehicles and len(res.vehicles[LEADER]["t"]):
            m[LEADER] = leader_metrics(scn, res)
            for name, st in zip(FOLLOWERS, stations, strict=False):
                if name in res.vehicles:
                    m[name] = follower_metrics(scn, res, name, st)
        metrics[method] = m
        warnings += flight_warnings(scn, method, res)
        diverged += divergences(scn, run, method, m)
        if scn.followers.network.enabled and m:
            team[method] = team_comparison(scn, res)
    return SwarmRunResult(run, failed, flights, metrics, warnings, diverged, team)
