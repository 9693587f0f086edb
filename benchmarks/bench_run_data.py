"""Cost of a mission's run data: writing one run's tables (``export_runs``: validation, degrees,
labels, key columns, field metadata, atomic write) against a bare ``pyarrow.parquet.write_table``
of the same flat columns, and reading a batch's ticks back as one table (``open_dataset``, schemas
unified) against ``pyarrow.dataset`` and a loop of ``read_parquet``; all interleaved in one run
through the shared harness. The runs are flown once, before any timing (mission/short, 120 s).

Usage: ``python benchmarks/bench_run_data.py [--runs 4] [--repeats 7]`` (with
``PYTHONPATH=<another checkout>`` the writing part measures that checkout's ``export_runs``)
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq
from harness import machine, measure, table

from tasks.closed_loop.report import export_runs
from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.export import read_parquet
from tasks.core.runner import plan_batch

try:  # a checkout before the layout data/<table>/ (PYTHONPATH=...): the writing part only
    from tasks.core.export import open_dataset
except ImportError:
    open_dataset = None


def flat(cols: dict) -> pa.Table:
    """The columns as a flat Arrow table, no metadata (the floor a Parquet writer costs)."""
    out = {}
    for name, col in cols.items():
        v = col.values
        if v.ndim == 1:
            out[name] = v
        else:
            for i in range(v.shape[1]):
                out[f"{name}_{i}"] = v[:, i] if v.ndim == 2 else v[:, i, i]
    return pa.table(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    print(machine())
    scn = plan_batch("mission/short", overrides=["timing.max_duration_s=120"]).scenario
    runs = [fly(WaypointMission(), scn, 0, r) for r in range(a.runs)]
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s)
        k = iter(range(10**6))

        def write_ours() -> None:
            export_runs(tmp / f"w{next(k)}", "mission/short", runs)

        def write_bare() -> None:
            d = tmp / f"b{next(k)}"
            d.mkdir()
            for r in runs:
                for kind, cols in {"ticks": r.lead.ticks, **r.lead.fixes}.items():
                    pq.write_table(flat(cols), d / f"{kind}-{r.run}.parquet")

        res = measure(
            {"export_runs": write_ours, "bare write_table": write_bare},
            repeats=a.repeats,
            warmup=1,
            per={"export_runs": a.runs, "bare write_table": a.runs},
        )
        print(f"writing one run's tables ({len(runs[0].lead['t'])} ticks):")
        print(table(res, reference="bare write_table", unit="ms", scale=1e3))
        batch = tmp / "batch"
        files = export_runs(batch, "mission/short", runs)
        size = sum((batch / f).stat().st_size for f in files) / a.runs
        print(f"bytes per run: {size:.0f}")
        if open_dataset is None:
            return
        ticks = sorted((batch / "data" / "ticks").glob("*.parquet"))
        res = measure(
            {
                "open_dataset": lambda: open_dataset(batch, "ticks"),
                "pyarrow.dataset": lambda: ds.dataset(batch / "data" / "ticks").to_table(),
                "read_parquet loop": lambda: [read_parquet(f) for f in ticks],
            },
            repeats=a.repeats,
            warmup=1,
        )
        print(f"reading the batch's ticks ({a.runs} runs):")
        print(table(res, reference="pyarrow.dataset", unit="ms", scale=1e3))


if __name__ == "__main__":
    main()
