"""Tables and metrics files shared by every experiment's report.

A run folder gets ``tables.md`` (every table, Markdown, in the paper's layout), one CSV per table in
``tables/`` and ``metrics.json`` (validated by a pydantic model whose JSON Schema is kept in
``docs/schemas/``).
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from tasks.core import console
from tasks.core.run_folder import atomic_write_text

Cell = str | float | int | None


def pool_blocks(
    blocks: Iterable[Mapping[str, Any]], summed: Sequence[str], per_run: Sequence[str]
) -> dict[str, Any]:
    """Reduce a batch's blocks one at a time: the ``summed`` arrays added up (a block's own
    arrays are not kept, so memory grows with the runs' per-run arrays only), the ``per_run``
    arrays concatenated along their first (run) axis.

    Args:
        blocks: each block's arrays by name (numpy arrays; a summed one of the same shape in every
            block).
        summed: names of the arrays to add up.
        per_run: names of the arrays to stack.

    Returns:
        Every name of ``summed`` and ``per_run`` with its pooled array.
    """
    import numpy as np

    sums: dict[str, Any] = {}
    cat: dict[str, list[Any]] = {k: [] for k in per_run}
    for block in blocks:
        for k in summed:
            sums[k] = block[k].copy() if k not in sums else sums[k] + block[k]
        for k in per_run:
            cat[k].append(block[k])
    return {**sums, **{k: np.concatenate(v) for k, v in cat.items()}}


@dataclass(frozen=True)
class Table:
    """A titled table.

    Attributes:
        title: caption, e.g. ``"Table 4 (test-1, 100 passages)"``.
        columns: column headers (with units).
        rows: rows of cells; floats are printed with ``digits`` decimals, ``None`` as a dash.
        digits: decimals for floats.
        note: a line printed under the table.
        slug: the CSV's file name stem (default: from the title).
        key: how many leading columns name a row, repeated in every group of columns when the
            terminal's copy is split (0: the leading columns of text, see :meth:`key_columns`).
    """

    title: str
    columns: Sequence[str]
    rows: Sequence[Sequence[Cell]]
    digits: int = 1
    note: str = ""
    slug: str = field(default="")
    key: int = 0

    def _fmt(self, c: Cell) -> str:
        if c is None:
            return "-"
        if isinstance(c, float):
            return "nan" if math.isnan(c) else f"{c:.{self.digits}f}"
        return str(c)

    def cells(self) -> list[list[str]]:
        """Rows as formatted strings."""
        return [[self._fmt(c) for c in row] for row in self.rows]

    def to_markdown(self) -> str:
        """GitHub-flavoured Markdown with a bold caption."""
        lines = [f"**{self.title}**", "", "| " + " | ".join(self.columns) + " |"]
        lines.append("|" + "|".join("---" for _ in self.columns) + "|")
        lines += ["| " + " | ".join(r) + " |" for r in self.cells()]
        if self.note:
            lines += ["", self.note]
        return "\n".join(lines) + "\n"

    def to_text(self) -> str:
        """Aligned plain text for the terminal, within :data:`tasks.core.console.WIDTH` columns (a
        wider table is narrowed on the screen only: headers wrapped, then groups of columns that
        repeat the key columns; see :func:`tasks.core.console.table`)."""
        return console.table(self.title, self.columns, self.cells(), self.note, self.key_columns())

    def key_columns(self) -> int:
        """How many leading columns name a row: :attr:`key`, or else the leading columns whose
        cells are all text (at least 1, at most 3)."""
        if self.key:
            return self.key
        k = 0
        while k < min(3, len(self.columns) - 1) and all(
            isinstance(r[k], str) or r[k] is None for r in self.rows
        ):
            k += 1
        return max(k, 1)

    def to_csv(self) -> str:
        """CSV with full-precision numbers."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for row in self.rows:
            w.writerow(["" if c is None else repr(c) if isinstance(c, float) else c for c in row])
        return buf.getvalue()

    def file_slug(self) -> str:
        """File name stem for the CSV."""
        s = self.slug or self.title
        return re.sub(r"[^a-z0-9]+", "-", s.lower()).strip("-")[:80]


def write_tables(out_dir: Path, tables: Sequence[Table], heading: str = "") -> list[str]:
    """Write ``tables.md`` and ``tables/<slug>.csv``.

    Returns:
        The written paths relative to ``out_dir``.
    """
    md = ([f"# {heading}", ""] if heading else []) + [t.to_markdown() for t in tables]
    atomic_write_text(out_dir / "tables.md", "\n".join(md))
    files = ["tables.md"]
    for t in tables:
        rel = f"tables/{t.file_slug()}.csv"
        atomic_write_text(out_dir / rel, t.to_csv())
        files.append(rel)
    return files


def write_metrics(out_dir: Path, metrics: BaseModel) -> str:
    """Write ``metrics.json`` from a pydantic model (sorted keys, stable float repr)."""
    text = json.dumps(metrics.model_dump(mode="json"), indent=2, sort_keys=True, allow_nan=False)
    atomic_write_text(out_dir / "metrics.json", text + "\n")
    return "metrics.json"
