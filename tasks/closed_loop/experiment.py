"""The registered form of a mission: a scenario type, a design, one run per block."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from bauv_sim import seabed
from bauv_sim.build import VEHICLE_CLEARANCE_M
from bauv_sim.errors import ConfigError, GeometryError
from tasks.closed_loop.parts import MissionDesign
from tasks.closed_loop.recording import MESH_MAX_SIDE
from tasks.closed_loop.report import MissionMetrics, report_mission
from tasks.closed_loop.report import report_work as mission_report_work
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import WaypointMission, check_world, fly
from tasks.core.registry import (
    Experiment,
    MemoryTerm,
    ReportContext,
    ReportSummary,
    ReportWork,
)

MESH_BYTES_PER_CELL = 600.0
"""Memory of the recording's seabed mesh per grid cell of the mission area, bytes, an upper
bound (:func:`tasks.closed_loop.recording.seabed_mesh`: its vertices, triangles, normals and
colours and rerun's copies of them, 273 B per cell at the peak, tracemalloc on 600 x 600 cells;
600 B is the bound of the mesh the report built from Python tuples before, 512 B per cell)."""

MESH_MARGIN_M = 160.0
"""How far the recorded mission area reaches beyond the way-points, the start and the transceiver,
m: the report's 60 m around the track, and 100 m for the track's excursions past them."""

BYTES_PER_TICK = 500.0
"""A run's memory per control tick, bytes: its per-tick columns measured 411 B per tick on
mission/short (one vehicle), plus the fix tables. Applied to ``timing.max_duration_s``, an upper
bound of a run's length."""


def check_in_water(scenario: MissionScenario) -> None:
    """Refuse a start or a way-point below the seabed of the scene (or within
    :data:`~bauv_sim.build.VEHICLE_CLEARANCE_M` of it): a depth the vehicle cannot reach, whose
    way-point would still count as reached since the acceptance radius is judged horizontally.
    Points outside the seabed grid are not checked (as when the scene is built). A seabed from
    a bathymetry file is read and resampled here, so that a file that cannot serve is refused
    before anything is written.

    Raises:
        ConfigError: naming the field, its value and the water depth there; or the bathymetry
            file, its variable and what is wrong with it (:func:`bauv_sim.seabed.generate`).
    """
    bed = seabed.generate(scenario.seabed, scenario.frame())
    points = [("start.depth_m", scenario.start)] + [
        (f"guidance.waypoints.{i}.depth_m", w) for i, w in enumerate(scenario.guidance.waypoints)
    ]
    for field_name, p in points:
        try:
            water = float(bed.depth_at(p.east_m, p.north_m))
        except GeometryError:
            continue
        if p.depth_m > water - VEHICLE_CLEARANCE_M:
            raise ConfigError(
                f"{field_name} = {p.depth_m:g}: the water is {water:.2f} m deep at east "
                f"{p.east_m:g} m, north {p.north_m:g} m; must be at most "
                f"{water - VEHICLE_CLEARANCE_M:.2f} m ({VEHICLE_CLEARANCE_M:g} m above the seabed)"
            )


CURRENT_MARGIN_M = 100.0
"""How far a track may stray beyond the way-points, the start and the transceiver, m, in the box a
gridded current must cover (:func:`check_current_covers`; :data:`MESH_MARGIN_M`'s excursions)."""

CURRENT_DEPTH_MARGIN_M = 5.0
"""How far below the deepest way-point or start the vehicle may go, m (its depth loop's
overshoot and the dives of a surfacing), in the depth a gridded current must cover."""


def check_gridded_current(
    current,
    frame,
    t_end_s: float,
    points_en_m: list[tuple[float, float]],
    depths_m: list[float],
) -> None:
    """Refuse a gridded current (``current.kind = "gridded"``) that cannot serve a mission,
    before anything is written: the file is read (once per process,
    :func:`bauv_sim.ocean.load_current_grid`) and must cover the time ``[0, t_end_s]``, the box
    of ``points_en_m`` widened by :data:`CURRENT_MARGIN_M`, and the deepest of ``depths_m`` plus
    :data:`CURRENT_DEPTH_MARGIN_M`. Other current kinds are not checked.

    Args:
        current: the scenario's current configuration.
        frame: the scenario's geographic frame (:class:`bauv_sim.geo.LocalFrame`), or None.
        t_end_s: the mission's longest duration, s.
        points_en_m: the points the mission reaches (east, north), m.
        depths_m: the depths it reaches, m (positive down).

    Raises:
        ConfigError: one line naming ``current.file``, the file, the variable and what is wrong
            (a bad file: :func:`bauv_sim.ocean.read_current_grid`), or what the grid does not
            cover and its extent; a gridded current without a ``geo`` origin.
    """
    from bauv_sim.currents import GriddedCurrentConfig, make_current

    if not isinstance(current, GriddedCurrentConfig):
        return
    field = make_current(current, None, frame)
    e, n = np.array(points_en_m, dtype=float).T
    m = CURRENT_MARGIN_M
    corners_e = [e.min() - m, e.max() + m, e.max() + m, e.min() - m]
    corners_n = [n.min() - m, n.min() - m, n.max() + m, n.max() + m]
    field.check_covers(
        t_end_s, np.array(corners_e), np.array(corners_n), max(depths_m) + CURRENT_DEPTH_MARGIN_M
    )


def check_current_covers(
    scenario: MissionScenario,
    points_en_m: list[tuple[float, float]] | None = None,
    depths_m: tuple[float, ...] = (),
) -> None:
    """:func:`check_gridded_current` for a mission scenario: its time
    ``[0, timing.max_duration_s]``, the box of the start, the way-points and the transceiver
    (and ``points_en_m``), and the deepest of their depths (and ``depths_m``).

    Args:
        scenario: the mission's scenario (its ``current``, ``geo``, ``timing``, ``start``,
            ``guidance.waypoints`` and transceiver).
        points_en_m: more points the mission reaches (east, north), m: way-points made per run.
        depths_m: more depths the mission reaches, m (positive down).

    Raises:
        ConfigError: as :func:`check_gridded_current`.
    """
    wps = scenario.guidance.waypoints
    pts = [(w.east_m, w.north_m) for w in wps] + list(points_en_m or [])
    pts.append((scenario.start.east_m, scenario.start.north_m))
    pts.append((scenario.transceiver_east_m, scenario.transceiver_north_m))
    depths = [scenario.start.depth_m] + [w.depth_m for w in wps] + list(depths_m)
    check_gridded_current(
        scenario.current, scenario.frame(), scenario.timing.max_duration_s, pts, depths
    )


CURRENT_BYTES_PER_CELL = 100.0
"""Memory of a gridded current per cell of its file's grid, bytes: the grid's three velocity
components and the interpolator's copies, 97 B per cell measured with tracemalloc reading a
12 x 5 x 60 x 60 file and building its field (:class:`bauv_sim.ocean.GriddedCurrent`)."""


def current_memory_terms(scenario: MissionScenario) -> list[MemoryTerm]:
    """The memory of a gridded current (none for the other kinds): held by every worker (its
    runs share the grid read once per process) and by the process that checks the batch
    (:data:`CURRENT_BYTES_PER_CELL` per cell of the file's grid, read from its header).

    Raises:
        ConfigError: the file is missing or has no eastward velocity (one line naming
            ``current.file``).
    """
    from bauv_sim.currents import GriddedCurrentConfig
    from bauv_sim.ocean import current_grid_cells

    cur = scenario.current
    if not isinstance(cur, GriddedCurrentConfig):
        return []
    try:
        cells = current_grid_cells(cur.file)
    except ConfigError as exc:
        raise ConfigError(f"current.file: {exc}") from None
    what = f"current.file = {cur.file} ({cells:.3g} grid cells)"
    b = CURRENT_BYTES_PER_CELL * cells
    return [MemoryTerm(b, True, what), MemoryTerm(b, False, what)]


def _mesh_bytes(scenario: MissionScenario) -> float:
    """Memory of the recording's seabed mesh, bytes: the grid cells of the mission area (the
    way-points, the start and the transceiver, :data:`MESH_MARGIN_M` around them, within the
    grid, at most :data:`~tasks.closed_loop.recording.MESH_MAX_SIDE` a side); 0 without a
    recording or way-points."""
    report, guidance = getattr(scenario, "report", None), getattr(scenario, "guidance", None)
    if not getattr(report, "recording", False) or guidance is None:
        return 0.0
    c = scenario.seabed
    pts = [(w.east_m, w.north_m) for w in guidance.waypoints]
    pts.append((scenario.start.east_m, scenario.start.north_m))
    pts.append((scenario.transceiver_east_m, scenario.transceiver_north_m))
    sides = []
    for axis in (0, 1):
        lo = max(min(p[axis] for p in pts) - MESH_MARGIN_M, -c.half_extent_m)
        hi = min(max(p[axis] for p in pts) + MESH_MARGIN_M, c.half_extent_m)
        sides.append(max(hi - lo, 0.0) / c.cell_m + 1)
    # the mesh is drawn on every k-th grid point beyond MESH_MAX_SIDE points a side
    step = max(1, math.ceil(max(sides) / MESH_MAX_SIDE))
    return MESH_BYTES_PER_CELL * (sides[0] / step) * (sides[1] / step)


@dataclass(frozen=True)
class MissionExperiment(Experiment):
    """A registered closed-loop mission (one run per block).

    Attributes:
        design: what the mission is made of (default: one vehicle flying way-points).
    """

    scenario_type = MissionScenario
    metrics_type = MissionMetrics
    report_seabed: ClassVar[bool] = True
    """Whether the report generates the scene's seabed (the recording's mesh of the mission
    area, :func:`tasks.closed_loop.report.record_mission`), for :meth:`memory`."""
    design: MissionDesign = field(default_factory=WaypointMission)

    def flight(
        self, scenario: MissionScenario, seed: int, run: int
    ) -> tuple[MissionDesign, MissionScenario]:
        """The design and the scenario that run ``run`` flies (the batch's, by default; a
        mission whose way-points are drawn per run returns its own)."""
        return self.design, scenario

    def check(self, scenario: MissionScenario, n_runs: int) -> None:
        """Checks of a batch: the recorded run and the faulty runs are runs of the batch; the
        start and every way-point are in the water (above the scene's seabed by at least
        :data:`~bauv_sim.build.VEHICLE_CLEARANCE_M` where the seabed grid covers them); a
        gridded current covers the mission (:func:`check_current_covers`).

        Raises:
            ConfigError: naming the field, its value and what is allowed; or a batch whose
                estimated memory is above the limit (checked first: the checks below generate
                the seabed grid).
        """
        from tasks.core.runner import check_memory

        check_memory(self, scenario, n_runs)
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )
        bad = [r for r in scenario.faults.physics_nan_runs if not 0 <= r < n_runs]
        if bad:
            raise ConfigError(
                f"faults.physics_nan_runs = {list(scenario.faults.physics_nan_runs)}: run "
                f"{bad[0]} is not a run of this batch (0 <= run < runs = {n_runs})"
            )
        check_in_water(scenario)
        check_current_covers(scenario)
        check_world(self.flight(scenario, 0, 0)[0], scenario)

    def memory(self, scenario: MissionScenario, n_runs: int) -> list[MemoryTerm]:
        """Estimated peak memory, bytes: a run of ``timing.max_duration_s`` in the worker that
        flies it, and every run in the report (which reads them all); the seabed grid of the
        scene, generated in the worker for every run (:attr:`~bauv_sim.seabed.SeabedConfig.
        grid_bytes`), and in the process that checks the batch and writes the report, with the
        recording's mesh of the mission area (:data:`MESH_BYTES_PER_CELL`); a gridded current's
        grid in both (:func:`current_memory_terms`)."""
        t = scenario.timing
        ticks = t.max_duration_s / t.control_tick_s + 1
        what = (
            f"timing.max_duration_s = {t.max_duration_s:g} with timing.control_tick_s = "
            f"{t.control_tick_s:g} s ({ticks:.3g} ticks)"
        )
        bed = scenario.seabed
        terms = [
            MemoryTerm(BYTES_PER_TICK * ticks, True, what),
            MemoryTerm(BYTES_PER_TICK * ticks * n_runs, False, f"{what} for runs = {n_runs}"),
            MemoryTerm(bed.grid_bytes, True, bed.grid_text),
        ]
        if self.report_seabed:
            terms.append(MemoryTerm(bed.grid_bytes + _mesh_bytes(scenario), False, bed.grid_text))
        return terms + current_memory_terms(scenario)

    def run_block(
        self, scenario: MissionScenario, seed: int, runs: tuple[int, ...]
    ) -> list[MissionRun]:
        return [fly(*self.flight(scenario, seed, r), seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_mission(self, ctx)

    def report_work(self, scenario: MissionScenario) -> ReportWork | None:  # type: ignore[override]
        """The figures and recording of :func:`report_mission`, in two report processes (a
        mission whose report is its own hands out none)."""
        if type(self).report is not MissionExperiment.report:
            return None
        return mission_report_work(scenario)
