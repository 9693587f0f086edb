"""Bathymetry files (bauv_sim.bathymetry): netCDF and GeoTIFF, resampled to the scene."""

import math

import numpy as np
import pytest

from bauv_sim.bathymetry import (
    BathymetryGrid,
    read_bathymetry,
    resample,
    write_geotiff,
    write_netcdf,
)
from bauv_sim.errors import ConfigError
from bauv_sim.geo import LocalFrame
from bauv_sim.seabed import Seabed, SeabedConfig

FRAME = LocalFrame(43.05, 5.95)
HALF, CELL = 400.0, 5.0


def _depth(lat, lon):
    """A smooth site: 30 m deep, a 12 m ridge running north-east, a 2 km swell."""
    e = (lon - 5.95) * 81_000.0
    n = (lat - 43.05) * 111_000.0
    return (
        30.0
        + 0.01 * n
        + 12.0 * np.exp(-(((e - n) / 300.0) ** 2)) * -1.0
        + 2.0 * np.sin(2 * math.pi * e / 2000.0)
    )


def _grid(step_deg=0.0008, pad=0.008):
    lat = np.arange(43.05 - pad, 43.05 + pad + 1e-12, step_deg)
    lon = np.arange(5.95 - pad, 5.95 + pad + 1e-12, step_deg)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    return BathymetryGrid(lon, lat, _depth(la, lo), "EPSG:4326", "site", "elevation")


def _check_nodes(grid: BathymetryGrid, depth_scene):
    """The heightfield (the triangles MuJoCo collides with) equals the file at its nodes under
    the scene to 1 cm."""
    cfg = SeabedConfig(half_extent_m=HALF, cell_m=CELL, depth_at_origin_m=6.0)
    bed = Seabed(cfg, depth_scene)
    la, lo = np.meshgrid(grid.y, grid.x, indexing="ij")
    e, n = FRAME.to_local(la, lo)
    inside = (np.abs(e) < HALF - CELL) & (np.abs(n) < HALF - CELL)
    assert inside.sum() > 100
    got = bed.depth_at(e[inside], n[inside])
    err = np.abs(got - grid.depth_m[inside])
    assert err.max() < 0.01, err.max()


@pytest.mark.parametrize("positive", ["up", "down"])
def test_netcdf_becomes_a_heightfield_equal_to_the_file_at_its_nodes(tmp_path, positive):
    grid = _grid()
    path = tmp_path / "site.nc"
    write_netcdf(grid, path, positive=positive)
    back = read_bathymetry(path)
    np.testing.assert_array_equal(back.depth_m, grid.depth_m)
    _check_nodes(grid, resample(back, FRAME, HALF, CELL))


def test_geotiff_geographic_and_utm(tmp_path):
    grid = _grid()
    path = tmp_path / "site.tif"
    write_geotiff(grid, path)
    back = read_bathymetry(path)
    np.testing.assert_allclose(back.x, grid.x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.depth_m, grid.depth_m, rtol=0, atol=1e-9)
    _check_nodes(grid, resample(back, FRAME, HALF, CELL))
    # the same site in UTM zone 31N (EPSG:32631) on a 25 m raster
    from pyproj import Transformer

    to_utm = Transformer.from_crs("EPSG:4326", "EPSG:32631", always_xy=True)
    x0, y0 = to_utm.transform(5.95, 43.05)
    x = x0 + np.arange(-700.0, 700.0 + 1e-9, 25.0)
    y = y0 + np.arange(-700.0, 700.0 + 1e-9, 25.0)
    X, Y = np.meshgrid(x, y)
    lon, lat = to_utm.transform(X, Y, direction="INVERSE")
    utm = BathymetryGrid(x, y, _depth(lat, lon), "EPSG:32631", "utm", "band 1")
    write_geotiff(utm, tmp_path / "utm.tif")
    back = read_bathymetry(tmp_path / "utm.tif")
    depth = resample(back, FRAME, HALF, CELL)
    cfg = SeabedConfig(half_extent_m=HALF, cell_m=CELL, depth_at_origin_m=6.0)
    bed = Seabed(cfg, depth)
    lon_n, lat_n = to_utm.transform(X, Y, direction="INVERSE")
    e, n = FRAME.to_local(lat_n, lon_n)
    inside = (np.abs(e) < HALF - CELL) & (np.abs(n) < HALF - CELL)
    assert np.max(np.abs(bed.depth_at(e[inside], n[inside]) - utm.depth_m[inside])) < 0.01


def test_bad_files_are_refused_in_one_line(tmp_path, monkeypatch):
    import xarray as xr

    import bauv_sim.bathymetry as bathy

    grid = _grid()
    good = tmp_path / "good.nc"
    write_netcdf(grid, good)
    with pytest.raises(ConfigError, match=r"nowhere\.nc: no such file"):
        read_bathymetry(tmp_path / "nowhere.nc")
    with pytest.raises(ConfigError, match=r"unknown bathymetry file kind '\.xyz'"):
        (tmp_path / "a.xyz").write_text("1 2 3")
        read_bathymetry(tmp_path / "a.xyz")

    def rewrite(mutate, name):
        ds = xr.open_dataset(good, engine="netcdf4").load()
        ds.close()
        path = tmp_path / name
        mutate(ds).to_netcdf(path, engine="netcdf4")
        return path

    def feet(ds):
        ds["elevation"].attrs["units"] = "ft"
        return ds

    with pytest.raises(ConfigError, match=r"feet\.nc: variable 'elevation' has units 'ft'"):
        read_bathymetry(rewrite(feet, "feet.nc"))
    with pytest.raises(ConfigError, match=r"novar\.nc: no variable with a standard_name"):
        read_bathymetry(
            rewrite(
                lambda ds: ds.rename({"elevation": "z"}).assign(
                    z=lambda d: d["z"].assign_attrs(standard_name="other")
                ),
                "novar.nc",
            )
        )

    def hole(ds):
        ds["elevation"][5, 5] = np.nan
        return ds

    holed = read_bathymetry(rewrite(hole, "hole.nc"))
    with pytest.raises(ConfigError, match=r"hole\.nc: variable 'elevation' has no data"):
        resample(holed, FRAME, HALF, CELL)
    with pytest.raises(ConfigError, match=r"good\.nc: variable 'elevation' does not cover"):
        resample(read_bathymetry(good), FRAME, 2000.0, 10.0)
    monkeypatch.setattr(bathy, "MAX_BATHYMETRY_BYTES", 100)
    with pytest.raises(ConfigError, match=r"good\.nc: variable 'elevation' of shape .* crop"):
        read_bathymetry(good)
