"""Dead reckoning from course, speed and depth change (seed 000 eq. 8-10 and 16).

For the additive models of seed 000 (``F = I``) the whole track is the initial position plus the
cumulative sum of the increments, and the covariance is ``P0`` plus the cumulative sum of the
per-step ``Q`` (eq. 9-10), so a batch of tracks is computed without a time loop.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nav.models import CourseSpeedDepthMotion

Array = NDArray[np.float64]


def dead_reckon(
    x0: Array,
    u: Array,
    dt_s: float,
    motion: CourseSpeedDepthMotion,
    P0: Array | None = None,
) -> tuple[Array, Array | None]:
    """Dead-reckoned tracks of a batch of runs.

    Args:
        x0: initial positions, shape (n, 3), m, world.
        u: inputs ``(course rad, speed m/s, depth change m)`` of each step, shape (n, T, 3);
            step k moves from tick k to tick k + 1.
        dt_s: step duration, s.
        motion: the motion model (its sigmas give the covariance).
        P0: initial covariance, shape (n, 3, 3) or (3, 3), or ``None`` to skip the covariance.

    Returns:
        ``(x, P)``: positions at ticks 0..T, shape (n, T + 1, 3), and covariances, shape
        (n, T + 1, 3, 3) (``None`` when ``P0`` is ``None``).
    """
    inc = motion.increment(u, dt_s)
    n, T, _ = inc.shape
    x = np.empty((n, T + 1, 3))
    x[:, 0] = x0
    x[:, 1:] = x0[:, None, :] + np.cumsum(inc, axis=1)
    if P0 is None:
        return x, None
    P = np.empty((n, T + 1, 3, 3))
    P[:, 0] = P0
    P[:, 1:] = np.broadcast_to(P0, (n, 3, 3))[:, None] + np.cumsum(motion.Q(u, dt_s), axis=1)
    return x, P
