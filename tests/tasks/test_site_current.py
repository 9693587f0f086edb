"""Issue 25 checks 4 and 5 for currents: ``mission/correction`` under a time-varying current from
an ocean model's file, and the files ``bauv run`` refuses (one line, exit 2, nothing written)."""

from __future__ import annotations

import csv
import datetime as dt
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from bauv_sim import currents, ocean
from bauv_sim.geo import LocalFrame

LAT, LON = 43.05, 5.95
FRAME = LocalFrame(LAT, LON)
START = dt.datetime(2026, 6, 1, 6, 0, 0)
RAMP_S = 1200.0
GEO = ["--set", f"geo.latitude_deg={LAT}", "--set", f"geo.longitude_deg={LON}"]

# the field at the file's first time (a uniform drift and a slowly turning gyre) and at its last
FIRST = currents.SumCurrent(
    currents.UniformCurrent(0.25, math.radians(20.0)),
    currents.GyreCurrent((100.0, -50.0), 5000.0, 1.0, False),
)
LAST = currents.UniformCurrent(0.35, math.radians(70.0))


def _axes(half_m: float, n: int, depths_m=(0.0, 30.0)):
    lat_n, _ = FRAME.to_geographic(np.array([0.0]), np.array([half_m]))
    _, lon_e = FRAME.to_geographic(np.array([half_m]), np.array([0.0]))
    dlat, dlon = float(lat_n[0]) - LAT, float(lon_e[0]) - LON
    return (
        np.asarray(depths_m, float),
        LAT + np.linspace(-dlat, dlat, n),
        LON + np.linspace(-dlon, dlon, n),
    )


def ramp_grid(half_m: float = 1500.0, end_s: float = RAMP_S) -> ocean.CurrentGrid:
    """A time-varying grid: FIRST at t = 0 and LAST at ``end_s``; between, the file's linear
    interpolation in time is the truth (the fields are linear enough in space over its cells that
    its bilinear interpolation in latitude/longitude is within 1e-5 m/s of them)."""
    d, lat, lon = _axes(half_m, 9)
    a = ocean.sample_current_grid(FIRST, FRAME, [0.0], d, lat, lon)
    b = ocean.sample_current_grid(LAST, FRAME, [0.0], d, lat, lon)
    comps = [np.concatenate([getattr(a, k), getattr(b, k)]) for k in ("u_m_s", "v_m_s", "w_m_s")]
    return ocean.CurrentGrid(np.array([0.0, end_s]), d, lat, lon, *comps)


def _bauv(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )


@pytest.mark.slow
def test_correction_runs_under_a_time_varying_current_from_a_file(tmp_path):
    """Check 4: the run's true current at the vehicle is the file's field where the vehicle is,
    when it is there; the report compares the procedure's estimate with it along the track (the
    table's figures recomputed here from the exported ticks)."""
    ocean.write_current_grid(ramp_grid(), tmp_path / "currents.nc", START)
    cur = ["--set", "current.kind=gridded", "--set", "current.file=currents.nc"]
    res = _bauv(tmp_path, "mission/correction", "--runs", "1", "--out", "out", *cur, *GEO)
    assert res.returncode == 0, res.stderr[-3000:]
    out = tmp_path / "out"
    ticks = pq.read_table(out / "data/ticks/run-000000-compensated-bauv.parquet").to_pandas()
    t = ticks["t"].to_numpy()
    pos = ticks[[f"truth_pos_{c}" for c in ("east", "north", "up")]].to_numpy()
    true = ticks[[f"truth_current_{c}" for c in ("east", "north", "up")]].to_numpy()
    w = (t / RAMP_S)[:, None]
    want = (1.0 - w) * FIRST.velocity_world(0.0, pos) + w * LAST.velocity_world(0.0, pos)
    assert np.abs(true - want).max() < 1e-5  # measured 2.4e-6 m/s
    assert np.ptp(true[:, 0]) > 0.05  # the current changed along the track
    # the along-track table: legs 1-3, every tick; the estimate is CP2's (uniform response: the
    # same for every course, so leg 3's estimate is the one made when leg 2 closed)
    est = ticks[["cp_current_east", "cp_current_north"]].to_numpy()
    est = est[np.isfinite(est).all(axis=1)][0]
    err = np.linalg.norm(est - true[:, :2], axis=1)
    dev = np.linalg.norm(true[:, :2] - true[:, :2].mean(axis=0), axis=1)
    with open(out / "tables" / "current-along-track.csv", newline="") as f:
        rows = {r[0]: r[1:] for r in csv.reader(f)}
    whole = [float(x) for x in rows["legs 1-3"]]
    assert whole[0] == pytest.approx(err.mean(), abs=1e-9)
    assert whole[1] == pytest.approx(np.sqrt(np.mean(err**2)), abs=1e-9)
    assert whole[2] == pytest.approx(err.max(), abs=1e-9)
    assert whole[6] == pytest.approx(np.sqrt(np.mean(dev**2)), abs=1e-9)
    assert (out / "current-along-track.png").is_file()


def write_declared(path: Path, n: int) -> None:
    """A real current file declaring 2 x 2 x n x n cells of u and v, nothing written into them
    (HDF5 allocates no chunk that is not written: the file is small)."""
    import netCDF4

    with netCDF4.Dataset(path, "w") as ds:
        for name, size, std, units in (
            ("time", 2, "time", "seconds since 2026-06-01 06:00:00"),
            ("depth", 2, "depth", "m"),
            ("latitude", n, "latitude", "degrees_north"),
            ("longitude", n, "longitude", "degrees_east"),
        ):
            ds.createDimension(name, size)
            var = ds.createVariable(name, "f8", (name,))
            var.standard_name, var.units = std, units
        ds["time"][:] = [0.0, 3600.0]
        ds["depth"][:] = [0.0, 30.0]
        ds["latitude"][:] = LAT + np.linspace(-0.05, 0.05, n)
        ds["longitude"][:] = LON + np.linspace(-0.05, 0.05, n)
        dims = ("time", "depth", "latitude", "longitude")
        for key, std in list(ocean.STANDARD_NAMES.items())[:2]:
            var = ds.createVariable(key, "f4", dims, chunksizes=(1, 1, 500, 500))
            var.standard_name, var.units = std, "m s-1"


def _write_bad(tmp_path: Path, what: str) -> Path:
    """A current file with one thing wrong (``what``)."""
    import xarray as xr

    path = tmp_path / f"{what}.nc"
    if what == "too-large":
        write_declared(path, 60000)
        return path

    grid = ramp_grid(
        half_m=200.0 if what == "small" else 1500.0, end_s=300.0 if what == "short" else RAMP_S
    )
    good = tmp_path / f"{what}-good.nc"
    ocean.write_current_grid(grid, good, START)
    with xr.open_dataset(good) as ds:
        ds = ds.load()
    if what == "missing":
        ds = ds.drop_vars("v")
    elif what == "units":
        ds["u"].attrs["units"] = "knots"
    elif what == "nan":
        ds["v"][0, 0, 3, 4] = np.nan
    ds.to_netcdf(path, engine="netcdf4")
    return path


@pytest.mark.slow
@pytest.mark.parametrize(
    ("what", "pattern"),
    [
        ("missing", "no variable with standard_name 'northward_sea_water_velocity'"),
        ("units", "variable 'u' has units 'knots', expected one of m s-1"),
        ("nan", "variable 'v' has 1 NaN or missing cells"),
        ("small", "is outside the grid's latitude"),
        ("short", "the mission's time [0, 900] s is outside the grid's [0, 300] s"),
        # the batch's memory estimate refuses it first (the reader's own limit where the
        # machine has the memory: tests/bauv_sim/test_gridded_current.py)
        ("too-large", "current.file = too-large.nc (1.44e+10 grid cells): the batch would need"),
        ("no-geo", "needs the scenario's geo origin (geo.latitude_deg, geo.longitude_deg)"),
    ],
)
def test_a_bad_current_file_is_refused_in_one_line(tmp_path, what, pattern):
    """Check 5: one line naming ``current.file``, the file (and the variable) and what is wrong;
    exit status 2; nothing written."""
    path = _write_bad(tmp_path, "small" if what == "no-geo" else what)
    args = ["--set", "current.kind=gridded", "--set", f"current.file={path.name}"]
    args += [] if what == "no-geo" else GEO
    res = _bauv(tmp_path, "mission/correction", "--runs", "1", "--out", "refused", *args)
    assert res.returncode == 2, res.stderr[-2000:]
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, lines
    assert pattern in lines[0] and "current.file" in lines[0] and path.name in lines[0], lines
    assert not (tmp_path / "refused").exists()


@pytest.mark.slow
def test_swarm_refuses_a_gridded_current_it_cannot_place(tmp_path):
    """mission/swarm builds its sea with the same scenario_sea: a gridded current is checked
    before anything is written (here: no geo origin to place the file's latitude/longitude)."""
    ocean.write_current_grid(ramp_grid(), tmp_path / "currents.nc", START)
    args = ["--set", "current.kind=gridded", "--set", "current.file=currents.nc"]
    res = _bauv(tmp_path, "mission/swarm", "--out", "refused", *args)
    assert res.returncode == 2, res.stderr[-2000:]
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "current.file = currents.nc" in lines[0], lines
    assert "geo.latitude_deg" in lines[0] and not (tmp_path / "refused").exists()
