"""An ocean model's current as a current kind (``current.kind = "gridded"``): the configuration,
``make_current`` with the scene's frame, the file read once per process, and the physical
acceptance check: an idle vehicle in a gridded steady current moves with the water."""

from __future__ import annotations

import datetime as dt
import math
import os

import numpy as np
import pytest
from pydantic import TypeAdapter, ValidationError
from scipy.integrate import solve_ivp

from bauv_sim import currents, manoeuvres, ocean
from bauv_sim.errors import ConfigError
from bauv_sim.geo import LocalFrame
from bauv_sim.sea import Sea

START = dt.datetime(2026, 6, 1, 6, 0, 0)
FRAME = LocalFrame(43.05, 5.95)


def _axes(half_m: float, n: int, times_s=(0.0,), depths_m=(0.0, 60.0)):
    """Latitude/longitude axes spanning +-half_m around the frame's origin, n nodes each."""
    lat_n, _ = FRAME.to_geographic(np.array([0.0]), np.array([half_m]))
    _, lon_e = FRAME.to_geographic(np.array([half_m]), np.array([0.0]))
    dlat, dlon = float(lat_n[0]) - FRAME.latitude_deg, float(lon_e[0]) - FRAME.longitude_deg
    lat = FRAME.latitude_deg + np.linspace(-dlat, dlat, n)
    lon = FRAME.longitude_deg + np.linspace(-dlon, dlon, n)
    return np.asarray(times_s, float), np.asarray(depths_m, float), lat, lon


def _write(tmp_path, field, name="current.nc", **kw):
    path = tmp_path / name
    grid = ocean.sample_current_grid(field, FRAME, *_axes(**({"half_m": 300.0, "n": 7} | kw)))
    ocean.write_current_grid(grid, path, START)
    return path


def _cfg(path, start_time=None):
    data = {"kind": "gridded", "file": str(path)}
    if start_time is not None:
        data["start_time"] = start_time
    return TypeAdapter(currents.CurrentConfig).validate_python(data)


def test_gridded_is_a_current_kind_and_needs_the_frame(tmp_path):
    path = _write(tmp_path, currents.UniformCurrent(0.3, math.radians(60.0)))
    cfg = _cfg(path, "2026-06-01T08:00:00+02:00")
    assert isinstance(cfg, currents.GriddedCurrentConfig)
    assert cfg.start() == START  # another offset is converted to UTC
    with pytest.raises(ValidationError, match="not an ISO 8601"):
        _cfg(path, "June 1st")
    with pytest.raises(ConfigError, match=r"current.file = .*geo.latitude_deg, geo.longitude_deg"):
        currents.make_current(cfg)
    f = currents.make_current(cfg, None, FRAME)
    want = currents.UniformCurrent(0.3, math.radians(60.0)).velocity_world(0.0, np.zeros(3))
    assert np.allclose(f.velocity_world(100.0, [50.0, -80.0, -10.0]), want, atol=1e-12)


def test_a_bad_file_is_one_line_naming_the_field_and_the_file(tmp_path):
    cfg = _cfg(tmp_path / "none.nc")
    with pytest.raises(ConfigError, match=r"^current.file: .*none.nc: no such file$"):
        currents.make_current(cfg, None, FRAME)


def test_a_grid_too_large_is_refused_from_its_header(tmp_path):
    """A real file declaring 2 x 2 x 12000 x 12000 cells (12.9 GiB as a float64 grid of three
    components): refused by the reader before its velocities are read; its size is known from the
    header alone (the batch's memory estimate)."""
    from tests.tasks.test_site_current import write_declared

    path = tmp_path / "big.nc"
    write_declared(path, 12000)
    assert path.stat().st_size < 10e6
    assert ocean.current_grid_cells(path) == 2 * 2 * 12000 * 12000
    with pytest.raises(
        ConfigError, match=r"variable 'u' of shape \(2, 2, 12000, 12000\) needs 12.9 GiB"
    ):
        ocean.read_current_grid(path)


def test_start_time_places_the_mission_in_the_files_time(tmp_path):
    """A field varying in time, written from START: with start_time 10 min after, the mission's
    t = 0 is the file's 600 s (default: the file's first time)."""
    gyre = currents.GyreCurrent((40.0, -30.0), 200.0, 0.3, True, 1800.0)
    path = _write(tmp_path, gyre, times_s=np.arange(0.0, 3601.0, 300.0))
    p = np.array([[60.0, 20.0, -5.0], [-100.0, 90.0, -20.0]])
    first = currents.make_current(_cfg(path), None, FRAME)
    later = currents.make_current(_cfg(path, "2026-06-01T06:10:00Z"), None, FRAME)
    for t in (0.0, 300.0, 1200.0):  # node times: the interpolation is exact in time there
        want_first = ocean.GriddedCurrent(ocean.read_current_grid(path, START), FRAME)
        assert np.allclose(first.velocity_world(t, p), want_first.velocity_world(t, p))
        assert np.allclose(later.velocity_world(t, p), want_first.velocity_world(t + 600.0, p))
    assert not np.allclose(later.velocity_world(0.0, p), first.velocity_world(0.0, p))


def test_the_file_is_read_once_per_process_and_again_when_it_changes(tmp_path, monkeypatch):
    path = _write(tmp_path, currents.UniformCurrent(0.2, 1.0))
    reads = []
    real = ocean.read_current_grid
    monkeypatch.setattr(ocean, "read_current_grid", lambda *a: reads.append(a) or real(*a))
    ocean._cached_grid.cache_clear()
    a = currents.make_current(_cfg(path), None, FRAME)
    b = currents.make_current(_cfg(path), None, FRAME)
    assert len(reads) == 1 and a.grid is b.grid
    ocean.write_current_grid(
        ocean.sample_current_grid(
            currents.UniformCurrent(0.4, 1.0), FRAME, *_axes(half_m=300.0, n=7)
        ),
        path,
        START,
    )
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000_000))
    c = currents.make_current(_cfg(path), None, FRAME)
    assert len(reads) == 2
    assert np.linalg.norm(c.velocity_world(0.0, np.zeros(3))[:2]) == pytest.approx(0.4)


# ---------------------------------------------------------------------------------------------
# Issue 25 check 2, second half: an idle physical vehicle in a gridded steady current moves with
# the water as the analytic field predicts.

OMEGA_RAD_S = 0.004
"""The gyre's angular speed inside its core (solid-body rotation, counter-clockwise), rad/s."""


def _water_uniform(t, en):
    return np.array([0.35 * math.sin(math.radians(60.0)), 0.35 * math.cos(math.radians(60.0))])


def _water_gyre(t, en, centre=(-20.0, 15.0)):
    # solid-body rotation about the centre, written here from its definition (not from the
    # library): w = omega z x (p - c)
    return OMEGA_RAD_S * np.array([-(en[1] - centre[1]), en[0] - centre[0]])


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["uniform", "gyre"])
def test_an_idle_vehicle_moves_with_the_gridded_water(tmp_path, kind):
    """The vehicle (motor off, the model's neutral trim) is put in the water at rest relative to
    it and drifts for 90 s; its horizontal track equals the streamline of the analytic field
    through its start, integrated here with scipy's ``solve_ivp`` (RK45, rtol 1e-10), within
    2 cm (measured: 5e-8 m uniform over 31.5 m; 1.1 mm in the gyre over 30 m and 0.36 rad of
    turn; with u and v swapped in the interpolated grid the track is metres off).

    The gyre is the core of a Rankine vortex (the library's :class:`~bauv_sim.currents.
    GyreCurrent`, core radius 400 m, so the field is linear over the grid and the grid's linear
    interpolation is exact at every point), sampled on a 300 m grid in latitude/longitude,
    written to netCDF and read back through ``current.kind = "gridded"``."""
    if kind == "uniform":
        analytic = currents.UniformCurrent(0.35, math.radians(60.0))
        water = _water_uniform
    else:
        # counter-clockwise, tangential speed omega * r up to the core radius
        analytic = currents.GyreCurrent((-20.0, 15.0), 400.0, OMEGA_RAD_S * 400.0, False)
        water = _water_gyre
    path = _write(tmp_path, analytic, half_m=300.0, n=7)
    field = currents.make_current(_cfg(path), None, FRAME)
    phys = manoeuvres.open_water_scene(depth_m=20.0, heading_deg=30.0)
    phys.set_pose([60.0, 40.0, -20.0], phys.roll_pitch_heading(), np.zeros(3))
    Sea(field).immerse(phys)  # carried with the water at it: at rest relative to the water
    start = phys.position_world()[:2].copy()
    duration_s, tick = 90.0, phys.control_tick_s
    track = [start]
    for _ in range(round(duration_s / tick)):
        phys.advance(tick)
        track.append(phys.position_world()[:2].copy())
    track = np.array(track)
    t = tick * np.arange(len(track))
    sol = solve_ivp(water, (0.0, duration_s), start, t_eval=t, rtol=1e-10, atol=1e-10)
    streamline = sol.y.T
    err = np.linalg.norm(track - streamline, axis=1)
    assert err.max() < 0.02, (kind, err.max())
    # the vehicle moved: the test is not passed by standing still
    assert np.linalg.norm(track[-1] - track[0]) > 20.0
