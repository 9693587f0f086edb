"""Metrics: chi-square bands, accumulators that merge like the whole."""

import numpy as np
import pytest

from nav.metrics import Histogram, SeriesSum, nees, nees_band, series_stats


@pytest.mark.parametrize(
    ("dim", "n", "lo", "hi"),
    [(2, 50, 1.48, 2.59), (2, 100, 1.63, 2.41), (3, 100, 2.54, 3.50), (3, 1000, 2.85, 3.15)],
)
def test_nees_band_matches_tabulated_values(dim, n, lo, hi):
    a, b = nees_band(dim, n)
    assert a == pytest.approx(lo, abs=0.01) and b == pytest.approx(hi, abs=0.01)


def test_nees_of_gaussian_samples_averages_dim():
    rng = np.random.default_rng(4)
    A = rng.normal(0, 1, (3, 3))
    P = A @ A.T + np.eye(3)
    e = rng.multivariate_normal(np.zeros(3), P, 200_000)
    assert nees(e, np.broadcast_to(P, (len(e), 3, 3))).mean() == pytest.approx(3.0, rel=0.01)


def test_series_sum_merges_like_the_whole():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(10, 7))
    p = rng.random((10, 7)) > 0.3
    whole = SeriesSum.of(v, p)
    merged = SeriesSum.of(v[:4], p[:4]).merge(SeriesSum.of(v[4:], p[4:]))
    assert np.allclose(whole.total, merged.total) and np.array_equal(whole.count, merged.count)
    expected = np.array([v[p[:, k], k].mean() if p[:, k].any() else np.nan for k in range(7)])
    assert np.allclose(whole.mean(), expected, equal_nan=True)


def test_histogram_counts_and_overflow():
    edges = np.arange(0.0, 5.0)
    h = Histogram.of(np.array([0.5, 1.5, 1.6, 10.0, -1.0]), edges)
    assert h.counts.tolist() == [2, 2, 0, 1]  # -1 clipped into the first, 10 into the last bin
    assert h.merge(h).counts.sum() == 10


def test_series_stats_ignores_absent():
    st = series_stats(np.array([5.0, 1.0, 3.0, 100.0]), np.array([True, True, True, False]))
    assert (st.min, st.max, st.mean) == (1.0, 5.0, 3.0)
    assert np.isnan(series_stats(np.array([1.0]), np.array([False])).mean)
