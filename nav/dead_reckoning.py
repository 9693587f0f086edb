"""Dead reckoning: a position advanced by the displacement of each step (seed 000 eq. 8-10 and 16,
seed 001 eq. 30-33), the one implementation every DR track uses.

The displacement of a step comes from a motion model (seed 000: course, speed and depth change,
:meth:`nav.models.CourseSpeedDepthMotion.increment`) or from a velocity times the step (seed 001's
corrected velocity, :func:`nav.surfacing.drns.dr_velocity`). Two forms:

* :func:`track`, batched over runs and steps: the start plus the cumulative sum of the
  displacements (``F = I``, so no time loop), also used for the covariance (eq. 9-10: ``P0`` plus
  the cumulative sum of the per-step ``Q``); :func:`dead_reckon` is seed 000's DR with it and
  :func:`track_with_covariance` the general form (seed 003's DR with its eq. 5 covariance,
  :func:`nav.relative.dr_track`), returning a :class:`DeadReckonedTrack`;
* :func:`step`, one step of a batch (``x + dx``), and :class:`DeadReckoning`, online, one step at
  a time, optionally with the covariance accumulated beside the position (the navigator's DR,
  seed 001's DRNS, seed 003's follower).

The two sum in different orders (the cumulative sum adds the displacements before the start, the
online form adds each one to the position), so they agree to rounding, not bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError
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
    np.cumsum(inc, axis=1, out=out[:, 1:])  # in place: no temporary of the track's size
    out[:, 1:] += s[:, None]
    return out


def step(position: ArrayLike, increment: ArrayLike) -> Array:
    """One dead-reckoning step of a batch: ``x_{k+1} = x_k + dx_k``.

    Args:
        position: positions at step k, shape (n, d) (or any shape), m.
        increment: the step's displacement, the same shape (or broadcastable), m.

    Returns:
        Positions at step k + 1, shape of the broadcast, m.
    """
    return np.asarray(position, dtype=float) + increment


@dataclass(frozen=True)
class DeadReckonedTrack:
    """Dead-reckoned tracks of a batch of runs with the covariance accumulated along them.

    Attributes:
        position_m: positions at samples 0..T, shape (n, T + 1, d), m.
        cov_m2: the start covariance plus the per-step covariances summed to each sample, shape
            (n, T + 1, d, d), m^2 (the covariance accumulated between samples j and k is
            ``cov_m2[:, k] - cov_m2[:, j]``, :meth:`covariance_between`).
    """

    position_m: Array
    cov_m2: Array

    def displacement(self, k: int | NDArray[np.intp], j: int | NDArray[np.intp]) -> Array:
        """DR displacement from sample ``j`` to sample ``k`` of every run, shape (n, d), m.

        Args:
            k, j: samples, ints or per-run arrays of shape (n,).
        """
        rows = np.arange(self.position_m.shape[0])
        return self.position_m[rows, k] - self.position_m[rows, j]

    def covariance_between(self, k: int | NDArray[np.intp], j: int | NDArray[np.intp]) -> Array:
        """Covariance accumulated from sample ``j`` to sample ``k``, shape (n, d, d), m^2."""
        rows = np.arange(self.cov_m2.shape[0])
        return self.cov_m2[rows, k] - self.cov_m2[rows, j]


def track_with_covariance(
    start: ArrayLike,
    increments: ArrayLike,
    increment_cov: ArrayLike,
    start_cov: ArrayLike | None = None,
) -> DeadReckonedTrack:
    """Dead-reckoned tracks of a batch of runs and their covariance (:func:`track` of both).

    ``x_k = x_0 + sum_{i < k} dx_i`` and ``P_k = P_0 + sum_{i < k} Q_i`` (``F = I``: seed 000 eq.
    9-10, seed 003 eq. 1 and 5).

    Args:
        start: positions at sample 0, shape (n, d), m.
        increments: the displacement of each step, shape (n, T, d), m.
        increment_cov: the covariance of each step's displacement, shape (n, T, d, d), m^2.
        start_cov: covariance at sample 0, shape (n, d, d) or (d, d), m^2 (default zero: the
            start is known).

    Returns:
        The tracks, samples 0..T.

    Raises:
        NavInputError: if the shapes do not match.
    """
    inc = np.asarray(increments, dtype=float)
    q = np.asarray(increment_cov, dtype=float)
    if inc.ndim != 3 or q.shape != (*inc.shape, inc.shape[-1]):
        raise NavInputError(
            f"increments (n, T, d) and increment_cov (n, T, d, d) must match, not shapes "
            f"{inc.shape} and {q.shape}"
        )
    n, _, d = inc.shape
    s = np.broadcast_to(np.asarray(start, dtype=float), (n, d))
    P0 = np.zeros((n, d, d)) if start_cov is None else np.asarray(start_cov, dtype=float)
    return DeadReckonedTrack(track(s, inc), track(np.broadcast_to(P0, (n, d, d)), q))


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
    """One dead-reckoned position, advanced one step at a time (the online form of :func:`track`),
    optionally with the covariance accumulated beside it (the online form of
    :func:`track_with_covariance`).

    Args:
        position: the start, shape (d,), e.g. (east, north[, up]), m, world.
        covariance: the start's covariance, shape (d, d), m^2, or ``None`` to carry none.

    Attributes:
        position: the current position, shape (d,), m.
        covariance: its accumulated covariance, shape (d, d), m^2, or ``None``.
    """

    def __init__(self, position: ArrayLike, covariance: ArrayLike | None = None):
        self.position = np.array(position, dtype=float)
        self.covariance = None if covariance is None else np.array(covariance, dtype=float)

    def advance(self, increment: Array, increment_cov: Array | None = None) -> None:
        """Add the displacement of one step, shape (d,), m, and its covariance, shape (d, d), m^2.

        Raises:
            NavInputError: if ``increment_cov`` is given to a track that carries no covariance,
                or not given to one that does.
        """
        if (increment_cov is None) != (self.covariance is None):
            raise NavInputError(
                "increment_cov must be given exactly when the track carries a covariance"
            )
        self.position = self.position + increment
        if self.covariance is not None:
            self.covariance = self.covariance + increment_cov

    def reset(self, position: ArrayLike, covariance: ArrayLike | None = None) -> None:
        """Restart from a position, shape (d,) (e.g. at a fix), with its covariance, shape (d, d)
        (``None``: the track carries no covariance from now on)."""
        self.position = np.array(position, dtype=float)
        self.covariance = None if covariance is None else np.array(covariance, dtype=float)
