"""Terminal output a newcomer reads right: every line within 100 columns (tables narrowed on the
screen, whole in the files), misspelt fields answered with the nearest valid names."""

import csv
import io
import textwrap

import pytest

from bauv_sim.config import Config
from tasks.core import registry
from tasks.core.console import WIDTH, labelled, table, wrap
from tasks.core.report import Table
from tests.tasks.refusal import run_in_process

# --- the helper, against what it must keep -------------------------------------------------------


def _table(n_cols: int, key: int = 1) -> Table:
    cols = ["Method", *(f"column number {i} (m)" for i in range(1, n_cols))]
    rows = [[m, *(i * 1.25 for i in range(1, n_cols))] for m in ("DR", "GA1", "EKF")]
    return Table("a title " * 30, cols, rows, digits=2, note="a note " * 40, key=key)


def test_a_wide_table_is_narrowed_on_the_screen_and_whole_in_the_files():
    t = _table(19)
    text = t.to_text()
    lines = text.splitlines()
    assert max(map(len, lines)) <= WIDTH
    # every cell of every row is still on the screen, and each row's name heads each group
    for row in t.cells():
        name = row[0]
        shown = [ln.split() for ln in lines if ln.split() and ln.split()[0] == name]
        assert len(shown) >= 2  # split into groups
        assert [c for part in shown for c in part[1:]] == row[1:]
    # title and note wrapped, not cut: their words all there, in order
    words = " ".join(lines).split()
    assert words[:30] == ["a", "title"] * 15 and words[-80:] == ["a", "note"] * 40
    # the files keep the whole table: one header line with every column
    md = t.to_markdown().splitlines()
    assert md[2] == "| " + " | ".join(t.columns) + " |"
    assert next(csv.reader(io.StringIO(t.to_csv()))) == list(t.columns)


def test_a_table_that_fits_is_printed_as_before():
    t = Table("Title", ["Method", "Mean (m)"], [["EKF", 1.25], ["DR", 10.5]], digits=2)
    assert (
        t.to_text()
        == "Title\nMethod  Mean (m)\n------  --------\nEKF         1.25\nDR         10.50\n"
    )


def test_headers_go_on_two_lines_before_the_columns_are_split():
    cols = ["Filter", *(f"long header {i} (m)" for i in range(7))]
    text = table("", cols, [["EKF", *(["1.0"] * 7)]])
    lines = text.splitlines()
    assert len(lines) == 4 and max(map(len, lines)) <= WIDTH  # 2 header lines, rule, one row
    assert lines[0].split() == ["long", "header"] * 7
    assert lines[1].split()[0] == "Filter" and lines[1].count("(m)") == 7


def test_key_columns_are_repeated_in_every_group():
    t = Table(
        "",
        ["vehicle", "method", *(f"quantity {i} (m)" for i in range(12))],
        [["f1", "EKF", *range(12)], ["f1", "GA2", *range(12, 24)]],
    )
    assert t.key_columns() == 2
    groups = [g for g in t.to_text().split("\n\n") if g.strip()]
    assert len(groups) >= 2
    for g in groups:
        rows = g.splitlines()[-2:]
        assert [r.split()[:2] for r in rows] == [["f1", "EKF"], ["f1", "GA2"]]


def test_prose_is_wrapped_at_spaces_with_long_words_whole():
    path = "/" + "x" * 120
    text = "word " * 50 + path + " end\nshort line\n"
    out = wrap(text)
    assert out.endswith("short line\n")
    lines = out.splitlines()
    assert all(len(ln) <= WIDTH for ln in lines if path not in ln)
    assert any(ln.strip() == path for ln in lines)  # a path is never cut
    assert " ".join(out.split()) == " ".join(text.split())
    assert all(ln.startswith("  ") for ln in lines[1:-1])  # continuations indented
    listed = labelled("mission/x", "word " * 40, 12).splitlines()
    assert all(len(ln) <= WIDTH for ln in listed) and listed[1].startswith(" " * 14 + "word")


# --- bad input: the nearest valid names, the name as typed --------------------------------------


@pytest.mark.parametrize(
    ("name", "override", "message"),
    [
        (
            "mission/correction",
            "current.speed=0.3",
            "unknown field 'current.speed' (value 0.3); did you mean current.speed_m_s?",
        ),
        (
            "paper-000/test-1",
            "sensors.usbl.priod_s=20",
            "unknown field 'sensors.usbl.priod_s' (value 20); did you mean sensors.usbl.period_s?",
        ),
        ("paper-003/test-1", "navigation.restrat=false", "did you mean navigation.restart?"),
        ("paper-000/test-1", "pasage.duration_s=10", "did you mean passage?"),
        # nothing near: no guess
        (
            "paper-000/test-1",
            "sensors.usbl.bogus=1",
            "unknown field 'sensors.usbl.bogus' (value 1)",
        ),
    ],
)
def test_a_misspelt_field_gets_the_nearest_valid_names(capsys, tmp_path, name, override, message):
    out = tmp_path / "out"
    code, err = run_in_process(capsys, "run", name, "--out", str(out), "--set", override)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and message in lines[0], err
    assert "uniform" not in lines[0] and "Traceback" not in err and not out.exists()
    if "bogus" in override:
        assert "did you mean" not in lines[0]


def test_an_out_of_range_field_inside_a_tagged_union_is_named_as_typed(capsys, tmp_path):
    code, err = run_in_process(capsys, "show", "mission/correction", "--set", "current.speed_m_s=9")
    assert code == 2 and "current.speed_m_s = 9" in err and "current.uniform" not in err


# --- every registered experiment and mission: no line over 100 columns --------------------------

SMALL = {
    "coop/team": ["team.duration_s=120", "report.curve_every_s=10"],
    "coop/sensitivity": [
        "team.duration_s=120",
        "report.curve_every_s=10",
        "sweep.drift_ppm=[10]",
        "sweep.sound_speed_m_s=[1530]",
    ],
    "trn/relief": [
        "track.duration_s=60",
        "filters.particles=400",
        "filters.grid_points=24",
        "sweep.relief_std_m=[0.5, 2.0]",
        "sweep.map_sigma_m=[0.1]",
    ],
    "paper-004/table-1": ["path.duration_s=30.0", "filters.train_paths=200"],
    "paper-004/table-1-seabed": ["path.duration_s=30.0", "filters.train_paths=200"],
    "paper-004/near-beacon": ["filters.train_paths=200"],
    "mission/swarm": ["timing.max_duration_s=100"],
    "mission/seed004": [
        "seed004.duration_s=20",
        "timing.max_duration_s=20",
        "seed004.train_paths=200",
        "seed004.surrogate_test_paths=100",
    ],
}
"""A small size of the experiments whose default size takes long: their output's shape (tables,
notes, warnings) is the same."""

CHEAP_S = 15
SLOW = {
    "coop/sensitivity",
    "mission/correction",
    "mission/seed004",
    "mission/surfacing",
    "mission/survey",
    "mission/swarm",
    "mission/trn",
    "vehicle/autopilot",
}
"""Over about ``CHEAP_S`` seconds at their small size (a mission flies its whole course)."""


def _switch_off(exp: registry.Experiment) -> list[str]:
    """Figures and the recording off where the scenario has them (the terminal output is the
    same; only the count of files written changes)."""
    report = exp.scenario_type.model_fields.get("report")
    fields = report.annotation.model_fields if report is not None else {}
    return [f"report.{k}=false" for k in ("figures", "recording") if k in fields]


PARAMS = [
    pytest.param(name, marks=[pytest.mark.slow] if name in SLOW else [], id=name)
    for name in registry.names()
]


@pytest.mark.parametrize("name", PARAMS)
def test_no_line_of_a_default_run_is_wider_than_100_columns(name, capsys, tmp_path):
    exp = registry.get(name)
    assert issubclass(exp.scenario_type, Config)
    runs = min(2, exp.max_runs or 2) if not name.startswith("mission/") else 1
    sets = [a for s in [*SMALL.get(name, []), *_switch_off(exp)] for a in ("--set", s)]
    out = tmp_path / "o"  # short: the paths printed are the run folder's
    from tasks.core import cli

    capsys.readouterr()
    try:
        cli.main(["run", name, "--runs", str(runs), "--quiet", "--out", str(out), *sets])
        code = 0
    except SystemExit as exc:
        code = exc.code
    printed = capsys.readouterr()
    assert code == 0, printed.err
    lines = (printed.out + printed.err).splitlines()
    assert len(lines) >= 3 and any("tables.md" in ln for ln in lines)
    wide = [ln for ln in lines if len(ln) > WIDTH]
    assert not wide, textwrap.shorten(wide[0], 200)
    # the tables were narrowed, not wrapped like prose: a table's rule (dashes under its header)
    # always starts a line; one indented would be the rest of a rule too wide, broken at a space
    rules = [ln for ln in lines if ln.strip() and set(ln.strip()) <= {"-", " "}]
    assert rules and all(r.startswith("-") for r in rules), rules


def test_bauv_list_fits(capsys):
    from tasks.core import cli

    capsys.readouterr()
    cli.main(["list"])
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) >= len(registry.names()) and max(map(len, lines)) <= WIDTH


def test_a_way_point_missed_by_truth_but_reached_by_the_estimate_is_explained():
    from tasks.closed_loop.report import _missed_note

    wp = dict(index=0, acceptance_radius_m=8.0, closest_true_distance_m=38.25)
    hit = dict(wp, index=1, closest_true_distance_m=1.0, reached_by_truth=True)
    note = _missed_note(
        [
            dict(wp, reached_by_truth=False, reached_by_estimate=True),
            dict(hit, reached_by_estimate=True),
        ]
    )
    # the estimate was within 8 m while the truth stayed 38.25 m away: an error of >= 30.25 m
    assert note.startswith("Way-point 0: NO by truth") and "at least 30.2 m" in note
    assert "Way-point 1" not in note
    assert _missed_note([dict(hit, reached_by_estimate=True)]) == ""


def test_a_cell_wider_than_the_screen_is_wrapped_not_left_wide():
    reason = "PhysicsError: " + "the simulation diverged at t = 12.5 s " * 6
    t = Table("Failed runs", ["Run", "Reason"], [[3, reason]], slug="failed")
    lines = t.to_text().splitlines()
    rule = next(i for i, ln in enumerate(lines) if ln.startswith("---"))
    assert max(map(len, lines)) <= WIDTH and rule >= 2
    assert " ".join(" ".join(lines[rule + 1 :]).split()) == "3 " + " ".join(reason.split())
