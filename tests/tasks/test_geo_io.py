"""Positions in latitude/longitude in mission scenarios and way-points from CSV/GeoJSON files
(tasks.closed_loop.geo), checked against geodesics computed independently (Vincenty's inverse,
tests/bauv_sim/test_geo.py) and through the CLI's refusals (exit 2, one line, nothing written)."""

import dataclasses
import json
import math

import pytest
import tomli_w
from pyproj import Geod

from bauv_sim.config import load_config, to_plain
from bauv_sim.errors import ConfigError
from tasks.core import registry
from tests.bauv_sim.test_geo import vincenty_inverse
from tests.tasks.refusal import run_in_process

LAT0, LON0 = 43.05, 5.95
GEO = {"geo": {"latitude_deg": LAT0, "longitude_deg": LON0}}
SURVEY = registry.get("mission/survey")


def expected_en(lat, lon):
    """East and north of a point: geodesic distance s and azimuth a from the origin (Vincenty),
    east = s sin a, north = s cos a (the azimuthal equidistant projection's definition)."""
    s, a = vincenty_inverse(LAT0, LON0, lat, lon)
    return s * math.sin(a), s * math.cos(a)


def survey(data=None, overrides=()):
    base = {**SURVEY.preset, **(data or {})}
    return load_config(SURVEY.scenario_type, base, (), overrides)


def test_waypoints_start_and_transceiver_in_latitude_longitude_are_the_geodesic_east_north():
    pts = [(43.0532, 5.9487), (43.0411, 5.9612), (43.0500, 5.9500)]
    scn = survey(
        {
            **GEO,
            "guidance": {
                "waypoints": [
                    {"latitude_deg": a, "longitude_deg": b, "depth_m": 4.0} for a, b in pts
                ]
            },
            "start": {"latitude_deg": 43.0471, "longitude_deg": 5.9433, "heading_deg": 45.0},
            "transceiver_latitude_deg": 43.0507,
            "transceiver_longitude_deg": 5.9519,
        }
    )
    for wp, (a, b) in zip(scn.guidance.waypoints, pts, strict=True):
        e, n = expected_en(a, b)
        assert abs(wp.east_m - e) < 0.01 and abs(wp.north_m - n) < 0.01
        assert wp.depth_m == 4.0
    e, n = expected_en(43.0471, 5.9433)
    assert abs(scn.start.east_m - e) < 0.01 and abs(scn.start.north_m - n) < 0.01
    assert scn.start.heading_deg == 45.0
    e, n = expected_en(43.0507, 5.9519)
    assert abs(scn.transceiver_east_m - e) < 0.01 and abs(scn.transceiver_north_m - n) < 0.01
    # the resolved scenario is in east/north and loads again to the same scenario
    plain = to_plain(scn)
    assert "latitude_deg" not in plain["start"] and "transceiver_latitude_deg" not in plain
    assert load_config(SURVEY.scenario_type, plain) == scn


def test_a_scenario_without_geographic_positions_is_passed_through_untouched():
    from tasks.closed_loop.geo import resolve_geographic

    data = to_plain(survey())
    assert resolve_geographic(data) is data
    assert "waypoints_file" not in data["guidance"]


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return str(p)


def test_csv_waypoints_in_latitude_longitude_and_in_east_north(tmp_path):
    f = write(
        tmp_path,
        "w.csv",
        "latitude_deg, longitude_deg,depth_m,acceptance_radius_m,surface\n"
        "43.0532,5.9487,4.5,,\n"
        "\n"
        "43.0411,5.9612,,6,true\n",
    )
    scn = survey(GEO, [f"guidance.waypoints_file={json.dumps(f)}"])
    wps = scn.guidance.waypoints
    assert len(wps) == 2 and scn.guidance.waypoints_file is None
    e, n = expected_en(43.0532, 5.9487)
    assert abs(wps[0].east_m - e) < 0.01 and abs(wps[0].north_m - n) < 0.01
    assert (wps[0].depth_m, wps[0].acceptance_radius_m, wps[0].surface) == (4.5, 8.0, False)
    assert (wps[1].depth_m, wps[1].acceptance_radius_m, wps[1].surface) == (3.0, 6.0, True)
    # east/north files need no origin
    f = write(tmp_path, "en.csv", "east_m,north_m,surface\n10,20,0\n-5.5,7,1\n")
    scn = survey(None, [f"guidance.waypoints_file={json.dumps(f)}"])
    assert [(w.east_m, w.north_m, w.surface) for w in scn.guidance.waypoints] == [
        (10.0, 20.0, False),
        (-5.5, 7.0, True),
    ]


def test_geojson_points_and_linestring_with_heights(tmp_path):
    pts = [(5.9487, 43.0532), (5.9612, 43.0411)]
    doc = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": [*pts[0], -6.0]},
                "properties": {"name": "A", "surface": True},
            },
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": list(pts[1])},
                "properties": {"depth_m": 2.5, "acceptance_radius_m": 5},
            },
        ],
    }
    f = write(tmp_path, "w.geojson", json.dumps(doc))
    wps = survey(GEO, [f"guidance.waypoints_file={json.dumps(f)}"]).guidance.waypoints
    for wp, (lon, lat) in zip(wps, pts, strict=True):
        e, n = expected_en(lat, lon)
        assert abs(wp.east_m - e) < 0.01 and abs(wp.north_m - n) < 0.01
    assert (wps[0].depth_m, wps[0].surface) == (6.0, True)  # height -6 m: 6 m deep
    assert (wps[1].depth_m, wps[1].acceptance_radius_m) == (2.5, 5.0)
    line = {
        "type": "Feature",
        "geometry": {"type": "LineString", "coordinates": [list(p) for p in pts]},
        "properties": {"depth_m": 7.0},
    }
    f = write(tmp_path, "l.json", json.dumps(line))
    wps = survey(GEO, [f"guidance.waypoints_file={json.dumps(f)}"]).guidance.waypoints
    assert [w.depth_m for w in wps] == [7.0, 7.0]
    e, n = expected_en(pts[1][1], pts[1][0])
    assert abs(wps[1].east_m - e) < 0.01 and abs(wps[1].north_m - n) < 0.01


REFUSED = [
    ({"start": {"latitude_deg": 43.0}}, "start.latitude_deg = 43.0: needs start.longitude_deg"),
    (
        {"transceiver_longitude_deg": 5.9},
        "transceiver_longitude_deg = 5.9: needs transceiver_latitude_deg",
    ),
    (
        {"guidance": {"waypoints": [{"east_m": 1.0, "north_m": 2.0, "latitude_deg": 43.0}]}},
        "guidance.waypoints.0.latitude_deg = 43.0: needs guidance.waypoints.0.longitude_deg",
    ),
    (
        {
            "guidance": {
                "waypoints": [
                    {"east_m": 1.0, "north_m": 2.0, "latitude_deg": 43.0, "longitude_deg": 5.9}
                ]
            }
        },
        "guidance.waypoints.0: give east_m/north_m or latitude_deg/longitude_deg, not both",
    ),
    (
        {"guidance": {"waypoints": [{"latitude_deg": 43.0, "longitude_deg": 5.9}, {"depth_m": 2}]}},
        "guidance.waypoints.1: needs a position: east_m and north_m, or latitude_deg and "
        "longitude_deg (east_m, north_m missing)",
    ),
    (
        {"start": {"latitude_deg": 91.0, "longitude_deg": 5.9}},
        "start.latitude_deg = 91.0: must be a finite number in [-90, 90]",
    ),
    (
        {"start": {"latitude_deg": 43.05, "longitude_deg": 59.5}},
        "start.latitude_deg, longitude_deg = 43.05, 59.5: 4286 km from the geo origin (43.05, "
        "5.95); at most 100 km allowed",
    ),
    (
        {"start": {"latitude_deg": "43N", "longitude_deg": 5.9}},
        "start.latitude_deg = '43N': must be a number (deg)",
    ),
]


@pytest.mark.parametrize(("data", "message"), REFUSED)
def test_bad_geographic_positions_are_one_line_naming_the_field(data, message):
    with pytest.raises(ConfigError) as exc:
        survey({**GEO, **data})
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_latitude_longitude_without_a_geo_origin_is_refused():
    with pytest.raises(ConfigError, match=r"start\.latitude_deg = 43\.0: a position in latitude/"):
        survey({"start": {"latitude_deg": 43.0, "longitude_deg": 5.9}})


FILES = [
    ("a.csv", "latitude_deg,longitude_deg,speed\n43,5,1\n", "line 1, column 3 = 'speed'"),
    ("a.csv", "latitude_deg,east_m\n43,5\n", "needs the columns latitude_deg and longitude_deg"),
    ("a.csv", "latitude_deg,longitude_deg\n43.05,5.95\n43.x,5.9\n", "line 3, column "),
    ("a.csv", "east_m,north_m,depth_m\n1,2,nan\n", "line 2, column 'depth_m' = 'nan'"),
    ("a.csv", "east_m,north_m,surface\n1,2,yes\n", "'surface' = 'yes': must be true, false"),
    ("a.csv", "east_m,north_m\n1,2\n3\n", "line 3: 1 cells, the header has 2"),
    ("a.csv", "east_m,north_m\n", "holds no way-point"),
    ("a.txt", "x", "extension must be .csv, .geojson or .json"),
    ("a.geojson", "{", "not JSON"),
    ("a.geojson", '{"type": "Polygon"}', "type = 'Polygon': must be a FeatureCollection"),
    (
        "a.geojson",
        '{"type":"Feature","geometry":{"type":"Point","coordinates":[5.9]},"properties":null}',
        "feature 0: coordinates = [5.9]",
    ),
    (
        "a.geojson",
        '{"type":"Feature","geometry":{"type":"Point","coordinates":[5.9,43,-2]},'
        '"properties":{"depth_m":5}}',
        "height = -2.0 m and property depth_m = 5.0 m disagree",
    ),
    (
        "a.geojson",
        '{"type":"Feature","crs":{"type":"name","properties":{"name":"EPSG:32631"}},'
        '"geometry":{"type":"Point","coordinates":[5.9,43]}}',
        "crs = 'EPSG:32631'",
    ),
    (
        "a.geojson",
        '{"type":"Feature","geometry":{"type":"Point","coordinates":[NaN,43]}}',
        "not JSON",
    ),
    ("a.geojson", "[" * 100_000, "nested too deep"),
]


@pytest.mark.parametrize(("name", "text", "message"), FILES)
def test_bad_waypoint_files_name_the_file_row_and_column(tmp_path, name, text, message):
    f = write(tmp_path, name, text)
    with pytest.raises(ConfigError) as exc:
        survey(GEO, [f"guidance.waypoints_file={json.dumps(f)}"])
    assert f"guidance.waypoints_file = {f!r}" in str(exc.value)
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_cli_refuses_with_exit_2_one_line_and_nothing_written(tmp_path, capsys):
    out = tmp_path / "out"
    missing = tmp_path / "none.csv"
    wp = f"guidance.waypoints_file={json.dumps(str(missing))}"
    code, err = run_in_process(capsys, "run", "mission/survey", "--out", str(out), "--set", wp)
    assert code == 2, err
    assert f"guidance.waypoints_file = {str(missing)!r}: not found" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()
    code, err = run_in_process(
        capsys, "run", "mission/short", "--out", str(out), "--set", "start.latitude_deg=43.0"
    )
    assert code == 2 and "start.latitude_deg = 43.0: needs start.longitude_deg" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_a_scenario_without_the_mission_validator_refuses_a_waypoints_file(tmp_path):
    f = write(tmp_path, "en.csv", "east_m,north_m\n1,2\n")
    swarm = registry.get("mission/swarm")
    with pytest.raises(ConfigError, match=r"waypoints_file = .*read by a mission scenario"):
        load_config(
            swarm.scenario_type,
            swarm.preset,
            (),
            [f"leader.guidance.waypoints_file={json.dumps(f)}"],
        )


@pytest.mark.slow
def test_a_mission_given_in_latitude_longitude_flies_as_the_same_one_in_east_north(
    tmp_path, capsys
):
    """mission/short's way-points, start and transceiver given as their latitude/longitude
    (from Vincenty's direct problem, pyproj.Geod, not the scenario's frame) fly the same mission
    as in east/north: the conversion's round trip is a few nanometres."""
    geod = Geod(ellps="WGS84")

    def lat_lon(east, north):
        az, s = math.degrees(math.atan2(east, north)), math.hypot(east, north)
        lon, lat, _ = geod.fwd(LON0, LAT0, az, s)
        return {"latitude_deg": lat, "longitude_deg": lon}

    wps = [
        {**lat_lon(0.0, 50.0), "depth_m": 3.0},
        {**lat_lon(40.0, 80.0), "depth_m": 3.0},
    ]
    tx = lat_lon(3.0, -4.0)
    common = ["--runs", "1", "--quiet", "--set", "report.recording=false"]
    common += ["--set", "report.figures=false"]
    code, err = run_in_process(
        capsys,
        "run",
        "mission/short",
        "--out",
        str(tmp_path / "en"),
        *common,
        "--set",
        "transceiver_east_m=3.0",
        "--set",
        "transceiver_north_m=-4.0",
    )
    assert code == 0, err
    scenario = tmp_path / "geo.toml"
    scenario.write_text(
        tomli_w.dumps(
            {
                **GEO,
                "guidance": {"waypoints": wps},
                "start": lat_lon(0.0, -20.0),
                "transceiver_latitude_deg": tx["latitude_deg"],
                "transceiver_longitude_deg": tx["longitude_deg"],
                "report": {"recording": False, "figures": False},
            }
        )
    )
    code, err = run_in_process(
        capsys,
        "run",
        "mission/short",
        "--out",
        str(tmp_path / "geo"),
        "--scenario",
        str(scenario),
        "--runs",
        "1",
        "--quiet",
    )
    assert code == 0, err
    a = json.loads((tmp_path / "en" / "metrics.json").read_text())["runs"][0]
    b = json.loads((tmp_path / "geo" / "metrics.json").read_text())["runs"][0]
    assert a["failed"] is None and b["failed"] is None
    for wa, wb in zip(a["waypoints"], b["waypoints"], strict=True):
        assert abs(wa["east_m"] - wb["east_m"]) < 1e-6
        assert abs(wa["north_m"] - wb["north_m"]) < 1e-6
        assert wa["reached_by_truth"] == wb["reached_by_truth"]
    for k, v in a["summary"].items():
        assert b["summary"][k] == pytest.approx(v, rel=1e-6, abs=1e-6), k


def test_the_gps_reports_latitude_longitude_and_the_navigation_makes_it_east_north():
    """With the frame in the rig, the GPS device's fix is the same fix (same seed, same error)
    in WGS 84 latitude/longitude: the geodesic direct problem of its east/north without the
    frame; the GPS adapter given the frame makes it east/north again (the navigator's input)."""
    import numpy as np

    from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
    from bauv_sim.geo import LocalFrame
    from bauv_sim.sensors.gps import GpsConfig
    from bauv_sim.sensors.rig import SensorRig
    from nav.models import HorizontalPositionMeasurement
    from tasks.closed_loop.navigation import GpsFixes

    frame = LocalFrame(LAT0, LON0)
    geod = Geod(ellps="WGS84")
    phys = build_physics(SceneConfig(beacons=(), vehicles=(VehicleSpec(depth_m=1.0),)))
    cfg = GpsConfig(period_s=0.2, acquisition_s=0.0)
    adapter = GpsFixes(HorizontalPositionMeasurement(2.5), np.zeros(3), False, frame)
    n = 0
    for k, (e, nn) in enumerate([(120.0, -340.0), (-2500.0, 800.0), (10.0, 4000.0)]):
        phys.set_pose([e, nn, 0.4], [0.0, 0.0, 1.0])
        plain = SensorRig({"gps": cfg}, phys, "bauv", seed=3, run=k)
        geo = SensorRig({"gps": cfg}, phys, "bauv", 3, k, extra={"gps": {"frame": frame}})
        (a,) = plain.sense(0, phys.truth(), phys.commands()).arrived
        (b,) = geo.sense(0, phys.truth(), phys.commands()).arrived
        east, north = a.value
        lon, lat, _ = geod.fwd(
            LON0, LAT0, math.degrees(math.atan2(east, north)), math.hypot(east, north)
        )
        assert abs(b.value[0] - lat) < 1e-10 and abs(b.value[1] - lon) < 1e-10  # 0.01 mm
        assert abs(east - e) < 15 and abs(north - nn) < 15  # the fix is near the antenna
        b = dataclasses.replace(b, attitude_rad=np.zeros(3))  # no compass/INS in this rig
        rec = adapter.apply(None, b, b.t_valid_s)
        assert (
            np.abs(rec.z - a.value).max() < 1e-6 and np.abs(rec.reference_m - a.value).max() < 1e-6
        )
        n += 1
    assert n == 3
