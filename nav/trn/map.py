"""The navigator's bathymetry map: depth on a regular grid, bilinear depth and gradient.

The map is what terrain-relative navigation matches the soundings against. It is never the truth:
:func:`degraded` makes the navigator's copy of a true seabed (a coarser grid, vertical noise per
cell, a common vertical offset), as a survey map differs from the seabed a vehicle meets (Anonsen
& Hallingstad 2006 discuss the map's vertical error as the main error source of TRN).

Depth is positive down (``-z`` of the world ENU frame), m; ``x`` east and ``y`` north, m. Cells
without data are NaN in the grid; a query that falls off the map, or into a grid cell one of whose
four corners is NaN, is flagged invalid and returns 0 (never NaN).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _axis(name: str, values: ArrayLike) -> tuple[Array, float]:
    a = np.asarray(values, dtype=float)
    if a.ndim != 1 or a.size < 2:
        raise NavInputError(f"{name} has shape {a.shape}: must be 1-D with at least 2 points")
    if not np.all(np.isfinite(a)):
        raise NavInputError(f"{name} holds non-finite values: must be finite")
    step = np.diff(a)
    d = float(step.mean())
    if not d > 0.0 or np.max(np.abs(step - d)) > 1e-6 * max(abs(d), 1.0):
        raise NavInputError(
            f"{name}: must be regular and increasing (steps {step.min()}..{step.max()})"
        )
    return a, d


class TerrainMap:
    """A regular-grid bathymetry map with bilinear interpolation.

    Args:
        x_m: east coordinates of the grid columns, shape ``(nx,)``, regular and increasing, m.
        y_m: north coordinates of the grid rows, shape ``(ny,)``, regular and increasing, m.
        depth_m: depth at the grid nodes, shape ``(ny, nx)``, m, positive down; NaN = no data.
        sigma_m: the map's stated vertical standard deviation (its own error), m, >= 0; the
            filters add it to each beam's measurement variance.

    Raises:
        NavInputError: axes not regular/increasing, shapes that do not match, sigma_m < 0 or not
            finite, or a depth of +-inf.
    """

    def __init__(self, x_m: ArrayLike, y_m: ArrayLike, depth_m: ArrayLike, sigma_m: float = 0.0):
        self.x_m, self.dx_m = _axis("x_m", x_m)
        self.y_m, self.dy_m = _axis("y_m", y_m)
        z = np.array(depth_m, dtype=float)
        if z.shape != (self.y_m.size, self.x_m.size):
            raise NavInputError(
                f"depth_m has shape {z.shape}: must be (ny, nx) = "
                f"({self.y_m.size}, {self.x_m.size})"
            )
        if np.any(np.isinf(z)):
            raise NavInputError("depth_m holds +-inf: must be finite or NaN (no data)")
        if not (math.isfinite(sigma_m) and sigma_m >= 0.0):
            raise NavInputError(f"sigma_m = {sigma_m}: must be finite and >= 0")
        self.depth_m = z
        self.sigma_m = float(sigma_m)
        finite = np.isfinite(z)
        # a cell (between four nodes) is usable when its four corners hold data
        cell_ok = finite[:-1, :-1] & finite[1:, :-1] & finite[:-1, 1:] & finite[1:, 1:]
        self._cell_ok = cell_ok.ravel()
        self._z0 = np.where(finite, z, 0.0).ravel()  # NaN-free copy for arithmetic
        self._nx = self.x_m.size
        self._ny = self.y_m.size

    def interpolation_sigma_m(self) -> float:
        """RMS error of the bilinear interpolation between the nodes, estimated from the map's
        own second differences, m.

        Between nodes a bilinear surface misses the terrain's curvature. On a cell at fractions
        ``(u, v)`` the error is, to second order, ``e = (u (1 - u) Dxx + v (1 - v) Dyy) / 2``,
        with ``Dxx = hx^2 d2z/dx2`` and ``Dyy = hy^2 d2z/dy2`` the nodes' second differences.
        Over ``u, v`` uniform (``E[u(1-u)] = 1/6``, ``E[(u(1-u))^2] = 1/30``):
        ``E[e^2] = (Dxx^2 / 30 + Dyy^2 / 30 + Dxx Dyy / 18) / 4``, averaged over the interior
        nodes with data. The map cannot show curvature finer than its own cells, so this is the
        part of the interpolation error the map itself reveals (a lower estimate on terrain
        rougher than its grid). 0 for a map of fewer than 3 x 3 nodes or without an interior
        node with data.

        Returns:
            The RMS error, m (a filter's measurement sigma adds it in quadrature).
        """
        z = self.depth_m
        if z.shape[0] < 3 or z.shape[1] < 3:
            return 0.0
        dxx = z[1:-1, 2:] - 2.0 * z[1:-1, 1:-1] + z[1:-1, :-2]
        dyy = z[2:, 1:-1] - 2.0 * z[1:-1, 1:-1] + z[:-2, 1:-1]
        e2 = (dxx * dxx / 30.0 + dyy * dyy / 30.0 + dxx * dyy / 18.0) / 4.0
        ok = np.isfinite(e2)
        if not ok.any():
            return 0.0
        return float(np.sqrt(np.mean(e2[ok])))

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` of the grid, m."""
        return float(self.x_m[0]), float(self.x_m[-1]), float(self.y_m[0]), float(self.y_m[-1])

    def _locate(self, x: ArrayLike, y: ArrayLike):
        fx = (np.asarray(x, dtype=float) - self.x_m[0]) * (1.0 / self.dx_m)
        fy = (np.asarray(y, dtype=float) - self.y_m[0]) * (1.0 / self.dy_m)
        fx, fy = np.broadcast_arrays(fx, fy)
        inside = (fx >= 0.0) & (fx <= self._nx - 1) & (fy >= 0.0) & (fy <= self._ny - 1)
        # NaN coordinates compare False above: they are flagged invalid
        fx = np.where(inside, fx, 0.0)
        fy = np.where(inside, fy, 0.0)
        ix = np.minimum(fx.astype(np.intp), self._nx - 2)  # floor: fx >= 0 here
        iy = np.minimum(fy.astype(np.intp), self._ny - 2)
        u = fx - ix
        v = fy - iy
        k = iy * self._nx + ix
        valid = inside & self._cell_ok[iy * (self._nx - 1) + ix]
        return k, u, v, valid

    def depth(self, x: ArrayLike, y: ArrayLike) -> tuple[Array, BoolArray]:
        """Bilinear depth at points.

        Args:
            x: east, m, any shape (broadcast with ``y``).
            y: north, m.

        Returns:
            ``(depth_m, valid)`` of the broadcast shape: the bilinear depth (m, positive down) and
            whether it is defined (on the map, on a cell with data); depth is 0 where invalid.
        """
        k, u, v, valid = self._locate(x, y)
        z = self._z0
        nx = self._nx
        z00 = z[k]
        z10 = z[k + 1]
        z01 = z[k + nx]
        z11 = z[k + nx + 1]
        a = z00 + u * (z10 - z00)
        b = z01 + u * (z11 - z01)
        d = a + v * (b - a)
        return np.where(valid, d, 0.0), valid

    def gradient(self, x: ArrayLike, y: ArrayLike) -> tuple[Array, BoolArray]:
        """Gradient of the bilinear depth surface at points.

        Args:
            x: east, m, any shape (broadcast with ``y``).
            y: north, m.

        Returns:
            ``(gradient, valid)``: ``d depth / d (x, y)``, shape ``(..., 2)``, m/m (0 where
            invalid), and the validity flags, shape ``(...)``.
        """
        k, u, v, valid = self._locate(x, y)
        z = self._z0
        nx = self._nx
        z00, z10, z01, z11 = z[k], z[k + 1], z[k + nx], z[k + nx + 1]
        gx = ((1.0 - v) * (z10 - z00) + v * (z11 - z01)) / self.dx_m
        gy = ((1.0 - u) * (z01 - z00) + u * (z11 - z10)) / self.dy_m
        g = np.stack([gx, gy], axis=-1)
        return np.where(valid[..., None], g, 0.0), valid


def degraded(
    truth: TerrainMap,
    cell_m: float,
    vertical_sigma_m: float,
    offset_m: float,
    rng: np.random.Generator,
) -> TerrainMap:
    """The navigator's copy of a seabed: resampled on a coarser grid, noisy and offset.

    The copy's nodes lie on a regular grid of spacing ``cell_m`` over the truth's extent (the
    truth is sampled bilinearly there; nodes on NaN cells stay NaN); each node gets an independent
    ``N(0, vertical_sigma_m^2)`` error and the whole map the common ``offset_m`` (a datum or tide
    error: positive = the map is deeper than the seabed). The copy's stated ``sigma_m`` is
    ``hypot(truth.sigma_m, vertical_sigma_m)``; the offset is not part of it (the filters remove a
    common bias per ping, see :mod:`nav.trn.likelihood`).

    Args:
        truth: the true seabed as a map.
        cell_m: node spacing of the copy, m, > 0 (coarser than the truth's for a survey map).
        vertical_sigma_m: standard deviation of the per-node vertical error, m, >= 0.
        offset_m: common vertical offset, m.
        rng: the generator the node errors are drawn from.

    Returns:
        The degraded map.

    Raises:
        NavInputError: a non-finite or out-of-range argument, or a cell larger than the map.
    """
    if not (math.isfinite(cell_m) and cell_m > 0.0):
        raise NavInputError(f"cell_m = {cell_m}: must be finite and > 0")
    if not (math.isfinite(vertical_sigma_m) and vertical_sigma_m >= 0.0):
        raise NavInputError(f"vertical_sigma_m = {vertical_sigma_m}: must be finite and >= 0")
    if not math.isfinite(offset_m):
        raise NavInputError(f"offset_m = {offset_m}: must be finite")
    x0, x1, y0, y1 = truth.extent
    nx = math.floor((x1 - x0) / cell_m + 1e-9) + 1
    ny = math.floor((y1 - y0) / cell_m + 1e-9) + 1
    if nx < 2 or ny < 2:
        raise NavInputError(
            f"cell_m = {cell_m}: must be at most the map's extent ({x1 - x0} x {y1 - y0} m)"
        )
    x = x0 + cell_m * np.arange(nx)
    y = y0 + cell_m * np.arange(ny)
    d, ok = truth.depth(x[None, :], y[:, None])
    d = np.where(ok, d, np.nan)
    noisy = d + vertical_sigma_m * rng.standard_normal(d.shape) + offset_m
    return TerrainMap(x, y, noisy, float(math.hypot(truth.sigma_m, vertical_sigma_m)))
