"""Run data a user can take away: typed columns with units, written as Apache Parquet."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Column:
    """A column of run data.

    Attributes:
        values: shape (T,), (T, k) or, for symmetric matrices, (T, k, k).
        unit: SI unit (``"m"``, ``"rad"``, ``"m/s"``...), ``"1"`` for dimensionless, ``"bool"``,
            ``"enum"``, ``"index"``, ``"text"``.
        description: what it is, with its frame.
        components: names of the last axis for (T, k) and (T, k, k) columns.
        nullable: whether NaN (float) marks a missing value (written as null).
    """

    values: np.ndarray
    unit: str
    description: str
    components: tuple[str, ...] = ()
    nullable: bool = False


def write_parquet(path, columns, metadata) -> None:  # provisional: replaced by the full writer
    import pyarrow as pa
    import pyarrow.parquet as pq

    fields, arrays = [], []
    for name, c in columns.items():
        v = np.asarray(c.values)
        flat = v.reshape(len(v), -1) if v.ndim > 1 else v[:, None]
        for j in range(flat.shape[1]):
            fields.append(
                pa.field(
                    f"{name}.{j}" if v.ndim > 1 else name,
                    pa.from_numpy_dtype(flat.dtype),
                    metadata={"unit": c.unit},
                )
            )
            arrays.append(pa.array(flat[:, j]))
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=metadata)), path)
