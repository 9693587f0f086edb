"""``nav.distributions`` against the ``scipy.stats`` functions it replaces."""

import numpy as np
import pytest
from scipy.stats import chi2, rice

from nav.distributions import chi2_ppf, rice_cdf


def test_equals_scipy_stats_bit_for_bit() -> None:
    p = np.concatenate(
        [
            [0.0, 1e-12, 0.005, 0.025, 0.5, 0.95, 0.975, 0.99, 0.999, 0.9999, 1.0],
            np.linspace(0, 1, 97),
        ]
    )
    for k in (1, 2, 3, 4, 6, 9, 16, 48, 300, 2.5):
        got = chi2_ppf(p, k)
        want = chi2.ppf(p, k)
        np.testing.assert_array_equal(got, want)  # NaN-aware, exact
        assert got.tobytes() == np.asarray(want, dtype=float).tobytes()


def test_known_values_and_invalid() -> None:
    # Tables: chi2(0.95, 1) = 3.841, chi2(0.95, 2) = -2 ln 0.05 = 5.991 (closed form for k = 2).
    assert chi2_ppf(0.95, 1) == pytest.approx(3.841458820694124, rel=1e-14)
    assert chi2_ppf(0.95, 2) == pytest.approx(-2 * np.log(0.05), rel=1e-14)
    assert np.isnan(chi2_ppf(1.5, 3)) and np.isnan(chi2_ppf(-0.1, 3))
    assert np.isnan(chi2_ppf(0.5, 0)) and np.isnan(chi2_ppf(0.5, -1))
    assert np.isnan(chi2.ppf(0.5, 0)) and np.isnan(chi2.ppf(1.5, 3))  # the same as scipy's


def test_rice_cdf_equals_scipy_stats_bit_for_bit() -> None:
    rng = np.random.default_rng(7)
    for _ in range(2000):
        s = float(rng.uniform(0.01, 20.0))
        d = float(rng.uniform(0.0, 30.0))
        r = float(rng.uniform(0.0, 40.0))
        assert rice_cdf(r, d / s, scale=s) == float(rice.cdf(r, d / s, scale=s))
    for r, b, s in ((0.0, 1.0, 2.0), (-1.0, 1.0, 2.0), (np.inf, 1.0, 2.0), (3.0, 0.0, 1.5)):
        assert rice_cdf(r, b, scale=s) == float(rice.cdf(r, b, scale=s))
    for r, b, s in ((1.0, -1.0, 1.0), (1.0, 1.0, 0.0), (np.nan, 1.0, 1.0)):
        assert np.isnan(rice_cdf(r, b, scale=s)) and np.isnan(rice.cdf(r, b, scale=s))


def test_rice_cdf_rayleigh_case() -> None:
    # b = 0: Rayleigh, P(R <= x) = 1 - exp(-x^2 / (2 s^2)).
    for x, s in ((1.0, 1.0), (2.5, 1.3), (0.1, 3.0)):
        assert rice_cdf(x, 0.0, scale=s) == pytest.approx(
            -np.expm1(-(x**2) / (2 * s**2)), rel=1e-12
        )
