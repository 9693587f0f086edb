"""The TRN measurement likelihood, its normalised innovation and the divergence test.

**Measurement model.** A ping's soundings ``z_i`` (depths at the horizontal offsets ``o_i`` from
the reference point, :mod:`nav.trn.soundings`) are, for the position hypothesis ``x``,

    z_i = h(x + o_i) + b + e_i,   e_i ~ N(0, s_i^2),   b ~ N(0, sigma_b^2)

with ``h`` the map's bilinear depth, ``s_i^2`` the beam's variance plus the map's, and ``b`` a
bias common to the ping's beams (the map's vertical offset, a tide or pressure-sensor error).

**Map offset: marginalised per ping, not a state.** Integrating ``b`` out analytically gives the
Gaussian likelihood of the innovations ``e_i = z_i - h(x + o_i)`` with the correlated covariance
``R = D + sigma_b^2 1 1^T`` (``D = diag(s_i^2)``), whose inverse and determinant follow from
Sherman-Morrison and the matrix determinant lemma in O(m):

    e^T R^-1 e = sum a_i e_i^2 - sigma_b^2 (sum a_i e_i)^2 / (1 + sigma_b^2 sum a_i),  a_i = 1/s_i^2
    log det R  = sum log s_i^2 + log(1 + sigma_b^2 sum a_i).

Why this and not a depth-bias state: the state stays 2-D, so the point-mass grid stays 2-D (a
third axis would multiply its cost by the bias grid's size) and the particles do not need a bias
dimension that resampling would collapse; a per-ping bias also absorbs a slowly varying offset
(tide) that a constant-bias state would need its own process noise for. The price: a ping's
information about position comes only from the beams' depth differences (one degree of freedom
per ping goes to the bias), so a single altimeter beam carries almost none when ``sigma_b`` is
large. As ``sigma_b -> inf`` the quadratic form becomes mbtrnav's "contour matching" weight
``exp(-1/2 (SSE - b_hat sum a_i e_i))`` with ``b_hat`` the per-particle weighted mean error
(``TNavParticleFilter.cpp``, ``USE_CONTOUR_MATCHING``).

**Beams off the map.** A beam whose hit point is off the map or on a cell without data is left out
of that hypothesis's likelihood and replaced by the weighted mean likelihood of that beam over the
hypotheses that do predict it, so a hypothesis neither gains nor loses, relative to the others, by
a beam it cannot predict: mbtrnav scales the weight of the particles outside a beam's "sub-cloud"
by the sub-cloud's mean update alike (``TNavParticleFilter.cpp``). A beam that no hypothesis can
predict is not used; a hypothesis that predicts no beam keeps its weight relative to the mean.

**Innovation and divergence.** The ping's NIS is ``nu^T S^-1 nu`` with ``nu = z - sum_j w_j h_j``
over the beams every weighted hypothesis predicts and ``S = Cov_w(h) + R`` (mbtrnav's
``TNavFilter::calculateNIS``). Summed over a window of pings it is chi-square with the summed
degrees of freedom for a consistent filter; mbtrnav re-initialises when the windowed NIS average
exceeds a fixed 1.4 per beam (``MAX_NIS_VALUE``); here the threshold is the chi-square quantile at
a stated false-alarm probability (:class:`DivergenceWindow`).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError
from nav.trn.map import TerrainMap
from nav.trn.options import beam_sigmas
from nav.trn.soundings import Soundings

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_LOG_2PI = math.log(2.0 * math.pi)


def log_likelihood(
    points_m: Array,
    terrain_map: TerrainMap,
    z_m: Array,
    offset_m: Array,
    s_m: Array,
    sigma_bias_m: float,
    weights: Array | None = None,
) -> tuple[Array, Array, BoolArray]:
    """Log-likelihood of one ping's soundings at position hypotheses (module docstring).

    The quadratic form is split into per-beam terms with the hypothesis's bias estimate
    ``b_j = sigma_b^2 sum a_i e_ij / (1 + sigma_b^2 sum a_i)`` (the posterior mean of the bias):
    ``e^T R^-1 e = sum a_i (e_ij - b_j)^2 + b_j^2 / sigma_b^2`` (completing the square), so that
    a beam a hypothesis cannot predict is replaced by the weighted mean likelihood of that beam's
    term over the hypotheses that predict it. Terms common to all hypotheses are left out (the
    result is a log-likelihood up to a constant of the ping).

    Args:
        points_m: position hypotheses (east, north), shape ``(n, 2)``, m.
        terrain_map: the navigator's map.
        z_m: measured depths of the beams used, shape ``(m,)``, m.
        offset_m: their horizontal offsets, shape ``(m, 2)``, m.
        s_m: their standard deviations (beam and map), shape ``(m,)``, m.
        sigma_bias_m: prior standard deviation of the ping's common bias, m.
        weights: prior weights of the hypotheses, ``(n,)`` (default equal), for the beams some
            hypotheses cannot predict.

    Returns:
        ``(loglik (n,), predicted (n, m), ok (n, m))``: the log-likelihood (finite), the map's
        depth at each hit point (0 where not ok) and whether the map defines it.
    """
    hx = points_m[:, 0:1] + offset_m[None, :, 0]
    hy = points_m[:, 1:2] + offset_m[None, :, 1]
    h, ok = terrain_map.depth(hx, hy)
    a = 1.0 / (s_m * s_m)
    sb2 = sigma_bias_m * sigma_bias_m
    if ok.all():  # the hot path: every hypothesis predicts every beam (constants left out)
        e = z_m[None, :] - h
        bias = (sb2 / (1.0 + sb2 * a.sum())) * (e @ a)
        r = e - bias[:, None]
        ll = -0.5 * ((r * r) @ a)
        if sb2 > 0.0:
            ll -= (0.5 / sb2) * bias * bias
        return ll, h, ok
    e = np.where(ok, z_m[None, :] - h, 0.0)
    aok = ok * a[None, :]
    sum_a = aok.sum(axis=1)
    denom = 1.0 + sb2 * sum_a
    bias = sb2 * (aok * e).sum(axis=1) / denom
    r = e - bias[:, None]
    per_beam = -0.5 * (a[None, :] * r * r + np.log(s_m * s_m)[None, :] + _LOG_2PI)
    # the determinant's term log(1 + sigma_b^2 sum a_i) is the same for every hypothesis that
    # predicts every beam and is left out, so that one predicting fewer beams is not favoured
    shared = -0.5 * (bias * bias / sb2) if sb2 > 0.0 else 0.0
    ll = shared + np.where(ok, per_beam, 0.0).sum(axis=1)
    missing = ~ok
    if missing.any():
        w = np.full(ok.shape[0], 1.0 / ok.shape[0]) if weights is None else weights
        beams = missing.any(axis=0) & ok.any(axis=0)
        wb = w[:, None] * ok[:, beams]
        top = np.where(ok[:, beams], per_beam[:, beams], -np.inf).max(axis=0)
        mean_lik = (wb * np.exp(np.where(ok[:, beams], per_beam[:, beams] - top, -np.inf))).sum(
            axis=0
        )
        mass = wb.sum(axis=0)
        fill = np.full(ok.shape[1], 0.0)
        good = mass > 0.0
        fill_b = np.where(
            good, top + np.log(np.where(good, mean_lik / np.where(good, mass, 1.0), 1.0)), 0.0
        )
        fill[beams] = fill_b
        ll = ll + (missing * fill[None, :]).sum(axis=1)
    return ll, h, ok


def normalise_log_weights(log_w: Array) -> Array:
    """Weights ``exp(log_w)`` normalised to sum 1, computed without overflow (finite input)."""
    w = np.exp(log_w - log_w.max())
    return w / w.sum()


def innovation_nis(
    weights: Array, predicted: Array, ok: BoolArray, z_m: Array, s_m: Array, sigma_bias_m: float
) -> tuple[float, int]:
    """The ping's normalised innovation squared against the weighted prediction.

    Args:
        weights: prior weights of the hypotheses, shape ``(n,)``, summing to 1.
        predicted: predicted depths, shape ``(n, m)``, m.
        ok: where they are defined, shape ``(n, m)``.
        z_m: measured depths, ``(m,)``, m.
        s_m: beam standard deviations, ``(m,)``, m.
        sigma_bias_m: prior standard deviation of the common bias, m.

    Returns:
        ``(nis, dof)``: over the beams that every hypothesis holding weight predicts, provided the
        hypotheses that predict them all hold at least half the weight; ``(0.0, 0)`` otherwise.
    """
    if ok.all():  # the hot path: every hypothesis predicts every beam
        beams = np.ones(ok.shape[1], dtype=bool)
        mean = weights @ predicted
        spread = (predicted.T * weights) @ predicted - np.outer(mean, mean)
    else:
        beams = (weights @ ok) >= 1.0 - 1e-9
        if not beams.any():
            return 0.0, 0
        all_ok = ok[:, beams].all(axis=1)
        mass = float(weights[all_ok].sum())
        if mass < 0.5:
            return 0.0, 0
        w = weights[all_ok] / mass
        h = predicted[all_ok][:, beams]
        mean = w @ h
        dev = h - mean
        spread = (dev * w[:, None]).T @ dev
    s = s_m[beams]
    cov = spread + np.diag(s * s) + sigma_bias_m * sigma_bias_m
    nu = z_m[beams] - mean
    nis = float(nu @ np.linalg.solve(cov, nu))
    return (nis, int(beams.sum())) if math.isfinite(nis) else (0.0, 0)


class DivergenceWindow:
    """The windowed NIS test: diverged when the last ``length`` pings' NIS sum exceeds the
    chi-square quantile ``1 - probability`` of their summed degrees of freedom.

    Args:
        length: pings in the window (the test runs once the window is full).
        probability: false-alarm probability of one test for a consistent filter.
    """

    def __init__(self, length: int, probability: float):
        self.length = length
        self.probability = probability
        self._nis: deque[tuple[float, int]] = deque(maxlen=length)
        self._limits: dict[int, float] = {}

    def clear(self) -> None:
        """Forget the window (after a re-initialisation)."""
        self._nis.clear()

    def push(self, nis: float, dof: int) -> bool:
        """Add one ping's NIS (skipped when ``dof`` is 0); True when the full window diverged."""
        if dof <= 0:
            return False
        self._nis.append((nis, dof))
        if len(self._nis) < self.length:
            return False
        total = sum(v for v, _ in self._nis)
        dof_sum = sum(d for _, d in self._nis)
        if dof_sum not in self._limits:
            from scipy.stats import chi2  # imported at the first full window

            self._limits[dof_sum] = float(chi2.ppf(1.0 - self.probability, dof_sum))
        return bool(total > self._limits[dof_sum])


def ping_inputs(
    soundings: Soundings, sigma_m: float | Array, map_sigma_m: float
) -> tuple[Array, Array, Array]:
    """The valid beams' depths ``(m',)``, offsets ``(m', 2)`` and standard deviations ``(m',)``
    (beam and map), m; beams with non-finite numbers are dropped.

    Raises:
        NavInputError: soundings whose arrays do not match, or a bad ``sigma_m``.
    """
    valid = np.asarray(soundings.valid, dtype=bool)
    m = valid.shape[0] if valid.ndim == 1 else -1
    if m < 0 or np.shape(soundings.depth_m) != (m,) or np.shape(soundings.offset_m) != (m, 2):
        raise NavInputError(
            f"soundings with offset_m {np.shape(soundings.offset_m)}, depth_m "
            f"{np.shape(soundings.depth_m)}, valid {valid.shape}: must be (m, 2), (m,), (m,)"
        )
    s_all = beam_sigmas(sigma_m, m, map_sigma_m)
    keep = valid & np.isfinite(soundings.depth_m) & np.all(np.isfinite(soundings.offset_m), axis=1)
    return (
        np.asarray(soundings.depth_m, dtype=float)[keep],
        np.asarray(soundings.offset_m, dtype=float)[keep],
        s_all[keep],
    )
