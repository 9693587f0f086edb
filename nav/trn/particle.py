"""The particle filter of terrain-relative navigation (horizontal position).

Particles ``x_j`` (east, north) with weights ``w_j``:

* **predict**: ``x_j <- x_j + d + L n_j``, ``n_j ~ N(0, I)``, ``L L^T = Q`` (the dead-reckoned
  displacement ``d`` over the step and its covariance ``Q``, from the DVL or the log);
* **update**: ``w_j <- w_j p(z | x_j)`` with the bias-marginalised Gaussian likelihood of
  :mod:`nav.trn.likelihood`, normalised in the log domain; the ping's NIS against the weighted
  prediction enters the divergence window;
* **divergence**: when the window's NIS sum exceeds its chi-square quantile, the particles are
  re-drawn from ``N(mean, P + reinit_sigma^2 I)`` around the current estimate with equal weights
  (mbtrnav's ``TerrainNav::reinitFilter`` re-creates its filter over an initialisation window
  around the navigation estimate and counts ``numReinits``), or around a point the caller gives
  (:meth:`ParticleTrn.reinitialise`, e.g. the dead-reckoned position);
* **resampling**: systematic (Kitagawa 1996; one uniform draw, N evenly spaced pointers into the
  weights' cumulative distribution) when the effective sample size ``1 / sum w^2`` falls below
  ``resample_threshold * N``, then roughening (Gordon, Salmond & Smith 1993, section 4.1):
  ``N(0, (K E_a N^(-1/2))^2)`` jitter along each axis, ``E_a`` the particles' span along it.

References:
    Gordon, Salmond & Smith (1993), *Novel approach to nonlinear/non-Gaussian Bayesian state
    estimation*, IEE Proc. F 140(2). Kitagawa (1996), *Monte Carlo filter and smoother for
    non-Gaussian nonlinear state space models*, JCGS 5(1). MB-System ``src/mbtrnav``
    (``TNavParticleFilter.cpp``, ``TerrainNav.cpp``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.trn.likelihood import (
    DivergenceWindow,
    innovation_nis,
    log_likelihood,
    normalise_log_weights,
    ping_inputs,
)
from nav.trn.map import TerrainMap
from nav.trn.options import TrnOptions, TrnUpdate, check_gaussian
from nav.trn.soundings import Soundings

Array = NDArray[np.float64]


def systematic_resample(weights: Array, rng: np.random.Generator) -> NDArray[np.intp]:
    """Indices of a systematic resampling (Kitagawa 1996).

    Args:
        weights: normalised weights, shape ``(n,)``.
        rng: one uniform draw is taken from it.

    Returns:
        ``(n,)`` indices into ``weights``, sorted.
    """
    n = weights.size
    cdf = np.cumsum(weights)
    cdf[-1] = 1.0  # rounding: every pointer finds a particle
    pointers = (rng.random() + np.arange(n)) / n
    return np.searchsorted(cdf, pointers, side="right").clip(0, n - 1)


def _gaussian_draw(rng: np.random.Generator, mean: Array, cov: Array, n: int) -> Array:
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))
    return mean + rng.standard_normal((n, 2)) @ root.T


class ParticleTrn:
    """Terrain-relative navigation with a particle filter (module docstring).

    Args:
        options: the filter's options (``particles``, resampling, divergence, bias).
        x0_m: initial mean (east, north), shape ``(2,)``, m.
        P0_m2: initial covariance, shape ``(2, 2)``, m^2.
        rng: the generator every draw comes from, or a seed for one.

    Attributes:
        reinitialisations: re-initialisations so far (by divergence or by the caller).

    Raises:
        NavInputError: bad options, mean or covariance.
    """

    def __init__(
        self,
        options: TrnOptions,
        x0_m: ArrayLike,
        P0_m2: ArrayLike,
        rng: np.random.Generator | int,
    ):
        self.options = options
        x0, p0 = check_gaussian("x0_m", x0_m, "P0_m2", P0_m2)
        self._rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        n = options.particles
        self.particles = _gaussian_draw(self._rng, x0, p0, n)
        self.weights = np.full(n, 1.0 / n)
        self._window = DivergenceWindow(options.nis_window, options.divergence_probability)
        self.reinitialisations = 0
        self.resamplings = 0

    def predict(self, displacement_m: ArrayLike, covariance_m2: ArrayLike) -> None:
        """Move every particle by the displacement plus a draw of its noise.

        Args:
            displacement_m: dead-reckoned displacement over the step (east, north), ``(2,)``, m.
            covariance_m2: its covariance ``Q``, ``(2, 2)``, m^2.

        Raises:
            NavInputError: a non-finite displacement or a bad covariance.
        """
        d, q = check_gaussian("displacement_m", displacement_m, "covariance_m2", covariance_m2)
        self.particles = _gaussian_draw(self._rng, self.particles + d, q, self.particles.shape[0])

    def update(
        self, terrain_map: TerrainMap, soundings: Soundings, sigma_m: float | ArrayLike
    ) -> TrnUpdate:
        """Weight the particles by one ping's soundings against the map.

        Args:
            terrain_map: the navigator's map.
            soundings: the ping's soundings (:func:`nav.trn.soundings`).
            sigma_m: each beam's depth standard deviation, float or ``(m,)``, m (the map's
                ``sigma_m`` is added in quadrature).

        Returns:
            The update's diagnostics; with no usable beam the filter is unchanged.

        Raises:
            NavInputError: a bad ``sigma_m``.
        """
        opt = self.options
        z, off, s = ping_inputs(soundings, sigma_m, terrain_map.sigma_m)
        if z.size == 0:
            return TrnUpdate(0.0, self.ess, False, False, 0)
        ll, h, ok = log_likelihood(
            self.particles, terrain_map, z, off, s, opt.sigma_bias_m, self.weights
        )
        used = int(ok.any(axis=0).sum())
        if used == 0:
            return TrnUpdate(0.0, self.ess, False, False, 0)
        nis, dof = innovation_nis(self.weights, h, ok, z, s, opt.sigma_bias_m)
        with np.errstate(divide="ignore"):  # a weight that underflowed to 0 stays 0
            log_w = np.log(self.weights)
        self.weights = normalise_log_weights(log_w + ll)
        ess = self.ess
        diverged = self._window.push(nis, dof)
        reinit = diverged and opt.reinitialise
        if reinit:
            self.reinitialise()
        elif ess < opt.resample_threshold * self.weights.size:
            self._resample()
        return TrnUpdate(nis, ess, diverged, reinit, used, dof)

    @property
    def ess(self) -> float:
        """Effective sample size ``1 / sum w^2`` of the current weights."""
        return float(1.0 / np.dot(self.weights, self.weights))

    def _resample(self) -> None:
        n = self.weights.size
        idx = systematic_resample(self.weights, self._rng)
        p = self.particles[idx]
        k = self.options.roughening
        if k > 0.0:
            span = p.max(axis=0) - p.min(axis=0)
            p = p + self._rng.standard_normal(p.shape) * (k * span * n**-0.5)
        self.particles = p
        self.weights = np.full(n, 1.0 / n)
        self.resamplings += 1

    def reinitialise(
        self, center_m: ArrayLike | None = None, covariance_m2: ArrayLike | None = None
    ) -> None:
        """Spread the particles afresh, with equal weights, and count it.

        Args:
            center_m: centre of the new spread (east, north), ``(2,)``, m; default the current
                estimate.
            covariance_m2: covariance of the new spread, ``(2, 2)``, m^2; default the current
                estimate's plus ``reinit_sigma_m^2 I``.
        """
        mean, cov = self.estimate()
        if center_m is not None or covariance_m2 is not None:
            c = mean if center_m is None else center_m
            p = (
                cov + self.options.reinit_sigma_m**2 * np.eye(2)
                if covariance_m2 is None
                else covariance_m2
            )
            mean, cov = check_gaussian("center_m", c, "covariance_m2", p)
        else:
            cov = cov + self.options.reinit_sigma_m**2 * np.eye(2)
        n = self.weights.size
        self.particles = _gaussian_draw(self._rng, mean, cov, n)
        self.weights = np.full(n, 1.0 / n)
        self._window.clear()
        self.reinitialisations += 1

    def estimate(self) -> tuple[Array, Array]:
        """Weighted mean and covariance of the particles.

        Returns:
            ``(mean (2,), covariance (2, 2))``, m and m^2.
        """
        w = self.weights
        mean = w @ self.particles
        dev = self.particles - mean
        cov = (dev * w[:, None]).T @ dev
        return mean, 0.5 * (cov + cov.T)
