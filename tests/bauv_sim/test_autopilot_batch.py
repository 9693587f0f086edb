"""The batched autopilot against the scalar one, run by run (issue 27, check 2)."""

import math

import numpy as np
import pytest

from bauv_sim.autopilot import Autopilot, AutopilotConfig, Measured
from bauv_sim.autopilot_batch import BatchAutopilot, BatchMeasured

N, TICKS, DT = 6, 300, 0.2
SPEEDS = np.array([0.0, 0.5, 1.0, 1.5])
FREQS = np.array([0.0, 0.45, 0.85, 1.3])


def table(v):
    return np.interp(v, SPEEDS, FREQS)


def _inputs(rng):
    """Measurements and set-points that exercise every branch: heading across north, dives and
    climbs beyond the integral zones, saturated fins and bias, stops (speed 0), and tail-beat
    frequencies that change the averaging window."""
    t = np.arange(TICKS) * DT
    m = {
        "heading_rad": np.mod(
            0.1 * np.sin(0.05 * t)[:, None] + rng.uniform(-0.3, 0.3, N), 2 * math.pi
        ),
        "yaw_rate_rad_s": rng.normal(0, 0.3, (TICKS, N)),
        "depth_m": 3 + np.cumsum(rng.normal(0, 0.05, (TICKS, N)), 0),
        "pitch_rad": rng.normal(0, 0.2, (TICKS, N)),
        "pitch_rate_rad_s": rng.normal(0, 0.3, (TICKS, N)),
        "roll_rad": rng.normal(0, 0.1, (TICKS, N)),
        "roll_rate_rad_s": rng.normal(0, 0.2, (TICKS, N)),
        "speed_m_s": np.abs(rng.normal(0.9, 0.3, (TICKS, N))),
    }
    course = np.mod(rng.uniform(-1, 1, (TICKS, N)) + (t > 20)[:, None] * math.pi, 2 * math.pi)
    depth = np.where((t > 30)[:, None], 8.0, 3.0) + rng.uniform(-0.2, 0.2, (TICKS, N))
    speed = np.where(rng.random((TICKS, N)) < 0.05, 0.0, rng.choice([0.6, 1.0, 1.4], (TICKS, N)))
    return m, course, depth, speed


@pytest.mark.parametrize("averaging", [True, False])
def test_each_run_equals_the_scalar_autopilot(averaging):
    cfg = AutopilotConfig(beat_averaging=averaging)
    m, course, depth, speed = _inputs(np.random.default_rng(3))
    batch = BatchAutopilot(cfg, N, table, battery0_m=0.01)
    scalars = [Autopilot(cfg, lambda v: float(table(v)), battery0_m=0.01) for _ in range(N)]
    for k in range(TICKS):
        bm = BatchMeasured(**{key: v[k] for key, v in m.items()})
        out = batch.step(DT, course[k], depth[k], speed[k], bm)
        for i, ap in enumerate(scalars):
            c = ap.step(
                DT, course[k, i], depth[k, i], speed[k, i],
                Measured(**{key: float(v[k, i]) for key, v in m.items()}),
            )  # fmt: skip
            got = [out.tail_beat_hz[i], out.tail_bias_rad[i], out.fin_port_rad[i],
                   out.fin_starboard_rad[i], out.battery_m[i]]  # fmt: skip
            want = [c.tail_beat_hz, c.tail_bias_rad, c.fin_port_rad, c.fin_starboard_rad,
                    c.battery_m]  # fmt: skip
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12, err_msg=f"tick {k} run {i}")
            assert batch.heading.integral[i] == pytest.approx(ap.heading.integral, abs=1e-12)
            assert batch.speed.integral[i] == pytest.approx(ap.speed.integral, abs=1e-12)


def test_the_inputs_reach_the_limits_and_the_stops():
    """The inputs above exercise saturation, stops and window changes (else the test is weak)."""
    cfg = AutopilotConfig()
    m, course, depth, speed = _inputs(np.random.default_rng(3))
    batch = BatchAutopilot(cfg, N, table)
    bias_max = math.radians(cfg.tail_bias_max_deg)
    sat, stops, freqs = 0, 0, set()
    for k in range(TICKS):
        out = batch.step(
            DT, course[k], depth[k], speed[k], BatchMeasured(**{a: v[k] for a, v in m.items()})
        )
        sat += int(np.sum(np.abs(out.tail_bias_rad) >= bias_max - 1e-12))
        stops += int(np.sum(out.tail_beat_hz == 0))
        freqs |= set(np.round(out.tail_beat_hz, 1))
    assert sat > 10 and stops > 10 and len(freqs) > 5
