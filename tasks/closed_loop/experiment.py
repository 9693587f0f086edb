"""The registered form of a mission: a scenario type, a design, one run per block."""

from __future__ import annotations

from dataclasses import dataclass, field

from bauv_sim.errors import ConfigError
from tasks.closed_loop.parts import MissionDesign
from tasks.closed_loop.report import MissionMetrics, report_mission
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.registry import Experiment, MemoryTerm, ReportContext, ReportSummary

BYTES_PER_TICK = 500.0
"""A run's memory per control tick, bytes: its per-tick columns measured 411 B per tick on
mission/short (one vehicle), plus the fix tables. Applied to ``timing.max_duration_s``, an upper
bound of a run's length."""


@dataclass(frozen=True)
class MissionExperiment(Experiment):
    """A registered closed-loop mission (one run per block).

    Attributes:
        design: what the mission is made of (default: one vehicle flying way-points).
    """

    scenario_type = MissionScenario
    metrics_type = MissionMetrics
    design: MissionDesign = field(default_factory=WaypointMission)

    def flight(
        self, scenario: MissionScenario, seed: int, run: int
    ) -> tuple[MissionDesign, MissionScenario]:
        """The design and the scenario that run ``run`` flies (the batch's, by default; a
        mission whose way-points are drawn per run returns its own)."""
        return self.design, scenario

    def check(self, scenario: MissionScenario, n_runs: int) -> None:
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )

    def memory(self, scenario: MissionScenario, n_runs: int) -> list[MemoryTerm]:
        """Estimated peak memory, bytes: a run of ``timing.max_duration_s`` in the worker that
        flies it, and every run in the report (which reads them all)."""
        t = scenario.timing
        ticks = t.max_duration_s / t.control_tick_s + 1
        what = (
            f"timing.max_duration_s = {t.max_duration_s:g} with timing.control_tick_s = "
            f"{t.control_tick_s:g} s ({ticks:.3g} ticks)"
        )
        return [
            MemoryTerm(BYTES_PER_TICK * ticks, True, what),
            MemoryTerm(BYTES_PER_TICK * ticks * n_runs, False, f"{what} for runs = {n_runs}"),
        ]

    def run_block(
        self, scenario: MissionScenario, seed: int, runs: tuple[int, ...]
    ) -> list[MissionRun]:
        return [fly(*self.flight(scenario, seed, r), seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_mission(self, ctx)
