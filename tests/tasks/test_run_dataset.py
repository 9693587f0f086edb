"""A batch's run data as one dataset (issue 26, check 3): one folder per table, every row keyed
by ``run`` and ``vehicle``, field names without dots, angles in degrees, enums as their labels;
``pyarrow.dataset`` reads a 4-run batch's ticks in one call, and the old layout is named when met
(``docs/run-data.md``)."""

import json
import re

import numpy as np
import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq
import pytest

from tasks.closed_loop.scenario import MODES
from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.export import (
    Column,
    ExportError,
    data_columns,
    open_dataset,
    read_parquet,
    write_parquet,
)
from tasks.core.runner import plan_batch, run

SHORT = "mission/short"
OVERRIDES = ["timing.max_duration_s=20", "report.figures=false", "report.recording=false"]
RUNS = 4


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    out = tmp_path_factory.mktemp("dataset") / "run"
    run(SHORT, n_runs=RUNS, seed=5, out_dir=out, overrides=OVERRIDES, progress=False)
    return out


def test_a_4_run_batch_reads_as_one_ticks_table_in_one_call(batch):
    """Check 3: ``pyarrow.dataset.dataset(RUN / "data" / "ticks")`` is the whole batch's ticks,
    one table with ``run`` (int32) and ``vehicle`` columns, the 4 runs, every file's rows, and
    no fix rows or fix columns."""
    files = sorted((batch / "data" / "ticks").iterdir())
    assert [f.name for f in files] == [f"run-{r:06d}-bauv.parquet" for r in range(RUNS)]
    t = ds.dataset(batch / "data" / "ticks").to_table()
    assert t.schema.field("run").type == pa.int32()
    assert t.schema.field("vehicle").type == pa.dictionary(pa.int32(), pa.string())
    assert sorted(set(t["run"].to_pylist())) == list(range(RUNS))
    assert set(t["vehicle"].to_pylist()) == {"bauv"}
    per_file = [pq.read_metadata(f).num_rows for f in files]
    assert t.num_rows == sum(per_file) and min(per_file) > 0
    counts = {r: t["run"].to_pylist().count(r) for r in range(RUNS)}
    assert list(counts.values()) == per_file  # each file's rows carry its run
    fix_only = {"t_valid", "t_arrival", "range", "azimuth_deg", "elevation_deg", "nis"}
    assert not fix_only & set(t.column_names)
    u = ds.dataset(batch / "data" / "usbl").to_table()
    assert fix_only <= set(u.column_names) and "truth_pos_east" not in u.column_names
    assert sorted(set(u["run"].to_pylist())) == list(range(RUNS))
    same = open_dataset(batch, "ticks")
    assert same.column_names == t.column_names and same.num_rows == t.num_rows
    assert same.schema.metadata[b"experiment"] == SHORT.encode()
    assert b"run" not in same.schema.metadata  # a key the files disagree on is not the table's


def test_no_field_name_holds_a_dot(batch):
    names = [f.name for p in (batch / "data").glob("*/*.parquet") for f in pq.read_schema(p)]
    assert len(names) > 100
    bad = [n for n in names if not re.fullmatch(r"[A-Za-z0-9_]+", n)]
    assert not bad


def test_guidance_mode_is_written_as_its_labels(batch):
    """The file's ``guidance_mode`` is a dictionary column whose strings are the names of the
    modes the run flew (the run's own integer codes, named by the scenario's MODES)."""
    scn = plan_batch(SHORT, overrides=OVERRIDES).scenario
    v = fly(WaypointMission(), scn, 5, 1).lead
    t = pq.read_table(batch / "data" / "ticks" / "run-000001-bauv.parquet")
    field = t.schema.field("guidance_mode")
    assert pa.types.is_dictionary(field.type)
    assert json.loads(field.metadata[b"labels"]) == list(MODES)
    assert t["guidance_mode"].to_pylist() == [MODES[i] for i in v["guidance_mode"]]
    assert t.to_pandas()["guidance_mode"].dtype == "category"
    cols, _ = read_parquet(batch / "data" / "ticks" / "run-000001-bauv.parquet")
    assert np.array_equal(cols["guidance_mode"].values, v["guidance_mode"])
    assert cols["guidance_mode"].labels == MODES


def test_angles_are_degrees_with_deg_in_their_names():
    cols = {
        "heading": Column(np.array([0.0, np.pi / 2, np.pi]), "rad", "h"),
        "rph": Column(np.zeros((3, 3)), "rad", "a", ("roll", "pitch", "heading")),
        "lat_deg": Column(np.ones(3), "deg", "already"),
        "pos_geo": Column(np.ones((3, 2)), "deg", "g", ("latitude", "longitude")),
        "range": Column(np.ones(3), "m", "r"),
    }
    got = data_columns(cols)
    assert list(got) == ["heading_deg", "rph_deg", "lat_deg", "pos_geo_deg", "range"]
    assert got["heading_deg"].values.tolist() == [0.0, 90.0, 180.0]
    assert {c.unit for k, c in got.items() if k != "range"} == {"deg"}
    with pytest.raises(ExportError, match="'x_deg': the degrees' name clashes"):
        data_columns({"x": Column(np.zeros(2), "rad", ""), "x_deg": Column(np.zeros(2), "deg", "")})


def test_schemas_of_different_vehicles_are_unified(tmp_path):
    """A column one vehicle lacks (a follower's ``hdop``) is null in the other's rows."""
    t = np.arange(3.0)
    for name, extra in (("leader", {}), ("f1", {"hdop": Column(t + 1, "1", "hdop")})):
        cols = {"run": Column(np.zeros(3, np.int32), "index", "run"), "t": Column(t, "s", "t")}
        write_parquet(tmp_path / "data" / "ticks" / f"run-000000-{name}.parquet", cols | extra, {})
    got = open_dataset(tmp_path, "ticks")
    assert got.num_rows == 6 and got.column_names == ["run", "t", "hdop"]
    assert got["hdop"].null_count == 3 and got.schema.field("hdop").nullable
    with pytest.raises(ExportError, match=r"no table 'gps' \(tables: ticks\)"):
        open_dataset(tmp_path, "gps")


def _old_layout_file(path):
    """A run-data file as the format's version 1 wrote it (fields joined with dots, radians)."""
    fields, arrays = [], []
    for i, comp in enumerate(("east", "north")):
        meta = {
            "unit": "m",
            "description": "position",
            "group": "pos",
            "shape": "[2]",
            "index": f"[{i}]",
            "components": '["east", "north"]',
            "dtype": "<f8",
            "nullable": "false",
        }
        fields.append(pa.field(f"pos.{comp}", pa.float64(), nullable=False, metadata=meta))
        arrays.append(pa.array([1.0 + i, 2.0 + i]))
    schema = pa.schema(fields, metadata={"bauv-sim.export": "1", "run": "0"})
    path.parent.mkdir(parents=True)
    pq.write_table(pa.Table.from_arrays(arrays, schema=schema), path)


def test_the_old_layout_is_named_and_its_files_still_read(tmp_path):
    old = tmp_path / "data" / "run-000000" / "bauv.ticks.parquet"
    _old_layout_file(old)
    with pytest.raises(ExportError) as exc:
        open_dataset(tmp_path, "ticks")
    msg = str(exc.value)
    assert "old layout data/run-NNNNNN/<vehicle>.<table>.parquet" in msg and "\n" not in msg
    assert "read_parquet" in msg
    cols, meta = read_parquet(old)
    assert cols["pos"].values.tolist() == [[1.0, 2.0], [2.0, 3.0]] and meta == {"run": "0"}


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ((None, "ticks"), "run_folder = None (NoneType): must be the path of a run folder"),
        (("{tmp}", "../ticks"), "table = '../ticks': must be a table's name"),
        (("{tmp}/nowhere", "ticks"), "no data folder"),
    ],
)
def test_open_dataset_refuses_bad_arguments_in_one_line(tmp_path, args, fragment):
    folder = args[0].format(tmp=tmp_path) if isinstance(args[0], str) else args[0]
    with pytest.raises(ExportError) as exc:
        open_dataset(folder, args[1])
    assert fragment in str(exc.value) and "\n" not in str(exc.value)
