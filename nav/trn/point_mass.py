"""The point-mass (grid) filter of terrain-relative navigation (Bergman 1999).

The density of the horizontal position is held as masses ``w_ij`` on a regular
``grid_points x grid_points`` grid, each mass standing for its cell (``d_x d_y``):

* **predict**: the grid is translated by the dead-reckoned displacement (exact), and the masses
  are convolved with the process noise ``N(0, Q)`` sampled on the grid's lattice (FFT, zero
  padded, no wrap-around). Noise smaller than one cell is accumulated (``pending``) and convolved
  once it reaches one cell along an axis (a sampled Gaussian narrower than a cell has the wrong
  variance); the estimate's covariance includes the pending part;
* **update**: ``w_ij <- w_ij p(z | x_ij)`` with the bias-marginalised likelihood of
  :mod:`nav.trn.likelihood`, normalised in the log domain;
* **re-centring** (Bergman 1999, ch. 4: the grid follows the support of the density): the grid
  is kept centred on the estimate with a half-width of ``grid_sigmas`` standard deviations per
  axis. When a posterior is much narrower than the grid's cells the prior is interpolated
  (bilinear) onto a finer grid around the posterior mean and the same ping is applied again (up
  to three times), so a sharp fix is resolved; when the density outgrows the grid or drifts off
  its centre it is moved onto a new grid, by bilinear interpolation when the new cells are finer
  and by bilinear splatting (mass-conserving) when they are coarser. Each mass's cell adds its
  uniform spread ``d^2 / 12`` per axis to the covariance;
* **divergence and re-initialisation** as :class:`nav.trn.ParticleTrn` (windowed NIS against its
  chi-square quantile, a Gaussian spread around the current estimate, counted).

References:
    Bergman (1999), *Recursive Bayesian Estimation: Navigation and Tracking Applications*,
    Linkoping Studies in Science and Technology, Dissertation 579, ch. 4 (the point-mass filter
    for terrain navigation). Anonsen & Hallingstad (2006), *Terrain aided underwater navigation
    using point mass and particle filters*, IEEE/ION PLANS.
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

_REFINES = 3
"""Re-applications of one ping on finer grids when its posterior is narrower than the cells."""


class PointMassTrn:
    """Terrain-relative navigation with a point-mass filter (module docstring).

    Args:
        options: the filter's options (``grid_points``, ``grid_sigmas``, divergence, bias).
        x0_m: initial mean (east, north), shape ``(2,)``, m.
        P0_m2: initial covariance, shape ``(2, 2)``, m^2.
        rng: accepted for the interface of :class:`nav.trn.ParticleTrn`; the filter draws
            nothing (same inputs, same numbers).

    Attributes:
        reinitialisations: re-initialisations so far.
    """

    def __init__(
        self,
        options: TrnOptions,
        x0_m: ArrayLike,
        P0_m2: ArrayLike,
        rng: np.random.Generator | int | None = None,
    ):
        self.options = options
        x0, p0 = check_gaussian("x0_m", x0_m, "P0_m2", P0_m2)
        n = options.grid_points
        self._h = 0.5 * (n - 1)
        self._idx = np.arange(n) - self._h
        self._pending = np.zeros((2, 2))
        self._window = DivergenceWindow(options.nis_window, options.divergence_probability)
        self.reinitialisations = 0
        self._set_gaussian(x0, p0)

    # ---- the grid -------------------------------------------------------------------------

    def _spacing(self, cov: Array) -> Array:
        sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        return np.maximum(
            2.0 * self.options.grid_sigmas * sd / (2.0 * self._h), self.options.min_cell_m
        )

    def _points(self, c: Array, d: Array) -> Array:
        gx = c[0] + d[0] * self._idx
        gy = c[1] + d[1] * self._idx
        px, py = np.meshgrid(gx, gy, indexing="ij")
        return np.column_stack([px.ravel(), py.ravel()])

    def _set_gaussian(self, mean: Array, cov: Array) -> None:
        floor = self.options.min_cell_m**2 * np.eye(2)
        cov = cov + floor
        self._c = mean.copy()
        self._d = self._spacing(cov)
        dev = self._points(self._c, self._d) - mean
        info = np.linalg.inv(cov)
        log_w = -0.5 * np.einsum("ni,ij,nj->n", dev, info, dev)
        self._w = normalise_log_weights(log_w)
        self._pending = np.zeros((2, 2))

    def _moments(self, w: Array, c: Array, d: Array) -> tuple[Array, Array]:
        p = self._points(c, d)
        mean = w @ p
        dev = p - mean
        cov = (dev * w[:, None]).T @ dev + np.diag(d * d / 12.0)
        return mean, 0.5 * (cov + cov.T)

    def _moved(self, w: Array, c: Array, d: Array, c_new: Array, d_new: Array) -> Array:
        """The masses ``w`` of grid (c, d) on grid (c_new, d_new), normalised."""
        n = self.options.grid_points
        if np.all(d_new <= d):  # finer: interpolate the density
            dens = (w / (d[0] * d[1])).reshape(n, n)
            grid = TerrainMap(c[0] + d[0] * self._idx, c[1] + d[1] * self._idx, dens.T)
            p = self._points(c_new, d_new)
            val, _ = grid.depth(p[:, 0], p[:, 1])
            out = np.clip(val, 0.0, None)
        else:  # coarser: splat each mass onto its four new neighbours (mass and mean kept)
            p = self._points(c, d)
            f = (p - (c_new - d_new * self._h)) / d_new
            i0 = np.floor(f).astype(np.intp)
            t = f - i0
            out = np.zeros(n * n)
            for di in (0, 1):
                for dj in (0, 1):
                    ii, jj = i0[:, 0] + di, i0[:, 1] + dj
                    share = (t[:, 0] if di else 1.0 - t[:, 0]) * (t[:, 1] if dj else 1.0 - t[:, 1])
                    inside = (ii >= 0) & (ii < n) & (jj >= 0) & (jj < n)
                    np.add.at(out, ii[inside] * n + jj[inside], (w * share)[inside])
        total = out.sum()
        if not total > 0.0:  # nothing overlaps: keep a Gaussian of the old moments
            mean, cov = self._moments(w, c, d)
            dev = self._points(c_new, d_new) - mean
            out = np.exp(-0.5 * np.einsum("ni,ij,nj->n", dev, np.linalg.inv(cov), dev))
            total = out.sum()
        return out / total

    def _fits(self, mean: Array, cov: Array) -> bool:
        sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        half = self._d * self._h
        wide_enough = np.all(half >= (self.options.grid_sigmas - 1.0) * sd + np.abs(mean - self._c))
        fine_enough = np.all(self._d <= 2.0 * self._spacing(cov))
        return bool(wide_enough and fine_enough)

    def _recentre(self, mean: Array, cov: Array) -> None:
        c_new, d_new = mean.copy(), self._spacing(cov)
        self._w = self._moved(self._w, self._c, self._d, c_new, d_new)
        self._c, self._d = c_new, d_new

    # ---- the filter -----------------------------------------------------------------------

    def predict(self, displacement_m: ArrayLike, covariance_m2: ArrayLike) -> None:
        """Translate the grid by the displacement and diffuse the masses by its noise.

        Args:
            displacement_m: dead-reckoned displacement over the step (east, north), ``(2,)``, m.
            covariance_m2: its covariance ``Q``, ``(2, 2)``, m^2.

        Raises:
            NavInputError: a non-finite displacement or a bad covariance.
        """
        disp, q = check_gaussian("displacement_m", displacement_m, "covariance_m2", covariance_m2)
        self._c = self._c + disp
        self._pending = self._pending + q
        if np.all(np.sqrt(np.diag(self._pending)) < self._d):
            return
        mean, cov = self.estimate()
        if not self._fits(mean, cov):
            self._recentre(mean, cov)
        self._diffuse(self._pending)
        self._pending = np.zeros((2, 2))

    def _diffuse(self, q: Array) -> None:
        n = self.options.grid_points
        d = self._d
        r = np.ceil(4.0 * np.sqrt(np.diag(q)) / d).astype(int)
        r = np.minimum(r, 2 * n)
        ox = d[0] * np.arange(-r[0], r[0] + 1)
        oy = d[1] * np.arange(-r[1], r[1] + 1)
        px, py = np.meshgrid(ox, oy, indexing="ij")
        off = np.stack([px, py], axis=-1)
        qq = q + 1e-12 * np.eye(2) * float(np.trace(q) + 1e-12)
        kernel = np.exp(-0.5 * np.einsum("...i,ij,...j->...", off, np.linalg.inv(qq), off))
        kernel /= kernel.sum()
        shape = (n + 2 * r[0], n + 2 * r[1])
        spec = np.fft.rfft2(self._w.reshape(n, n), s=shape) * np.fft.rfft2(kernel, s=shape)
        full = np.fft.irfft2(spec, s=shape)
        out = np.clip(full[r[0] : r[0] + n, r[1] : r[1] + n], 0.0, None).ravel()
        total = out.sum()
        if total > 0.0:
            self._w = out / total

    def update(
        self, terrain_map: TerrainMap, soundings: Soundings, sigma_m: float | ArrayLike
    ) -> TrnUpdate:
        """Weight the grid by one ping's soundings against the map (module docstring).

        Args:
            terrain_map: the navigator's map.
            soundings: the ping's soundings (:func:`nav.trn.soundings`).
            sigma_m: each beam's depth standard deviation, float or ``(m,)``, m.

        Returns:
            The update's diagnostics; with no usable beam the filter is unchanged.

        Raises:
            NavInputError: a bad ``sigma_m``.
        """
        opt = self.options
        z, off, s = ping_inputs(soundings, sigma_m, terrain_map.sigma_m)
        if z.size == 0:
            return TrnUpdate(0.0, self.ess, False, False, 0)
        prior, c, d = self._w, self._c, self._d
        nis, dof, used = 0.0, 0, 0
        for attempt in range(_REFINES + 1):
            ll, h, ok = log_likelihood(
                self._points(c, d), terrain_map, z, off, s, opt.sigma_bias_m, prior
            )
            if attempt == 0:
                used = int(ok.any(axis=0).sum())
                if used == 0:
                    return TrnUpdate(0.0, self.ess, False, False, 0)
                nis, dof = innovation_nis(prior, h, ok, z, s, opt.sigma_bias_m)
            with np.errstate(divide="ignore"):
                log_prior = np.log(prior)
            post = normalise_log_weights(log_prior + ll)
            mean, cov = self._moments(post, c, d)
            cov = cov + self._pending
            d_new = self._spacing(cov)
            if attempt == _REFINES or np.all(d <= 2.0 * d_new):
                break
            d_new = np.clip(d_new, d / 4.0, d)  # at most 4x finer per pass: the new grid
            # spans +-8 old cells, wider than a posterior that fits in a few of them
            prior = self._moved(prior, c, d, mean, d_new)
            c = mean.copy()
            d = d_new
        self._w, self._c, self._d = post, c, d
        ess = self.ess
        diverged = self._window.push(nis, dof)
        reinit = diverged and opt.reinitialise
        if reinit:
            self.reinitialise()
        return TrnUpdate(nis, ess, diverged, reinit, used, dof)

    @property
    def ess(self) -> float:
        """Effective number of grid points ``1 / sum w^2``."""
        return float(1.0 / np.dot(self._w, self._w))

    def reinitialise(
        self, center_m: ArrayLike | None = None, covariance_m2: ArrayLike | None = None
    ) -> None:
        """Spread the grid afresh (a Gaussian) and count it.

        Args:
            center_m: centre (east, north), ``(2,)``, m; default the current estimate.
            covariance_m2: covariance, ``(2, 2)``, m^2; default the current estimate's plus
                ``reinit_sigma_m^2 I``.
        """
        mean, cov = self.estimate()
        c = mean if center_m is None else center_m
        p = (
            cov + self.options.reinit_sigma_m**2 * np.eye(2)
            if covariance_m2 is None
            else covariance_m2
        )
        mean, cov = check_gaussian("center_m", c, "covariance_m2", p)
        self._set_gaussian(mean, cov)
        self._window.clear()
        self.reinitialisations += 1

    def estimate(self) -> tuple[Array, Array]:
        """Mean and covariance of the grid density (cells' spread and pending noise included).

        Returns:
            ``(mean (2,), covariance (2, 2))``, m and m^2.
        """
        mean, cov = self._moments(self._w, self._c, self._d)
        return mean, cov + self._pending

    @property
    def grid(self) -> tuple[Array, Array]:
        """The grid's points ``(n^2, 2)``, m, and their masses ``(n^2,)`` (for figures, tests)."""
        return self._points(self._c, self._d), self._w.copy()
