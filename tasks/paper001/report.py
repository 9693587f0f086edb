"""Seed 001 replica's report: per-cell statistics, the paper's Tables 1-3 beside ours, the
metrics and the fit of the paper's numbers (:mod:`tasks.paper001.replica`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import BaseModel, Field

from tasks.core.report import Table
from tasks.paper001.paper import PAPER, PAPER_COLUMNS, paper_value
from tasks.paper001.run import MissionBlock, merge_blocks, simulate_block
from tasks.paper001.scenario import Array, Paper001Scenario

# --------------------------------------------------------------------------------------------
# Statistics, tables and metrics


class MethodStats(BaseModel):
    """Statistics of one DR / course method in one cell."""

    n_legs: int
    mean_end_error_m: float = Field(description="Table 1: mean DR error at the end of leg 3")
    max_end_error_m: float = Field(description="Table 2: largest DR error at the end of leg 3")
    mean_along_leg_error_m: float = Field(description="DR error averaged over leg 3 and missions")
    mean_course_deviation_deg: float = Field(description="Table 3: |course over ground - nu|")
    mean_current_error_m_s: float | None = Field(
        None, description="|estimated - true mean current| on leg 3"
    )


class CellMetrics(BaseModel):
    """One grid cell."""

    systematic_speed_m_s: float
    current_speed_m_s: float
    beta_deg: float
    nocp: MethodStats
    cp1: MethodStats
    cp2: MethodStats
    baseline: MethodStats
    ordering_nocp_cp1_cp2: bool = Field(description="mean end error noCP > CP1 > CP2")
    cp2_improvement_over_nocp: float = Field(description="mean end error noCP / CP2")


class Paper001Metrics(BaseModel):
    """``metrics.json`` of ``paper-001/replica``."""

    experiment: str
    seed: int
    n_missions: int
    step_s: float
    rho_s_cos_coeffs: list[float]
    current_speed_rel_var: float
    current_speed_var_m2_s2: float
    cells: list[CellMetrics]
    acceptance_ordering_every_cell: bool
    acceptance_cp2_fivefold_at_max_current: bool
    failed_cells: list[str]


def _stats(block: MissionBlock, ci: int, procs: list[int], kind: str, dev: str) -> MethodStats:
    d = block.data
    end = d[f"end_error_{kind}_m"][:, ci, procs].ravel()
    cur = None
    if kind == "cp":
        cur = float(np.mean(d["current_error_cp_m_s"][:, ci, procs]))
    elif kind == "baseline":
        cur = float(np.mean(d["current_error_baseline_m_s"][:, ci, procs]))
    return MethodStats(
        n_legs=int(end.size),
        mean_end_error_m=float(np.mean(end)),
        max_end_error_m=float(np.max(end)),
        mean_along_leg_error_m=float(np.mean(d[f"mean_error_{kind}_m"][:, ci, procs])),
        mean_course_deviation_deg=float(np.mean(d[f"deviation_{dev}_deg"][:, ci, procs])),
        mean_current_error_m_s=cur,
    )


def cell_metrics(block: MissionBlock) -> list[CellMetrics]:
    """Per-cell statistics of the merged missions."""
    out = []
    for ci, (vg, vc, b) in enumerate(block.cells):
        nocp = _stats(block, ci, [0, 1], "nocp", "direct")
        cp1 = _stats(block, ci, [0], "cp", "cp")
        cp2 = _stats(block, ci, [1], "cp", "cp")
        base = _stats(block, ci, [0, 1], "baseline", "baseline")
        e0, e1, e2 = nocp.mean_end_error_m, cp1.mean_end_error_m, cp2.mean_end_error_m
        out.append(
            CellMetrics(
                systematic_speed_m_s=vg,
                current_speed_m_s=vc,
                beta_deg=b,
                nocp=nocp,
                cp1=cp1,
                cp2=cp2,
                baseline=base,
                ordering_nocp_cp1_cp2=bool(e0 > e1 > e2),
                cp2_improvement_over_nocp=float(e0 / e2) if e2 > 0 else float("inf"),
            )
        )
    return out


def _pooled(block: MissionBlock, key: str, vg: float, vc: float, procs: list[int]) -> Array:
    sel = [i for i, c in enumerate(block.cells) if c[0] == vg and c[1] == vc]
    return block.data[key][:, sel][:, :, procs].ravel()


def paper_tables(block: MissionBlock, scenario: Paper001Scenario) -> list[Table]:
    """Tables 1-3 in the paper's layout (ours beside the paper's), plus supplementary tables."""
    cols = [(vg, vc) for vg in scenario.systematic_speeds_m_s for vc in scenario.current_speeds_m_s]
    header = ["row"]
    for vg, vc in cols:
        header += [f"|Vg|={vg:g} |Vc|={vc:g}", "paper"]
    specs = [
        (
            "table1",
            "end_error_{}_m",
            np.mean,
            "Table 1. Average errors [m] along the 100 m leg "
            "after the correction (DR error at its end, mean over missions)",
        ),
        (
            "table2",
            "end_error_{}_m",
            np.max,
            "Table 2. Maximum errors [m] along the 100 m leg "
            "after the correction (largest over missions)",
        ),
        (
            "table3",
            "deviation_{}_deg",
            np.mean,
            "Table 3. Average deviation [deg] of the course "
            "over ground from the desired course, direct course (without CP) and Eq. 22-26 (CP)",
        ),
    ]
    n = len(block.runs)
    tables = []
    for tname, pattern, agg, title in specs:
        dev = tname == "table3"
        # (label, method, beta or None for pooled rows, data kind, procedures)
        row_specs: list[tuple[str, str, float | None, str, list[int]]] = [
            ("without CP", "nocp", None, "direct" if dev else "nocp", [0, 1])
        ]
        for b in scenario.betas_deg:
            row_specs.append((f"beta = {b:g}: CP1", "cp1", b, "cp", [0]))
            row_specs.append((f"beta = {b:g}: CP2", "cp2", b, "cp", [1]))
        row_specs.append(("baseline (GPS-DR)/T", "baseline", None, "baseline", [0, 1]))
        rows: list[list[Any]] = []
        for label, method, beta, kind, procs in row_specs:
            cells: list[Any] = [label]
            for vg, vc in cols:
                key = pattern.format(kind)
                if beta is None:
                    vals = _pooled(block, key, vg, vc, procs)
                else:
                    ci = block.cells.index((vg, vc, beta))
                    vals = block.data[key][:, ci, procs].ravel()
                cells += [float(agg(vals)), paper_value(tname, method, beta, vg, vc)]
            rows.append(cells)
        note = (
            f"{n} missions per procedure and cell; 'without CP' and baseline pool both procedures' "
            f"missions and every beta ({2 * n * len(scenario.betas_deg)} legs per column)."
        )
        tables.append(Table(title, header, rows, digits=2, note=note, slug=tname))

    # supplementary: per cell, errors averaged over the leg and current estimate errors
    sup_rows = []
    for c in cell_metrics(block):
        sup_rows.append(
            [
                f"{c.systematic_speed_m_s:g}",
                f"{c.current_speed_m_s:g}",
                f"{c.beta_deg:g}",
                c.nocp.mean_end_error_m,
                c.cp1.mean_end_error_m,
                c.cp2.mean_end_error_m,
                c.baseline.mean_end_error_m,
                c.nocp.mean_along_leg_error_m,
                c.cp1.mean_along_leg_error_m,
                c.cp2.mean_along_leg_error_m,
                c.cp1.mean_current_error_m_s,
                c.cp2.mean_current_error_m_s,
                c.baseline.mean_current_error_m_s,
                "yes" if c.ordering_nocp_cp1_cp2 else "NO",
                c.cp2_improvement_over_nocp,
            ]
        )
    tables.append(
        Table(
            "Per cell: mean end-of-leg error [m], error averaged over the leg [m], current "
            "estimate error on leg 3 [m/s], acceptance",
            [
                "|Vg|",
                "|Vc|",
                "beta",
                "end noCP",
                "end CP1",
                "end CP2",
                "end base",
                "leg-avg noCP",
                "leg-avg CP1",
                "leg-avg CP2",
                "dVc CP1",
                "dVc CP2",
                "dVc base",
                "noCP>CP1>CP2",
                "noCP/CP2",
            ],
            sup_rows,
            digits=3,
            slug="per-cell",
        )
    )
    return tables


def paper_log_ratios(block: MissionBlock) -> Array:
    """``log(ours / paper)`` for every mean the paper prints in Tables 1 and 3 (the without-CP,
    CP1 and CP2 rows; 40 values) that the block's grid covers."""
    out = []
    for t, pattern in (("table1", "end_error_{}_m"), ("table3", "deviation_{}_deg")):
        for (method, beta), paper in PAPER[t].items():
            for (vg, vc), pv in zip(PAPER_COLUMNS, paper, strict=True):
                if method == "nocp":
                    kind = "nocp" if t == "table1" else "direct"
                    vals = _pooled(block, pattern.format(kind), vg, vc, [0, 1])
                elif (vg, vc, beta) in block.cells:
                    ci = block.cells.index((vg, vc, beta))
                    proc = [0] if method == "cp1" else [1]
                    vals = block.data[pattern.format("cp")][:, ci, proc].ravel()
                else:
                    continue
                if vals.size:
                    out.append(math.log(float(np.mean(vals)) / pv))
    return np.array(out)


def paper_fit_objective(
    scenario: Paper001Scenario, seeds: tuple[int, ...], n_missions: int = 30
) -> float:
    """RMS over the paper's Table 1 and 3 means of ``log(ours / paper)``, each averaged over seeds.

    This is how the default hull response ``rho_s`` was chosen (see
    :class:`nav.surfacing.CurrentResponse`)::

        for a1, a2 in itertools.product(np.arange(0, 0.26, 0.05), repeat=2):
            sc = load_config(Paper001Scenario, {}, (), ["world.step_s=0.02",
                             f"world.rho_s_cos_coeffs=[1.0, {a1}, {a2}]"])
            print(a1, a2, paper_fit_objective(sc, (101, 102, 103)))

    Args:
        scenario: the experiment (its grid should contain the paper's).
        seeds: batch seeds to average over.
        n_missions: missions per seed.

    Returns:
        The RMS log ratio (0 when every mean equals the paper's).
    """
    runs = tuple(range(n_missions))
    logs = [paper_log_ratios(merge_blocks([simulate_block(scenario, s, runs)])) for s in seeds]
    return float(np.sqrt(np.mean(np.mean(logs, axis=0) ** 2)))
