"""``mission/survey`` on the site's bathymetry file (issue 25, checks 3 and 5): the scene and the
recording are the file's seabed; bad files are refused in one line before anything is written."""

from __future__ import annotations

import subprocess
import sys
import tomllib

import numpy as np
import pytest

from bauv_sim.bathymetry import write_netcdf
from tests.bauv_sim.test_seabed_file import GEO, mujoco_seabed_z, site_grid
from tests.tasks.refusal import assert_refused

GEO_SET = (
    "--set",
    f"geo.latitude_deg={GEO.latitude_deg}",
    "--set",
    f"geo.longitude_deg={GEO.longitude_deg}",
)


def _static(path, entity: str, component: str) -> np.ndarray:
    """A static component of an entity read back from an ``.rrd`` file."""
    import rerun.chunk as rc

    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path == "/" + entity and chunk.is_static:
            rb = chunk.to_record_batch()
            if component in rb.schema.names:
                return np.asarray(rb.column(component).to_pylist()[0], dtype=float)
    raise KeyError(f"{entity}:{component} not in {path}")


@pytest.fixture(scope="module")
def survey(tmp_path_factory):
    """One short survey run on a netCDF site file (1.8 km a side, 20 m deep with a ridge)."""
    tmp = tmp_path_factory.mktemp("site")
    grid = site_grid(step_deg=0.0005, pad_deg=0.012)
    write_netcdf(grid, tmp / "site.nc")
    out = tmp / "run"
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "tasks.core.cli",
            "run",
            "mission/survey",
            "--runs",
            "1",
            "--quiet",
            "--out",
            str(out),
            *GEO_SET,
            "--set",
            "seabed.file=site.nc",
            "--set",
            "seabed.half_extent_m=600",
            "--set",
            "timing.max_duration_s=60",
        ],
        capture_output=True,
        text=True,
        cwd=tmp,
    )
    assert res.returncode == 0, res.stderr
    return tmp, grid, out


@pytest.mark.slow
def test_survey_runs_on_the_file_and_its_scene_is_the_file(survey, monkeypatch):
    from tasks.closed_loop.world import single_vehicle_scene
    from tasks.core.registry import get

    tmp, grid, out = survey
    scenario = tomllib.loads((out / "scenario.toml").read_text())
    assert scenario["seabed"]["file"] == "site.nc"
    assert scenario["geo"] == {"latitude_deg": 43.05, "longitude_deg": 5.95}
    monkeypatch.chdir(tmp)  # the file's path is relative to where the run was started
    scn = get("mission/survey").scenario_type.model_validate(scenario)
    from bauv_sim.build import build_physics

    phys = build_physics(single_vehicle_scene(scn))
    la, lo = np.meshgrid(grid.y, grid.x, indexing="ij")
    e, n = GEO.frame().to_local(la, lo)
    inside = (np.abs(e) < 590.0) & (np.abs(n) < 590.0)
    assert inside.sum() > 200
    z = mujoco_seabed_z(phys, e[inside], n[inside])
    assert np.abs(z + grid.depth_m[inside]).max() < 0.01


def test_recording_shows_the_sites_seabed(survey):
    """The recording's seabed mesh, read back from the .rrd, is the file's surface: at every
    node of the file it covers, the mesh (its own triangles) is the file's height to 1 cm."""
    from matplotlib.tri import LinearTriInterpolator, Triangulation

    _, grid, out = survey
    rrd = out / "recording.rrd"
    verts = _static(rrd, "world/seabed", "Mesh3D:vertex_positions")
    tris = _static(rrd, "world/seabed", "Mesh3D:triangle_indices").astype(int)
    assert len(verts) > 1000
    tri = Triangulation(verts[:, 0], verts[:, 1], tris)
    la, lo = np.meshgrid(grid.y, grid.x, indexing="ij")
    e, n = GEO.frame().to_local(la, lo)
    lo_xy, hi_xy = verts[:, :2].min(axis=0), verts[:, :2].max(axis=0)
    inside = (e > lo_xy[0]) & (e < hi_xy[0]) & (n > lo_xy[1]) & (n < hi_xy[1])
    assert inside.sum() > 20
    z = LinearTriInterpolator(tri, verts[:, 2])(e[inside], n[inside])
    assert not np.ma.is_masked(z)
    assert np.abs(np.asarray(z) + grid.depth_m[inside]).max() < 0.01


# -- check 5: bad bathymetry files from the command line ----------------------------------------


def _rewrite(tmp_path, name, mutate):
    import xarray as xr

    grid = site_grid()
    write_netcdf(grid, tmp_path / "good.nc")
    ds = xr.open_dataset(tmp_path / "good.nc", engine="netcdf4").load()
    ds.close()
    mutate(ds).to_netcdf(tmp_path / name, engine="netcdf4")
    return name


def _refused(tmp_path, file, pattern, *extra):
    assert_refused(
        tmp_path,
        "mission/survey",
        *GEO_SET,
        "--set",
        f"seabed.file={file}",
        "--set",
        "seabed.half_extent_m=400",
        *extra,
        pattern=pattern,
    )


@pytest.mark.slow
def test_missing_variable_is_refused(tmp_path):
    def unnamed(ds):
        ds["elevation"].attrs["standard_name"] = "sea_surface_height"
        return ds

    name = _rewrite(tmp_path, "unnamed.nc", unnamed)
    _refused(tmp_path, name, "unnamed.nc: no variable with a standard_name of elevation or depth")
    _refused(
        tmp_path,
        "good.nc",
        "good.nc: no variable 'bathy' (variables: elevation)",
        "--set",
        "seabed.variable=bathy",
    )


@pytest.mark.slow
def test_wrong_units_are_refused(tmp_path):
    def fathoms(ds):
        ds["elevation"].attrs["units"] = "fathoms"
        return ds

    name = _rewrite(tmp_path, "fathoms.nc", fathoms)
    _refused(tmp_path, name, "fathoms.nc: variable 'elevation' has units 'fathoms', expected m")


@pytest.mark.slow
def test_nan_cells_under_the_scene_are_refused(tmp_path):
    def hole(ds):
        ds["elevation"][10, 10] = np.nan  # the grid's centre, under the scene
        return ds

    name = _rewrite(tmp_path, "hole.nc", hole)
    _refused(tmp_path, name, "hole.nc: variable 'elevation' has no data (NaN or no-data cells)")


@pytest.mark.slow
def test_scene_outside_the_files_extent_is_refused(tmp_path):
    write_netcdf(site_grid(), tmp_path / "small.nc")  # +-0.008 deg: about +-650 m east
    assert_refused(
        tmp_path,
        "mission/survey",
        *GEO_SET,
        "--set",
        "seabed.file=small.nc",
        pattern="small.nc: variable 'elevation' does not cover the scene",
    )  # the default seabed.half_extent_m = 1000 m


@pytest.mark.slow
def test_a_file_without_a_geo_origin_is_refused(tmp_path):
    write_netcdf(site_grid(), tmp_path / "site.nc")
    assert_refused(
        tmp_path,
        "mission/survey",
        "--set",
        "seabed.file=site.nc",
        "--set",
        "seabed.half_extent_m=400",
        pattern="seabed.file = site.nc: needs the scenario's geo origin (geo.latitude_deg, "
        "geo.longitude_deg)",
    )


@pytest.mark.slow
def test_a_grid_too_large_for_memory_is_refused(tmp_path):
    """A real netCDF declaring 100000 x 100000 nodes (never written: a few MB on disk)."""
    import netCDF4

    path = tmp_path / "huge.nc"
    with netCDF4.Dataset(path, "w") as ds:
        for name, lo, hi, axis in (("lat", 42.0, 44.0, "latitude"), ("lon", 5.0, 7.0, "longitude")):
            ds.createDimension(name, 100_000)
            v = ds.createVariable(name, "f8", (name,))
            v.standard_name = axis
            v.units = "degrees_north" if name == "lat" else "degrees_east"
            v[:] = np.linspace(lo, hi, 100_000)
        z = ds.createVariable("elevation", "f4", ("lat", "lon"))
        z.standard_name, z.units = "height_above_mean_sea_level", "m"
    assert path.stat().st_size < 10_000_000
    _refused(
        tmp_path,
        "huge.nc",
        "seabed.file = huge.nc (variable 'elevation' of 100000 x 100000 nodes)",
    )


def test_trn_navigator_map_is_a_degraded_copy_of_the_file(tmp_path):
    """mission/trn on a site file: the true map is the file's seabed (the site's heights at its
    nodes, from the analytic site the file was written from) and the navigator's map is the
    degraded copy of it (its offset and node noise), not of a generated seabed."""
    from bauv_sim.geo import GeoOriginConfig
    from tasks.missions.trn.scenario import PRESET, SEABED_PRESET, TrnScenario
    from tasks.missions.trn.terrain import navigator_map, true_map
    from tests.bauv_sim.test_seabed_file import site_depth

    write_netcdf(site_grid(step_deg=0.0002, pad_deg=0.005), tmp_path / "site.nc")
    scn = TrnScenario.model_validate(
        {
            **PRESET,
            "geo": {"latitude_deg": GEO.latitude_deg, "longitude_deg": GEO.longitude_deg},
            "seabed": {**SEABED_PRESET, "file": str(tmp_path / "site.nc")},
        }
    )
    assert scn.geo == GeoOriginConfig(latitude_deg=43.05, longitude_deg=5.95)
    frame = scn.frame()
    truth = true_map(scn.seabed, frame=frame)
    X, Y = np.meshgrid(truth.x_m, truth.y_m)
    site = site_depth(*frame.to_geographic(X, Y))
    assert np.abs(truth.depth_m - site).max() < 0.01
    nav = navigator_map(scn, seed=3)
    assert nav.x_m[1] - nav.x_m[0] == pytest.approx(scn.map.cell_m)
    Xn, Yn = np.meshgrid(nav.x_m, nav.y_m)
    err = nav.depth_m - site_depth(*frame.to_geographic(Xn, Yn))
    assert abs(err.mean() - scn.map.offset_m) < 0.005, err.mean()
    assert abs(err.std() - scn.map.vertical_sigma_m) < 0.005, err.std()
