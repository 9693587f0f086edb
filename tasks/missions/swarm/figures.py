"""The figure and the recording of one ``mission/swarm`` run (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np

from tasks.closed_loop.result import MissionRun
from tasks.missions.swarm.run import SwarmRunResult, leader_course_true
from tasks.missions.swarm.scenario import FOLLOWERS, LEADER, SwarmScenario, station_offsets

VEHICLE_COLORS = (
    "black",
    "blue",
    "vermillion",
    "bluish_green",
    "orange",
    "sky_blue",
    "reddish_purple",
    "olive",
    "wine",
    "grey",
)
"""The figure style's colours of the leader, f1, f2 ... (repeated beyond ten vehicles)."""


def swarm_figure(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out) -> list[str]:
    """Tracks of the recorded run (every vehicle's truth and estimate, first method) and each
    follower's true distance to its station over time, per method (PNG and PDF, project
    style)."""
    from tasks.core import style

    with style.context():
        return _draw_swarm(name, scn, rec, methods, out, style)


def _draw_swarm(name: str, scn: SwarmScenario, rec: SwarmRunResult, methods, out, style):
    pal = style.PALETTE
    vehicle_colors = itertools.cycle([pal[k] for k in VEHICLE_COLORS])
    method_names = {"ga1": "GA1", "ga2": "GA2", "ekf": "EKF", "dr": "DR"}
    fig, axs = style.subplots("page", 3.8, 1, 2)
    flight = rec.flights[methods[0]]
    ax = axs[0]
    for (vn, v), c in zip(flight.vehicles.items(), vehicle_colors, strict=False):
        ax.plot(v["truth_pos"][:, 0], v["truth_pos"][:, 1], "-", color=c, lw=1.0, label=vn)
        ax.plot(v["ekf_pos"][:, 0], v["ekf_pos"][:, 1], ":", color=c, lw=0.8, label="_")
    ax.plot([], [], "k:", lw=0.8, label="estimates")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"Truth and estimates ({method_names.get(methods[0], methods[0])})")
    ax.legend(loc="best")
    ax = axs[1]
    tick = scn.timing.control_tick_s
    dashes = ["-", "--", "-.", ":"]
    for m in methods:
        f = rec.flights[m]
        if LEADER not in f.vehicles:
            continue
        lead = f.vehicles[LEADER]
        course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
        for j, (vn, st) in enumerate(zip(FOLLOWERS, station_offsets(scn), strict=False)):
            if vn not in f.vehicles:
                continue
            v = f.vehicles[vn]
            n = min(len(v["t"]), len(lead["t"]))
            b = math.radians(st.relative_bearing_deg)
            sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
                [np.sin(course[:n] + b), np.cos(course[:n] + b)]
            )
            ax.plot(
                v["t"][:n],
                np.maximum(np.hypot(*(v["truth_pos"][:n, :2] - sp).T), 1e-2),
                dashes[j % 4],
                color=style.color(method_names.get(m, m)),
                lw=0.8,
                label=f"{vn} {method_names.get(m, m)}",
            )
    ax.set_yscale("log")
    style.log_ticks(ax)
    ax.set_xlabel(style.label("time", "s"))
    ax.set_ylabel(style.label("true distance to the station", "m"))
    style.title(ax, "Station-keeping error")
    ax.legend(ncol=2, loc="best")
    return style.save(fig, out / "swarm.png")


def record_swarm(name: str, scn: SwarmScenario, flights: dict[str, MissionRun], out) -> str:
    """``recording.rrd`` of a run: every method's flight in one file, each under its own subtree
    and 3-D view (:func:`tasks.closed_loop.recording.record_flights`): every vehicle's hull,
    truth and estimate labelled with the vehicle and the method, the followers' range circles
    and their true distance to the station (:func:`with_station_error`), the leader's
    way-points, the transceiver and the seabed."""
    from tasks.closed_loop.recording import mission_scene, record_flights

    scene = mission_scene(scn, guidance=scn.leader.guidance, transceiver=True)
    flown = {m: with_station_error(scn, f) for m, f in flights.items() if f.vehicles}
    return record_flights(out, name, scene, flown)


def with_station_error(scn: SwarmScenario, flight: MissionRun) -> MissionRun:
    """The flight with each follower's true distance to its station as a per-tick column,
    ``station_error`` (m): from the station point of the leader's true position and true course
    (:func:`~tasks.missions.swarm.run.leader_course_true`), as the figure draws it; the recording
    shows it among the mission's columns. A copy: the run data is not changed."""
    from tasks.core.export import Column

    if LEADER not in flight.vehicles:
        return flight
    lead = flight.vehicles[LEADER]
    tick = scn.timing.control_tick_s
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
    vehicles = dict(flight.vehicles)
    for vn, st in zip(FOLLOWERS, station_offsets(scn), strict=False):
        v = vehicles.get(vn)
        if v is None:
            continue
        n = min(len(v["t"]), len(lead["t"]))
        b = math.radians(st.relative_bearing_deg)
        sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
            [np.sin(course[:n] + b), np.cos(course[:n] + b)]
        )
        err = np.full(len(v["t"]), np.nan)
        err[:n] = np.hypot(*(v["truth_pos"][:n, :2] - sp).T)
        what = "true distance to the station (the leader's true position and course)"
        col = Column(err, "m", what, (), n < len(err))
        vehicles[vn] = dataclasses.replace(v, ticks={**v.ticks, "station_error": col})
    return dataclasses.replace(flight, vehicles=vehicles)
