"""Reductions of seed 003's tracks to the paper's statistics and to consistency sums: per-run sums
that merge over blocks of runs in run order (so pooled statistics do not depend on the block split),
and the pooled statistics of Tables 1-3 (maximum, arithmetic mean, standard deviation of the
distance to the reference, every 10 Hz sample of every run pooled).

Arrays carry a leading run axis n; positions are (east, north) in m.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.metrics import nees

Array = NDArray[np.float64]

N_DISTANCE_SUMS = 4
"""Columns of :func:`distance_sums`: count, sum, sum of squares, maximum."""
N_CONSISTENCY_SUMS = 4
"""Columns of :func:`consistency_sums`: fixes, NEES sum, stated trace sum, squared error sum."""


def distances(estimate_m: ArrayLike, reference_m: ArrayLike) -> Array:
    """Horizontal distance of estimates to the reference, shape (n, T + 1), m.

    Args:
        estimate_m: estimates, shape (n, T + 1, 2), m.
        reference_m: the reference track, shape (T + 1, 2) or (n, T + 1, 2), m.
    """
    return np.hypot(*(np.asarray(estimate_m) - reference_m).transpose(2, 0, 1))


def distance_sums(distance_m: ArrayLike) -> Array:
    """Per-run count, sum, sum of squares and maximum of the distance over samples 1..T (at sample
    0 every estimate starts on the reference).

    Args:
        distance_m: distances, shape (n, T + 1), m.

    Returns:
        Shape (n, 4): count, sum (m), sum of squares (m^2), maximum (m).
    """
    w = np.asarray(distance_m, dtype=float)[:, 1:]
    return np.stack(
        [np.full(len(w), w.shape[1], dtype=float), w.sum(1), (w * w).sum(1), w.max(1)], axis=1
    )


def pooled_stats(sums: ArrayLike) -> tuple[float, float, float] | None:
    """Maximum, arithmetic mean and (population) standard deviation of every sample of every run
    from their :func:`distance_sums`.

    Args:
        sums: shape (runs, 4).

    Returns:
        ``(max, mean, std)`` in m, or ``None`` when there is no sample.
    """
    s = np.asarray(sums, dtype=float)
    count, total, sq, mx = (s[:, i] for i in range(4))
    N = count.sum()
    if N <= 0:
        return None
    mean = total.sum() / N
    var = max(sq.sum() / N - mean * mean, 0.0)
    return float(mx.max()), float(mean), math.sqrt(var)


def consistency_sums(error_m: ArrayLike, cov_m2: ArrayLike, accepted: NDArray[np.bool_]) -> Array:
    """Per-run sums that compare a method's stated accuracy at its fixes with its actual error.

    Only accepted fixes with a finite, positive-definite stated covariance count.

    Args:
        error_m: estimate minus reference at each fix, shape (n, K, 2), m.
        cov_m2: the stated covariance at each fix, shape (n, K, 2, 2), m^2.
        accepted: whether each fix was made, shape (n, K).

    Returns:
        Shape (n, 4): fixes counted, sum of their NEES ``e^T C^-1 e`` (:func:`nav.metrics.nees`),
        sum of the stated covariance's trace (m^2) and of the squared error (m^2).
    """
    e = np.asarray(error_m, dtype=float)
    C = np.asarray(cov_m2, dtype=float)
    det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] ** 2
    ok = accepted & np.isfinite(det) & (det > 0) & np.isfinite(C).all(axis=(-1, -2))
    Cs = np.where(ok[..., None, None], C, np.eye(2))
    nees_k = nees(e, Cs)
    tr = Cs[..., 0, 0] + Cs[..., 1, 1]
    e2 = (e * e).sum(-1)
    return np.stack(
        [
            ok.sum(1),
            np.where(ok, nees_k, 0).sum(1),
            np.where(ok, tr, 0).sum(1),
            np.where(ok, e2, 0).sum(1),
        ],
        axis=1,
    ).astype(float)


def longest_gaps(t_fix_s: ArrayLike, accepted: NDArray[np.bool_], t_end_s: float) -> Array:
    """Longest time of each run without an accepted fix, from t = 0 to ``t_end_s``.

    Args:
        t_fix_s: time of each range, shape (K,), s.
        accepted: whether each range made a fix, shape (n, K).
        t_end_s: end of the run, s.

    Returns:
        Shape (n,), s.
    """
    t_fix = np.asarray(t_fix_s, dtype=float)
    gaps = np.empty(len(accepted))
    for i in range(len(accepted)):
        times = np.concatenate([[0.0], t_fix[accepted[i]], [t_end_s]])
        gaps[i] = np.max(np.diff(times))
    return gaps
