"""Run data a user can take away: the Parquet files of a mission batch hold every run's truth,
estimates, measurements and commands, equal to the run's own arrays (angles in degrees) and to the
rerun recording, with a unit on every field (``docs/run-data.md``)."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from tasks.closed_loop.result import CURRENT_COLUMN, FIX_COLUMNS, TICK_COLUMNS
from tasks.closed_loop.world import WaypointMission, fly
from tasks.core.export import data_columns, key_columns, read_parquet
from tasks.core.recording import read_time_series
from tasks.core.runner import plan_batch, run

from .run_data_doc import prose_units, table_units

SHORT = "mission/short"
OVERRIDES = ["timing.max_duration_s=60", "report.figures=false"]


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    out = tmp_path_factory.mktemp("batch") / "run"
    run(SHORT, n_runs=2, seed=3, out_dir=out, overrides=OVERRIDES, progress=False)
    scn = plan_batch(SHORT, overrides=OVERRIDES).scenario
    flown = [fly(WaypointMission(), scn, 3, r).lead for r in range(2)]
    return out, flown


def file(out, table, r, vehicle="bauv"):
    """A run's table in the layout data/<table>/run-NNNNNN-<vehicle>.parquet."""
    return out / "data" / table / f"run-{r:06d}-{vehicle}.parquet"


def as_written(name, unit):
    """A column's name and unit in the files: an angle in degrees, ``_deg`` ending its name."""
    if unit == "rad":
        return name + "_deg", "deg"
    return name, unit


@pytest.mark.slow
def test_every_run_has_its_tables_and_every_field_a_unit(batch):
    out, _ = batch
    tables = {p.name for p in (out / "data").iterdir()}
    assert {"ticks", "usbl"} <= tables <= {"ticks", "usbl", "gps"}
    for r in range(2):
        paths = [file(out, t, r) for t in sorted(tables)]
        assert file(out, "ticks", r).is_file() and file(out, "usbl", r).is_file()
        for path in (p for p in paths if p.exists()):
            schema = pq.read_schema(path)
            meta = {k.decode(): v.decode() for k, v in schema.metadata.items()}
            assert meta["experiment"] == SHORT and meta["run"] == str(r) and meta["seed"] == "3"
            for field in schema:
                assert field.metadata and field.metadata[b"unit"], (path.name, field.name)


def test_parquet_truth_and_ekf_equal_the_runs_arrays(batch):
    out, flown = batch
    for r, v in enumerate(flown):
        table = pq.read_table(file(out, "ticks", r))
        assert table.num_rows == len(v["t"])
        for i, axis in enumerate(("east", "north", "up")):
            assert np.array_equal(table[f"truth_pos_{axis}"].to_numpy(), v["truth_pos"][:, i])
            assert np.array_equal(table[f"ekf_pos_{axis}"].to_numpy(), v["ekf_pos"][:, i])
        assert table.schema.field("truth_pos_east").metadata[b"unit"] == b"m"
        assert table.schema.field("ekf_P_east_north").metadata[b"unit"] == b"m^2"
        assert np.array_equal(table["ekf_P_east_north"].to_numpy(), v["ekf_P"][:, 0, 1])
        cols, _ = read_parquet(file(out, "ticks", r))
        n = len(v["t"])
        want = {**key_columns(n, r, "bauv"), **data_columns(v.ticks)}
        assert list(cols) == list(want)
        for name, col in want.items():
            assert np.array_equal(cols[name].values, col.values), name
            assert (cols[name].unit, cols[name].labels) == (col.unit, col.labels), name
        heading = np.degrees(v["truth_rph"][:, 2])  # degrees, from the run's own radians
        assert np.array_equal(cols["truth_rph_deg"].values[:, 2], heading)
        fixes, _ = read_parquet(file(out, "usbl", r))
        usbl = v.fixes["usbl"]
        want = {**key_columns(len(usbl["t_valid"].values), r, "bauv"), **data_columns(usbl)}
        assert list(fixes) == list(want)
        for name, col in want.items():
            assert np.array_equal(fixes[name].values, col.values, equal_nan=True), name
        az = usbl["azimuth"].values
        assert np.allclose(fixes["azimuth_deg"].values, az * 180 / np.pi, rtol=1e-15, atol=0)
        assert fixes["accepted"].values.dtype == bool


def test_parquet_equals_the_recording(batch):
    out, _ = batch
    table = pq.read_table(file(out, "ticks", 0))
    rec = out / "recording.rrd"
    t, truth = read_time_series(rec, "world/bauv/truth/position", "Points3D:positions")
    _, ekf = read_time_series(rec, "world/bauv/ekf/position", "Points3D:positions")
    assert np.allclose(t, table["t"].to_numpy())
    for name, got in (("truth_pos", truth), ("ekf_pos", ekf)):
        want = np.column_stack([table[f"{name}_{a}"].to_numpy() for a in ("east", "north", "up")])
        # rerun stores positions as float32: agreement to float32 rounding (1e-7 relative)
        assert np.allclose(got, want, rtol=2e-7, atol=1e-5), name


def test_the_batch_is_complete_with_every_runs_data(batch):
    out, _ = batch
    assert json.loads((out / "run.json").read_text())["state"] == "complete"
    assert file(out, "ticks", 1).is_file()


# ---------------------------------------------------------------------------------------------
# the units and the times the files state, against docs/run-data.md and against physics


def test_every_columns_unit_is_the_one_docs_run_data_states(batch):
    """The unit of every column, as declared (TICK_COLUMNS, FIX_COLUMNS) and as written in the
    field metadata of the batch's files, is the unit ``docs/run-data.md`` gives it."""
    doc = table_units()
    ticks = doc["`data/ticks/`"]
    fixes = doc["`data/usbl/` and `data/gps/`"]
    modem = doc["`data/modem/` (`mission/swarm`'s followers)"]
    doa = doc["`data/doa/` (`mission/seed004`)"]
    assert ticks["meas_heading_deg"] == "deg" and fixes["azimuth_deg"] == "deg"  # parse found them
    for name, (unit, _, _) in TICK_COLUMNS.items():
        name, unit = as_written(name, unit)
        assert ticks.get(name) == unit, (name, unit, ticks.get(name))
    assert ticks["ekf_current"] == CURRENT_COLUMN[0]
    for device, table in (("usbl", fixes), ("gps", fixes), ("modem", modem), ("doa", doa)):
        for name, spec in FIX_COLUMNS[device].items():
            name, unit = as_written(name, spec[0])
            assert table.get(name) == unit, (device, name, unit, table.get(name))
    for key in ("run", "vehicle", "variant"):
        assert key in ticks and key in fixes and key in modem and key in doa, key
    out, _ = batch
    for path in sorted((out / "data").glob("*/run-000000-bauv.parquet")):
        table = ticks if path.parent.name == "ticks" else fixes
        for field in pq.read_schema(path):
            group = field.metadata[b"group"].decode()
            assert field.metadata[b"unit"].decode() == table[group], (path.name, field.name)


def test_angles_labelled_deg_are_degrees_of_the_physics(batch):
    """The angle columns hold what their ``deg`` label and ``_deg`` name say: the compass
    heading lies in [0, 360) and within the compass's noise (2 deg, mission preset) of the true
    heading, both read as degrees; every USBL fix's own position is the transceiver plus (range,
    azimuth, elevation) turned into east/north/up with the angles read as degrees clockwise from
    north and up from the horizontal (the same transceiver for every fix, to the transponder's
    lever arm: the fix is of the reference point). No field of any table is in radians."""
    out, _ = batch
    t = pq.read_table(file(out, "ticks", 0))
    assert t.schema.field("meas_heading_deg").metadata[b"unit"] == b"deg"
    meas, true = t["meas_heading_deg"].to_numpy(), t["truth_rph_deg_heading"].to_numpy()
    assert np.all((meas >= 0) & (meas < 360)) and np.all(np.abs(true) <= 360)
    assert meas.max() > 2 * np.pi  # not radians labelled as degrees (mission/short turns east)
    e = (meas - true + 180) % 360 - 180
    assert e.std() == pytest.approx(2.0, rel=5 * np.sqrt(1 / (2 * e.size)))
    u = pq.read_table(file(out, "usbl", 0))
    r, az, el = (u[k].to_numpy() for k in ("range", "azimuth_deg", "elevation_deg"))
    for k in ("azimuth_deg", "elevation_deg"):
        assert u.schema.field(k).metadata[b"unit"] == b"deg"
    az, el = np.radians(az), np.radians(el)
    rel = np.column_stack(
        [r * np.cos(el) * np.sin(az), r * np.cos(el) * np.cos(az), r * np.sin(el)]
    )
    pos = np.column_stack([u[f"position_{a}"].to_numpy() for a in ("east", "north", "up")])
    tx = pos - rel
    assert len(tx) >= 5 and np.abs(tx - np.median(tx, axis=0)).max() < 1.0
    for path in (out / "data").glob("*/*.parquet"):
        for field in pq.read_schema(path):
            unit = field.metadata[b"unit"]
            assert unit != b"rad", (path.name, field.name)
            if unit == b"deg":
                assert field.metadata[b"group"].endswith(b"_deg"), (path.name, field.name)


def test_fixes_arrive_after_their_validity_by_the_devices_latency(batch):
    """Each USBL fix reaches the navigator at the first control tick at or after its time of
    validity plus the acoustic travel time (range / sound speed) and the configured processing
    delay (mission preset: 1 s); times of validity fall on the USBL's period."""
    out, _ = batch
    scn = plan_batch(SHORT, overrides=OVERRIDES).scenario
    cfg, tick = scn.sensors.usbl, scn.timing.control_tick_s
    assert cfg.processing_delay_s > 0
    for r in range(2):
        u = pq.read_table(file(out, "usbl", r))
        tv, ta, rng = (u[k].to_numpy() for k in ("t_valid", "t_arrival", "range"))
        assert len(tv) >= 5 and np.all(tv <= ta)
        due = tv + rng / cfg.sound_speed_m_s + cfg.processing_delay_s
        assert np.all(ta >= due - 1e-3) and np.all(ta < due + tick + 1e-3), ta - due
        k = tv / cfg.period_s
        assert np.allclose(k, np.round(k), atol=1e-9)


def test_attitude_components_are_the_quaternions_roll_pitch_heading(batch):
    """``truth_rph_deg``'s components are what their names say, against the attitude quaternion
    (body FLU to world ENU) turned into a rotation matrix here: pitch (nose up +) is the asin of
    the body x axis's up component, roll (starboard down +) the angle of the body y (port) axis
    above the horizontal about x, heading clockwise from north of the body x axis."""
    out, _ = batch
    t = pq.read_table(file(out, "ticks", 0))
    w, x, y, z = (t[f"truth_quat_wxyz_{c}"].to_numpy() for c in "wxyz")
    # columns of R: the body axes in the world
    bx = np.column_stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    by_up = 2 * (y * z + w * x)
    bz_up = 1 - 2 * (x * x + y * y)
    pitch = np.arcsin(bx[:, 2])
    roll = np.arctan2(by_up, bz_up)
    heading = np.arctan2(bx[:, 0], bx[:, 1]) % (2 * np.pi)
    got = {c: np.radians(t[f"truth_rph_deg_{c}"].to_numpy()) for c in ("roll", "pitch", "heading")}
    assert np.abs(got["roll"] - got["pitch"]).max() > 1e-3  # the two can be told apart
    np.testing.assert_allclose(got["pitch"], pitch, atol=1e-9)
    np.testing.assert_allclose(got["roll"], roll, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (got["heading"] - heading))), 0, atol=1e-9)


def test_missions_own_columns_have_the_units_docs_run_data_states():
    """The per-tick columns mission/correction, mission/swarm's followers, mission/seed004 and
    mission/trn add carry the units ``docs/run-data.md`` gives them in its paragraphs on those
    missions."""
    from tasks.missions.correction import EXTRA_COLUMNS
    from tasks.missions.seed004.parts import EXTRA_COLUMNS as SEED004_COLUMNS
    from tasks.missions.swarm import FOLLOWER_COLUMNS
    from tasks.missions.trn.parts import EXTRA_COLUMNS as TRN_COLUMNS

    for lead, columns in (
        ("`mission/correction` adds", EXTRA_COLUMNS),
        ("`mission/swarm`'s followers", FOLLOWER_COLUMNS),
        ("`mission/seed004` flies one filter", SEED004_COLUMNS),
        ("`mission/trn` flies every navigator", TRN_COLUMNS),
    ):
        doc = prose_units(lead)
        assert len(doc) == len(columns), (lead, sorted(doc))
        for name, spec in columns.items():
            name, unit = as_written(name, spec[1])
            assert unit == doc[name], (lead, name, unit, doc[name])
