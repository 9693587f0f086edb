"""Parquet export: units on every field, covariances as their upper triangle, a bit-exact round
trip, NaN refused unless declared missing, atomic writes."""

import struct

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tasks.core import store
from tasks.core.export import Column, ExportError, read_parquet, write_parquet

T = 5
XYZ = ("x", "y", "z")
LABELS = ("transit", "ascend", "surface", "dive", "done")


def _covariances():
    a = np.random.default_rng(3).normal(size=(T, 3, 3))
    p = a @ a.transpose(0, 2, 1)
    p[0, 0, 1] = p[0, 1, 0] = -0.0
    p[1, 2, 2] = 5e-324
    return p


def _columns():
    return {
        "t": Column(np.array([0.0, -0.0, 5e-324, 1.7976931348623157e308, np.inf]), "s", "time"),
        "position": Column(
            np.arange(T * 3, dtype=float).reshape(T, 3) / 7, "m", "world ENU position", XYZ
        ),
        "P": Column(_covariances(), "m2", "position covariance", XYZ),
        "quat": Column(
            np.linspace(-1, 1, T * 4, dtype=np.float32).reshape(T, 4),
            "1",
            "attitude, scalar first",
            ("w", "x", "y", "z"),
        ),
        "usbl_event": Column(np.array([True, False, False, True, False]), "bool", "a fix arrived"),
        "mode": Column(np.array([0, 1, 1, 2, 4], dtype=np.int8), "enum", "guidance mode index"),
        "count": Column(np.array([0, 1, 2, 3, 2**64 - 1], dtype=np.uint64), "1", "a counter"),
        "label": Column(np.array(["transit", "dive", "", "ü✓", "done"]), "text", "mode name"),
        "fix_range": Column(
            np.array([np.nan, 10.5, np.nan, 12.25, 13.0]), "m", "USBL range", nullable=True
        ),
        "phase": Column(np.array([3, 0, 0, 4, 3], dtype=np.int16), "enum", "mode", labels=LABELS),
    }


def _bits(a):
    return a.tobytes() if a.dtype.kind != "f" else np.ascontiguousarray(a).view(np.uint8).tobytes()


def test_round_trip_is_bit_exact_with_units(tmp_path):
    cols = _columns()
    path = tmp_path / "ticks.parquet"
    write_parquet(path, cols, {"experiment": "mission/short", "seed": "0", "run": "3"})
    got, meta = read_parquet(path)
    assert meta == {"experiment": "mission/short", "seed": "0", "run": "3"}
    assert list(got) == list(cols)
    for name, col in cols.items():
        g = got[name]
        assert (g.unit, g.description, g.components, g.nullable, g.labels) == (
            col.unit,
            col.description,
            col.components,
            col.nullable,
            col.labels,
        ), name
        assert g.values.dtype.str == col.values.dtype.str and g.values.shape == col.values.shape
        if col.nullable:
            assert np.array_equal(np.isnan(g.values), np.isnan(col.values))
            ok = ~np.isnan(col.values)
            assert _bits(g.values[ok]) == _bits(col.values[ok])
        else:
            assert _bits(g.values) == _bits(col.values), name
    assert struct.pack(">d", got["P"].values[0, 1, 0]) == struct.pack(">d", -0.0)


def test_any_parquet_reader_sees_the_fields_and_their_units(tmp_path):
    cols = _columns()
    path = tmp_path / "ticks.parquet"
    write_parquet(path, cols, {"experiment": "x"})
    table = pq.read_table(path)
    tri = ["P_x_x", "P_x_y", "P_x_z", "P_y_y", "P_y_z", "P_z_z"]
    assert table.schema.names == [
        "t",
        "position_x",
        "position_y",
        "position_z",
        *tri,
        "quat_w",
        "quat_x",
        "quat_y",
        "quat_z",
        "usbl_event",
        "mode",
        "count",
        "label",
        "fix_range",
        "phase",
    ]
    for f in table.schema:
        assert f.metadata[b"unit"] and b"description" in f.metadata, f.name
        assert f.nullable == (f.name == "fix_range"), f.name
    assert table.schema.field("P_x_y").metadata[b"unit"] == b"m2"
    assert table.schema.field("position_z").metadata[b"unit"] == b"m"
    assert table.schema.field("quat_w").type == pa.float32()
    assert table.schema.field("usbl_event").type == pa.bool_()
    assert table.schema.field("count").type == pa.uint64()
    assert table.schema.metadata[b"experiment"] == b"x"
    p = cols["P"].values
    for name in tri:
        i, j = (XYZ.index(c) for c in name.split("_")[1:])
        assert np.array_equal(table.column(name).to_numpy(), p[:, i, j])
    assert table.column("fix_range").null_count == 2
    assert table.column("label").to_pylist() == ["transit", "dive", "", "ü✓", "done"]
    # a labelled column: its labels, dictionary-encoded (a pandas category)
    assert table.schema.field("phase").type == pa.dictionary(pa.int32(), pa.string())
    assert table.column("phase").to_pylist() == ["dive", "transit", "transit", "done", "dive"]


def _refused(tmp_path, columns, fragment, metadata=None):
    path = tmp_path / "out.parquet"
    with pytest.raises(ExportError) as exc:
        write_parquet(path, columns, metadata or {})
    assert fragment in str(exc.value) and "\n" not in str(exc.value), str(exc.value)
    assert list(tmp_path.iterdir()) == []  # nothing written, no temporary file left


def test_non_symmetric_matrices_are_refused(tmp_path):
    p = _covariances()
    p[3, 0, 2] += 1e-12
    _refused(tmp_path, {"P": Column(p, "m2", "cov", XYZ)}, "column 'P': not symmetric")
    q = _covariances()
    q[2, 1, 0], q[2, 0, 1] = 0.0, -0.0  # equal as numbers, not bit for bit
    _refused(tmp_path, {"P": Column(q, "m2", "cov", XYZ)}, "row 2 [0, 1]")


def test_nan_is_refused_unless_the_column_is_nullable(tmp_path):
    v = np.array([[1.0, 2.0], [3.0, np.nan]])
    _refused(tmp_path, {"xy": Column(v, "m", "d", ("x", "y"))}, "column 'xy': NaN at index (1, 1)")
    p = _covariances()
    p[4, 1, 1] = np.nan
    _refused(tmp_path, {"P": Column(p, "m2", "cov", XYZ)}, "column 'P': NaN at index (4, 1, 1)")


@pytest.mark.parametrize(
    ("columns", "fragment"),
    [
        ({}, "no columns"),
        ({"a": Column(np.zeros(3), "m", ""), "b": Column(np.zeros(4), "m", "")}, "numbers of rows"),
        ({"a": Column(np.zeros((3, 2)), "m", "", ("x",))}, "needs 2 component names"),
        ({"a": Column(np.zeros((3, 2)), "m", "")}, "needs 2 component names"),
        ({"a": Column(np.zeros(3), "m", "", ("x",))}, "has no components"),
        ({"a": Column(np.zeros((3, 2)), "m", "", ("x", "x"))}, "repeat a name"),
        ({"a": Column(np.zeros((3, 2, 3)), "m", "", ("x", "y"))}, "must be square"),
        ({"a": Column(np.zeros((3, 1, 1, 1)), "m", "", ("x",))}, "must be (T,)"),
        ({"a": Column(np.zeros(3, dtype=complex), "m", "")}, "dtype complex128"),
        ({"a": Column(np.array([None, 1, 2]), "m", "")}, "dtype object"),
        ({"a": Column(np.zeros(3, dtype=np.float16), "m", "")}, "dtype float16"),
        ({"a": Column([1.0, 2.0], "m", "")}, "not a numpy array"),
        ({"a": Column(np.zeros(3), "", "")}, "unit ''"),
        ({"": Column(np.zeros(3), "m", "")}, "column name ''"),
        ({"a": np.zeros(3)}, "not a Column"),
        (
            {"a_b": Column(np.zeros(3), "m", ""), "a": Column(np.zeros((3, 1)), "m", "", ("b",))},
            "occur twice",
        ),
        ({"truth_pos.east": Column(np.zeros(3), "m", "")}, "holds a dot"),
        ({"a": Column(np.zeros((3, 2)), "m", "", ("x.y", "z"))}, "component name holds a dot"),
        ({"a": Column(np.zeros(3), "1", "", labels=("x", "x"))}, "repeat a name"),
        ({"a": Column(np.zeros(3), "1", "", labels=("x",))}, "labels need integer codes"),
        ({"a": Column(np.array([0, 2]), "1", "", labels=("x", "y"))}, "code 2 at row 1 has no"),
        ({"a": Column(np.array([0, -1]), "1", "", labels=("x", "y"))}, "code -1 at row 1"),
    ],
)
def test_bad_columns_are_refused_before_anything_is_written(tmp_path, columns, fragment):
    _refused(tmp_path, columns, fragment)


@pytest.mark.parametrize(
    ("metadata", "fragment"),
    [
        ({"bauv-sim.export": "2"}, "reserved"),
        ({"ARROW:schema": "x"}, "reserved"),
        ({"n": 1}, "must be strings"),
    ],
)
def test_bad_metadata_is_refused(tmp_path, metadata, fragment):
    _refused(tmp_path, {"a": Column(np.zeros(3), "m", "")}, fragment, metadata)


def test_writing_is_atomic(tmp_path, monkeypatch):
    path = tmp_path / "ticks.parquet"
    write_parquet(path, {"a": Column(np.zeros(3), "m", "")}, {"v": "old"})
    before = path.read_bytes()

    def broken(table, where, **kw):
        # half a file, into whatever write_parquet hands over (a path or a stream)
        if hasattr(where, "write"):
            where.write(b"PAR1 half a file")
        else:
            with open(where, "wb") as fh:
                fh.write(b"PAR1 half a file")
        raise OSError("disk full")

    monkeypatch.setattr(pq, "write_table", broken)
    with pytest.raises(OSError, match="disk full"):
        write_parquet(path, {"a": Column(np.ones(3), "m", "")}, {"v": "new"})
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["ticks.parquet"]


def test_writing_creates_the_folder(tmp_path):
    path = tmp_path / "parquet" / "run-0" / "ticks.parquet"
    write_parquet(path, {"a": Column(np.zeros(2), "m", "")}, {})
    assert read_parquet(path)[0]["a"].values.shape == (2,)


def test_files_not_written_here_are_refused(tmp_path):
    foreign = tmp_path / "foreign.parquet"
    pq.write_table(pa.table({"a": [1.0, 2.0]}), foreign)
    with pytest.raises(ExportError, match=r"not written by tasks\.core\.export"):
        read_parquet(foreign)
    junk = tmp_path / "junk.parquet"
    junk.write_bytes(b"not parquet")
    with pytest.raises(ExportError, match="cannot read Parquet"):
        read_parquet(junk)


def test_columns_are_plain_data():
    col = _columns()["P"]
    got = store.loads(store.dumps({"ticks": {"P": col}})).value["ticks"]["P"]
    assert type(got) is Column and got.components == XYZ and got.unit == "m2"
    assert _bits(got.values) == _bits(col.values)


@pytest.mark.parametrize("path", [None, 5, ["a.parquet"]])
def test_read_parquet_refuses_a_path_of_the_wrong_type(path):
    from tasks.core.export import ExportError, read_parquet

    with pytest.raises(ExportError, match=r"path = .* must be the path of a Parquet file"):
        read_parquet(path)
