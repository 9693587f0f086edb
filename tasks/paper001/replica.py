"""Seed 001's experiment: correction procedures CP1 and CP2 under modelled currents (Tables 1-3).

Each mission (one Monte Carlo run) is flown in every grid cell ``(|Vg|, |Vc|, beta)`` twice: once
for CP1 (three random courses, the first two neither the same nor opposite) and once for CP2 (45,
225 deg, then a random course). Per mission and procedure:

1. legs 1 and 2 in the kinematic world (:mod:`bauv_sim.kinematic.seed001`, eq. 27-29) on the direct
   courses, each from a GPS fix with DR restarted there (eq. 30-31), surfacing at its end;
2. the correction procedure on the two legs' position errors (:func:`nav.surfacing.cp1` /
   :func:`nav.surfacing.cp2`), and the baseline (current = (GPS - DR) / time) on leg 2;
3. leg 3 on the direct course ``nu_3``, dead-reckoned uncorrected (eq. 30-31), with the CP's
   correction (eq. 32-33) and with the baseline's: Tables 1 and 2;
4. leg 3 again (same random draws) on the compensated course of eq. 22-26 (CP2: three phases):
   Table 3, the deviation of the true track from ``nu_3``.

Reading of the tables (the text does not define them; this reading reproduces the "without CP"
rows): the error "along 100 m distance" is the distance between DR and truth at the end of the
100 m leg after the correction (``T = 100 s``: the time uncorrected DR needs for it); Table 1 is its
mean over missions, Table 2 its maximum over missions. The error averaged over the leg's duration is
reported beside them. Table 3's deviation is the angle between the true displacement over leg 3 and
``nu_3``. The "without CP" and baseline rows pool both procedures' missions and both ``beta``
(the paper prints one such row per column); acceptance compares within each cell.

Randomness: every (mission, cell, procedure) has its own streams (courses, current, ``Vr`` of each
leg), so results do not depend on the grid, on block grouping or on the worker count; the two
leg-3 variants share their ``Vr`` draws and current (paired comparison).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from pydantic import BaseModel

from bauv_sim.config import Config
from tasks.core.registry import Experiment, ReportContext, ReportSummary, register
from tasks.core.report import write_metrics, write_tables
from tasks.paper001.figures import replica_figures
from tasks.paper001.report import Paper001Metrics, cell_metrics, paper_tables
from tasks.paper001.run import MissionBlock, merge_blocks, simulate_block
from tasks.paper001.scenario import NAME, Paper001Scenario

# --------------------------------------------------------------------------------------------
# Registration


@dataclass(frozen=True)
class Paper001Replica(Experiment):
    """Seed 001 Tables 1-3 in the kinematic world."""

    scenario_type: ClassVar[type[Config]] = Paper001Scenario
    metrics_type: ClassVar[type[BaseModel] | None] = Paper001Metrics

    def block_size(self, scenario: Config) -> int:
        assert isinstance(scenario, Paper001Scenario)
        return scenario.missions_per_block

    def run_block(self, scenario: Config, seed: int, runs: tuple[int, ...]) -> MissionBlock:
        assert isinstance(scenario, Paper001Scenario)
        return simulate_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        scenario = ctx.scenario
        assert isinstance(scenario, Paper001Scenario)
        block = merge_blocks(list(ctx.blocks))
        tables = paper_tables(block, scenario)
        files = write_tables(ctx.out_dir, tables, heading="Seed 001 replica: correction procedures")
        cells = cell_metrics(block)
        failed = [
            f"|Vg|={c.systematic_speed_m_s:g} |Vc|={c.current_speed_m_s:g} beta={c.beta_deg:g}"
            for c in cells
            if not c.ordering_nocp_cp1_cp2
        ]
        vc_max = max(scenario.current_speeds_m_s)
        fivefold = all(
            c.cp2_improvement_over_nocp >= 5.0 for c in cells if c.current_speed_m_s == vc_max
        )
        metrics = Paper001Metrics(
            experiment=NAME,
            seed=ctx.seed,
            n_missions=ctx.n_runs,
            step_s=scenario.world.step_s,
            rho_s_cos_coeffs=list(scenario.world.rho_s_cos_coeffs),
            current_speed_rel_var=scenario.world.current_speed_rel_var,
            current_speed_var_m2_s2=scenario.world.current_speed_var_m2_s2,
            cells=cells,
            acceptance_ordering_every_cell=not failed,
            acceptance_cp2_fivefold_at_max_current=fivefold,
            failed_cells=failed,
        )
        files.append(write_metrics(ctx.out_dir, metrics))
        if scenario.report.figures:
            files += replica_figures(ctx.out_dir, block, scenario)
        text = "\n".join(t.to_text() for t in tables)
        ordering = "yes" if not failed else "NO: " + "; ".join(failed)
        text += (
            f"\nacceptance: noCP > CP1 > CP2 in every cell: {ordering}"
            f"; CP2 >= 5x better than noCP at |Vc| = {vc_max:g}: {'yes' if fivefold else 'NO'}\n"
        )
        return ReportSummary(text, tuple(files))


register(
    Paper001Replica(
        name=NAME,
        summary="Seed 001 Tables 1-3: CP1, CP2 and the baseline under modelled currents "
        "(kinematic world, eq. 27-34)",
        default_runs=30,
    )
)
