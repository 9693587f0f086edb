"""Estimate-versus-truth metrics: distances, per-passage statistics, NEES and its chi-square band,
and accumulators that reduce a batch block by block without holding the paths."""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def horizontal_distance(est: Array, truth: Array) -> Array:
    """Horizontal distance between positions, shape (...), m (inputs (..., 2 or 3))."""
    d = np.asarray(est)[..., :2] - np.asarray(truth)[..., :2]
    return np.hypot(d[..., 0], d[..., 1])


def distance_3d(est: Array, truth: Array) -> Array:
    """Euclidean distance between positions, shape (...), m (inputs (..., 3))."""
    return np.linalg.norm(np.asarray(est) - np.asarray(truth), axis=-1)


def first_exceedance(t_s: Array, error_m: Array, limit_m: float) -> float | None:
    """The first time an estimate's error exceeds a limit (the estimate has run away).

    Args:
        t_s: times, shape (T,), s.
        error_m: the estimate's error against the truth at those times, shape (T,), m.
        limit_m: the limit, m.

    Returns:
        The first ``t_s[k]`` with ``error_m[k] > limit_m``, or ``None`` if there is none (a
        non-finite error counts as beyond any limit).
    """
    e = np.asarray(error_m, dtype=float)
    over = ~(e <= limit_m)
    if not over.any():
        return None
    return float(np.asarray(t_s, dtype=float)[int(np.argmax(over))])


def nees(err: Array, P: Array) -> Array:
    """Normalised estimation error squared ``e^T P^-1 e``.

    Args:
        err: estimate minus truth, shape (..., d).
        P: the estimate's covariance, shape (..., d, d).

    Returns:
        Shape (...).
    """
    return np.einsum("...i,...i->...", err, np.linalg.solve(P, err[..., None])[..., 0])


def chi2_ppf(probability: float | Array, dof: float | Array) -> float | Array:
    """Quantile of the chi-square distribution with ``dof`` degrees of freedom.

    ``x = 2 P^-1(dof / 2, probability)`` with ``P(a, x)`` the regularised lower incomplete gamma
    function, solved here in double precision (:func:`_gamma_p_inverse`; equal to
    ``scipy.stats.chi2.ppf`` to 1e-12 relative, tested) so that a report's NEES band and the
    gates' limits do not import scipy (``scipy.special`` alone takes 0.2 s of CPU, on the
    critical path of a short batch: issue 13).

    Args:
        probability: lower-tail probability in [0, 1], scalar or array.
        dof: degrees of freedom (> 0), scalar or array broadcast with ``probability``.

    Returns:
        The quantile, a float for scalar arguments, else an array of the broadcast shape;
        ``inf`` for probability 1, ``0`` for probability 0, NaN outside [0, 1].
    """
    p, k = np.broadcast_arrays(np.asarray(probability, dtype=float), np.asarray(dof, dtype=float))
    out = np.array(
        [2.0 * _gamma_p_inverse(kk / 2.0, pp) for pp, kk in zip(p.ravel(), k.ravel(), strict=True)]
    ).reshape(p.shape)
    return float(out) if out.ndim == 0 else out


def _gamma_p_q(a: float, x: float) -> tuple[float, float]:
    """Regularised incomplete gamma functions ``(P(a, x), Q(a, x))``, ``P + Q = 1``.

    The one computed directly is the smaller: ``P`` by its power series
    ``P = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1) ... (a + n))`` for ``x < a + 1``, ``Q``
    by its continued fraction (evaluated with the modified Lentz method) above; the prefactor is
    formed in logarithms (Abramowitz & Stegun 6.5.29 and 6.5.31).
    """
    if x <= 0.0:
        return 0.0, 1.0
    log_prefactor = _log_gamma_density(a, x) + math.log(x)
    eps = 1e-17
    if x < a + 1.0:
        term = total = 1.0 / a
        n = a
        while abs(term) > abs(total) * eps:
            n += 1.0
            term *= x / n
            total += term
        p = total * math.exp(log_prefactor)
        return p, 1.0 - p
    tiny = 1e-300
    b = x + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    i = 0
    while True:
        i += 1
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) <= eps or i > 100_000:
            break
    q = math.exp(log_prefactor) * h
    return 1.0 - q, q


def _log_gamma_density(a: float, x: float) -> float:
    """``log(x^(a - 1) e^-x / Gamma(a))`` (x > 0). For ``a >= 50`` it is written
    ``a (log1p(t) - t) + 1/2 log(a / 2 pi) - log x - Stirling's correction`` with
    ``t = (x - a) / a``, which keeps full precision where ``a log x`` and ``log Gamma(a)`` are
    both ~1e7 and cancel (Abramowitz & Stegun 6.1.41)."""
    if a < 50.0:
        return (a - 1.0) * math.log(x) - x - math.lgamma(a)
    t = (x - a) / a
    a2 = a * a
    stirling = (1.0 / 12.0 - (1.0 / 360.0 - (1.0 / 1260.0 - 1.0 / (1680.0 * a2)) / a2) / a2) / a
    return a * (math.log1p(t) - t) + 0.5 * math.log(a / (2.0 * math.pi)) - math.log(x) - stirling


def _gamma_p_inverse(a: float, p: float) -> float:
    """``x`` with ``P(a, x) = p`` (a > 0): Halley's iteration on the smaller tail, from the
    Wilson-Hilferty cube-root normal approximation, kept inside a shrinking bracket (bisection
    when a step leaves it)."""
    if not (a > 0.0) or not (0.0 <= p <= 1.0):
        return math.nan
    if p == 0.0:
        return 0.0
    if p == 1.0:
        return math.inf
    z = NormalDist().inv_cdf(p)
    h = 1.0 / (9.0 * a)
    x = a * (1.0 - h + z * math.sqrt(h)) ** 3
    if not x > 0.0:  # small a, small p: P ~ x^a / Gamma(a + 1)
        x = math.exp((math.log(p) + math.lgamma(a + 1.0)) / a)
    lo, hi = 0.0, math.inf
    upper = p > 0.5  # solve on Q = 1 - p, the accurate tail
    target = 1.0 - p if upper else p
    for _ in range(200):
        pp, qq = _gamma_p_q(a, x)
        value = (target - qq) if upper else (pp - target)  # increasing in x
        if value == 0.0:
            return x
        if value > 0.0:
            hi = x
        else:
            lo = x
        density = math.exp(_log_gamma_density(a, x))
        step = value / density if density > 0.0 else math.inf
        # Halley: the density's log-derivative is (a - 1) / x - 1
        step /= 1.0 + 0.5 * step * ((a - 1.0) / x - 1.0) if abs(step) < x else 1.0
        new = x - step
        if not (lo < new < hi) or not math.isfinite(new):
            new = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * x
        if abs(new - x) <= 4e-16 * x:
            return new
        x = new
    return x


def nees_band(dim: int, n_runs: int, probability: float = 0.95) -> tuple[float, float]:
    """Two-sided band of the NEES averaged over ``n_runs`` consistent runs.

    The sum of ``n_runs`` NEES values of dimension ``dim`` is chi-square with ``n_runs * dim``
    degrees of freedom (Bar-Shalom, Li & Kirubarajan 2001, section 5.4).

    Returns:
        ``(low, high)`` for the average.
    """
    k = dim * n_runs
    a = (1.0 - probability) / 2.0
    return float(chi2_ppf(a, k) / n_runs), float(chi2_ppf(1.0 - a, k) / n_runs)


@dataclass(frozen=True)
class SeriesStats:
    """Minimum, maximum and mean of one series over its present samples (NaN if none)."""

    min: float
    max: float
    mean: float


def series_stats(values: Array, present: NDArray[np.bool_] | None = None) -> SeriesStats:
    """Statistics of a 1-D series over its present samples (seed 000 tables' three columns)."""
    v = np.asarray(values, dtype=float)
    if present is not None:
        v = v[np.asarray(present, dtype=bool)]
    if v.size == 0:
        return SeriesStats(float("nan"), float("nan"), float("nan"))
    return SeriesStats(float(v.min()), float(v.max()), float(v.mean()))


def _bin_counts(v: Array, edges: Array) -> NDArray[np.int64]:
    """Counts of ``np.histogram(v, bins=edges)`` for values inside the edges, in linear time.

    The bin of each value is first guessed from the mean bin width and then moved by one where
    the guess is off against the edges themselves, so the counts are exactly those of bins
    ``[e_i, e_i+1)`` (numpy's uniform-bin method, here for the given edges rather than its own
    linspace); numpy's general path for explicit edges sorts the values. Tested equal.
    """
    nb = len(edges) - 1
    if nb < 1 or v.size == 0:
        return np.zeros(max(nb, 0), dtype=np.int64)
    width = (edges[-1] - edges[0]) / nb
    idx = np.clip(((v - edges[0]) / width).astype(np.intp), 0, nb - 1)
    # a guess is off by at most one bin for edges of nearly equal width: one correction, then
    # a check (numpy's sorting path if the edges are far from uniform)
    idx -= v < edges[idx]
    idx += (v >= edges[idx + 1]) & (idx < nb - 1)
    if np.any(v < edges[idx]) or np.any((v >= edges[idx + 1]) & (idx < nb - 1)):
        counts, _ = np.histogram(v, bins=edges)  # edges far from uniform
        return counts.astype(np.int64)
    return np.bincount(idx, minlength=nb).astype(np.int64)


def batch_stats(values: Array, present: NDArray[np.bool_] | None = None) -> Array:
    """:func:`series_stats` of each row of a batch at once.

    Args:
        values: series, shape (n, T).
        present: which samples exist, shape (n, T) (default all).

    Returns:
        Shape (n, 3): min, max and mean over each row's present samples; NaN for a row with
        none.
    """
    v = np.asarray(values, dtype=float)
    out = np.empty((v.shape[0], 3))
    if present is None:
        out[:, 0], out[:, 1], out[:, 2] = v.min(axis=1), v.max(axis=1), v.mean(axis=1)
        return out
    p = np.asarray(present, dtype=bool)
    count = p.sum(axis=1)
    out[:, 0] = np.where(p, v, np.inf).min(axis=1)
    out[:, 1] = np.where(p, v, -np.inf).max(axis=1)
    out[:, 2] = np.where(p, v, 0.0).sum(axis=1) / np.maximum(count, 1)
    out[count == 0] = np.nan
    return out


@dataclass
class SeriesSum:
    """Running sum and count of a batch of time series, per time step, mergeable in order.

    ``zeta(k) = sum / count`` is seed 000's mean distance over passages at moment k (eq. 24, read as
    a mean as the figures show).

    Attributes:
        total: sums, shape (T,).
        count: number of present samples summed, shape (T,).
    """

    total: Array
    count: NDArray[np.int64]

    @classmethod
    def of(cls, values: Array, present: NDArray[np.bool_] | None = None) -> SeriesSum:
        """Sum a block of series, shape (n, T), over its runs."""
        v = np.asarray(values, dtype=float)
        p = np.ones(v.shape, dtype=bool) if present is None else np.asarray(present, dtype=bool)
        return cls(np.where(p, v, 0.0).sum(axis=0), p.sum(axis=0).astype(np.int64))

    def merge(self, other: SeriesSum) -> SeriesSum:
        """The sum of two accumulators (merge blocks in block order for bit-identical results)."""
        return SeriesSum(self.total + other.total, self.count + other.count)

    def mean(self) -> Array:
        """Mean per time step, NaN where nothing was present."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.count > 0, self.total / np.maximum(self.count, 1), np.nan)


@dataclass
class Histogram:
    """Counts of values in fixed bins, mergeable; the last bin also counts overflow.

    Attributes:
        edges: bin edges, shape (B + 1,).
        counts: counts, shape (B,).
    """

    edges: Array
    counts: NDArray[np.int64]

    @classmethod
    def of(cls, values: Array, edges: Array, present: NDArray[np.bool_] | None = None) -> Histogram:
        """Histogram of the present values."""
        v = np.asarray(values, dtype=float)
        if present is not None:
            v = v[np.asarray(present, dtype=bool)]
        e = np.asarray(edges, dtype=float)
        v = np.clip(v.ravel(), e[0], np.nextafter(e[-1], -np.inf))
        return cls(e, _bin_counts(v, e))

    def merge(self, other: Histogram) -> Histogram:
        """Sum of two histograms with the same edges."""
        if not np.array_equal(self.edges, other.edges):
            raise ValueError("histograms with different edges cannot merge")
        return Histogram(self.edges, self.counts + other.counts)
