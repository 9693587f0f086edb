"""Running seed 003's tests: measure a block of runs (:mod:`bauv_sim.kinematic.seed003`), position
them four ways with :mod:`nav.relative` (DR, GA1, GA2, the range EKF) under each reading the
scenario asks for, and reduce them to the accumulators the report merges
(:class:`Paper003Block`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bauv_sim.kinematic.seed003 import Seed003Measurements, SquareTruth, measure
from nav.dead_reckoning import DeadReckonedTrack
from nav.relative import (
    FixedTrack,
    LeaderRanges,
    consistency_sums,
    distance_sums,
    distances,
    dr_track,
    ekf_track,
    ga_track,
    hdop_after_step,
    longest_gaps,
)
from nav.relative.metrics import N_CONSISTENCY_SUMS, N_DISTANCE_SUMS
from tasks.core import store
from tasks.paper003.scenario import (
    HdopMapConfig,
    Paper003Scenario,
    Reading,
    readings,
    scenario_reading,
    truth_of,
)

Array = NDArray[np.float64]

METHODS = ("DR", "GA1", "GA2", "EKF")
"""Positioning methods, in table order (EKF is beyond the paper)."""
FIXED = ("GA1", "GA2", "EKF")
"""The methods that use the ranges."""
CONSISTENCY_ROWS = ("GA1", "GA2", "EKF", "GA1 prior", "GA2 prior")
"""Stated accuracies compared with the actual error: GA's ``GaFix.covariance`` (with the
a-posteriori variance factor delta_0^2, redundancy 1), the EKF's posterior, and GA's
``covariance_prior`` ``(A^T P A)^-1`` (without the factor)."""


def ranges_of(meas: Seed003Measurements) -> LeaderRanges:
    """The ranges of the measurements, as :mod:`nav.relative` takes them."""
    return LeaderRanges(meas.fix_tick, meas.range_m, meas.range_produced, meas.leader_m)


def dead_reckon(
    scn: Paper003Scenario, meas: Seed003Measurements, truth: SquareTruth
) -> DeadReckonedTrack:
    """DR from the measured course and speed (eq. 1) from the known start, with the eq. 5
    covariance summed along the run (:func:`nav.relative.dr_track`)."""
    nc = scn.navigation
    return dr_track(
        meas.course_rad,
        meas.speed_m_s,
        truth.follower_m[0],
        scn.path.tick_s,
        math.radians(nc.sigma_course_deg),
        nc.sigma_speed_m_s,
    )


@dataclass(frozen=True)
class Samples:
    """Every method's track for some runs under one reading.

    Attributes:
        runs: run indices.
        truth: the reference motion.
        meas: the measurements.
        tracks: method -> estimates, shape (n, T + 1, 2), m.
        fixed: method (GA1, GA2, EKF) -> its fixes.
    """

    runs: tuple[int, ...]
    truth: SquareTruth
    meas: Seed003Measurements
    tracks: dict[str, Array]
    fixed: dict[str, FixedTrack]

    def distances(self) -> dict[str, Array]:
        """Distance to F's reference position, method -> shape (n, T + 1), m."""
        ref = self.truth.follower_m
        return {k: distances(v, ref) for k, v in self.tracks.items()}


def simulate(
    scn: Paper003Scenario,
    seed: int,
    runs: tuple[int, ...],
    reading: Reading | None = None,
    truth: SquareTruth | None = None,
    meas: Seed003Measurements | None = None,
    dr: DeadReckonedTrack | None = None,
) -> Samples:
    """Measure and position some runs under one reading (default: the scenario's).

    ``truth``, ``meas`` and ``dr`` may be passed in when they are shared by several readings of
    the same geometry (they depend on ``seed``, ``runs`` and the geometry only).
    """
    rd = reading or scenario_reading(scn)
    truth = truth or truth_of(scn, rd.geometry)
    meas = meas or measure(scn.sensors, truth, seed, runs)
    nc = scn.navigation
    dr = dr or dead_reckon(scn, meas, truth)
    opt = nc.ga_options(rd.jacobian, rd.restart)
    ranges = ranges_of(meas)
    fixed = {
        "GA1": ga_track("ga1", dr, ranges, opt, nc.max_hdop),
        "GA2": ga_track("ga2", dr, ranges, opt, nc.max_hdop),
        "EKF": ekf_track(dr, ranges, nc.ekf_options()),
    }
    tracks = {"DR": dr.position_m, **{k: v.position_m for k, v in fixed.items()}}
    return Samples(tuple(runs), truth, meas, tracks, fixed)


def hdop_figure2(cfg: HdopMapConfig, points_east_m: Array, points_north_m: Array) -> Array:
    """HDOP of the Figure 2 set-up at follower positions around the leader at (0, 0).

    F has moved ``step_m`` on ``course_deg`` since its DR start and receives the range to L
    (:func:`nav.relative.hdop_after_step`).

    Args:
        points_east_m, points_north_m: follower positions, any equal shapes, m.

    Returns:
        HDOP, the same shape.
    """
    p = np.stack([np.ravel(points_east_m), np.ravel(points_north_m)], axis=1)
    h = hdop_after_step(p, np.zeros_like(p), math.radians(cfg.course_deg), cfg.step_m)
    return h.reshape(np.shape(points_east_m))


# ----------------------------------------------------------------------------------------------
# Block reduction

N_RUN_STATS = N_DISTANCE_SUMS  # count, sum, sum of squares, max of the distance over ticks 1..T
N_CONS = N_CONSISTENCY_SUMS  # fixes with a finite stated covariance, NEES, trace, squared error
N_FIX = 6  # ranges expected, received, accepted, refused short, refused HDOP, HDOP sum (accepted)


@store.plain_data("paper003.Paper003Block")
@dataclass
class Paper003Block:
    """What a block of runs contributes to the report (accumulators, no full tracks but a few).

    Per-run arrays keep the report's sums in run order whatever the block size, so the pooled
    statistics are bit-identical for any block split and worker count.

    Attributes:
        runs: run indices of the block.
        labels: reading labels, in :func:`readings` order (R).
        per_run: shape (n, R, 4 methods, 4): count, sum, sum of squares and max of the distance
            to the reference over ticks 1..T, m.
        consistency: shape (n, R, 5 (:data:`CONSISTENCY_ROWS`), 4): accepted fixes with a
            finite stated covariance, sum of their NEES, sum of the stated covariance's trace
            (m^2) and of the squared actual error (m^2).
        fixes: shape (n, R, 3, 6): ranges expected, received, accepted, refused as too short,
            refused for HDOP, sum of the accepted fixes' HDOP.
        longest_gap_s: longest time without an accepted fix, shape (n, R, 3), s.
        hdop_median: median HDOP of the accepted fixes per run and method, shape (n, 3) (default
            reading; NaN where none was accepted).
        routes: run -> method (and ``"reference"``) -> path points (float32), runs below
            ``report.routes_max`` (default reading).
        single: for ``report.single_sample``: ``"distance/M"`` (T + 1,) m and ``"track/M"``
            (T + 1, 2) m of each method M, and ``"fix/M"`` (K, 2) m, ``"accepted/M"`` (K,),
            ``"hdop/M"`` (K,) of GA1, GA2, EKF: the recording and the run data are written from
            these, not simulated again.
    """

    runs: tuple[int, ...]
    labels: tuple[str, ...]
    per_run: Array
    consistency: Array
    fixes: Array
    longest_gap_s: Array
    hdop_median: Array
    routes: dict[int, dict[str, NDArray[np.float32]]] = field(default_factory=dict)
    single: dict[int, dict[str, NDArray]] = field(default_factory=dict)


def _consistency(s: Samples, row: str) -> Array:
    name, _, prior = row.partition(" ")
    f = s.fixed[name]
    ref = s.truth.follower_m[s.meas.fix_tick]
    C = f.fix_cov_prior_m2 if prior else f.fix_cov_m2
    return consistency_sums(f.fix_position_m - ref, C, f.accepted)


def _fix_stats(s: Samples, name: str, t_end_s: float) -> tuple[Array, Array]:
    f = s.fixed[name]
    m = s.meas
    n_fix = len(m.fix_tick)
    stats = np.stack(
        [
            np.full(len(s.runs), n_fix, dtype=float),
            m.range_produced.sum(1),
            f.accepted.sum(1),
            f.refused_short.sum(1),
            f.refused_hdop.sum(1),
            f.hdop.sum(1),
        ],
        axis=1,
    ).astype(float)
    return stats, longest_gaps(s.truth.t_s[m.fix_tick], f.accepted, t_end_s)


def reduce_block(scn: Paper003Scenario, seed: int, runs: tuple[int, ...]) -> Paper003Block:
    """Simulate a block of runs under every reading it computes and reduce it to accumulators."""
    rds = readings(scn)
    n, R = len(runs), len(rds)
    per_run = np.empty((n, R, len(METHODS), N_RUN_STATS))
    cons = np.empty((n, R, len(CONSISTENCY_ROWS), N_CONS))
    fixes = np.empty((n, R, len(FIXED), N_FIX))
    gaps = np.empty((n, R, len(FIXED)))
    shared: dict[tuple[str, str], tuple[SquareTruth, Seed003Measurements, DeadReckonedTrack]] = {}
    block: Paper003Block | None = None
    t_end = scn.path.n_legs * scn.path.leg_s
    for r, rd in enumerate(rds):
        if rd.geometry not in shared:
            truth = truth_of(scn, rd.geometry)
            meas = measure(scn.sensors, truth, seed, runs)
            dr = dead_reckon(scn, meas, truth)
            shared[rd.geometry] = (truth, meas, dr)
        s = simulate(scn, seed, runs, rd, *shared[rd.geometry])
        d = s.distances()
        for m, name in enumerate(METHODS):
            if not np.isfinite(d[name]).all():
                raise ValueError(f"{name}: a non-finite estimate in runs {runs[0]}-{runs[-1]}")
            per_run[:, r, m] = distance_sums(d[name])
        for m, row in enumerate(CONSISTENCY_ROWS):
            cons[:, r, m] = _consistency(s, row)
        for m, name in enumerate(FIXED):
            fixes[:, r, m], gaps[:, r, m] = _fix_stats(s, name, t_end)
        if r == 0:
            block = _default_parts(scn, s, d)
    assert block is not None
    block.runs = tuple(runs)
    block.labels = tuple(rd.label for rd in rds)
    block.per_run, block.consistency, block.fixes, block.longest_gap_s = per_run, cons, fixes, gaps
    return block


def _default_parts(scn: Paper003Scenario, s: Samples, d: dict[str, Array]) -> Paper003Block:
    every = max(1, round(scn.report.routes_every_s / scn.path.tick_s))
    med = np.full((len(s.runs), len(FIXED)), np.nan)
    for m, name in enumerate(FIXED):
        f = s.fixed[name]
        for i in range(len(s.runs)):
            if f.accepted[i].any():
                med[i, m] = float(np.median(f.hdop[i][f.accepted[i]]))
    block = Paper003Block(
        runs=s.runs,
        labels=(),
        per_run=np.empty(0),
        consistency=np.empty(0),
        fixes=np.empty(0),
        longest_gap_s=np.empty(0),
        hdop_median=med,
    )
    for i, run in enumerate(s.runs):
        if run < scn.report.routes_max:
            block.routes[run] = {k: v[i, ::every].astype(np.float32) for k, v in s.tracks.items()}
        if run == scn.report.single_sample:
            one = {f"distance/{k}": v[i] for k, v in d.items()}
            one.update({f"track/{k}": v[i] for k, v in s.tracks.items()})
            for k, f in s.fixed.items():
                one[f"fix/{k}"] = f.fix_position_m[i]
                one[f"accepted/{k}"] = f.accepted[i]
                one[f"hdop/{k}"] = f.hdop[i]
            block.single[run] = one
    return block
