"""One vehicle of a mission recording (:mod:`tasks.closed_loop.recording`), drawn from its run
data alone (:class:`~tasks.closed_loop.result.VehicleRun`) and the estimates its navigation part
declared (:attr:`~tasks.closed_loop.result.VehicleRun.estimates`).

Entity paths, with ``<tag>`` the vehicle's name (``<flight>/<vehicle>`` when the recording holds
several flights) and ``<m>`` a method's slug (``ekf``, ``ga1``, ``trn_pf``):

* ``world/<tag>/body``: the true pose (``Transform3D`` per tick); ``body/hull`` its mesh, the
  fins and tail as child transforms at their true joint angles (:data:`VEHICLE_PARTS`);
* ``world/<tag>/truth``, ``world/<tag>/<m>``: ``position`` (a labelled point per tick) and
  ``path`` (the whole track); ``world/<tag>/<m>/covariance``: the 1-sigma ellipsoid once per
  second;
* ``world/<tag>/<device>/{accepted,rejected}``: the fixes (``latest`` per fix time, ``all``);
  ``world/<tag>/<device>/range``: each range's horizontal circle (modem);
* ``world/<tag>/current/{true,<m>}``: the current at the vehicle, arrows x20 once per second;
* time series ``<plot>/<tag>/<series>`` under the plots ``errors``, ``consistency`` (NEES of every
  estimate with a covariance, its chi-square band, the fixes' NIS), ``innovation``, ``fixes``,
  ``current``, ``depth``, ``heading``, ``speed``, ``power``, ``actuators``, ``guidance`` and
  ``mission`` (the mission's own scalar columns);
* ``events/<tag>``: the vehicle's events in words (:func:`mission_events`).
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.figures import circle, unwrapped_heading_deg
from tasks.closed_loop.result import EstimateTrack, VehicleRun

Color = tuple[int, int, int]

VEHICLE_PARTS: tuple[tuple[str, str, str, tuple[float, float, float], tuple[float, ...]], ...] = (
    # entity under world/<tag>/body, mesh, (column, component), joint axis (body), pose in parent
    (
        "fin_port",
        "lateral_fin_port.obj",
        "truth_fin_angles:0",
        (0.0, -1.0, 0.0),
        (0.2, 0.105, -0.04),
    ),
    (
        "fin_starboard",
        "lateral_fin_starboard.obj",
        "truth_fin_angles:1",
        (0.0, -1.0, 0.0),
        (0.2, -0.105, -0.04),
    ),
    ("peduncle", "peduncle.obj", "truth_tail_angles:0", (0.0, 0.0, 1.0), (-0.35, 0.0, 0.0)),
    (
        "peduncle/caudal_fin",
        "caudal_fin.obj",
        "truth_tail_angles:1",
        (0.0, 0.0, 1.0),
        (-0.45, 0.0, 0.0),
    ),
)
"""The moving bodies of ``models/bauv/bauv.xml`` (body positions in their parent body, m; hinge
axes, body frame), each drawn with its visual mesh at its true joint angle of every tick."""

GUIDANCE_MODES = ("transit", "ascend", "surface", "dive", "done")
"""Names of the ``guidance_mode`` values (:data:`tasks.closed_loop.result.TICK_COLUMNS`)."""

MEASURED_FIXES = ("usbl", "gps")
"""Fix tables whose ``position`` is the measurement itself (their innovation is the fix minus the
estimate); a modem table's ``position`` is the estimate after the range."""

CURRENT_ARROW_SCALE = 20.0
"""The current's arrows are drawn this many times longer than 1 m per m/s (to be visible)."""


def slug(method: str) -> str:
    """A method's name as an entity path part: ``"TRN-PF"`` -> ``"trn_pf"``."""
    return re.sub(r"[^0-9a-z]+", "_", method.lower()).strip("_") or "estimate"


def estimate_positions(v: VehicleRun, e: EstimateTrack) -> NDArray[np.float64]:
    """An estimate's positions, shape (T, 3), m, world ENU: a horizontal (T, 2) estimate is drawn
    at the true depth."""
    p = np.asarray(v[e.column], dtype=float)
    if p.shape[1] == 2:
        p = np.column_stack([p, v["truth_pos"][:, 2]])
    return p


def covariance_matrices(v: VehicleRun, e: EstimateTrack) -> NDArray[np.float64] | None:
    """An estimate's declared covariance as matrices, shape (T, d, d) with d = 3 (3-D) or 2
    (horizontal), m^2; a column stored flat, (T, d * d), is reshaped; None without one."""
    if e.covariance is None or e.covariance not in v.ticks:
        return None
    P = np.asarray(v[e.covariance], dtype=float)
    if P.ndim == 2 and P.shape[1] in (4, 9):
        d = 2 if P.shape[1] == 4 else 3
        P = P.reshape(len(P), d, d)
    if P.ndim != 3 or P.shape[1] != P.shape[2] or P.shape[1] not in (2, 3):
        return None
    return P


def estimate_covariance(v: VehicleRun, e: EstimateTrack) -> NDArray[np.float64] | None:
    """An estimate's covariance, shape (T, 3, 3), m^2 (a horizontal one with a zero vertical: a
    flat ellipse), or None without one."""
    P = covariance_matrices(v, e)
    if P is not None and P.shape[1] == 2:
        P3 = np.zeros((len(P), 3, 3))
        P3[:, :2, :2] = P
        return P3
    return P


def nees(v: VehicleRun, e: EstimateTrack) -> tuple[NDArray[np.float64], int] | None:
    """An estimate's NEES at each tick against the truth, ``e^T P^-1 e`` over the covariance's
    dimensions (3: 3-D; 2: horizontal), with its degrees of freedom; None without a covariance.
    Ticks whose covariance is singular or not finite give NaN (left out of the series)."""
    P = covariance_matrices(v, e)
    if P is None:
        return None
    d = P.shape[1]
    err = (np.asarray(v[e.column], dtype=float)[:, :d] - v["truth_pos"][:, :d])[..., None]
    out = np.full(len(P), np.nan)
    ok = np.isfinite(P).all(axis=(1, 2)) & np.isfinite(err[..., 0]).all(axis=1)
    ok[ok] &= np.abs(np.linalg.det(P[ok])) > 0
    out[ok] = np.einsum("ti,ti->t", err[ok, :, 0], np.linalg.solve(P[ok], err[ok])[..., 0])
    return out, d


def record_body(r, root: str, v: VehicleRun, t: NDArray[np.float64]) -> None:
    """The hull posed by the truth at ``<root>/body`` and the fins and tail at their true joint
    angles (``truth_fin_angles``, ``truth_tail_angles``) as its child transforms; the dorsal fin,
    fixed to the hull, once."""
    import rerun as rr

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from tasks.core.recording import TIMELINE

    assets = MODEL_DIR / "assets"
    body = f"{root}/body"
    r.send_columns(
        body,
        indexes=[rr.TimeColumn(TIMELINE, duration=t)],
        columns=rr.Transform3D.columns(
            translation=v["truth_pos"], quaternion=quat_wxyz_to_xyzw(v["truth_quat_wxyz"])
        ),
    )
    r.log(f"{body}/hull", rr.Asset3D(path=assets / "hull.obj"), static=True)
    r.log(
        f"{body}/dorsal_fin",
        rr.Transform3D(translation=[0.05, 0.0, 0.15]),
        rr.Asset3D(path=assets / "dorsal_fin.obj"),
        static=True,
    )
    for entity, mesh, source, axis, pos in VEHICLE_PARTS:
        col, comp = source.split(":")
        if col not in v.ticks:
            continue  # run data written before the joint angles were recorded
        half = 0.5 * v[col][:, int(comp)]
        ax = np.asarray(axis, dtype=float)
        quat_xyzw = np.column_stack([np.sin(half)[:, None] * ax, np.cos(half)])
        r.send_columns(
            f"{body}/{entity}",
            indexes=[rr.TimeColumn(TIMELINE, duration=t)],
            columns=rr.Transform3D.columns(
                translation=np.tile(pos, (len(t), 1)), quaternion=quat_xyzw
            ),
        )
        r.log(f"{body}/{entity}/mesh", rr.Asset3D(path=assets / mesh), static=True)


def record_vehicle(rec, tag: str, label: str, v: VehicleRun, color: Color) -> None:
    """Everything of one vehicle (module docstring) into a recording.

    Args:
        rec: the :class:`~tasks.core.recording.Recording`.
        tag: the vehicle's entity path part (``bauv``, ``ga1/f1``).
        label: its name in labels and legends (``f1``, ``f1 (ga1)``).
        v: its run data.
        color: its colour (the truth's, 0-255 RGB).
    """
    from tasks.core import style

    t = v["t"]
    root = f"world/{tag}"
    record_body(rec.rec, root, v, t)
    rec.track(f"{tag}/truth", t, v["truth_pos"], color, label=f"{label} truth")
    every = max(1, round(1.0 / max(float(t[1] - t[0]), 1e-9))) if len(t) > 1 else 1
    for e in v.estimates:
        if e.column not in v.ticks:
            continue
        m = slug(e.method)
        c = style.rgb(e.method)
        pos = estimate_positions(v, e)
        name = f"{label} {e.method}"
        rec.track(f"{tag}/{m}", t, pos, c, radius_m=-4.0, label=name)
        P = estimate_covariance(v, e)
        if P is not None:
            rec.ellipsoids(f"{tag}/{m}", t[::every], pos[::every], P[::every], c)
        rec.scalars(
            f"errors/{tag}/{m}",
            t,
            np.hypot(*(pos - v["truth_pos"])[:, :2].T),
            c,
            f"{name} horizontal error (m)",
        )
        n = nees(v, e)
        if n is not None:
            record_nees(rec, f"consistency/{tag}/{m}", t, *n, c, name)
    record_fixes(rec, tag, label, v)
    record_current(rec, tag, label, v, every)
    record_commands(rec, tag, label, v)
    record_mission_columns(rec, tag, label, v)
    rec.events(f"events/{tag}", *mission_events(v, label))


def record_nees(rec, entity, t, values, dof: int, color: Color, name: str, p=0.95) -> None:
    """A NEES series and the chi-square band of one run (probability ``p``) beside it."""
    from scipy.stats import chi2  # imported with the recording only

    rec.scalars(f"{entity}_nees", t, values, color, f"{name} NEES (dof {dof})")
    lo, hi = chi2.ppf(np.array([(1 - p) / 2, (1 + p) / 2]), dof)
    for which, val in (("low", lo), ("high", hi)):
        rec.scalars(
            f"{entity}_nees_band_{which}",
            t[[0, -1]],
            np.full(2, val),
            (0, 158, 115),
            f"{name}: {100 * p:g} % chi-square band, one run, dof {dof} ({val:.2f})",
        )


def record_fixes(rec, tag: str, label: str, v: VehicleRun) -> None:
    """Every fix table: accepted and rejected fixes as points, the accepted flag as a series, the
    innovation of measured fixes (the fix minus the first declared estimate at its time of
    validity), the NIS where the table has one, and a range's horizontal circle (modem)."""
    from tasks.core import style

    first = next((e for e in v.estimates if e.column in v.ticks), None)
    t = v["t"]
    for device, fx in v.fixes.items():
        if not fx or "t_arrival" not in fx or "accepted" not in fx:
            continue
        ta = fx["t_arrival"].values
        ok = fx["accepted"].values.astype(bool)
        c = style.rgb(device.upper())
        name = f"{label} {device.upper()}"
        if "position" in fx:
            pos = fx["position"].values
            for flag, which, cc in ((ok, "accepted", c), (~ok, "rejected", (230, 0, 0))):
                if flag.any():
                    rec.fixes(f"{tag}/{device}/{which}", ta[flag], pos[flag], cc)
        rec.scalars(
            f"fixes/{tag}/{device}_accepted",
            ta,
            ok.astype(float),
            c,
            f"{name} fix accepted (1) or rejected (0)",
        )
        if device in MEASURED_FIXES and first is not None and "t_valid" in fx and "position" in fx:
            est = estimate_positions(v, first)
            tv = fx["t_valid"].values
            inn = fx["position"].values[:, :2] - np.column_stack(
                [np.interp(tv, t, est[:, j]) for j in range(2)]
            )
            for j, axis in enumerate(("east", "north")):
                rec.scalars(
                    f"innovation/{tag}/{device}_{axis}",
                    ta,
                    inn[:, j],
                    c if j == 0 else (0, 114, 178),
                    f"{name} fix - {first.method}, {axis} (m)",
                )
        if "nis" in fx:
            dof = 3 if device == "usbl" else 2
            rec.scalars(
                f"consistency/{tag}/nis_{device}",
                ta,
                fx["nis"].values,
                c,
                f"{name} NIS (dof {dof})",
            )
        if {"horizontal_range", "centre_east", "centre_north"} <= set(fx):
            record_ranges(rec, f"world/{tag}/{device}/range", fx, v, c)
        if {"beacon_east", "beacon_north", "beacon_up", "t_valid"} <= set(fx):
            record_bearings(rec, f"world/{tag}/{device}", fx, v, c)


def record_ranges(rec, entity: str, fx, v: VehicleRun, color: Color) -> None:
    """Each range's horizontal circle around the centre it used, at its arrival time and at the
    vehicle's true depth then (grey when the range was refused)."""
    import rerun as rr

    from tasks.core.recording import TIMELINE

    r = rec.rec
    t = v["t"]
    z = v["truth_pos"][:, 2]
    for ta, rng, ce, cn, ok in zip(
        fx["t_arrival"].values,
        fx["horizontal_range"].values,
        fx["centre_east"].values,
        fx["centre_north"].values,
        fx["accepted"].values,
        strict=True,
    ):
        if not rng > 0:
            continue
        r.set_time(TIMELINE, duration=float(ta))
        r.log(
            entity,
            rr.LineStrips3D(
                [circle(float(ce), float(cn), float(rng), float(np.interp(ta, t, z)))],
                colors=color if ok else (150, 150, 150),
                radii=-1.0,
            ),
        )
    r.reset_time()


def record_bearings(rec, entity: str, fx, v: VehicleRun, color: Color) -> None:
    """Each bearing as a ray from the vehicle's true position at its time of validity to the
    beacon it saw, at its arrival time (``<entity>/accepted`` in the device's colour,
    ``<entity>/rejected`` in red): every set of one time as one row."""
    import rerun as rr

    from tasks.core.recording import TIMELINE

    r = rec.rec
    t = v["t"]
    tv = fx["t_valid"].values
    ta = fx["t_arrival"].values
    ok = fx["accepted"].values.astype(bool)
    beacon = np.column_stack([fx[k].values for k in ("beacon_east", "beacon_north", "beacon_up")])
    at = np.column_stack([np.interp(tv, t, v["truth_pos"][:, j]) for j in range(3)])
    for which, flag, c in (("accepted", ok, color), ("rejected", ~ok, (230, 0, 0))):
        times = np.unique(ta[flag])
        for tk in times:
            k = np.flatnonzero(flag & (ta == tk))
            r.set_time(TIMELINE, duration=float(tk))
            r.log(
                f"{entity}/{which}",
                rr.LineStrips3D(np.stack([at[k], beacon[k]], axis=1), colors=c, radii=-1.0),
            )
        if len(times):
            r.reset_time()


def record_current(rec, tag: str, label: str, v: VehicleRun, every: int) -> None:
    """The true current at the vehicle and every estimate of it (a per-tick column in m/s with
    east and north components, e.g. ``ekf_current``): arrows above the vehicle and series."""
    if "truth_current" not in v.ticks:
        return
    t = v["t"][::every]
    origins = v["truth_pos"][::every] + [0.0, 0.0, 2.0]
    true = v["truth_current"][::every]
    k = CURRENT_ARROW_SCALE
    rec.arrows(f"{tag}/current/true", t, origins, k * true, (0, 190, 220))
    rec.scalars(f"current/{tag}/true_east", t, true[:, 0], (0, 190, 220), f"{label} true east")
    rec.scalars(f"current/{tag}/true_north", t, true[:, 1], (0, 120, 140), f"{label} true north")
    for col, c in v.ticks.items():
        if (
            col.startswith("truth")
            or c.unit != "m/s"
            or tuple(c.components[:2])
            != (
                "east",
                "north",
            )
        ):
            continue
        est = np.asarray(c.values, dtype=float)[::every, :2]
        shown = np.nan_to_num(est)
        rec.arrows(f"{tag}/current/{col}", t, origins + [0.0, 0.0, 1.0], k * shown, (31, 119, 180))
        for j, axis in enumerate(("east", "north")):
            rec.scalars(
                f"current/{tag}/{col}_{axis}",
                t,
                est[:, j],
                (31, 119, 180) if j == 0 else (20, 60, 140),
                f"{label} {col} {axis} (m/s)",
            )


def record_commands(rec, tag: str, label: str, v: VehicleRun) -> None:
    """Depth, heading, speed, power, actuators and guidance against their commands."""
    t = v["t"]
    s = rec.scalars
    s(f"depth/{tag}/true", t, -v["truth_pos"][:, 2], (0, 0, 0), f"{label} true depth (m)")
    s(f"depth/{tag}/commanded", t, v["guidance_depth"], (148, 0, 211), f"{label} commanded (m)")
    h, c = unwrapped_heading_deg(v["truth_rph"][:, 2], v["guidance_course"])
    s(f"heading/{tag}/true", t, h, (0, 0, 0), f"{label} true heading, unwrapped (deg)")
    s(f"heading/{tag}/commanded", t, c, (148, 0, 211), f"{label} commanded course (deg)")
    s(
        f"speed/{tag}/through_water",
        t,
        np.hypot(*v["truth_vel_water"][:, :2].T),
        (31, 119, 180),
        f"{label} speed through water (m/s)",
    )
    s(
        f"speed/{tag}/over_ground",
        t,
        np.hypot(*v["truth_vel"][:, :2].T),
        (214, 39, 40),
        f"{label} speed over ground (m/s)",
    )
    s(f"power/{tag}/motor", t, v["motor_power"], (255, 127, 14), f"{label} motor power (W)")
    for col, rgb, what in (
        ("cmd_fin_port", (44, 160, 44), "port fin"),
        ("cmd_fin_starboard", (23, 190, 207), "starboard fin"),
        ("cmd_tail_bias", (188, 189, 34), "tail bias"),
    ):
        s(f"actuators/{tag}/{col[4:]}", t, np.degrees(v[col]), rgb, f"{label} {what} (deg)")
    s(
        f"guidance/{tag}/mode",
        t,
        v["guidance_mode"].astype(float),
        (148, 0, 211),
        f"{label} mode: " + ", ".join(f"{i} {m}" for i, m in enumerate(GUIDANCE_MODES)),
    )
    s(
        f"guidance/{tag}/waypoint",
        t,
        v["guidance_waypoint"].astype(float),
        (0, 0, 0),
        f"{label} way-point index",
    )


def record_mission_columns(rec, tag: str, label: str, v: VehicleRun) -> None:
    """Every scalar per-tick column the mission added (beyond :data:`~tasks.closed_loop.result.
    TICK_COLUMNS` and the declared estimates), e.g. the swarm follower's HDOP, the TRN's DVL
    mode, as series ``mission/<tag>/<column>`` named with its description and unit."""
    from tasks.closed_loop.result import TICK_COLUMNS

    declared = {e.column for e in v.estimates} | {e.covariance for e in v.estimates}
    t = v["t"]
    for col, c in v.ticks.items():
        if col in TICK_COLUMNS or col in declared:
            continue
        vals = np.asarray(c.values)
        if vals.ndim != 1 or vals.dtype.kind not in "biuf":
            continue
        unit = "" if c.unit in ("1", "") else f" ({c.unit})"
        rec.scalars(
            f"mission/{tag}/{col}", t, vals.astype(float), None, f"{label} {c.description}{unit}"
        )


def mission_events(v: VehicleRun, label: str = "") -> tuple[list[float], list[str], list[str]]:
    """Events of a vehicle's run in words: way-points reached (the guidance moves to the next),
    mode changes (surfacing, diving), fixes rejected (by the gate or refused).

    Args:
        v: the vehicle's run data.
        label: the vehicle's name, put before each text (none when empty).

    Returns:
        ``(t_s, texts, levels)``: k times (s), k strings, k rerun levels.
    """
    t = v["t"]
    ts: list[float] = []
    texts: list[str] = []
    levels: list[str] = []
    wp = np.asarray(v["guidance_waypoint"]).astype(int)
    mode = np.asarray(v["guidance_mode"]).astype(int)
    ts.append(float(t[0]))
    texts.append(f"start: heading for WP{wp[0]}, mode {_mode(mode[0])}")
    levels.append("INFO")
    n_wp = len(v.waypoints)
    for k in np.flatnonzero(np.diff(wp) != 0) + 1:
        ts.append(float(t[k]))
        nxt = f"heading for WP{wp[k]}" if wp[k] < n_wp or not n_wp else "the last way-point"
        texts.append(f"WP{wp[k - 1]} reached (by the estimate); {nxt}")
        levels.append("INFO")
    for k in np.flatnonzero(np.diff(mode) != 0) + 1:
        ts.append(float(t[k]))
        texts.append(f"guidance mode {_mode(mode[k - 1])} -> {_mode(mode[k])}")
        levels.append("INFO")
    for kind, fx in v.fixes.items():
        if not fx or "accepted" not in fx or "t_arrival" not in fx:
            continue
        ok = fx["accepted"].values.astype(bool)
        nis = fx["nis"].values if "nis" in fx else np.full(len(ok), np.nan)
        tv = fx["t_valid"].values if "t_valid" in fx else fx["t_arrival"].values
        for k in np.flatnonzero(~ok):
            n = "" if not np.isfinite(nis[k]) else f" (NIS {nis[k]:.1f})"
            ts.append(float(fx["t_arrival"].values[k]))
            texts.append(f"{kind.upper()} fix valid at {tv[k]:.1f} s rejected{n}")
            levels.append("WARN")
    for w in v.waypoints:
        if not w["reached_by_truth"]:
            ts.append(float(w["closest_at_s"]))
            texts.append(
                f"WP{w['index']} missed by truth: closest {w['closest_true_distance_m']:.1f} m "
                f"> {w['acceptance_radius_m']:g} m"
            )
            levels.append("WARN")
    ts.append(float(t[-1]))
    texts.append(f"end at {t[-1]:.1f} s")
    levels.append("INFO")
    if label:
        texts = [f"{label}: {x}" for x in texts]
    return ts, texts, levels


def _mode(m: int) -> str:
    return GUIDANCE_MODES[m] if 0 <= m < len(GUIDANCE_MODES) else str(m)
