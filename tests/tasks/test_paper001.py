"""Seed 001's replica end to end (acceptance 2 at CI size), determinism and the step size.

CI runs the full 30 missions per cell at a coarse step of 0.02 s (about a second): the step only
changes the white-noise ``Vr`` (see ``bauv_sim.kinematic.seed001``), which
``test_coarse_step_keeps_the_statistics`` bounds on paired missions. The replica reported in the
issue runs at the paper's 0.001 s.
"""

import json

import numpy as np
import pytest

from bauv_sim.config import load_config
from tasks.core import registry
from tasks.core.runner import run
from tasks.paper001 import paper as p001_paper
from tasks.paper001 import replica as paper001
from tasks.paper001 import report as p001_report
from tasks.paper001 import run as p001_run
from tasks.paper001 import scenario as p001_scenario

COARSE = ["world.step_s=0.02"]


def scenario(*overrides):
    return load_config(p001_scenario.Paper001Scenario, {}, (), list(overrides))


@pytest.fixture(scope="module")
def replica(tmp_path_factory):
    out = tmp_path_factory.mktemp("p001") / "run"
    run(paper001.NAME, seed=1, out_dir=out, overrides=COARSE, progress=False)
    return out


def test_registered_with_the_papers_parameters():
    exp = registry.get(paper001.NAME)
    assert exp.default_runs == 30
    sc = load_config(exp.scenario_type, exp.preset)
    assert sc.systematic_speeds_m_s == (0.1, 0.3) and sc.current_speeds_m_s == (0.1, 0.5)
    assert sc.betas_deg == (5.0, 20.0) and sc.cp1_beta_max_deg == 20.0
    w = sc.world
    assert (w.current_direction_deg, w.random_speed_max_m_s, w.step_s) == (20.0, 0.3, 0.001)
    assert (w.current_speed_rel_var, w.current_direction_var_deg2) == (0.02, 10.0)
    assert w.current_hold_max_steps == 10000 and w.vehicle_speed_m_s == 1.0


@pytest.mark.slow
def test_acceptance_2_ordering_and_improvement(replica):
    m = json.loads((replica / "metrics.json").read_text())
    p001_report.Paper001Metrics.model_validate(m)
    assert m["n_missions"] == 30 and len(m["cells"]) == 8
    for c in m["cells"]:
        e = [c[k]["mean_end_error_m"] for k in ("nocp", "cp1", "cp2")]
        assert e[0] > e[1] > e[2], c
        if c["current_speed_m_s"] == 0.5:
            assert e[0] / e[2] >= 5.0, c
        # the compensated course also orders the deviations from the desired course
        d = [c[k]["mean_course_deviation_deg"] for k in ("nocp", "cp1", "cp2")]
        assert d[0] > d[1] > d[2], c
    assert m["acceptance_ordering_every_cell"] and m["acceptance_cp2_fivefold_at_max_current"]
    assert m["failed_cells"] == []


def test_uncorrected_rows_reproduce_the_paper(replica):
    """Without CP the error after 100 m is |Vs + Vc_eff| x 100 s: the geometry and eq. 29's hull
    scaling, not the procedures. Within 25 % of the paper's 30-mission means."""
    rows = (replica / "tables" / "table1.csv").read_text().splitlines()
    nocp = rows[1].split(",")
    assert nocp[0] == "without CP"
    ours = [float(x) for x in nocp[1::2]]
    paper = [float(x) for x in nocp[2::2]]
    assert paper == [12.84, 47.96, 31.1, 43.19]
    assert np.allclose(ours, paper, rtol=0.25), ours


def test_run_folder_is_complete(replica):
    for name in [
        "metrics.json",
        "tables.md",
        "tables/table1.csv",
        "tables/table2.csv",
        "tables/table3.csv",
        "tables/per-cell.csv",
        "tracks-cp1-mission0.png",
        "tracks-cp2-mission0.png",
        "course-cp1-mission0.png",
        "course-cp2-mission0.png",
        "error-along-leg3.png",
        "scenario.toml",
    ]:
        assert (replica / name).is_file(), name
    md = (replica / "tables.md").read_text()
    for title in ("Table 1.", "Table 2.", "Table 3.", "beta = 20: CP2", "baseline", "paper"):
        assert title in md


def test_results_do_not_depend_on_block_grouping():
    sc = scenario(*COARSE, "report.figure_missions=3")
    whole = p001_run.simulate_block(sc, 4, (0, 1, 2))
    parts = p001_run.merge_blocks(
        [p001_run.simulate_block(sc, 4, (0,)), p001_run.simulate_block(sc, 4, (1, 2))]
    )
    assert whole.data.keys() == parts.data.keys()
    for k in whole.data:
        assert np.array_equal(whole.data[k], parts.data[k]), k
    assert len(whole.tracks) == len(parts.tracks) == 6
    # a different seed is a different experiment
    other = p001_run.simulate_block(sc, 5, (0,))
    assert not np.array_equal(other.data["courses_deg"][0], whole.data["courses_deg"][0])


@pytest.mark.slow
def test_coarse_step_keeps_the_statistics():
    """Paired missions at t = 0.001 s and 0.02 s: courses and current are identical, only Vr
    differs (0.04 vs 0.18 m per axis over a leg): cell means move by a fraction of a metre."""
    runs = (0, 1, 2)
    fine = p001_run.simulate_block(scenario("report.figures=false"), 9, runs)
    coarse = p001_run.simulate_block(scenario(*COARSE, "report.figures=false"), 9, runs)
    assert np.array_equal(fine.data["courses_deg"], coarse.data["courses_deg"])
    for kind in ("nocp", "cp", "baseline"):
        d = fine.data[f"end_error_{kind}_m"] - coarse.data[f"end_error_{kind}_m"]
        assert np.max(np.abs(d.mean(axis=0))) < 0.6, kind
    for kind in ("direct", "cp"):
        d = fine.data[f"deviation_{kind}_deg"] - coarse.data[f"deviation_{kind}_deg"]
        assert np.max(np.abs(d.mean(axis=0))) < 0.3, kind


def test_paper_values_lookup():
    assert p001_paper.paper_value("table1", "cp2", 5.0, 0.3, 0.1) == 0.93
    assert p001_paper.paper_value("table3", "nocp", 20.0, 0.3, 0.5) == 16.52
    assert p001_paper.paper_value("table2", "cp1", 10.0, 0.3, 0.5) is None
    assert p001_paper.paper_value("table1", "cp1", 5.0, 0.2, 0.5) is None


@pytest.mark.slow
def test_fit_objective_prefers_the_default_hull_response():
    """The default rho_s was fitted to the paper's Tables 1 and 3 (nav.surfacing.CurrentResponse);
    on a seed outside the fit it still beats a hull without angle dependence."""
    fitted = p001_report.paper_fit_objective(scenario(*COARSE, "report.figures=false"), (7,))
    flat = p001_report.paper_fit_objective(
        scenario(*COARSE, "report.figures=false", "world.rho_s_cos_coeffs=[1.0]"), (7,)
    )
    assert fitted < 0.45 < flat
