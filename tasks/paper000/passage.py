"""Seed 000 (Naus & Nowak 2016): DR, EKF and USBL-only positioning on a straight passage.

Registers ``paper-000/test-1``, ``test-2`` and ``test-3``: the BAUV passes a seabed USBL
transceiver (section 6, Figure 7) while COG, SOG and the depth change are measured every second and
USBL range, azimuth and elevation every 5, 20 or 100 s. Each passage is positioned three ways:

* **DR**: dead reckoning from the measured course, speed and depth change (eq. 8, 16);
* **EKF**: the extended Kalman filter of eq. 15-23 fusing the same inputs with the USBL fixes;
* **USBL**: the position computed from each USBL measurement alone (inverse of eq. 15).

The report gives the paper's tables: for single passages the minimum, maximum and mean distance to
the reference position; for N passages the same statistics of zeta(k), the mean over passages of the
distance at moment k (eq. 24 writes a sum; the figures and the tables' values are a mean). Distances
are horizontal for EKF and DR and three-dimensional for USBL (its elevation error dominates; see
``../shared/seeds/README.md``). Statistics run over ticks 1..T (the paper's tables start after the
first measurement: their smallest DR and EKF distances are the one-step error, not the zero initial
error) and over the fix times for USBL.

The experiment is scenario + run + report: :mod:`tasks.paper000.scenario` (the devices, the
filter's assumptions, the readings of the paper where it is silent), :mod:`tasks.paper000.run`
(the sensors sampled along the passage, the navigations of :mod:`nav.usbl`, the block's
statistics), :mod:`tasks.paper000.report` (metrics, tables, :mod:`~tasks.paper000.figures`,
:mod:`~tasks.paper000.recording`) and the paper's numbers as data (:mod:`tasks.paper000.paper`).
"""

from __future__ import annotations

from dataclasses import dataclass

from bauv_sim.config import load_config, to_plain
from bauv_sim.errors import ConfigError
from tasks.core.registry import (
    Experiment,
    MemoryTerm,
    ReportContext,
    ReportSummary,
    register,
)
from tasks.paper000.paper import PAPER_TABLES
from tasks.paper000.recording import record_passage
from tasks.paper000.report import Paper000Metrics, report_paper000
from tasks.paper000.run import (
    BLOCK_BYTES_PER_RUN_TICK,
    METHODS,
    measure_passages,
    reduce_block,
    run_ekf,
    simulate_passages,
)
from tasks.paper000.scenario import Paper000Scenario, block_passages

__all__ = [
    "PAPER_TABLES",
    "Paper000Scenario",
    "StraightPassageExperiment",
    "measure_passages",
    "record_passage",
    "run_ekf",
    "simulate_passages",
]
"""Names other code reads from this module (the experiment's parts live in the modules above)."""


@dataclass(frozen=True)
class StraightPassageExperiment(Experiment):
    """Seed 000 test: N passages with USBL fixes every ``usbl_period_s``."""

    scenario_type = Paper000Scenario
    metrics_type = Paper000Metrics
    test: str = "test-1"

    def block_size(self, scenario: Paper000Scenario) -> int:
        return block_passages(scenario)

    def check(self, scenario: Paper000Scenario, n_runs: int) -> None:
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )

    def run_block(self, scenario: Paper000Scenario, seed: int, runs: tuple[int, ...]):
        return reduce_block(scenario, simulate_passages(scenario, seed, runs))

    def memory(self, scenario: Paper000Scenario, n_runs: int) -> list[MemoryTerm]:
        """Estimated peak memory of a batch, bytes, in parts (see :class:`MemoryTerm`).

        A block holds every passage's paths for every tick (:data:`BLOCK_BYTES_PER_RUN_TICK`),
        and its histograms; the report holds the per-tick sums of every method, the routes and
        single passages it draws, the histograms and a few numbers per run.
        """
        p, rep = scenario.passage, scenario.report
        ticks = p.duration_s / p.tick_s + 1
        block = min(block_passages(scenario), n_runs)
        bins = rep.histogram_max_m / rep.histogram_bin_m
        timing = (
            f"passage.duration_s = {p.duration_s:g} with passage.tick_s = {p.tick_s:g} s "
            f"({ticks:.3g} ticks)"
        )
        paths = min(rep.routes_max, n_runs) * 36 + rep.single_passages * 24 + 160
        return [
            MemoryTerm(
                BLOCK_BYTES_PER_RUN_TICK * block * ticks,
                True,
                f"{timing} in blocks of runner.block_size = {block} passages",
            ),
            MemoryTerm(paths * ticks, False, timing),
            MemoryTerm(
                2 * len(METHODS) * 8 * bins,
                True,
                f"report.histogram_bin_m = {rep.histogram_bin_m:g} ({bins:.3g} bins up to "
                f"report.histogram_max_m = {rep.histogram_max_m:g})",
            ),
            MemoryTerm(110.0 * n_runs, False, f"runs = {n_runs}"),
        ]

    def off_paper_fields(self, scenario: Paper000Scenario) -> list[str]:
        """The scenario fields that differ from the paper's setting of this test.

        The ``report`` and ``runner`` sections do not change the numbers and are left out. The
        paper's tables are compared (labelled, with a ratio) only when this list is empty.

        Returns:
            Dotted field names, sorted.
        """
        paper = _flat(to_plain(load_config(Paper000Scenario, self.preset)))
        mine = _flat(to_plain(scenario))
        return sorted(
            k
            for k in set(paper) | set(mine)
            if k.split(".")[0] not in ("report", "runner") and paper.get(k) != mine.get(k)
        )

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_paper000(self, ctx)


def _flat(data: dict, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for k, v in data.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


_SUMMARY = "seed 000 Test {n}: straight passage, USBL fix every {p:g} s; DR vs EKF vs USBL"
for _n, _test in enumerate(("test-1", "test-2", "test-3"), start=1):
    _period = PAPER_TABLES[_test]["usbl_period_s"]
    register(
        StraightPassageExperiment(
            name=f"paper-000/{_test}",
            summary=_SUMMARY.format(n=_n, p=_period),
            preset={"sensors": {"usbl": {"period_s": _period}}},
            default_runs=100,
            test=_test,
        )
    )
