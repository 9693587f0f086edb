"""The formation of ``mission/swarm``: the leader's pattern and the followers' stations relative
to it (given, or generated for any number of followers) (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.frames import unit_vector_scalar

Array = NDArray[np.float64]

MIN_STATION_SEPARATION_M = 2.5
"""Smallest distance between two followers' station points (and, through
:attr:`StationConfig.distance_m`, between a station and the leader), m: about one and a half
hull lengths (1.6 m to the caudal-fin hinge)."""


def racetrack(
    length_m: float = 230.0,
    radius_m: float = 50.0,
    spacing_m: float = 40.0,
    step_deg: float = 20.0,
    depth_m: float = 3.0,
) -> list[dict[str, float]]:
    """The leader's default pattern from (0, 0): north ``length_m`` (a way-point every
    ``spacing_m``, so that the direct course to the next one keeps the leader near the line in
    the cross current), a clockwise half circle of ``radius_m`` (a way-point every ``step_deg``:
    the turn is wide enough for a follower 10-20 m inside it), then south ``length_m``; about
    620 m, 10 minutes at 1 m/s."""
    legs = np.arange(spacing_m, length_m + 1e-9, spacing_m)
    if legs[-1] < length_m - 1e-9:
        legs = np.append(legs, length_m)
    wps = [(0.0, float(n)) for n in legs]
    for b in np.arange(270.0 + step_deg, 450.0 + 1e-9, step_deg):
        e, n = unit_vector_scalar(math.radians(b % 360))
        wps.append((radius_m + radius_m * e, length_m + radius_m * n))
    wps += [(2 * radius_m, float(n)) for n in legs[::-1][1:]] + [(2 * radius_m, 0.0)]
    return [
        {"east_m": e, "north_m": n, "depth_m": depth_m, "acceptance_radius_m": 5.0} for e, n in wps
    ]


class StationConfig(Config):
    """A follower's station relative to the leader."""

    relative_bearing_deg: float = Field(
        90.0,
        ge=0,
        lt=360,
        description="bearing of the station from the leader, clockwise from the leader's course "
        "(90: abeam to starboard, 270: to port, 180: astern), deg",
    )
    distance_m: float = Field(10.0, gt=2.5, le=200, description="distance from the leader, m")


STATION_RING_M = 10.0
"""Distance between the rings of generated stations, m (:func:`generated_station`)."""
STATION_RING_BEARINGS_DEG = (90.0, 270.0, 180.0)
"""Relative bearings of a ring of generated stations: abeam to starboard, to port, astern."""


def generated_station(index: int) -> StationConfig:
    """The station of follower ``index`` (0-based) when the scenario gives none for it: rings of
    three stations (abeam to starboard, abeam to port, astern) at 10, 20, 30 ... m,

        relative bearing = (90, 270, 180)[index mod 3] deg,
        distance = 10 * (index div 3 + 1) m.

    The four default stations are the first four of this sequence (:data:`DEFAULT_STATIONS`).

    Args:
        index: the follower's index, >= 0 (``f1`` is 0).
    """
    ring, k = divmod(index, len(STATION_RING_BEARINGS_DEG))
    return StationConfig(
        relative_bearing_deg=STATION_RING_BEARINGS_DEG[k], distance_m=STATION_RING_M * (ring + 1)
    )


DEFAULT_STATIONS = tuple(generated_station(i) for i in range(4))
"""Four stations: abeam to starboard and to port at 10 m, astern at 10 m, starboard at 20 m (the
first four of :func:`generated_station`)."""


def station_point_m(station: StationConfig, course_rad: float = 0.0) -> Array:
    """A station's offset from the leader (east, north), shape (2,), m, for the leader's course
    (rad clockwise from north)."""
    b = course_rad + math.radians(station.relative_bearing_deg)
    return station.distance_m * np.array(unit_vector_scalar(b))
