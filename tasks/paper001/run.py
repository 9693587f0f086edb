"""Seed 001 replica's missions: a block of runs in every cell, CP1 and CP2, legs 1-3 in the
kinematic world with :mod:`nav.surfacing`'s procedures (:mod:`tasks.paper001.replica`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bauv_sim import rng as rng_mod
from bauv_sim.frames import velocity_from_course_speed
from bauv_sim.kinematic import seed001 as kin
from nav.angles import course_of, diff_course, unit_vector
from nav.surfacing import (
    CurrentResponse,
    baseline,
    compensated_course,
    cp1,
    cp2,
    dr_track,
    dr_velocity,
)
from tasks.core import store
from tasks.paper001.scenario import DR_KINDS, PROCEDURES, Array, Paper001Scenario, cell_key

# --------------------------------------------------------------------------------------------
# Missions


@store.plain_data("paper001.MissionBlock")
@dataclass(frozen=True)
class MissionBlock:
    """The results of a block of missions (plain data: kept on disk by the runner).

    Attributes:
        runs: the mission indices.
        cells: the grid cells ``(|Vg|, |Vc|, beta_deg)``.
        data: named arrays of shape (runs, cells, procedures[, ...]); procedures in
            :data:`PROCEDURES` order.
        tracks: example tracks of the figure cell, one dict per (figure mission, procedure).
    """

    runs: tuple[int, ...]
    cells: tuple[tuple[float, float, float], ...]
    data: dict[str, Array]
    tracks: list[dict[str, Any]] = field(default_factory=list)


def _streams(seed: int, rows: list[tuple[int, str, str]], *names: str) -> list[np.random.Generator]:
    return [rng_mod.generator(seed, run, "paper-001", ck, proc, *names) for run, ck, proc in rows]


def simulate_procedure(
    scenario: Paper001Scenario, seed: int, runs: tuple[int, ...], procedure: str
) -> tuple[dict[str, Array], list[dict[str, Any]]]:
    """Fly the missions of one procedure in every cell.

    Args:
        scenario: the experiment.
        seed: batch seed.
        runs: mission indices.
        procedure: ``"cp1"`` or ``"cp2"``.

    Returns:
        ``(data, tracks)``: arrays of shape (len(runs), n_cells[, ...]) and the figure tracks.
    """
    cfg = scenario.world
    cells = scenario.cells()
    rows = [(run, cell_key(c), procedure) for run in runs for c in cells]
    n = len(rows)
    shape = (len(runs), len(cells))
    cell_arr = np.array([c for _ in runs for c in cells])  # (n, 3)
    vehicle = kin.Seed001Vehicle(cell_arr[:, 0], np.radians(cell_arr[:, 2]))
    vc = cell_arr[:, 1]
    T = cfg.leg_duration_s
    va = cfg.vehicle_speed_m_s

    nu = kin.draw_courses(
        procedure,  # type: ignore[arg-type]
        _streams(seed, rows, "courses"),
        cp1_min_separation_rad=math.radians(scenario.cp1_min_course_separation_deg),
        cp2_courses_rad=tuple(math.radians(a) for a in scenario.cp2_courses_deg),  # type: ignore[arg-type]
    )
    pert = kin.draw_perturbations(cfg, 3.0 * T + cfg.sample_s, _streams(seed, rows, "current"))

    def leg(start: Array, j: int, course: Array) -> kin.LegTruth:
        return kin.leg_truth(
            cfg, vehicle, vc, pert, start, (j - 1) * T, course, _streams(seed, rows, f"vr-leg{j}")
        )

    leg1 = leg(np.zeros((n, 2)), 1, nu[:, 0])
    leg2 = leg(leg1.pos_world_m[:, -1], 2, nu[:, 1])
    dr_disp = va * T * unit_vector(nu[:, :2])  # eq. 30-31 over each leg
    delta = np.stack([leg1.displacement_world_m, leg2.displacement_world_m], axis=1) - dr_disp
    if procedure == "cp1":
        est = cp1(
            delta,
            T,
            nu[:, :2],
            beta_max_rad=math.radians(scenario.cp1_beta_max_deg),
            beta_step_rad=math.radians(scenario.cp1_beta_step_deg),
            min_separation_rad=math.radians(scenario.cp1_min_course_separation_deg),
        )
    else:
        est = cp2(delta, T, nu[:, :2], response=CurrentResponse(cfg.rho_s_cos_coeffs))
    fix2 = leg2.pos_world_m[:, -1]
    base = baseline(fix2, leg2.pos_world_m[:, 0] + dr_disp[:, 1], T)

    # leg 3 on the direct course: Tables 1-2
    leg3 = leg(fix2, 3, nu[:, 2])
    k = cfg.samples_per_leg
    dr = {
        kind: dr_track(
            fix2,
            np.broadcast_to(dr_velocity(nu[:, 2], va, e)[:, None, :], (n, k, 2)),
            cfg.sample_s,
        )
        for kind, e in (("nocp", None), ("cp", est), ("baseline", base))
    }
    err = {kind: np.linalg.norm(dr[kind] - leg3.pos_world_m, axis=-1) for kind in DR_KINDS}

    # leg 3 on the compensated course (same draws): Table 3
    sol_cp = compensated_course(nu[:, 2], va, est)
    sol_base = compensated_course(nu[:, 2], va, base)
    leg3_cp = leg(fix2, 3, sol_cp.course_rad)
    leg3_base = leg(fix2, 3, sol_base.course_rad)

    def deviation(lt: kin.LegTruth) -> Array:
        return np.degrees(diff_course(course_of(lt.displacement_world_m), nu[:, 2]))

    c_est3 = est.current_for_course(nu[:, 2])
    true_vs_world = velocity_from_course_speed(nu[:, 0] + vehicle.beta_rad, vehicle.vs_m_s)
    est_vs_world = est.vs_world(nu[:, 0])
    data: dict[str, Array] = {
        "courses_deg": np.degrees(nu),
        "cp_valid": est.valid.astype(float),
        "vs_est_m_s": est.vs_m_s,
        "beta_est_deg": np.degrees(est.beta_rad),
        "vs_error_m_s": np.linalg.norm(est_vs_world - true_vs_world, axis=-1),
        "current_est_leg3_m_s": c_est3,
        "current_true_leg3_m_s": leg3.mean_current_world_m_s,
        "current_true_leg12_m_s": 0.5 * (leg1.mean_current_world_m_s + leg2.mean_current_world_m_s),
        "current_error_cp_m_s": np.linalg.norm(c_est3 - leg3.mean_current_world_m_s, axis=-1),
        "current_error_baseline_m_s": np.linalg.norm(
            base.current_world_m_s - leg3.mean_current_world_m_s, axis=-1
        ),
        "deviation_direct_deg": deviation(leg3),
        "deviation_cp_deg": deviation(leg3_cp),
        "deviation_baseline_deg": deviation(leg3_base),
        "compensated_course_deg": np.degrees(sol_cp.course_rad),
        "compensation_feasible": sol_cp.feasible.astype(float),
    }
    for kind in DR_KINDS:
        data[f"end_error_{kind}_m"] = err[kind][:, -1]
        data[f"mean_error_{kind}_m"] = np.mean(err[kind], axis=1)
        data[f"error_curve_{kind}_m"] = err[kind]
    data = {key: v.reshape(shape + v.shape[1:]) for key, v in data.items()}

    tracks: list[dict[str, Any]] = []
    fig_cell = tuple(scenario.report.figure_cell)
    if scenario.report.figures and fig_cell in [tuple(c) for c in cells]:
        ci = [tuple(c) for c in cells].index(fig_cell)
        for ri, run in enumerate(runs):
            if run >= scenario.report.figure_missions:
                continue
            i = ri * len(cells) + ci
            tracks.append(
                {
                    "run": run,
                    "procedure": procedure,
                    "cell": fig_cell,
                    "truth": [lt.pos_world_m[i] for lt in (leg1, leg2, leg3)],
                    "truth_compensated": leg3_cp.pos_world_m[i],
                    "truth_compensated_baseline": leg3_base.pos_world_m[i],
                    "dr": {kind: dr[kind][i] for kind in DR_KINDS},
                    "nu_deg": np.degrees(nu[i]),
                    "alpha3_compensated_deg": float(np.degrees(sol_cp.course_rad[i])),
                    "waypoint3": fix2[i] + cfg.leg_length_m * unit_vector(nu[i, 2]),
                    "current_est": c_est3[i],
                    "current_baseline": base.current_world_m_s[i],
                    "current_true": leg3.mean_current_world_m_s[i],
                    "t_s": leg3.t_s,
                }
            )
    return data, tracks


def simulate_block(scenario: Paper001Scenario, seed: int, runs: tuple[int, ...]) -> MissionBlock:
    """Fly a block of missions for both procedures in every cell (see the module docstring)."""
    parts = [simulate_procedure(scenario, seed, runs, p) for p in PROCEDURES]
    keys = parts[0][0].keys()
    data = {key: np.stack([p[0][key] for p in parts], axis=2) for key in keys}
    tracks = [t for p in parts for t in p[1]]
    return MissionBlock(tuple(runs), tuple(scenario.cells()), data, tracks)


def merge_blocks(blocks: list[MissionBlock]) -> MissionBlock:
    """Concatenate blocks along the mission axis (in block order)."""
    if not blocks:
        raise ValueError("no blocks to merge")
    data = {k: np.concatenate([b.data[k] for b in blocks], axis=0) for k in blocks[0].data}
    runs = tuple(r for b in blocks for r in b.runs)
    return MissionBlock(runs, blocks[0].cells, data, [t for b in blocks for t in b.tracks])
