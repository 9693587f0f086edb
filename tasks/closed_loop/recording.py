"""The recording of a mission run (``recording.rrd``, rerun): seabed, vehicles, tracks, fixes,
current, consistency, guidance and the event log."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.figures import circle, unwrapped_heading_deg
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.scenario import MissionScenario


def record_mission(name: str, scn: MissionScenario, run: MissionRun, out) -> str:
    """Write ``recording.rrd`` of a mission run (see the module docstring of
    :mod:`tasks.core.recording`)."""
    import rerun as rr
    import rerun.blueprint as rrb

    from bauv_sim.frames import quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR
    from bauv_sim.seabed import generate
    from tasks.core.recording import COLORS, Recording

    a = run.lead
    t = a["t"]
    rec = Recording(out / "recording.rrd", name, f"{name}/seed{run.seed}/run{run.run}")
    r = rec.rec
    # seabed mesh around the mission area
    bed = generate(scn.seabed, scn.frame())
    pts = np.array(
        [[w.east_m, w.north_m] for w in scn.guidance.waypoints]
        + [[scn.transceiver_east_m, scn.transceiver_north_m]]
    )
    lo = np.minimum(a["truth_pos"][:, :2].min(axis=0), pts.min(axis=0)) - 60.0
    hi = np.maximum(a["truth_pos"][:, :2].max(axis=0), pts.max(axis=0)) + 60.0
    mesh = seabed_mesh(bed, lo, hi)
    if mesh is not None:
        verts, tris, normals, colors = mesh
        r.log(
            "world/seabed",
            rr.Mesh3D(
                vertex_positions=verts,
                triangle_indices=tris,
                vertex_normals=normals,
                vertex_colors=colors,
            ),
            static=True,
        )
    tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, 0.0])
    tx[2] = float(bed.height_world(tx[0], tx[1]))
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    wp = scn.guidance.waypoints
    r.log(
        "world/waypoints",
        rr.Points3D(
            [[w.east_m, w.north_m, -w.depth_m] for w in wp],
            radii=-8.0,
            colors=(148, 0, 211),
            labels=[f"WP{i}" for i in range(len(wp))],
        ),
        static=True,
    )
    r.log(
        "world/waypoints/acceptance",
        rr.LineStrips3D(
            [circle(w.east_m, w.north_m, w.acceptance_radius_m, -w.depth_m) for w in wp],
            colors=(148, 0, 211),
            radii=-1.5,
        ),
        static=True,
    )
    # the moving hull
    r.send_columns(
        "world/vehicle",
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Transform3D.columns(
            translation=a["truth_pos"], quaternion=quat_wxyz_to_xyzw(a["truth_quat_wxyz"])
        ),
    )
    r.log("world/vehicle/hull", rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"), static=True)
    record_moving_parts(r, a, t)
    rec.track("truth", t, a["truth_pos"], COLORS["truth"])
    rec.track("ekf", t, a["ekf_pos"], COLORS["ekf"])
    rec.track("dr", t, a["dr_pos"], COLORS["dr"])
    every = max(1, round(1.0 / max(float(t[1] - t[0]), 1e-9))) if len(t) > 1 else 1
    rec.ellipsoids("ekf", t[::every], a["ekf_pos"][::every], a["ekf_P"][::every], COLORS["ekf"])
    record_fixes(rec, a)
    record_current(rec, a, every)
    record_consistency(rec, a)
    record_guidance(rec, a)
    record_events(rec, a)
    err = lambda k: np.hypot(*(a[k] - a["truth_pos"])[:, :2].T)  # noqa: E731
    rec.scalars("errors/ekf", t, err("ekf_pos"), COLORS["ekf"], "EKF horizontal error (m)")
    rec.scalars("errors/dr", t, err("dr_pos"), COLORS["dr"], "DR horizontal error (m)")
    rec.scalars("depth/true", t, -a["truth_pos"][:, 2], (0, 0, 0), "true depth (m)")
    rec.scalars("depth/commanded", t, a["guidance_depth"], (148, 0, 211), "commanded depth (m)")
    h, c = unwrapped_heading_deg(a["truth_rph"][:, 2], a["guidance_course"])
    rec.scalars("heading/true", t, h, (0, 0, 0), "true heading, unwrapped (deg)")
    rec.scalars("heading/commanded", t, c, (148, 0, 211), "commanded course (deg)")
    rec.scalars(
        "speed/through_water",
        t,
        np.hypot(*a["truth_vel_water"][:, :2].T),
        (31, 119, 180),
        "speed through water (m/s)",
    )
    rec.scalars(
        "speed/over_ground",
        t,
        np.hypot(*a["truth_vel"][:, :2].T),
        (214, 39, 40),
        "speed over ground (m/s)",
    )
    rec.scalars("power/motor", t, a["motor_power"], (255, 127, 14), "motor power (W)")
    rec.scalars(
        "actuators/fin_port", t, np.degrees(a["cmd_fin_port"]), (44, 160, 44), "port fin (deg)"
    )
    rec.scalars(
        "actuators/fin_starboard",
        t,
        np.degrees(a["cmd_fin_starboard"]),
        (23, 190, 207),
        "starboard fin (deg)",
    )
    rec.scalars(
        "actuators/tail_bias", t, np.degrees(a["cmd_tail_bias"]), (188, 189, 34), "tail bias (deg)"
    )
    rec.blueprint(
        "errors",
        "consistency",
        "innovation",
        "current",
        "guidance",
        "heading",
        "depth",
        follow="/world/vehicle",
        eye_controls=rrb.EyeControls3D(
            position=[-7.0, 3.5, 3.0], look_target=[0.0, 0.0, 0.0], eye_up=[0.0, 0.0, 1.0]
        ),
        log="events",
        world_name="world (camera follows the vehicle)",
    )
    rec.close()
    return "recording.rrd"


SEABED_SHALLOW_RGB = (0.86, 0.79, 0.56)
"""The recording's seabed colour at the shallowest point of the mission area (sand)."""
SEABED_DEEP_RGB = (0.18, 0.33, 0.45)
"""Its colour at the deepest point (the colour ramps linearly with depth in between)."""


def seabed_mesh(
    bed, lo: NDArray[np.float64], hi: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float32], NDArray[np.uint8]] | None:
    """The scene's seabed over a box as the recording's mesh: the heightfield's grid points and
    the triangles MuJoCo collides with (each cell split from its lower-left to its upper-right
    corner), shaded by the surface's normals and coloured by depth, so that the relief shows.

    Args:
        bed: the scene's :class:`~bauv_sim.seabed.Seabed`.
        lo: the box's (east, north) lower corner, m.
        hi: its upper corner, m.

    Returns:
        ``(vertices (k, 3) m world, triangles (t, 3), normals (k, 3), colours (k, 4) RGBA)``,
        or None when the box holds fewer than 2 x 2 grid points.
    """
    c = bed.config
    grid = np.arange(c.n) * c.cell_m - c.half_extent_m
    ix = np.flatnonzero((grid >= lo[0]) & (grid <= hi[0]))
    iy = np.flatnonzero((grid >= lo[1]) & (grid <= hi[1]))
    if len(ix) < 2 or len(iy) < 2:
        return None
    X, Y = np.meshgrid(grid[ix], grid[iy])
    Z = -bed.depth_m[np.ix_(iy, ix)]
    verts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange(Z.size).reshape(Z.shape)
    q0, q1 = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    q2, q3 = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    tris = np.concatenate([np.column_stack([q0, q1, q2]), np.column_stack([q0, q2, q3])])
    dz_dy, dz_dx = np.gradient(Z, c.cell_m)
    normals = np.column_stack([-dz_dx.ravel(), -dz_dy.ravel(), np.ones(Z.size)])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    span = float(Z.max() - Z.min())
    f = (Z.max() - Z.ravel())[:, None] / span if span > 0 else np.zeros((Z.size, 1))
    rgb = (1 - f) * np.asarray(SEABED_SHALLOW_RGB) + f * np.asarray(SEABED_DEEP_RGB)
    colors = np.column_stack([np.round(255 * rgb), np.full(Z.size, 255)]).astype(np.uint8)
    return verts, tris, normals.astype(np.float32), colors


VEHICLE_PARTS: tuple[tuple[str, str, str, tuple[float, float, float], tuple[float, ...]], ...] = (
    # entity under world/vehicle, mesh, (column, component), joint axis (body), pose in parent
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


def record_moving_parts(r, v: VehicleRun, t: NDArray[np.float64]) -> None:
    """Fins and tail at their true joint angles (``truth_fin_angles``, ``truth_tail_angles``),
    as child transforms of ``world/vehicle``; the dorsal fin, fixed to the hull, once."""
    import rerun as rr

    from bauv_sim.hull import MODEL_DIR

    assets = MODEL_DIR / "assets"
    r.log(
        "world/vehicle/dorsal_fin",
        rr.Transform3D(translation=[0.05, 0.0, 0.15]),
        rr.Asset3D(path=assets / "dorsal_fin.obj"),
        static=True,
    )
    for entity, mesh, source, axis, pos in VEHICLE_PARTS:
        col, comp = source.split(":")
        if col not in v.ticks:
            continue  # run data written before the joint angles were recorded
        angle = v[col][:, int(comp)]
        half = 0.5 * angle
        ax = np.asarray(axis, dtype=float)
        quat_xyzw = np.column_stack([np.sin(half)[:, None] * ax, np.cos(half)])
        r.send_columns(
            f"world/vehicle/{entity}",
            indexes=[rr.TimeColumn("sim_time", duration=t)],
            columns=rr.Transform3D.columns(
                translation=np.tile(pos, (len(t), 1)), quaternion=quat_xyzw
            ),
        )
        r.log(f"world/vehicle/{entity}/mesh", rr.Asset3D(path=assets / mesh), static=True)


GUIDANCE_MODES = ("transit", "ascend", "surface", "dive", "done")
"""Names of the ``guidance_mode`` values (:data:`tasks.closed_loop.result.TICK_COLUMNS`)."""


def position_nees(v: VehicleRun) -> NDArray[np.float64]:
    """The EKF's position NEES at each tick, ``e^T P^-1 e`` with ``e`` the 3-D error, shape (T,)."""
    e = v["ekf_pos"] - v["truth_pos"]
    return np.einsum("ti,ti->t", e, np.linalg.solve(v["ekf_P"], e[..., None])[..., 0])


def record_fixes(rec, v: VehicleRun) -> None:
    """Fixes split into accepted and rejected (gate) entities, their flag as a series, and each
    fix's position innovation: the fix minus the EKF's estimate at its time of validity."""
    from tasks.core.recording import COLORS

    for kind in ("usbl", "gps"):
        fx = v.fixes.get(kind)
        if not fx:
            continue
        ta = fx["t_arrival"].values
        tv = fx["t_valid"].values
        pos = fx["position"].values
        ok = fx["accepted"].values.astype(bool)
        for flag, name, color in ((ok, "accepted", COLORS[kind]), (~ok, "rejected", (230, 0, 0))):
            if flag.any():
                rec.fixes(f"{kind}/{name}", ta[flag], pos[flag], color)
        rec.scalars(
            f"fixes/{kind}_accepted",
            ta,
            ok.astype(float),
            COLORS[kind],
            f"{kind.upper()} fix accepted (1) or rejected by the gate (0)",
        )
        t = v["t"]
        est = np.column_stack([np.interp(tv, t, v["ekf_pos"][:, j]) for j in range(2)])
        innov = pos[:, :2] - est
        for j, axis in enumerate(("east", "north")):
            rec.scalars(
                f"innovation/{kind}_{axis}",
                ta,
                innov[:, j],
                COLORS[kind] if j == 0 else (0, 114, 178),
                f"{kind.upper()} fix - EKF, {axis} (m)",
            )
        if "nis" in fx:
            dof = 3 if kind == "usbl" else 2
            rec.scalars(
                f"consistency/nis_{kind}",
                ta,
                fx["nis"].values,
                COLORS[kind],
                f"{kind.upper()} NIS (dof {dof})",
            )


def record_current(rec, v: VehicleRun, every: int) -> None:
    """The true current at the vehicle and the EKF's estimate beside it: arrows (x20) above the
    vehicle and east/north series."""
    t = v["t"][::every]
    origins = v["truth_pos"][::every] + [0.0, 0.0, 2.0]
    true = v["truth_current"][::every]
    rec.arrows("current/true", t, origins, 20.0 * true, (0, 190, 220))
    rec.scalars("current/true_east", t, true[:, 0], (0, 190, 220), "true current east (m/s)")
    rec.scalars("current/true_north", t, true[:, 1], (0, 120, 140), "true current north (m/s)")
    if "ekf_current" in v.ticks:
        est = v["ekf_current"][::every]
        rec.arrows("current/estimated", t, origins + [0.0, 0.0, 1.0], 20.0 * est, (31, 119, 180))
        rec.scalars("current/ekf_east", t, est[:, 0], (31, 119, 180), "EKF current east (m/s)")
        rec.scalars("current/ekf_north", t, est[:, 1], (20, 60, 140), "EKF current north (m/s)")


def record_consistency(rec, v: VehicleRun, probability: float = 0.95) -> None:
    """The EKF's position NEES at each tick against the chi-square band of one run (dof 3)."""
    t = v["t"]
    rec.scalars(
        "consistency/nees", t, position_nees(v), (31, 119, 180), "EKF position NEES (dof 3)"
    )
    from scipy.stats import chi2  # imported with the recording only

    lo, hi = chi2.ppf(np.array([(1 - probability) / 2, (1 + probability) / 2]), 3)
    for name, val in (("band_low", lo), ("band_high", hi)):
        rec.scalars(
            f"consistency/nees_{name}",
            t[[0, -1]],
            np.full(2, val),
            (0, 158, 115),
            f"{100 * probability:g} % chi-square band, one run ({val:.2f})",
        )


def record_guidance(rec, v: VehicleRun) -> None:
    """Guidance mode (0 transit, 1 ascend, 2 surface, 3 dive, 4 done) and way-point index."""
    t = v["t"]
    rec.scalars(
        "guidance/mode",
        t,
        v["guidance_mode"].astype(float),
        (148, 0, 211),
        "mode: " + ", ".join(f"{i} {m}" for i, m in enumerate(GUIDANCE_MODES)),
    )
    rec.scalars(
        "guidance/waypoint", t, v["guidance_waypoint"].astype(float), (0, 0, 0), "way-point index"
    )


def mission_events(v: VehicleRun) -> tuple[list[float], list[str], list[str]]:
    """Events of a run in words: way-points reached (the guidance moves to the next), mode
    changes (surfacing, diving), fixes rejected by the gate.

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
    for kind in ("usbl", "gps"):
        fx = v.fixes.get(kind)
        if not fx:
            continue
        ok = fx["accepted"].values.astype(bool)
        nis = fx["nis"].values if "nis" in fx else np.full(len(ok), np.nan)
        for k in np.flatnonzero(~ok):
            n = "" if not np.isfinite(nis[k]) else f" (NIS {nis[k]:.1f})"
            ts.append(float(fx["t_arrival"].values[k]))
            texts.append(f"{kind.upper()} fix valid at {fx['t_valid'].values[k]:.1f} s rejected{n}")
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
    return ts, texts, levels


def _mode(m: int) -> str:
    return GUIDANCE_MODES[m] if 0 <= m < len(GUIDANCE_MODES) else str(m)


def record_events(rec, v: VehicleRun) -> None:
    """The run's events (:func:`mission_events`) as the text log ``events``."""
    rec.events("events", *mission_events(v))
