"""What a medium answers about sound between two points, and the isovelocity medium.

Frames: world ENU, z up (depth = -z), positions in metres. Angles are elevations from the
horizontal, positive up. The eigenray of a horizontally stratified medium stays in the vertical
plane through its two ends, so the azimuth of either end seen from the other is the straight
line's; only the travel time and the elevations depend on the medium.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Eigenray:
    """The direct ray from a source to a receiver.

    Attributes:
        travel_time_s: time the sound takes, shape (...), s.
        launch_elevation_rad: elevation of the ray leaving the source, shape (...), rad, positive
            up.
        arrival_elevation_rad: elevation, seen from the receiver, of the direction the sound
            arrives from (towards the source along the arriving ray's tangent), shape (...),
            rad, positive up: what an array at the receiver measures.
    """

    travel_time_s: Array
    launch_elevation_rad: Array
    arrival_elevation_rad: Array


class Propagation(Protocol):
    """A medium: the direct eigenray between points (shapes broadcast over ``...``)."""

    def eigenray(self, source_world_m: ArrayLike, receiver_world_m: ArrayLike) -> Eigenray:
        """The direct ray from ``source_world_m`` (shape (..., 3), m, world ENU) to
        ``receiver_world_m`` (shape (..., 3))."""
        ...


@dataclass(frozen=True)
class Isovelocity:
    """One sound speed everywhere: straight rays, travel time = distance / speed.

    Attributes:
        speed_m_s: the sound speed, m/s.
    """

    speed_m_s: float = 1500.0

    def eigenray(self, source_world_m: ArrayLike, receiver_world_m: ArrayLike) -> Eigenray:
        """The straight ray (see :class:`Propagation`)."""
        d = np.asarray(receiver_world_m, dtype=float) - np.asarray(source_world_m, dtype=float)
        horizontal = np.hypot(d[..., 0], d[..., 1])
        distance = np.sqrt(horizontal**2 + d[..., 2] ** 2)
        launch = np.arctan2(d[..., 2], horizontal)
        return Eigenray(distance / self.speed_m_s, launch, -launch)
