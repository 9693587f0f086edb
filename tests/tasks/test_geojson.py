"""Run data on the Earth (issue 25, check 6): with a geo origin, a mission's Parquet tables carry
latitude/longitude beside east/north (deg, WGS 84) and each vehicle's tracks are written as
GeoJSON; the GeoJSON is read back with GDAL's OGR (pyogrio) and shapely, independent of the
writer, and its coordinates are checked against the Parquet's and against the east/north through
an independent inverse (the geodesic direct problem from the origin: pyproj.Geod)."""

import json
import math

import numpy as np
import pyogrio.raw  # the dev extra's GIS reader (GDAL's OGR)
import pytest
import shapely
from pyproj import Geod

from bauv_sim.geo import LocalFrame
from tasks.closed_loop.report import export_runs
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.core import cli
from tasks.core.export import Column, read_parquet
from tasks.core.geojson import write_tracks_geojson

LAT0, LON0 = 43.05, 5.95
TRACKS = ("truth_pos", "ekf_pos", "dr_pos")
DEG_TOL = 2e-8
"""GeoJSON coordinates are rounded to 1e-8 deg (<= 1.1 mm); 2e-8 deg is 2.2 mm."""
WGS84 = Geod(ellps="WGS84")


def geodesic_lat_lon(east, north):
    """Latitude and longitude of (east, north): the point at geodesic distance hypot(e, n) and
    azimuth atan2(e, n) from the origin (the azimuthal equidistant projection's definition),
    by the geodesic direct problem, not by the projection the writer uses."""
    east, north = np.asarray(east, float), np.asarray(north, float)
    az = np.degrees(np.arctan2(east, north))
    lon, lat, _ = WGS84.fwd(
        np.full(east.shape, LON0), np.full(east.shape, LAT0), az, np.hypot(east, north)
    )
    return np.asarray(lat), np.asarray(lon)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("geo") / "run"
    args = ["run", "mission/short", "--runs", "1", "--quiet", "--out", str(out)]
    sets = [
        f"geo.latitude_deg={LAT0}",
        f"geo.longitude_deg={LON0}",
        "report.recording=false",
        "report.figures=false",
        "guidance.waypoints.0.surface=true",  # GPS fixes at the first way-point
    ]
    try:
        cli.main(args + [a for s in sets for a in ("--set", s)])
    except SystemExit as exc:
        assert exc.code == 0
    return out / "data"


def read_features(path):
    """(properties, shapely geometry) of every feature, read by GDAL's OGR."""
    meta, _, geometry, field_data = pyogrio.raw.read(path)
    names = list(meta["fields"])
    assert meta["crs"] == "EPSG:4326"
    out = []
    for i, wkb in enumerate(geometry):
        props = {n: field_data[j][i] for j, n in enumerate(names)}
        out.append((props, shapely.from_wkb(wkb)))
    return out


@pytest.mark.slow
def test_geojson_tracks_read_by_ogr_equal_the_parquet_latitude_longitude(folder):
    ticks, _ = read_parquet(folder / "ticks" / "run-000000-bauv.parquet")
    feats = read_features(folder / "tracks" / "run-000000-bauv.geojson")
    lines = {p["track"]: g for p, g in feats if g.geom_type == "LineString"}
    assert set(lines) == set(TRACKS)
    for name in TRACKS:
        xy = shapely.get_coordinates(lines[name])  # (lon, lat)
        geo = ticks[f"{name}_geo_deg"]
        assert geo.unit == "deg" and geo.components == ("latitude", "longitude")
        assert "WGS 84" in geo.description
        assert xy.shape == (len(ticks["t"].values), 2)
        assert np.abs(xy[:, 1] - geo.values[:, 0]).max() < DEG_TOL
        assert np.abs(xy[:, 0] - geo.values[:, 1]).max() < DEG_TOL
        # and against east/north through the independent inverse
        pos = ticks[name].values
        lat, lon = geodesic_lat_lon(pos[:, 0], pos[:, 1])
        assert np.abs(xy[:, 1] - lat).max() < DEG_TOL
        assert np.abs(xy[:, 0] - lon).max() < DEG_TOL
        assert np.abs(geo.values[:, 0] - lat).max() < 1e-10  # 0.01 mm
        assert np.abs(geo.values[:, 1] - lon).max() < 1e-10
    props = next(p for p, g in feats if p.get("track") == "truth_pos")
    assert (props["run"], props["vehicle"], props["experiment"]) == (0, "bauv", "mission/short")
    assert props["t_end_s"] == pytest.approx(ticks["t"].values[-1])
    # the way-points as points
    points = {p["point"]: g for p, g in feats if g.geom_type == "Point"}
    lat, lon = geodesic_lat_lon([0.0, 40.0], [50.0, 80.0])  # mission/short's way-points
    for i in range(2):
        p = points[f"waypoint {i}"]
        assert abs(p.y - lat[i]) < DEG_TOL and abs(p.x - lon[i]) < DEG_TOL
    p = points["usbl transceiver"]  # mission/short's, at the origin
    assert (p.x, p.y) == (LON0, LAT0) and len(points) == 3


def test_gps_fixes_and_fix_positions_carry_latitude_longitude(folder):
    gps, _ = read_parquet(folder / "gps" / "run-000000-bauv.parquet")
    assert len(gps["east"].values) >= 3
    lat, lon = geodesic_lat_lon(gps["east"].values, gps["north"].values)
    assert gps["latitude_deg"].unit == gps["longitude_deg"].unit == "deg"
    assert np.abs(gps["latitude_deg"].values - lat).max() < 1e-10
    assert np.abs(gps["longitude_deg"].values - lon).max() < 1e-10
    usbl, _ = read_parquet(folder / "usbl" / "run-000000-bauv.parquet")
    lat, lon = geodesic_lat_lon(usbl["position"].values[:, 0], usbl["position"].values[:, 1])
    assert np.abs(usbl["position_geo_deg"].values - np.c_[lat, lon]).max() < 1e-10


def test_without_a_geo_origin_the_run_data_are_as_before(folder, tmp_path):
    ticks, _ = read_parquet(folder / "ticks" / "run-000000-bauv.parquet")
    keys = ("run", "vehicle")
    plain = {k: c for k, c in ticks.items() if not k.endswith("_geo_deg") and k not in keys}
    run = MissionRun(0, 0, None, {"bauv": VehicleRun("bauv", plain)})
    files = export_runs(tmp_path, "x", [run])
    assert files == ["data/ticks/run-000000-bauv.parquet"]
    back, _ = read_parquet(tmp_path / files[0])
    assert list(back) == [*keys, *plain]
    files = export_runs(tmp_path / "geo", "x", [run], frame=LocalFrame(LAT0, LON0))
    assert files[-1] == "data/tracks/run-000000-bauv.geojson"


def test_missing_positions_are_null_and_left_out_of_the_track(tmp_path):
    t = np.arange(5.0)
    pos = np.c_[t * 10.0, t * 5.0]
    pos[2] = np.nan
    ticks = {
        "t": Column(t, "s", "time"),
        "track": Column(pos, "m", "a track", ("east", "north"), nullable=True),
        "shift": Column(pos * 0 + 1.0, "m", "displacement", ("east", "north"), nullable=True),
    }
    frame = LocalFrame(LAT0, LON0)
    run = MissionRun(0, 0, None, {"v": VehicleRun("v", ticks)})
    export_runs(tmp_path, "x", [run], frame=frame)
    back, _ = read_parquet(tmp_path / "data/ticks/run-000000-v.parquet")
    geo = back["track_geo_deg"].values
    assert np.isnan(geo[2]).all() and np.isfinite(np.delete(geo, 2, axis=0)).all()
    assert "shift_geo_deg" not in back  # a displacement is no position
    feats = read_features(tmp_path / "data/tracks/run-000000-v.geojson")
    (props, line) = feats[0]
    assert props["n_points"] == 4 and len(feats) == 1
    lat, lon = geodesic_lat_lon(pos[[0, 1, 3, 4], 0], pos[[0, 1, 3, 4], 1])
    xy = shapely.get_coordinates(line)
    assert np.abs(xy - np.c_[lon, lat]).max() < DEG_TOL


def test_the_file_is_rfc_7946_json_longitude_first(tmp_path):
    ticks = {
        "t": Column(np.array([0.0, 1.0]), "s", "time"),
        "p": Column(np.array([[0.0, 0.0], [0.0, 1000.0]]), "m", "p", ("east", "north")),
    }
    path = tmp_path / "a.geojson"
    write_tracks_geojson(path, ticks, LocalFrame(LAT0, LON0), {"run": 1})
    doc = json.loads(path.read_text())
    assert doc["type"] == "FeatureCollection"
    (f,) = doc["features"]
    (lon_a, lat_a), (lon_b, lat_b) = f["geometry"]["coordinates"]
    assert (lon_a, lat_a) == (LON0, LAT0)
    assert lon_b == pytest.approx(LON0, abs=1e-8)
    assert lat_b - LAT0 == pytest.approx(1000.0 / 111_100.0, rel=2e-3)  # 1 km north
    assert math.isclose(f["properties"]["t_end_s"], 1.0)
