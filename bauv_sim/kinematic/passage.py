"""Seed 000's straight passage past a seabed USBL transceiver (section 6, Figure 7).

The vehicle moves at constant course, speed and depth ("undisturbed movement"); its reference
position at tick k is dead-reckoned exactly from the reference course and speed. Figure 7 is given
only as a picture; the defaults below reproduce it and the published statistics:

* COG 220 deg, SOG 1 m/s, depth 3 m, transceiver at 6 m depth, 600 s at 1 s ticks (section 6);
* closest approach to the transceiver at t = 450 s (the USBL accuracy is best in 400-500 s,
  section 6.1), 10 m abeam, transceiver on the starboard side. The abeam distance is not in the
  text: 10 m makes the smallest mean USBL-only 3-D error of 100 passages 1.3 m, as in Tables 4 and 8
  (at 20 m it would be about 2.4 m).

The start is derived from the closest approach unless given explicitly.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.frames import unit_vector_scalar, velocity_from_course_speed
from bauv_sim.sensors.base import check_multiple
from bauv_sim.truth import Truth


class TransceiverConfig(Config):
    """A USBL transceiver fixed on or above the seabed."""

    east_m: float = Field(0.0, description="east position, m, world")
    north_m: float = Field(0.0, description="north position, m, world")
    depth_m: float = Field(6.0, ge=0, description="depth, m (seed 000: 6 m)")

    def position_world_m(self) -> NDArray[np.float64]:
        """Position, shape (3,), m, world (z up)."""
        return np.array([self.east_m, self.north_m, -self.depth_m])


class StraightPassageConfig(Config):
    """Geometry and timing of the straight passage (defaults: seed 000 Figure 7, see module)."""

    course_deg: float = Field(220.0, ge=0, lt=360, description="course over ground, deg")
    speed_m_s: float = Field(1.0, gt=0, le=10, description="speed over ground, m/s")
    depth_m: float = Field(3.0, ge=0, description="depth, m")
    duration_s: float = Field(600.0, gt=0, description="length of the passage, s")
    tick_s: float = Field(1.0, gt=0, description="time step of truth and motion sensors, s")
    closest_approach_time_s: float = Field(
        450.0, ge=0, description="time of the closest approach to the transceiver, s"
    )
    closest_approach_offset_m: float = Field(
        10.0,
        description="horizontal abeam distance at closest approach, m; + = transceiver to "
        "starboard",
    )
    start_east_m: float | None = Field(None, description="explicit start east, m (with north)")
    start_north_m: float | None = Field(None, description="explicit start north, m (with east)")

    @model_validator(mode="after")
    def _check(self) -> StraightPassageConfig:
        check_multiple(self.duration_s, self.tick_s, "passage.duration_s")
        if (self.start_east_m is None) != (self.start_north_m is None):
            raise ValueError("give both start_east_m and start_north_m, or neither")
        return self

    @property
    def n_ticks(self) -> int:
        """Number of ticks including t = 0."""
        return round(self.duration_s / self.tick_s) + 1


def passage_start(
    cfg: StraightPassageConfig, transceiver: TransceiverConfig
) -> NDArray[np.float64]:
    """Start position, shape (3,), m, world."""
    if cfg.start_east_m is not None and cfg.start_north_m is not None:
        return np.array([cfg.start_east_m, cfg.start_north_m, -cfg.depth_m])
    c = math.radians(cfg.course_deg)
    along = np.array(unit_vector_scalar(c))
    starboard = np.array([along[1], -along[0]])  # the course turned 90 deg clockwise
    tx = transceiver.position_world_m()[:2]
    closest = tx - cfg.closest_approach_offset_m * starboard
    start = closest - cfg.closest_approach_time_s * cfg.speed_m_s * along
    return np.array([start[0], start[1], -cfg.depth_m])


def straight_passage(cfg: StraightPassageConfig, transceiver: TransceiverConfig) -> Truth:
    """Truth of the straight passage, shared by every run (run axis of length 1).

    Returns:
        :class:`~bauv_sim.truth.Truth` on ticks 0..T with level attitude, heading = course, no
        current.
    """
    n = cfg.n_ticks
    t = np.arange(n) * cfg.tick_s
    c = math.radians(cfg.course_deg)
    v_h = velocity_from_course_speed(c, cfg.speed_m_s)
    vel = np.array([v_h[0], v_h[1], 0.0])
    pos = passage_start(cfg, transceiver) + t[:, None] * vel
    ones = np.ones((1, n))
    return Truth(
        t_s=t,
        pos_world_m=pos[None],
        vel_ground_world_m_s=np.broadcast_to(vel, (1, n, 3)),
        vel_water_world_m_s=np.broadcast_to(vel, (1, n, 3)),
        heading_rad=c * ones,
        roll_pitch_rad=np.zeros((1, n, 2)),
        current_world_m_s=np.zeros((1, n, 3)),
    )
