"""Run data and recording of seed 003's tests: per-run statistics (``data/runs/runs.parquet``)
and the single sample's time series (``data/sample/run-NNNNNN.parquet``) as Parquet, and the
single sample's ``recording.rrd``, from the blocks' own numbers."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tasks.core import export, style
from tasks.core.recording import Recording
from tasks.core.registry import Experiment, ReportContext
from tasks.paper003.run import FIXED, METHODS
from tasks.paper003.scenario import (
    Paper003Scenario,
    periodic_fix_ticks,
    scenario_reading,
    truth_of,
)

Array = NDArray[np.float64]


def write_run_data(
    exp: Experiment, ctx: ReportContext, scn: Paper003Scenario, per_run: Array
) -> list[str]:
    """Parquet ``data/runs/runs.parquet``: per-run statistics, one row per run (column ``run``,
    int32), ``<method>_max``, ``<method>_mean``, ``<method>_std`` (m)."""
    meta = {"experiment": exp.name, "seed": str(ctx.seed), "runs": str(ctx.n_runs)}
    cols = {"run": export.Column(np.arange(ctx.n_runs, dtype=np.int32), "index", "run index")}
    for m, name in enumerate(METHODS):
        st = per_run[:, m]
        mean = st[:, 1] / st[:, 0]
        std = np.sqrt(np.maximum(st[:, 2] / st[:, 0] - mean * mean, 0.0))
        cols[f"{name}_max"] = export.Column(st[:, 3], "m", f"{name}: largest distance to reference")
        cols[f"{name}_mean"] = export.Column(mean, "m", f"{name}: mean distance to reference")
        cols[f"{name}_std"] = export.Column(std, "m", f"{name}: std of the distance (ddof 0)")
    export.write_parquet(ctx.out_dir / "data" / "runs" / "runs.parquet", cols, meta)
    return ["data/runs/runs.parquet"]


def record_sample(
    exp: Experiment, scn: Paper003Scenario, seed: int, run: int, one: dict, out_dir
) -> list[str]:
    """Write ``recording.rrd`` and the Parquet time series ``data/sample/run-NNNNNN.parquet`` of the
    single sample from its block data (the batch's own numbers)."""
    truth = truth_of(scn, scenario_reading(scn).geometry)
    t = truth.t_s
    t_fix = t[periodic_fix_ticks(scn)]

    def z3(p: Array) -> Array:
        return np.concatenate([p, np.zeros((len(p), 1))], axis=1)

    files = []
    if scn.report.recording:
        rec = Recording(out_dir / "recording.rrd", exp.name, f"{exp.name}/seed{seed}/run{run}")
        rec.track("leader", t, z3(truth.leader_m), (120, 120, 120))
        rec.track("truth", t, z3(truth.follower_m), style.rgb("truth"))
        for k in METHODS:
            rec.track(k.lower(), t, z3(one[f"track/{k}"]), style.rgb(k))
        for k in FIXED:
            ok = one[f"accepted/{k}"]
            rec.fixes(f"{k.lower()}_fix", t_fix[ok], z3(one[f"fix/{k}"][ok]), style.rgb(k))
            rec.scalars(f"hdop/{k.lower()}", t_fix[ok], one[f"hdop/{k}"][ok], style.rgb(k), k)
        for k in METHODS:
            rec.scalars(f"distance/{k.lower()}", t, one[f"distance/{k}"], style.rgb(k), k)
        rec.blueprint("distance", "hdop")
        rec.close()
        files.append("recording.rrd")
    if scn.report.run_data:
        en = ("east", "north")
        cols = {
            "run": export.Column(np.full(len(t), run, dtype=np.int32), "index", "run index"),
            "t": export.Column(t, "s", "time"),
            "leader": export.Column(truth.leader_m, "m", "leader reference", en),
            "reference": export.Column(truth.follower_m, "m", "follower reference", en),
        }
        for k in METHODS:
            cols[k] = export.Column(one[f"track/{k}"], "m", f"{k} estimate", en)
            cols[f"{k}_distance"] = export.Column(
                one[f"distance/{k}"], "m", f"{k}: distance to the reference"
            )
        rel = f"data/sample/run-{run:06d}.parquet"
        meta = {"experiment": exp.name, "seed": str(seed), "run": str(run)}
        export.write_parquet(out_dir / rel, cols, meta)
        files.append(rel)
    return files
