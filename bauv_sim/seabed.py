"""The seabed: a generated, gently varying bathymetry, or the site's own from a bathymetry file,
stored as a MuJoCo heightfield.

Depth below the surface (positive down) at horizontal position (x east, y north):

    depth(x, y) = depth_at_origin + slope * r + relief(x, y) - relief(0, 0),    r = sqrt(x^2 + y^2)

where ``relief`` is a sum of ``n_modes`` plane waves with random directions, wavelengths
log-uniform in [``min_wavelength_m``, ``max_wavelength_m``] and phases, scaled to the standard
deviation ``relief_std_m`` and drawn from the seabed's own random stream. Depths are clipped to
at least ``min_depth_m``. The defaults follow seed 000's test geometry: the USBL transceiver at the
origin lies on the seabed at 6 m depth, and the bottom falls away gently (5 m per km) with about
1 m of relief, so that a vehicle at 3 m depth clears it everywhere.

With ``file`` set (a CF netCDF or a GeoTIFF, :mod:`bauv_sim.bathymetry`), the depths are the
file's instead, resampled onto the same square grid (``half_extent_m``, ``cell_m``) around the
scene's geographic origin (:class:`~bauv_sim.geo.LocalFrame`, from the scenario's ``geo``):
``depth(x, y)`` is the file's depth at the latitude/longitude of (x, y), and the relief's fields
are not used.

The grid is a MuJoCo heightfield in its custom binary format (int32 nrow, int32 ncol, float32
data, row 0 at the smallest y, column 0 at the smallest x), normalised to [0, 1]; the geom's z is
the deepest point and its elevation range the depth range. :func:`height_world` interpolates the
same triangles MuJoCo collides with (each cell split along the diagonal from its lower-left to its
upper-right corner).
"""

from __future__ import annotations

import argparse
import functools
import math
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, model_validator

from bauv_sim import PROJECT_ROOT
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.geo import LocalFrame
from bauv_sim.rng import generator

SEABED_DIR = PROJECT_ROOT / "assets" / "seabed"
"""Folder of the generated seabed heightfields."""

DEFAULT_SEABED_FILE = SEABED_DIR / "default.bin"
"""The heightfield of the default scene (``models/bauv/scene.xml``)."""


MAX_HALF_EXTENT_M = 10_000.0
"""The largest half side of a seabed grid, m. The world frame is a local tangent plane (flat ENU,
:mod:`bauv_sim.frames`); at 10 km from its origin the sea surface has fallen r^2 / (2 R) = 7.8 m
below it (R = 6371 km), more than the water depth at the scenes' origin (6 m), and the error grows
as r^2: a seabed farther out is not the sea the simulator's frame describes."""

MIN_CELL_M = 0.01
"""The finest seabed grid spacing, m: 1 cm, 200 cells along the 2 m vehicle; finer triangles add
nothing to its contacts or to a multibeam whose range noise is centimetres, and only grow the
grid (:data:`GRID_BYTES_PER_POINT` per point)."""

GRID_BYTES_PER_POINT = 48.0
"""Peak memory of :func:`generate` per grid point, bytes: the two coordinate grids, the relief and
the working arrays of one plane wave, six float64 arrays at once (tracemalloc: 48.2 B per point on
a 2001 x 2001 grid). Building a scene holds less on top of the finished grid (the float32
heightfield and its bytes), so this is the peak of a process that builds one."""

RESAMPLE_BYTES_PER_POINT = 60.0
"""Peak memory of resampling a bathymetry file onto the seabed grid per grid point, bytes
(:func:`bauv_sim.bathymetry.resample`: the points' east/north, latitude/longitude and depth,
float64; tracemalloc: 48.0 B per point on 1001 x 1001 and 2001 x 2001 grids, 58.5 B at most)."""

FILE_BYTES_PER_NODE = 34.0
"""Peak memory of a bathymetry file per node of its grid, bytes: the grid read (8 B per node,
24 B while it is read and converted) stays in memory while the spline through its nodes around
the scene is built (25 B per node, tracemalloc on 1e5 to 7e5 nodes); counted over the whole file,
an upper bound of the part around the scene."""


class SeabedConfig(Config):
    """Parameters of a generated seabed, or of one resampled from a bathymetry file (see the
    module docstring)."""

    half_extent_m: float = Field(
        1000.0,
        gt=0,
        le=MAX_HALF_EXTENT_M,
        description="half side of the square grid, m (at most 10 km: the world frame is a flat "
        "tangent plane)",
    )
    cell_m: float = Field(10.0, ge=MIN_CELL_M, description="grid spacing, m (at least 1 cm)")
    depth_at_origin_m: float = Field(6.0, gt=0, description="depth at (0, 0), m")
    slope: float = Field(0.005, ge=0, le=0.5, description="radial increase of depth, m per m")
    relief_std_m: float = Field(1.0, ge=0, description="standard deviation of the relief, m")
    n_modes: int = Field(24, ge=1, le=1000, description="plane waves in the relief")
    min_wavelength_m: float = Field(60.0, gt=0, description="shortest relief wavelength, m")
    max_wavelength_m: float = Field(600.0, gt=0, description="longest relief wavelength, m")
    min_depth_m: float = Field(4.5, gt=0, description="shallowest allowed depth, m")
    base_m: float = Field(1.0, gt=0, description="thickness of the heightfield's base, m")
    seed: int = Field(1, ge=0, description="seed of the relief's random stream")
    file: str | None = Field(
        None,
        description="the site's bathymetry: a CF netCDF (.nc, latitude/longitude, elevation or "
        "depth in m) or a GeoTIFF (.tif, any reference system), resolved against the current "
        "directory; the grid (half_extent_m, cell_m around the scenario's geo origin, which it "
        "needs) is resampled from it and the generated relief's fields (depth_at_origin_m, "
        "slope, relief_std_m, n_modes, min/max_wavelength_m, min_depth_m, seed) are not used "
        "(default: none, the generated seabed)",
    )
    variable: str | None = Field(
        None,
        description="the netCDF variable of the bathymetry (default: the one whose "
        "standard_name is an elevation or a depth); with a netCDF file only",
    )
    values: Literal["elevation", "depth"] = Field(
        "elevation",
        description="what a GeoTIFF's band holds: elevation positive up (a DEM's convention) or "
        "depth positive down; a netCDF says it by its attributes",
    )

    @model_validator(mode="after")
    def _grid(self) -> SeabedConfig:
        n = self.half_extent_m / self.cell_m
        if abs(n - round(n)) > 1e-9 or round(n) < 1:
            raise ValueError(
                f"half_extent_m = {self.half_extent_m} must be a whole number of "
                f"cells of {self.cell_m} m"
            )
        if self.max_wavelength_m < self.min_wavelength_m:
            raise ValueError("max_wavelength_m must be >= min_wavelength_m")
        if self.depth_at_origin_m < self.min_depth_m:
            raise ValueError("depth_at_origin_m must be >= min_depth_m")
        kind = None if self.file is None else _file_kind(self.file)
        if self.variable is not None and kind != "netcdf":
            raise ValueError(
                f"variable = {self.variable!r}: names a variable of a netCDF seabed.file "
                f"(file = {self.file!r})"
            )
        if self.values != "elevation" and kind != "geotiff":
            raise ValueError(
                f"values = {self.values!r}: is the band of a GeoTIFF seabed.file "
                f"(file = {self.file!r}); a netCDF says it by its attributes"
            )
        return self

    @property
    def n(self) -> int:
        """Grid points per side (odd: the origin is a grid point)."""
        return 2 * round(self.half_extent_m / self.cell_m) + 1

    @property
    def grid_bytes(self) -> float:
        """Peak memory of generating this seabed, bytes (:data:`GRID_BYTES_PER_POINT` per grid
        point; from a file, :data:`RESAMPLE_BYTES_PER_POINT` per grid point and
        :data:`FILE_BYTES_PER_NODE` per node of the file's grid, read from its header), for the
        batch's memory check before any grid is allocated.

        Raises:
            ConfigError: for a file that cannot be read (naming it).
        """
        if self.file is None:
            return GRID_BYTES_PER_POINT * float(self.n) ** 2
        return RESAMPLE_BYTES_PER_POINT * float(self.n) ** 2 + FILE_BYTES_PER_NODE * float(
            math.prod(self._file_shape()[0])
        )

    @property
    def grid_text(self) -> str:
        """The fields that size the grid, as a memory check names them."""
        text = (
            f"seabed.half_extent_m = {self.half_extent_m:g} with seabed.cell_m = "
            f"{self.cell_m:g} m ({self.n} x {self.n} grid points)"
        )
        if self.file is None:
            return text
        shape, name = self._file_shape()
        return (
            f"seabed.file = {self.file} (variable '{name}' of "
            f"{' x '.join(str(k) for k in shape)} nodes) and {text}"
        )

    def _file_shape(self) -> tuple[tuple[int, ...], str]:
        from bauv_sim.bathymetry import grid_shape

        assert self.file is not None
        return grid_shape(self.file, self.variable)


@dataclass(frozen=True)
class Seabed:
    """A generated seabed grid.

    Attributes:
        config: its parameters.
        depth_m: depth at the grid points, shape (n, n), m; ``depth_m[i, j]`` is at
            y = -half + i cell, x = -half + j cell.
    """

    config: SeabedConfig
    depth_m: NDArray[np.float64]

    @property
    def z_min_m(self) -> float:
        """World z of the deepest point, m."""
        return -float(self.depth_m.max())

    @property
    def z_max_m(self) -> float:
        """World z of the shallowest point, m."""
        return -float(self.depth_m.min())

    def normalised(self) -> NDArray[np.float32]:
        """Heights normalised to [0, 1] as MuJoCo stores them, shape (n, n), float32."""
        z = -self.depth_m
        span = self.z_max_m - self.z_min_m
        if span <= 0:
            return np.zeros_like(z, dtype=np.float32)
        return ((z - self.z_min_m) / span).astype(np.float32)

    def to_bytes(self) -> bytes:
        """The heightfield in MuJoCo's custom binary format."""
        n = self.config.n
        return struct.pack("<ii", n, n) + self.normalised().astype("<f4").tobytes()

    def hfield_size(self) -> tuple[float, float, float, float]:
        """MuJoCo ``hfield size``: (radius x, radius y, elevation range, base), m."""
        c = self.config
        return (c.half_extent_m, c.half_extent_m, max(self.z_max_m - self.z_min_m, 1e-6), c.base_m)

    def height_world(self, x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
        """World z of the seabed surface (the triangulated heightfield), m.

        Args:
            x_m: east, any shape, m.
            y_m: north, broadcastable with ``x_m``, m.

        Returns:
            Seabed z (negative below the surface), broadcast shape, m.

        Raises:
            GeometryError: for points outside the grid.
        """
        c = self.config
        x, y = np.broadcast_arrays(np.asarray(x_m, float), np.asarray(y_m, float))
        gx = (x + c.half_extent_m) / c.cell_m
        gy = (y + c.half_extent_m) / c.cell_m
        n = c.n
        if np.any((gx < 0) | (gx > n - 1) | (gy < 0) | (gy > n - 1)):
            raise GeometryError(f"point outside the seabed grid (half extent {c.half_extent_m} m)")
        j = np.minimum(np.floor(gx).astype(int), n - 2)
        i = np.minimum(np.floor(gy).astype(int), n - 2)
        u, v = gx - j, gy - i
        # heights as MuJoCo stores them (float32 normalised), back to metres
        hn = self.normalised().astype(np.float64)
        span = self.hfield_size()[2]
        z = self.z_min_m + span * hn
        z00, z10 = z[i, j], z[i, j + 1]
        z01, z11 = z[i + 1, j], z[i + 1, j + 1]
        # triangles split along (0,0)-(1,1)
        lower = u >= v
        return np.where(
            lower, z00 + u * (z10 - z00) + v * (z11 - z10), z00 + v * (z01 - z00) + u * (z11 - z01)
        )

    @functools.cached_property
    def _z_grid(self) -> NDArray[np.float64]:
        """World z at the grid points as MuJoCo stores them (float32 normalised), m."""
        return self.z_min_m + self.hfield_size()[2] * self.normalised().astype(np.float64)

    @functools.cached_property
    def max_slope(self) -> float:
        """Largest ``|grad z|`` over the heightfield's triangles (dimensionless)."""
        z, c = self._z_grid, self.config.cell_m
        dx, dy = np.diff(z, axis=1), np.diff(z, axis=0)
        lower = np.hypot(dx[:-1], dy[:, 1:])  # (z10 - z00, z11 - z10)
        upper = np.hypot(dx[1:], dy[:, :-1])  # (z11 - z01, z01 - z00)
        return float(max(lower.max(), upper.max())) / c

    def _facet(self, x: NDArray[np.float64], y: NDArray[np.float64]):
        """Triangle and plane of the heightfield at points (r,) inside the grid: ``(key, z,
        dz/dx, dz/dy, u, v)``, each (r,); ``key`` numbers the triangle (cell and half), ``u, v``
        are the point's coordinates in its cell, in cells (the lower triangle is ``u >= v``)."""
        c = self.config
        n = c.n
        gx = (x + c.half_extent_m) / c.cell_m
        gy = (y + c.half_extent_m) / c.cell_m
        j = np.minimum(np.floor(gx).astype(np.int64), n - 2)
        i = np.minimum(np.floor(gy).astype(np.int64), n - 2)
        u, v = gx - j, gy - i
        zf = self._z_grid.ravel()
        k00 = i * n + j
        z00, z10, z01, z11 = zf[k00], zf[k00 + 1], zf[k00 + n], zf[k00 + n + 1]
        lower = u >= v
        du = np.where(lower, z10 - z00, z11 - z01)
        dv = np.where(lower, z11 - z10, z01 - z00)
        z = np.where(lower, z00 + u * du + v * dv, z00 + v * dv + u * du)
        return 2 * k00 + lower, z, du / c.cell_m, dv / c.cell_m, u, v

    def ray_ranges(
        self,
        origin_m: ArrayLike,
        directions: ArrayLike,
        max_range_m: float,
        tol_m: float = 1e-9,
        max_iterations: int = 10_000,
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Distance along rays to the first crossing of the triangulated heightfield, analytically
        (the surface MuJoCo's rays meet, :meth:`height_world`), batched.

        Along a ray ``x(s) = o + s e`` the height above the seabed ``f(s) = z(s) - h(x(s), y(s))``
        is linear on each triangle the ray passes over. From a point above triangle T: if the ray
        meets T's plane before it leaves T, that is the first crossing (exact); otherwise the ray
        moves on to the larger of T's exit and ``s + f / Lip`` (``Lip = |e_z| + |e_xy|
        max_slope`` bounds ``|f'|``), neither of which can pass the first crossing. A ray that
        leaves the grid, or starts at or below the seabed, has no echo.

        Args:
            origin_m: ray origins, shape (..., 3), m, world.
            directions: ray directions, shape (..., 3) (broadcast with the origins; normalised
                here).
            max_range_m: no echo beyond this distance, m.
            tol_m: a ray within ``tol_m`` (height over ``Lip``) of the seabed has met it, m.
            max_iterations: cap of the march (an error if reached).

        Returns:
            ``(range_m, hit)``, shape (...): ``range_m`` is 0 where ``hit`` is False.

        Raises:
            GeometryError: for a zero or non-finite direction, a non-finite origin, or a march
                that does not finish in ``max_iterations`` steps.
        """
        o, e = np.broadcast_arrays(np.asarray(origin_m, float), np.asarray(directions, float))
        shape = o.shape[:-1]
        o, e = o.reshape(-1, 3), e.reshape(-1, 3)
        norm = np.linalg.norm(e, axis=1)
        if not np.all(np.isfinite(norm) & (norm > 0)) or not np.all(np.isfinite(o)):
            raise GeometryError(
                "ray_ranges: origins must be finite, directions finite and non-zero"
            )
        e = e / norm[:, None]
        half, cell = self.config.half_extent_m, self.config.cell_m
        lip = np.abs(e[:, 2]) + np.hypot(e[:, 0], e[:, 1]) * self.max_slope
        r = np.zeros(len(o))
        hit = np.zeros(len(o), bool)
        # start where the ray comes down to the highest point of the seabed
        top = self.z_max_m
        above = o[:, 2] > top
        with np.errstate(divide="ignore"):
            s = np.where(above & (e[:, 2] < 0), (o[:, 2] - top) / -e[:, 2], 0.0)
        idx = np.flatnonzero(~(above & (e[:, 2] >= 0)) & (s <= max_range_m))
        for _ in range(max_iterations):
            if idx.size == 0:
                break
            si, ei = s[idx], e[idx]
            p = o[idx] + si[:, None] * ei
            inside = (np.abs(p[:, 0]) <= half) & (np.abs(p[:, 1]) <= half)
            _, h, gx, gy, u, v = self._facet(
                np.where(inside, p[:, 0], 0.0), np.where(inside, p[:, 1], 0.0)
            )
            f = p[:, 2] - h
            slope = ei[:, 2] - gx * ei[:, 0] - gy * ei[:, 1]  # f' over this triangle
            a, b = ei[:, 0] / cell, ei[:, 1] / cell  # du/ds, dv/ds
            lower = u >= v
            with np.errstate(divide="ignore", invalid="ignore"):
                to_plane = np.where(slope < 0, f / -slope, np.inf)
                # where the ray leaves the triangle: lower (v >= 0, u <= 1, u >= v), upper
                # (u >= 0, v <= 1, v > u)
                e1 = np.where(
                    lower, np.where(b < 0, -v / b, np.inf), np.where(a < 0, -u / a, np.inf)
                )
                e2 = np.where(
                    lower,
                    np.where(a > 0, (1 - u) / a, np.inf),
                    np.where(b > 0, (1 - v) / b, np.inf),
                )
                d = np.where(lower, a - b, b - a)
                e3 = np.where(d < 0, np.abs(u - v) / -d, np.inf)
            to_exit = np.minimum(np.minimum(e1, e2), e3)
            above_bed = f > 0
            in_tri = above_bed & (to_plane <= to_exit)
            near = above_bed & (f <= tol_m * lip[idx])
            root = np.where(in_tri, si + to_plane, si)
            found = inside & (in_tri | near | (~above_bed & (si > 0))) & (root <= max_range_m)
            step = np.maximum(to_exit * (1 + 1e-12) + 1e-12, f / lip[idx])
            nxt = si + step
            gone = ~found & (~inside | ~above_bed | (nxt > max_range_m))
            r[idx[found]] = root[found]
            hit[idx[found]] = True
            go = ~(found | gone)
            s[idx[go]] = nxt[go]
            idx = idx[go]
        if idx.size:
            raise GeometryError(f"ray_ranges: the march did not finish in {max_iterations} steps")
        return np.where(hit, r, 0.0).reshape(shape), hit.reshape(shape)

    def depth_at(self, x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
        """Depth of the seabed below the surface, m (positive down); see :meth:`height_world`."""
        return -self.height_world(x_m, y_m)


def generate(config: SeabedConfig | None = None, frame: LocalFrame | None = None) -> Seabed:
    """Generate a seabed from its parameters (deterministic for a given seed), or resample the
    site's bathymetry file (``config.file``) around the scene's geographic origin.

    Args:
        config: parameters; the defaults when None.
        frame: the scene's frame on the Earth (the scenario's ``geo``); needed with a file, not
            used without.

    Returns:
        The :class:`Seabed`. From a file it is read and resampled once per process, file
        version, configuration and frame (:func:`_from_file`; its depths are read-only).

    Raises:
        ConfigError: with a file: no frame, or what :func:`bauv_sim.bathymetry.read_bathymetry`
            and :func:`bauv_sim.bathymetry.resample` refuse (a missing file or variable, units
            not metres, no-data cells under the scene, a scene beyond the file's extent, a grid
            too large), in one line naming the file and the variable.
    """
    c = config or SeabedConfig()
    if c.file is not None:
        if frame is None:
            raise ConfigError(
                f"seabed.file = {c.file}: needs the scenario's geo origin (geo.latitude_deg, "
                "geo.longitude_deg)"
            )
        path = Path(c.file).resolve()
        try:
            version = path.stat().st_mtime_ns
        except OSError:
            raise ConfigError(f"seabed.file = {c.file}: no such file") from None
        return _from_file(c, frame, str(path), version)
    rng = generator(c.seed, 0, "seabed", "relief")
    ax = np.linspace(-c.half_extent_m, c.half_extent_m, c.n)
    X, Y = np.meshgrid(ax, ax)  # [i, j] = (y_i, x_j)
    lam = np.exp(rng.uniform(np.log(c.min_wavelength_m), np.log(c.max_wavelength_m), c.n_modes))
    theta = rng.uniform(0.0, 2.0 * np.pi, c.n_modes)
    phase = rng.uniform(0.0, 2.0 * np.pi, c.n_modes)
    k = 2.0 * np.pi / lam
    relief = np.zeros_like(X)
    relief0 = 0.0
    for kk, th, ph in zip(k, theta, phase, strict=True):
        relief += np.cos(kk * (np.cos(th) * X + np.sin(th) * Y) + ph)
        relief0 += np.cos(ph)
    # sum of n unit cosines with random phases has variance n / 2
    scale = c.relief_std_m / np.sqrt(0.5 * c.n_modes)
    depth = c.depth_at_origin_m + c.slope * np.hypot(X, Y) + scale * (relief - relief0)
    depth = np.maximum(depth, c.min_depth_m)
    return Seabed(c, depth)


@functools.lru_cache(maxsize=2)
def _from_file(c: SeabedConfig, frame: LocalFrame, path: str, version: int) -> Seabed:
    """The seabed of ``c.file`` (cached on its resolved ``path`` and ``version``, its
    modification time in ns: a rewritten file is read again; messages name it as given)."""
    from bauv_sim.bathymetry import read_bathymetry, resample

    assert c.file is not None
    grid = read_bathymetry(c.file, c.variable, c.values)
    depth = resample(grid, frame, c.half_extent_m, c.cell_m)
    depth.setflags(write=False)
    return Seabed(c, depth)


def _file_kind(file: str) -> Literal["netcdf", "geotiff"] | None:
    from bauv_sim.bathymetry import file_kind

    return file_kind(file)


def write(seabed: Seabed, path: str | Path = DEFAULT_SEABED_FILE) -> Path:
    """Write a heightfield file (MuJoCo custom binary format).

    Args:
        seabed: the seabed.
        path: target file.

    Returns:
        The path written.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(seabed.to_bytes())
    return p


def main(argv: list[str] | None = None) -> None:
    """Regenerate the default seabed file and print its MuJoCo geometry."""
    parser = argparse.ArgumentParser(description="generate the default seabed heightfield")
    parser.add_argument("--out", default=str(DEFAULT_SEABED_FILE))
    args = parser.parse_args(argv)
    sb = generate()
    path = write(sb, args.out)
    print(f"wrote {path} ({path.stat().st_size} bytes)")
    print(f"hfield size = {' '.join(f'{v:.6g}' for v in sb.hfield_size())}")
    print(f"geom z = {sb.z_min_m:.6g} (deepest point); shallowest z = {sb.z_max_m:.6g}")
    print(f"depth at origin = {float(sb.depth_at(0.0, 0.0)):.6g} m")


if __name__ == "__main__":
    main()
