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


def test_chi2_quantile_closed_forms_and_scipy():
    """Two degrees of freedom: ``x = -2 log(1 - p)``; one: the square of the normal quantile of
    ``(1 + p) / 2`` (and ``pi p^2 / 2`` near zero); elsewhere scipy's ``chi2.ppf`` (Cephes), up
    to three million degrees of freedom (the band of a million 3-D runs)."""
    from statistics import NormalDist

    from scipy.stats import chi2

    from nav.metrics import chi2_ppf

    for p in (1e-12, 1e-6, 0.001, 0.025, 0.3, 0.5, 0.95, 0.975, 0.999, 1 - 1e-9):
        assert chi2_ppf(p, 2) == pytest.approx(-2.0 * np.log1p(-p), rel=1e-14, abs=0)
        if p >= 0.001:  # (1 + p) / 2 keeps p to 1e-13; (1 - p) / 2 is exact above 1/2
            z = NormalDist().inv_cdf((1 - p) / 2 if p > 0.5 else (1 + p) / 2)
            assert chi2_ppf(p, 1) == pytest.approx(z * z, rel=1e-12, abs=0)
    # and near zero, where P(1/2, x/2) = sqrt(2x / pi) (1 - x/6 + ...)
    assert chi2_ppf(1e-12, 1) == pytest.approx(np.pi / 2 * 1e-24, rel=1e-14, abs=0)
    for dof in (0.5, 1, 3, 7, 20, 99, 100, 101, 300, 30_000, 300_000, 3_000_000):
        for p in (1e-10, 0.001, 0.025, 0.5, 0.95, 0.975, 0.999):
            if p == 1e-10 and dof > 1e6:
                continue  # scipy is off there (below)
            assert chi2_ppf(p, dof) == pytest.approx(chi2.ppf(p, dof), rel=2e-12, abs=0)
    # P(1.5e6, x / 2) of this x, summed in 40-digit arithmetic (the power series), is
    # 9.99999999998898e-11; scipy's 2984444.26455415 gives 1.0000064e-10
    assert chi2_ppf(1e-10, 3_000_000) == pytest.approx(2984444.2621490527, rel=1e-13, abs=0)
    np.testing.assert_allclose(chi2_ppf(np.array([0.1, 0.9]), 3), chi2.ppf([0.1, 0.9], 3), 1e-14)
    assert chi2_ppf(0.0, 3) == 0.0 and chi2_ppf(1.0, 3) == np.inf
    assert np.isnan(chi2_ppf(1.5, 3)) and np.isnan(chi2_ppf(0.5, 0))


def test_first_exceedance_is_the_first_time_beyond_the_limit():
    from nav.metrics import first_exceedance

    t = np.arange(6) * 0.5
    assert first_exceedance(t, np.array([0.0, 1.0, 2.0, 0.5, 3.0, 0.0]), 1.5) == 1.0
    assert first_exceedance(t, np.array([0.0, 1.0, 1.5, 0.5, 1.5, 0.0]), 1.5) is None
    assert first_exceedance(t, np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0]), 1.5) == 0.5
