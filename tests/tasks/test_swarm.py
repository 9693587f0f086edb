"""``mission/swarm`` (seed 003 on the physical BAUVs): station keeping from one acoustic range
every 5 s, the methods against dead reckoning on the same draws, degradation to DR when ranges
stop, determinism, and several followers sharing the modem channel.

Flights are short (one or two minutes of simulated time, few vehicles): the physics is heavy."""

import json
import math

import numpy as np
import pytest

from tasks.closed_loop.world import build_environment, fly
from tasks.core.recording import read_time_series
from tasks.core.runner import plan_batch, run
from tasks.missions.swarm import LEADER, REFUSAL_CODES, SwarmMission, fly_run

from .run_data_doc import prose_units

NAME = "mission/swarm"


def scenario(*overrides):
    return plan_batch(NAME, overrides=list(overrides)).scenario


@pytest.fixture(scope="module")
def compared():
    """One follower abeam at 10 m for 100 s in the 0.2 m/s cross current; the leader sends its
    true position (as the paper's experiment), so that the follower's own navigation is judged;
    GA1, GA2, the range EKF and DR on the same draws."""
    scn = scenario(
        "timing.max_duration_s=100",
        "followers.sensors.modem.broadcast='truth'",
        'navigation.methods=["ga1","ga2","ekf","dr"]',
    )
    return scn, fly_run(scn, 4, 0)


def _true_station_error(flight, distance_m=10.0, bearing_rad=math.pi / 2):
    """The follower's true distance to its station: the leader's true position plus the offset
    at the relative bearing from the leader's true course (its ground velocity averaged over
    the last 2 s, ten ticks: the hull swings with the tail beat)."""
    lead, v = flight.vehicles[LEADER], flight.vehicles["f1"]
    vel = lead["truth_vel"][:, :2]
    mean = np.column_stack([np.convolve(vel[:, i], np.ones(10) / 10)[: len(vel)] for i in (0, 1)])
    course = np.arctan2(mean[:, 0], mean[:, 1])
    station = lead["truth_pos"][:, :2] + distance_m * np.column_stack(
        [np.sin(course + bearing_rad), np.cos(course + bearing_rad)]
    )
    return v["t"], np.hypot(*(v["truth_pos"][:, :2] - station).T)


@pytest.mark.slow
def test_station_keeping_holds_the_follower_near_its_station(compared):
    """Bound, after the first 30 s: the navigation error (GA2 here, at most ~1.5 m: between two
    ranges the DR error grows by the compass and log errors, +-2 deg x 5 m and +-0.3 m/s over 25
    ticks, a few decimetres, and the current error; each range resets the radial error to
    +-0.125 m), plus the station's swing when the leader changes course (it steers +-15 deg
    between way-points in the cross current: 10 m x sin 15 deg = 2.6 m), which the guidance
    follows with a 1 / 0.08 = 12.5 s time constant, plus the 0.2 / 0.08 = 2.5 m lag of the
    proportional part before the integral takes the current up: 1.5 + 2.6 + 2.5 ~ 6.6 m; the
    mean stays well below (3 m). Dead reckoning on the same draws breaks both bounds."""
    _, res = compared
    assert res.failed is None
    assert res.metrics["ga2"]["f1"]["fixes_accepted"] >= 18  # one every 5 s from t = 5 s
    t, err = _true_station_error(res.flights["ga2"])
    late = t > 30.0
    assert err[late].max() < 6.6 + 1.0, err[late].max()
    assert err[late].mean() < 3.0, err[late].mean()
    assert res.metrics["ga2"]["f1"]["station_mean_error_m"] == pytest.approx(err.mean(), rel=0.05)
    t, err_dr = _true_station_error(res.flights["dr"])
    assert err_dr[late].max() > 7.6 and err_dr[late].mean() > 3.0


def test_ranges_beat_dead_reckoning_on_the_same_draws(compared):
    _, res = compared
    dr = res.metrics["dr"]["f1"]
    # same draws: the pure DR track of each flight starts from the same estimate
    for k in ("ga1", "ga2", "ekf"):
        assert np.array_equal(
            res.flights[k].vehicles["f1"]["dr_pos"][0],
            res.flights["dr"].vehicles["f1"]["dr_pos"][0],
        )
    # DR drifts with the current it cannot see (0.2 m/s: about 10 m by 100 s, 20 at the end)
    assert dr["est_mean_error_m"] > 5.0 and dr["est_max_error_m"] > 15.0
    for k in ("ga2", "ekf"):
        m = res.metrics[k]["f1"]
        assert m["est_mean_error_m"] < 0.4 * dr["est_mean_error_m"], k
        assert m["est_max_error_m"] < 0.5 * dr["est_max_error_m"], k
        assert m["station_mean_error_m"] < 0.5 * dr["station_mean_error_m"], k
        assert m["fixes_refused"] == 0
    # GA1 with the printed Jacobian (A's columns swapped, nav.relative) jumps to the wrong
    # candidate on the circle now and then and does not always beat DR: mean / largest error
    # over 100 s on seeds 0-4, 1.4 / 2.9, 2.2 / 6.4, 0.5 / 2.9, 4.2 / 11.0, 7.3 / 23.6 m against
    # DR's 9.5-11.5 / 18.9-21.2 m (the thin-plate fins of issue 21; seed 4 here). What it does
    # guarantee (eq. 3's constraint): every fix lies on the circle of the measured horizontal
    # range about the leader's stated position, so its error stays within the circle's diameter
    # plus the DR drift of one 5 s interval.
    m = res.metrics["ga1"]["f1"]
    fx = res.flights["ga1"].vehicles["f1"].fixes["modem"]
    ranges = fx["horizontal_range"].values
    on = np.hypot(
        fx["position"].values[:, 0] - fx["centre_east"].values,
        fx["position"].values[:, 1] - fx["centre_north"].values,
    )
    assert m["fixes_refused"] == 0 and m["fixes_accepted"] >= 18
    np.testing.assert_allclose(on, ranges, rtol=0, atol=1e-6)
    assert m["est_max_error_m"] < 2.0 * ranges.max() + 2.0, (m["est_max_error_m"], ranges.max())
    assert dr["fixes_accepted"] == 0


@pytest.mark.slow
def test_missing_ranges_degrade_to_dead_reckoning_with_a_warning():
    scn = scenario(
        "timing.max_duration_s=120",
        "followers.sensors.modem.outages_s=[[22.0, 200.0]]",
        "navigation.dr_warning_s=60",
        "navigation.method=ga1",
    )
    res = fly_run(scn, 1, 0)
    f = res.flights["ga1"].vehicles["f1"]
    assert res.failed is None
    for key, col in f.ticks.items():
        if col.values.dtype.kind == "f":
            assert np.all(np.isfinite(col.values)), key
    fixes = f.fixes["modem"]
    assert fixes["t_valid"].values.max() < 22.0  # nothing after the outage began
    # on dead reckoning once the last range is in: the estimate moves as the compass + log
    # track plus the last current the leader sent (held)
    t = f["t"]
    after = np.flatnonzero(t > fixes["t_arrival"].values.max() + 0.2)
    cur = f["current_est"][after]
    assert np.all(cur == cur[0]) and 0.05 < np.hypot(*cur[0]) < 0.5  # the EKF's, converging
    moved = f["ekf_pos"][after, :2] - f["ekf_pos"][after[0], :2]
    dr = f["dr_pos"][after, :2] - f["dr_pos"][after[0], :2]
    assert np.allclose(moved, dr + (t[after] - t[after[0]])[:, None] * cur[0], atol=1e-6)
    assert any("f1: no accepted range for" in w and "dead reckoning" in w for w in res.warnings)
    assert res.metrics["ga1"]["f1"]["longest_dr_gap_s"] >= 60.0


@pytest.mark.slow
def test_leader_out_of_modem_range_gives_no_range_and_a_warning():
    res = fly_run(
        scenario(
            "timing.max_duration_s=70",
            "followers.sensors.modem.max_range_m=5",
            "followers.sensors.modem.processing_delay_s=0.1",
            "navigation.method=ga1",
        ),
        1,
        0,
    )
    f = res.flights["ga1"].vehicles["f1"]
    assert "modem" not in f.fixes and res.metrics["ga1"]["f1"]["fixes_accepted"] == 0
    # pure DR: no fix moves it (the EKF's prediction and the DR track sum the same increments
    # in a different order: equal to rounding)
    assert np.allclose(f["ekf_pos"], f["dr_pos"], rtol=0, atol=1e-9)
    assert any("no accepted range for 70 s" in w for w in res.warnings), res.warnings


@pytest.mark.slow
def test_flights_are_deterministic():
    scn = scenario("timing.max_duration_s=20", "followers.count=2")
    a = fly(SwarmMission("ekf"), scn, 3, 0)
    b = fly(SwarmMission("ekf"), scn, 3, 0)
    c = fly(SwarmMission("ekf"), scn, 4, 0)
    for name in ("leader", "f1", "f2"):
        for key in ("truth_pos", "ekf_pos", "dr_pos", "meas_heading", "hdop"):
            if key in a.vehicles[name].ticks:
                assert np.array_equal(a.vehicles[name][key], b.vehicles[name][key]), key
    assert not np.array_equal(a.vehicles["f1"]["meas_heading"], c.vehicles["f1"]["meas_heading"])


@pytest.mark.slow
def test_four_followers_share_the_channel_in_slots():
    scn = scenario("timing.max_duration_s=15", "followers.count=4")
    env = build_environment(SwarmMission("ga2"), scn, 0, 0)
    names = ("leader", "f1", "f2", "f3", "f4")
    assert next(iter(env.observation_spec())).startswith("leader/")  # specs before reset
    assert env.action_spec().shape == (5 * len(names),)
    res = fly(SwarmMission("ga2"), scn, 0, 0)
    assert res.failed is None and tuple(res.vehicles) == names
    exchange = 300.0 / 1500.0 + 0.5
    times = sorted(
        (float(t), n) for n in names[1:] for t in res.vehicles[n].fixes["modem"]["t_valid"].values
    )
    assert len(times) == 8  # two periods of four slots (5 s, 10 s + slot offsets)
    assert [n for _, n in times] == ["f1", "f2", "f3", "f4"] * 2
    gaps = np.diff([t for t, _ in times])
    assert np.all(gaps >= exchange - 1e-9)
    offsets = [t - 5.0 for t, _ in times[:4]]
    assert offsets == pytest.approx([0.0, 1.2, 2.4, 3.6])  # (slot * 25) // 4 ticks of 0.2 s


@pytest.mark.slow
def test_report_recording_and_warning_of_a_batch(tmp_path):
    """The batch report: every vehicle, its estimate, a range circle per fix and the HDOP in the
    recording (read back); the warning in the tables and metrics; no NaN in metrics.json."""
    out = tmp_path / "swarm"
    run(
        NAME,
        n_runs=1,
        seed=2,
        out_dir=out,
        progress=False,
        overrides=[
            "timing.max_duration_s=40",
            "followers.count=2",
            "followers.sensors.modem.outages_s=[[12.0, 100.0]]",
            "navigation.dr_warning_s=20",
            'navigation.methods=["ga2","dr"]',
        ],
    )
    text = (out / "metrics.json").read_text()
    assert "NaN" not in text
    m = json.loads(text)
    assert [(r["follower"], r["method"]) for r in m["followers"]] == [
        ("f1", "ga2"),
        ("f1", "dr"),
        ("f2", "ga2"),
        ("f2", "dr"),
    ]
    assert any("f2: no accepted range for" in w for w in m["warnings"])
    assert "Warnings" in (out / "tables.md").read_text()
    rec = out / "recording.rrd"
    data = json.loads(json.dumps(m["runs"][0]["metrics"]["ga2"]))
    assert data["f1"]["fixes_accepted"] == 2  # at 5 and 10 s, then the outage
    for v, m in (("leader", "ekf"), ("f1", "ga2"), ("f2", "ga2")):
        root = f"world/ga2/{v}"
        t, truth = read_time_series(rec, f"{root}/truth/position", "Points3D:positions")
        _, est = read_time_series(rec, f"{root}/{m}/position", "Points3D:positions")
        assert len(t) == 201 and truth.shape == est.shape == (201, 3)
    t, circles = read_time_series(rec, "world/ga2/f1/modem/range", "LineStrips3D:strips")
    assert len(t) == 2  # one circle at each of the two fixes, at its arrival
    for c in np.asarray(circles, dtype=float):
        r = np.hypot(*(c[:, :2] - c[:-1, :2].mean(axis=0)).T)
        assert np.allclose(r, r[0], atol=1e-3) and 7.0 < r[0] < 14.0  # about 10 m abeam
    # the followers' true distance to the station: its mean and max are the metrics' (run.py)
    for v in ("f1", "f2"):
        _, st = read_time_series(rec, f"mission/ga2/{v}/station_error", "Scalars:scalars")
        assert st.mean() == pytest.approx(data[v]["station_mean_error_m"], rel=1e-9)
        assert st.max() == pytest.approx(data[v]["station_max_error_m"], rel=1e-9)
    th, hdop = read_time_series(rec, "mission/ga2/f1/hdop", "Scalars:scalars")
    assert len(th) == 201 and np.all((hdop >= 1.0) & (hdop <= 100.0))
    assert (out / "data" / "modem" / "run-000000-ga2-f1.parquet").is_file()
    # the batch's ticks as one table: every method and vehicle, the followers' own columns
    # null in the leader's rows, the leader's EKF current null in the followers'
    from tasks.core.export import open_dataset

    t = open_dataset(out, "ticks").to_pandas()
    assert set(t["variant"]) == {"ga2", "dr"} and set(t["vehicle"]) == {LEADER, "f1", "f2"}
    lead = t["vehicle"] == LEADER
    assert t.loc[lead, "hdop"].isna().all() and t.loc[~lead, "hdop"].notna().all()
    if "ekf_current_east" in t:
        assert t.loc[~lead, "ekf_current_east"].isna().all()
    assert set(open_dataset(out, "modem")["refusal"].to_pylist()) <= set(REFUSAL_CODES)


def _bauv_run(*args):
    import subprocess
    import sys

    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", *args], capture_output=True, text=True
    )


@pytest.mark.slow
def test_the_shipped_mission_keeps_every_follower_better_than_its_dead_reckoning(tmp_path):
    """`bauv run mission/swarm` as shipped (600 s, the racetrack with its turn): every follower's
    estimate beats its own dead reckoning, no estimate diverges, exit status 0. (With GA1 as
    printed, the default before, the follower's estimate ran away after the leader's turn: mean
    error 106 m against DR's 61 m, largest 415 m, and the run exited 0 without a word.)"""
    out = tmp_path / "swarm"
    res = _bauv_run(
        NAME,
        "--out",
        str(out),
        "--quiet",
        "--set",
        "report.recording=false",
        "--set",
        "report.figures=false",
    )
    assert res.returncode == 0, res.stderr
    m = json.loads((out / "metrics.json").read_text())
    assert m["n_failed"] == 0 and m["n_diverged"] == 0 and m["divergences"] == []
    assert m["followers"]
    for row in m["followers"]:
        v = row["values"]
        assert v["est_mean_error_m"] < 0.25 * v["dr_mean_error_m"], row
        assert v["est_max_error_m"] < v["dr_mean_error_m"], row
        assert v["diverged_runs"] == 0


@pytest.mark.slow
def test_a_diverged_estimate_is_named_and_fails_the_batch(tmp_path):
    """An aided estimate farther from the truth than navigation.divergence_m is named in the
    report and metrics.json, counted in the table, and `bauv run` exits with status 1; dead
    reckoning is reported by its error, never as diverged."""
    out = tmp_path / "swarm"
    res = _bauv_run(
        NAME,
        "--out",
        str(out),
        "--quiet",
        "--seed",
        "2",
        "--set",
        "timing.max_duration_s=30",
        "--set",
        "report.recording=false",
        "--set",
        "report.figures=false",
        "--set",
        'navigation.methods=["ekf","dr"]',
        "--set",
        "navigation.divergence_m=0.3",
    )
    assert res.returncode == 1, (res.returncode, res.stderr)
    assert "diverged" in res.stderr
    m = json.loads((out / "metrics.json").read_text())
    run0 = m["runs"][0]["metrics"]
    for method in ("ekf", "dr"):
        for name in ("leader", "f1"):
            err = run0[method][name]
            assert ("diverged_at_s" in err) == (
                err.get("est_max_error_m", err.get("ekf_max_error_m")) > 0.3
            )
    named = [d for d in m["divergences"] if " dr f1:" in d]
    assert named == []
    expected = sum(
        "diverged_at_s" in run0[meth][name]
        for meth in ("ekf", "dr")
        for name in ("leader", "f1")
        if name == "leader" or meth != "dr"
    )
    assert expected >= 2 and m["n_diverged"] == expected == len(m["divergences"])
    assert all("navigation.divergence_m" in d for d in m["divergences"])
    rows = {r["method"]: r["values"] for r in m["followers"]}
    assert rows["ekf"]["diverged_runs"] == 1 and "diverged_runs" not in rows["dr"]
    assert "diverged" in (out / "tables.md").read_text()


def test_follower_columns_have_the_units_docs_run_data_states(compared):
    """The columns a follower adds carry, as written to the files (angles in degrees,
    ``_deg`` names), the units ``docs/run-data.md`` states for them, and the leader's stated
    course labelled rad inside is a course in radians: in [0, 2 pi), and after the first
    messages within 20 deg on average of the leader's true course over ground."""
    from tasks.core.export import data_columns
    from tasks.missions.swarm import FOLLOWER_COLUMNS

    doc = prose_units("`mission/swarm`'s followers")
    assert doc["leader_course_deg"] == "deg" and doc["hdop"] == "1"  # the parse found them
    _, res = compared
    f, lead = res.flights["ga1"].vehicles["f1"], res.flights["ga1"].vehicles[LEADER]
    written = data_columns({name: f.ticks[name] for name in FOLLOWER_COLUMNS})
    assert len(written) == len(FOLLOWER_COLUMNS)
    for name, col in written.items():
        assert col.unit == doc[name], (name, col.unit, doc[name])
    course = f["leader_course"]
    assert np.all((course >= 0) & (course < 2 * np.pi))
    v = lead["truth_vel"][:, :2]
    d = np.angle(np.exp(1j * (course - np.arctan2(v[:, 0], v[:, 1]))))
    assert np.degrees(np.abs(d[f["t"] > 10]).mean()) < 20


def test_ranges_arrive_after_their_validity_by_the_modems_latency(compared):
    """Each range reaches the follower's navigation at the first control tick at or after its
    time of validity plus the acoustic travel time (range / sound speed) and the modem's
    processing delay."""
    scn, res = compared
    modem, tick = scn.followers.sensors.modem, scn.timing.control_tick_s
    fx = res.flights["ga1"].vehicles["f1"].fixes["modem"]
    tv, ta, rng = (fx[k].values for k in ("t_valid", "t_arrival", "range"))
    assert len(tv) >= 10 and modem.processing_delay_s > 0
    due = tv + rng / modem.sound_speed_m_s + modem.processing_delay_s
    assert np.all(ta >= due - 1e-3) and np.all(ta < due + tick + 1e-3), ta - due


def test_modem_table_centre_is_the_leaders_position(compared):
    """The modem table's ``centre_east``, ``centre_north`` are the east and north of the range
    circle's centre: with the leader sending its true position, within 1 m of the leader's true
    position when the range arrives (the transducers' lever arms are decimetres), on a path
    whose east and north differ by tens of metres (swapped columns would be far off)."""
    _, res = compared
    lead, fx = res.flights["ga1"].vehicles[LEADER], res.flights["ga1"].vehicles["f1"].fixes["modem"]
    ticks = {round(t, 6): i for i, t in enumerate(lead["t"])}
    truth = lead["truth_pos"][[ticks[round(t, 6)] for t in fx["t_arrival"].values], :2]
    centre = np.column_stack([fx["centre_east"].values, fx["centre_north"].values])
    assert len(centre) >= 10 and np.abs(truth[:, 1] - truth[:, 0]).mean() > 10.0
    assert np.abs(centre - truth).max() < 1.0


def test_the_modem_tables_refusal_labels_are_the_codes_names():
    """The labels the modem table's ``refusal`` is written with name the codes the followers
    record (``REFUSAL_CODES``: name -> code), in code order."""
    from tasks.closed_loop.result import ENUM_LABELS

    assert {name: i for i, name in enumerate(ENUM_LABELS["refusal"])} == REFUSAL_CODES
