"""Estimate-versus-truth metrics: distances, per-passage statistics, NEES and its chi-square band,
and accumulators that reduce a batch block by block without holding the paths."""

from __future__ import annotations

from dataclasses import dataclass

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


def nees_band(dim: int, n_runs: int, probability: float = 0.95) -> tuple[float, float]:
    """Two-sided band of the NEES averaged over ``n_runs`` consistent runs.

    The sum of ``n_runs`` NEES values of dimension ``dim`` is chi-square with ``n_runs * dim``
    degrees of freedom (Bar-Shalom, Li & Kirubarajan 2001, section 5.4).

    Returns:
        ``(low, high)`` for the average.
    """
    from scipy.stats import chi2  # imported here: the metrics alone do not need it

    k = dim * n_runs
    a = (1.0 - probability) / 2.0
    return float(chi2.ppf(a, k) / n_runs), float(chi2.ppf(1.0 - a, k) / n_runs)


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
