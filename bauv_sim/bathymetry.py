"""Bathymetry from a file: a CF-convention netCDF grid or a GeoTIFF, resampled to the scene.

A survey team's site comes as a grid of depths or elevations: a netCDF file following the CF
conventions (GEBCO, EMODnet, a multibeam survey's export: ``latitude``/``longitude`` coordinates
recognised by ``standard_name`` or ``axis``, a variable of elevation positive up
(``height_above_mean_sea_level``, ``altitude``, ``height_above_reference_ellipsoid``,
``positive = "up"``) or of depth positive down (``sea_floor_depth_below_sea_surface``,
``sea_floor_depth_below_geoid``, ``depth``, ``positive = "down"``), in metres), or a GeoTIFF in
any coordinate reference system (geographic WGS 84, UTM, ...), one band of elevation (or of depth
with ``values = "depth"``) with its no-data value. xarray with the netCDF4 engine reads the
first, rasterio (GDAL, the GIS tools' raster library) the second; pyproj transforms between the
scene's geographic frame (:class:`~bauv_sim.geo.LocalFrame`) and the file's reference system.

:func:`resample` puts the file's grid on the scene's square heightfield grid (the
:class:`~bauv_sim.seabed.Seabed` layout: ``depth[i, j]`` at north ``-half + i cell``, east
``-half + j cell``): each scene node's latitude/longitude (or the file's projected x/y) is
interpolated in the file's grid by a **bicubic** spline through its nodes (the not-a-knot
interpolating spline of FITPACK, ``scipy.interpolate.RectBivariateSpline`` with ``s = 0``; of
lower degree along an axis of fewer than four nodes). It is the interpolant of
``RegularGridInterpolator``'s ``cubic`` method (equal to 3e-7 of the values on a 1200 x 900
test grid) at 16 B of peak memory per node of the file's grid around the scene instead of 360 B,
and 45 times faster. Bilinear resampling would leave a kink at every node of the file, which the
scene's triangles cut across: 3.6 cm off at the nodes of the tests' 12 m ridge on 5 m cells,
against under 1 cm with the cubic.
A scene node outside the file's extent, or in a cell with a no-data value, is refused with one
line naming the file and the variable; so is a grid larger than :data:`MAX_BATHYMETRY_BYTES`
(checked from the header, before it is read).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.geo import LocalFrame
from bauv_sim.ocean import cf_variable, open_netcdf

Array = NDArray[np.float64]

MAX_BATHYMETRY_BYTES = 2 * 1024**3
"""Largest bathymetry grid read into memory (float64), bytes."""
ELEVATION_NAMES = (
    "height_above_mean_sea_level",
    "altitude",
    "height_above_reference_ellipsoid",
    "height",
)
DEPTH_NAMES = (
    "sea_floor_depth_below_sea_surface",
    "sea_floor_depth_below_geoid",
    "sea_floor_depth_below_mean_sea_level",
    "depth",
)
METRES = ("m", "meter", "meters", "metre", "metres")


@dataclass(frozen=True)
class BathymetryGrid:
    """A bathymetry grid in its file's reference system.

    Attributes:
        x: the grid's first horizontal axis (longitude, deg, or projected easting, m), shape
            (X,), increasing.
        y: the second (latitude, deg, or northing, m), shape (Y,), increasing.
        depth_m: depth below the sea surface, shape (Y, X), m, positive down (negative on land);
            NaN where the file has no data.
        crs: the reference system of ``x``/``y`` (a pyproj-readable string: ``"EPSG:4326"``
            for latitude/longitude).
        source: the file (for messages).
        variable: the variable or band read (for messages).
    """

    x: Array
    y: Array
    depth_m: Array
    crs: str
    source: str
    variable: str


def _check_size(shape: tuple[int, ...], where: str, variable: str) -> None:
    nbytes = 8 * math.prod(shape)
    if nbytes > MAX_BATHYMETRY_BYTES:
        raise ConfigError(
            f"{where}: variable '{variable}' of shape {shape} needs {nbytes / 1024**3:.1f} GiB "
            f"(limit {MAX_BATHYMETRY_BYTES / 1024**3:.0f} GiB): crop the file to the site"
        )


def read_netcdf(path: str | Path, variable: str | None = None) -> BathymetryGrid:
    """Read a CF-convention netCDF bathymetry (see the module docstring).

    Args:
        path: the file.
        variable: the variable to read; ``None``: the one whose ``standard_name`` is an
            elevation or a depth (:data:`ELEVATION_NAMES`, :data:`DEPTH_NAMES`).

    Raises:
        ConfigError: one line naming the file and the variable: missing, units not metres,
            unknown sign convention, dimensions not (latitude, longitude), too large.
    """
    where = str(path)
    with open_netcdf(path) as ds:
        lat = cf_variable(ds, "latitude", "Y", where, ("latitude", "lat"))
        lon = cf_variable(ds, "longitude", "X", where, ("longitude", "lon"))
        var = _variable(ds, variable, where)
        name = str(var.name)
        units = var.attrs.get("units")
        if units not in METRES:
            raise ConfigError(f"{where}: variable '{name}' has units '{units}', expected m")
        std = var.attrs.get("standard_name", "")
        positive = var.attrs.get("positive")
        if positive is None:
            positive = "up" if std in ELEVATION_NAMES else "down" if std in DEPTH_NAMES else None
        if positive not in ("up", "down"):
            raise ConfigError(
                f"{where}: variable '{name}': say whether it is an elevation or a depth "
                "(attribute positive = up or down, or a standard_name of either)"
            )
        if set(var.dims) != {lat.name, lon.name}:
            raise ConfigError(
                f"{where}: variable '{name}' has dimensions {var.dims}, expected "
                f"({lat.name}, {lon.name})"
            )
        _check_size(var.shape, where, name)
        values = var.transpose(lat.name, lon.name).values.astype(float)
        depth = -values if positive == "up" else values
        x, y = np.asarray(lon.values, dtype=float), np.asarray(lat.values, dtype=float)
    return _sorted(BathymetryGrid(x, y, depth, "EPSG:4326", where, name))


def read_geotiff(
    path: str | Path, values: Literal["elevation", "depth"] = "elevation", band: int = 1
) -> BathymetryGrid:
    """Read a GeoTIFF bathymetry with rasterio (one band, any reference system).

    Args:
        path: the file.
        values: what the band holds: elevation positive up (a DEM's convention) or depth
            positive down.
        band: the band (1-based).

    Raises:
        ConfigError: one line naming the file and the band: unreadable, no reference system,
            a rotated grid, too large.
    """
    import rasterio

    where = str(path)
    try:
        src = rasterio.open(path)
    except (OSError, rasterio.errors.RasterioIOError) as exc:
        raise ConfigError(f"{where}: not a readable GeoTIFF ({exc})") from None
    with src:
        name = f"band {band}"
        if not 1 <= band <= src.count:
            raise ConfigError(f"{where}: no {name} (the file has {src.count})")
        if src.crs is None:
            raise ConfigError(f"{where}: {name} has no coordinate reference system")
        t = src.transform
        if t.b != 0.0 or t.d != 0.0:
            raise ConfigError(f"{where}: {name} is on a rotated grid (not supported)")
        _check_size((src.height, src.width), where, name)
        data = src.read(band, masked=True).astype(float).filled(np.nan)
        # pixel centres
        x = t.c + t.a * (np.arange(src.width) + 0.5)
        y = t.f + t.e * (np.arange(src.height) + 0.5)
        crs = src.crs.to_wkt()
    depth = -data if values == "elevation" else data
    return _sorted(BathymetryGrid(x, y, depth, crs, where, name))


NETCDF_SUFFIXES = (".nc", ".nc4", ".cdf", ".netcdf")
GEOTIFF_SUFFIXES = (".tif", ".tiff", ".gtiff")


def file_kind(path: str | Path) -> Literal["netcdf", "geotiff"] | None:
    """The kind of a bathymetry file by its suffix, or None for an unknown one."""
    suffix = Path(path).suffix.lower()
    return (
        "netcdf" if suffix in NETCDF_SUFFIXES else "geotiff" if suffix in GEOTIFF_SUFFIXES else None
    )


def grid_shape(path: str | Path, variable: str | None = None) -> tuple[tuple[int, ...], str]:
    """The shape of a bathymetry file's grid and its variable's name, from the header alone
    (nothing of the grid is read), for a memory check before reading.

    Args:
        path: the file.
        variable: the netCDF variable (None: found as :func:`read_netcdf` finds it).

    Returns:
        ``(shape, name)``: the variable's (or band's) shape and its name.

    Raises:
        ConfigError: one line naming the file (and the variable): missing, unreadable, unknown
            kind, no such variable.
    """
    p = _existing(path)
    where = str(path)
    if file_kind(p) == "geotiff":
        import rasterio

        try:
            with rasterio.open(p) as src:
                return (src.height, src.width), "band 1"
        except (OSError, rasterio.errors.RasterioIOError) as exc:
            raise ConfigError(f"{where}: not a readable GeoTIFF ({exc})") from None
    with open_netcdf(p) as ds:
        var = _variable(ds, variable, where)
        return tuple(int(k) for k in var.shape), str(var.name)


def _existing(path: str | Path) -> Path:
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{p}: no such file")
    if file_kind(p) is None:
        raise ConfigError(
            f"{p}: unknown bathymetry file kind '{p.suffix.lower()}' (netCDF .nc or GeoTIFF .tif)"
        )
    return p


def _variable(ds, variable: str | None, where: str):
    """The bathymetry variable of an open netCDF dataset (named, or found by standard name)."""
    if variable is not None:
        if variable not in ds.data_vars:
            raise ConfigError(
                f"{where}: no variable '{variable}' (variables: {', '.join(ds.data_vars)})"
            )
        return ds[variable]
    found = [
        ds[v]
        for v in ds.data_vars
        if ds[v].attrs.get("standard_name") in ELEVATION_NAMES + DEPTH_NAMES
    ]
    if not found:
        raise ConfigError(
            f"{where}: no variable with a standard_name of elevation or depth (one of "
            f"{', '.join(ELEVATION_NAMES + DEPTH_NAMES)})"
        )
    return found[0]


def read_bathymetry(
    path: str | Path,
    variable: str | None = None,
    values: Literal["elevation", "depth"] = "elevation",
) -> BathymetryGrid:
    """Read a bathymetry file by its kind: ``.nc``/``.nc4``/``.cdf`` netCDF, ``.tif``/``.tiff``
    GeoTIFF (see :func:`read_netcdf`, :func:`read_geotiff`).

    Raises:
        ConfigError: for a missing file or an unknown suffix, and what the readers refuse.
    """
    p = _existing(path)
    if file_kind(p) == "netcdf":
        return read_netcdf(p, variable)
    return read_geotiff(p, values)


def _sorted(grid: BathymetryGrid) -> BathymetryGrid:
    ix, iy = np.argsort(grid.x, kind="stable"), np.argsort(grid.y, kind="stable")
    x, y = grid.x[ix], grid.y[iy]
    for a, n in ((x, "x"), (y, "y")):
        if len(a) < 2 or not (np.diff(a) > 0).all() or not np.isfinite(a).all():
            raise ConfigError(
                f"{grid.source}: variable '{grid.variable}': its {n} axis must have at least two "
                "distinct, finite values"
            )
    return BathymetryGrid(x, y, grid.depth_m[np.ix_(iy, ix)], grid.crs, grid.source, grid.variable)


def resample(grid: BathymetryGrid, frame: LocalFrame, half_extent_m: float, cell_m: float) -> Array:
    """The file's depths at the scene's heightfield nodes (cubic in the file's grid).

    Args:
        grid: the file's grid.
        frame: the scene's geographic frame.
        half_extent_m: half side of the scene's square grid, m.
        cell_m: its spacing, m (``half_extent_m`` a whole number of cells).

    Returns:
        Depths, shape (n, n) with n = 2 half / cell + 1, m, ``[i, j]`` at north
        ``-half + i cell``, east ``-half + j cell``.

    Raises:
        ConfigError: naming the file and the variable when the scene reaches beyond the file's
            extent or onto no-data cells.
    """
    from pyproj import CRS, Transformer
    from scipy.interpolate import RectBivariateSpline, RegularGridInterpolator

    n = 2 * round(half_extent_m / cell_m) + 1
    ax = np.linspace(-half_extent_m, half_extent_m, n)
    east, north = np.meshgrid(ax, ax)
    lat, lon = frame.to_geographic(east, north)
    target = CRS.from_user_input(grid.crs)
    if target.equals(CRS.from_epsg(4326), ignore_axis_order=True):
        gx, gy = lon, lat
    else:
        tr = Transformer.from_crs(CRS.from_epsg(4326), target, always_xy=True)
        gx, gy = tr.transform(lon, lat)
    inside = (gx >= grid.x[0]) & (gx <= grid.x[-1]) & (gy >= grid.y[0]) & (gy <= grid.y[-1])
    if not inside.all():
        i, j = np.argwhere(~inside)[0]
        raise ConfigError(
            f"{grid.source}: variable '{grid.variable}' does not cover the scene: the node "
            f"({east[i, j]:g}, {north[i, j]:g}) m east/north is outside the file's extent "
            "(shrink seabed.half_extent_m or move the origin)"
        )
    # the file's nodes around the scene (two beyond each edge: the cubic's support)
    jx = slice(max(0, np.searchsorted(grid.x, gx.min()) - 2), np.searchsorted(grid.x, gx.max()) + 2)
    iy = slice(max(0, np.searchsorted(grid.y, gy.min()) - 2), np.searchsorted(grid.y, gy.max()) + 2)
    x, y, d = grid.x[jx], grid.y[iy], grid.depth_m[iy, jx]
    if not np.isfinite(d).all():
        where = RegularGridInterpolator((y, x), d, method="linear")(np.stack([gy, gx], axis=-1))
        bad = ~np.isfinite(where)
        i, j = np.argwhere(bad)[0] if bad.any() else (0, 0)
        what = (
            f"under the scene at ({east[i, j]:g}, {north[i, j]:g}) m east/north"
            if bad.any()
            else "within two cells of the scene's edge"
        )
        raise ConfigError(
            f"{grid.source}: variable '{grid.variable}' has no data (NaN or no-data cells) {what}"
        )
    # cubic: the resampled surface passes through the file's nodes without the bilinear
    # interpolant's kinks there, so the scene's triangles meet the nodes to O(cell^2 curvature)
    spline = RectBivariateSpline(y, x, d, kx=min(3, len(y) - 1), ky=min(3, len(x) - 1), s=0)
    return spline(gy.ravel(), gx.ravel(), grid=False).reshape(gx.shape)


def write_netcdf(grid: BathymetryGrid, path: str | Path, positive: Literal["up", "down"] = "up"):
    """Write a latitude/longitude grid as a CF netCDF-4 file of elevation (``positive = "up"``,
    GEBCO's convention) or depth (the files the tests and the example site use)."""
    import xarray as xr

    if grid.crs != "EPSG:4326":
        raise ConfigError(f"{path}: a netCDF bathymetry is written on latitude/longitude only")
    values = -grid.depth_m if positive == "up" else grid.depth_m
    std = "height_above_mean_sea_level" if positive == "up" else "sea_floor_depth_below_sea_surface"
    name = "elevation" if positive == "up" else "depth"
    ds = xr.Dataset(
        {
            name: (
                ("lat", "lon"),
                values,
                {"standard_name": std, "units": "m", "positive": positive},
            )
        },
        coords={
            "lat": (
                "lat",
                grid.y,
                {"standard_name": "latitude", "units": "degrees_north", "axis": "Y"},
            ),
            "lon": (
                "lon",
                grid.x,
                {"standard_name": "longitude", "units": "degrees_east", "axis": "X"},
            ),
        },
        attrs={"Conventions": "CF-1.8"},
    )
    ds.to_netcdf(path, engine="netcdf4")


def write_geotiff(grid: BathymetryGrid, path: str | Path, nodata: float = -32767.0) -> None:
    """Write a grid as a one-band GeoTIFF of elevation in its reference system (north up; NaN
    cells as ``nodata``). The axes must be evenly spaced (a raster)."""
    import rasterio
    from affine import Affine

    dx, dy = np.diff(grid.x), np.diff(grid.y)
    if not (np.allclose(dx, dx[0], rtol=1e-9) and np.allclose(dy, dy[0], rtol=1e-9)):
        raise ConfigError(f"{path}: a GeoTIFF needs evenly spaced axes")
    elev = -grid.depth_m[::-1]  # row 0 at the north
    elev = np.where(np.isfinite(elev), elev, nodata)
    # the corner of the north-west pixel, pixels dx wide and dy high
    transform = Affine.translation(grid.x[0] - dx[0] / 2, grid.y[-1] + dy[0] / 2) @ Affine.scale(
        dx[0], -dy[0]
    )
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        height=elev.shape[0],
        width=elev.shape[1],
        count=1,
        dtype="float64",
        crs=grid.crs,
        transform=transform,
        nodata=nodata,
    ) as dst:
        dst.write(elev, 1)
