"""Currents from an ocean model: CF-convention grids of ``u``, ``v`` (and ``w``) on (time, depth,
latitude, longitude), read with xarray and interpolated in space and time.

An ocean model's forecast (CMEMS, HYCOM, ROMS output regridded to latitude/longitude) is a
netCDF file following the CF conventions: coordinates recognised by their ``standard_name``
(``time``, ``depth``, ``latitude``, ``longitude``; or ``axis`` T/Z/Y/X), velocities by theirs
(``eastward_sea_water_velocity``, ``northward_sea_water_velocity``,
``upward_sea_water_velocity``) in m/s (``units`` ``m s-1`` or ``m/s``; cm/s is converted), depth
positive down in metres (``positive = "down"``; an ``up`` axis of heights is turned into depths).
:func:`read_current_grid` reads one with xarray's netCDF4 engine (the reference netCDF library,
which reads netCDF-3 and netCDF-4/HDF5 files alike); :func:`write_current_grid` writes one in the
same conventions (the files the tests and the example site use: nothing is downloaded).

:class:`GriddedCurrent` is a :class:`~bauv_sim.currents.CurrentField`: the water velocity at a
point of the scene is the **linear interpolation** of the grid in time, depth, latitude and
longitude (``scipy.interpolate.RegularGridInterpolator``, method ``linear``: multilinear on a
rectilinear grid), the point's latitude and longitude from the scene's
:class:`~bauv_sim.geo.LocalFrame`. Above the shallowest level the shallowest value holds (an
ocean model's first level is the surface layer's); a grid with one time is steady. Outside the
grid's horizontal extent, below its deepest level or outside its time range the field does not
guess: :meth:`GriddedCurrent.check_covers` refuses the mission before it runs, and an evaluation
outside raises :class:`~bauv_sim.errors.BauvSimError`. The water's acceleration for the
Froude-Krylov force comes from the sea (:mod:`bauv_sim.sea`), which differences the field over
each control tick along the vehicle's motion.
"""

from __future__ import annotations

import datetime as dt
import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim.errors import BauvSimError, ConfigError
from bauv_sim.geo import LocalFrame

Array = NDArray[np.float64]

STANDARD_NAMES = {
    "u": "eastward_sea_water_velocity",
    "v": "northward_sea_water_velocity",
    "w": "upward_sea_water_velocity",
}
"""CF standard names of the velocity components."""
SPEED_UNITS = {
    "m s-1": 1.0,
    "m/s": 1.0,
    "m s**-1": 1.0,
    "meter second-1": 1.0,
    "cm s-1": 0.01,
    "cm/s": 0.01,
}
"""Accepted ``units`` of a velocity, with the factor to m/s."""
MAX_GRID_BYTES = 2 * 1024**3
"""Largest velocity grid read into memory (all components, float64), bytes."""


@dataclass(frozen=True)
class CurrentGrid:
    """A current on a rectilinear (time, depth, latitude, longitude) grid.

    Attributes:
        time_s: times of the grid from the mission's start (t = 0), shape (T,), s, increasing.
        depth_m: depths, shape (D,), m, positive down, increasing.
        latitude_deg: WGS 84 latitudes, shape (Y,), deg, increasing.
        longitude_deg: WGS 84 longitudes, shape (X,), deg, increasing.
        u_m_s: eastward velocity, shape (T, D, Y, X), m/s.
        v_m_s: northward velocity, shape (T, D, Y, X), m/s.
        w_m_s: upward velocity, shape (T, D, Y, X), m/s (zeros when the file has none).
    """

    time_s: Array
    depth_m: Array
    latitude_deg: Array
    longitude_deg: Array
    u_m_s: Array
    v_m_s: Array
    w_m_s: Array

    def __post_init__(self) -> None:
        shape = tuple(
            len(a) for a in (self.time_s, self.depth_m, self.latitude_deg, self.longitude_deg)
        )
        for name in ("u_m_s", "v_m_s", "w_m_s"):
            if np.shape(getattr(self, name)) != shape:
                raise ConfigError(f"{name}: shape {np.shape(getattr(self, name))}, not {shape}")
        for name in ("time_s", "depth_m", "latitude_deg", "longitude_deg"):
            a = np.asarray(getattr(self, name))
            if not np.isfinite(a).all() or (len(a) > 1 and not (np.diff(a) > 0).all()):
                raise ConfigError(f"{name}: must be finite and strictly increasing")


def sample_current_grid(
    field,
    frame: LocalFrame,
    time_s: ArrayLike,
    depth_m: ArrayLike,
    latitude_deg: ArrayLike,
    longitude_deg: ArrayLike,
) -> CurrentGrid:
    """A current field sampled at the nodes of a grid (to write an analytic field as a file).

    Args:
        field: a :class:`~bauv_sim.currents.CurrentField` of the scene.
        frame: the scene's geographic frame.
        time_s, depth_m, latitude_deg, longitude_deg: the grid's axes, shapes (T,), (D,), (Y,),
            (X,) (s from the start, m down, deg, deg).

    Returns:
        The grid, with ``field.velocity_world(t, (east, north, -depth))`` at every node.
    """
    t = np.asarray(time_s, dtype=float)
    d = np.asarray(depth_m, dtype=float)
    lat = np.asarray(latitude_deg, dtype=float)
    lon = np.asarray(longitude_deg, dtype=float)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    east, north = frame.to_local(la, lo)
    out = np.zeros((3, len(t), len(d), len(lat), len(lon)))
    for i, ti in enumerate(t):
        for j, dj in enumerate(d):
            pos = np.stack([east, north, np.full_like(east, -dj)], axis=-1).reshape(-1, 3)
            vel = np.asarray(field.velocity_world(ti, pos), dtype=float).reshape(
                len(lat), len(lon), 3
            )
            out[:, i, j] = np.moveaxis(vel, -1, 0)
    return CurrentGrid(t, d, lat, lon, out[0], out[1], out[2])


def write_current_grid(grid: CurrentGrid, path: str | Path, start: dt.datetime) -> None:
    """Write a grid as a CF-convention netCDF-4 file (what an ocean model's product looks like).

    Args:
        grid: the grid.
        path: the file to write.
        start: the date and time of the mission's t = 0 (UTC); the file's time axis is
            "seconds since" it.
    """
    import xarray as xr

    dims = ("time", "depth", "latitude", "longitude")
    # the time axis as dates, written as CF "seconds since <start>": the grid's seconds exactly
    dates = np.datetime64(start.replace(tzinfo=None), "ns") + (grid.time_s * 1e9).round().astype(
        "timedelta64[ns]"
    )
    coords = {
        "time": ("time", dates, {"standard_name": "time", "axis": "T"}),
        "depth": (
            "depth",
            grid.depth_m,
            {"standard_name": "depth", "axis": "Z", "units": "m", "positive": "down"},
        ),
        "latitude": (
            "latitude",
            grid.latitude_deg,
            {"standard_name": "latitude", "axis": "Y", "units": "degrees_north"},
        ),
        "longitude": (
            "longitude",
            grid.longitude_deg,
            {"standard_name": "longitude", "axis": "X", "units": "degrees_east"},
        ),
    }
    data = {
        key: (dims, getattr(grid, f"{key}_m_s"), {"standard_name": name, "units": "m s-1"})
        for key, name in STANDARD_NAMES.items()
    }
    ds = xr.Dataset(data, coords=coords, attrs={"Conventions": "CF-1.8"})
    units = f"seconds since {start.replace(tzinfo=None).isoformat(sep=' ')}"
    ds.to_netcdf(path, engine="netcdf4", encoding={"time": {"units": units, "dtype": "float64"}})


def open_netcdf(path: str | Path, decode_times: bool = True):
    """Open a netCDF file with xarray's netCDF4 engine (lazily: nothing read but the header).

    Raises:
        ConfigError: the file is missing or not a readable netCDF file (one line naming it).
    """
    import xarray as xr

    where = str(path)
    if not Path(path).is_file():
        raise ConfigError(f"{where}: no such file")
    try:
        return xr.open_dataset(path, engine="netcdf4", decode_times=decode_times)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{where}: not a readable netCDF file ({exc})") from None


def cf_variable(ds, standard_name: str, axis: str | None, where: str, names: tuple[str, ...] = ()):
    """The variable of an xarray dataset with a CF ``standard_name`` (or ``axis`` attribute),
    else the first of ``names`` the dataset has.

    Raises:
        ConfigError: naming the file (``where``) and the standard name when there is none.
    """
    for name in list(ds.coords) + list(ds.data_vars):
        attrs = ds[name].attrs
        if attrs.get("standard_name") == standard_name or (
            axis is not None and attrs.get("axis") == axis
        ):
            return ds[name]
    for name in names:
        if name in ds.variables:
            return ds[name]
    raise ConfigError(f"{where}: no variable with standard_name '{standard_name}'")


def read_current_grid(path: str | Path, start: dt.datetime | None = None) -> CurrentGrid:
    """Read an ocean model's current from a CF-convention netCDF file.

    Args:
        path: the file.
        start: the date and time of the mission's t = 0 (UTC), to place the file's times;
            ``None`` for the file's first time.

    Returns:
        The grid (velocities in m/s, depth positive down, axes increasing).

    Raises:
        ConfigError: one line naming the file, the variable and what is wrong: the file is
            missing or unreadable, a coordinate or velocity is missing, a unit is not one of
            :data:`SPEED_UNITS` (or metres for depth, degrees for latitude/longitude), a
            velocity has NaN or missing cells, or the grid is larger than
            :data:`MAX_GRID_BYTES`.
    """
    where = str(path)
    with open_netcdf(path) as ds:
        time = cf_variable(ds, "time", "T", where)
        depth = cf_variable(ds, "depth", "Z", where)
        lat = cf_variable(ds, "latitude", "Y", where)
        lon = cf_variable(ds, "longitude", "X", where)
        for var, allowed in (
            (lat, ("degrees_north", "degree_north", "degrees")),
            (lon, ("degrees_east", "degree_east", "degrees")),
        ):
            if var.attrs.get("units", "degrees") not in allowed:
                raise ConfigError(
                    f"{where}: variable '{var.name}' has units '{var.attrs.get('units')}', "
                    f"expected one of {', '.join(allowed)}"
                )
        if depth.attrs.get("units", "m") not in ("m", "meter", "meters", "metre", "metres"):
            raise ConfigError(
                f"{where}: variable '{depth.name}' has units '{depth.attrs.get('units')}', "
                "expected m"
            )
        comps = {}
        for key, name in STANDARD_NAMES.items():
            try:
                var = cf_variable(ds, name, None, where)
            except ConfigError:
                if key == "w":
                    continue
                raise
            units = var.attrs.get("units")
            if units not in SPEED_UNITS:
                raise ConfigError(
                    f"{where}: variable '{var.name}' has units '{units}', expected one of "
                    f"{', '.join(SPEED_UNITS)}"
                )
            order = (time.name, depth.name, lat.name, lon.name)
            if set(var.dims) != set(order):
                raise ConfigError(
                    f"{where}: variable '{var.name}' has dimensions {var.dims}, expected {order}"
                )
            nbytes = 8 * math.prod(var.shape) * 3
            if nbytes > MAX_GRID_BYTES:
                raise ConfigError(
                    f"{where}: variable '{var.name}' of shape {var.shape} needs "
                    f"{nbytes / 1024**3:.1f} GiB as a grid (limit "
                    f"{MAX_GRID_BYTES / 1024**3:.0f} GiB): crop the file to the mission's area"
                )
            values = var.transpose(*order).values.astype(float) * SPEED_UNITS[units]
            if not np.isfinite(values).all():
                bad = int((~np.isfinite(values)).sum())
                raise ConfigError(
                    f"{where}: variable '{var.name}' has {bad} NaN or missing cells (land or "
                    "fill values): crop the file to water"
                )
            comps[key] = values
        t = time.values
        if np.issubdtype(t.dtype, np.datetime64):
            t0 = t.min() if start is None else np.datetime64(start.replace(tzinfo=None), "ns")
            t_s = (t - t0) / np.timedelta64(1, "s")
        else:
            t_s = np.asarray(t, dtype=float)
            if start is None:
                t_s = t_s - t_s.min()
        d = np.asarray(depth.values, dtype=float)
        if depth.attrs.get("positive", "down") == "up":
            d = -d
        axes = [
            np.asarray(t_s, dtype=float),
            d,
            np.asarray(lat.values, dtype=float),
            np.asarray(lon.values, dtype=float),
        ]
    # sort every axis increasing (a file may store latitude north to south)
    for ax in range(4):
        order_ = np.argsort(axes[ax], kind="stable")
        axes[ax] = axes[ax][order_]
        for key in comps:
            comps[key] = np.take(comps[key], order_, axis=ax)
    w = comps.get("w", np.zeros_like(comps["u"]))
    return CurrentGrid(axes[0], axes[1], axes[2], axes[3], comps["u"], comps["v"], w)


class GriddedCurrent:
    """A current field interpolated linearly from a grid (see the module docstring).

    Args:
        grid: the grid.
        frame: the scene's geographic frame (east/north -> latitude/longitude).
        name: what to call the grid in messages (its file).
    """

    def __init__(self, grid: CurrentGrid, frame: LocalFrame, name: str = "current grid"):
        from scipy.interpolate import RegularGridInterpolator

        self.grid = grid
        self.frame = frame
        self.name = name
        self.steady = len(grid.time_s) == 1
        self._axes = [grid.time_s, grid.depth_m, grid.latitude_deg, grid.longitude_deg]
        values = np.stack([grid.u_m_s, grid.v_m_s, grid.w_m_s], axis=-1)
        # squeeze single-node axes out of the interpolation: the value holds along them
        self._keep = [len(a) > 1 for a in self._axes]
        sl = tuple(slice(None) if k else 0 for k in self._keep)
        pts = [a for a, k in zip(self._axes, self._keep, strict=True) if k]
        self._values = values[sl]
        self._interp = (
            RegularGridInterpolator(pts, self._values, method="linear", bounds_error=True)
            if pts
            else None
        )

    def _query(self, t: Array, depth: Array, lat: Array, lon: Array) -> Array:
        cols = [c for c, k in zip((t, depth, lat, lon), self._keep, strict=True) if k]
        if self._interp is None:
            return np.broadcast_to(self._values, (len(t), 3)).copy()
        return self._interp(np.stack(cols, axis=-1))

    def check_covers(
        self, t_end_s: float, east_m: ArrayLike, north_m: ArrayLike, max_depth_m: float
    ) -> None:
        """Refuse a mission the grid does not cover (before it runs).

        Args:
            t_end_s: the mission's longest duration, s.
            east_m, north_m: the corners (or every point) of the mission's area, m.
            max_depth_m: the deepest the mission goes, m.

        Raises:
            ConfigError: naming the grid, what is outside and the grid's extent.
        """
        g = self.grid
        if not self.steady and (g.time_s[0] > 0.0 or g.time_s[-1] < t_end_s):
            raise ConfigError(
                f"{self.name}: the mission's time [0, {t_end_s:g}] s is outside the grid's "
                f"[{g.time_s[0]:g}, {g.time_s[-1]:g}] s from the start"
            )
        if len(g.depth_m) > 1 and max_depth_m > g.depth_m[-1]:
            raise ConfigError(
                f"{self.name}: the mission's depth {max_depth_m:g} m is below the grid's deepest "
                f"level {g.depth_m[-1]:g} m"
            )
        lat, lon = self.frame.to_geographic(np.asarray(east_m), np.asarray(north_m))
        out = (
            (lat < g.latitude_deg[0])
            | (lat > g.latitude_deg[-1])
            | (lon < g.longitude_deg[0])
            | (lon > g.longitude_deg[-1])
        )
        if out.any():
            i = int(np.flatnonzero(out.ravel())[0])
            raise ConfigError(
                f"{self.name}: the mission's point ({float(np.ravel(east_m)[i]):g}, "
                f"{float(np.ravel(north_m)[i]):g}) m east/north (lat {float(lat.ravel()[i]):.5f}, "
                f"lon {float(lon.ravel()[i]):.5f}) is outside the grid's latitude "
                f"[{g.latitude_deg[0]:.5f}, {g.latitude_deg[-1]:.5f}] and longitude "
                f"[{g.longitude_deg[0]:.5f}, {g.longitude_deg[-1]:.5f}]"
            )

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> Array:
        """Water velocity at points (see :class:`~bauv_sim.currents.CurrentField`).

        Args:
            t_s: time, s (scalar, or broadcast against the points).
            pos_world_m: points, shape (3,) or (..., 3), m, world ENU.

        Returns:
            Velocity, shape of ``pos_world_m``, m/s, world ENU.

        Raises:
            BauvSimError: at a point or time the grid does not cover.
        """
        pos = np.asarray(pos_world_m, dtype=float)
        flat = pos.reshape(-1, 3)
        lat, lon = self.frame.to_geographic(flat[:, 0], flat[:, 1])
        depth = np.maximum(-flat[:, 2], self.grid.depth_m[0])
        t = np.broadcast_to(np.asarray(t_s, dtype=float).reshape(-1), (len(flat),))
        cols = [np.array(t, dtype=float), depth, lat, lon]
        inside = np.ones(len(flat), dtype=bool)
        for c, a, keep in zip(cols, self._axes, self._keep, strict=True):
            if keep:
                # a node's own coordinates come back through the projection within ~1e-12 deg
                eps = 1e-9 * max(1.0, abs(a[-1] - a[0]))
                c[(c < a[0]) & (c >= a[0] - eps)] = a[0]
                c[(c > a[-1]) & (c <= a[-1] + eps)] = a[-1]
                inside &= (c >= a[0]) & (c <= a[-1])
        if not inside.all():
            i = int(np.flatnonzero(~inside)[0])
            raise BauvSimError(
                f"{self.name}: no current at t = {cols[0][i]:g} s, position "
                f"{flat[i].round(2).tolist()} m (lat {lat[i]:.6f}, lon {lon[i]:.6f}): outside "
                "the grid"
            )
        vel = self._query(*cols)
        return vel.reshape(pos.shape)


@functools.lru_cache(maxsize=4)
def _cached_grid(path: str, mtime_ns: int, size: int, start: dt.datetime | None) -> CurrentGrid:
    return read_current_grid(path, start)


def load_current_grid(path: str | Path, start: dt.datetime | None = None) -> CurrentGrid:
    """:func:`read_current_grid`, read once per process for a file as it is on disk.

    The grid is cached on the file's resolved path, its modification time and size and the
    start (the last four grids): every run of a batch in a worker process builds its sea from the
    same grid without reading the file again, and a file rewritten between batches is read anew.
    The grid's arrays are shared between the runs; nothing writes to them.

    Args:
        path: the file.
        start: the date and time of the mission's t = 0 (UTC), or ``None`` for the file's first
            time.

    Raises:
        ConfigError: as :func:`read_current_grid`.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"{path}: no such file")
    st = p.stat()
    return _cached_grid(str(p.resolve()), st.st_mtime_ns, st.st_size, start)


def current_grid_cells(path: str | Path) -> int:
    """The number of cells of a current file's grid (time x depth x latitude x longitude of its
    eastward velocity), read from its header without reading the velocities: for a memory
    estimate before the file is read.

    Raises:
        ConfigError: the file is missing or unreadable, or has no eastward velocity (one line
            naming the file).
    """
    where = str(path)
    with open_netcdf(path, decode_times=False) as ds:
        return math.prod(cf_variable(ds, STANDARD_NAMES["u"], None, where).shape)
