"""Station keeping in ``mission/swarm``: a follower's guidance towards its station relative to
the leader, on its own estimate (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import unit_vector_scalar, wrap_2pi_scalar
from nav.guidance import GuidanceCommand
from nav.navigator import FollowerReport
from tasks.closed_loop.navigation import NavOutput, report_of
from tasks.missions.swarm.scenario import StationConfig, StationGuidanceConfig

Array = NDArray[np.float64]


@dataclass
class StationGuidance:
    """Station keeping on the follower's estimate (module docstring).

    Args:
        cfg: the gains and limits.
        station: the station relative to the leader.
        tick_s: control tick, s.
        leader_done: whether the leader's pattern is over (the mission ends with it).
    """

    cfg: StationGuidanceConfig
    station: StationConfig
    tick_s: float
    leader_done: Callable[[], bool]

    def __post_init__(self) -> None:
        self._integral = np.zeros(2)
        self.bearing = math.radians(self.station.relative_bearing_deg)

    @property
    def done(self) -> bool:
        return self.leader_done()

    def station_point(self, leader_xy: Array, leader_course: float) -> Array:
        """The station for a leader position (2,) m and course (rad), shape (2,), m."""
        return leader_xy + self.station.distance_m * np.array(
            unit_vector_scalar(leader_course + self.bearing)
        )

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        c = self.cfg
        rep = report_of(nav, FollowerReport)
        course_l = rep.leader_course
        speed_l = float(np.hypot(*rep.leader.velocity_world_m_s))
        s = self.station_point(rep.leader_est, course_l)
        e = s - nav.estimate.x[:2]
        corr = c.gain_per_s * e
        norm = float(np.hypot(*corr))
        if norm > c.max_correction_m_s:
            corr *= c.max_correction_m_s / norm
        self._integral += c.integral_gain_per_s2 * e * self.tick_s
        norm = float(np.hypot(*self._integral))
        if norm > c.max_integral_m_s:
            self._integral *= c.max_integral_m_s / norm
        u = np.array(unit_vector_scalar(course_l))
        n = np.array([u[1], -u[0]])  # to starboard of the leader's course
        w = corr + self._integral
        along = max(speed_l + float(w @ u), c.min_speed_m_s)
        cross = float(w @ n)
        lim = math.tan(math.radians(c.max_crossing_deg))
        cross = max(-lim * along, min(lim * along, cross))
        course = wrap_2pi_scalar(course_l + math.atan2(cross, along))
        speed = min(max(math.hypot(along, cross), c.min_speed_m_s), c.max_speed_m_s)
        mode = "done" if self.done else "transit"
        return GuidanceCommand(course, c.depth_m, speed, mode, 0)

    def waypoints(self) -> list[tuple[float, float, float]]:
        return []

    def legs(self) -> list[dict[str, Any]]:
        return []

    def outcome(self) -> dict[str, Any]:
        return {
            "relative_bearing_deg": self.station.relative_bearing_deg,
            "distance_m": self.station.distance_m,
        }
