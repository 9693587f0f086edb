"""Seed 000's three navigations of a batch of passages: dead reckoning, the EKF with USBL fixes,
and the USBL fixes alone (Naus & Nowak 2016, eq. 8, 15-23).

From the same inputs (the measured course, speed and depth change of every tick, and the USBL's
range, azimuth and elevation at the fix ticks):

* **DR**: ``x_k = x_0 + sum_{i < k} f(u_i)`` (eq. 8, 16) through :func:`nav.dead_reckoning.track`;
* **EKF**: eq. 15-23 over all passages at once (:func:`nav.usbl.tracks.ekf_tracks`: F = I, so a
  prediction adds the step's displacement and process noise, both computed for all steps in one
  pass and shared with DR);
* **USBL**: each fix inverted alone (the inverse of eq. 15,
  :meth:`nav.models.UsblMeasurement.invert`).

Plain parameters only: arrays with the run axis first (the EKF's tracks time-major, see
:mod:`nav.usbl.tracks`), the motion and measurement models of :mod:`nav.models`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nav.dead_reckoning import track
from nav.models import CourseSpeedDepthMotion, UsblMeasurement
from nav.usbl.tracks import Tracks, ekf_tracks

Array = NDArray[np.float64]


@dataclass(frozen=True)
class PassageEstimates:
    """The three navigations of n passages of T ticks with k USBL fixes.

    Attributes:
        ekf: the EKF's tracks (time-major states (T + 1, 3, n) and packed covariances
            (T + 1, 6, n), NIS and gate decisions (n, k)).
        dr_m: dead-reckoned positions, shape (n, T + 1, 3), m, world (a view).
        usbl_m: each fix inverted alone, shape (n, k, 3), m, world; meaningless where no fix was
            produced.
    """

    ekf: Tracks
    dr_m: Array
    usbl_m: Array


def passage_ekf(
    x0: Array,
    P0: Array,
    u: Array,
    tick_s: float,
    fix_tick: NDArray[np.intp],
    z: Array,
    z_produced: NDArray[np.bool_],
    motion: CourseSpeedDepthMotion,
    usbl: UsblMeasurement,
    gate_probability: float | None = None,
    steps: tuple[Array, Array] | None = None,
) -> Tracks:
    """The EKF of eq. 15-23 over the passages, batched over runs.

    Args:
        x0: initial estimates, shape (n, 3), m, world.
        P0: initial covariance, shape (3, 3), m^2.
        u: DR inputs ``(course rad, speed m/s, depth change m)`` of each step, shape (n, T, 3).
        tick_s: step duration, s.
        fix_tick: tick of each USBL fix, shape (k,), each in 1..T.
        z: USBL measurements ``(r m, alpha rad, beta rad)``, shape (n, k, 3).
        z_produced: which fixes were produced, shape (n, k).
        motion: the filter's motion model (its sigmas give Q).
        usbl: the filter's USBL model (diagonal R).
        gate_probability: the chi-square gate on the NIS, or None.
        steps: ``motion.increment_and_packed_Q(u, tick_s)`` if already computed.

    Returns:
        The tracks: states (T + 1, 3, n) and packed covariances (T + 1, 6, n), time-major.
    """
    inc, Q = motion.increment_and_packed_Q(u, tick_s) if steps is None else steps
    return ekf_tracks(x0, P0, inc, Q, fix_tick, z, z_produced, usbl, gate_probability)


def navigate_passages(
    x0: Array,
    P0: Array,
    u: Array,
    tick_s: float,
    fix_tick: NDArray[np.intp],
    z: Array,
    z_produced: NDArray[np.bool_],
    motion: CourseSpeedDepthMotion,
    usbl: UsblMeasurement,
    gate_probability: float | None = None,
) -> PassageEstimates:
    """DR, the EKF and the USBL fixes alone over n passages (arguments of :func:`passage_ekf`).

    DR and the EKF's predictions add the same displacements (eq. 8 and 17), computed once.

    Returns:
        The three navigations.
    """
    steps = motion.increment_and_packed_Q(u, tick_s)
    inc = steps[0]  # (T, 3, n)
    # the DR tracks, component-major (3, T + 1, n): every tick's row of n passages contiguous
    dr = track(np.asarray(x0, dtype=float).T, inc.transpose(1, 0, 2))
    tracks = passage_ekf(
        x0, P0, u, tick_s, fix_tick, z, z_produced, motion, usbl, gate_probability, steps
    )
    return PassageEstimates(tracks, dr.transpose(2, 1, 0), usbl.invert(z))
