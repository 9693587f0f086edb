"""``mission/trn``: the experiment (checks, memory, the flights of a block) and its registration
(package docstring)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from bauv_sim.errors import ConfigError
from tasks.closed_loop.experiment import BYTES_PER_TICK as MISSION_BYTES_PER_TICK
from tasks.closed_loop.experiment import MissionExperiment
from tasks.core.registry import MemoryTerm, ReportContext, ReportSummary, register
from tasks.missions.trn.parts import TrnMission
from tasks.missions.trn.report import TrnMetrics, report_trn
from tasks.missions.trn.run import fly_run
from tasks.missions.trn.scenario import PRESET, TrnScenario
from tasks.missions.trn.terrain import survey_box

MAP_BYTES_PER_NODE = 80.0
"""Memory of the navigator's map per node, bytes: the truth's crop, the degraded copy and its
working arrays (float64 depths, the NaN-free copy, the cell mask, the holes' grids)."""


BYTES_PER_TICK = 850.0
"""A flight's memory per control tick, bytes: the standard columns and the mission's (every
method's position and covariance, the DVL's mode, the TRN's update), measured 803 B per tick
(numpy's bytes of a flight's columns), against the 500 B of a standard mission."""


@dataclass(frozen=True)
class TrnExperiment(MissionExperiment):
    """DVL and terrain-relative navigation on the physical BAUV (one flight per run, every method
    on it)."""

    scenario_type = TrnScenario
    metrics_type = TrnMetrics

    def flight(self, scenario: TrnScenario, seed: int, run: int):
        return TrnMission(), scenario

    def memory(self, scenario: TrnScenario, n_runs: int) -> list[MemoryTerm]:
        """The mission's terms (its per-tick ones at :data:`BYTES_PER_TICK`: a run keeps its
        flight for the run data) and the navigator's map (in the worker and in the report)."""
        terms = super().memory(scenario, n_runs)
        k = BYTES_PER_TICK / MISSION_BYTES_PER_TICK
        terms = [dataclasses.replace(t, bytes=k * t.bytes) for t in terms[:2]] + terms[2:]
        c, bed = scenario.map, scenario.seabed
        half = (
            bed.half_extent_m
            if c.half_extent_m is None
            else min(c.half_extent_m, bed.half_extent_m)
        )
        nodes = (2 * half / c.cell_m + 1) ** 2
        what = f"map.cell_m = {c.cell_m:g} over +-{half:g} m ({nodes:.3g} nodes)"
        return [
            *terms,
            MemoryTerm(MAP_BYTES_PER_NODE * nodes + bed.grid_bytes, True, what),
            MemoryTerm(MAP_BYTES_PER_NODE * nodes + bed.grid_bytes, False, what),
        ]

    def check(self, scenario: TrnScenario, n_runs: int) -> None:
        """The mission's checks, and: the survey (start and way-points) inside the seabed grid
        with the DVL's footprint to spare, and the map not coarser than its extent.

        Raises:
            ConfigError: naming the field, its value and what is allowed.
        """
        super().check(scenario, n_runs)
        x0, x1, y0, y1 = survey_box(scenario)
        reach = max(abs(x0), abs(x1), abs(y0), abs(y1)) + 30.0
        if reach > scenario.seabed.half_extent_m:
            raise ConfigError(
                f"seabed.half_extent_m = {scenario.seabed.half_extent_m:g}: the survey reaches "
                f"{reach - 30.0:g} m from the origin; must be at least {reach:g} m (30 m to spare)"
            )
        c = scenario.map
        half = scenario.seabed.half_extent_m if c.half_extent_m is None else c.half_extent_m
        if c.cell_m > half:
            raise ConfigError(
                f"map.cell_m = {c.cell_m:g}: must be at most the map's half extent {half:g} m"
            )

    def run_block(self, scenario: TrnScenario, seed: int, runs: tuple[int, ...]):
        return [fly_run(scenario, seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_trn(self, ctx)


register(
    TrnExperiment(
        name="mission/trn",
        summary="DVL and terrain-relative navigation over relief, no USBL after the dive: DR on "
        "the log / on the DVL, DVL + particle / point-mass TRN, the USBL EKF (0.3 m/s current)",
        preset=PRESET,
        default_runs=8,
    )
)
