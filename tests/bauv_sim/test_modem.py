"""The acoustic modem (seed 003's HS modem): range errors against their distributions, latency,
limits, TDMA slots, determinism, and the online device between two vehicles of one scene."""

import dataclasses
import itertools
import math

import numpy as np
import pytest
from scipy import stats

from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.errors import ConfigError
from bauv_sim.sensors.modem import (
    Modem,
    ModemConfig,
    check_slots,
    slot_indices,
)
from bauv_sim.sensors.online import Broadcast, Peer
from bauv_sim.sensors.rig import SensorRig
from bauv_sim.truth import Truth

N, K = 200, 500  # 100,000 ranges per statistic


def _measure(cfg, r=10.0, runs=N, k=K, name="f/modem", seed=3):
    m = Modem(cfg, seed, tuple(range(runs)), name)
    return m.measure(np.full((runs, k), r), np.arange(k, dtype=float))


def test_seed003_default_error_is_uniform_on_a_tenth_plus_bias():
    v, ok, _ = _measure(ModemConfig())
    assert ok.all()
    e = (v - 10.0).ravel()
    n = e.size
    # bounded by the half-width 0.1 m about the 0.025 m bias, and reaching it
    assert np.abs(e - 0.025).max() <= 0.1 and np.abs(e - 0.025).max() > 0.0999
    # mean: the bias, within 4 standard errors of the uniform (sd 0.1 / sqrt 3)
    assert abs(e.mean() - 0.025) < 4 * (0.1 / math.sqrt(3)) / math.sqrt(n)
    # variance a^2 / 3; the sample variance of a uniform has variance (mu4 - s^4) / n,
    # mu4 = a^4 / 5, s^4 = a^4 / 9
    a = 0.1
    sd_var = math.sqrt((a**4 / 5 - a**4 / 9) / n)
    assert abs(e.var() - a**2 / 3) < 4 * sd_var
    # shape: chi-square goodness of fit of 20 equal bins, at the 0.999 quantile of 19 dof
    counts, _ = np.histogram(e - 0.025, bins=20, range=(-0.1, 0.1))
    chi = ((counts - n / 20) ** 2 / (n / 20)).sum()
    assert chi < stats.chi2.ppf(0.999, 19)


def test_gaussian_range_error_variance_in_its_chi_square_band():
    cfg = ModemConfig(range={"sigma_m": 0.05, "bias_m": 0.0})
    v, _, _ = _measure(cfg)
    e = (v - 10.0).ravel()
    n = e.size
    q = (n - 1) * e.var(ddof=1) / 0.05**2
    assert stats.chi2.ppf(0.0005, n - 1) < q < stats.chi2.ppf(0.9995, n - 1)


def test_latency_is_travel_time_plus_processing():
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0}, processing_delay_s=0.7)
    r = np.array([[5.0, 40.0, 250.0]])
    t = np.array([10.0, 15.0, 20.0])
    v, ok, t_arr = Modem(cfg, 0, (0,)).measure(r, t)
    assert ok.all() and np.allclose(v, r)
    assert np.allclose(t_arr, t + r / 1500.0 + 0.7)


def test_maximum_range_zero_range_outage_and_dropout():
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0}, max_range_m=100.0, min_range_m=0.5)
    r = np.array([[10.0, 99.9, 100.1, 0.0, 0.3, 1e9]])
    _, ok, _ = Modem(cfg, 0, (0,)).measure(r, np.arange(6.0))
    assert ok[0].tolist() == [True, True, False, False, False, False]
    # a zero range is no range (two transducers at one point)
    exact = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0})
    _, ok, _ = Modem(exact, 0, (0,)).measure(np.array([[0.0, 1e-6]]), np.arange(2.0))
    assert ok[0].tolist() == [False, True]
    # a bias cannot make a zero range a range
    cfg0 = ModemConfig(range={"sigma_m": 0.0, "bias_m": -0.05})
    _, ok, _ = Modem(cfg0, 0, (0,)).measure(np.array([[0.0, 0.04, 0.2]]), np.arange(3.0))
    assert ok[0].tolist() == [False, False, True]
    # outage windows [start, end)
    cfg = ModemConfig(outages_s=((10.0, 20.0),))
    _, ok, _ = Modem(cfg, 0, (0,)).measure(np.full((1, 30), 10.0), np.arange(30.0))
    assert ok[0].tolist() == [not (10 <= t < 20) for t in range(30)]
    # dropouts: the rate within 4 binomial standard deviations
    p = 0.3
    _, ok, _ = _measure(ModemConfig(dropout_probability=p))
    n = ok.size
    assert abs((~ok).mean() - p) < 4 * math.sqrt(p * (1 - p) / n)
    with pytest.raises(ValueError, match="outages_s"):
        ModemConfig(outages_s=((5.0, 2.0),))


def test_dropouts_do_not_change_the_range_errors():
    a, _, _ = _measure(ModemConfig(), runs=3, k=50)
    b, _, _ = _measure(ModemConfig(dropout_probability=0.5), runs=3, k=50)
    assert np.array_equal(a, b)


def test_slots_never_collide():
    tick = 0.2
    cfg = ModemConfig()  # 5 s, 300 m, 0.5 s: an exchange takes 0.7 s
    for slots in (1, 2, 3, 4):
        every = check_slots(cfg, tick, slots)
        assert every == 25
        intervals = []
        for s in range(slots):
            idx = slot_indices(2000, every, s, slots)
            assert np.all(np.diff(idx) == every)
            assert idx[0] == every + (s * every) // slots
            intervals += [(i * tick, i * tick + cfg.exchange_s, s) for i in idx]
        intervals.sort()
        for (a0, a1, sa), (b0, _, sb) in itertools.pairwise(intervals):
            assert sa != sb or slots == 1
            assert b0 >= a1 - 1e-9, (slots, a0, b0)
    # slot spacing shorter than one exchange is refused, naming the field
    with pytest.raises(ConfigError, match=r"sensors.modem.period_s = 2"):
        check_slots(ModemConfig(period_s=2.0), tick, 4)
    with pytest.raises(ConfigError, match="whole multiple"):
        check_slots(ModemConfig(period_s=5.1), tick, 1)
    with pytest.raises(ValueError, match="slot"):
        slot_indices(100, 25, 4, 4)


def test_same_seed_same_ranges_and_each_link_its_own_stream():
    a, _, _ = _measure(ModemConfig(), runs=4, k=20)
    b, _, _ = _measure(ModemConfig(), runs=4, k=20)
    assert np.array_equal(a, b)
    c, _, _ = _measure(ModemConfig(), runs=4, k=20, name="g/modem")
    assert not np.array_equal(a, c)
    # run 2 draws the same numbers alone as in a batch
    alone = Modem(ModemConfig(), 3, (2,), "f/modem").measure(
        np.full((1, 20), 10.0), np.arange(20.0)
    )[0]
    assert np.array_equal(alone[0], a[2])


def _truth(pos):
    n, T = pos.shape[:2]
    z = np.zeros((n, T, 3))
    return Truth(np.arange(T) * 0.2, pos, z, z, np.zeros((n, T)), np.zeros((n, T, 2)), z)


def test_batched_ranges_between_two_kinematic_tracks():
    T = 30
    lead = np.zeros((1, T, 3))
    lead[0, :, 1] = np.arange(T) * 0.2  # north at 1 m/s
    fol = lead + [10.0, 0.0, -1.0]
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0}, transducer_body_m=(0.5, 0.0, 0.0))
    idx = slot_indices(T, 5, 1, 2)
    s = Modem(cfg, 0, (0,)).sample(_truth(lead), _truth(fol), idx)
    # heading 0 (north): the transducer 0.5 m ahead of both reference points; range unchanged
    assert np.allclose(s.values, math.sqrt(101.0))
    assert np.allclose(s.t_s, idx * 0.2)
    assert s.produced.all()


@pytest.fixture(scope="module")
def pair():
    scene = SceneConfig(
        vehicles=(
            VehicleSpec(name="leader", east_m=0.0, north_m=0.0, heading_deg=30.0),
            VehicleSpec(name="f1", east_m=8.0, north_m=-6.0, heading_deg=30.0, depth_m=4.0),
        )
    )
    return build_physics(scene, control_tick_s=0.2)


def _rig(physics, cfg, **extra):
    return SensorRig({"modem": cfg}, physics, "f1", 5, 0, "f1", extra={"modem": extra})


def _at(vt, k):
    """A vehicle's (unmoving) truth stamped with the time of tick k (0.2 s ticks)."""
    return dataclasses.replace(vt, t_s=0.2 * k)


def test_online_device_ranges_between_the_model_sites_in_its_slot(pair):
    cfg = ModemConfig(range={"sigma_m": 0.0, "bias_m": 0.0})
    rig = _rig(pair, cfg, sender="leader", slot=1, slots=2)
    site = {v: pair.site_position_world("modem", v) for v in ("leader", "f1")}
    true_r = float(np.linalg.norm(site["leader"] - site["f1"]))
    bc = Broadcast("leader", 0.0, np.zeros(3), np.ones(3), np.array([0.5, 0.8]), np.eye(2))
    lead_truth, me = pair.truth("leader"), pair.truth("f1")
    got = []
    for k in range(1, 80):
        tick = rig.sense(k, _at(me, k), {}, peers={"leader": Peer(_at(lead_truth, k), bc)})
        got += [(k, m) for m in tick.arrived]
    # slot 1 of 2 with a 25-tick period: ticks 25 + 12 = 37, 62; the truth does not move here,
    # so each range arrives at the first tick after t_valid + travel + 0.5 s
    ks = [m.t_valid_s for _, m in got]
    assert np.allclose(ks, [37 * 0.2, 62 * 0.2])
    for k, m in got:
        assert m.value[0] == pytest.approx(true_r, abs=1e-12)
        assert m.t_arrival_s == pytest.approx(m.t_valid_s + true_r / 1500 + 0.5)
        assert k * 0.2 >= m.t_arrival_s - 1e-9 > (k - 1) * 0.2
        assert m.payload is bc
    assert rig.lever_arms_body_m["modem"] == pytest.approx((0.36, 0.0, 0.166), abs=1e-9)


def test_online_device_sends_the_truth_when_asked_and_needs_a_sender(pair):
    cfg = ModemConfig(broadcast="truth")
    rig = _rig(pair, cfg)
    lead = pair.truth("leader")
    tick = None
    for k in range(1, 30):
        tick = rig.sense(k, _at(pair.truth("f1"), k), {}, peers={"leader": Peer(lead, None)})
        if tick.arrived:
            break
    m = tick.arrived[0]
    assert np.array_equal(m.payload.position_world_m, lead.position_world_m)
    assert m.payload.covariance_m2 is None
    assert np.allclose(m.payload.transducer_world_m, pair.site_position_world("modem", "leader"))
    # an estimate is needed when the estimate is to be sent: nothing without one
    rig = _rig(pair, ModemConfig())
    for k in range(1, 30):
        assert not rig.sense(k, _at(pair.truth("f1"), k), {}, peers={"leader": Peer(lead)}).arrived
    with pytest.raises(ConfigError, match="sender 'boss' is not another vehicle"):
        _rig(pair, cfg, sender="boss")
    with pytest.raises(ConfigError, match="slot 2 not in"):
        _rig(pair, cfg, slot=2, slots=2)
