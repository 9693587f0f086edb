"""Per-vehicle accuracy and consistency of a team's tracks against the truth.

Error: the horizontal distance of the estimate to the truth, pooled over runs and samples (mean,
maximum) and at the last sample (mean over runs). Consistency: the normalised estimation error
squared of the horizontal position, ``NEES = e^T P^-1 e`` (2 degrees of freedom), against the
two-sided chi-square band of the mean of n independent runs, ``[chi2_{a/2}(2 n) / n,
chi2_{1-a/2}(2 n) / n]`` (Bar-Shalom, Li & Kirubarajan 2001, *Estimation with Applications to
Tracking and Navigation*, section 5.4.2; :func:`nav.metrics.nees_band`). The band's sample size is
the number of runs: the samples of one run are correlated and add no independent degrees of
freedom, so the mean NEES pooled over runs and samples is compared with the band of n runs (the
conservative choice), and the fraction of samples whose mean over runs lies in that band is
reported beside it (about 95 % for a consistent filter).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.cooperative.tracks import TeamTracks
from nav.errors import NavInputError
from nav.metrics import nees_band

Array = NDArray[np.float64]


@dataclass(frozen=True)
class VehicleMetrics:
    """One vehicle's accuracy and consistency under one method.

    Attributes:
        vehicle: the vehicle (0: the leader).
        mean_error_m: mean horizontal error over runs and samples (from ``first_sample``), m.
        final_error_m: mean over runs of the error at the last sample, m.
        max_error_m: largest error over runs and samples, m.
        nees: mean NEES (2 dof) over runs and samples with a positive-definite covariance, or
            ``None`` when there is none.
        nees_band: two-sided band of the mean NEES of n runs, ``(low, high)``.
        nees_in_band_fraction: fraction of the samples (with every run's covariance positive
            definite) whose mean NEES over runs lies in the band, or ``None``.
        consistent: ``nees <= nees_band[1]`` (not over-confident), or ``None`` without NEES.
        clock_rmse_s: root mean square error of the clock offset over runs and samples, s, or
            ``None`` when the method has no clock or no true offsets were given.
        runs: n.
        samples: samples per run counted.
    """

    vehicle: int
    mean_error_m: float
    final_error_m: float
    max_error_m: float
    nees: float | None
    nees_band: tuple[float, float]
    nees_in_band_fraction: float | None
    consistent: bool | None
    clock_rmse_s: float | None
    runs: int
    samples: int


def horizontal_errors(tracks: TeamTracks, truth_m: ArrayLike) -> Array:
    """Horizontal distance of every estimate to the truth, shape (n, v, k), m.

    Args:
        tracks: the estimates.
        truth_m: true (east, north), shape (n, v, k, 2) or (n, v, k, 3), m.
    """
    d = tracks.position_m - np.asarray(truth_m, dtype=float)[..., :2]
    return np.hypot(d[..., 0], d[..., 1])


def position_nees(tracks: TeamTracks, truth_m: ArrayLike) -> tuple[Array, NDArray[np.bool_]]:
    """NEES of the horizontal position at every sample, and where it is defined.

    Returns:
        ``(nees (n, v, k), valid (n, v, k))``: ``e^T P^-1 e`` written out for 2 x 2 (zero where
        the covariance is not positive definite or not finite: ``valid`` False).
    """
    e = tracks.position_m - np.asarray(truth_m, dtype=float)[..., :2]
    P = tracks.cov_m2
    a, b, d = P[..., 0, 0], 0.5 * (P[..., 0, 1] + P[..., 1, 0]), P[..., 1, 1]
    det = a * d - b * b
    valid = np.isfinite(det) & (det > 0) & (a > 0) & np.isfinite(e).all(axis=-1)
    safe = np.where(valid, det, 1.0)
    e0, e1 = e[..., 0], e[..., 1]
    value = (d * e0 * e0 - 2.0 * b * e0 * e1 + a * e1 * e1) / safe
    return np.where(valid, value, 0.0), valid


def team_metrics(
    tracks: TeamTracks,
    truth_m: ArrayLike,
    true_offset_s: ArrayLike | None = None,
    first_sample: int = 1,
    probability: float = 0.95,
) -> tuple[VehicleMetrics, ...]:
    """Per-vehicle error and consistency of one method's tracks (the module's statistics).

    Args:
        tracks: the estimates, n runs of v vehicles on k samples.
        truth_m: true positions, shape (n, v, k, 2) (or 3 with the up coordinate), m.
        true_offset_s: true clock offsets, shape (n, v, k), s, or ``None``.
        first_sample: samples before it are left out (sample 0: every method starts from the
            same start).
        probability: the band's two-sided probability.

    Returns:
        One :class:`VehicleMetrics` per vehicle.

    Raises:
        NavInputError: on mismatched shapes or no sample left.
    """
    truth = np.asarray(truth_m, dtype=float)
    n, v, k = tracks.position_m.shape[:3]
    if truth.shape[:3] != (n, v, k) or truth.shape[3] not in (2, 3):
        raise NavInputError(
            f"truth_m must have shape {(n, v, k, 2)} like the tracks, not {truth.shape}"
        )
    if not 0 <= first_sample < k:
        raise NavInputError(f"first_sample must be in 0..{k - 1}, not {first_sample!r}")
    offsets = None
    if true_offset_s is not None:
        offsets = np.asarray(true_offset_s, dtype=float)
        if offsets.shape != (n, v, k):
            raise NavInputError(f"true_offset_s must have shape {(n, v, k)}, not {offsets.shape}")
    err = horizontal_errors(tracks, truth)[:, :, first_sample:]
    nees_all, valid = position_nees(tracks, truth)
    nees_all, valid = nees_all[:, :, first_sample:], valid[:, :, first_sample:]
    band = nees_band(2, n, probability)
    out = []
    for i in range(v):
        ok = valid[:, i]
        count = int(ok.sum())
        mean_nees = float(nees_all[:, i][ok].mean()) if count else None
        full = ok.all(axis=0)  # samples where every run has a covariance
        in_band = None
        if full.any():
            per_sample = nees_all[:, i][:, full].mean(axis=0)
            in_band = float(np.mean((per_sample >= band[0]) & (per_sample <= band[1])))
        clock = None
        if offsets is not None and tracks.has_clock:
            diff = tracks.clock_offset_s[:, i, first_sample:] - offsets[:, i, first_sample:]
            clock = float(np.sqrt(np.mean(diff * diff)))
        out.append(
            VehicleMetrics(
                vehicle=i,
                mean_error_m=float(err[:, i].mean()),
                final_error_m=float(err[:, i, -1].mean()),
                max_error_m=float(err[:, i].max()),
                nees=mean_nees,
                nees_band=band,
                nees_in_band_fraction=in_band,
                consistent=None if mean_nees is None else bool(mean_nees <= band[1]),
                clock_rmse_s=clock,
                runs=n,
                samples=k - first_sample,
            )
        )
    return tuple(out)
