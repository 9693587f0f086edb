"""Positions of a mission scenario given in WGS 84 latitude and longitude, and way-points read
from a file, resolved into the scene's east/north before the scenario is validated.

A way-point (``guidance.waypoints[i]``), the start (``start``) and the USBL transceiver
(``transceiver_*``) may be given as ``latitude_deg``/``longitude_deg`` instead of
``east_m``/``north_m``; ``guidance.waypoints_file`` names a CSV or GeoJSON file of way-points.
:func:`resolve_geographic` runs as a ``mode="before"`` validator of
:class:`~tasks.closed_loop.scenario.MissionScenario`: it reads the file, converts every
geographic position with the scenario's ``geo`` origin (:class:`bauv_sim.geo.LocalFrame`, PROJ's
azimuthal equidistant projection on WGS 84) and hands pydantic the scenario in east/north only,
so every consumer keeps reading ``east_m``/``north_m``. The resolved scenario (``bauv show``,
the run folder's ``scenario.toml``) holds the converted east/north and the ``geo`` origin, and
no ``waypoints_file``: it is self-contained (a run resumed after the file changed flies what it
flew), and loading it again gives the same scenario.

Rules (each broken one is one line naming the field, the value and what is allowed):

* a way-point has exactly one pair: ``east_m``/``north_m`` or ``latitude_deg``/``longitude_deg``
  (both, neither or half a pair is refused);
* the start and the transceiver always hold an east/north pair (their defaults, or the
  mission's preset, are merged under every scenario before validation, so a given local pair
  cannot be told from the default): a complete geographic pair replaces it; half a pair is
  refused;
* a geographic position needs the ``geo`` origin;
* latitudes in [-90, 90], longitudes in [-180, 180], finite.

Way-point files (paths relative to the current directory, at most
:data:`MAX_WAYPOINTS_FILE_BYTES`):

* **CSV** (``.csv``), read with the standard :mod:`csv` module: a header row, then one row per
  way-point. Columns: ``latitude_deg,longitude_deg`` or ``east_m,north_m`` (one pair), and
  optionally ``depth_m``, ``acceptance_radius_m``, ``surface`` (``true``/``false``/``1``/``0``);
  an empty optional cell takes the field's default.
* **GeoJSON** (``.geojson`` or ``.json``, RFC 7946), read with the standard :mod:`json` module
  (GeoJSON is JSON with a fixed structure: a GIS library would add a dependency to parse it and
  would still leave every field to be checked here): a FeatureCollection of Point features (one
  way-point each, in order; its ``properties`` may hold ``depth_m``, ``acceptance_radius_m``,
  ``surface``), or one LineString (a Feature or the FeatureCollection's only feature; one
  way-point per vertex, the feature's properties applying to every vertex). Coordinates are
  ``[longitude, latitude]`` in WGS 84 (RFC 7946 section 3.1.1); an optional third coordinate is
  a **height** (m, up, section 4), so it gives ``depth_m = -height`` (a property ``depth_m``
  beside it must agree within 1 mm). A ``crs`` member other than OGC CRS84 is refused.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from bauv_sim.config import MAX_ARRAY_ITEMS, MAX_TOML_BYTES, read_text_file
from bauv_sim.geo import GeoOriginConfig, LocalFrame

GEO = ("latitude_deg", "longitude_deg")
LOCAL = ("east_m", "north_m")
OPTIONAL = ("depth_m", "acceptance_radius_m", "surface")
"""A way-point's optional fields, as a file may give them (defaults: the scenario's)."""
MAX_WAYPOINTS_FILE_BYTES = MAX_TOML_BYTES
"""The largest way-point file, bytes (the largest scenario file: 4 MiB)."""
DEPTH_AGREEMENT_M = 1e-3
"""A GeoJSON height and a ``depth_m`` property beside it agree within this, m."""
MAX_DISTANCE_FROM_ORIGIN_M = 100_000.0
"""A geographic position farther than this from the ``geo`` origin is refused, m: the scene is
flat (distances between points away from the origin are off by about (r / R)^2, 2.5e-4 at
100 km), and a position thousands of kilometres away is a typing error."""
CRS84 = ("urn:ogc:def:crs:OGC:1.3:CRS84", "urn:ogc:def:crs:OGC::CRS84", "EPSG:4326")


def resolve_geographic(data: Any) -> Any:
    """The scenario data with its way-point file read and its geographic positions in east/north
    (module docstring); data without either is returned as it is (the same object).

    Args:
        data: the scenario as nested data (before pydantic validates it).

    Returns:
        The data to validate: a new dict where something was resolved.

    Raises:
        ValueError: one line naming the field (or the file, row and column), the value and what
            is allowed (pydantic makes it one line of :class:`~bauv_sim.errors.ConfigError`).
    """
    if not isinstance(data, Mapping):
        return data
    guidance = data.get("guidance")
    file = guidance.get("waypoints_file") if isinstance(guidance, Mapping) else None
    waypoints = guidance.get("waypoints") if isinstance(guidance, Mapping) else None
    start = data.get("start")
    wanted = (
        file is not None
        or any(k.startswith("transceiver_") and k.endswith(GEO) for k in data)
        or (isinstance(start, Mapping) and any(k in start for k in GEO))
        or (
            isinstance(waypoints, list | tuple)
            and any(isinstance(w, Mapping) and any(k in w for k in GEO) for w in waypoints)
        )
    )
    if not wanted:
        return data
    out = dict(data)
    if isinstance(guidance, Mapping) and "waypoints_file" in guidance:
        g = dict(guidance)
        g.pop("waypoints_file")
        if file is not None:
            g["waypoints"] = read_waypoints_file(file)
        out["guidance"] = g
    origin = _Origin(out.get("geo"))
    if file is not None and out.get("geo") is None:
        rows = out["guidance"]["waypoints"]
        if any("latitude_deg" in w for w in rows):
            raise ValueError(
                f"guidance.waypoints_file = {file!r}: way-points in latitude/longitude need the "
                "scenario's geo origin (geo.latitude_deg, geo.longitude_deg)"
            )
    g = out.get("guidance")
    if isinstance(g, Mapping) and isinstance(g.get("waypoints"), list | tuple):
        where = "guidance.waypoints"
        if file is not None:
            where = f"guidance.waypoints_file = {file!r}: way-point "
        wps = []
        for i, w in enumerate(g["waypoints"]):
            if isinstance(w, Mapping):
                w = _resolve_point(w, f"{where}{i}" if file else f"{where}.{i}", origin, True)
            wps.append(w)
        out["guidance"] = {**g, "waypoints": wps}
    if isinstance(start, Mapping):
        out["start"] = _resolve_point(start, "start", origin, False)
    keys = {f"transceiver_{k}": k for k in (*GEO, *LOCAL)}
    given = {k: v for k, v in out.items() if k in keys}
    if any(keys[k] in GEO for k in given):
        point = _resolve_point(
            {keys[k]: v for k, v in given.items()}, "transceiver", origin, False, "_"
        )
        if all(k in point for k in LOCAL) and not any(k in point for k in GEO):
            for k in given:
                out.pop(k)
            out.update({f"transceiver_{k}": point[k] for k in LOCAL})
    return out


class _Origin:
    """The scenario's frame, built when a geographic position needs it."""

    def __init__(self, geo: Any):
        self.geo = geo
        self._frame: LocalFrame | None = None

    def frame(self, field: str, value: Any) -> LocalFrame | None:
        """The frame, or ``None`` when the ``geo`` table is itself invalid (pydantic then reports
        it, as the scenario's first problem)."""
        if self._frame is not None:
            return self._frame
        geo = self.geo
        if geo is None:
            raise ValueError(
                f"{field} = {value!r}: a position in latitude/longitude needs the scenario's geo "
                "origin (geo.latitude_deg, geo.longitude_deg)"
            )
        if isinstance(geo, Mapping):
            try:
                geo = GeoOriginConfig.model_validate(geo)
            except ValueError:
                return None
        if not isinstance(geo, GeoOriginConfig):
            return None
        self._frame = geo.frame()
        return self._frame


def _number(value: Any, field: str, low: float, high: float, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{field} = {value!r}: must be a number ({unit})")
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{field} = {value!r}: must be a finite number in [{low:g}, {high:g}]")
    return float(value)


def _resolve_point(
    point: Mapping[str, Any], where: str, origin: _Origin, exactly_one: bool, sep: str = "."
) -> Mapping[str, Any]:
    """One position (a way-point, the start, the transceiver) with its geographic pair made
    east/north; ``exactly_one``: refuse a local pair beside the geographic one; messages name
    a field ``f"{where}{sep}{name}"``."""
    geo = [k for k in GEO if k in point]
    local = [k for k in LOCAL if k in point]
    if len(geo) == 1:
        other = GEO[1 - GEO.index(geo[0])]
        raise ValueError(f"{where}{sep}{geo[0]} = {point[geo[0]]!r}: needs {where}{sep}{other} too")
    if exactly_one and geo and local:
        raise ValueError(
            f"{where}: give east_m/north_m or latitude_deg/longitude_deg, not both "
            f"(got {', '.join(local + geo)})"
        )
    if exactly_one and not geo and len(local) != 2:
        missing = [k for k in LOCAL if k not in point]
        raise ValueError(
            f"{where}: needs a position: east_m and north_m, or latitude_deg and longitude_deg "
            f"({', '.join(missing)} missing)"
        )
    if not geo:
        return point
    lat = _number(point["latitude_deg"], f"{where}{sep}latitude_deg", -90.0, 90.0, "deg")
    lon = _number(point["longitude_deg"], f"{where}{sep}longitude_deg", -180.0, 180.0, "deg")
    frame = origin.frame(f"{where}{sep}latitude_deg", lat)
    if frame is None:
        return point
    east, north = frame.to_local(lat, lon)
    r = math.hypot(float(east), float(north))
    if not r <= MAX_DISTANCE_FROM_ORIGIN_M:
        raise ValueError(
            f"{where}{sep}latitude_deg, longitude_deg = {lat!r}, {lon!r}: {r / 1000:.0f} km from "
            f"the geo origin ({frame.latitude_deg!r}, {frame.longitude_deg!r}); at most "
            f"{MAX_DISTANCE_FROM_ORIGIN_M / 1000:g} km allowed"
        )
    out = {k: v for k, v in point.items() if k not in GEO and k not in LOCAL}
    return {"east_m": float(east), "north_m": float(north), **out}


# ---------------------------------------------------------------------------------------------
# Way-point files


def read_waypoints_file(path: Any) -> list[dict[str, Any]]:
    """The way-points of a CSV or GeoJSON file (module docstring), as scenario data.

    Args:
        path: the file (``str``; relative to the current directory).

    Returns:
        One dict per way-point, in order: ``latitude_deg``/``longitude_deg`` (GeoJSON, CSV with
        those columns) or ``east_m``/``north_m`` (CSV), and the optional fields the file gives.

    Raises:
        ValueError: naming the file, and the row (CSV line, GeoJSON feature or vertex) and column
            (or property) of the first problem, the value and what is allowed.
    """
    field = f"guidance.waypoints_file = {path!r}"
    if not isinstance(path, str) or not path:
        raise ValueError(f"{field}: must be the path of a .csv or .geojson file (a string)")
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".csv", ".geojson", ".json"):
        raise ValueError(f"{field}: the file's extension must be .csv, .geojson or .json")
    text = read_text_file(p, MAX_WAYPOINTS_FILE_BYTES, field, encoding="utf-8-sig")
    rows = _read_csv(text, field) if suffix == ".csv" else _read_geojson(text, field)
    if not rows:
        raise ValueError(f"{field}: holds no way-point (at least 1 needed)")
    if len(rows) > MAX_ARRAY_ITEMS:
        raise ValueError(f"{field}: {len(rows)} way-points; at most {MAX_ARRAY_ITEMS} allowed")
    return rows


def _float_cell(text: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where} = {text!r}: must be a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{where} = {text!r}: must be a finite number")
    return value


def _bool_cell(text: str, where: str) -> bool:
    word = text.strip().lower()
    if word in ("true", "1"):
        return True
    if word in ("false", "0"):
        return False
    raise ValueError(f"{where} = {text!r}: must be true, false, 1 or 0")


_CELL: dict[str, Callable[[str, str], Any]] = {
    "latitude_deg": _float_cell,
    "longitude_deg": _float_cell,
    "east_m": _float_cell,
    "north_m": _float_cell,
    "depth_m": _float_cell,
    "acceptance_radius_m": _float_cell,
    "surface": _bool_cell,
}


def _read_csv(text: str, field: str) -> list[dict[str, Any]]:
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        header = next(reader, None)
        if header is None:
            raise ValueError(f"{field}: empty (a header row is needed)")
        names = [h.strip() for h in header]
        for i, name in enumerate(names):
            if name not in _CELL:
                raise ValueError(
                    f"{field}: line 1, column {i + 1} = {name!r}: unknown column; allowed: "
                    f"{', '.join(_CELL)}"
                )
        if len(set(names)) != len(names):
            raise ValueError(f"{field}: line 1: a column is named twice ({', '.join(names)})")
        pairs = [pair for pair in (GEO, LOCAL) if any(k in names for k in pair)]
        if len(pairs) != 1 or not all(k in names for k in pairs[0]):
            raise ValueError(
                f"{field}: line 1 = {','.join(names)!r}: needs the columns latitude_deg and "
                "longitude_deg, or east_m and north_m (one pair)"
            )
        rows = []
        for row in reader:
            line = reader.line_num
            if not any(cell.strip() for cell in row):
                continue  # a blank line
            if len(row) != len(names):
                raise ValueError(
                    f"{field}: line {line}: {len(row)} cells, the header has {len(names)}"
                )
            wp: dict[str, Any] = {}
            for name, cell in zip(names, row, strict=True):
                where = f"{field}: line {line}, column {name!r}"
                if not cell.strip():
                    if name in pairs[0]:
                        raise ValueError(f"{where}: empty (required)")
                    continue
                wp[name] = _CELL[name](cell.strip(), where)
            rows.append(wp)
            if len(rows) > MAX_ARRAY_ITEMS:
                break
    except csv.Error as exc:
        raise ValueError(f"{field}: line {reader.line_num}: not CSV ({exc})") from None
    return rows


def _reject_constant(name: str) -> None:
    raise ValueError(f"{name} is not a JSON number")


def _read_geojson(text: str, field: str) -> list[dict[str, Any]]:
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except ValueError as exc:
        raise ValueError(f"{field}: not JSON ({exc})") from None
    except RecursionError:
        raise ValueError(f"{field}: arrays or objects nested too deep to be GeoJSON") from None
    if not isinstance(doc, dict):
        raise ValueError(f"{field}: a GeoJSON object is needed, got a {type(doc).__name__}")
    crs = doc.get("crs")
    if crs is not None:
        name = crs.get("properties", {}).get("name") if isinstance(crs, dict) else None
        if name not in CRS84:
            raise ValueError(
                f"{field}: crs = {name or crs!r}: coordinates must be WGS 84 longitude, latitude "
                "(RFC 7946; OGC CRS84)"
            )
    kind = doc.get("type")
    if kind == "FeatureCollection":
        features = doc.get("features")
        if not isinstance(features, list):
            raise ValueError(f"{field}: the FeatureCollection's 'features' must be an array")
    elif kind == "Feature":
        features = [doc]
    else:
        raise ValueError(
            f"{field}: type = {kind!r}: must be a FeatureCollection (of Points, or one "
            "LineString) or a LineString Feature"
        )
    geometries = []
    for i, f in enumerate(features):
        where = f"{field}: feature {i}"
        if not isinstance(f, dict) or f.get("type") != "Feature":
            raise ValueError(f"{where}: must be an object with type = 'Feature'")
        geom = f.get("geometry")
        gtype = geom.get("type") if isinstance(geom, dict) else None
        if gtype not in ("Point", "LineString"):
            raise ValueError(
                f"{where}: geometry type = {gtype!r}: must be Point or LineString (way-points)"
            )
        props = f.get("properties")
        if props is None:
            props = {}
        if not isinstance(props, dict):
            raise ValueError(f"{where}: properties must be an object or null")
        geometries.append((where, gtype, geom.get("coordinates"), props))
    lines = [g for g in geometries if g[1] == "LineString"]
    if lines and len(geometries) != 1:
        raise ValueError(
            f"{field}: {len(lines)} LineString(s) among {len(geometries)} features: give one "
            "LineString, or Points only"
        )
    rows = []
    for where, gtype, coords, props in geometries:
        if gtype == "Point":
            rows.append(_geojson_point(coords, props, where))
            continue
        if not isinstance(coords, list) or len(coords) < 2:
            raise ValueError(f"{where}: a LineString needs at least 2 positions")
        if len(coords) > MAX_ARRAY_ITEMS:
            raise ValueError(f"{where}: {len(coords)} positions; at most {MAX_ARRAY_ITEMS}")
        rows += [_geojson_point(c, props, f"{where}, vertex {j}") for j, c in enumerate(coords)]
    return rows


def _geojson_point(coords: Any, props: Mapping[str, Any], where: str) -> dict[str, Any]:
    if not isinstance(coords, list) or len(coords) not in (2, 3):
        raise ValueError(
            f"{where}: coordinates = {coords!r}: must be [longitude, latitude] or [longitude, "
            "latitude, height] (deg, deg, m)"
        )
    lon = _number(coords[0], f"{where}: longitude", -180.0, 180.0, "deg")
    lat = _number(coords[1], f"{where}: latitude", -90.0, 90.0, "deg")
    wp: dict[str, Any] = {"latitude_deg": lat, "longitude_deg": lon}
    for key, value in props.items():
        if key not in OPTIONAL:
            continue  # a GIS tool's own properties (name, id, ...) are not way-point fields
        if key == "surface":
            if not isinstance(value, bool):
                raise ValueError(f"{where}: property surface = {value!r}: must be true or false")
            wp[key] = value
        else:
            wp[key] = _number(value, f"{where}: property {key}", -math.inf, math.inf, "m")
    if len(coords) == 3:
        height = _number(coords[2], f"{where}: height", -math.inf, math.inf, "m, up")
        given = wp.get("depth_m")
        if given is not None and abs(given + height) > DEPTH_AGREEMENT_M:
            raise ValueError(
                f"{where}: height = {height!r} m and property depth_m = {given!r} m disagree "
                "(the third coordinate is a height, up: depth = -height)"
            )
        wp["depth_m"] = -height
    return wp
