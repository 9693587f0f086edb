"""``trn/relief``: terrain-relative navigation against the terrain's relief and the map's error,
on kinematic truth, for Monte Carlo at scale (issue 23).

A vehicle flies a lawn-mower at constant speed and depth over a generated seabed
(:func:`bauv_sim.seabed.generate`, flat mean, relief standard deviation from the sweep: 0.25,
0.5, 1, 2 and 5 m by default); its DVL pings at 5 Hz against the seabed's triangles
(:class:`bauv_sim.sensors.dvl.Dvl`), its heading comes from a compass with white noise. Three
estimates start from the same erroneous position (``filters.initial_sigma_m``):

* **DR-DVL**: dead reckoning on the DVL's velocity rotated by the measured heading
  (:mod:`nav.dvl`, :mod:`nav.dead_reckoning`);
* **TRN-PF** and **TRN-PMF**: the particle and point-mass TRN filters (:mod:`nav.trn`), fed the DR
  displacement between updates and one ping's four soundings every ``filters.update_every``
  pings, against the navigator's map, a degraded copy of the true seabed
  (:func:`nav.trn.degraded`: a coarser cell ``map.cell_m``, per-cell vertical noise from the
  sweep's ``map_sigma_m``, an offset ``map.offset_m``): the map is never the truth;

beside the posterior Cramer-Rao bound (:func:`nav.trn.trn_pcrb`) from the true track and the
TRUE seabed's gradients at the beams' footprints, with the true process noise of the dead
reckoning and the beams' range noise plus the map's vertical noise as measurement noise.

Run: ``bauv run trn/relief`` (``--runs N``, ``--workers K``, ``--set sweep.relief_std_m=[1, 2]``,
``--set sweep.map_sigma_m=[0.1]``, ``--set map.cell_m=20``). Every run draws from its own
streams (:mod:`bauv_sim.rng`): the same seed gives the same numbers whatever the blocks or the
workers. The modules: :mod:`tasks.trn.scenario`, :mod:`tasks.trn.run`, :mod:`tasks.trn.report`,
:mod:`tasks.trn.figures`; this one registers the experiment.
"""

from __future__ import annotations

from dataclasses import dataclass

from tasks.core.registry import Experiment, MemoryTerm, ReportContext, ReportSummary, register
from tasks.trn.report import TrnReliefMetrics, report_relief
from tasks.trn.run import check_filters, run_block, update_times
from tasks.trn.scenario import TrnReliefScenario

__all__ = ["TrnReliefExperiment"]


@dataclass(frozen=True)
class TrnReliefExperiment(Experiment):
    """TRN against relief and map error (module docstring)."""

    scenario_type = TrnReliefScenario
    metrics_type = TrnReliefMetrics

    def block_size(self, scenario: TrnReliefScenario) -> int:
        return scenario.runner.block_size

    def check(self, scenario: TrnReliefScenario, n_runs: int) -> None:
        check_filters(scenario.filters)

    def memory(self, scenario: TrnReliefScenario, n_runs: int) -> list[MemoryTerm]:
        """A block's truth, pings and errors, the PF's particles and the PMF's grid, and the true
        seabed of one run (generated once per relief); the report's per-run statistics."""
        pings = len(update_times(scenario)) * scenario.filters.update_every
        n_set = len(scenario.settings())
        block = min(scenario.runner.block_size, n_runs)
        f = scenario.filters
        seabed = scenario.terrain.seabed(1.0, 0)
        per_run = 8.0 * pings * 60 + 8.0 * n_set * 3 * pings / f.update_every
        return [
            MemoryTerm(
                block * per_run,
                True,
                f"track.duration_s = {scenario.track.duration_s:g} ({pings} pings) x "
                f"{n_set} settings in blocks of runner.block_size = {block} runs",
            ),
            MemoryTerm(
                8.0 * (20 * f.particles + 20 * f.grid_points**2),
                True,
                f"filters.particles = {f.particles}, filters.grid_points = {f.grid_points}",
            ),
            MemoryTerm(seabed.grid_bytes, True, seabed.grid_text.replace("seabed.", "terrain.")),
            MemoryTerm(8.0 * n_runs * n_set * 13, False, f"runs = {n_runs} x {n_set} settings"),
        ]

    def run_block(self, scenario: TrnReliefScenario, seed: int, runs: tuple[int, ...]):
        return run_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_relief(self.name, self.summary, ctx)


register(
    TrnReliefExperiment(
        name="trn/relief",
        summary="kinematic TRN Monte Carlo: PF and PMF error against relief (0.25-5 m) and map "
        "error, beside the PCRB and DVL dead reckoning",
        default_runs=8,
    )
)
