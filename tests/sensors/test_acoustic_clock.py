"""Clocks: the linear clock's reading and its exact inverse, the per-run draws against their
distributions, determinism by vehicle stream, validation."""

import math

import numpy as np
import pytest
from scipy import stats

from bauv_sim.acoustics.clock import Clock, ClockConfig, draw_clocks
from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError


def test_local_is_true_plus_offset_and_drift():
    clock = Clock(np.array([0.01, -0.002]), np.array([2e-6, -5e-7]))
    t = np.array([[0.0, 100.0, 3600.0], [0.0, 100.0, 3600.0]])
    # worked out by hand: local = t + b0 + d t
    expected = np.array(
        [
            [0.01, 100.0 + 0.01 + 2e-4, 3600.0 + 0.01 + 7.2e-3],
            [-0.002, 100.0 - 0.002 - 5e-5, 3600.0 - 0.002 - 1.8e-3],
        ]
    )
    np.testing.assert_allclose(clock.local(t), expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(clock.offset(t), expected - t, rtol=0, atol=1e-12)


def test_true_of_local_inverts_local():
    rng = np.random.default_rng(1)
    clock = Clock(rng.normal(0, 0.1, 50), rng.normal(0, 1e-5, 50))
    t = rng.uniform(0, 1e4, (50, 7))
    np.testing.assert_allclose(clock.true_of_local(clock.local(t)), t, rtol=0, atol=1e-9)
    T = rng.uniform(0, 1e4, (50, 7))
    np.testing.assert_allclose(clock.local(clock.true_of_local(T)), T, rtol=0, atol=1e-9)


def test_drawn_offsets_and_drifts_follow_their_normal_laws():
    cfg = ClockConfig(offset_s=0.002, drift_ppm=1.0, offset_sigma_s=0.001, drift_sigma_ppm=0.5)
    n = 4000
    clock = draw_clocks(cfg, 7, tuple(range(n)), "f1")
    for x, mu, sd in ((clock.offset0_s, 0.002, 0.001), (clock.drift, 1e-6, 0.5e-6)):
        assert abs(x.mean() - mu) < 4 * sd / math.sqrt(n)
        q = (n - 1) * x.var(ddof=1) / sd**2
        assert stats.chi2.ppf(0.0005, n - 1) < q < stats.chi2.ppf(0.9995, n - 1)
    # the two draws are independent
    assert abs(np.corrcoef(clock.offset0_s, clock.drift)[0, 1]) < 4 / math.sqrt(n)


def test_draws_depend_on_the_vehicle_and_run_only():
    cfg = ClockConfig(offset_sigma_s=0.01, drift_sigma_ppm=1.0)
    a = draw_clocks(cfg, 3, (0, 1, 2, 3), "f1")
    b = draw_clocks(cfg, 3, (2,), "f1")
    assert a.offset0_s[2] == b.offset0_s[0] and a.drift[2] == b.drift[0]
    c = draw_clocks(cfg, 3, (0, 1, 2, 3), "f2")
    assert not np.any(a.offset0_s == c.offset0_s)


def test_fixed_clock_draws_nothing():
    c = draw_clocks(ClockConfig(offset_s=0.5, drift_ppm=2.0), 1, (0, 1), "x")
    np.testing.assert_array_equal(c.offset0_s, [0.5, 0.5])
    np.testing.assert_array_equal(c.drift, [2e-6, 2e-6])


@pytest.mark.parametrize("field,value", [("offset_sigma_s", -1.0), ("jitter_s", -0.1)])
def test_bad_clock_names_the_field(field, value):
    with pytest.raises(ConfigError, match=field):
        load_config(ClockConfig, overrides=[f"{field}={value}"])
