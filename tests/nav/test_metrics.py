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


@pytest.mark.parametrize(
    "edges",
    [
        np.arange(0.0, 50.0 + 0.25, 0.5),  # the reports' edges: arange, not numpy's linspace
        np.arange(0.0, 3.0 + 0.05, 0.1),
        np.array([0.0, 0.1, 0.5, 2.0, 9.0]),  # far from uniform: numpy's own path
    ],
)
def test_histogram_counts_equal_numpys_for_the_given_edges(edges, monkeypatch):
    from nav.metrics import _bin_counts

    g = np.random.default_rng(4)
    v = g.uniform(edges[0], edges[-1], 200_000)
    # values exactly on every edge and one ulp either side: where a guess from the width errs
    on = np.concatenate(
        [edges[:-1], np.nextafter(edges[1:-1], -np.inf), np.nextafter(edges[:-1], np.inf)]
    )
    v = np.concatenate([v, on])
    want, _ = np.histogram(v, bins=edges)
    uniform = np.allclose(np.diff(edges), edges[1] - edges[0])
    if uniform:  # the linear-time path itself, not numpy's sorting one as a fallback
        monkeypatch.setattr(np, "histogram", None)
    assert np.array_equal(_bin_counts(v, edges), want)
    monkeypatch.undo()
    h = Histogram.of(np.concatenate([v, [edges[-1] + 5.0]]), edges)  # overflow into the last bin
    assert h.counts.sum() == v.size + 1 and h.counts[-1] == want[-1] + 1


def test_batch_stats_are_series_stats_row_by_row():
    from nav.metrics import batch_stats

    g = np.random.default_rng(5)
    v = g.gamma(2.0, 3.0, (50, 121))
    present = g.random((50, 121)) < 0.7
    present[3] = False  # a row with no sample: NaN, as series_stats
    present[4] = False
    present[4, 17] = True  # and one with a single sample
    for got, pres in ((batch_stats(v), None), (batch_stats(v, present), present)):
        for i in range(len(v)):
            st = series_stats(v[i], None if pres is None else pres[i])
            np.testing.assert_allclose(got[i], [st.min, st.max, st.mean], rtol=1e-13)
    assert np.isnan(batch_stats(v, present)[3]).all()


def test_nees_band_is_the_chi_square_band_of_the_sum():
    """The band of the NEES averaged over n runs of dimension d: the sum is chi-square with n d
    degrees of freedom. Two degrees of freedom have the closed form ``x = -2 log(1 - p)``, one
    the square of the normal quantile; many are near normal with mean k and variance 2 k."""
    from statistics import NormalDist

    from nav.metrics import nees_band

    for q in (0.9, 0.95, 0.99):
        a = (1 - q) / 2
        lo, hi = nees_band(2, 1, q)
        assert lo == pytest.approx(-2.0 * np.log1p(-a), rel=1e-13, abs=0)
        assert hi == pytest.approx(-2.0 * np.log(a), rel=1e-13, abs=0)
        lo, hi = nees_band(1, 1, q)
        assert lo == pytest.approx(NormalDist().inv_cdf(0.5 + a / 2) ** 2, rel=1e-12, abs=0)
        assert hi == pytest.approx(NormalDist().inv_cdf(1 - a / 2) ** 2, rel=1e-12, abs=0)
        # a million 3-D runs: k = 3e6, the band of the average is 1 -+ z sqrt(2 / k) to 1e-6
        k, z = 3_000_000, NormalDist().inv_cdf(1 - a)
        lo, hi = nees_band(3, 1_000_000, q)
        assert lo / 3 == pytest.approx(1 - z * np.sqrt(2 / k), abs=1e-5)
        assert hi / 3 == pytest.approx(1 + z * np.sqrt(2 / k), abs=1e-5)


def test_first_exceedance_is_the_first_time_beyond_the_limit():
    from nav.metrics import first_exceedance

    t = np.arange(6) * 0.5
    assert first_exceedance(t, np.array([0.0, 1.0, 2.0, 0.5, 3.0, 0.0]), 1.5) == 1.0
    assert first_exceedance(t, np.array([0.0, 1.0, 1.5, 0.5, 1.5, 0.0]), 1.5) is None
    assert first_exceedance(t, np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0]), 1.5) == 0.5
