"""Parquet export of time series with their units, readable by any Parquet tool.

A table is a mapping of named :class:`Column` objects sharing their first axis (time, ``T`` rows).
Each column becomes one or more flat Parquet fields, their names made of letters, digits and
``_`` only (a column or component name with a dot is refused):

* ``(T,)``: one field named as the column;
* ``(T, k)``: ``k`` fields ``"{name}_{component}"``, in component order;
* ``(T, k, k)``, a symmetric matrix per row (a covariance): its upper triangle, the fields
  ``"{name}_{ci}_{cj}"`` for ``i <= j`` in row-major order (a non-symmetric matrix is refused);
* a labelled column (integer codes with :attr:`Column.labels`): one dictionary-encoded field of
  the labels (Arrow ``dictionary<int32, string>``, a pandas category).

Every field carries Parquet field metadata: ``unit`` (SI, ``"1"`` for dimensionless,
``"deg"``, ``"bool"``, ``"enum"``, ...), ``description``, and what :func:`read_parquet` needs to
regroup the fields into the same arrays, bit for bit: ``group`` (the column's name), ``shape``
(the column's shape after ``T``, JSON), ``index`` (this field's index in it, JSON),
``components`` (JSON), ``dtype`` (numpy's ``dtype.str``), ``nullable`` and ``labels`` (JSON). The
table's metadata is the caller's ``metadata`` plus ``bauv-sim.export = "2"``.

Run data (``docs/run-data.md``) states angles in degrees: :func:`data_columns` turns a table's
radian columns into degrees with ``_deg`` at the end of their names; :func:`open_dataset` reads
one table of a whole batch (``<run folder>/data/<table>/*.parquet``) as one Arrow table.

NaN never reaches an output silently: a float column holding NaN is refused, naming the column,
unless the column is declared ``nullable=True``; then NaN is written as a Parquet null (and read
back as NaN).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bauv_sim.errors import BauvSimError
from tasks.core import store
from tasks.core.files import atomic_write_bytes
from tasks.core.lazy import LazyModule

pa = LazyModule("pyarrow")  # imported when run data is written or read
pq = LazyModule("pyarrow.parquet", after=(pa,))

FORMAT_KEY = "bauv-sim.export"
"""Key of the table metadata marking a file written by :func:`write_parquet`."""

FORMAT_VERSION = "2"
"""Version 2: field names joined with ``_``, labelled columns. Version 1 (names joined with ``.``,
the layout ``data/run-NNNNNN/<vehicle>.<table>.parquet``) is still read by :func:`read_parquet`
for one release."""

_READ_VERSIONS = ("1", FORMAT_VERSION)
_FIELD_KEYS = ("unit", "description", "group", "shape", "index", "components", "dtype", "nullable")


class ExportError(BauvSimError, ValueError):
    """A column cannot be exported, or a file cannot be read back (the message names which)."""


@store.plain_data("export.Column")  # results made of columns can be kept as runner blocks
@dataclass(frozen=True)
class Column:
    """One named quantity of a table, with its unit.

    Attributes:
        values: shape (T,), (T, k) or, for a symmetric matrix per row, (T, k, k); dtype bool,
            signed or unsigned integer, float32, float64 or unicode.
        unit: SI unit (``"m"``, ``"m/s"``, ``"rad"``, ``"m2"``), ``"1"`` for dimensionless,
            ``"bool"``, ``"enum"``, ...
        description: what the quantity is (frame, sign convention, ...).
        components: names of the last axis for (T, k) and (T, k, k) (e.g. ``("x", "y", "z")``);
            empty for (T,).
        nullable: whether NaN marks a missing value (written as null); otherwise a NaN is an
            error.
        labels: for an integer (T,) column of codes, the label of each code (code ``i`` is
            ``labels[i]``); written as a dictionary-encoded string field. Empty otherwise.
    """

    values: np.ndarray
    unit: str
    description: str
    components: tuple[str, ...] = ()
    nullable: bool = False
    labels: tuple[str, ...] = ()


def _fail(name: str, what: str) -> ExportError:
    return ExportError(f"column {name!r}: {what}")


def _check(name: Any, col: Any) -> int:
    """Validate one column; return its number of rows."""
    if type(name) is not str or not name:
        raise ExportError(f"column name {name!r}: must be a non-empty string")
    if "." in name:
        raise ExportError(
            f"column name {name!r}: holds a dot; names are letters, digits and '_' "
            f"(e.g. {name.replace('.', '_')!r})"
        )
    if not isinstance(col, Column):
        raise _fail(name, f"{type(col).__name__} is not a Column")
    v = col.values
    if not isinstance(v, np.ndarray):
        raise _fail(name, f"values are a {type(v).__name__}, not a numpy array")
    k = v.dtype.kind
    if not (k in "biuU" or (k == "f" and v.dtype.itemsize in (4, 8))):
        raise _fail(name, f"dtype {v.dtype} is not bool, int, uint, float32, float64 or unicode")
    if v.ndim not in (1, 2, 3):
        raise _fail(name, f"shape {v.shape}: must be (T,), (T, k) or (T, k, k)")
    if type(col.unit) is not str or not col.unit:
        raise _fail(name, f"unit {col.unit!r}: must be a non-empty string")
    if type(col.description) is not str:
        raise _fail(name, "description must be a string")
    comps = col.components
    if type(comps) is not tuple or any(type(c) is not str or not c for c in comps):
        raise _fail(name, f"components {comps!r}: must be a tuple of non-empty strings")
    if len(set(comps)) != len(comps):
        raise _fail(name, f"components {comps!r} repeat a name")
    if any("." in c for c in comps):
        raise _fail(name, f"components {comps!r}: a component name holds a dot")
    labels = col.labels
    if type(labels) is not tuple or any(type(x) is not str for x in labels):
        raise _fail(name, f"labels {labels!r}: must be a tuple of strings")
    if labels:
        if len(set(labels)) != len(labels):
            raise _fail(name, f"labels {labels!r} repeat a name")
        if k not in "iu" or v.ndim != 1 or col.nullable:
            raise _fail(name, f"labels need integer codes of shape (T,), got {v.dtype} {v.shape}")
        bad = (v < 0) | (v >= len(labels))
        if bad.any():
            at = int(np.argmax(bad))
            raise _fail(name, f"code {v[at]} at row {at} has no label (0 .. {len(labels) - 1})")
    if v.ndim == 1 and comps:
        raise _fail(name, f"shape {v.shape} has no components, got {comps!r}")
    if v.ndim >= 2 and len(comps) != v.shape[1]:
        raise _fail(name, f"shape {v.shape} needs {v.shape[1]} component names, got {comps!r}")
    if v.ndim == 3:
        if v.shape[2] != v.shape[1]:
            raise _fail(name, f"shape {v.shape}: a (T, k, k) column must be square")
        if not np.array_equal(_bits(v), _bits(v.transpose(0, 2, 1))):
            t, i, j = np.argwhere(_bits(v) != _bits(v.transpose(0, 2, 1)))[0]
            raise _fail(
                name,
                f"not symmetric (bit for bit): row {t} [{i}, {j}] = {v[t, i, j]!r} but "
                f"[{j}, {i}] = {v[t, j, i]!r}",
            )
    if k == "f" and not col.nullable:
        nan = np.isnan(v)
        if nan.any():
            at = tuple(int(x) for x in np.argwhere(nan)[0])
            raise _fail(
                name, f"NaN at index {at} (declare the column nullable=True if NaN means missing)"
            )
    return v.shape[0]


def _bits(v: np.ndarray) -> np.ndarray:
    """The array's values as unsigned integers of the same size (floats compare by their bits)."""
    if v.dtype.kind == "f":
        return np.ascontiguousarray(v).view(f"u{v.dtype.itemsize}")
    return v


def _field_parts(name: str, col: Column) -> list[tuple[str, tuple[int, ...], np.ndarray]]:
    v, comps = col.values, col.components
    if v.ndim == 1:
        return [(name, (), v)]
    if v.ndim == 2:
        return [(f"{name}_{c}", (i,), v[:, i]) for i, c in enumerate(comps)]
    k = v.shape[1]
    return [
        (f"{name}_{comps[i]}_{comps[j]}", (i, j), v[:, i, j]) for i in range(k) for j in range(i, k)
    ]


def _arrow(values: np.ndarray, nullable: bool, labels: tuple[str, ...] = ()) -> pa.Array:
    native = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
    if labels:
        codes = pa.array(native.astype(np.int32))
        return pa.DictionaryArray.from_arrays(codes, pa.array(labels, pa.string()))
    if nullable and native.dtype.kind == "f":
        return pa.array(native, mask=np.isnan(native))
    return pa.array(native)


def write_parquet(
    path: str | Path, columns: Mapping[str, Column], metadata: Mapping[str, str]
) -> None:
    """Write columns with their units as one Parquet file, atomically.

    Args:
        path: the file to write (replaced whole, or not at all; its folder is created).
        columns: the table's columns by name, in field order; all with the same number of rows.
        metadata: the table's metadata (string keys and values), e.g. experiment, seed, run.

    Raises:
        ExportError: naming the column (or key) and what is wrong, before anything is written.
    """
    if not columns:
        raise ExportError("no columns to write")
    rows = {name: _check(name, col) for name, col in columns.items()}
    if len(set(rows.values())) > 1:
        raise ExportError(f"columns have different numbers of rows: {rows}")
    for key, value in metadata.items():
        if type(key) is not str or type(value) is not str:
            raise ExportError(f"metadata {key!r} = {value!r}: keys and values must be strings")
        if key == FORMAT_KEY or key.startswith("ARROW:"):
            raise ExportError(f"metadata key {key!r} is reserved")
    fields, arrays = [], []
    for name, col in columns.items():
        shape = list(col.values.shape[1:])
        for fname, index, values in _field_parts(name, col):
            meta = {
                "unit": col.unit,
                "description": col.description,
                "group": name,
                "shape": json.dumps(shape),
                "index": json.dumps(list(index)),
                "components": json.dumps(list(col.components)),
                "dtype": col.values.dtype.str,
                "nullable": json.dumps(col.nullable),
                "labels": json.dumps(list(col.labels)),
            }
            arr = _arrow(values, col.nullable, col.labels)
            fields.append(pa.field(fname, arr.type, nullable=col.nullable, metadata=meta))
            arrays.append(arr)
    names = [f.name for f in fields]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ExportError(f"field names {dup} occur twice (a column name and a component clash)")
    schema = pa.schema(fields, metadata={**metadata, FORMAT_KEY: FORMAT_VERSION})
    table = pa.Table.from_arrays(arrays, schema=schema)
    # encoded in memory, then written atomically by tasks.core.files: a full disk leaves no
    # partial file and raises a plain OSError, and nothing is written through a symbolic link
    buf = pa.BufferOutputStream()
    pq.write_table(table, buf)
    atomic_write_bytes(Path(path), memoryview(buf.getvalue()))


def _group_meta(path: Path, field: pa.Field) -> dict[str, Any]:
    raw = field.metadata or {}
    try:
        meta = {k: raw[k.encode()].decode("utf-8") for k in _FIELD_KEYS}
        meta["labels"] = raw.get(b"labels", b"[]").decode("utf-8")  # version 1 has none
        for k in ("shape", "index", "components", "nullable", "labels"):
            meta[k] = json.loads(meta[k])
        dtype = np.dtype(meta["dtype"])
    except (KeyError, ValueError, TypeError) as exc:
        raise ExportError(
            f"{path}: field {field.name!r} lacks the metadata of tasks.core.export ({exc})"
        ) from None
    if dtype.kind not in "biufU" or dtype.fields is not None:
        raise ExportError(f"{path}: field {field.name!r}: dtype {meta['dtype']!r} is not supported")
    meta["dtype"] = dtype
    return meta


def read_parquet(path: str | Path) -> tuple[dict[str, Column], dict[str, str]]:
    """Read a file written by :func:`write_parquet` back into its columns, bit for bit.

    It returns the file's columns as written: for run data, angles in degrees under their
    ``_deg`` names (:func:`data_columns`), a labelled column as its integer codes with its
    ``labels``, the key columns ``run``, ``vehicle`` (and ``variant``). Files of the format's
    version 1 (run data before the layout ``data/<table>/``: fields joined with ``.``, angles in
    radians) are still read, as they were written, for one release.

    Args:
        path: the Parquet file.

    Returns:
        ``(columns in their written order, the table's metadata)``; values have the dtype and
        shape they were written with (a nullable column's nulls read back as NaN).

    Raises:
        ExportError: if the file cannot be read or was not written by :func:`write_parquet`.
    """
    if not isinstance(path, str | os.PathLike):
        raise ExportError(
            f"path = {path!r} ({type(path).__name__}): must be the path of a Parquet file "
            "(str or Path)"
        )
    p = Path(path)
    try:
        table = pq.read_table(p)
    except (OSError, pa.ArrowException) as exc:
        raise ExportError(f"{p}: cannot read Parquet: {' '.join(str(exc).split())}") from None
    raw_meta = {k.decode(): v.decode() for k, v in (table.schema.metadata or {}).items()}
    if raw_meta.pop(FORMAT_KEY, None) not in _READ_VERSIONS:
        raise ExportError(
            f"{p}: not written by tasks.core.export (no {FORMAT_KEY} = "
            f"{' or '.join(_READ_VERSIONS)})"
        )
    metadata = {k: v for k, v in raw_meta.items() if not k.startswith("ARROW:")}
    groups: dict[str, dict[str, Any]] = {}
    parts: dict[str, dict[tuple[int, ...], np.ndarray]] = {}
    for i, field in enumerate(table.schema):
        meta = _group_meta(p, field)
        name = meta["group"]
        first = groups.setdefault(name, meta)
        if any(first[k] != meta[k] for k in _FIELD_KEYS if k != "index"):
            raise ExportError(f"{p}: field {field.name!r} disagrees with column {name!r}")
        chunked = table.column(i)
        if chunked.null_count and not meta["nullable"]:
            raise ExportError(f"{p}: field {field.name!r} holds nulls but is not nullable")
        if meta["labels"]:
            values = _codes(p, field.name, chunked, meta["labels"], meta["dtype"])
        else:
            values = np.asarray(chunked.to_numpy(), dtype=meta["dtype"])
        parts.setdefault(name, {})[tuple(meta["index"])] = values
    columns = {}
    for name, meta in groups.items():
        shape, got = meta["shape"], parts[name]
        if len(shape) == 0:
            want = [()]
        elif len(shape) == 1:
            want = [(i,) for i in range(shape[0])]
        else:
            want = [(i, j) for i in range(shape[0]) for j in range(i, shape[0])]
        if sorted(got) != want:
            raise ExportError(f"{p}: column {name!r} has fields {sorted(got)}, expected {want}")
        n = table.num_rows
        values = np.empty((n, *shape), dtype=meta["dtype"])
        for idx, v in got.items():
            values[(slice(None), *idx)] = v
            if len(idx) == 2:
                values[:, idx[1], idx[0]] = v
        columns[name] = Column(
            values,
            meta["unit"],
            meta["description"],
            tuple(meta["components"]),
            meta["nullable"],
            tuple(meta["labels"]),
        )
    return columns, metadata


def _codes(path: Path, field: str, chunked: Any, labels: list[str], dtype: np.dtype) -> np.ndarray:
    """The integer codes (index into ``labels``) of a dictionary-encoded field."""
    arr = chunked.combine_chunks() if chunked.num_chunks != 1 else chunked.chunk(0)
    if not pa.types.is_dictionary(arr.type):
        raise ExportError(f"{path}: field {field!r} has labels but is not dictionary-encoded")
    where = {label: i for i, label in enumerate(labels)}
    try:
        lookup = np.array([where[x] for x in arr.dictionary.to_pylist()], dtype=np.int64)
    except KeyError as exc:
        raise ExportError(f"{path}: field {field!r}: value {exc} is not one of {labels}") from None
    indices = arr.indices.to_numpy(zero_copy_only=False)
    return lookup[indices].astype(dtype) if len(lookup) else indices.astype(dtype)


ANGLE_SUFFIX = "_deg"
"""Ends the name of every angle column of run data (unit ``deg``)."""


def data_columns(columns: Mapping[str, Column]) -> dict[str, Column]:
    """A table's columns as run data states them: angles in degrees, ``_deg`` in their names.

    A column of unit ``rad`` becomes ``<name>_deg`` of unit ``deg``, its values
    ``np.degrees(values)`` (its components keep their names: ``truth_rph`` (roll, pitch,
    heading) becomes the fields ``truth_rph_deg_roll``, ...); a column already in ``deg`` whose
    name does not end in ``_deg`` gets the suffix (``truth_pos_geo`` -> ``truth_pos_geo_deg``).
    Every other column is kept as it is.

    Args:
        columns: the table's columns by name (angles in radians, SI inside the project).

    Returns:
        The columns in the same order, renamed and converted.

    Raises:
        ExportError: if a new name clashes with a column of the table.
    """
    out: dict[str, Column] = {}
    for name, col in columns.items():
        if col.unit == "rad":
            deg = np.degrees(col.values) if col.values.dtype.kind == "f" else col.values
            col = Column(deg, "deg", col.description, col.components, col.nullable, col.labels)
        if col.unit == "deg" and not name.endswith(ANGLE_SUFFIX):
            name = name + ANGLE_SUFFIX
        if name in out:
            raise ExportError(f"column {name!r}: the degrees' name clashes with another column")
        out[name] = col
    return out


def key_columns(n: int, run: int, vehicle: str, variant: str | None = None) -> dict[str, Column]:
    """The key columns that make a batch's files one dataset: ``run`` (int32), ``vehicle`` and,
    for a mission flying variants, ``variant`` (labelled: dictionary-encoded strings).

    Args:
        n: the table's number of rows.
        run: the run index of the batch.
        vehicle: the vehicle's name in the scene.
        variant: the variant (``compensated``, ``ga1``, ...), or ``None`` for none.

    Returns:
        The columns, each of ``n`` rows.
    """
    zeros = np.zeros(n, dtype=np.int32)
    out = {
        "run": Column(np.full(n, run, dtype=np.int32), "index", "run index of the batch"),
        "vehicle": Column(zeros, "text", "vehicle name in the scene", labels=(vehicle,)),
    }
    if variant is not None:
        out["variant"] = Column(
            zeros.copy(),
            "text",
            "variant of the run the mission flew (its own name: a course, a navigation method)",
            labels=(variant,),
        )
    return out


def data_file(table: str, run: int, vehicle: str, variant: str | None = None) -> Path:
    """Where a run's table lies in its run folder: ``data/<table>/run-NNNNNN[-<variant>]-<vehicle>
    .parquet`` (``tracks`` GeoJSON: ``data/tracks/...geojson``).

    Args:
        table: the table (``ticks``, ``usbl``, ``gps``, ``modem``, ``network``, ``tracks``).
        run: run index.
        vehicle: the vehicle's name.
        variant: the variant, or ``None``.

    Returns:
        The path relative to the run folder.
    """
    ext = "geojson" if table == "tracks" else "parquet"
    mid = f"-{variant}" if variant else ""
    return Path("data") / table / f"run-{run:06d}{mid}-{vehicle}.{ext}"


def open_dataset(run_folder: str | Path, table: str) -> pa.Table:
    """Read one table of a whole batch (every run, variant and vehicle) as one Arrow table.

    The files ``<run folder>/data/<table>/*.parquet`` are read in name order (run, variant,
    vehicle) with their schemas unified: a column some vehicles lack (a follower's ``hdop``, the
    EKF's ``ekf_current``) is null in the others' rows. The rows carry their ``run``,
    ``vehicle`` (and ``variant``); the table's metadata keeps the keys every file agrees on
    (``experiment``, ``seed``, ``table``). ``pyarrow.dataset.dataset(<run folder>/data/<table>)``
    reads the same files where their schemas are equal (one vehicle kind).

    Args:
        run_folder: the batch's run folder (holding ``data/``), or its ``data`` folder.
        table: ``ticks``, ``usbl``, ``gps``, ``modem``, ``network``.

    Returns:
        The rows of every file; ``.to_pandas()`` for a data frame (labels as categories).

    Raises:
        ExportError: if there is no such table, the folder holds the old layout
            (``data/run-NNNNNN/<vehicle>.<table>.parquet``), or the schemas do not unify.
    """
    import pyarrow.dataset as ds

    if not isinstance(run_folder, str | os.PathLike):
        raise ExportError(
            f"run_folder = {run_folder!r} ({type(run_folder).__name__}): must be the path of a "
            "run folder (str or Path)"
        )
    if type(table) is not str or not table.isidentifier():
        raise ExportError(f"table = {table!r}: must be a table's name (ticks, usbl, gps, ...)")
    root = Path(run_folder)
    data = root if root.name == "data" and not (root / "data").is_dir() else root / "data"
    if not data.is_dir():
        raise ExportError(f"{root}: no data folder (run a mission batch, or name its run folder)")
    folder = data / table
    files = sorted(folder.glob("*.parquet")) if folder.is_dir() else []
    if not files:
        old = sorted(p.name for p in data.glob("run-*") if p.is_dir())
        if old:
            raise ExportError(
                f"{data}: the old layout data/run-NNNNNN/<vehicle>.<table>.parquet ({old[0]}/ "
                "...), written before data/<table>/run-NNNNNN-<vehicle>.parquet; read its files "
                "one at a time with tasks.core.export.read_parquet, or run the batch again"
            )
        kinds = sorted(p.name for p in data.iterdir() if p.is_dir())
        raise ExportError(f"{data}: no table {table!r} (tables: {', '.join(kinds) or 'none'})")
    try:
        schemas = [pq.read_schema(f) for f in files]
        unified = pa.unify_schemas(schemas)
    except (OSError, pa.ArrowException) as exc:
        raise ExportError(f"{folder}: schemas do not unify: {' '.join(str(exc).split())}") from None
    everywhere = set.intersection(*(set(s.names) for s in schemas))
    fields = [f if f.name in everywhere else f.with_nullable(True) for f in unified]
    metas = [dict(s.metadata or {}) for s in schemas]
    common = {k: v for k, v in metas[0].items() if all(m.get(k) == v for m in metas[1:])}
    schema = pa.schema(fields, metadata=common)
    return ds.dataset([str(f) for f in files], schema=schema, format="parquet").to_table()
