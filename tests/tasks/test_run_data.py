"""Run data a user can take away: the Parquet files of a mission batch hold every run's truth,
estimates, measurements and commands, equal to the run's own arrays and to the rerun recording,
with a unit on every field (``docs/run-data.md``)."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.export import read_parquet
from tasks.core.recording import read_time_series
from tasks.core.runner import plan_batch, run

SHORT = "mission/short"
OVERRIDES = ["timing.max_duration_s=60", "report.figures=false"]


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    out = tmp_path_factory.mktemp("batch") / "run"
    run(SHORT, n_runs=2, seed=3, out_dir=out, overrides=OVERRIDES, progress=False)
    scn = plan_batch(SHORT, overrides=OVERRIDES).scenario
    flown = [fly(WaypointMission(), scn, 3, r).lead for r in range(2)]
    return out, flown


def test_every_run_has_its_tables_and_every_field_a_unit(batch):
    out, _ = batch
    for r in range(2):
        folder = out / "data" / f"run-{r:06d}"
        names = {p.name for p in folder.iterdir()}
        assert {"bauv.ticks.parquet", "bauv.usbl.parquet"} <= names
        assert names <= {"bauv.ticks.parquet", "bauv.usbl.parquet", "bauv.gps.parquet"}
        for path in folder.iterdir():
            schema = pq.read_schema(path)
            meta = {k.decode(): v.decode() for k, v in schema.metadata.items()}
            assert meta["experiment"] == SHORT and meta["run"] == str(r) and meta["seed"] == "3"
            for field in schema:
                assert field.metadata and field.metadata[b"unit"], (path.name, field.name)


def test_parquet_truth_and_ekf_equal_the_runs_arrays(batch):
    out, flown = batch
    for r, v in enumerate(flown):
        table = pq.read_table(out / "data" / f"run-{r:06d}" / "bauv.ticks.parquet")
        assert table.num_rows == len(v["t"])
        for i, axis in enumerate(("east", "north", "up")):
            assert np.array_equal(table[f"truth_pos.{axis}"].to_numpy(), v["truth_pos"][:, i])
            assert np.array_equal(table[f"ekf_pos.{axis}"].to_numpy(), v["ekf_pos"][:, i])
        assert table.schema.field("truth_pos.east").metadata[b"unit"] == b"m"
        assert table.schema.field("ekf_P.east.north").metadata[b"unit"] == b"m^2"
        assert np.array_equal(table["ekf_P.east.north"].to_numpy(), v["ekf_P"][:, 0, 1])
        cols, _ = read_parquet(out / "data" / f"run-{r:06d}" / "bauv.ticks.parquet")
        assert set(cols) == set(v.ticks)
        for name, col in v.ticks.items():
            assert np.array_equal(cols[name].values, col.values), name
            assert cols[name].unit == col.unit
        fixes, _ = read_parquet(out / "data" / f"run-{r:06d}" / "bauv.usbl.parquet")
        for name, col in v.fixes["usbl"].items():
            assert np.array_equal(fixes[name].values, col.values), name
        assert fixes["accepted"].values.dtype == bool


def test_parquet_equals_the_recording(batch):
    out, _ = batch
    table = pq.read_table(out / "data" / "run-000000" / "bauv.ticks.parquet")
    rec = out / "recording.rrd"
    t, truth = read_time_series(rec, "world/truth/position", "Points3D:positions")
    _, ekf = read_time_series(rec, "world/ekf/position", "Points3D:positions")
    assert np.allclose(t, table["t"].to_numpy())
    for name, got in (("truth_pos", truth), ("ekf_pos", ekf)):
        want = np.column_stack([table[f"{name}.{a}"].to_numpy() for a in ("east", "north", "up")])
        # rerun stores positions as float32: agreement to float32 rounding (1e-7 relative)
        assert np.allclose(got, want, rtol=2e-7, atol=1e-5), name


def test_the_batch_is_complete_with_every_runs_data(batch):
    out, _ = batch
    assert json.loads((out / "run.json").read_text())["state"] == "complete"
    assert (out / "data" / "run-000001" / "bauv.ticks.parquet").is_file()
