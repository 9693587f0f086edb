"""Way-point guidance: desired course, depth and speed from the *estimated* position.

The mission is a list of way-points, each with an acceptance radius and a depth, some marked for a
surfacing manoeuvre (seed 001: the vehicle surfaces to take a GPS fix). For each leg the desired
course is the direct course from the estimated position to the way-point (seed 001, "direct course
nu"), or the course of a pluggable course law (seed 001's current-compensating course, eq. 22-26).

A way-point is reached when, given the estimate and its uncertainty, the true position is inside
the acceptance circle with probability ``reach_probability`` (0.95): with the estimate at
horizontal distance d from the way-point and sigma the standard deviation along its worst
horizontal direction (taken isotropic, which is conservative), the true distance is Rice
distributed, and the test is ``P(Rice(d, sigma) <= R) >= p``. When sigma is so large that even
d = 0 cannot satisfy it (R < sigma sqrt(-2 ln(1 - p))), the vehicle aims to pass within
``min_reach_m`` of the way-point instead, which is the best it can do. An estimate without a
covariance (sigma = 0) reaches it inside the circle. The vehicle only knows where it thinks it is.
A leg that takes longer than ``max_leg_time_s`` is abandoned and the way-point counted as missed,
so a mission always ends.

Surfacing: ``ascend`` (depth 0 at reduced speed until the estimated depth is above
``surface_depth_m``), ``surface`` (hold until ``fixes_needed`` GPS fixes arrived and ``hold_s``
passed), then ``dive`` to the next leg's depth while heading for the next way-point.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from nav.angles import course_of_scalar
from nav.errors import NavInputError

Array = NDArray[np.float64]
CourseLaw = Callable[[Array, "Waypoint"], float]
"""(estimated position (3,), way-point) -> desired course, rad clockwise from north."""


@dataclass(frozen=True)
class Waypoint:
    """A way-point.

    Attributes:
        east_m: east coordinate, m, world.
        north_m: north coordinate, m, world.
        depth_m: depth of the leg that ends here, m.
        acceptance_radius_m: horizontal radius within which it counts as reached, m.
        surface: whether to surface here for a GPS fix.
    """

    east_m: float
    north_m: float
    depth_m: float
    acceptance_radius_m: float = 5.0
    surface: bool = False


@dataclass(frozen=True)
class GuidanceCommand:
    """What guidance asks of the autopilot.

    Attributes:
        course_rad: desired course, rad clockwise from north.
        depth_m: desired depth, m.
        speed_m_s: desired speed through water, m/s.
        mode: ``transit``, ``ascend``, ``surface``, ``dive`` or ``done``.
        waypoint: index of the way-point being approached (== len(waypoints) when done).
    """

    course_rad: float
    depth_m: float
    speed_m_s: float
    mode: str
    waypoint: int


def direct_course(position: Array, wp: Waypoint) -> float:
    """Direct course from a position to a way-point, rad clockwise from north, in [0, 2 pi)."""
    return course_of_scalar(wp.east_m - position[0], wp.north_m - position[1])


def horizontal_sigma_m(P: Array) -> float:
    """Standard deviation of a position estimate along its worst horizontal direction: the
    square root of the larger eigenvalue of the horizontal 2x2 block of ``P`` (shape (3, 3) or
    larger, m^2), m."""
    tr = P[0, 0] + P[1, 1]
    det = P[0, 0] * P[1, 1] - P[0, 1] ** 2
    return math.sqrt(max(0.5 * tr + math.sqrt(max(0.25 * tr**2 - det, 0.0)), 0.0))


@dataclass
class LegRecord:
    """How a leg ended: reached (by the estimate) or missed (timed out), and when."""

    waypoint: int
    reached: bool
    t_s: float


@dataclass
class WaypointGuidance:
    """Way-point guidance state machine (see the module docstring).

    Args:
        waypoints: the mission.
        speed_m_s: cruise speed through water, m/s.
        surface_speed_m_s: speed while ascending and at the surface, m/s.
        surface_depth_m: estimated depth counted as surfaced, m.
        hold_s: minimum time at the surface, s.
        fixes_needed: GPS fixes to collect before diving.
        max_leg_time_s: a leg taking longer is abandoned, s.
        course_law: desired course for a leg (default: the direct course).
        reach_probability: probability that the true position is inside the circle.
        min_reach_m: distance that counts as reached when the probability cannot be met, m.
    """

    waypoints: Sequence[Waypoint]
    speed_m_s: float = 1.0
    surface_speed_m_s: float = 0.4
    surface_depth_m: float = 0.3
    hold_s: float = 10.0
    fixes_needed: int = 1
    max_leg_time_s: float = 1200.0
    course_law: CourseLaw = direct_course
    reach_probability: float = 0.95
    min_reach_m: float = 1.0
    index: int = 0
    mode: str = "transit"
    legs: list[LegRecord] = field(default_factory=list)
    _leg_start_s: float | None = None
    _surfaced_at_s: float | None = None
    _fixes: int = 0
    _hold_course: float = 0.0
    _sigma: float = 0.0

    def __post_init__(self) -> None:
        if not self.waypoints:
            raise NavInputError("a way-point mission needs at least one way-point")
        for i, wp in enumerate(self.waypoints):
            if wp.acceptance_radius_m <= 0 or wp.depth_m < 0:
                raise NavInputError(
                    f"waypoints[{i}]: acceptance_radius_m = {wp.acceptance_radius_m} must be > 0 "
                    f"and depth_m = {wp.depth_m} >= 0"
                )

    @property
    def done(self) -> bool:
        """Whether the mission is over."""
        return self.mode == "done"

    def gps_fix(self) -> None:
        """Tell guidance a GPS fix arrived (counts only at the surface)."""
        if self.mode == "surface":
            self._fixes += 1

    def _next_leg(self, t_s: float, reached: bool) -> None:
        self.legs.append(LegRecord(self.index, reached, t_s))
        self.index += 1
        self._leg_start_s = t_s
        self.mode = "done" if self.index >= len(self.waypoints) else "transit"

    def reached(self, dist_m: float, radius_m: float, sigma_m: float) -> bool:
        """The reach test of the module docstring.

        Args:
            dist_m: horizontal distance of the estimate to the way-point, m.
            radius_m: acceptance radius, m.
            sigma_m: standard deviation of the estimate (worst horizontal direction), m.
        """
        if dist_m > radius_m:
            return False
        if sigma_m <= 0.0:
            return True
        p = self.reach_probability
        if radius_m < sigma_m * math.sqrt(-2.0 * math.log(1.0 - p)):
            return dist_m <= self.min_reach_m  # the probability cannot be met: pass over it
        from scipy.stats import rice  # on first use: scipy.stats costs ~0.4 s to import

        return float(rice.cdf(radius_m, dist_m / sigma_m, scale=sigma_m)) >= p

    def step(self, t_s: float, position: Array, sigma_m: float = 0.0) -> GuidanceCommand:
        """The command for now.

        Args:
            t_s: time, s.
            position: estimated position (east, north, up), shape (3,), m, world.
            sigma_m: standard deviation of the estimate along its worst horizontal direction, m
                (0 for an estimate without a covariance).

        Returns:
            The command.
        """
        p = np.asarray(position, dtype=float)
        self._sigma = float(sigma_m)
        if self._leg_start_s is None:
            self._leg_start_s = t_s
        if self.mode == "done":
            return GuidanceCommand(self._hold_course, 0.0, 0.0, "done", self.index)
        wp = self.waypoints[self.index]
        if self.mode in ("transit", "dive"):
            dist = math.hypot(wp.east_m - p[0], wp.north_m - p[1])
            if self.reached(dist, wp.acceptance_radius_m, self._sigma):
                if wp.surface:
                    self.mode, self._fixes, self._surfaced_at_s = "ascend", 0, None
                    self._hold_course = self.course_law(p, wp)
                else:
                    self._next_leg(t_s, True)
                    return self.step(t_s, p, self._sigma)
            elif t_s - self._leg_start_s > self.max_leg_time_s:
                self._next_leg(t_s, False)
                return self.step(t_s, p, self._sigma)
            else:
                if self.mode == "dive" and -p[2] >= 0.8 * wp.depth_m:
                    self.mode = "transit"
                self._hold_course = self.course_law(p, wp)
                return GuidanceCommand(
                    self._hold_course, wp.depth_m, self.speed_m_s, self.mode, self.index
                )
        if self.mode == "ascend":
            if -p[2] <= self.surface_depth_m:
                self.mode, self._surfaced_at_s = "surface", t_s
            return GuidanceCommand(
                self._hold_course, 0.0, self.surface_speed_m_s, "ascend", self.index
            )
        # at the surface
        assert self._surfaced_at_s is not None
        if self._fixes >= self.fixes_needed and t_s - self._surfaced_at_s >= self.hold_s:
            self._next_leg(t_s, True)
            if self.mode == "done":
                return GuidanceCommand(self._hold_course, 0.0, 0.0, "done", self.index)
            self.mode = "dive"
            nxt = self.waypoints[self.index]
            self._hold_course = self.course_law(p, nxt)
            return GuidanceCommand(
                self._hold_course, nxt.depth_m, self.speed_m_s, "dive", self.index
            )
        return GuidanceCommand(
            self._hold_course, 0.0, self.surface_speed_m_s, "surface", self.index
        )
