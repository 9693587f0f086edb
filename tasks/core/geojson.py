"""Run data on the Earth: latitude/longitude companions of the position columns, and the tracks
as GeoJSON (RFC 7946) for a GIS or a web map.

With a geographic origin (:class:`bauv_sim.geo.LocalFrame`), the tables of the run data keep
their east/north columns and gain, for each **position column** (unit ``m``, components starting
``east, north``, and not a displacement: its description does not say "displacement"), a column
``<name>_geo`` with components ``latitude, longitude`` (unit ``deg``, WGS 84), and a table with
scalar ``east``/``north`` columns (the GPS fixes) gains ``latitude``/``longitude``
(:func:`with_geographic`); the files name them ``<name>_geo_deg``, ``latitude_deg``,
``longitude_deg`` (:func:`tasks.core.export.data_columns`). The conversion is the frame's inverse
azimuthal equidistant projection (PROJ, on the WGS 84 ellipsoid); a missing position (NaN in a
nullable column) has a missing latitude and longitude.

:func:`write_tracks_geojson` writes one FeatureCollection: a LineString per position column of
a tick table (the truth and every estimate; one vertex per tick, ``[longitude, latitude]`` in
WGS 84 as RFC 7946 section 3.1.1 orders them, rounded to :data:`DECIMALS` decimals: 1.1 mm at
most), with the run's properties and the track's name, description and first and last times;
and a Point per way-point. Heights are not written: the scene's z is relative to the origin's
surface, not to the ellipsoid GeoJSON's third coordinate would mean.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from bauv_sim.geo import LocalFrame
from tasks.core.export import Column
from tasks.core.files import atomic_write_bytes

DECIMALS = 8
"""Decimals of a degree written to GeoJSON: 1e-8 deg is at most 1.1 mm on the Earth."""
GEO_SUFFIX = "_geo"
"""A position column ``name``'s latitude/longitude companion is ``name + GEO_SUFFIX``."""
GEO_COMPONENTS = ("latitude", "longitude")


def is_position(col: Column) -> bool:
    """Whether a column holds positions in the scene's frame (module docstring)."""
    v = col.values
    return (
        col.unit == "m"
        and v.ndim == 2
        and col.components[:2] == ("east", "north")
        and "displacement" not in col.description.lower()
        and v.dtype.kind == "f"
    )


def _frame_text(frame: LocalFrame) -> str:
    return f"geo origin {frame.latitude_deg!r} N, {frame.longitude_deg!r} E"


def geographic(frame: LocalFrame, east_m: np.ndarray, north_m: np.ndarray) -> np.ndarray:
    """Latitude and longitude of positions, NaN where a position is missing.

    Args:
        frame: the scene's frame.
        east_m: shape (T,), m.
        north_m: shape (T,), m.

    Returns:
        shape (T, 2): latitude, longitude, deg, WGS 84.
    """
    out = np.full((len(east_m), 2), np.nan)
    ok = np.isfinite(east_m) & np.isfinite(north_m)
    if ok.any():
        lat, lon = frame.to_geographic(east_m[ok], north_m[ok])
        out[ok, 0], out[ok, 1] = lat, lon
    return out


def with_geographic(columns: Mapping[str, Column], frame: LocalFrame) -> dict[str, Column]:
    """The columns, with latitude/longitude companions after each position (module docstring).

    Args:
        columns: a table of the run data (one device's fixes, or the ticks).
        frame: the scene's frame.

    Returns:
        A new table: every column of ``columns`` in order (the same objects), each position
        column followed by ``<name>_geo`` (shape (T, 2), deg), and ``north`` of a table with
        scalar ``east``/``north`` (m) followed by ``latitude`` and ``longitude`` (shape (T,), deg).
    """
    out: dict[str, Column] = {}
    origin = _frame_text(frame)
    scalar_pair = all(
        k in columns and columns[k].unit == "m" and columns[k].values.ndim == 1
        for k in ("east", "north")
    )
    for name, col in columns.items():
        out[name] = col
        if is_position(col):
            v = col.values.astype(float)
            geo = geographic(frame, v[:, 0], v[:, 1])
            out[name + GEO_SUFFIX] = Column(
                geo,
                "deg",
                f"WGS 84 latitude and longitude of {name} ({origin}; PROJ azimuthal equidistant)",
                GEO_COMPONENTS,
                bool(np.isnan(geo).any()) or col.nullable,
            )
        elif scalar_pair and name == "north":
            e = columns["east"].values.astype(float)
            geo = geographic(frame, e, col.values.astype(float))
            nullable = bool(np.isnan(geo).any())
            for j, comp in enumerate(GEO_COMPONENTS):
                out[comp] = Column(
                    geo[:, j].copy(),
                    "deg",
                    f"WGS 84 {comp} of (east, north) ({origin}; PROJ azimuthal equidistant)",
                    (),
                    nullable,
                )
    return out


def _position(lat: float, lon: float) -> list[float]:
    return [round(float(lon), DECIMALS), round(float(lat), DECIMALS)]


def track_features(
    ticks: Mapping[str, Column], frame: LocalFrame, properties: Mapping[str, Any]
) -> list[dict[str, Any]]:
    """A LineString Feature per position column of a tick table (module docstring).

    Args:
        ticks: the per-tick columns, with the time ``t`` (s).
        frame: the scene's frame.
        properties: properties every feature carries (run, vehicle, ...).

    Returns:
        GeoJSON Feature objects; a track with one position is a Point, missing positions (NaN)
        are left out of it (``n_points`` counts the vertices written).
    """
    t = ticks["t"].values if "t" in ticks else None
    features = []
    for name, col in ticks.items():
        if not is_position(col):
            continue
        v = col.values.astype(float)
        ok = np.isfinite(v[:, 0]) & np.isfinite(v[:, 1])
        if not ok.any():
            continue
        geo = geographic(frame, v[ok, 0], v[ok, 1])
        coords = [_position(lat, lon) for lat, lon in geo]
        props: dict[str, Any] = {**properties, "track": name, "description": col.description}
        if t is not None:
            times = t[ok]
            props.update(t_start_s=float(times[0]), t_end_s=float(times[-1]))
        props["n_points"] = len(coords)
        geometry = (
            {"type": "LineString", "coordinates": coords}
            if len(coords) > 1
            else {"type": "Point", "coordinates": coords[0]}
        )
        features.append({"type": "Feature", "geometry": geometry, "properties": props})
    return features


def point_features(
    points: Iterable[tuple[str, float, float]], frame: LocalFrame, properties: Mapping[str, Any]
) -> list[dict[str, Any]]:
    """Point Features of named positions (way-points, a transceiver).

    Args:
        points: ``(name, east m, north m)`` in the scene's frame.
        frame: the scene's frame.
        properties: properties every feature carries.
    """
    out = []
    for name, east, north in points:
        (lat, lon) = geographic(frame, np.array([east]), np.array([north]))[0]
        out.append(
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": _position(lat, lon)},
                "properties": {**properties, "point": name, "east_m": east, "north_m": north},
            }
        )
    return out


def write_tracks_geojson(
    path: str | Path,
    ticks: Mapping[str, Column],
    frame: LocalFrame,
    properties: Mapping[str, Any],
    points: Iterable[tuple[str, float, float]] = (),
) -> None:
    """Write a vehicle's tracks (and named points) as a GeoJSON FeatureCollection, atomically.

    Args:
        path: the file (``.geojson``; replaced whole or not at all).
        ticks: the vehicle's per-tick columns (see :func:`track_features`).
        frame: the scene's frame.
        properties: JSON-serialisable properties of every feature (run, vehicle, experiment).
        points: named positions (see :func:`point_features`).

    Raises:
        ValueError: if a property is not JSON (NaN included: RFC 8259 has none).
        OSError: if the file cannot be written (nothing is left behind).
    """
    features = track_features(ticks, frame, properties)
    features += point_features(points, frame, properties)
    doc = {"type": "FeatureCollection", "features": features}
    text = json.dumps(doc, allow_nan=False, separators=(",", ":"))
    atomic_write_bytes(Path(path), text.encode("utf-8"))
