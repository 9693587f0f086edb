"""Figures of a mission run (PNG and PDF, project style): route, errors and the vehicle's state,
and the drawing helpers the missions share (way-point circles, current arrows, unwrapped
headings)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import velocity_from_course_speed
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.scenario import MissionScenario


def circle(cx: float, cy: float, r: float, z: float = 0.0, n: int = 48) -> NDArray[np.float64]:
    """A horizontal circle as a closed polyline, shape (n + 1, 3), m, world."""
    ring = (cx, cy) + velocity_from_course_speed(np.linspace(0, 2 * np.pi, n + 1), r)
    return np.column_stack([ring, np.full(n + 1, z)])


def _title_words(name: str) -> str:
    """A mission's registry name in words: ``"mission/survey"`` -> ``"Survey mission"``."""
    return f"{name.split('/')[-1].replace('_', ' ').replace('-', ' ').capitalize()} mission"


def unwrapped_heading_deg(
    heading_rad: NDArray[np.float64], command_rad: NDArray[np.float64] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Heading without the 0/360 jump, and a command drawn beside it.

    Args:
        heading_rad: headings, shape (T,), rad clockwise from north (any wrap).
        command_rad: commanded course, shape (T,), rad, or ``None``.

    Returns:
        ``(heading_deg (T,), command_deg (T,) or None)``: the heading unwrapped (continuous); the
        command placed within 180 deg of it (its wrapped difference added), so both cross north
        without a vertical line.
    """
    h = np.unwrap(np.asarray(heading_rad, dtype=float))
    if command_rad is None:
        return np.degrees(h), None
    d = np.angle(np.exp(1j * (np.asarray(command_rad, dtype=float) - h)))
    return np.degrees(h), np.degrees(h + d)


def moving_mean(values: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Centred moving mean over ``n`` samples (shorter at the ends), shape as ``values``."""
    v = np.asarray(values, dtype=float)
    n = max(1, min(int(n), len(v)))
    c = np.concatenate([[0.0], np.cumsum(v)])
    lo = np.clip(np.arange(len(v)) - n // 2, 0, len(v))
    hi = np.clip(lo + n, 0, len(v))
    return (c[hi] - c[lo]) / np.maximum(hi - lo, 1)


def waypoint_marks(ax, waypoints, z_color: str | None = None) -> None:
    """Draw way-points as acceptance circles labelled with their index (as in the tables)."""
    from tasks.core import style

    col = z_color or style.color("waypoint")
    for i, w in enumerate(waypoints):
        c = circle(w.east_m, w.north_m, w.acceptance_radius_m)
        ax.plot(c[:, 0], c[:, 1], color=col, lw=0.8, zorder=2)
        ax.annotate(
            f"WP{i}",
            (w.east_m + w.acceptance_radius_m * 0.7, w.north_m + w.acceptance_radius_m * 0.7),
            textcoords="offset points",
            xytext=(1, 1),
            ha="left",
            va="bottom",
            color=col,
            fontsize=6.5,
            fontweight="bold",
            zorder=6,
        )
    if len(waypoints):
        ax.plot([], [], color=col, lw=0.8, label="way-point (acceptance circle)")


def current_arrow(
    ax, current_en: NDArray[np.float64], label: str, color: str, ls="-", slot: int = 0
) -> None:
    """An arrow of the mean current in the top left corner of the axes (its length in the
    legend's words: the speed, m/s); drawn in axes coordinates so it never covers the route."""
    speed = float(np.hypot(*current_en[:2]))
    if speed <= 0:
        return
    u = np.asarray(current_en[:2]) / speed
    x0, y0 = 0.09 + 0.17 * slot, 0.9
    ax.annotate(
        "",
        xy=(x0 + 0.07 * u[0], y0 + 0.07 * u[1]),
        xytext=(x0 - 0.07 * u[0], y0 - 0.07 * u[1]),
        xycoords="axes fraction",
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.4, "ls": ls},
        zorder=7,
    )
    ax.plot([], [], color=color, lw=1.4, ls=ls, label=f"{label} {speed:.2f} m/s (arrow: direction)")


MISSION_FIGURES = ("route", "errors", "state")
"""The figures of a mission run, in the order they are listed."""


def mission_figures(
    name: str,
    scn: MissionScenario,
    run: MissionRun,
    runs: list[MissionRun],
    out,
    which: tuple[str, ...] = MISSION_FIGURES,
) -> list[str]:
    """Route, errors and vehicle state of the recorded run (PNG and PDF, project style).

    Args:
        name: the mission's registry name (in the titles).
        scn: its scenario.
        run: the recorded run.
        runs: every run of the batch (the route figure draws the others' true tracks).
        out: the folder to write into.
        which: the figures to draw, names of :data:`MISSION_FIGURES` (the report draws them in
            two processes).

    Returns:
        The files written, in the order of :data:`MISSION_FIGURES`.
    """
    from tasks.core import style  # matplotlib only when figures are drawn

    draw = {"route": _route, "errors": _errors, "state": _state}
    files: list[str] = []
    with style.context():
        for fig in MISSION_FIGURES:
            if fig in which:
                files += draw[fig](name, scn, run, runs, out, style)
    return files


def _route(name, scn, run, runs, out, style) -> list[str]:
    a = run.lead
    words = f"{_title_words(name)}, run {run.run}"
    # the figure as tall as the route (equal scales), the legend below it
    xy = np.concatenate(
        [a["truth_pos"][:, :2], a["ekf_pos"][:, :2], a["dr_pos"][:, :2]]
        + [np.array([[w.east_m, w.north_m]]) for w in scn.guidance.waypoints]
    )
    span = np.ptp(xy, axis=0) + 2.0 * max(
        [w.acceptance_radius_m for w in scn.guidance.waypoints] + [10.0]
    )
    ratio = float(span[1] / span[0])
    axes_h = min(6.5, 0.9 * style.PAGE_IN * ratio)
    width = float(np.clip(axes_h / ratio / 0.85, 5.0, style.PAGE_IN))
    fig, ax = style.subplots(width, axes_h + 1.5)
    others = [o for o in runs if o is not run and o.vehicles]
    for i, other in enumerate(others):
        p = other.lead["truth_pos"]
        ax.plot(
            p[:, 0], p[:, 1], color="0.75", lw=0.5, label="other runs (truth)" if i == 0 else "_"
        )
    fx = a.fixes.get("usbl")
    if fx:
        pos, ok = fx["position"].values, fx["accepted"].values.astype(bool)
        ax.plot(
            pos[ok, 0],
            pos[ok, 1],
            **style.line("USBL", label="USBL fixes (accepted)", ms=2, alpha=0.6, zorder=1),
        )
        if (~ok).any():
            ax.plot(
                pos[~ok, 0],
                pos[~ok, 1],
                "x",
                color=style.color("USBL"),
                ms=4,
                mew=0.8,
                label="USBL fixes (rejected by the gate)",
                zorder=1,
            )
    gp = fix_positions(a, "gps")
    if len(gp):
        ax.plot(gp[:, 0], gp[:, 1], **style.line("GPS", label="GPS fixes", ms=4, zorder=5))
    ax.plot(a["dr_pos"][:, 0], a["dr_pos"][:, 1], **style.line("DR", zorder=3))
    ax.plot(a["ekf_pos"][:, 0], a["ekf_pos"][:, 1], **style.line("EKF", zorder=4))
    ax.plot(a["truth_pos"][:, 0], a["truth_pos"][:, 1], **style.line("truth", lw=1.2, zorder=3))
    ax.plot(*a["truth_pos"][0, :2], "o", color="k", ms=4, mfc="white", zorder=6, label="start")
    waypoint_marks(ax, scn.guidance.waypoints)
    if scn.sensors.use_usbl:
        ax.plot(scn.transceiver_east_m, scn.transceiver_north_m, "k^", ms=6, label="transceiver")
    current_arrow(ax, a["truth_current"].mean(axis=0), "mean current", style.color("current"))
    if "ekf_current" in a.ticks:
        est = a["ekf_current"]
        current_arrow(ax, est[-1], "EKF current at the end", style.color("EKF"), "--", 1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"{words}: route, steering on the {scn.navigation.steer_on.upper()} estimate")
    style.figure_legend(fig, (ax,), ncol=3 if width > 6.0 else 2)
    return style.save(fig, out / "route.png")


def _errors(name, scn, run, runs, out, style) -> list[str]:
    """Horizontal distance on a log axis, then the EKF's east and north errors with its own
    +-2 sigma."""
    a = run.lead
    t = a["t"]
    words = f"{_title_words(name)}, run {run.run}"
    k = 2.0
    e_ekf = a["ekf_pos"] - a["truth_pos"]
    e_dr = a["dr_pos"] - a["truth_pos"]
    P = a["ekf_P"]
    sd = np.sqrt(np.maximum(np.stack([P[:, 0, 0], P[:, 1, 1]], axis=1), 0.0))
    fig, axs = style.subplots("page", 5.2, 3, 1, sharex=True)
    for key, e in (("DR", e_dr), ("EKF", e_ekf)):
        d = np.hypot(e[:, 0], e[:, 1])
        keep = d > 0
        axs[0].plot(t[keep], d[keep], **style.line(key))
    radius = k * np.hypot(sd[:, 0], sd[:, 1])
    axs[0].plot(t, radius, **style.line("EKF", label=f"EKF {k:g}$\\sigma$ radius", ls=":"))
    axs[0].set_yscale("log")
    style.log_ticks(axs[0])
    axs[0].set_ylabel(style.label("horizontal error", "m"))
    axs[0].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    for j, (ax, comp) in enumerate(zip(axs[1:], ("east", "north"), strict=True)):
        ax.fill_between(
            t,
            -k * sd[:, j],
            k * sd[:, j],
            color=style.color("EKF"),
            alpha=0.18,
            lw=0,
            label=f"EKF $\\pm${k:g}$\\sigma$",
        )
        ax.plot(t, e_ekf[:, j], **style.line("EKF", label=f"EKF {comp} error"))
        ax.set_ylabel(style.label(f"{comp} error", "m"))
        # the scale of the error and of most of the bound (a bound that is large only before
        # the first fix is drawn past the axis, not squashing the rest)
        lim = 1.25 * max(float(np.max(np.abs(e_ekf[:, j]))), float(np.percentile(k * sd[:, j], 90)))
        ax.set_ylim(-lim, lim)
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    axs[-1].set_xlabel(style.label("time", "s"))
    inside = np.mean(np.all(np.abs(e_ekf[:, :2]) <= k * sd, axis=1))
    fig.suptitle(
        f"{words}: navigation error (EKF inside {k:g}$\\sigma$ on both axes "
        f"{100 * inside:.0f} % of the time)",
    )
    style.panel_letters(axs)
    return style.save(fig, out / "errors.png")


def _state(name, scn, run, runs, out, style) -> list[str]:
    """Depth, heading, speed and motor power against their commands."""
    a = run.lead
    t = a["t"]
    words = f"{_title_words(name)}, run {run.run}"
    fig, axs = style.subplots("page", 6.4, 4, 1, sharex=True)
    axs[0].plot(t, -a["truth_pos"][:, 2], **style.line("truth", label="true depth"))
    axs[0].plot(t, a["guidance_depth"], **style.line("command"))
    axs[0].invert_yaxis()
    axs[0].set_ylabel(style.label("depth", "m"))
    h, c = unwrapped_heading_deg(a["truth_rph"][:, 2], a["guidance_course"])
    axs[1].plot(t, h, **style.line("truth", label="true heading (unwrapped)"))
    axs[1].plot(t, c, **style.line("command", label="commanded course"))
    axs[1].set_ylabel(style.label("heading", "deg"))
    axs[2].plot(
        t, np.hypot(*a["truth_vel_water"][:, :2].T), **style.line("EKF", label="through water")
    )
    axs[2].plot(
        t, np.hypot(*a["truth_vel"][:, :2].T), **style.line("DR", label="over ground", ls="-")
    )
    axs[2].plot(t, a["guidance_speed"], **style.line("command"))
    axs[2].set_ylabel(style.label("speed", "m/s"))
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    n5 = max(1, round(5.0 / dt))
    axs[3].plot(t, a["motor_power"], color="0.75", lw=0.4, label="per tick")
    axs[3].plot(
        t,
        moving_mean(a["motor_power"], n5),
        color=style.PALETTE["orange"],
        lw=1.0,
        label="mean over 5 s",
    )
    axs[3].set_ylabel(style.label("motor power", "W"))
    axs[3].set_xlabel(style.label("time", "s"))
    for x in axs:
        if x.get_legend_handles_labels()[0]:
            x.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), borderaxespad=0.0)
    fig.suptitle(f"{words}: vehicle state")
    style.panel_letters(axs)
    return style.save(fig, out / "state.png")


def fix_positions(v: VehicleRun, device: str) -> NDArray[np.float64]:
    """The fix positions of a device, shape (k, 3), m, world (k = 0 when there are none)."""
    fx = v.fixes.get(device)
    return fx["position"].values if fx else np.zeros((0, 3))
