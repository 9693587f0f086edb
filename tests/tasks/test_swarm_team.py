"""``mission/swarm`` with more vehicles (issue 24): followers beyond the four default stations on
generated stations, sharing the modem's period in six slots; the scenario's refusals.

Flights are short (15 s of simulated time): the physics is heavy."""

import math

import numpy as np
import pytest

from bauv_sim.errors import ConfigError
from tasks.closed_loop.world import fly
from tasks.core.runner import plan_batch
from tasks.missions.swarm import LEADER, SwarmMission, station_offsets

NAME = "mission/swarm"


def scenario(*overrides):
    return plan_batch(NAME, overrides=list(overrides)).scenario


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
