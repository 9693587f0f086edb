"""The figure and the recording of one ``mission/swarm`` run (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

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
COLORS_V = [
    (0, 0, 0),
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (230, 159, 0),
    (86, 180, 233),
    (204, 121, 167),
    (153, 153, 51),
    (136, 34, 85),
    (127, 127, 127),
]
"""Recording colours of the leader, f1, f2 ... (:data:`VEHICLE_COLORS` as RGB)."""


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


def record_swarm(name: str, scn: SwarmScenario, run: MissionRun, method: str, out) -> str:
    """``recording.rrd`` of a flight: every vehicle (hull, truth, estimate), each follower's
    range circle at each fix (the leader position it used, the horizontal range), its HDOP, its
    station and navigation errors."""
    import rerun as rr

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from tasks.closed_loop.report import circle
    from tasks.core.recording import TIMELINE, Recording

    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}/{method}")
    r = rec.rec
    tick = scn.timing.control_tick_s
    lead = run.vehicles[LEADER]
    course = leader_course_true(lead, max(1, round(scn.leader.velocity_window_s / tick)))
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, -20.0])
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    stations = dict(zip(FOLLOWERS, station_offsets(scn), strict=False))
    plots = []
    for (vn, v), color in zip(run.vehicles.items(), itertools.cycle(COLORS_V)):
        t = v["t"]
        r.send_columns(
            f"world/{vn}/vehicle",
            indexes=[rr.TimeColumn(TIMELINE, duration=t)],
            columns=rr.Transform3D.columns(
                translation=v["truth_pos"], quaternion=quat_wxyz_to_xyzw(v["truth_quat_wxyz"])
            ),
        )
        r.log(
            f"world/{vn}/vehicle/hull",
            rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"),
            static=True,
        )
        rec.track(f"{vn}/truth", t, v["truth_pos"], color)
        light = tuple(int(c + (255 - c) * 0.5) for c in color)
        rec.track(f"{vn}/estimate", t, v["ekf_pos"], light, radius_m=0.4)
        if vn == LEADER:
            continue
        fx = v.fixes.get("modem")
        if fx:
            z = -scn.station.depth_m
            for ta, rng_h, ce, cn, ok in zip(
                fx["t_arrival"].values,
                fx["horizontal_range"].values,
                fx["centre_east"].values,
                fx["centre_north"].values,
                fx["accepted"].values,
                strict=True,
            ):
                r.set_time(TIMELINE, duration=float(ta))
                if rng_h > 0:
                    r.log(
                        f"world/{vn}/range_circle",
                        rr.LineStrips3D(
                            [circle(float(ce), float(cn), float(rng_h), z)],
                            colors=color if ok else (150, 150, 150),
                            radii=0.08,
                        ),
                    )
            r.reset_time()
        rec.scalars(f"hdop/{vn}", t, v["hdop"], color, f"{vn} HDOP")
        st = stations[vn]
        n = min(len(t), len(lead["t"]))
        b = math.radians(st.relative_bearing_deg)
        sp = lead["truth_pos"][:n, :2] + st.distance_m * np.column_stack(
            [np.sin(course[:n] + b), np.cos(course[:n] + b)]
        )
        rec.track(
            f"{vn}/station",
            t[:n],
            np.column_stack([sp, np.full(n, -scn.station.depth_m)]),
            (255, 127, 14),
            radius_m=0.3,
            strip=False,
        )
        rec.scalars(
            f"station_error/{vn}",
            t[:n],
            np.hypot(*(v["truth_pos"][:n, :2] - sp).T),
            color,
            f"{vn} true distance to station (m)",
        )
        rec.scalars(
            f"errors/{vn}",
            t,
            np.hypot(*(v["ekf_pos"] - v["truth_pos"])[:, :2].T),
            color,
            f"{vn} {method.upper()} position error (m)",
        )
        plots = ["hdop", "station_error", "errors"]
    rec.blueprint(*plots)
    rec.close()
    return "recording.rrd"
