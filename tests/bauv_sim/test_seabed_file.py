"""The scene's seabed from a bathymetry file (bauv_sim.seabed with ``file``, bauv_sim.build with
``geo``): MuJoCo's heightfield against the file's heights at the file's nodes."""

import math

import mujoco
import numpy as np
import pytest

from bauv_sim import seabed
from bauv_sim.bathymetry import BathymetryGrid, write_geotiff, write_netcdf
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.errors import ConfigError
from bauv_sim.geo import GeoOriginConfig, LocalFrame

GEO = GeoOriginConfig(latitude_deg=43.05, longitude_deg=5.95)
HALF, CELL = 400.0, 5.0


def site_depth(lat, lon):
    """A smooth made-up site: 20 m deep, a 6 m ridge running north-west, a 900 m swell."""
    e = (np.asarray(lon) - 5.95) * 81_400.0
    n = (np.asarray(lat) - 43.05) * 111_100.0
    return (
        20.0
        + 0.004 * n
        - 6.0 * np.exp(-(((e + 0.5 * n) / 250.0) ** 2))
        + 1.5 * np.sin(2 * math.pi * e / 900.0)
    )


def site_grid(step_deg=0.0008, pad_deg=0.008) -> BathymetryGrid:
    lat = np.arange(43.05 - pad_deg, 43.05 + pad_deg + 1e-12, step_deg)
    lon = np.arange(5.95 - pad_deg, 5.95 + pad_deg + 1e-12, step_deg)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    return BathymetryGrid(lon, lat, site_depth(la, lo), "EPSG:4326", "site", "elevation")


def file_config(path, **kw) -> seabed.SeabedConfig:
    return seabed.SeabedConfig(half_extent_m=HALF, cell_m=CELL, file=str(path), **kw)


def mujoco_seabed_z(physics, east, north):
    """World z of the scene's seabed under points, by MuJoCo's own ray (straight down from 10 m
    above the surface, against the seabed geom alone)."""
    m, d = physics.model.ptr, physics.data.ptr
    gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "seabed")
    out = []
    for e, n in zip(np.ravel(east), np.ravel(north), strict=True):
        dist = mujoco.mj_rayHfield(m, d, gid, np.array([e, n, 10.0]), np.array([0.0, 0.0, -1.0]))
        assert dist >= 0, (e, n)
        out.append(10.0 - dist)
    return np.array(out)


def test_netcdf_scene_heights_equal_the_file_at_its_nodes(tmp_path):
    grid = site_grid()
    path = tmp_path / "site.nc"
    write_netcdf(grid, path)
    cfg = file_config(path)
    phys = build_physics(
        SceneConfig(seabed=cfg, geo=GEO, vehicles=(VehicleSpec(depth_m=3.0),), beacons=())
    )
    la, lo = np.meshgrid(grid.y, grid.x, indexing="ij")
    e, n = GEO.frame().to_local(la, lo)
    inside = (np.abs(e) < HALF - CELL) & (np.abs(n) < HALF - CELL)
    assert inside.sum() > 80
    z = mujoco_seabed_z(phys, e[inside], n[inside])
    err = np.abs(z - -grid.depth_m[inside])
    assert err.max() < 0.01, err.max()
    # the same surface as the library's (the triangles MuJoCo collides with)
    bed = seabed.generate(cfg, GEO.frame())
    np.testing.assert_allclose(bed.height_world(e[inside], n[inside]), z, atol=2e-3)
    # not the generated seabed: 6 m at the origin there, about 20 m here
    assert abs(float(bed.depth_at(0.0, 0.0)) - float(site_depth(43.05, 5.95))) < 0.01


def test_geotiff_on_the_scene_nodes_is_the_heightfield(tmp_path):
    """A GeoTIFF in the scene's own projection whose pixels are the scene's nodes: MuJoCo's
    heightfield data, de-normalised, is the file's elevation at every node to 1 cm."""
    frame = GEO.frame()
    ax = np.arange(-HALF - 4 * CELL, HALF + 4 * CELL + 1e-9, CELL)
    E, N = np.meshgrid(ax, ax)
    lat, lon = frame.to_geographic(E, N)
    aeqd = (
        f"+proj=aeqd +lat_0={GEO.latitude_deg!r} +lon_0={GEO.longitude_deg!r} +x_0=0 +y_0=0 "
        "+ellps=WGS84 +units=m +no_defs"
    )
    grid = BathymetryGrid(ax, ax, site_depth(lat, lon), aeqd, "aeqd", "band 1")
    path = tmp_path / "site.tif"
    write_geotiff(grid, path)
    phys = build_physics(
        SceneConfig(seabed=file_config(path), geo=GEO, vehicles=(VehicleSpec(),), beacons=())
    )
    m = phys.model.ptr
    hid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_HFIELD, "seabed")
    gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "seabed")
    nrow, ncol = int(m.hfield_nrow[hid]), int(m.hfield_ncol[hid])
    adr = int(m.hfield_adr[hid])
    data = np.asarray(m.hfield_data[adr : adr + nrow * ncol]).reshape(nrow, ncol)
    z = m.geom_pos[gid][2] + m.hfield_size[hid][2] * data  # de-normalised, world z
    n = round(HALF / CELL)
    assert (nrow, ncol) == (2 * n + 1, 2 * n + 1)
    assert m.hfield_size[hid][0] == HALF
    inner = slice(4, 4 + 2 * n + 1)  # the file's pixels that are the scene's nodes
    err = np.abs(z - -grid.depth_m[inner, inner])
    assert err.max() < 0.01, err.max()


def test_depth_values_and_named_variable(tmp_path):
    grid = site_grid()
    write_netcdf(grid, tmp_path / "depth.nc", positive="down")
    a = seabed.generate(file_config(tmp_path / "depth.nc", variable="depth"), GEO.frame())
    write_netcdf(grid, tmp_path / "elev.nc", positive="up")
    b = seabed.generate(file_config(tmp_path / "elev.nc"), GEO.frame())
    np.testing.assert_array_equal(a.depth_m, b.depth_m)
    # a GeoTIFF band of depths positive down
    flipped = BathymetryGrid(grid.x, grid.y, -grid.depth_m, grid.crs, "d", "band 1")
    write_geotiff(flipped, tmp_path / "depth.tif")  # writes -depth_m: the depths, as elevation
    c = seabed.generate(file_config(tmp_path / "depth.tif", values="depth"), GEO.frame())
    np.testing.assert_allclose(c.depth_m, b.depth_m, atol=1e-9)


def test_file_needs_a_frame_and_fields_belong_to_their_file_kind(tmp_path):
    write_netcdf(site_grid(), tmp_path / "site.nc")
    cfg = file_config(tmp_path / "site.nc")
    with pytest.raises(ConfigError, match=r"^seabed\.file = .*site\.nc: needs the scenario's geo"):
        seabed.generate(cfg)
    with pytest.raises(ConfigError, match=r"seabed\.file = .*gone\.nc: no such file"):
        seabed.generate(file_config(tmp_path / "gone.nc"), GEO.frame())
    with pytest.raises(ValueError, match="variable = 'z': names a variable of a netCDF"):
        seabed.SeabedConfig(file="a.tif", variable="z")
    with pytest.raises(ValueError, match="values = 'depth': is the band of a GeoTIFF"):
        seabed.SeabedConfig(file="a.nc", values="depth")
    with pytest.raises(ValueError, match="variable = 'z'"):
        seabed.SeabedConfig(variable="z")


def test_cached_per_frame_and_file_version(tmp_path):
    path = tmp_path / "site.nc"
    grid = site_grid()
    write_netcdf(grid, path)
    cfg = file_config(path)
    a = seabed.generate(cfg, GEO.frame())
    assert seabed.generate(cfg, GEO.frame()) is a
    assert not a.depth_m.flags.writeable
    other = seabed.generate(cfg, LocalFrame(43.051, 5.95))  # 111 m further north
    e, n = GEO.frame().to_local(43.051, 5.95)
    assert abs(float(other.depth_at(0.0, 0.0)) - float(a.depth_at(e, n))) < 0.01
    assert not np.array_equal(other.depth_m, a.depth_m)
    # the file rewritten (deeper by 1 m): read again
    import os

    write_netcdf(BathymetryGrid(grid.x, grid.y, grid.depth_m + 1.0, grid.crs, "", ""), path)
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    b = seabed.generate(cfg, GEO.frame())
    np.testing.assert_allclose(b.depth_m, a.depth_m + 1.0, atol=1e-9)


def test_memory_terms_from_the_file_header(tmp_path):
    """The grid's bytes count the file's nodes (read from its header, nothing of the grid read)
    and the scene's points."""
    import netCDF4

    path = tmp_path / "big.nc"
    with netCDF4.Dataset(path, "w") as ds:
        ds.createDimension("lat", 30_000)
        ds.createDimension("lon", 40_000)
        lat = ds.createVariable("lat", "f8", ("lat",))
        lat.standard_name, lat.units = "latitude", "degrees_north"
        lat[:] = np.linspace(42.0, 44.0, 30_000)
        lon = ds.createVariable("lon", "f8", ("lon",))
        lon.standard_name, lon.units = "longitude", "degrees_east"
        lon[:] = np.linspace(5.0, 7.0, 40_000)
        v = ds.createVariable("elevation", "f4", ("lat", "lon"))
        v.standard_name, v.units = "height_above_mean_sea_level", "m"
    assert path.stat().st_size < 5_000_000  # declared, never written
    cfg = file_config(path)
    expected = (
        seabed.RESAMPLE_BYTES_PER_POINT * cfg.n**2 + seabed.FILE_BYTES_PER_NODE * 30_000 * 40_000
    )
    assert cfg.grid_bytes == pytest.approx(expected)
    assert f"seabed.file = {path} (variable 'elevation' of 30000 x 40000 nodes)" in cfg.grid_text
