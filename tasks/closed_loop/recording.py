"""The recording of a mission run (``recording.rrd``, rerun), the same for every mission: the
scene (seabed, transceiver, beacons, way-points or the nominal path) and, per vehicle of every
flight, what :mod:`tasks.closed_loop.recording_vehicle` draws from its run data (hull posed by
the truth with fins and tail moving, truth and each declared estimate with its covariance, the
fixes accepted and rejected, errors, NEES with its band, innovations, commands, events).

A mission gets its recording by declaring its vehicles and their navigators' estimates
(:attr:`~tasks.closed_loop.parts.VehicleParts.estimates`) and calling :func:`record_flights`
with its scene (:func:`mission_scene` for a way-point mission) and the run's flights.

One file per run folder. A mission flying several flights per run (the swarm's methods, the
correction's two courses) writes them into the same recording, each flight under its own entity
subtree ``world/<flight>/...`` (one timeline, ``sim_time``: the flights start at 0 together) and
its own 3-D view (a tab named after the flight); a single flight's vehicles sit at
``world/<vehicle>``. The scene is at ``world/seabed`` and ``world/scene/...``.

The time panels show the whole mission (their visible time range is the whole timeline, not the
viewer's default window before the time cursor).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.figures import circle
from tasks.closed_loop.recording_vehicle import (
    GUIDANCE_MODES,
    VEHICLE_PARTS,
    mission_events,
    record_vehicle,
)
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.scenario import MissionScenario

__all__ = [
    "GUIDANCE_MODES",
    "PLOTS",
    "VEHICLE_PARTS",
    "VEHICLE_RGB",
    "RecordingScene",
    "mission_events",
    "mission_scene",
    "record_flights",
    "record_mission",
    "seabed_mesh",
]

VEHICLE_RGB: tuple[tuple[int, int, int], ...] = (
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
)
"""The truth's colour of the first, second ... vehicle of a flight (0-255 RGB, the figures'
palette: black, blue, vermillion, bluish green ...; repeated beyond ten)."""

PLOTS = (
    ("errors", "consistency", "innovation", "fixes", "mission"),
    ("depth", "heading", "speed", "current", "guidance", "actuators", "power"),
)
"""The time-series views: two tab groups, stacked (plot roots of
:mod:`tasks.closed_loop.recording_vehicle`)."""


@dataclass(frozen=True)
class RecordingScene:
    """What a recording draws of the scene.

    Attributes:
        seabed: the scene's :class:`~bauv_sim.seabed.Seabed` (drawn around the mission area), or
            None for none.
        points: landmarks, ``(label, position (3,) m world ENU, 0-255 RGB)``: the USBL
            transceiver, beacons.
        waypoints: ``(east m, north m, depth m, acceptance radius m)``, in order.
        path: the nominal path, shape (k, 3), m, world ENU, or None.
        margin_m: how far the seabed reaches beyond the tracks and landmarks, m.
    """

    seabed: Any = None
    points: Sequence[tuple[str, NDArray[np.float64], tuple[int, int, int]]] = ()
    waypoints: Sequence[tuple[float, float, float, float]] = ()
    path: NDArray[np.float64] | None = None
    margin_m: float = 60.0


def mission_scene(
    scn: Any, seabed: bool = True, guidance: Any = None, transceiver: bool | None = None
) -> RecordingScene:
    """The scene of a way-point mission's scenario: its seabed (``scn.seabed``), its USBL
    transceiver on the seabed (``scn.transceiver_east_m``/``_north_m``, when its navigation uses
    USBL: ``scn.sensors.use_usbl``) and its way-points (``scn.guidance.waypoints``).

    Args:
        scn: the scenario.
        seabed: whether to draw the seabed.
        guidance: the guidance configuration whose way-points to draw (default:
            ``scn.guidance``; the swarm's: its leader's).
        transceiver: whether to draw the transceiver (default: when the scenario uses USBL).
    """
    from bauv_sim.seabed import generate

    bed = generate(scn.seabed, scn.frame()) if seabed and hasattr(scn, "seabed") else None
    points = []
    if transceiver is None:
        sensors = getattr(scn, "sensors", None)
        transceiver = bool(getattr(sensors, "use_usbl", True))
    if transceiver and hasattr(scn, "transceiver_east_m"):
        tx = np.array([scn.transceiver_east_m, scn.transceiver_north_m, 0.0])
        tx[2] = float(bed.height_world(tx[0], tx[1])) if bed is not None else 0.0
        points.append(("USBL transceiver", tx, (0, 0, 0)))
    guidance = getattr(scn, "guidance", None) if guidance is None else guidance
    wps = getattr(guidance, "waypoints", ()) or ()
    return RecordingScene(
        bed,
        points,
        [(w.east_m, w.north_m, w.depth_m, w.acceptance_radius_m) for w in wps],
    )


def record_mission(name: str, scn: MissionScenario, run: MissionRun, out) -> str:
    """Write ``recording.rrd`` of a one-flight way-point mission run
    (:func:`record_flights` with :func:`mission_scene`)."""
    return record_flights(out, name, mission_scene(scn), {"": run})


def record_flights(
    out: Path,
    name: str,
    scene: RecordingScene,
    flights: Mapping[str, MissionRun],
    file: str = "recording.rrd",
) -> str:
    """Write the recording of one run: the scene and every vehicle of every flight.

    Args:
        out: the run folder.
        name: the experiment's name (the recording's application id).
        scene: what to draw of the scene.
        flights: the run's flights by name (``{"": run}`` for a mission flying one); every
            flight's vehicles with their declared estimates.
        file: the file's name in ``out``.

    Returns:
        The file written, relative to ``out``.
    """
    from tasks.core.recording import Recording

    runs = [r for r in flights.values() if r.vehicles]
    first = next(iter(flights.values()))
    multi = len(flights) > 1
    rec = Recording(
        Path(out) / file,
        name,
        f"{name}/seed{first.seed}/run{first.run}" + ("" if multi else _suffix(flights)),
    )
    record_scene(rec, scene, [v["truth_pos"] for r in runs for v in r.vehicles.values()])
    views = []
    for flight, run in flights.items():
        lone = len(run.vehicles) == 1
        for (vn, v), color in zip(run.vehicles.items(), itertools.cycle(VEHICLE_RGB)):
            tag = f"{flight}/{vn}" if multi else vn
            label = f"{vn} ({flight})" if multi else vn
            record_vehicle(rec, tag, label, v, (0, 0, 0) if lone else color)
        if run.vehicles:
            views.append((flight, run))
    record_blueprint(rec, views, multi)
    rec.close()
    return file


def _suffix(flights: Mapping[str, MissionRun]) -> str:
    key = next(iter(flights))
    return f"/{key}" if key else ""


def record_scene(rec, scene: RecordingScene, tracks: Sequence[NDArray[np.float64]]) -> None:
    """The seabed around the tracks and landmarks, the landmarks, way-points and path."""
    import rerun as rr

    r = rec.rec
    pts = [p[:, :2] for p in tracks if len(p)]
    pts += [np.asarray(p, float)[None, :2] for _, p, _ in scene.points]
    pts += [np.array([[w[0], w[1]] for w in scene.waypoints])] if scene.waypoints else []
    if scene.path is not None and len(scene.path):
        pts.append(np.asarray(scene.path, float)[:, :2])
    if scene.seabed is not None and pts:
        allp = np.concatenate(pts)
        lo = allp.min(axis=0) - scene.margin_m
        hi = allp.max(axis=0) + scene.margin_m
        mesh = seabed_mesh(scene.seabed, lo, hi)
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
    for i, (label, p, color) in enumerate(scene.points):
        rec.point(f"scene/points/{i}", np.asarray(p, float), color, label)
    wp = scene.waypoints
    if wp:
        r.log(
            "world/scene/waypoints",
            rr.Points3D(
                [[w[0], w[1], -w[2]] for w in wp],
                radii=-8.0,
                colors=(148, 0, 211),
                labels=[f"WP{i}" for i in range(len(wp))],
            ),
            static=True,
        )
        r.log(
            "world/scene/waypoints/acceptance",
            rr.LineStrips3D(
                [circle(w[0], w[1], w[3], -w[2]) for w in wp], colors=(148, 0, 211), radii=-1.5
            ),
            static=True,
        )
    if scene.path is not None and len(scene.path):
        r.log(
            "world/scene/path",
            rr.LineStrips3D(
                [np.asarray(scene.path, float)],
                colors=(148, 0, 211),
                radii=-1.5,
                labels=["nominal path"],
            ),
            static=True,
        )


def record_blueprint(rec, views: Sequence[tuple[str, MissionRun]], multi: bool) -> None:
    """One 3-D view per flight (tabs named after it; a lone vehicle's view rides with it), the
    events under them, and the time-series views (:data:`PLOTS`) over the whole timeline."""
    import rerun.blueprint as rrb

    from tasks.core.recording import TIMELINE

    whole = rrb.VisibleTimeRange(
        TIMELINE, start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite()
    )
    # the visible range says which data a view queries; the x axis's own view range says what it
    # shows: without it the viewer opens the plots on the last seconds around the time cursor
    ends = [float(v["t"][-1]) for _, run in views for v in run.vehicles.values() if len(v["t"])]
    axis = rrb.TimeAxis(
        view_range=rrb.TimeRange(
            start=rrb.TimeRangeBoundary.absolute(seconds=0.0),
            end=rrb.TimeRangeBoundary.absolute(seconds=max(ends, default=1.0)),
        )
    )
    worlds = []
    for flight, run in views:
        names = ", ".join(run.vehicles)
        if len(run.vehicles) == 1 and not multi:
            vn = next(iter(run.vehicles))
            worlds.append(
                rrb.Spatial3DView(
                    origin=f"/world/{vn}/body",
                    contents="/world/**",
                    name=f"world: {vn} (camera follows it)",
                    eye_controls=rrb.EyeControls3D(
                        position=[-7.0, 3.5, 3.0],
                        look_target=[0.0, 0.0, 0.0],
                        eye_up=[0.0, 0.0, 1.0],
                    ),
                )
            )
            continue
        sub = f"/world/{flight}/**" if multi else "/world/**"
        worlds.append(
            rrb.Spatial3DView(
                origin="/world",
                contents=["/world", "/world/seabed", "/world/scene/**", sub],
                name=f"{flight}: {names}" if multi else f"world: {names}",
            )
        )
    world = rrb.Tabs(*worlds) if len(worlds) > 1 else worlds[0]
    left = rrb.Vertical(world, rrb.TextLogView(origin="/events", name="events"), row_shares=[4, 1])
    groups = [
        rrb.Tabs(
            *[rrb.TimeSeriesView(origin=f"/{p}", name=p, time_ranges=whole, axis_x=axis) for p in g]
        )
        for g in PLOTS
    ]
    rec.rec.send_blueprint(
        rrb.Blueprint(
            rrb.Horizontal(left, rrb.Vertical(*groups), column_shares=[3, 2]),
            collapse_panels=True,
        )
    )


MESH_MAX_SIDE = 200
"""The most grid points the recording's seabed mesh has along a side (40,000 vertices, about
2.6 MB in the file): mission/seed004's 1 m cells over its 1 km area were 19 MB at full
resolution, 6 times the rest of its recording."""

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
    A box more than :data:`MESH_MAX_SIDE` grid points across is drawn on every k-th grid point
    (k the smallest that fits), so that a fine seabed does not outweigh the mission's data: its
    vertices are still the heightfield's points, its cells k times wider.

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
    step = max(1, -(-max(len(ix), len(iy)) // MESH_MAX_SIDE))  # every step-th grid point
    ix, iy = ix[::step], iy[::step]
    X, Y = np.meshgrid(grid[ix], grid[iy])
    Z = -bed.depth_m[np.ix_(iy, ix)]
    verts = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    idx = np.arange(Z.size).reshape(Z.shape)
    q0, q1 = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    q2, q3 = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    tris = np.concatenate([np.column_stack([q0, q1, q2]), np.column_stack([q0, q2, q3])])
    dz_dy, dz_dx = np.gradient(Z, step * c.cell_m)
    normals = np.column_stack([-dz_dx.ravel(), -dz_dy.ravel(), np.ones(Z.size)])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    span = float(Z.max() - Z.min())
    f = (Z.max() - Z.ravel())[:, None] / span if span > 0 else np.zeros((Z.size, 1))
    rgb = (1 - f) * np.asarray(SEABED_SHALLOW_RGB) + f * np.asarray(SEABED_DEEP_RGB)
    colors = np.column_stack([np.round(255 * rgb), np.full(Z.size, 255)]).astype(np.uint8)
    return verts, tris, normals.astype(np.float32), colors
