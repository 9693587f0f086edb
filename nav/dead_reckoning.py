"""Dead reckoning: a position advanced by the displacement of each step (seed 000 eq. 8-10 and 16,
seed 001 eq. 30-33), the one implementation every DR track uses.

The displacement of a step comes from a motion model (seed 000: course, speed and depth change,
:meth:`nav.models.CourseSpeedDepthMotion.increment`) or from a velocity times the step (seed 001's
corrected velocity, :func:`nav.correction.dr_velocity`). Two forms:

* :func:`track`, batched over runs and steps: the start plus the cumulative sum of the
  displacements (``F = I``, so no time loop), also used for the covariance (eq. 9-10: ``P0`` plus
  the cumulative sum of the per-step ``Q``); :func:`dead_reckon` is seed 000's DR with it;
* :class:`DeadReckoning`, online, one step at a time (the navigator's DR, seed 001's DRNS).

The two sum in different orders (the cumulative sum adds the displacements before the start, the
online form adds each one to the position), so they agree to rounding, not bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.models import CourseSpeedDepthMotion

Array = NDArray[np.float64]


def track(start: ArrayLike, increments: ArrayLike) -> Array:
    """Dead-reckoned tracks of a batch of runs: ``x_k = x_0 + sum_{i < k} dx_i``.

    Args:
        start: positions at step 0, shape (n, *s) (e.g. (n, 3) m, world; or covariances (n, 3, 3)).
        increments: the displacement of each step, shape (n, T, *s); step k moves from sample k
            to sample k + 1.

    Returns:
        Samples 0..T, shape (n, T + 1, *s).
    """
    s = np.asarray(start, dtype=float)
    inc = np.asarray(increments, dtype=float)
    out = np.empty((inc.shape[0], inc.shape[1] + 1, *inc.shape[2:]))
    out[:, 0] = s
    out[:, 1:] = s[:, None] + np.cumsum(inc, axis=1)
    return out


def dead_reckon(
    x0: Array,
    u: Array,
    dt_s: float,
    motion: CourseSpeedDepthMotion,
    P0: Array | None = None,
) -> tuple[Array, Array | None]:
    """Seed 000's dead-reckoned tracks of a batch of runs, with their covariance.

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
    x = track(x0, motion.increment(u, dt_s))
    if P0 is None:
        return x, None
    n = x.shape[0]
    return x, track(np.broadcast_to(P0, (n, 3, 3)), motion.Q(u, dt_s))


class DeadReckoning:
    """One dead-reckoned position, advanced one step at a time (the online form of :func:`track`).

    Args:
        position: the start, shape (d,), e.g. (east, north[, up]), m, world.
    """

    def __init__(self, position: ArrayLike):
        self.position = np.array(position, dtype=float)

    def advance(self, increment: Array) -> None:
        """Add the displacement of one step, shape (d,), m."""
        self.position = self.position + increment

    def reset(self, position: ArrayLike) -> None:
        """Restart from a position, shape (d,) (e.g. at a fix)."""
        self.position = np.array(position, dtype=float)
