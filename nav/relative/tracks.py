"""Seed 003's methods over a batch of runs and a whole track at once: GA1 or GA2 at every range with
DR in between (:func:`ga_track`), and the range-only EKF (:func:`ekf_track`), both from one
dead-reckoned track (:func:`nav.relative.dr_track`). The numbers of
:class:`nav.relative.FollowerNavigator` stepped tick by tick (tested), without a time loop between
ranges: ``F = I``, so the DR displacement and the summed eq. 5 increments between two ranges are
differences of the track's cumulative sums.

Arrays carry a leading run axis n; positions are (east, north) in m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.dead_reckoning import DeadReckonedTrack
from nav.ekf import predict
from nav.errors import NavInputError
from nav.relative.adjustment import GaOptions, ga_fix, hdop
from nav.relative.ranging import range_update

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LeaderRanges:
    """The ranges a batch of followers receives, each with the leader's broadcast position.

    Attributes:
        fix_tick: sample of the DR track at which each range arrives, shape (K,), increasing.
        range_m: measured ranges, shape (n, K), m (anything where not ``present``).
        present: whether each range was received, shape (n, K).
        leader_m: the leader's broadcast position with each range, shape (n, K, 2), m.
    """

    fix_tick: NDArray[np.intp]
    range_m: Array
    present: NDArray[np.bool_]
    leader_m: Array

    def __post_init__(self) -> None:
        n_fix = len(self.fix_tick)
        n = self.range_m.shape[0] if np.ndim(self.range_m) == 2 else -1
        shapes = (np.shape(self.range_m), np.shape(self.present), np.shape(self.leader_m))
        if n < 0 or shapes != ((n, n_fix), (n, n_fix), (n, n_fix, 2)):
            raise NavInputError(
                f"LeaderRanges: range_m (n, K), present (n, K) and leader_m (n, K, 2) with K = "
                f"{n_fix} ranges, not shapes {shapes}"
            )


@dataclass(frozen=True)
class RangeEkfOptions:
    """The range-only EKF's sigmas and guard (beyond seed 003).

    Attributes:
        sigma_range_m: the range's standard deviation, m.
        min_range_m: ranges below this are refused (the follower on the leader), m.
        initial_sigma_m: the start's standard deviation per axis, m (0: the start is known).
        leader_sigma_m: standard deviation per axis of the leader's broadcast position, m (0:
            taken as exact, as in the paper; else added to R along the line of sight).
    """

    sigma_range_m: float = 0.1
    min_range_m: float = 0.5
    initial_sigma_m: float = 0.0
    leader_sigma_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sigma_range_m", "min_range_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise NavInputError(f"{name} must be a finite number > 0, not {v!r}")
        for name in ("initial_sigma_m", "leader_sigma_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise NavInputError(f"{name} must be a finite number >= 0, not {v!r}")


@dataclass(frozen=True)
class FixedTrack:
    """A method that uses the ranges, over some runs.

    Attributes:
        position_m: estimates at every tick, shape (n, T + 1, 2), m.
        fix_position_m: the estimate right after each range, shape (n, K, 2), m.
        fix_cov_m2: its stated covariance, shape (n, K, 2, 2), m^2 (GA: ``GaFix.covariance``;
            EKF: the posterior).
        fix_cov_prior_m2: GA's ``GaFix.covariance_prior`` (EKF: the posterior), same shape.
        accepted: whether each range corrected the estimate, shape (n, K).
        hdop: HDOP at each accepted fix, shape (n, K) (0 where not accepted).
        refused_short: ranges refused for being below ``min_range_m``, shape (n, K).
        refused_hdop: GA fixes refused for their HDOP, shape (n, K).
    """

    position_m: Array
    fix_position_m: Array
    fix_cov_m2: Array
    fix_cov_prior_m2: Array
    accepted: NDArray[np.bool_]
    hdop: Array
    refused_short: NDArray[np.bool_]
    refused_hdop: NDArray[np.bool_]


def _assemble(dr: Array, offsets: Array, fix_tick: NDArray[np.intp]) -> Array:
    """``estimate(t) = DR(t) + offset of the last fix at or before t``, shape (n, T + 1, 2)."""
    seg = np.searchsorted(fix_tick, np.arange(dr.shape[1]), side="right")
    return dr + offsets[:, seg]


def _check(dr: DeadReckonedTrack, ranges: LeaderRanges) -> None:
    n, samples = dr.position_m.shape[:2]
    if ranges.range_m.shape[0] != n:
        raise NavInputError(f"ranges of {ranges.range_m.shape[0]} runs for a DR track of {n}")
    tick = np.asarray(ranges.fix_tick)
    if len(tick) and not (0 <= tick[0] and tick[-1] < samples and (np.diff(tick) > 0).all()):
        raise NavInputError(
            f"fix_tick must increase within 0..{samples - 1}, the DR track's samples"
        )


def ga_track(
    method: Literal["ga1", "ga2"],
    dr: DeadReckonedTrack,
    ranges: LeaderRanges,
    options: GaOptions,
    max_hdop: float | None = None,
) -> FixedTrack:
    """GA1 or GA2 at every range, DR in between (seed 003, eq. 2-6), batched over runs.

    The DR segment of each adjustment starts at the last accepted fix (the start before the
    first): with ``options.restart`` its start ``X_F(k)`` is that fix's GA position and its end
    the GA position plus the DR displacement since; without, start and end are the undisturbed
    DR positions (as :class:`nav.relative.FollowerNavigator`). Between fixes the estimate is the
    last GA position plus the DR displacement since it. The covariance of the segment is the sum
    of the eq. 5 increments since the last accepted fix. A range that makes no fix (absent, below
    ``min_range_m``, HDOP above ``max_hdop``) leaves the estimate dead-reckoning on.

    Args:
        method: ``"ga1"`` or ``"ga2"``.
        dr: the DR track with its eq. 5 covariance from the start, samples 0..T.
        ranges: the ranges, at samples of ``dr``.
        options: GA readings and guards.
        max_hdop: fixes with a larger HDOP (eq. 7-8) are refused; ``None`` keeps all.

    Returns:
        The estimates and what each range did.

    Raises:
        NavInputError: on mismatched shapes or an unknown method.
    """
    _check(dr, ranges)
    pos = dr.position_m
    n = pos.shape[0]
    rows = np.arange(n)
    n_fix = len(ranges.fix_tick)
    anchor = pos[:, 0].copy()  # the estimate at the last accepted fix
    prev = np.zeros(n, dtype=np.intp)  # tick of the last accepted fix
    offsets = np.zeros((n, n_fix + 1, 2))
    fix_pos = np.empty((n, n_fix, 2))
    fix_cov = np.empty((n, n_fix, 2, 2))
    fix_prior = np.empty((n, n_fix, 2, 2))
    accepted = np.zeros((n, n_fix), dtype=bool)
    hd = np.zeros((n, n_fix))
    short = np.zeros((n, n_fix), dtype=bool)
    high = np.zeros((n, n_fix), dtype=bool)
    for j, t in enumerate(ranges.fix_tick):
        since = dr.displacement(t, prev)
        cov = dr.covariance_between(t, prev)
        if options.restart:
            start, end = anchor, anchor + since
        else:
            start, end = pos[rows, prev], pos[:, t]
        present = ranges.present[:, j]
        range_m = ranges.range_m[:, j]
        fix = ga_fix(method, start, end, ranges.leader_m[:, j], range_m, cov, options, present)
        ok = fix.valid.copy()
        short[:, j] = present & (range_m < options.min_range_m)
        if max_hdop is not None:
            high[:, j] = ok & ~(fix.hdop <= max_hdop)
            ok &= ~high[:, j]
        est = anchor + since
        fix_pos[:, j] = np.where(ok[:, None], fix.position, est)
        fix_cov[:, j] = fix.covariance
        fix_prior[:, j] = fix.covariance_prior
        accepted[:, j] = ok
        hd[:, j] = np.where(ok, fix.hdop, 0.0)
        anchor = np.where(ok[:, None], fix.position, anchor)
        prev = np.where(ok, t, prev)
        offsets[:, j + 1] = anchor - pos[rows, prev]
    return FixedTrack(
        _assemble(pos, offsets, ranges.fix_tick),
        fix_pos,
        fix_cov,
        fix_prior,
        accepted,
        hd,
        short,
        high,
    )


def ekf_track(dr: DeadReckonedTrack, ranges: LeaderRanges, options: RangeEkfOptions) -> FixedTrack:
    """The range-only EKF (beyond the paper), batched over runs.

    Predicts with eq. 1 and Q = eq. 5 (:func:`nav.ekf.predict` with ``F = I``, ``f(x)`` = x plus
    the DR displacement since the previous range and Q the eq. 5 increments summed over it) and
    updates with each range to the broadcast leader position
    (:func:`nav.relative.range_update`, i.e. :func:`nav.ekf.update`). Ranges below
    ``min_range_m`` are refused, as by :class:`nav.relative.FollowerNavigator`. The HDOP of an
    accepted update is eq. 7-8 with the estimate after the previous range as the segment's start.

    Args:
        dr: the DR track with its eq. 5 covariance from the start, samples 0..T.
        ranges: the ranges, at samples of ``dr``.
        options: sigmas and guard.

    Returns:
        The estimates and what each range did (``fix_cov_prior_m2`` is the posterior too;
        ``refused_hdop`` is all False).

    Raises:
        NavInputError: on mismatched shapes.
    """
    _check(dr, ranges)
    pos = dr.position_m
    n = pos.shape[0]
    n_fix = len(ranges.fix_tick)
    x = pos[:, 0].copy()
    x_last = x  # the estimate after the previous range: the start of the HDOP's DR segment
    P = np.broadcast_to(np.eye(2) * options.initial_sigma_m**2, (n, 2, 2)).copy()
    F = np.broadcast_to(np.eye(2), (n, 2, 2))
    prev = 0
    offsets = np.zeros((n, n_fix + 1, 2))
    fix_pos = np.empty((n, n_fix, 2))
    fix_cov = np.empty((n, n_fix, 2, 2))
    accepted = np.zeros((n, n_fix), dtype=bool)
    hd = np.zeros((n, n_fix))
    short = np.zeros((n, n_fix), dtype=bool)
    leader_cov = None
    if options.leader_sigma_m > 0:
        leader_cov = np.broadcast_to(np.eye(2) * options.leader_sigma_m**2, (n, 2, 2))
    for j, t in enumerate(ranges.fix_tick):
        # F = I: x- = x + DR displacement, P- = P + summed eq. 5 increments (eq. 17-18)
        x_prior, P_prior = predict(
            x, P, x + dr.displacement(t, prev), F, dr.covariance_between(t, prev)
        )
        present = ranges.present[:, j]
        short[:, j] = present & (ranges.range_m[:, j] < options.min_range_m)
        use = present & ~short[:, j]
        x, P, info = range_update(
            x_prior,
            P_prior,
            ranges.leader_m[:, j],
            ranges.range_m[:, j],
            options.sigma_range_m,
            leader_cov=leader_cov,
            present=use,
        )
        accepted[:, j] = info.applied
        hd[:, j] = np.where(info.applied, hdop(x_last, x, ranges.leader_m[:, j]), 0.0)
        x_last = x
        fix_pos[:, j], fix_cov[:, j] = x, P
        prev = t
        offsets[:, j + 1] = x - pos[:, t]
    return FixedTrack(
        _assemble(pos, offsets, ranges.fix_tick),
        fix_pos,
        fix_cov,
        fix_cov,
        accepted,
        hd,
        short,
        np.zeros((n, n_fix), dtype=bool),
    )
