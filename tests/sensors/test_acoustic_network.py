"""The acoustic network against closed forms worked out here: the one-way range's clock bias
(acceptance 2, first half), the reception time of a moving receiver, two-way ranging's
cancellation of the offsets, collisions, half-duplex, and packet loss against range by the sonar
equation (acceptance 3), with Monte Carlo bands of the right sample size."""

import math

import numpy as np
import pytest
from scipy import stats

from bauv_sim.acoustics.clock import ClockConfig
from bauv_sim.acoustics.network import (
    LOST_COLLISION,
    LOST_HALF_DUPLEX,
    LOST_OK,
    LOST_RANGE,
    LOST_SONAR,
    AcousticNetwork,
    AcousticNetworkConfig,
)
from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError
from nav.acoustics import Isovelocity

C = 1500.0
NAMES = ("leader", "f1", "f2")
T_GRID = np.arange(0.0, 120.0001, 0.5)

# straight lines at constant velocity: p(t) = a + u t (linear interpolation on the grid is exact)
START = np.array([[0.0, 0.0, -5.0], [300.0, 100.0, -20.0], [-200.0, 400.0, -40.0]])
VEL = np.array([[1.5, 0.2, 0.0], [-0.8, 1.1, 0.0], [0.6, -1.4, 0.05]])


def line_positions(start=START, vel=VEL, t=T_GRID):
    """(v, 1, k, 3) positions of vehicles on straight lines."""
    return (start[:, None, :] + vel[:, None, :] * t[None, :, None])[:, None]


def test_owtt_range_is_true_range_plus_sound_speed_times_clock_offsets():
    """Acceptance 2 (first half): noise off, isovelocity at c_nom, clocks with offset and drift:
    range - |p_j(t_tx) - p_i(t_rx)| = c (offset_i(t_rx) - offset_j(t_tx)), exactly."""
    clocks = {
        "leader": ClockConfig(offset_s=0.0, drift_ppm=0.0),
        "f1": ClockConfig(offset_s=0.004, drift_ppm=3.0),
        "f2": ClockConfig(offset_s=-0.0025, drift_ppm=-2.0),
    }
    cfg = AcousticNetworkConfig(clocks=clocks, period_s=12.0, slot_s=4.0)
    r = AcousticNetwork(cfg, NAMES, 5, (0,)).exchange(T_GRID, line_positions())
    assert r.produced.all() and r.sender.size >= 3 * 2 * 8
    off0 = np.array([clocks[v].offset_s for v in NAMES])
    drift = np.array([clocks[v].drift_ppm for v in NAMES]) * 1e-6
    j, i = r.sender, r.receiver
    # the test's own clocks: the transmit instant is where the sender's clock reads T
    t_tx = (r.tx_local_s[0] - off0[j]) / (1 + drift[j])
    np.testing.assert_allclose(r.t_tx_s[0], t_tx, rtol=0, atol=1e-12)
    t_rx = r.t_rx_s[0]
    # the reception instant is the travel's: |p_j(t_tx) - p_i(t_rx)| = c (t_rx - t_tx)
    p_tx = START[j] + VEL[j] * t_tx[:, None]
    p_rx = START[i] + VEL[i] * t_rx[:, None]
    true = np.linalg.norm(p_tx - p_rx, axis=1)
    np.testing.assert_allclose(true, C * (t_rx - t_tx), rtol=1e-12)
    np.testing.assert_allclose(r.true_range_m[0], true, rtol=1e-12)
    bias = C * ((off0[i] + drift[i] * t_rx) - (off0[j] + drift[j] * t_tx))
    np.testing.assert_allclose(r.range_m[0] - true, bias, rtol=0, atol=1e-8)
    assert np.abs(bias).max() > 5.0  # the offsets matter: metres of bias


def test_reception_time_of_a_receiver_moving_radially_is_the_closed_form():
    """A receiver receding along the line from a fixed source at speed u: its distance at time
    t is r0 + u t, so t_rx = t_tx + (r0 + u t_rx) / c, i.e. t_rx = (t_tx + r0 / c) / (1 - u/c)."""
    r0, u = 500.0, 2.5
    direction = np.array([0.6, 0.8, 0.0])
    start = np.array([[0.0, 0.0, -10.0], [*(r0 * direction[:2]), -10.0], [0.0, -900.0, -10.0]])
    vel = np.array([[0.0, 0.0, 0.0], [*(u * direction[:2]), 0.0], [0.0, 0.0, 0.0]])
    cfg = AcousticNetworkConfig(order=("leader",), period_s=10.0, slot_s=2.0)
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, line_positions(start, vel))
    e = np.flatnonzero(r.receiver == 1)
    t_tx = r.t_tx_s[0, e]
    expected = (t_tx + r0 / C) / (1 - u / C)
    np.testing.assert_allclose(r.t_rx_s[0, e], expected, rtol=1e-13)
    # the receiver moved 2.5 m/s x 0.34 s: the range is not the range at the transmit instant
    assert np.all(r.true_range_m[0, e] - (r0 + u * t_tx) > 0.8)


def test_the_true_medium_sets_the_travel_time_not_the_nominal_speed():
    cfg = AcousticNetworkConfig(period_s=12.0, slot_s=4.0)
    still = line_positions(START, np.zeros_like(VEL))
    r = AcousticNetwork(cfg, NAMES, 1, (0,), Isovelocity(1480.0)).exchange(T_GRID, still)
    d = np.linalg.norm(START[r.sender] - START[r.receiver], axis=1)
    # a range at the nominal 1500 m/s from a travel time at 1480 m/s: d * 1500 / 1480
    np.testing.assert_allclose(r.range_m[0], d * C / 1480.0, rtol=1e-12)


def test_twtt_cancels_the_clock_offsets():
    clocks = {"f1": ClockConfig(offset_s=0.2), "f2": ClockConfig(offset_s=-0.3)}
    cfg = AcousticNetworkConfig(ranging="twtt", clocks=clocks, period_s=12.0, slot_s=4.0)
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, line_positions())
    ok = r.produced[0]
    assert ok.sum() >= 20
    # noise off, no drift: the range is the mean of the two legs' true ranges (0.2 s = 300 m of
    # offset gone)
    np.testing.assert_allclose(r.range_m[0, ok], r.true_range_m[0, ok], rtol=0, atol=1e-7)


def test_twtt_drift_leaves_the_stated_term():
    d_j, d_i, ta = 5e-6, -4e-6, 0.5
    clocks = {"leader": ClockConfig(drift_ppm=d_i * 1e6), "f1": ClockConfig(drift_ppm=d_j * 1e6)}
    cfg = AcousticNetworkConfig(
        ranging="twtt", clocks=clocks, order=("leader",), turnaround_s=ta, period_s=12.0
    )
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, line_positions())
    e = np.flatnonzero((r.sender == 1) & r.produced[0])
    rt = r.t_rx_s[0, e] - r.t_tx_s[0, e]
    term = C / 2 * (d_i * rt - d_j * ta / (1 + d_j))
    np.testing.assert_allclose(r.range_m[0, e] - r.true_range_m[0, e], term, rtol=1e-3, atol=1e-9)


def test_two_senders_in_one_slot_collide_where_they_arrive_together():
    # f2 equidistant from the leader and f1, both transmitting in one slot: their packets reach
    # f2 together and are both lost; the leader and f1 are transmitting (half-duplex)
    start = np.array([[-100.0, 0.0, -10.0], [100.0, 0.0, -10.0], [0.0, 300.0, -10.0]])
    still = line_positions(start, np.zeros((3, 3)))
    cfg = AcousticNetworkConfig(order=("leader+f1", "f2"), period_s=10.0, slot_s=2.0)
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, still)
    same_slot = r.sender != 2
    at_f2 = same_slot & (r.receiver == 2)
    assert at_f2.sum() >= 10
    assert np.all(r.lost[0, at_f2] == LOST_COLLISION)
    # between the two (200 m, 0.13 s of travel) each is still transmitting its 0.2 s packet
    between = same_slot & (r.receiver != 2)
    assert np.all(r.lost[0, between] == LOST_HALF_DUPLEX)
    assert np.all(r.lost[0, r.sender == 2] == LOST_OK)
    # a packet shorter than the travel between the two senders: each hears the other
    short = cfg.model_copy(update={"packet_s": 0.05})
    r2 = AcousticNetwork(short, NAMES, 1, (0,)).exchange(T_GRID, still)
    assert np.all(r2.lost[0, between] == LOST_OK)
    assert np.all(r2.lost[0, at_f2] == LOST_COLLISION)  # simultaneous arrivals still collide
    # f2 off the bisector: the arrivals 178 m = 0.119 s apart, more than the short packet
    start[2] = [600.0, 300.0, -10.0]
    r3 = AcousticNetwork(short, NAMES, 1, (0,)).exchange(T_GRID, line_positions(start, 0 * start))
    assert np.all(r3.lost[0] == LOST_OK)


def test_beyond_max_range_nothing_arrives():
    start = START.copy()
    start[2] = [5000.0, 0.0, -10.0]
    cfg = AcousticNetworkConfig(period_s=12.0, slot_s=4.0, max_range_m=2000.0)
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, line_positions(start, 0 * VEL))
    far = (r.sender == 2) | (r.receiver == 2)
    assert np.all(r.lost[0, far] == LOST_RANGE) and np.all(r.lost[0, ~far] == LOST_OK)


def sonar_snr_db(r, sl, f, b_khz, k, s, w, di):
    """The sonar equation from the published formulas (Thorp 1967 in dB/km as Stojanovic 2007
    eq. 3; Coates 1990 noise as Stojanovic 2007 eq. 7), written out independently here."""
    f2 = f * f
    alpha = 0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003
    tl = k * 10 * np.log10(r) + alpha * r / 1000
    lf = math.log10(f)
    parts = [
        17 - 30 * lf,
        40 + 20 * (s - 0.5) + 26 * lf - 60 * math.log10(f + 0.03),
        50 + 7.5 * math.sqrt(w) + 20 * lf - 40 * math.log10(f + 0.4),
        -15 + 20 * lf,
    ]
    nl = 10 * math.log10(sum(10 ** (p / 10) for p in parts))
    return sl - tl - (nl + 10 * math.log10(b_khz * 1000)) + di


def test_packet_loss_against_range_follows_the_sonar_equation():
    """Acceptance 3: the fraction of packets received at each range equals Phi((SNR - DT) /
    sigma) from the test's own sonar equation, inside the binomial band of the sample size."""
    sonar = dict(
        enabled=True,
        source_level_db=130.0,
        frequency_khz=20.0,
        bandwidth_khz=4.0,
        spreading_k=1.5,
        directivity_db=2.0,
        detection_threshold_db=12.0,
        shipping=0.7,
        wind_m_s=6.0,
        fading_sigma_db=4.0,
    )
    ranges = np.array([150.0, 400.0, 700.0, 1000.0, 1400.0])
    v = ranges.size + 1
    names = tuple(f"v{i}" for i in range(v))
    # the sender at the origin, receivers on a circle of directions, deep apart, still
    ang = np.linspace(0, 2 * np.pi, v - 1, endpoint=False)
    start = np.zeros((v, 3))
    start[1:, 0], start[1:, 1] = ranges * np.cos(ang), ranges * np.sin(ang)
    start[:, 2] = -30.0
    t = np.arange(0.0, 400.0001, 1.0)
    pos = (start[:, None, :] + 0 * t[None, :, None])[:, None]
    cfg = load_config(
        AcousticNetworkConfig,
        base={"order": ["v0"], "period_s": 10.0, "slot_s": 2.0, "sonar": sonar},
    )
    n = 400
    r = AcousticNetwork(cfg, names, 11, tuple(range(n))).exchange(t, pos)
    s = sonar
    expected_snr = sonar_snr_db(
        ranges, s["source_level_db"], 20.0, 4.0, 1.5, 0.7, 6.0, s["directivity_db"]
    )
    p = stats.norm.cdf((expected_snr - 12.0) / 4.0)
    assert p.min() < 0.15 and p.max() > 0.9  # the ranges span the transition
    for k in range(ranges.size):
        e = r.receiver == k + 1
        np.testing.assert_allclose(r.snr_db[:, e], expected_snr[k], atol=1e-9)
        got = r.produced[:, e]
        trials = got.size
        assert np.all(r.lost[:, e][~got] == LOST_SONAR)
        band = 4 * math.sqrt(trials * p[k] * (1 - p[k])) + 1
        assert abs(got.sum() - trials * p[k]) < band, (ranges[k], got.mean(), p[k])


def test_hard_threshold_loses_exactly_beyond_the_sonar_range():
    sonar = {"enabled": True, "source_level_db": 150.0, "detection_threshold_db": 12.0}
    cfg = load_config(
        AcousticNetworkConfig, base={"order": ["v0"], "sonar": sonar, "max_range_m": 1e5}
    )
    # the range where the test's SNR meets the threshold, by bisection
    lo, hi = 1.0, 1e5
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        snr = sonar_snr_db(mid, 150.0, 25.0, 5.0, 1.5, 0.5, 5.0, 0.0)
        lo, hi = (mid, hi) if snr >= 12.0 else (lo, mid)
    ranges = np.array([0.9 * lo, 0.99 * lo, 1.01 * lo, 1.2 * lo])
    start = np.zeros((5, 3))
    ang = np.arange(4) * np.pi / 2  # one sender: nothing collides
    start[1:, 0], start[1:, 1] = ranges * np.cos(ang), ranges * np.sin(ang)
    t = np.arange(0.0, 200.0001, 1.0)
    pos = (start[:, None, :] + 0 * t[None, :, None])[:, None]
    names = tuple(f"v{i}" for i in range(5))
    r = AcousticNetwork(cfg, names, 1, (0, 1)).exchange(t, pos)
    for k, ok in enumerate([True, True, False, False]):
        e = r.receiver == k + 1
        assert np.all(r.produced[:, e] == ok)


def test_timestamp_noise_has_its_variance():
    clocks = {v: ClockConfig(jitter_s=2e-4) for v in NAMES}
    cfg = AcousticNetworkConfig(clocks=clocks, travel_time_sigma_s=3e-4, period_s=12.0, slot_s=4.0)
    n = 300
    r = AcousticNetwork(cfg, NAMES, 4, tuple(range(n))).exchange(T_GRID, line_positions())
    e = (r.range_m - r.true_range_m).ravel() / C
    sd = math.hypot(2e-4, 3e-4)
    q = (e.size - 1) * e.var(ddof=1) / sd**2
    assert stats.chi2.ppf(0.0005, e.size - 1) < q < stats.chi2.ppf(0.9995, e.size - 1)
    assert abs(e.mean()) < 4 * sd / math.sqrt(e.size)


def test_a_run_draws_the_same_numbers_alone_or_in_a_batch():
    clocks = {
        v: ClockConfig(offset_sigma_s=0.01, drift_sigma_ppm=1.0, jitter_s=1e-4) for v in NAMES
    }
    sonar = {"enabled": True, "source_level_db": 140.0, "fading_sigma_db": 5.0}
    cfg = load_config(
        AcousticNetworkConfig,
        base={"clocks": clocks, "sonar": sonar, "travel_time_sigma_s": 1e-4},
    )
    a = AcousticNetwork(cfg, NAMES, 9, (0, 1, 2, 3)).exchange(T_GRID, line_positions())
    b = AcousticNetwork(cfg, NAMES, 9, (2,)).exchange(T_GRID, line_positions())
    for f in ("range_m", "rx_local_s", "t_tx_s", "produced", "lost"):
        np.testing.assert_array_equal(getattr(a, f)[2], getattr(b, f)[0])
    assert not np.array_equal(a.range_m[0], a.range_m[1])


@pytest.mark.parametrize(
    "base,field",
    [
        ({"slot_s": 4.0, "period_s": 10.0}, "slot_s"),
        ({"order": ["leader", "nobody"]}, "order"),
        ({"order": ["leader", "leader"]}, "order"),
        ({"clocks": {"ghost": {}}}, "clocks"),
    ],
)
def test_a_schedule_that_does_not_fit_names_the_field(base, field):
    cfg = load_config(AcousticNetworkConfig, base=base)
    with pytest.raises(ConfigError, match=field):
        AcousticNetwork(cfg, NAMES, 1, (0,))


def test_bad_packet_names_the_field():
    with pytest.raises(ConfigError, match="packet_s"):
        load_config(AcousticNetworkConfig, overrides=["packet_s=3.0"])


# ----------------------------------------------------------------------------------------------
# The online device


def _truth(k_t, p, v):
    from bauv_sim.physics_state import VehicleTruth

    return VehicleTruth(
        t_s=k_t,
        position_world_m=p,
        quat_wxyz=np.array([1.0, 0.0, 0.0, 0.0]),
        roll_pitch_heading_rad=np.zeros(3),
        depth_m=-p[2],
        velocity_world_m_s=v,
        velocity_through_water_world_m_s=v,
        current_world_m_s=np.zeros(3),
        angular_velocity_body_rad_s=np.zeros(3),
    )


def _fly_devices(cfg, tick=0.1, t_end=T_GRID[-1], seed=9, run=2, propagation=None):
    """Every vehicle's device, stepped on the straight lines; returns the measurements by
    receiver."""
    from bauv_sim.acoustics.network import AcousticNetworkDevice
    from bauv_sim.sensors.online import Broadcast, DeviceBuild, Peer, TickContext

    devs = {
        me: AcousticNetworkDevice(
            cfg,
            DeviceBuild(
                "net",
                f"{me}/net",
                seed,
                run,
                tick,
                None,
                None,
                me,
                {"vehicles": NAMES},
                propagation,
            ),
        )
        for me in NAMES
    }
    got = {me: [] for me in NAMES}
    for k in range(1, round(t_end / tick) + 1):
        t = k * tick
        truths = {v: _truth(t, START[n] + VEL[n] * t, VEL[n]) for n, v in enumerate(NAMES)}
        for me in NAMES:
            peers = {
                v: Peer(truths[v], Broadcast(v, t, truths[v].position_world_m, None, VEL[0, :2]))
                for v in NAMES
                if v != me
            }
            m = devs[me].step(TickContext(k, t, truths[me], {}, {}, peers))
            if m is not None:
                got[me].append(m)
    return got


@pytest.mark.slow
@pytest.mark.parametrize("propagation", [None, Isovelocity(1490.0)])
def test_online_device_gives_the_batched_numbers_on_the_same_truth(propagation):
    clocks = {
        "leader": ClockConfig(jitter_s=1e-4),
        "f1": ClockConfig(offset_s=0.003, drift_ppm=2.0, offset_sigma_s=0.002, jitter_s=1e-4),
        "f2": ClockConfig(offset_s=-0.004, drift_sigma_ppm=1.0, jitter_s=1e-4),
    }
    sonar = {"enabled": True, "source_level_db": 126.0, "fading_sigma_db": 4.0}
    cfg = load_config(
        AcousticNetworkConfig,
        base={
            "clocks": clocks,
            "sonar": sonar,
            "travel_time_sigma_s": 2e-4,
            "period_s": 9.0,
            "slot_s": 3.0,
            "transducer_body_m": [0.0, 0.0, 0.0],
        },
    )
    arm = np.array([0.3, -0.1, 0.05])
    cfg = cfg.model_copy(update={"transducer_body_m": tuple(arm)})
    batched = AcousticNetwork(cfg, NAMES, 9, (0, 2), propagation).exchange(
        T_GRID, line_positions(START + arm, VEL)
    )
    online = _fly_devices(cfg, propagation=propagation)
    lost_some = False
    for i, me in enumerate(NAMES):
        e = np.flatnonzero((batched.receiver == i) & batched.produced[1])
        lost_some |= bool((~batched.produced[1][batched.receiver == i]).any())
        ms = [m for m in online[me] if m.payload.tx_local_s <= batched.tx_local_s[1].max()]
        assert len(ms) == e.size > 5
        for m, ev in zip(ms, e, strict=True):
            p = m.payload
            assert p.sender == NAMES[batched.sender[ev]] and p.receiver == me
            assert p.tx_local_s == batched.tx_local_s[1, ev]
            assert p.rx_local_s == pytest.approx(batched.rx_local_s[1, ev], abs=1e-9)
            assert m.value[0] == pytest.approx(batched.range_m[1, ev], abs=1e-6)
            assert p.snr_db == pytest.approx(batched.snr_db[1, ev], abs=1e-9)
            assert m.t_valid_s == pytest.approx(batched.t_rx_s[1, ev], abs=1e-9)
            assert m.t_arrival_s == pytest.approx(batched.t_available_s[1, ev], abs=1e-9)
            assert p.broadcast.sender == p.sender
    assert lost_some  # the sonar's draws were exercised


CROWDED = {"period_s": 3.0, "slot_s": 0.25, "turnaround_s": 0.1, "packet_s": 0.1}


@pytest.mark.slow
@pytest.mark.parametrize("schedule", [{"reply_stagger_s": 0.0}, {"reply_stagger_s": 0.3}, CROWDED])
def test_online_twtt_gives_the_batched_numbers_on_the_same_truth(schedule):
    clocks = {
        "leader": ClockConfig(offset_s=0.01, jitter_s=1e-4),
        "f1": ClockConfig(offset_s=-0.02, drift_ppm=3.0, jitter_s=1e-4),
        "f2": ClockConfig(offset_sigma_s=0.01, drift_sigma_ppm=2.0, jitter_s=1e-4),
    }
    sonar = {"enabled": True, "source_level_db": 128.0, "fading_sigma_db": 4.0}
    cfg = load_config(
        AcousticNetworkConfig,
        base={
            "ranging": "twtt",
            "clocks": clocks,
            "sonar": sonar,
            "travel_time_sigma_s": 2e-4,
            "period_s": 9.0,
            "slot_s": 3.0,
            "transducer_body_m": [0.2, 0.0, -0.1],
            **schedule,
        },
    )
    arm = np.array([0.2, 0.0, -0.1])
    batched = AcousticNetwork(cfg, NAMES, 9, (0, 2)).exchange(
        T_GRID, line_positions(START + arm, VEL)
    )
    online = _fly_devices(cfg)
    counts = np.bincount(batched.lost[1], minlength=5)
    assert counts[LOST_OK] > 10 and counts[LOST_SONAR] > 0
    if schedule.get("reply_stagger_s", 0.0) == 0.0:
        assert counts[LOST_COLLISION] > 0  # replies arriving together
    if schedule is CROWDED:  # slots shorter than an exchange: replies meet the next pings
        assert counts[LOST_HALF_DUPLEX] > 0
    for i, me in enumerate(NAMES):
        e = np.flatnonzero((batched.receiver == i) & batched.produced[1])
        ms = [m for m in online[me] if m.payload.tx_local_s <= batched.tx_local_s[1].max()]
        assert len(ms) == e.size > 3
        order = np.argsort(batched.t_rx_s[1, e], kind="stable")  # the device emits by arrival
        for m, ev in zip(sorted(ms, key=lambda m: m.t_valid_s), e[order], strict=True):
            p = m.payload
            assert p.kind == "twtt" and p.receiver == me
            assert p.sender == NAMES[batched.sender[ev]]
            assert p.tx_local_s == batched.tx_local_s[1, ev]
            assert p.rx_local_s == pytest.approx(batched.rx_local_s[1, ev], abs=1e-9)
            assert m.value[0] == pytest.approx(batched.range_m[1, ev], abs=1e-6)
            assert p.snr_db == pytest.approx(batched.snr_db[1, ev], abs=1e-9)
            assert m.t_valid_s == pytest.approx(batched.t_rx_s[1, ev], abs=1e-9)


def test_online_device_in_a_rig_ranges_between_the_model_sites_with_the_clock_bias():
    import dataclasses

    from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
    from bauv_sim.sensors.online import Broadcast, Peer
    from bauv_sim.sensors.rig import SensorRig

    scene = SceneConfig(
        vehicles=(
            VehicleSpec(name="leader", east_m=0.0, north_m=0.0, heading_deg=30.0),
            VehicleSpec(name="f1", east_m=80.0, north_m=-60.0, heading_deg=30.0, depth_m=4.0),
        )
    )
    phys = build_physics(scene, control_tick_s=0.2)
    cfg = AcousticNetworkConfig(clocks={"f1": ClockConfig(offset_s=0.002)}, start_s=2.0)
    rig = SensorRig({"net": cfg}, phys, "f1", 5, 0, "f1")
    site = {v: phys.site_position_world("modem", v) for v in ("leader", "f1")}
    true_r = float(np.linalg.norm(site["leader"] - site["f1"]))
    lead, me = phys.truth("leader"), phys.truth("f1")
    lead = dataclasses.replace(lead, velocity_world_m_s=np.zeros(3))
    me = dataclasses.replace(me, velocity_world_m_s=np.zeros(3))
    bc = Broadcast("leader", 0.0, np.zeros(3), np.ones(3), np.zeros(2), clock_offset_s=1e-4)
    got = []
    for k in range(1, 100):
        t = 0.2 * k
        peers = {"leader": Peer(dataclasses.replace(lead, t_s=t), bc)}
        got += rig.sense(k, dataclasses.replace(me, t_s=t), {}, peers=peers).arrived
    # the leader transmits at 2, 12 s (slot 0); f1's own slot (2 s later) is not heard by f1
    assert [round(m.payload.tx_local_s, 9) for m in got] == [2.0, 12.0]
    for m in got:
        # the range is the true one plus c x (f1's offset - the leader's): +3 m
        assert m.value[0] == pytest.approx(true_r + C * 0.002, abs=1e-9)
        assert m.t_valid_s == pytest.approx(m.payload.tx_local_s + true_r / C, abs=1e-12)
        assert m.t_arrival_s == pytest.approx(m.t_valid_s + 0.5)
        assert m.payload.broadcast is bc and m.payload.sender == "leader"
    assert rig.lever_arms_body_m["net"] == pytest.approx((0.36, 0.0, 0.166), abs=1e-9)


def test_twtt_replies_collide_unless_staggered():
    # two responders at one range: replies sent together arrive together at the interrogator
    start = np.array([[0.0, 0.0, -10.0], [300.0, 0.0, -10.0], [0.0, 300.0, -10.0]])
    still = line_positions(start, np.zeros((3, 3)))
    clocks = {"f1": ClockConfig(offset_s=0.05), "f2": ClockConfig(offset_s=-0.07)}
    cfg = AcousticNetworkConfig(ranging="twtt", order=("leader",), clocks=clocks)
    r = AcousticNetwork(cfg, NAMES, 1, (0,)).exchange(T_GRID, still)
    assert r.sender.size >= 10 and np.all(r.lost == LOST_COLLISION)
    # the second responder waits 0.3 s more (more than a packet): both ranges, offsets cancelled
    staggered = cfg.model_copy(update={"reply_stagger_s": 0.3})
    r = AcousticNetwork(staggered, NAMES, 1, (0,)).exchange(T_GRID, still)
    assert r.produced.all()
    np.testing.assert_allclose(r.range_m, 300.0, rtol=0, atol=1e-9)
    # f2's reply reaches the leader 0.3 s after f1's: a responder's offset does not delay it
    # (it times its turnaround on its own clock from its own timestamp)
    np.testing.assert_allclose(r.t_rx_s[0, 1::2] - r.t_rx_s[0, ::2], 0.3, atol=1e-9)


def test_modem_one_way_option_ranges_by_travel_time_and_clocks():
    import dataclasses

    from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
    from bauv_sim.sensors.modem import ModemConfig
    from bauv_sim.sensors.online import Broadcast, Peer
    from bauv_sim.sensors.rig import SensorRig

    scene = SceneConfig(
        vehicles=(
            VehicleSpec(name="leader", east_m=0.0, north_m=0.0, heading_deg=30.0),
            VehicleSpec(name="f1", east_m=80.0, north_m=-60.0, heading_deg=30.0, depth_m=4.0),
        )
    )
    phys = build_physics(scene, control_tick_s=0.2)
    site = {v: phys.site_position_world("modem", v) for v in ("leader", "f1")}
    true_r = float(np.linalg.norm(site["leader"] - site["f1"]))
    lead = dataclasses.replace(phys.truth("leader"), velocity_world_m_s=np.zeros(3))
    me = dataclasses.replace(phys.truth("f1"), velocity_world_m_s=np.array([1.0, -0.5, 0.0]))
    bc = Broadcast("leader", 0.0, np.zeros(3), np.ones(3), np.zeros(2))
    clocks = {"leader": ClockConfig(offset_s=-0.001), "f1": ClockConfig(offset_s=0.002)}
    exact = {"sigma_m": 0.0, "bias_m": 0.0}

    def fly(cfg):
        rig = SensorRig({"modem": cfg}, phys, "f1", 5, 0, "f1", extra={"modem": {}})
        got = []
        for k in range(1, 60):
            t = 0.2 * k
            peers = {"leader": Peer(dataclasses.replace(lead, t_s=t), bc)}
            truth = dataclasses.replace(me, t_s=t)  # f1's velocity, its position held
            got += rig.sense(k, truth, {}, peers=peers).arrived
        return got

    instant = fly(ModemConfig(range=exact))
    assert [m.value[0] for m in instant] == pytest.approx([true_r] * 2, abs=1e-12)
    one_way = fly(ModemConfig(range=exact, ranging="owtt", clocks=clocks))
    assert len(one_way) == 2
    for m0, m in zip(instant, one_way, strict=True):
        T = m0.t_valid_s  # the slot's time
        t_tx = T + 0.001  # the leader's clock, 1 ms behind, reads T 1 ms late
        # f1 (held at its tick's position, moving at v from there) receives at t_rx:
        # |p_leader - (p_f1 + v (t_rx - T))| = c (t_rx - t_tx), solved here as a quadratic
        d = site["f1"] - site["leader"]
        v = np.array([1.0, -0.5, 0.0])
        # |d + v s| = c (s + T - t_tx), s = t_rx - T
        a = v @ v - C**2
        b = 2 * (d @ v) - 2 * C**2 * (T - t_tx)
        c = d @ d - C**2 * (T - t_tx) ** 2
        s = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
        t_rx = T + s
        assert m.t_valid_s == pytest.approx(t_rx, abs=1e-12)
        assert m.t_arrival_s == pytest.approx(t_rx + 0.5, abs=1e-12)
        # the range: c (local_f1(t_rx) - T) = c (t_rx - t_tx) + c (0.002 - (-0.001))
        assert m.value[0] == pytest.approx(C * (t_rx - t_tx) + C * 0.003, abs=1e-9)
        assert m.payload is bc
