"""``mission/swarm`` with more vehicles (issue 24): followers beyond the four default stations on
generated stations, sharing the modem's period in six slots; the scenario's refusals.

Flights are short (15 s of simulated time): the physics is heavy."""

import math

import numpy as np
import pytest

from bauv_sim.errors import ConfigError
from tasks.closed_loop.world import fly
from tasks.core.runner import plan_batch
from tasks.missions.swarm import LEADER, SwarmMission, fly_run, station_offsets

NAME = "mission/swarm"


def scenario(*overrides):
    return plan_batch(NAME, overrides=list(overrides)).scenario


@pytest.mark.slow
def test_six_followers_fly_on_generated_stations_in_six_slots():
    """f5 and f6 get the stations after the four defaults (20 m abeam to port, 20 m astern): they
    start there (the leader heads north: port is west, astern is south), and the six followers
    are ranged in six slots of the 5 s period, (slot * 25) // 6 ticks of 0.2 s apart."""
    scn = scenario("timing.max_duration_s=15", "followers.count=6")
    st = [(s.relative_bearing_deg, s.distance_m) for s in station_offsets(scn)]
    assert st == [(90, 10), (270, 10), (180, 10), (90, 20), (270, 20), (180, 20)]
    res = fly(SwarmMission("ekf"), scn, 0, 0)
    names = (LEADER, "f1", "f2", "f3", "f4", "f5", "f6")
    assert res.failed is None and tuple(res.vehicles) == names
    lead0 = res.vehicles[LEADER]["truth_pos"][0, :2]
    assert scn.leader.start.heading_deg == 0.0
    expect = {"f5": (-20.0, 0.0), "f6": (0.0, -20.0), "f1": (10.0, 0.0)}
    for name, (bearing, dist) in zip(names[1:], st, strict=True):  # the station it steers to
        out = res.vehicles[name].outcome
        assert (out["relative_bearing_deg"], out["distance_m"]) == (bearing, dist), name
    for name, off in expect.items():
        rel = res.vehicles[name]["truth_pos"][0, :2] - lead0
        # start scatter: leader 1 m, follower 0.5 m per axis (4 sigma)
        assert np.all(np.abs(rel - off) < 4 * math.hypot(1.0, 0.5)), (name, rel)
    times = sorted(
        (float(t), n) for n in names[1:] for t in res.vehicles[n].fixes["modem"]["t_valid"].values
    )
    assert [n for _, n in times] == list(names[1:]) * 2
    offsets = [t - 5.0 for t, _ in times[:6]]
    assert offsets == pytest.approx([0.2 * ((s * 25) // 6) for s in range(6)])
    for name in names[1:]:
        v = res.vehicles[name]
        assert np.all(np.isfinite(v["ekf_pos"])) and len(v["t"]) == 76


def test_seven_followers_need_a_longer_modem_period():
    """Seven slots of 5 s are 0.6 s apart, shorter than one exchange (0.7 s): refused, naming
    the field; with a 6 s period they fit."""
    with pytest.raises(ConfigError, match=r"followers\.sensors\.modem\.period_s = 5"):
        scenario("followers.count=7")
    scn = scenario("followers.count=7", "followers.sensors.modem.period_s=6")
    assert len(station_offsets(scn)) == 7


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        (["followers.count=13"], r"followers\.count"),
        (
            [
                "followers.count=2",
                "followers.stations=[{relative_bearing_deg=90,distance_m=10},"
                "{relative_bearing_deg=91,distance_m=10}]",
            ],
            r"f2's station \(given\) is 0\.17 m from f1's",
        ),
        (
            [
                "followers.count=3",
                "followers.stations=[{relative_bearing_deg=180,distance_m=10},"
                "{relative_bearing_deg=90,distance_m=30}]",
            ],
            r"f3's station \(generated\) is 0\.00 m from f1's",
        ),
    ],
)
def test_stations_too_close_or_too_many_followers_are_refused(overrides, match):
    with pytest.raises(ConfigError, match=match):
        scenario(*overrides)


def test_the_memory_estimate_counts_every_vehicle_of_every_flight():
    """A run holds (1 + followers) vehicles' columns per method flown: the per-tick terms of the
    estimate scale with both (the block file's ceiling follows the estimate)."""
    one = scenario()
    many = scenario("followers.count=6", 'navigation.methods=["ekf","ga2"]')
    plan = plan_batch(NAME)
    a, b = plan.experiment.memory(one, 1), plan.experiment.memory(many, 1)
    assert b[0].bytes == pytest.approx(a[0].bytes * 14 / 2)
    assert b[1].bytes == pytest.approx(a[1].bytes * 14 / 2)
    assert b[2:] == a[2:]


# ---------------------------------------------------------------------------------------------
# The acoustic network (issue 24)

C_NOM = 1500.0
F1_OFFSET_S = 0.002


@pytest.fixture(scope="module")
def networked():
    """Three followers and the leader on the acoustic network for 26 s (ranges from 5 s, one
    transmission per vehicle every 5 s); f1's clock runs 2 ms ahead of the others'."""
    scn = scenario(
        "timing.max_duration_s=26",
        "followers.count=3",
        "followers.network.enabled=true",
        f"followers.network.clocks={{f1={{offset_s={F1_OFFSET_S}}}}}",
        "navigation.method=ekf",
    )
    return scn, fly_run(scn, 5, 0)


MODEM_SITE_M = np.array([0.36, 0.0, 0.166])
"""The modem transducer in the hull model (models/bauv/bauv.xml, site ``modem``), body FLU, m."""


def _at(v, t_s):
    """A vehicle's true transducer position (east, north, up) at time ``t_s``: its reference
    point linear between ticks, the lever arm rotated by the attitude of the nearest tick."""
    from bauv_sim.frames import R_from_quat_wxyz

    p = np.array([np.interp(t_s, v["t"], v["truth_pos"][:, a]) for a in range(3)])
    q = int(np.argmin(np.abs(v["t"] - t_s)))
    return p + R_from_quat_wxyz(v["truth_quat_wxyz"][q]) @ MODEM_SITE_M


@pytest.mark.slow
def test_every_vehicle_hears_every_other_with_its_clock_bias(networked):
    """Each vehicle receives every other vehicle's transmissions (the cycles from 5 s); a range
    is the true distance between the transmitter at its transmission and the receiver at the
    reception plus c x (receiver's offset - sender's offset): +3 m for what f1 hears, -3 m for
    what f1 sends, 0 otherwise (within 0.15 m: the device moves the sender from the tick before
    its transmission with that tick's velocity, the hull swinging with the tail beat, and this
    test interpolates between ticks)."""
    _, res = networked
    flight = res.flights["ekf"]
    team = ("leader", "f1", "f2", "f3")
    offset = {"leader": 0.0, "f1": F1_OFFSET_S, "f2": 0.0, "f3": 0.0}
    for i, name in enumerate(team):
        tab = flight.vehicles[name].fixes["network"]
        senders = tab["sender"].values
        others = [j for j in range(4) if j != i]
        assert set(senders.tolist()) == set(others), name
        assert all(4 <= (senders == j).sum() <= 5 for j in others), name  # cycles at 5 .. 25 s
        for row, j in enumerate(senders):
            sender = team[j]
            t_tx = tab["tx_local"].values[row] - offset[sender]
            p_tx = _at(flight.vehicles[sender], t_tx)
            p_rx = _at(flight.vehicles[name], tab["t_valid"].values[row])
            bias = C_NOM * (offset[name] - offset[sender])
            true = float(np.linalg.norm(p_tx - p_rx))
            assert tab["range"].values[row] - true == pytest.approx(bias, abs=0.15), (name, j)
        assert np.all(tab["t_arrival"].values - tab["t_valid"].values == pytest.approx(0.5))


def test_every_team_methods_estimate_is_in_the_vehicles_ticks(networked):
    """Each team method's estimate of every vehicle is kept in its per-tick columns (the run
    data: ``team_<method>_pos``, ``team_<method>_P``). Truth: the team metrics, computed from the
    method's tracks before they were stored, give the same mean and final horizontal errors
    against the true track (from the second sample, as :func:`nav.cooperative.team_metrics`)."""
    from tasks.missions.swarm.team import TEAM_METHODS, track_column

    _, res = networked
    flight = res.flights["ekf"]
    for method in TEAM_METHODS:
        for name in ("leader", "f1", "f2", "f3"):
            v = flight.vehicles[name]
            col = track_column(method)
            pos, cov = v[col], v[col[: -len("pos")] + "P"]
            k = int(np.isfinite(pos[:, 0]).sum())
            assert k > 100 and np.isfinite(pos[:k]).all() and np.isfinite(cov[:k]).all()
            np.testing.assert_array_equal(cov[:k], np.swapaxes(cov[:k], 1, 2))
            e = np.hypot(*(pos[1:k] - v["truth_pos"][1:k, :2]).T)
            m = res.team["ekf"][method][name]
            assert e.mean() == pytest.approx(m["mean_error_m"], rel=1e-12), (method, name)
            assert e[-1] == pytest.approx(m["final_error_m"], rel=1e-12), (method, name)


def test_the_team_record_is_the_flights_measurements(networked):
    """The record built after the flight holds every range each vehicle received (sender,
    receiver, stamps, range), the leader's USBL fixes, and the dead-reckoned steps the
    followers' EKF predicted with: between two ticks without a range its estimate moves by the
    record's step exactly."""
    from tasks.missions.swarm.team import team_record

    scn, res = networked
    flight = res.flights["ekf"]
    rec = team_record(scn, flight)
    team = ("leader", "f1", "f2", "f3")
    for i, name in enumerate(team):
        tab = flight.vehicles[name].fixes["network"]
        mine = rec.range_receiver == i
        assert mine.sum() == len(tab["range"].values)
        np.testing.assert_array_equal(rec.range_m[0, mine], tab["range"].values)
        np.testing.assert_array_equal(rec.range_sender[mine], tab["sender"].values)
        np.testing.assert_array_equal(rec.range_rx_local_s[0, mine], tab["rx_local"].values)
        t = rec.t_s
        assert np.all(t[rec.range_rx_tick[mine]] >= tab["rx_local"].values - 1e-9)
        tx = rec.range_tx_tick[mine]  # the sample at or before the scheduled transmission
        assert np.all(t[tx] <= tab["tx_local"].values + 1e-9)
        assert np.all(t[tx + 1] > tab["tx_local"].values + 1e-9)
    usbl = flight.vehicles["leader"].fixes["usbl"]
    np.testing.assert_array_equal(rec.fix_m[0], usbl["position"].values[:, :2])
    for i, name in enumerate(team[1:], start=1):
        v = flight.vehicles[name]
        moved = np.diff(v["ekf_pos"][:, :2], axis=0)
        quiet = ~v["fix_event"][1:].astype(bool)
        assert quiet.sum() > 100
        np.testing.assert_allclose(moved[quiet], rec.dr_step_m[0, i][quiet], atol=1e-9)
        # over ground = the pure compass + log track through water + the current it held
        through_water = np.diff(v["dr_pos"][:, :2], axis=0)
        dt = np.diff(v["t"])[:, None]
        held = v["current_est"][:-1]
        assert np.abs(held).max() > 0.05  # the leader's current reached it
        np.testing.assert_allclose(rec.dr_step_m[0, i], through_water + dt * held, atol=1e-9)


def test_usbl_fix_covariance_is_the_noise_through_the_inverse_geometry():
    """The covariance the team record gives the leader's USBL fixes
    (:meth:`nav.models.UsblMeasurement.fix_covariance`, horizontal block) against the covariance
    of positions inverted from measurements with the stated noise, by finite differences of the
    inversion (range r along (azimuth, elevation))."""
    from nav.models import UsblMeasurement

    z = np.array([[80.0, 0.7, -0.2], [30.0, 4.0, -0.6]])
    sig = (0.2, np.radians(1.0), np.radians(1.0))

    def invert(m):
        r, az, el = m
        return np.array([r * np.cos(el) * np.sin(az), r * np.cos(el) * np.cos(az)])

    covs = UsblMeasurement(np.zeros(3), *sig, min_horizontal_m=0.0).fix_covariance(z)[:, :2, :2]
    for row, cov in zip(z, covs, strict=True):
        J = np.column_stack([(invert(row + h) - invert(row - h)) / 2e-6 for h in 1e-6 * np.eye(3)])
        np.testing.assert_allclose(cov, J @ np.diag(np.square(sig)) @ J.T, rtol=1e-6)


@pytest.mark.slow
def test_the_network_changes_nothing_when_off():
    """Off (the default), the followers keep the modem (no network device, no network table,
    no team comparison, no ``team`` key in metrics.json; the golden mission_swarm is the check
    bit for bit)."""
    scn = scenario("timing.max_duration_s=12")
    res = fly_run(scn, 1, 0)
    assert res.team == {}
    for v in res.flights["ekf"].vehicles.values():
        assert "network" not in v.fixes and "network" not in v.outcome


@pytest.mark.slow
def test_decentralised_flies_on_the_network_and_the_batch_reports_the_team(tmp_path):
    """A batch on the network with the decentralised method: every follower fuses the ranges
    from every other vehicle and, relayed back in the receivers' broadcasts, the ranges it sent
    (the clock offsets then stay near their true 0 instead of wandering by milliseconds); the
    report has the team table and metrics.json the team rows of every method and vehicle
    (NaN-free), and each vehicle's network table is exported."""
    import json

    from tasks.core.runner import run

    out = tmp_path / "swarm"
    run(
        "mission/swarm",
        n_runs=1,
        seed=3,
        out_dir=out,
        progress=False,
        overrides=[
            "timing.max_duration_s=30",
            "followers.count=2",
            "followers.network.enabled=true",
            "navigation.method=decentralised",
            "report.recording=false",
            "report.figures=false",
        ],
    )
    text = (out / "metrics.json").read_text()
    assert "NaN" not in text
    m = json.loads(text)
    assert m["n_failed"] == 0
    rows = {(r["flight"], r["method"], r["vehicle"]): r["values"] for r in m["team"]}
    methods = ("ga2", "leader-ekf", "decentralised", "central")
    assert set(rows) == {
        ("decentralised", meth, v) for meth in methods for v in ("leader", "f1", "f2")
    }
    for (_, meth, v), values in rows.items():
        assert values["mean_error_m"] > 0 and values["nees"] > 0 and values["nees_high"] > 2
        assert ("clock_rmse_ms" in values) == (meth in ("decentralised", "central"))
        if v != "leader":
            assert values["ranges_used"] >= (8 if meth in ("decentralised", "central") else 4)
    assert "Team navigation" in (out / "tables.md").read_text()
    assert (
        m["runs"][0]["team"]["decentralised"]["central"]["f1"]
        == rows[("decentralised", "central", "f1")]
    )
    assert (out / "data" / "network" / "run-000000-decentralised-f2.parquet").is_file()
    for f in ("f1", "f2"):
        got = m["runs"][0]["metrics"]["decentralised"][f]
        assert got["fixes_accepted"] >= 8  # 2 senders x 5 cycles, the last may be cut
    # the relays and the clock estimate, from the flight itself
    from tasks.missions.swarm import fly_run

    scn = plan_batch(
        NAME,
        overrides=[
            "timing.max_duration_s=30",
            "followers.count=2",
            "followers.network.enabled=true",
            "navigation.method=decentralised",
        ],
    ).scenario
    res = fly_run(scn, 3, 0)
    for f in ("f1", "f2"):
        outcome = res.flights["decentralised"].vehicles[f].outcome
        assert outcome["fix_counts"].get("relayed accepted", 0) >= 6, outcome["fix_counts"]
        assert abs(outcome["clock_offset_s"]) < 2e-4  # true offset 0 (prior sigma 1 ms)


@pytest.mark.slow
def test_the_team_methods_on_a_decentralised_flight_rank_as_cooperation_predicts():
    """Issue 24's acceptance 4 on the physical vehicles: three followers fly 400 s on the
    network with the decentralised method; on that flight's measurements, averaged over the
    followers, the centralised EKF's error is at most the decentralised filters', which is at
    most seed 003's range EKF on the leader's ranges (measured, seed 0: 1.10, 1.45 and 1.61 m;
    per follower central <= decentralised everywhere, but f1's leader-only EKF, 1.23 m, beats
    its decentralised filter, 1.38 m), and the decentralised filters are not over-confident
    (NEES 1.3-2.6 against the band's upper end 7.38), while GA2's stated covariance is
    (NEES in the hundreds)."""
    scn = scenario(
        "timing.max_duration_s=400",
        "followers.count=3",
        "followers.network.enabled=true",
        "navigation.method=decentralised",
    )
    res = fly_run(scn, 0, 0)
    assert res.failed is None
    team = res.team["decentralised"]
    followers = ("f1", "f2", "f3")

    def mean(method):
        return np.mean([team[method][f]["mean_error_m"] for f in followers])

    assert mean("central") <= mean("decentralised") <= mean("leader-ekf")
    for f in followers:
        assert team["central"][f]["mean_error_m"] <= team["decentralised"][f]["mean_error_m"]
        dec = team["decentralised"][f]
        assert dec["nees"] <= dec["nees_high"] and dec["consistent"] == 1.0
        assert team["ga2"][f]["nees"] > team["ga2"][f]["nees_high"]
