"""What ``bauv`` prints to the terminal, fitted within :data:`WIDTH` columns.

A table keeps its whole width in the files (``tables.md`` and its CSV, :mod:`tasks.core.report`);
on the terminal, one wider than :data:`WIDTH` has its long headers wrapped onto two lines and, if
it is still too wide, is split into groups of columns, each group repeating the table's key
columns (the leading columns of names, e.g. ``Method``) so that every row can be read on its own.
A line of prose longer than :data:`WIDTH` is wrapped at spaces, its continuation lines indented
two spaces more than the line (a word longer than the width, e.g. a path, is left whole).
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence

WIDTH = 100
"""The widest line ``bauv`` prints to the terminal, characters."""

GAP = "  "
"""Between two columns of a table."""


def wrap(text: str, width: int = WIDTH) -> str:
    """Wrap every line of ``text`` longer than ``width`` at spaces.

    Args:
        text: lines separated by ``\\n`` (a trailing newline is kept).
        width: the widest line wanted, characters.

    Returns:
        The text with each long line broken at spaces; a continuation line is indented two
        spaces more than its line. Shorter lines are unchanged.
    """
    out = []
    for line in text.split("\n"):
        if len(line) <= width:
            out.append(line)
            continue
        indent = line[: len(line) - len(line.lstrip())]
        out += textwrap.wrap(
            line,
            width,
            initial_indent="",
            subsequent_indent=indent + "  ",
            break_long_words=False,
            break_on_hyphens=False,
        )
    return "\n".join(out)


def table(
    title: str,
    columns: Sequence[str],
    cells: Sequence[Sequence[str]],
    note: str = "",
    key: int = 1,
    width: int = WIDTH,
) -> str:
    """A table as aligned text within ``width`` columns.

    The first column is aligned left, the others right. A table that fits is one block with a
    one-line header; else its headers are wrapped onto two lines where that narrows a column;
    else its columns are split into groups, each headed by the first ``key`` columns. A row
    still too wide (one cell wider than the screen) is wrapped like prose and its rule cut.

    Args:
        title: printed above (wrapped).
        columns: the headers, one per column.
        cells: rows of formatted cells, each as long as ``columns``.
        note: printed below (wrapped), or ``""``.
        key: how many leading columns name a row (repeated in every group), at least 1.
        width: the widest line wanted, characters.

    Returns:
        The text, ending with a newline.
    """
    n = len(columns)
    key = max(1, min(key, n - 1)) if n > 1 else 1
    body_w = [max([len(r[i]) for r in cells], default=0) for i in range(n)]
    one_line = [max(b, len(c)) for b, c in zip(body_w, columns, strict=True)]
    if _span(one_line, range(n)) <= width:
        heads = [[c] for c in columns]
        widths = one_line
    else:
        heads = [_two_lines(c, b) for c, b in zip(columns, body_w, strict=True)]
        widths = [max(b, *map(len, h)) for b, h in zip(body_w, heads, strict=True)]
    groups = _groups(widths, key, width)
    out = [wrap(title, width)] if title else []
    for g, cols in enumerate(groups):
        if g:
            out.append("")
        depth = max(len(heads[i]) for i in cols)
        for k in range(depth):
            padded = [
                heads[i][k - depth + len(heads[i])] if k >= depth - len(heads[i]) else ""
                for i in cols
            ]
            out.append(_line(padded, [widths[i] for i in cols]))
        out.append(GAP.join("-" * widths[i] for i in cols)[:width])
        out += [_line([r[i] for i in cols], [widths[i] for i in cols]) for r in cells]
    if note:
        out.append(wrap(note, width))
    # a cell wider than the screen by itself (a failed run's reason): its row wrapped like prose
    return wrap("\n".join(out), width) + "\n"


def _span(widths: Sequence[int], cols: Sequence[int]) -> int:
    return sum(widths[i] for i in cols) + len(GAP) * (len(cols) - 1)


def _line(cells: Sequence[str], widths: Sequence[int]) -> str:
    first = cells[0].ljust(widths[0])
    rest = [c.rjust(w) for c, w in zip(cells[1:], widths[1:], strict=True)]
    return GAP.join([first, *rest]).rstrip()


def _two_lines(header: str, body: int) -> list[str]:
    """``header`` on one line, or on two (at a space) where that makes its column narrower than
    the header and no narrower than ``body``, the widest cell."""
    if len(header) <= body or " " not in header:
        return [header]
    best = [header]
    for cut in (i for i, ch in enumerate(header) if ch == " "):
        parts = [header[:cut], header[cut + 1 :]]
        if max(map(len, parts)) < max(map(len, best)):
            best = parts
    return best


def _groups(widths: Sequence[int], key: int, width: int) -> list[list[int]]:
    """The columns split into groups that fit ``width``, each starting with the key columns: the
    fewest groups, with the other columns shared out as evenly as that allows (a table of
    repeating triplets, value / paper / ratio, then splits between triplets); a column too wide
    for any group gets one of its own."""
    n = len(widths)
    if _span(widths, range(n)) <= width:
        return [list(range(n))]
    keys, rest = list(range(key)), list(range(key, n))
    for g in range(2, len(rest) + 1):
        size, extra = divmod(len(rest), g)
        chunks, start = [], 0
        for j in range(g):
            stop = start + size + (1 if j < extra else 0)
            chunks.append(keys + rest[start:stop])
            start = stop
        if all(_span(widths, c) <= width for c in chunks):
            return chunks
    return [[*keys, i] for i in rest]


def labelled(label: str, text: str, label_width: int, width: int = WIDTH) -> str:
    """``label`` padded to ``label_width``, two spaces, then ``text`` wrapped within ``width``
    with its continuation lines under its first (e.g. ``bauv list``'s name and summary)."""
    indent = " " * (label_width + len(GAP))
    return textwrap.fill(
        text,
        width,
        initial_indent=label.ljust(label_width) + GAP,
        subsequent_indent=indent,
        break_long_words=False,
        break_on_hyphens=False,
    )
