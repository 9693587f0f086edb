"""Way-point guidance of :mod:`nav.guidance` over a batch of vehicles at once (issue 27).

:class:`BatchWaypointGuidance` flies every run through the same way-points with the transit
legs of :class:`~nav.guidance.WaypointGuidance`: the direct course from each run's *estimated*
position, the probabilistic reach test on the estimate's worst horizontal standard deviation
(Rice distribution), the ``min_reach_m`` fallback and the ``max_leg_time_s`` abandonment, each
run on its own leg. Surfacing way-points (GPS fixes at the surface) are not flown by the batch
(refused). Each run's commands are those of a scalar :class:`WaypointGuidance` given the same
estimates (tested run by run in ``tests/nav/test_guidance_batch.py``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError
from nav.guidance import Waypoint

Array = NDArray[np.float64]


def horizontal_sigma_batch_m(P: Array) -> Array:
    """:func:`nav.guidance.horizontal_sigma_m` of each run: the square root of the larger
    eigenvalue of the horizontal 2x2 block of ``P`` (shape (n, d, d), m^2), m, shape (n,)."""
    a, b, d = P[:, 0, 0], P[:, 0, 1], P[:, 1, 1]
    tr = a + d
    det = a * d - b**2
    return np.sqrt(np.maximum(0.5 * tr + np.sqrt(np.maximum(0.25 * tr**2 - det, 0.0)), 0.0))


class BatchWaypointGuidance:
    """Transit way-point guidance of n runs (module docstring).

    Args:
        waypoints: the mission, the same for every run (no ``surface`` way-points).
        n: runs.
        speed_m_s: cruise speed through water, m/s.
        max_leg_time_s: a leg taking longer is abandoned (counted missed), s.
        reach_probability: probability that the truth is inside the acceptance circle.
        min_reach_m: distance that counts as reached when the probability cannot be met, m.

    Attributes:
        index: the way-point each run approaches, shape (n,) (``len(waypoints)`` when done).
        reached: whether each leg of each run ended reached, shape (n, k) (False: missed or not
            yet ended).
        leg_end_s: when each leg of each run ended, s, shape (n, k), NaN until it ends.
    """

    def __init__(
        self,
        waypoints: Sequence[Waypoint],
        n: int,
        speed_m_s: float = 1.0,
        max_leg_time_s: float = 1200.0,
        reach_probability: float = 0.95,
        min_reach_m: float = 1.0,
    ):
        if not waypoints:
            raise NavInputError("a way-point mission needs at least one way-point")
        for i, wp in enumerate(waypoints):
            if wp.acceptance_radius_m <= 0 or wp.depth_m < 0:
                raise NavInputError(
                    f"waypoints[{i}]: acceptance_radius_m = {wp.acceptance_radius_m} must be > 0 "
                    f"and depth_m = {wp.depth_m} >= 0"
                )
            if wp.surface:
                raise NavInputError(
                    f"waypoints[{i}].surface = True: batch guidance flies transit legs only"
                )
        self.waypoints = tuple(waypoints)
        self.n = n
        self.speed_m_s = float(speed_m_s)
        self.max_leg_time_s = float(max_leg_time_s)
        self.reach_probability = float(reach_probability)
        self.min_reach_m = float(min_reach_m)
        k = len(self.waypoints)
        self._wp = np.array(
            [[w.east_m, w.north_m, w.depth_m, w.acceptance_radius_m] for w in self.waypoints]
            + [[0.0, 0.0, 0.0, 1.0]]  # a sentinel row for runs that are done
        )
        self.index = np.zeros(n, dtype=np.intp)
        self.reached = np.zeros((n, k), dtype=bool)
        self.leg_end_s = np.full((n, k), np.nan)
        self._leg_start_s: Array | None = None
        self.hold_course_rad = np.zeros(n)

    @property
    def done(self) -> NDArray[np.bool_]:
        """Whether each run's mission is over, shape (n,)."""
        return self.index >= len(self.waypoints)

    def reach_test(self, dist_m: Array, radius_m: Array, sigma_m: Array) -> NDArray[np.bool_]:
        """:meth:`nav.guidance.WaypointGuidance.reached` of each run, shapes (n,)."""
        inside = dist_m <= radius_m
        out = inside & (sigma_m <= 0.0)
        p = self.reach_probability
        hopeless = radius_m < sigma_m * math.sqrt(-2.0 * math.log(1.0 - p))
        probe = inside & (sigma_m > 0.0)
        out |= probe & hopeless & (dist_m <= self.min_reach_m)
        ask = probe & ~hopeless
        if ask.any():
            from scipy.stats import rice

            s = sigma_m[ask]
            cdf = rice.cdf(radius_m[ask], dist_m[ask] / s, scale=s)
            out[ask] = cdf >= p
        return out

    def step(self, t_s: float, position: Array, sigma_m: Array) -> tuple[Array, Array, Array]:
        """The commands for now.

        Args:
            t_s: time, s.
            position: estimated positions (east, north, up), shape (n, 3), m, world.
            sigma_m: each estimate's standard deviation along its worst horizontal direction,
                shape (n,), m (0 for an estimate without a covariance).

        Returns:
            ``(course rad clockwise from north, depth m, speed through water m/s)``, each shape
            (n,); a run that is done holds its last course at depth 0 and speed 0.
        """
        if self._leg_start_s is None:
            self._leg_start_s = np.full(self.n, float(t_s))
        k = len(self.waypoints)
        rows = np.arange(self.n)
        # a run can end several legs in one tick (the scalar recurses): at most k passes
        for _ in range(k + 1):
            active = ~self.done
            if not active.any():
                break
            wp = self._wp[self.index]
            dist = np.hypot(wp[:, 0] - position[:, 0], wp[:, 1] - position[:, 1])
            hit = active & self.reach_test(dist, wp[:, 3], sigma_m)
            late = active & ~hit & (t_s - self._leg_start_s > self.max_leg_time_s)
            end = hit | late
            if not end.any():
                break
            i = self.index[end]
            self.reached[rows[end], i] = hit[end]
            self.leg_end_s[rows[end], i] = t_s
            self.index = np.where(end, self.index + 1, self.index)
            self._leg_start_s = np.where(end, t_s, self._leg_start_s)
        going = ~self.done
        wp = self._wp[self.index]
        de, dn = wp[:, 0] - position[:, 0], wp[:, 1] - position[:, 1]
        course = np.arctan2(de, dn) % (2 * math.pi)
        course = np.where(course >= 2 * math.pi, 0.0, course)
        self.hold_course_rad = np.where(going, course, self.hold_course_rad)
        depth = np.where(going, wp[:, 2], 0.0)
        speed = np.where(going, self.speed_m_s, 0.0)
        return self.hold_course_rad.copy(), depth, speed
