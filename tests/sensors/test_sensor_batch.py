"""Sensor errors drawn ahead for a batch (bauv_sim.sensors.batch) against the devices' error
processes sampled one at a time, with the noise off, and in distribution (issue 27, check 2)."""

import math

import numpy as np
import pytest

from bauv_sim.sensors.batch import BatchUsbl, PrefetchedErrors
from bauv_sim.sensors.errors import ErrorModel, ErrorProcess
from bauv_sim.sensors.usbl import Usbl, UsblConfig

RUNS = (0, 3, 7, 8, 100)
PATH = ("sensor", "test", "x")


def _pair(model, runs=RUNS, block=7):
    one = ErrorProcess(model, 42, runs, PATH)
    ahead = PrefetchedErrors(ErrorProcess(model, 42, runs, PATH), 0.2, block)
    return one, ahead


def _truth(rng, k):
    return rng.normal(0, 10, (k, len(RUNS)))


@pytest.mark.parametrize(
    "model",
    [
        ErrorModel(sigma=0.3),
        ErrorModel(distribution="uniform", sigma=0.3, scale_factor=0.01),
        ErrorModel(sigma=0.1, dropout_probability=0.3),
        ErrorModel(sigma=0.1, sector_bias=(0.1, 0.2, -0.1, 0.0), deviation=(0.1, 0, 0.02, 0, 0)),
    ],
    ids=["gaussian", "uniform-scale", "dropout", "reference"],
)
def test_the_same_numbers_bit_for_bit_without_bias_or_walk(model):
    """23 samples over blocks of 7: the process sampled one at a time gives the same numbers."""
    rng = np.random.default_rng(0)
    one, ahead = _pair(model)
    x = _truth(rng, 23)
    ref = rng.uniform(0, 2 * math.pi, x.shape)
    for j in range(23):
        t = 0.2 * j
        want, ok_w = one.apply(x[j][:, None], np.array([t]), ref[j][:, None])
        got, ok_g = ahead.measure(x[j], t, ref[j])
        assert np.array_equal(got, want[:, 0]) and np.array_equal(ok_g, ok_w[:, 0])


@pytest.mark.parametrize(
    "model",
    [
        ErrorModel(sigma=0.1, bias=0.7, random_walk=0.05, scale_factor=-0.02),
        ErrorModel(sigma=0.1, outlier_probability=0.2, outlier_sigma=5.0, dropout_probability=0.3),
    ],
    ids=["bias-walk", "outliers"],
)
def test_bias_walk_and_outliers_to_rounding(model):
    rng = np.random.default_rng(1)
    one, ahead = _pair(model)
    x = _truth(rng, 30)
    for j in range(30):
        want, ok_w = one.apply(x[j][:, None], np.array([0.2 * j]))
        got, ok_g = ahead.measure(x[j], 0.2 * j)
        np.testing.assert_allclose(got, want[:, 0], rtol=0, atol=1e-12)
        assert np.array_equal(ok_g, ok_w[:, 0])


def test_noise_off_measures_the_truth_with_its_scale_and_bias():
    model = ErrorModel(sigma=0.0, bias=0.25, scale_factor=0.01)
    _, ahead = _pair(model)
    x = _truth(np.random.default_rng(2), 3)
    for j in range(3):
        got, ok = ahead.measure(x[j], 0.2 * j)
        np.testing.assert_allclose(got, 1.01 * x[j] + 0.25, rtol=1e-15)
        assert ok.all()


def test_a_run_draws_the_same_in_any_batch():
    model = ErrorModel(sigma=1.0)
    big = PrefetchedErrors(ErrorProcess(model, 9, RUNS, PATH), 1.0, 4)
    alone = PrefetchedErrors(ErrorProcess(model, 9, (7,), PATH), 1.0, 16)
    for j in range(10):
        a, _ = big.measure(np.zeros(len(RUNS)), float(j))
        b, _ = alone.measure(np.zeros(1), float(j))
        assert a[2] == b[0]


@pytest.mark.parametrize("dist", ["gaussian", "uniform"])
def test_errors_in_distribution(dist):
    """Over 4000 runs x 25 samples the error has mean 0 and the model's standard deviation
    (gaussian sigma; uniform k sigma / sqrt 3 on +-k sigma), within 5 standard errors."""
    sigma, n, k = 0.5, 4000, 25
    model = ErrorModel(distribution=dist, sigma=sigma, uniform_k=3.0)
    ahead = PrefetchedErrors(ErrorProcess(model, 5, tuple(range(n)), PATH), 1.0, 10)
    e = np.stack([ahead.measure(np.zeros(n), float(j))[0] for j in range(k)])
    std = model.noise_std
    m = e.size
    assert abs(e.mean()) < 5 * std / math.sqrt(m)
    assert abs(e.var() / std**2 - 1) < 5 * math.sqrt(2 / m)
    if dist == "uniform":
        assert np.abs(e).max() <= 3 * sigma


def test_usbl_fixes_equal_the_device_sampled_one_at_a_time():
    cfg = UsblConfig(dropout_probability=0.2, max_range_m=60.0, processing_delay_s=1.0)
    trans = np.array([0.0, 0.0, -6.0])
    dev = Usbl(cfg, trans, 3, RUNS)
    batch = BatchUsbl(Usbl(cfg, trans, 3, RUNS), block=4)
    rng = np.random.default_rng(6)
    for j in range(11):
        t = 5.0 * j
        pos = rng.normal(0, 40, (len(RUNS), 3))
        pos[0] = trans + [0.0, 0.0, 0.5]  # straight above: folded over the zenith
        want = dev.measure(np.array([t]), pos[:, None, :])
        got = batch.measure(t, pos)
        assert np.array_equal(got[0], want[0][:, 0])
        assert np.array_equal(got[1], want[1][:, 0])
        np.testing.assert_allclose(got[2], want[2][:, 0], rtol=1e-15)
    assert not want[1].all() and want[1].any()
