"""Acceptance check 2, second half: a filter with the clock offset (and drift) in its state
recovers the offset from one-way-travel-time ranges, and its NEES over 100 runs stays in the
chi-square band.

The measurements are generated here from the truth: a vehicle on a curved path dead-reckons with
white noise of the stated covariance; three beacons at known positions and depths with
synchronised clocks transmit in turn on a schedule; the reception instant solves
``t_rx = t_tx + |p_beacon - p(t_rx)| / c`` on the vehicle's true trajectory; the vehicle stamps it
with its clock ``t + b0 + d t`` plus jitter; the range is ``c (L - T)``.
"""

import numpy as np

from nav.cooperative import ClockOptions, CoopNavigator, PeerEstimate
from nav.metrics import nees_band

C = 1500.0
BEACONS = np.array([[0.0, 0.0], [400.0, 50.0], [150.0, 380.0]])
BEACON_DEPTH = np.array([30.0, 25.0, 35.0])
DEPTH = 10.0


def _path(t, phase):
    """A curving path, (..., 2) m, at about 1.5 m/s."""
    return np.stack(
        [
            100.0 + 1.2 * t + 20 * np.sin(t / 40 + phase),
            100.0 + 0.9 * t + 20 * np.cos(t / 55 + phase),
        ],
        axis=-1,
    )


def _run(n=100, duration_s=400.0, dt_s=0.5, seed=11, break_clock=None):
    rng = np.random.default_rng(seed)
    clock = ClockOptions(
        offset_sigma_s=2e-3, drift_sigma=2e-6, offset_noise_s2_per_s=1e-14, drift_noise_per_s=1e-20
    )
    k = round(duration_s / dt_s) + 1
    t = np.arange(k) * dt_s
    phase = rng.uniform(0, 2 * np.pi, n)
    truth = _path(t[None, :], phase[:, None])  # (n, k, 2)
    b0 = rng.normal(0, clock.offset_sigma_s, n)
    drift = rng.normal(0, clock.drift_sigma, n)
    step_sigma = 0.1 * dt_s
    steps = np.diff(truth, axis=1) + rng.normal(0, step_sigma, (n, k - 1, 2))
    step_cov = np.broadcast_to(np.eye(2) * step_sigma**2, (n, 2, 2))
    start_sigma = 3.0
    start = truth[:, 0] + rng.normal(0, start_sigma, (n, 2))
    nav = CoopNavigator(
        start, np.broadcast_to(np.eye(2) * start_sigma**2, (n, 2, 2)), clock, fusion="naive"
    )
    sigma_range = 0.2
    # beacon j transmits at true (= its local) time 1.0 + 1.5 j + 4.5 m
    events = []
    for cycle in range(int(duration_s // 4.5) - 1):
        for j in range(3):
            T = 1.0 + 1.5 * j + 4.5 * cycle
            t_rx = np.full(n, T)
            for _ in range(8):
                p = _path(t_rx, phase)
                dist = np.sqrt(((p - BEACONS[j]) ** 2).sum(-1) + (DEPTH - BEACON_DEPTH[j]) ** 2)
                t_rx = T + dist / C
            L = t_rx + b0 + drift * t_rx + rng.normal(0, sigma_range / C, n)
            q = int(np.ceil(t_rx.max() / dt_s))
            events.append((q, j, T, L))
    events.sort(key=lambda e: e[0])
    x_err = np.empty((n, k, 4))
    P_all = np.empty((n, k, 4, 4))
    e_idx = 0
    for q in range(k):
        if q > 0:
            nav.predict(steps[:, q - 1], step_cov, dt_s)
        while e_idx < len(events) and events[e_idx][0] == q:
            _, j, T, L = events[e_idx]
            e_idx += 1
            beacon = PeerEstimate.from_parts(
                np.broadcast_to(BEACONS[j], (n, 2)),
                np.broadcast_to(np.eye(2) * 1e-6, (n, 2, 2)),
                np.zeros(n),
                np.full(n, 1e-16),
            )
            lag = t[q] - (L - nav.clock_offset)
            nav.fuse_range(
                C * (L - T),
                beacon,
                sigma_m=sigma_range,
                depth_m=DEPTH,
                peer_depth_m=BEACON_DEPTH[j],
                sound_speed_m_s=C,
                lag_s=break_clock(lag) if break_clock else lag,
                velocity_m_s=steps[:, q - 1] / dt_s,
            )
        true_state = np.concatenate(
            [truth[:, q], (b0 + drift * t[q])[:, None], drift[:, None]], axis=1
        )
        x_err[:, q] = nav.x - true_state
        P_all[:, q] = nav.P
    return x_err, P_all, b0 + drift * t[-1], clock


def _nees(err, P):
    return np.einsum("...i,...i->...", err, np.linalg.solve(P, err[..., None])[..., 0])


def test_the_clock_offset_is_recovered_and_the_nees_over_100_runs_is_in_the_band():
    err, P, final_offset, clock = _run()
    n = err.shape[0]
    # the offset: from 2 ms prior to below 0.1 ms (c * 0.1 ms = 15 cm)
    rms_final = np.sqrt(np.mean(err[:, -1, 2] ** 2))
    assert rms_final < 0.05 * clock.offset_sigma_s, rms_final
    assert np.sqrt(np.mean(final_offset**2)) > 1e-3  # there was an offset to recover
    # stated accuracy matches: NEES of the full state [e, n, b, d] (4 dof), pooled over the
    # samples after the first ranges, against the band of 100 runs
    nees = _nees(err[:, 20:], P[:, 20:])
    low, high = nees_band(4, n)
    assert low <= nees.mean() <= high, (nees.mean(), low, high)
    # and the offset alone (1 dof)
    nees_b = err[:, 20:, 2] ** 2 / P[:, 20:, 2, 2]
    low1, high1 = nees_band(1, n)
    assert low1 <= nees_b.mean() <= high1, (nees_b.mean(), low1, high1)


def test_the_band_check_fails_when_the_filter_is_wrong():
    # the receiver's position at the reception taken a quarter of a second forward instead of
    # back: the same check must see it (NEES far above the band)
    err, P, _, _ = _run(n=100, break_clock=lambda lag: -lag - 0.25)
    nees = _nees(err[:, 20:], P[:, 20:])
    assert nees.mean() > nees_band(4, 100)[1]
