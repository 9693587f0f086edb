"""``coop/team`` and ``coop/sensitivity``: a team of AUVs navigating together on kinematic truth,
for Monte Carlo at scale (issue 24).

A leader flies a racetrack near the surface under a ship's USBL (and a GPS fix at the start);
three followers keep stations around it at their own depths with a slow wander, on compass, log
and pressure only (:mod:`bauv_sim.kinematic.team`, :mod:`tasks.coop.measure`). Every vehicle
broadcasts on an acoustic network in TDMA slots; every other vehicle receives each broadcast and
measures a one-way travel time on its own drifting clock (:class:`bauv_sim.acoustics.
AcousticNetwork`: the sender's and the receiver's positions at their own instants, the true
medium, the sonar equation, collisions). The same measurements go to every method of
:func:`nav.cooperative.team_tracks`:

* ``dr``: dead reckoning from the start;
* ``ga2`` and ``leader-ekf``: seed 003's positioning of each follower on its ranges to the leader
  alone (geodetic adjustment GA2, range EKF; no clock);
* ``decentralised``: each vehicle's own filter with its clock offset in the state, fusing ranges
  from every other vehicle with the sender's broadcast estimate by covariance intersection;
* ``central``: one EKF over the whole team with every range and every clock (the reference).

``coop/team`` reports per vehicle and method the mean and final error, the NEES beside its
chi-square band, the clock-offset error; ``coop/sensitivity`` repeats it over clock drift,
sound-speed mismatch and packet loss (one change at a time from the base, same runs and draws).

Run: ``bauv run coop/team`` (``--runs 100``, ``--set team.duration_s=300``...). The modules:
:mod:`tasks.coop.scenario`, :mod:`tasks.coop.measure`, :mod:`tasks.coop.setting`,
:mod:`tasks.coop.run`, :mod:`tasks.coop.report`, :mod:`tasks.coop.figures`; this one registers
the experiments.
"""

from __future__ import annotations

from dataclasses import dataclass

from tasks.coop.report import CoopMetrics, report_coop
from tasks.coop.run import check, run_block
from tasks.coop.scenario import CoopScenario
from tasks.core.registry import Experiment, MemoryTerm, ReportContext, ReportSummary, register

__all__ = ["CoopExperiment"]

SENSITIVITY = {
    "sweep": {
        "drift_ppm": [10.0, 100.0],
        "sound_speed_m_s": [1480.0, 1520.0],
        "sound_profile": ["munk"],
        "source_level_db": [125.0, 120.0, 115.0],
    }
}
"""The preset of ``coop/sensitivity``: one change at a time from the base."""


@dataclass(frozen=True)
class CoopExperiment(Experiment):
    """A team navigating together (module docstring)."""

    scenario_type = CoopScenario
    metrics_type = CoopMetrics

    def block_size(self, scenario: CoopScenario) -> int:
        return scenario.runner.block_size

    def check(self, scenario: CoopScenario, n_runs: int) -> None:
        check(scenario)

    def memory(self, scenario: CoopScenario, n_runs: int) -> list[MemoryTerm]:
        """A block's measurements and one method's tracks (positions, covariances, clocks of
        every vehicle at every sample); the report's per-run statistics."""
        k = scenario.team.n_ticks
        v = len(scenario.team.names)
        block = min(scenario.runner.block_size, n_runs)
        n_set = len(scenario.settings())
        m = len(scenario.methods)
        return [
            MemoryTerm(
                8.0 * block * v * k * 40,
                True,
                f"team.duration_s = {scenario.team.duration_s:g} ({k} samples of team.tick_s) x "
                f"{v} vehicles in blocks of runner.block_size = {block} runs",
            ),
            MemoryTerm(
                8.0 * n_runs * n_set * m * v * 4,
                False,
                f"runs = {n_runs} x {n_set} settings x {m} methods",
            ),
        ]

    def run_block(self, scenario: CoopScenario, seed: int, runs: tuple[int, ...]):
        return run_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_coop(self.name, self.summary, ctx)


register(
    CoopExperiment(
        name="coop/team",
        summary="kinematic team of a leader on USBL and three followers: DR, seed 003's "
        "leader-only GA2 and EKF, decentralised (CI) and central cooperative navigation on OWTT "
        "ranges with clocks",
        default_runs=100,
    )
)
register(
    CoopExperiment(
        name="coop/sensitivity",
        summary="coop/team's methods against clock drift, sound-speed mismatch and packet loss",
        preset=SENSITIVITY,
        default_runs=10,
    )
)
