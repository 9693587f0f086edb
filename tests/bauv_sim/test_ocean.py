"""Currents from an ocean model's CF grid (bauv_sim.ocean): written, read back, interpolated."""

import datetime as dt
import math

import numpy as np
import pytest

from bauv_sim.currents import GyreCurrent, SumCurrent, UniformCurrent
from bauv_sim.errors import BauvSimError, ConfigError
from bauv_sim.geo import LocalFrame
from bauv_sim.ocean import (
    GriddedCurrent,
    read_current_grid,
    sample_current_grid,
    write_current_grid,
)

START = dt.datetime(2026, 6, 1, 12, 0, 0)
FRAME = LocalFrame(43.2, 5.3)


def _field(tidal: bool):
    return SumCurrent(
        UniformCurrent(0.15, math.radians(60.0)),
        GyreCurrent((150.0, -80.0), 300.0, 0.25, True, 600.0 if tidal else None),
    )


def _axes(n_t: int):
    lat = 43.2 + np.linspace(-0.01, 0.012, 7)
    lon = 5.3 + np.linspace(-0.013, 0.011, 9)
    depth = np.array([0.0, 5.0, 12.0, 30.0])
    t = np.linspace(0.0, 900.0, n_t) if n_t > 1 else np.array([0.0])
    return t, depth, lat, lon


@pytest.fixture(params=[1, 4], ids=["steady", "tidal"])
def written(request, tmp_path):
    n_t = request.param
    field = _field(tidal=n_t > 1)
    grid = sample_current_grid(field, FRAME, *_axes(n_t))
    path = tmp_path / "current.nc"
    write_current_grid(grid, path, START)
    return field, grid, path


def test_read_back_equals_the_analytic_field_at_the_nodes(written):
    field, grid, path = written
    back = read_current_grid(path, START)
    for name in ("time_s", "depth_m", "latitude_deg", "longitude_deg"):
        np.testing.assert_array_equal(getattr(back, name), getattr(grid, name))
    gc = GriddedCurrent(back, FRAME)
    t, depth, lat, lon = _axes(len(grid.time_s))
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    east, north = FRAME.to_local(la, lo)
    for ti in t:
        for d in depth:
            pos = np.stack([east, north, np.full_like(east, -d)], -1)
            want = field.velocity_world(ti, pos.reshape(-1, 3))
            got = gc.velocity_world(ti, pos.reshape(-1, 3))
            assert np.max(np.abs(got - want)) < 1e-9


def test_interpolates_linearly_between_nodes_and_times(written):
    _, grid, path = written
    gc = GriddedCurrent(read_current_grid(path, START), FRAME)
    lat_m = 0.5 * (grid.latitude_deg[2] + grid.latitude_deg[3])
    lon_m = 0.5 * (grid.longitude_deg[4] + grid.longitude_deg[5])
    e, n = FRAME.to_local(lat_m, lon_m)
    d_m = 0.5 * (grid.depth_m[1] + grid.depth_m[2])
    t_m = 0.5 * (grid.time_s[1] + grid.time_s[2]) if len(grid.time_s) > 1 else 0.0
    got = gc.velocity_world(t_m, np.array([float(e), float(n), -d_m]))
    # the multilinear midpoint is the mean of the cell's corners (2^3 or 2^4 of them)
    ts = [1, 2] if len(grid.time_s) > 1 else [0]
    corners = [
        np.array([c[i, j, k, m] for c in (grid.u_m_s, grid.v_m_s, grid.w_m_s)])
        for i in ts
        for j in (1, 2)
        for k in (2, 3)
        for m in (4, 5)
    ]
    np.testing.assert_allclose(got, np.mean(corners, axis=0), rtol=0, atol=1e-12)
    # a quarter of the way along longitude only: 3/4 and 1/4 of the two nodes
    lon_q = grid.longitude_deg[4] + 0.25 * (grid.longitude_deg[5] - grid.longitude_deg[4])
    e, n = FRAME.to_local(grid.latitude_deg[2], lon_q)
    got = gc.velocity_world(grid.time_s[0], np.array([float(e), float(n), -grid.depth_m[1]]))
    want = 0.75 * grid.u_m_s[0, 1, 2, 4] + 0.25 * grid.u_m_s[0, 1, 2, 5]
    assert abs(got[0] - want) < 1e-12


def test_above_the_first_level_the_first_level_holds(written):
    _, grid, path = written
    gc = GriddedCurrent(read_current_grid(path, START), FRAME)
    e, n = FRAME.to_local(grid.latitude_deg[3], grid.longitude_deg[4])
    above = gc.velocity_world(0.0, np.array([float(e), float(n), 0.5]))
    at0 = gc.velocity_world(0.0, np.array([float(e), float(n), 0.0]))
    np.testing.assert_array_equal(above, at0)


def test_outside_the_grid_is_refused(written):
    _, _, path = written
    gc = GriddedCurrent(read_current_grid(path, START), FRAME)
    with pytest.raises(BauvSimError, match="outside the grid"):
        gc.velocity_world(0.0, np.array([5000.0, 0.0, -3.0]))
    with pytest.raises(ConfigError, match="outside the grid's latitude"):
        gc.check_covers(100.0, [0.0, 5000.0], [0.0, 0.0], 10.0)
    with pytest.raises(ConfigError, match="below the grid's deepest level 30 m"):
        gc.check_covers(100.0, [0.0], [0.0], 40.0)
    if not gc.steady:
        with pytest.raises(ConfigError, match=r"time \[0, 1000\] s is outside"):
            gc.check_covers(1000.0, [0.0], [0.0], 10.0)
    gc.check_covers(900.0, [0.0, 100.0], [0.0, -100.0], 30.0)


def _write(tmp_path, mutate):
    import xarray as xr

    grid = sample_current_grid(_field(False), FRAME, *_axes(1))
    path = tmp_path / "good.nc"
    write_current_grid(grid, path, START)
    ds = xr.open_dataset(path, engine="netcdf4").load()
    ds.close()
    ds = mutate(ds)
    bad = tmp_path / "bad.nc"
    ds.to_netcdf(bad, engine="netcdf4")
    return bad


def test_bad_files_name_the_file_the_variable_and_what_is_wrong(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        read_current_grid(tmp_path / "missing.nc", START)
    (tmp_path / "junk.nc").write_text("not netcdf")
    with pytest.raises(ConfigError, match=r"junk\.nc: not a readable netCDF file"):
        read_current_grid(tmp_path / "junk.nc", START)
    bad = _write(tmp_path, lambda ds: ds.drop_vars("v"))
    with pytest.raises(
        ConfigError, match=r"bad\.nc: no variable with standard_name 'northward_sea_water_velocity'"
    ):
        read_current_grid(bad, START)

    def knots(ds):
        ds["u"].attrs["units"] = "knots"
        return ds

    with pytest.raises(ConfigError, match=r"bad\.nc: variable 'u' has units 'knots'"):
        read_current_grid(_write(tmp_path, knots), START)

    def land(ds):
        ds["u"][0, 0, 1, 1] = np.nan
        return ds

    with pytest.raises(ConfigError, match=r"bad\.nc: variable 'u' has 1 NaN or missing cells"):
        read_current_grid(_write(tmp_path, land), START)


def test_a_grid_too_large_is_refused_before_it_is_read(tmp_path, monkeypatch):
    import bauv_sim.ocean as ocean

    grid = sample_current_grid(_field(False), FRAME, *_axes(1))
    path = tmp_path / "c.nc"
    write_current_grid(grid, path, START)
    monkeypatch.setattr(ocean, "MAX_GRID_BYTES", 1000)
    with pytest.raises(ConfigError, match=r"c\.nc: variable 'u' of shape .* crop the file"):
        read_current_grid(path, START)


def test_centimetres_per_second_and_a_height_axis_are_converted(tmp_path):
    grid = sample_current_grid(_field(False), FRAME, *_axes(1))

    def cm_and_up(ds):
        for k in ("u", "v", "w"):
            ds[k] = ds[k] * 100.0
            ds[k].attrs = {
                "standard_name": ds[k].attrs.get(
                    "standard_name",
                    {
                        "u": "eastward_sea_water_velocity",
                        "v": "northward_sea_water_velocity",
                        "w": "upward_sea_water_velocity",
                    }[k],
                ),
                "units": "cm s-1",
            }
        ds = ds.assign_coords(
            depth=(
                "depth",
                -ds["depth"].values,
                {"standard_name": "depth", "units": "m", "positive": "up"},
            )
        )
        return ds

    back = read_current_grid(_write(tmp_path, cm_and_up), START)
    np.testing.assert_array_equal(back.depth_m, grid.depth_m)
    np.testing.assert_allclose(back.u_m_s, grid.u_m_s, rtol=1e-12, atol=1e-15)
