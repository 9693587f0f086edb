"""A synthetic team for the tests of nav.cooperative, generated here from its truth (no bauv_sim):
a leader on a square with fixes, followers in a wandering formation at distinct depths, clocks
with offset and drift, and OWTT ranges on a TDMA schedule with the travel time solved on the true
trajectories (the vehicles move while the sound travels). The test below checks the generator
itself: with no noise a range is the distance between the two instants plus c times the clocks'
difference (acceptance check 2's first half, restated on this independent generator)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nav.cooperative import TeamRecord

C = 1500.0
LEG_S = 120.0
SPEED = 1.0


@dataclass
class Team:
    record: TeamRecord
    truth_m: np.ndarray  # (n, v, k, 2)
    true_offset_s: np.ndarray  # (n, v, k)


def _leader(t):
    """Leader on a square of 120 s legs at 1 m/s, first course 45 deg (seed 003's path)."""
    t = np.asarray(t, dtype=float)
    course = np.deg2rad(45.0 + 90.0 * np.arange(8))
    legs = np.stack([np.sin(course), np.cos(course)], axis=1) * SPEED * LEG_S
    corners = np.concatenate([[[0.0, 0.0]], np.add.accumulate(legs, axis=0)])
    leg = np.minimum((t // LEG_S).astype(int), 7)
    frac = (t - leg * LEG_S)[..., None] / LEG_S
    return corners[leg] + frac * legs[leg]


OFFSETS = np.array([[0.0, 0.0], [-40.0, 10.0], [30.0, -35.0], [15.0, 45.0], [-25.0, -30.0]])
DEPTHS = np.array([2.0, 8.0, 14.0, 20.0, 5.0])


def truth(vehicle, t, phase):
    """Position of a vehicle at times t (any shape), (..., 2): the leader's plus the station
    offset and a slow wander (phase per run, broadcast with t)."""
    p = _leader(t)
    if vehicle == 0:
        return p
    w = 2 * np.pi / (150.0 + 40.0 * vehicle)
    wander = 12.0 * np.stack([np.sin(w * t + phase), np.cos(0.7 * w * t + phase)], axis=-1)
    return p + OFFSETS[vehicle] + wander


def _arrival(sender, t_tx, receiver, guess, phase):
    """True reception time of a ping sent by ``sender`` at ``t_tx`` (n,): the fixed point of
    ``t_rx = t_tx + |p_s(t_tx) - p_r(t_rx)| / c`` on the receiver's trajectory."""
    p_tx = truth(sender, t_tx, phase[:, sender])
    t_rx = guess.copy()
    for _ in range(6):
        p_rx = truth(receiver, t_rx, phase[:, receiver])
        dz = DEPTHS[receiver] - DEPTHS[sender]
        t_rx = t_tx + np.sqrt(((p_rx - p_tx) ** 2).sum(-1) + dz**2) / C
    return t_rx


def make_team(
    n=20,
    v=4,
    duration_s=300.0,
    dt_s=0.2,
    seed=0,
    step_sigma_m_s=0.15,
    fix_every_s=10.0,
    fix_sigma_m=1.0,
    start_sigma_m=1.0,
    offset_sigma_s=1e-3,
    drift_sigma=1e-6,
    sigma_range_m=0.1,
    slot_s=2.0,
    leader_offset_sigma_s=1e-7,
    fix_vehicles=(0,),
    kind="owtt",
    turnaround_s=0.5,
):
    rng = np.random.default_rng(seed)
    k = round(duration_s / dt_s) + 1
    t = np.arange(k) * dt_s
    phase = rng.uniform(0, 2 * np.pi, (n, v))
    tt = np.broadcast_to(t, (n, k))
    truth_m = np.stack([truth(i, tt, phase[:, i, None]) for i in range(v)], axis=1)
    # DR: true displacement + white noise with the stated covariance
    step_sigma = step_sigma_m_s * dt_s
    dr_step = np.diff(truth_m, axis=2) + rng.normal(0, step_sigma, (n, v, k - 1, 2))
    dr_cov = np.broadcast_to(np.eye(2) * step_sigma**2, (n, v, k - 1, 2, 2)).copy()
    depth = np.broadcast_to(DEPTHS[:v][None, :, None], (n, v, k)).copy()
    start_cov = np.broadcast_to(np.eye(2) * start_sigma_m**2, (n, v, 2, 2)).copy()
    start = truth_m[:, :, 0] + rng.normal(0, start_sigma_m, (n, v, 2))
    # fixes
    every = round(fix_every_s / dt_s)
    ticks = np.arange(every, k, every)
    fix_tick = np.concatenate([ticks for _ in fix_vehicles] + [np.zeros(0, int)])
    fix_vehicle = np.concatenate(
        [np.full(len(ticks), i) for i in fix_vehicles] + [np.zeros(0, int)]
    )
    fix_m = truth_m[:, fix_vehicle, fix_tick] + rng.normal(0, fix_sigma_m, (n, len(fix_tick), 2))
    fix_cov = np.broadcast_to(np.eye(2) * fix_sigma_m**2, (n, len(fix_tick), 2, 2)).copy()
    # clocks: local(t) = t + b0 + d t
    b0 = rng.normal(0, offset_sigma_s, (n, v))
    d = rng.normal(0, drift_sigma, (n, v))
    b0[:, 0] = rng.normal(0, leader_offset_sigma_s, n)
    d[:, 0] = 0.0
    true_offset = b0[..., None] + d[..., None] * t
    # OWTT on TDMA: vehicle s transmits at local time c P + s slot + 0.1
    period = v * slot_s
    ev = {k_: [] for k_ in ("s", "r", "tx", "rx", "z", "T", "L")}
    cycle = 0
    while True:
        base = cycle * period
        if base + period > duration_s - 3.0:
            break
        for s in range(v):
            T = np.full(n, base + s * slot_s + 0.1)
            t_tx = (T - b0[:, s]) / (1.0 + d[:, s])
            if kind == "twtt":  # s interrogates one peer per slot, round robin
                r = (s + 1 + cycle % (v - 1)) % v
                t1 = _arrival(s, t_tx, r, t_tx, phase)
                t2 = t1 + turnaround_s / (1.0 + d[:, r])  # the reply, the responder's clock
                t3 = _arrival(r, t2, s, t2, phase)
                L = t3 + b0[:, s] + d[:, s] * t3 + rng.normal(0, 2 * sigma_range_m / C, n)
                ev["s"].append(r)
                ev["r"].append(s)
                ev["tx"].append(int(np.floor(t_tx.min() / dt_s + 1e-9)))
                ev["rx"].append(int(np.ceil(t3.max() / dt_s - 1e-9)))
                ev["z"].append(C * (L - T - turnaround_s) / 2)
                ev["T"].append(T)
                ev["L"].append(L)
                continue
            for r in range(v):
                if r == s:
                    continue
                t_rx = _arrival(s, t_tx, r, t_tx, phase)
                L = t_rx + b0[:, r] + d[:, r] * t_rx + rng.normal(0, sigma_range_m / C, n)
                ev["s"].append(s)
                ev["r"].append(r)
                ev["tx"].append(int(np.floor(t_tx.min() / dt_s + 1e-9)))
                ev["rx"].append(int(np.ceil(t_rx.max() / dt_s - 1e-9)))
                ev["z"].append(C * (L - T))
                ev["T"].append(T)
                ev["L"].append(L)
        cycle += 1
    m = len(ev["s"])
    record = TeamRecord(
        t_s=t,
        dr_step_m=dr_step,
        dr_step_cov_m2=dr_cov,
        depth_m=depth,
        start_m=start,
        start_cov_m2=start_cov,
        fix_tick=fix_tick,
        fix_vehicle=fix_vehicle,
        fix_m=fix_m,
        fix_cov_m2=fix_cov,
        fix_present=np.ones((n, len(fix_tick)), dtype=bool),
        range_sender=np.array(ev["s"]),
        range_receiver=np.array(ev["r"]),
        range_tx_tick=np.array(ev["tx"]),
        range_rx_tick=np.array(ev["rx"]),
        range_m=np.stack(ev["z"], axis=1),
        range_tx_local_s=np.stack(ev["T"], axis=1),
        range_rx_local_s=np.stack(ev["L"], axis=1),
        range_present=np.ones((n, m), dtype=bool),
        kind=kind,
        sound_speed_m_s=C,
        sigma_range_m=sigma_range_m,
    )
    return Team(record, truth_m, true_offset)


def test_a_noise_free_range_is_the_distance_at_the_two_instants_plus_c_times_the_offsets():
    team = make_team(n=3, v=3, duration_s=40.0, sigma_range_m=1e-12, seed=5)
    rec = team.record
    rng = np.random.default_rng(5)
    phase = rng.uniform(0, 2 * np.pi, (3, 3))  # the generator's first draw
    t = rec.t_s
    for e in range(rec.range_m.shape[1]):
        s, r = rec.range_sender[e], rec.range_receiver[e]
        offset = team.true_offset_s  # b0 + d t on the sample grid: recover b0, d
        d = (offset[:, :, 1] - offset[:, :, 0]) / (t[1] - t[0])
        b0 = offset[:, :, 0]
        T, L = rec.range_tx_local_s[:, e], rec.range_rx_local_s[:, e]
        t_tx = (T - b0[:, s]) / (1 + d[:, s])
        t_rx = (L - b0[:, r]) / (1 + d[:, r])
        p_tx = truth(s, t_tx, phase[:, s])
        p_rx = truth(r, t_rx, phase[:, r])
        dist = np.sqrt(((p_rx - p_tx) ** 2).sum(-1) + (DEPTHS[r] - DEPTHS[s]) ** 2)
        bias = C * ((b0[:, r] + d[:, r] * t_rx) - (b0[:, s] + d[:, s] * t_tx))
        np.testing.assert_allclose(rec.range_m[:, e], dist + bias, rtol=0, atol=1e-6)
        assert np.all(np.abs(bias) > 0)
        assert np.all(t[rec.range_tx_tick[e]] <= t_tx + 1e-9)
        assert np.all(t[rec.range_rx_tick[e]] >= t_rx - 1e-9)
