"""The example site under assets/sites/example: the committed files are what the generator
writes, and they read back through the project's readers as the site's analytic sea."""

from __future__ import annotations

import numpy as np
import pytest

from bauv_sim import bathymetry, example_site, ocean
from bauv_sim.config import loads_toml


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    folder = tmp_path_factory.mktemp("site")
    example_site.write_site(folder)
    return folder


@pytest.mark.parametrize("name", ["bathymetry.nc", "bathymetry.tif"])
def test_committed_bathymetry_is_the_generators(fresh, name):
    got = bathymetry.read_bathymetry(example_site.SITE_DIR / name)
    new = bathymetry.read_bathymetry(fresh / name)
    np.testing.assert_array_equal(got.depth_m, new.depth_m)
    np.testing.assert_array_equal(got.x, new.x)
    np.testing.assert_array_equal(got.y, new.y)


def test_committed_current_is_the_generators(fresh):
    got = ocean.read_current_grid(example_site.SITE_DIR / "currents.nc", example_site.START)
    new = ocean.read_current_grid(fresh / "currents.nc", example_site.START)
    for name in ("time_s", "depth_m", "latitude_deg", "longitude_deg", "u_m_s", "v_m_s"):
        np.testing.assert_array_equal(getattr(got, name), getattr(new, name))
    assert (example_site.SITE_DIR / "site.toml").read_text() == (fresh / "site.toml").read_text()


def test_bathymetry_at_the_nodes_is_the_sites_seabed():
    """The netCDF's nodes hold the analytic depth of the module docstring (worked out here from
    the nodes' latitude/longitude through the site's frame)."""
    g = bathymetry.read_bathymetry(example_site.SITE_DIR / "bathymetry.nc")
    lo, la = np.meshgrid(g.x, g.y)
    e, n = example_site.frame().to_local(la, lo)
    s = 0.6 * e - 0.8 * n
    shelf = 20.0 + 12.0 * np.tanh(s / 1500.0) - 5.0 * np.exp(-(((e - 400.0) / 150.0) ** 2))
    deep = g.depth_m > 6.0  # not clipped at the site's shallowest depth
    assert np.abs(g.depth_m - shelf)[deep].max() <= 2.3 + 1e-9  # the relief's amplitudes' sum
    np.testing.assert_allclose(g.depth_m, example_site.site_depth_m(e, n), atol=1e-9)
    assert 6.0 <= g.depth_m.min() and g.depth_m.max() < 45.0


def test_current_is_time_varying_and_follows_the_tide():
    """The M2 tide turns the flow: at the origin's surface the current at t = 0 and at a quarter
    period differ by the ellipse's axes (0.25 m/s along 60 deg, then 0.08 m/s across)."""
    g = ocean.read_current_grid(example_site.SITE_DIR / "currents.nc", example_site.START)
    field = ocean.GriddedCurrent(g, example_site.frame())
    assert len(g.time_s) == 17 and g.time_s[-1] == 4 * 3600.0
    v0 = field.velocity_world(0.0, np.zeros(3))
    v_true = example_site.SiteCurrent().velocity_world(0.0, np.zeros(3))
    np.testing.assert_allclose(v0, v_true, atol=1e-9)
    v3 = field.velocity_world(10800.0, np.zeros(3))
    assert np.linalg.norm(v3 - v0) > 0.1


def test_site_toml_names_the_files():
    path = example_site.SITE_DIR / "site.toml"
    cfg = loads_toml(path.read_text(), str(path))
    assert cfg["geo"] == {"latitude_deg": 43.05, "longitude_deg": 5.95}
    assert cfg["seabed"]["file"] == "assets/sites/example/bathymetry.nc"
    assert cfg["current"] == {"kind": "gridded", "file": "assets/sites/example/currents.nc"}
