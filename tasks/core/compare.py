"""``bauv compare``: the metrics of several run folders side by side.

Each run folder's ``metrics.json`` is flattened to dotted names
(``aggregate.ekf_mean_error_m.mean``; a list's items by index, ``runs.0.summary.duration_s``)
holding its numbers and booleans (text and null are left out, and so is a number that is not
finite: NaN never reaches an output). The
selected metrics are shown as one row each with a column per run folder: on the terminal (at
most :data:`TERMINAL_COLUMNS` characters wide, values to 6 significant digits), and with
``--out DIR`` written whole as ``compare.md`` and ``compare.csv`` (every value as Python writes
it back exactly) and drawn as ``compare.png`` (+ ``compare.pdf``): a panel per metric, a bar per
run folder.

Without ``--metric`` the metrics are those outside lists (a batch's per-run lists would swamp the
table); each ``--metric`` glob (``fnmatch``, case-sensitive, against the dotted name, lists
included) selects instead. Folders of different experiments may be compared: a metric one of
them lacks is shown as ``-`` (empty in the CSV).

Bad input is refused before anything is written, as :class:`~bauv_sim.errors.ConfigError` (one
line, exit status 2 from ``bauv``): a path that is not a run folder (no ``run.json``), a batch
that did not complete, a missing or unreadable ``metrics.json``, the same folder twice, a glob
that matches no metric, an ``--out`` folder that exists and is not empty.
"""

from __future__ import annotations

import csv
import fnmatch
import io
import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from bauv_sim.errors import ConfigError
from tasks.core import style
from tasks.core.files import atomic_write_bytes

__all__ = [
    "FIGURE_PANELS",
    "TERMINAL_COLUMNS",
    "Comparison",
    "RunMetrics",
    "check_out",
    "compare",
    "csv_text",
    "flatten",
    "load_run",
    "markdown",
    "terminal_table",
    "write",
]

TERMINAL_COLUMNS = 100
"""Widest terminal table, characters; more run folders than fit are shown in several tables."""

FIGURE_PANELS = 24
"""Most metrics drawn in ``compare.png`` (the first ones selected); the files hold them all."""

Value = float | int | bool


@dataclass(frozen=True)
class RunMetrics:
    """One run folder's metrics.

    Attributes:
        folder: the run folder as given.
        label: its column heading (the folder's name, or more of its path where two names clash).
        experiment: the experiment named by ``run.json``.
        seed: the batch seed (``run.json``).
        n_runs: Monte Carlo runs of the batch (``run.json``).
        values: dotted metric name -> value (int, float or bool as in the file), in file order.
    """

    folder: Path
    label: str
    experiment: str
    seed: int
    n_runs: int
    values: dict[str, Value]


@dataclass(frozen=True)
class Comparison:
    """The selected metrics of several run folders.

    Attributes:
        runs: the run folders in the order given.
        metrics: the selected dotted names, in the order first seen.
    """

    runs: tuple[RunMetrics, ...]
    metrics: tuple[str, ...]

    def value(self, metric: str, run: RunMetrics) -> Value | None:
        """The value of ``metric`` in ``run``, None where that folder lacks it."""
        return run.values.get(metric)


def flatten(data: object, prefix: str = "") -> dict[str, Value]:
    """The numbers and booleans of a JSON document under dotted names.

    Args:
        data: a parsed JSON value.
        prefix: the name of ``data`` itself ("" at the top).

    Returns:
        Dotted name -> value: dict keys joined by ``.``, list items by their index; numbers and
        booleans as JSON gave them (int, float, bool). Text, null and non-finite numbers are
        left out.
    """
    out: dict[str, Value] = {}
    if isinstance(data, Mapping):
        items: Iterable[tuple[str, object]] = ((str(k), v) for k, v in data.items())
    elif isinstance(data, list):
        items = ((str(i), v) for i, v in enumerate(data))
    else:
        if isinstance(data, bool | int):
            out[prefix] = data  # an int stays exact, however large
        elif isinstance(data, float) and math.isfinite(data):
            out[prefix] = data
        return out
    for key, value in items:
        out.update(flatten(value, f"{prefix}.{key}" if prefix else key))
    return out


def _in_list(name: str, data: object) -> bool:
    """Whether the dotted ``name`` passes through a list of ``data``."""
    for part in name.split("."):
        if isinstance(data, list):
            return True
        if not isinstance(data, Mapping) or part not in data:
            return False
        data = data[part]
    return False


def _read_json(path: Path, what: str, folder: str) -> object:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"RUN = {folder!r}: no {what} in it") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"RUN = {folder!r}: {what} cannot be read ({exc})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise ConfigError(f"RUN = {folder!r}: {what} is not JSON ({exc})") from None


def load_run(folder: str | Path, label: str | None = None) -> tuple[RunMetrics, set[str]]:
    """Read one run folder's ``run.json`` and ``metrics.json``.

    Args:
        folder: a run folder written by ``bauv run``.
        label: the column heading (default: the folder's name).

    Returns:
        The folder's metrics, and the names among them that pass through a list.

    Raises:
        ConfigError: not a folder, no ``run.json`` (not a run folder), a batch not complete, no
            ``metrics.json`` or one that is not a JSON object.
    """
    path = Path(folder)
    shown = str(folder)
    if not path.is_dir():
        raise ConfigError(f"RUN = {shown!r}: not a folder; give run folders written by bauv run")
    if not (path / "run.json").is_file():
        raise ConfigError(f"RUN = {shown!r}: not a run folder (no run.json in it)")
    record = _read_json(path / "run.json", "run.json", shown)
    if not isinstance(record, dict) or not isinstance(record.get("experiment"), str):
        raise ConfigError(f"RUN = {shown!r}: run.json names no experiment")
    if record.get("state", "complete") != "complete":
        raise ConfigError(
            f"RUN = {shown!r}: the batch is {record.get('state')!r}, not complete "
            "(finish it with bauv run --resume)"
        )
    metrics = _read_json(path / "metrics.json", "metrics.json", shown)
    if not isinstance(metrics, dict):
        raise ConfigError(f"RUN = {shown!r}: metrics.json is not a JSON object")
    values = flatten(metrics)
    listed = {name for name in values if _in_list(name, metrics)}
    seed, n_runs = record.get("seed"), record.get("n_runs")
    return (
        RunMetrics(
            folder=path,
            label=label or path.resolve().name,
            experiment=record["experiment"],
            seed=seed if isinstance(seed, int) else -1,
            n_runs=n_runs if isinstance(n_runs, int) else -1,
            values=values,
        ),
        listed,
    )


def _labels(folders: Sequence[Path]) -> list[str]:
    """Column headings: each folder's name, with as many parent names as it takes to tell
    folders of the same name apart."""
    parts = [f.resolve().parts for f in folders]
    depth = 1
    while True:
        labels = ["/".join(p[-depth:]) for p in parts]
        if len(set(labels)) == len(labels) or depth >= max(len(p) for p in parts):
            return labels
        depth += 1


def compare(folders: Sequence[str | Path], patterns: Sequence[str] = ()) -> Comparison:
    """Read and select the metrics of run folders.

    Args:
        folders: run folders, at least one, each once.
        patterns: ``fnmatch`` globs on the dotted names (empty: every metric outside a list).

    Returns:
        The comparison, metrics in the order first seen across the folders.

    Raises:
        ConfigError: a folder refused by :func:`load_run`, a folder given twice, a glob that
            matches no metric of any folder.
    """
    if not folders:
        raise ConfigError("RUN: give at least one run folder")
    seen: dict[Path, str] = {}
    for f in folders:
        key = Path(f).resolve()
        if key in seen:
            raise ConfigError(f"RUN = {str(f)!r}: given twice (as {seen[key]!r} before)")
        seen[key] = str(f)
    labels = _labels([Path(f) for f in folders])
    loaded = [load_run(f, lab) for f, lab in zip(folders, labels, strict=True)]
    runs = tuple(r for r, _ in loaded)
    listed = set().union(*(names for _, names in loaded))
    names = list(dict.fromkeys(n for r in runs for n in r.values))
    if not patterns:
        selected = [n for n in names if n not in listed]
    else:
        selected = []
        for pat in patterns:
            hits = [n for n in names if fnmatch.fnmatchcase(n, pat)]
            if not hits:
                some = ", ".join(n for n in names if n not in listed)
                some = some if len(some) <= 160 else some[:157] + "..."
                raise ConfigError(
                    f"--metric = {pat!r}: matches no metric of the run folders "
                    f"(dotted names, e.g. {some or 'none: no numbers in metrics.json'})"
                )
            selected.extend(h for h in hits if h not in selected)
    if not selected:
        raise ConfigError("RUN: the run folders' metrics.json hold no number outside a list")
    return Comparison(runs=runs, metrics=tuple(selected))


def _short(value: Value | None) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int) and abs(value) >= 10**15:  # 'g' would go through a float
        digits = str(abs(value))
        sign = "-" if value < 0 else ""
        return f"{sign}{digits[0]}.{digits[1:6]}e+{len(digits) - 1}"
    return f"{value:.6g}"


def _exact(value: Value | None, missing: str) -> str:
    if value is None:
        return missing
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _fit(text: str, width: int, keep_end: bool = False) -> str:
    if len(text) <= width:
        return text
    return "..." + text[-(width - 3) :] if keep_end else text[: width - 3] + "..."


def terminal_table(cmp: Comparison, columns: int = TERMINAL_COLUMNS) -> str:
    """The comparison as plain text at most ``columns`` characters wide.

    Values to 6 significant digits; a metric name too long for its column keeps its end; run
    folders that do not fit beside each other continue in another table below.

    Args:
        cmp: the comparison.
        columns: widest line, characters (at least 40).

    Returns:
        The text, ending with a newline.
    """
    value_w = 12
    cells = {r.label: [_short(cmp.value(m, r)) for m in cmp.metrics] for r in cmp.runs}
    name_w = min(max(len(m) for m in cmp.metrics), max(20, columns - 2 - (value_w + 2)))
    per_table = max(1, (columns - name_w) // (value_w + 2))
    lines = [
        f"{i + 1}. {r.label}: {r.experiment}, seed {r.seed}, {r.n_runs} run(s)"
        for i, r in enumerate(cmp.runs)
    ]
    lines = [_fit(line, columns) for line in lines]
    for start in range(0, len(cmp.runs), per_table):
        group = cmp.runs[start : start + per_table]
        heads = [_fit(f"{start + j + 1}. {r.label}", value_w, True) for j, r in enumerate(group)]
        lines.append("")
        lines.append("  ".join(["metric".ljust(name_w), *(h.rjust(value_w) for h in heads)]))
        lines.append("  ".join(["-" * name_w, *("-" * value_w for _ in group)]))
        for i, m in enumerate(cmp.metrics):
            row = [_fit(m, name_w, True).ljust(name_w)]
            row += [_fit(cells[r.label][i], value_w).rjust(value_w) for r in group]
            lines.append("  ".join(row).rstrip())
    return "\n".join(lines) + "\n"


def markdown(cmp: Comparison) -> str:
    """The comparison as a Markdown page: the run folders, then every metric, values exact."""
    out = ["# Metrics compared", ""]
    out += ["| # | run folder | experiment | seed | runs |", "|---|---|---|---|---|"]
    out += [
        f"| {i + 1} | `{r.folder}` | {r.experiment} | {r.seed} | {r.n_runs} |"
        for i, r in enumerate(cmp.runs)
    ]
    out += ["", "| metric | " + " | ".join(f"{i + 1}. {r.label}" for i, r in enumerate(cmp.runs))]
    out[-1] += " |"
    out.append("|---|" + "---:|" * len(cmp.runs))
    for m in cmp.metrics:
        vals = " | ".join(_exact(cmp.value(m, r), "-") for r in cmp.runs)
        out.append(f"| `{m}` | {vals} |")
    return "\n".join(out) + "\n"


def csv_text(cmp: Comparison) -> str:
    """The comparison as CSV: a ``metric`` column, then one per run folder (its label); values
    exact (``repr``), ``true``/``false``, empty where the folder lacks the metric."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["metric", *(r.label for r in cmp.runs)])
    for m in cmp.metrics:
        w.writerow([m, *(_exact(cmp.value(m, r), "") for r in cmp.runs)])
    return buf.getvalue()


def _plotted(value: Value | None) -> float | None:
    """A value as the bar's length (a boolean as 0 or 1); None if missing or beyond a float."""
    if value is None:
        return None
    try:
        return float(value)
    except OverflowError:
        return None


@style.styled
def figure(cmp: Comparison, path: Path) -> list[str]:
    """Draw the first :data:`FIGURE_PANELS` metrics: a panel each, a horizontal bar per run
    folder (numbered as in the tables; booleans as 0/1), its value written beside it.

    Args:
        cmp: the comparison.
        path: the PNG file (a PDF is written beside it).

    Returns:
        The names of the files written.
    """
    import numpy as np

    shown = cmp.metrics[:FIGURE_PANELS]
    ncols = min(3, len(shown))
    nrows = math.ceil(len(shown) / ncols)
    n = len(cmp.runs)
    fig, axes = style.subplots(
        "page", height_in=min(11.0, nrows * (0.45 + 0.22 * n)), nrows=nrows, ncols=ncols
    )
    axes = np.ravel(axes)
    colors = [c["color"] for c in style.RC["axes.prop_cycle"]]
    ticks = [f"{i + 1}" for i in range(n)]
    for ax, m in zip(axes, shown, strict=False):
        vals = [cmp.value(m, r) for r in cmp.runs]
        y = np.arange(n)[::-1]
        for yi, v, i in zip(y, vals, range(n), strict=True):
            x = _plotted(v)
            if x is None:
                why = " missing" if v is None else " beyond a float"
                ax.text(0, yi, why, ha="left", va="center", fontsize=6, color="0.4")
                continue
            ax.barh(yi, x, color=colors[i % len(colors)], height=0.7)
            side = "left" if x >= 0 else "right"
            ax.text(x, yi, f" {_short(v)} ", ha=side, va="center", fontsize=6)
        ax.set_yticks(y, ticks)
        ax.axvline(0.0, color="0.3", linewidth=0.6)
        ax.margins(x=0.25)
        ax.grid(axis="y", visible=False)
        ax.set_title(_fit(m, 48, keep_end=True), loc="left", fontsize=7)
    for ax in axes[len(shown) :]:
        ax.set_axis_off()
    legend = ", ".join(f"{i + 1}: {_fit(r.label, 40, True)}" for i, r in enumerate(cmp.runs))
    left_out = len(cmp.metrics) - len(shown)
    more = f"; the first {len(shown)} of {len(cmp.metrics)} metrics" if left_out else ""
    fig.suptitle(f"Run folders {legend}{more}", fontsize=7)
    return style.save(fig, path)


def check_out(out_dir: str | Path) -> Path:
    """Refuse an ``--out`` that is a file or a folder that is not empty.

    Raises:
        ConfigError: naming the folder.
    """
    out = Path(out_dir)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ConfigError(f"--out = {str(out_dir)!r}: exists and is not an empty folder")
    return out


def write(cmp: Comparison, out_dir: str | Path) -> list[Path]:
    """Write ``compare.md``, ``compare.csv``, ``compare.png`` and ``compare.pdf`` in ``out_dir``.

    Args:
        cmp: the comparison.
        out_dir: a folder that does not exist or is empty (created with its parents).

    Returns:
        The files written.

    Raises:
        ConfigError: ``out_dir`` is a file, or a folder that is not empty.
    """
    out = check_out(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(out / "compare.md", markdown(cmp).encode())
    atomic_write_bytes(out / "compare.csv", csv_text(cmp).encode())
    names = figure(cmp, out / "compare.png")
    return [out / "compare.md", out / "compare.csv", *(out / n for n in names)]
