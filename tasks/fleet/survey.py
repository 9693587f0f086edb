"""``fleet/survey``: a thousand one-hour lawn-mower surveys on the manoeuvring model, every run
with its sensors, EKF, guidance and autopilot, vectorised over the runs (issue 27, check 2).

Run: ``bauv run fleet/survey`` (1000 runs by default; ``--runs N``, ``--workers W``,
``--set plan.lanes=3``). The runs go in blocks of ``runner.block_size`` (vectorised together),
the blocks to the workers; every run draws from its own streams, so the same seed gives the same
numbers bit for bit whatever the blocks' distribution over the workers. Modules:
:mod:`tasks.fleet.scenario`, :mod:`tasks.fleet.run`, :mod:`tasks.fleet.report`; this one
registers the experiment.
"""

from __future__ import annotations

from dataclasses import dataclass

from bauv_sim.config import Config
from tasks.core.registry import Experiment, MemoryTerm, ReportContext, ReportSummary, register
from tasks.fleet.report import FleetMetrics, report_fleet
from tasks.fleet.run import TRACK_COLUMNS, FleetBlock, fly_block
from tasks.fleet.scenario import FleetScenario

__all__ = ["FleetExperiment"]

TRACK_FLOATS = 1 + sum(3 if c else 1 for _, _, c in TRACK_COLUMNS.values())
"""Numbers per run and record time in a block's tracks (time included)."""


@dataclass(frozen=True)
class FleetExperiment(Experiment):
    """Way-point missions on the manoeuvring model, vectorised over runs (module docstring)."""

    scenario_type = FleetScenario
    metrics_type = FleetMetrics

    def block_size(self, scenario: Config) -> int:
        assert isinstance(scenario, FleetScenario)
        return scenario.runner.block_size

    def memory(self, scenario: Config, n_runs: int) -> list[MemoryTerm]:
        assert isinstance(scenario, FleetScenario)
        t = scenario.timing
        records = int(t.max_duration_s / t.record_every_s) + 1
        b = min(scenario.runner.block_size, n_runs)
        tracks = 8.0 * TRACK_FLOATS * records * b if scenario.report.tracks else 0.0
        hist = 8.0 * 40 * b * (scenario.navigation.history_s / t.control_tick_s + 2)
        return [
            MemoryTerm(
                tracks + hist,
                True,
                f"runner.block_size = {b} runs x timing.max_duration_s = {t.max_duration_s:g} / "
                f"timing.record_every_s = {t.record_every_s:g}",
            )
        ]

    def run_block(self, scenario: Config, seed: int, runs: tuple[int, ...]) -> FleetBlock:
        assert isinstance(scenario, FleetScenario)
        return fly_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_fleet(self.name, self.summary, ctx)


register(
    FleetExperiment(
        name="fleet/survey",
        summary="manoeuvring model: 1000 one-hour lawn-mower surveys, sensors, EKF, guidance "
        "and autopilot vectorised over runs, 0.25 m/s current",
        default_runs=1000,
    )
)
