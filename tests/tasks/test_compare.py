"""``bauv compare``: the numbers shown are the run folders' metrics.json, read here on their own."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from tasks.core import cli, compare
from tests.tasks.refusal import run_in_process


def make_run(root: Path, name: str, metrics: dict, experiment="mission/short", **record) -> Path:
    """A run folder as ``bauv run`` leaves it, as far as compare reads it."""
    folder = root / name
    folder.mkdir(parents=True)
    rec = {"experiment": experiment, "seed": 3, "n_runs": 2, "state": "complete", **record}
    (folder / "run.json").write_text(json.dumps(rec))
    (folder / "metrics.json").write_text(json.dumps(metrics))
    return folder


def leaves(doc, path=()):
    """(path parts, value, inside a list) of every number and boolean of a JSON document."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from leaves(v, (*path, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            for p, val, _ in leaves(v, (*path, str(i))):
                yield p, val, True
    elif isinstance(doc, bool | int | float) and doc == doc:
        yield path, doc, False


def read_csv(path: Path) -> tuple[list[str], dict[str, list[str]]]:
    rows = list(csv.reader(path.open()))
    return rows[0], {r[0]: r[1:] for r in rows[1:]}


def cell(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)  # an int as an int, a float as the shortest text that reads back exactly


A = {
    "experiment": "mission/short",
    "aggregate": {"ekf_mean_error_m": {"mean": 0.5511215587369405, "max": 2.25}, "n": 4},
    "all_reached": True,
    "note": "text is left out",
    "missing": None,
    "runs": [{"run": 0, "summary": {"duration_s": 109.2}}, {"run": 1, "summary": {}}],
}
B = {
    "experiment": "mission/short",
    "aggregate": {"ekf_mean_error_m": {"mean": 1e-17, "max": -3.0}, "n": 7},
    "all_reached": False,
    "extra_m": 12345678.901234567,
    "events": 2**70,
    "runs": [{"run": 0, "summary": {"duration_s": 111.8}}],
}


def test_csv_and_markdown_hold_every_value_exactly(tmp_path, capsys):
    a, b = make_run(tmp_path, "a", A), make_run(tmp_path, "b", B)
    code, err = run_in_process(capsys, "compare", str(a), str(b), "--out", str(tmp_path / "cmp"))
    assert code == 0, err
    head, rows = read_csv(tmp_path / "cmp" / "compare.csv")
    assert head == ["metric", "a", "b"]
    expected: dict[str, list[str]] = {}
    for col, doc in enumerate((A, B)):
        for path, value, in_list in leaves(doc):
            if not in_list:
                expected.setdefault(".".join(path), ["", ""])[col] = cell(value)
    assert rows == expected  # every number outside a list, exact, empty where missing
    md = (tmp_path / "cmp" / "compare.md").read_text()
    for name, (va, vb) in expected.items():
        assert f"| `{name}` | {va or '-'} | {vb or '-'} |" in md
    for f in ("compare.png", "compare.pdf"):
        assert (tmp_path / "cmp" / f).stat().st_size > 1000


def test_globs_select_list_items_in_order(tmp_path):
    a, b = make_run(tmp_path, "a", A), make_run(tmp_path, "b", B)
    cmp = compare.compare([a, b], ["runs.*.summary.*", "aggregate.*.mean", "extra_*", "*.mean"])
    assert cmp.metrics == (
        "runs.0.summary.duration_s",
        "aggregate.ekf_mean_error_m.mean",
        "extra_m",
    )
    got = [[cmp.value(m, r) for r in cmp.runs] for m in cmp.metrics]
    assert got == [[109.2, 111.8], [0.5511215587369405, 1e-17], [None, 12345678.901234567]]


def test_terminal_table_fits_100_columns_and_shows_every_value(tmp_path):
    group = {f"metric_with_a_long_name_{i}": i / 7 for i in range(5)}
    folders = [
        make_run(tmp_path / f"batch-{k}", "2026-12-04T10-00-00-seed0", {"group": group, "k": k})
        for k in range(9)
    ]
    res = subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "compare", *map(str, folders)],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stderr
    out = res.stdout
    assert max(len(line) for line in out.splitlines()) <= 100
    for k in range(9):  # folders of one name told apart by their parent
        assert f"{k + 1}. batch-{k}/2026-12-04T10-00-00-seed0: mission/short" in out
    k_rows = [line.split() for line in out.splitlines() if line.startswith("k ")]
    assert len(k_rows) > 1  # nine folders do not fit side by side in 100 columns
    assert [float(v) for row in k_rows for v in row[1:]] == [float(k) for k in range(9)]
    for i in range(5):
        rows = [
            ln.split()
            for ln in out.splitlines()
            if ln.startswith(f"group.metric_with_a_long_name_{i} ")
        ]
        assert [float(v) for row in rows for v in row[1:]] == [float(f"{i / 7:.6g}")] * 9


def test_not_finite_values_are_left_out(tmp_path, capsys):
    a = make_run(tmp_path, "a", {"x_m": 1.5, "y_m": 2.0})
    huge = "1" + "0" * 400  # an int no float holds: exact in the files, drawn as no bar
    (a / "metrics.json").write_text(f'{{"x_m": NaN, "y_m": 2.0, "z": Infinity, "n": {huge}}}')
    b = make_run(tmp_path, "b", {"x_m": 1.5, "y_m": 3.0})
    code, err = run_in_process(capsys, "compare", str(a), str(b), "--out", str(tmp_path / "o"))
    assert code == 0, err
    _, rows = read_csv(tmp_path / "o" / "compare.csv")
    assert rows == {"x_m": ["", "1.5"], "y_m": ["2.0", "3.0"], "n": [huge, ""]}
    for f in ("compare.csv", "compare.md"):
        text = (tmp_path / "o" / f).read_text().lower().split("| metric |")[-1]
        assert "nan" not in text and "inf" not in text, text


def _bad(tmp_path: Path, case: str) -> tuple[list[str], str]:
    good = make_run(tmp_path, "good", A)
    if case == "no folder":
        return [str(tmp_path / "nowhere")], "not a folder"
    if case == "not a run folder":
        (tmp_path / "plain").mkdir()
        return [str(tmp_path / "plain")], "not a run folder (no run.json"
    if case == "no metrics":
        (make_run(tmp_path, "r", A) / "metrics.json").unlink()
        return [str(tmp_path / "r")], "no metrics.json"
    if case == "metrics not json":
        (make_run(tmp_path, "r", A) / "metrics.json").write_text("{")
        return [str(tmp_path / "r")], "metrics.json is not JSON"
    if case == "incomplete":
        make_run(tmp_path, "r", A, state="incomplete")
        return [str(tmp_path / "r")], "'incomplete', not complete"
    if case == "twice":
        return [str(good), str(tmp_path / "." / "good")], "given twice"
    if case == "glob":
        return [str(good), "--metric", "aggregate.*.median"], "--metric = 'aggregate.*.median'"
    if case == "out not empty":
        (tmp_path / "out").mkdir()
        (tmp_path / "out" / "keep").write_text("x")
        return [str(good)], "--out = "
    raise AssertionError(case)


@pytest.mark.parametrize(
    "case",
    [
        "no folder",
        "not a run folder",
        "no metrics",
        "metrics not json",
        "incomplete",
        "twice",
        "glob",
        "out not empty",
    ],
)
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, case):
    args, pattern = _bad(tmp_path, case)
    out = tmp_path / "out"
    before = sorted(p.name for p in out.iterdir()) if out.exists() else None
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        cli.main(["compare", *args, "--out", str(out)])
    code, printed, err = exc.value.code, *capsys.readouterr()
    assert code == 2 and printed == ""  # no table either
    lines = err.strip().splitlines()
    assert len(lines) == 1 and pattern in lines[0] and "Traceback" not in err, lines
    assert (sorted(p.name for p in out.iterdir()) if out.exists() else None) == before


def test_real_run_folder_against_its_metrics_json(tmp_path):
    """A batch of paper-000/test-1 (nested tables, per-draw lists): every number outside a list,
    exact, in the run's own column."""
    run = tmp_path / "p0"
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "tasks.core.cli",
            "run",
            "paper-000/test-1",
            "--runs",
            "3",
            "--out",
            str(run),
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stderr
    cmp = compare.compare([run])
    doc = json.loads((run / "metrics.json").read_text())
    expected = {".".join(p): v for p, v, in_list in leaves(doc) if not in_list and math.isfinite(v)}
    assert len(expected) > 30
    assert {m: cmp.value(m, cmp.runs[0]) for m in cmp.metrics} == expected
    assert cmp.runs[0].experiment == "paper-000/test-1" and cmp.runs[0].n_runs == 3
