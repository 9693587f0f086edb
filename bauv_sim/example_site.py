"""The example dive site under ``assets/sites/example/``: files in the conventions of real products,
generated here (nothing is downloaded; the site is made up).

The site is off Toulon, origin 43.0500 N, 5.9500 E (WGS 84). Its files are what a team preparing
a dive would bring:

* ``bathymetry.nc``: a CF-1.8 netCDF grid of elevation (positive up, m) on latitude/longitude
  nodes every 0.0005 deg (about 56 m north, 41 m east), +-3.5 km around the origin, as GEBCO or
  EMODnet deliver it;
* ``bathymetry.tif``: the same seabed as a GeoTIFF in UTM zone 31N (EPSG:32631), 50 m pixels, as
  a survey's export in a projected system comes;
* ``currents.nc``: a CF-1.8 netCDF ocean-model current (``eastward_sea_water_velocity``,
  ``northward_sea_water_velocity``, ``upward_sea_water_velocity`` in m s-1) on time x depth x
  latitude x longitude: 0-4 h every 15 min from 2026-06-01 06:00 UTC, depths 0-60 m, every
  0.005 deg (about 560 m north, 410 m east) over +-4.5 km, the resolution of a coastal model;
* ``site.toml``: a scenario file naming the three (``bauv run mission/survey --scenario
  assets/sites/example/site.toml``).

The seabed (depth, m, positive down, at east ``e`` and north ``n`` from the origin, m): a shelf
deepening to the south-east, ``20 + 12 tanh(s / 1500)`` with ``s = 0.6 e - 0.8 n``; a ridge of
5 m along north-south at 400 m east (Gaussian, 150 m wide); and 1.5 m of relief from six plane
waves of 180-600 m wavelength; at least 6 m deep. The current: a semi-diurnal (M2, 12.42 h)
tidal ellipse of 0.25 m/s along 60 deg and 0.08 m/s across, on a 0.05 m/s residual setting
200 deg, plus a steady clockwise gyre of 0.15 m/s at 500 m from its centre (600 m east,
400 m south), both weakening with depth by 40 % at 60 m. Regenerate with
``python -m bauv_sim.example_site`` (bit for bit the same files' values).
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import PROJECT_ROOT
from bauv_sim.bathymetry import BathymetryGrid, write_geotiff, write_netcdf
from bauv_sim.currents import GyreCurrent
from bauv_sim.geo import LocalFrame
from bauv_sim.ocean import sample_current_grid, write_current_grid

Array = NDArray[np.float64]

SITE_DIR = PROJECT_ROOT / "assets" / "sites" / "example"
"""Folder of the example site's files."""
LATITUDE_DEG = 43.05
"""The site's origin, WGS 84 latitude, deg."""
LONGITUDE_DEG = 5.95
"""The site's origin, WGS 84 longitude, deg."""
START = dt.datetime(2026, 6, 1, 6, 0, 0, tzinfo=dt.UTC)
"""The current file's first time (a mission's t = 0 by default)."""
M2_PERIOD_S = 12.4206012 * 3600.0
"""The principal lunar semi-diurnal tide's period, s."""

_RELIEF = (  # (wavelength m, direction deg, phase rad, amplitude m): six plane waves
    (600.0, 20.0, 0.3, 0.55),
    (420.0, 75.0, 1.9, 0.45),
    (330.0, 140.0, 4.0, 0.4),
    (260.0, 200.0, 2.6, 0.35),
    (210.0, 310.0, 5.1, 0.3),
    (180.0, 250.0, 0.9, 0.25),
)


def site_depth_m(east_m: ArrayLike, north_m: ArrayLike) -> Array:
    """The site's true depth (module docstring), m, positive down, at points of the scene.

    Args:
        east_m, north_m: points, any (equal) shape, m, from the origin.

    Returns:
        Depth, the points' shape, m.
    """
    e = np.asarray(east_m, dtype=float)
    n = np.asarray(north_m, dtype=float)
    s = 0.6 * e - 0.8 * n
    depth = 20.0 + 12.0 * np.tanh(s / 1500.0) - 5.0 * np.exp(-(((e - 400.0) / 150.0) ** 2))
    for wavelength, direction, phase, amplitude in _RELIEF:
        k = 2.0 * math.pi / wavelength
        a = math.radians(direction)
        depth = depth + amplitude * np.sin(k * (e * math.sin(a) + n * math.cos(a)) + phase)
    return np.maximum(depth, 6.0)


class SiteCurrent:
    """The site's true current (module docstring), a :class:`~bauv_sim.currents.CurrentField`."""

    def __init__(self) -> None:
        self._gyre = GyreCurrent((600.0, -400.0), 500.0, 0.15, clockwise=True)

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> Array:
        """Water velocity, shape of ``pos_world_m`` (..., 3), m/s, world ENU, at time ``t_s``
        (s from :data:`START`)."""
        p = np.asarray(pos_world_m, dtype=float)
        phase = 2.0 * math.pi * np.asarray(t_s, dtype=float) / M2_PERIOD_S
        major, minor = 0.25 * np.cos(phase), 0.08 * np.sin(phase)
        a = math.radians(60.0)
        tide_e = major * math.sin(a) + minor * math.cos(a)
        tide_n = major * math.cos(a) - minor * math.sin(a)
        r = math.radians(200.0)
        gyre = self._gyre.velocity_world(t_s, p)
        east = tide_e + 0.05 * math.sin(r) + gyre[..., 0]
        north = tide_n + 0.05 * math.cos(r) + gyre[..., 1]
        scale = 1.0 - 0.4 * np.clip(-p[..., 2], 0.0, 60.0) / 60.0
        east, north = np.broadcast_arrays(east * scale, north * scale)
        return np.stack([east, north, np.zeros_like(east)], axis=-1)


def frame() -> LocalFrame:
    """The site's east/north frame."""
    return LocalFrame(LATITUDE_DEG, LONGITUDE_DEG)


def bathymetry_grid() -> BathymetryGrid:
    """The site's seabed on latitude/longitude nodes (``bathymetry.nc``)."""
    lat = np.round(LATITUDE_DEG + 0.0005 * np.arange(-63, 64), 10)
    lon = np.round(LONGITUDE_DEG + 0.0005 * np.arange(-85, 86), 10)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    east, north = frame().to_local(la, lo)
    return BathymetryGrid(lon, lat, site_depth_m(east, north), "EPSG:4326", "example", "elevation")


def bathymetry_utm_grid() -> BathymetryGrid:
    """The site's seabed on a UTM 31N raster of 50 m pixels (``bathymetry.tif``)."""
    from pyproj import Transformer

    to_utm = Transformer.from_crs("EPSG:4326", "EPSG:32631", always_xy=True)
    x0, y0 = to_utm.transform(LONGITUDE_DEG, LATITUDE_DEG)
    x = np.round(x0 / 50.0) * 50.0 + 50.0 * np.arange(-70, 71)
    y = np.round(y0 / 50.0) * 50.0 + 50.0 * np.arange(-70, 71)
    xx, yy = np.meshgrid(x, y)
    lon, lat = to_utm.transform(xx, yy, direction="INVERSE")
    east, north = frame().to_local(lat, lon)
    return BathymetryGrid(x, y, site_depth_m(east, north), "EPSG:32631", "example", "band 1")


def current_grid():
    """The site's current on the ocean model's grid (``currents.nc``)."""
    times = 900.0 * np.arange(17)
    depths = np.array([0.0, 5.0, 10.0, 20.0, 40.0, 60.0])
    lat = np.round(LATITUDE_DEG + 0.005 * np.arange(-9, 10), 10)
    lon = np.round(LONGITUDE_DEG + 0.005 * np.arange(-12, 13), 10)
    return sample_current_grid(SiteCurrent(), frame(), times, depths, lat, lon)


SITE_TOML = """\
# The example site (bauv_sim/example_site.py): generated data in the conventions of real
# products. Paths are relative to the directory bauv is run from (the repository's root).
#   bauv run mission/survey --scenario assets/sites/example/site.toml
[geo]
latitude_deg = {lat}
longitude_deg = {lon}

[seabed]
file = "assets/sites/example/bathymetry.nc"

[current]
kind = "gridded"
file = "assets/sites/example/currents.nc"
"""


def write_site(folder: str | Path = SITE_DIR) -> list[Path]:
    """Write the site's files into ``folder``.

    Returns:
        The files written.
    """
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "bathymetry.nc", out / "bathymetry.tif", out / "currents.nc", out / "site.toml"]
    write_netcdf(bathymetry_grid(), files[0], positive="up")
    write_geotiff(bathymetry_utm_grid(), files[1])
    write_current_grid(current_grid(), files[2], START)
    files[3].write_text(SITE_TOML.format(lat=LATITUDE_DEG, lon=LONGITUDE_DEG))
    return files


def main(argv: list[str] | None = None) -> None:
    """``python -m bauv_sim.example_site [--out DIR]``: write the example site."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(SITE_DIR), help="folder (default: assets/sites/example)")
    for f in write_site(ap.parse_args(argv).out):
        print(f)


if __name__ == "__main__":
    main()
