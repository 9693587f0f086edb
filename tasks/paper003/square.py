"""Seed 003 (Naus & Piskur 2022): a follower positioned relative to the swarm leader on a square.

Registers ``paper-003/test-1``, ``test-2`` and ``test-3`` (section 3): the leader L flies one
square (120 s a side at 1 m/s, first course 45 deg) and the follower F keeps 10 m at a relative
bearing of 90 deg (Tests 1, 3) or 180 deg (Test 2). F measures course and speed at 10 Hz with the
errors of a poorly calibrated (Tests 1-2) or a calibrated (Test 3) INS and log, and receives the
range to L with L's position every 5 s. Each run is positioned four ways on the same draws:

* **DR**: dead reckoning from the measured course and speed (eq. 1);
* **GA1**, **GA2**: at every range, the geodetic adjustment on the circle of the range (eq. 2-4)
  weighted by the DR covariance accumulated since the last fix (eq. 5-6), with DR going on from
  the fix in between (:func:`nav.relative.ga_fix`);
* **EKF** (beyond the paper): the range-only EKF on the same ranges, predicting with eq. 1 and
  Q = eq. 5 (:func:`nav.relative.range_update`).

The tables are the paper's (Tables 1-3): maximum, arithmetic mean and standard deviation of the
distance between F's reference position and each estimate, for a single test sample (run
``report.single_sample``) and for all runs. The "100 test samples" columns pool every 10 Hz sample
of every run (the seed's reading notes: with pooling the DR rows come out within a few percent;
with the mean curve they do not). Statistics run over ticks 1..T (t = 0.1 .. 480 s; at t = 0 every
estimate starts on the reference).

Readings the paper leaves open are scenario options (``formation.*`` in
:mod:`bauv_sim.kinematic.seed003`, ``navigation.jacobian`` and ``navigation.restart`` as
:class:`nav.relative.GaOptions`); ``report.readings = "all"`` computes GA1 and GA2 for every
combination of them on the same draws and reports each beside the paper (no single reading
reproduces every GA cell; nothing is tuned to the tables). The square turns right by default: the
DR rows, which do not depend on any GA reading, come out within 2 % of the paper that way and 30-45
% off turning left.

Bad geometry and data degrade to DR with a warning in the report and ``metrics.json``: a range
below ``navigation.min_range_m`` (zero range), no range (``sensors.modem.max_range_m``,
``sensors.modem.dropout_windows_s``, the vocabulary's dropout probability), or a fix whose HDOP
exceeds ``navigation.max_hdop``; GA and the EKF then dead-reckon on from their last fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import product
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.config import Config, load_config
from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.seed003 import (
    FormationConfig,
    Seed003Measurements,
    Seed003Sensors,
    SquarePathConfig,
    SquareTruth,
    measure,
    square_truth,
)
from bauv_sim.sensors.base import check_multiple, periodic_indices
from nav.metrics import nees_band
from nav.relative import GaOptions, dr_increment_covariance, dr_step, ga_fix, hdop, range_update
from tasks.core import export, figures, store
from tasks.core.recording import COLORS, Recording
from tasks.core.registry import Experiment, ReportContext, ReportSummary, block_by_work, register
from tasks.core.report import Table, write_metrics, write_tables

Array = NDArray[np.float64]

METHODS = ("DR", "GA1", "GA2", "EKF")
"""Positioning methods, in table order (EKF is beyond the paper)."""
FIXED = ("GA1", "GA2", "EKF")
"""The methods that use the ranges."""
CONSISTENCY_ROWS = ("GA1", "GA2", "EKF", "GA1 prior", "GA2 prior")
"""Stated accuracies compared with the actual error: GA's ``GaFix.covariance`` (with the
a-posteriori variance factor delta_0^2, redundancy 1), the EKF's posterior, and GA's
``covariance_prior`` ``(A^T P A)^-1`` (without the factor)."""
STATS = ("max", "mean", "std")
REC_COLORS = {
    "DR": COLORS["dr"],
    "GA1": (44, 160, 44),
    "GA2": (148, 103, 189),
    "EKF": COLORS["ekf"],
}


# The paper's Tables 1-3: method -> (max, mean, std) for (single sample, 100 samples), m.
PaperCells = dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]]
PAPER_TABLES: dict[str, tuple[str, PaperCells]] = {
    "test-1": (
        "Table 1",
        {
            "DR": ((22.31, 14.26, 6.44), (23.70, 14.13, 6.34)),
            "GA1": ((8.39, 3.42, 2.39), (8.57, 3.48, 2.41)),
            "GA2": ((15.36, 7.90, 3.68), (15.36, 7.70, 3.63)),
        },
    ),
    "test-2": (
        "Table 2",
        {
            "DR": ((22.31, 14.25, 6.43), (23.71, 14.13, 6.34)),
            "GA1": ((9.98, 5.78, 3.43), (10.77, 6.57, 3.81)),
            "GA2": ((10.81, 8.12, 2.99), (10.89, 8.20, 2.89)),
        },
    ),
    "test-3": (
        "Table 3",
        {
            "DR": ((2.52, 1.56, 0.72), (3.79, 1.46, 0.78)),
            "GA1": ((0.91, 0.39, 0.21), (2.55, 0.73, 0.50)),
            "GA2": ((1.6, 0.69, 0.40), (3.19, 0.77, 0.52)),
        },
    ),
}


# ----------------------------------------------------------------------------------------------
# Scenario


class NavigationConfig(Config):
    """What the follower's navigation assumes and how GA reads the paper (seed 003, eq. 2-6)."""

    sigma_course_deg: float = Field(
        2.0, gt=0, description="sigma_C of eq. 5, deg (the VN-100 documentation's 2 deg)"
    )
    sigma_speed_m_s: float = Field(
        0.3, gt=0, description="sigma_S of eq. 5, m/s (the Alize documentation's 0.3 m/s)"
    )
    sigma_range_m: float = Field(
        0.1, gt=0, description="delta_Dh of the weight matrix P and the EKF's range sigma, m"
    )
    jacobian: Literal["printed", "true"] = Field(
        "printed",
        description="A of eq. 2: the rows as printed (geodetic column order) or the true "
        "Jacobian (nav.relative)",
    )
    restart: bool = Field(
        True, description="DR restarts from the GA position after each fix (else runs on)"
    )
    min_range_m: float = Field(
        0.5, gt=0, description="ranges below this make no fix (GA and EKF dead-reckon on), m"
    )
    min_step_m: float = Field(
        1e-3, gt=0, description="below this DR displacement the bearing row gets weight 0, m"
    )
    max_hdop: float | None = Field(
        None, gt=0, description="GA fixes with a larger HDOP are refused (none: keep all)"
    )
    leader_sigma_m: float = Field(
        0.0,
        ge=0,
        description="the EKF's sigma per axis of the leader's broadcast position, m (0: taken "
        "as exact, as in the paper; set it with sensors.modem.broadcast)",
    )
    ekf_initial_sigma_m: float = Field(
        0.0, ge=0, description="EKF's initial sigma per axis, m (0: the start is known)"
    )

    def ga_options(self, jacobian: str | None = None, restart: bool | None = None) -> GaOptions:
        """The :class:`nav.relative.GaOptions` of this configuration (or of another reading)."""
        return GaOptions(
            jacobian=self.jacobian if jacobian is None else jacobian,  # type: ignore[arg-type]
            restart=self.restart if restart is None else restart,
            sigma_range_m=self.sigma_range_m,
            min_range_m=self.min_range_m,
            min_step_m=self.min_step_m,
        )


class HdopMapConfig(Config):
    """Figure 2: HDOP around the leader for F moving at course 90 deg with D_r = 10 m."""

    half_width_m: float = Field(30.0, gt=0, description="the map spans +-this around L, m")
    cells: int = Field(121, ge=11, le=801, description="grid points per axis")
    course_deg: float = Field(90.0, ge=0, lt=360, description="F's course, deg")
    step_m: float = Field(10.0, gt=0, description="D_r: F's DR displacement since its start, m")


class ReportConfig(Config):
    """What the report computes, draws and writes."""

    readings: Literal["default", "all"] = Field(
        "default",
        description="default: the scenario's reading only; all: GA1/GA2 (and DR, EKF) for every "
        "combination of formation.offset, formation.bearing_of, navigation.jacobian and "
        "navigation.restart on the same draws",
    )
    single_sample: int = Field(0, ge=0, description="run of the single-test-sample columns")
    routes_max: int = Field(100, ge=0, le=1000, description="runs drawn in the 100-sample paths")
    routes_every_s: float = Field(1.0, gt=0, description="spacing of the drawn path points, s")
    figures: bool = True
    recording: bool = True
    run_data: bool = Field(True, description="write Parquet run data (single sample, per run)")
    hdop_map: HdopMapConfig = Field(default_factory=HdopMapConfig)
    warn_hdop: float = Field(
        3.0,
        gt=0,
        description="warn when the median HDOP of the accepted fixes exceeds this (abeam ~1.4; "
        "on the course line ~D_r, 5 in 5 s)",
    )
    consistency_probability: float = Field(0.95, gt=0, lt=1)


BLOCK_RUN_TICKS = 2_400_000
"""The work of a default block, run-ticks (see :class:`RunnerConfig`)."""


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int | None = Field(
        None,
        ge=1,
        le=100_000,
        description=(
            "runs per block; default: sized by work, as many runs as make "
            f"{BLOCK_RUN_TICKS:,} run-ticks (500 runs of the paper's 4,800 ticks at 10 Hz): "
            "1.5x faster than blocks of 100, about 0.5 GB per block"
        ),
    )


def block_runs(scn: Paper003Scenario) -> int:
    """Runs per block: ``runner.block_size``, or by work (:data:`BLOCK_RUN_TICKS`)."""
    return block_by_work(scn.runner.block_size, scn.path.n_ticks - 1, BLOCK_RUN_TICKS)


class Paper003Scenario(Config):
    """Scenario of seed 003's tests (defaults: Test 1)."""

    path: SquarePathConfig = Field(default_factory=SquarePathConfig)
    formation: FormationConfig = Field(default_factory=FormationConfig)
    sensors: Seed003Sensors = Field(default_factory=Seed003Sensors)
    navigation: NavigationConfig = Field(default_factory=NavigationConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)


@dataclass(frozen=True)
class Reading:
    """One combination of the readings the paper leaves open."""

    offset: str
    bearing_of: str
    jacobian: str
    restart: bool

    @property
    def label(self) -> str:
        """Short label, e.g. ``world/F-from-L/printed/restart``."""
        b = "F-from-L" if self.bearing_of == "follower_from_leader" else "L-from-F"
        r = "restart" if self.restart else "no-restart"
        return f"{self.offset}/{b}/{self.jacobian}/{r}"

    @property
    def geometry(self) -> tuple[str, str]:
        """The part of the reading that changes the truth."""
        return (self.offset, self.bearing_of)


def scenario_reading(scn: Paper003Scenario) -> Reading:
    """The reading of the scenario itself."""
    f, n = scn.formation, scn.navigation
    return Reading(f.offset, f.bearing_of, n.jacobian, n.restart)


def readings(scn: Paper003Scenario) -> tuple[Reading, ...]:
    """The readings a block computes: the scenario's first, then (``report.readings = "all"``)
    every other combination in a fixed order."""
    own = scenario_reading(scn)
    if scn.report.readings == "default":
        return (own,)
    every = [
        Reading(o, b, j, r)
        for o, b, j, r in product(
            ("world", "leg"),
            ("follower_from_leader", "leader_from_follower"),
            ("printed", "true"),
            (True, False),
        )
    ]
    return (own, *[r for r in every if r != own])


def _truth(scn: Paper003Scenario, geometry: tuple[str, str]) -> SquareTruth:
    f = scn.formation.model_copy(update={"offset": geometry[0], "bearing_of": geometry[1]})
    return square_truth(scn.path, f)


# ----------------------------------------------------------------------------------------------
# Navigation of a block of runs


@dataclass(frozen=True)
class DeadReckoning:
    """The DR track and its accumulated covariance for some runs (seed 003, eq. 1, 5).

    Attributes:
        position_m: DR positions, shape (n, T + 1, 2), m (east, north).
        cov_m2: sum of the eq. 5 increments from t = 0, shape (n, T + 1, 2, 2), m^2 (the
            covariance since a tick j is ``cov_m2[:, k] - cov_m2[:, j]``).
    """

    position_m: Array
    cov_m2: Array


def dead_reckon(
    meas: Seed003Measurements, start_m: Array, tick_s: float, nav_cfg: NavigationConfig
) -> DeadReckoning:
    """DR from the measured course and speed (eq. 1) with the cumulative eq. 5 covariance.

    Args:
        meas: the measurements, course and speed shape (n, T).
        start_m: the known start, shape (2,), m.
        tick_s: the step, s.
        nav_cfg: the sigmas of eq. 5.
    """
    n, T = meas.course_rad.shape
    c, s = meas.course_rad.ravel(), meas.speed_m_s.ravel()
    inc = dr_step(np.zeros((n * T, 2)), c, s, tick_s).reshape(n, T, 2)
    dc = dr_increment_covariance(
        c, s, tick_s, math.radians(nav_cfg.sigma_course_deg), nav_cfg.sigma_speed_m_s
    ).reshape(n, T, 2, 2)
    pos = np.empty((n, T + 1, 2))
    pos[:, 0] = start_m
    np.cumsum(inc, axis=1, out=pos[:, 1:])
    pos[:, 1:] += start_m
    cov = np.zeros((n, T + 1, 2, 2))
    np.cumsum(dc, axis=1, out=cov[:, 1:])
    return DeadReckoning(pos, cov)


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


def ga_track(
    method: Literal["ga1", "ga2"],
    meas: Seed003Measurements,
    dr: DeadReckoning,
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
    """
    n = len(meas.runs)
    rows = np.arange(n)
    pos, cum = dr.position_m, dr.cov_m2
    K = len(meas.fix_tick)
    anchor = pos[:, 0].copy()  # the estimate at the last accepted fix
    prev = np.zeros(n, dtype=np.intp)  # tick of the last accepted fix
    offsets = np.zeros((n, K + 1, 2))
    fix_pos = np.empty((n, K, 2))
    fix_cov = np.empty((n, K, 2, 2))
    fix_prior = np.empty((n, K, 2, 2))
    accepted = np.zeros((n, K), dtype=bool)
    hd = np.zeros((n, K))
    short = np.zeros((n, K), dtype=bool)
    high = np.zeros((n, K), dtype=bool)
    for j, t in enumerate(meas.fix_tick):
        since = pos[:, t] - pos[rows, prev]
        cov = cum[:, t] - cum[rows, prev]
        if options.restart:
            start, end = anchor, anchor + since
        else:
            start, end = pos[rows, prev], pos[:, t]
        present = meas.range_produced[:, j]
        fix = ga_fix(
            method, start, end, meas.leader_m[:, j], meas.range_m[:, j], cov, options, present
        )
        ok = fix.valid.copy()
        short[:, j] = present & (meas.range_m[:, j] < options.min_range_m)
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
        _assemble(pos, offsets, meas.fix_tick),
        fix_pos,
        fix_cov,
        fix_prior,
        accepted,
        hd,
        short,
        high,
    )


def ekf_track(
    meas: Seed003Measurements, dr: DeadReckoning, nav_cfg: NavigationConfig
) -> FixedTrack:
    """The range-only EKF (beyond the paper): predict with eq. 1 and Q = eq. 5 (F = I, so the
    prediction over a window is the DR displacement and the summed increments), update with
    each range to the broadcast leader position (:func:`nav.relative.range_update`). Ranges
    below ``min_range_m`` are refused, as by :class:`nav.relative.FollowerNavigator`."""
    n = len(meas.runs)
    pos, cum = dr.position_m, dr.cov_m2
    K = len(meas.fix_tick)
    x = pos[:, 0].copy()
    x_last = x  # the estimate after the previous range: the start of the HDOP's DR segment
    P = np.broadcast_to(np.eye(2) * nav_cfg.ekf_initial_sigma_m**2, (n, 2, 2)).copy()
    prev = 0
    offsets = np.zeros((n, K + 1, 2))
    fix_pos = np.empty((n, K, 2))
    fix_cov = np.empty((n, K, 2, 2))
    accepted = np.zeros((n, K), dtype=bool)
    hd = np.zeros((n, K))
    short = np.zeros((n, K), dtype=bool)
    leader_cov = None
    if nav_cfg.leader_sigma_m > 0:
        leader_cov = np.broadcast_to(np.eye(2) * nav_cfg.leader_sigma_m**2, (n, 2, 2))
    for j, t in enumerate(meas.fix_tick):
        x_prior = x + (pos[:, t] - pos[:, prev])
        P_prior = P + (cum[:, t] - cum[:, prev])
        present = meas.range_produced[:, j]
        short[:, j] = present & (meas.range_m[:, j] < nav_cfg.min_range_m)
        use = present & ~short[:, j]
        x, P, info = range_update(
            x_prior,
            P_prior,
            meas.leader_m[:, j],
            meas.range_m[:, j],
            nav_cfg.sigma_range_m,
            leader_cov=leader_cov,
            present=use,
        )
        accepted[:, j] = info.applied
        hd[:, j] = np.where(info.applied, hdop(x_last, x, meas.leader_m[:, j]), 0.0)
        x_last = x
        fix_pos[:, j], fix_cov[:, j] = x, P
        prev = t
        offsets[:, j + 1] = x - pos[:, t]
    return FixedTrack(
        _assemble(pos, offsets, meas.fix_tick),
        fix_pos,
        fix_cov,
        fix_cov,
        accepted,
        hd,
        short,
        np.zeros((n, K), dtype=bool),
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
        return {k: np.hypot(*(v - ref).transpose(2, 0, 1)) for k, v in self.tracks.items()}


def simulate(
    scn: Paper003Scenario,
    seed: int,
    runs: tuple[int, ...],
    reading: Reading | None = None,
    truth: SquareTruth | None = None,
    meas: Seed003Measurements | None = None,
    dr: DeadReckoning | None = None,
) -> Samples:
    """Measure and position some runs under one reading (default: the scenario's).

    ``truth``, ``meas`` and ``dr`` may be passed in when they are shared by several readings of
    the same geometry (they depend on ``seed``, ``runs`` and the geometry only).
    """
    rd = reading or scenario_reading(scn)
    truth = truth or _truth(scn, rd.geometry)
    meas = meas or measure(scn.sensors, truth, seed, runs)
    nc = scn.navigation
    dr = dr or dead_reckon(meas, truth.follower_m[0], scn.path.tick_s, nc)
    opt = nc.ga_options(rd.jacobian, rd.restart)
    fixed = {
        "GA1": ga_track("ga1", meas, dr, opt, nc.max_hdop),
        "GA2": ga_track("ga2", meas, dr, opt, nc.max_hdop),
        "EKF": ekf_track(meas, dr, nc),
    }
    tracks = {"DR": dr.position_m, **{k: v.position_m for k, v in fixed.items()}}
    return Samples(tuple(runs), truth, meas, tracks, fixed)


# ----------------------------------------------------------------------------------------------
# Block reduction

N_RUN_STATS = 4  # count, sum, sum of squares, max of the distance over ticks 1..T
N_CONS = 4  # fixes with a finite stated covariance, NEES sum, stated trace sum, squared error sum
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


def _per_run(d: Array) -> Array:
    """(n, T + 1) distances -> (n, 4) count, sum, sum of squares, max over ticks 1..T."""
    w = d[:, 1:]
    return np.stack(
        [np.full(len(w), w.shape[1], dtype=float), w.sum(1), (w * w).sum(1), w.max(1)], axis=1
    )


def _consistency(s: Samples, row: str) -> Array:
    name, _, prior = row.partition(" ")
    f = s.fixed[name]
    ref = s.truth.follower_m[s.meas.fix_tick]
    e = f.fix_position_m - ref  # (n, K, 2)
    C = f.fix_cov_prior_m2 if prior else f.fix_cov_m2
    det = C[..., 0, 0] * C[..., 1, 1] - C[..., 0, 1] ** 2
    ok = f.accepted & np.isfinite(det) & (det > 0) & np.isfinite(C).all(axis=(-1, -2))
    Cs = np.where(ok[..., None, None], C, np.eye(2))
    nees = np.einsum("nki,nki->nk", e, np.linalg.solve(Cs, e[..., None])[..., 0])
    tr = Cs[..., 0, 0] + Cs[..., 1, 1]
    e2 = (e * e).sum(-1)
    return np.stack(
        [
            ok.sum(1),
            np.where(ok, nees, 0).sum(1),
            np.where(ok, tr, 0).sum(1),
            np.where(ok, e2, 0).sum(1),
        ],
        axis=1,
    ).astype(float)


def _fix_stats(s: Samples, name: str, t_end_s: float) -> tuple[Array, Array]:
    f = s.fixed[name]
    m = s.meas
    K = len(m.fix_tick)
    stats = np.stack(
        [
            np.full(len(s.runs), K, dtype=float),
            m.range_produced.sum(1),
            f.accepted.sum(1),
            f.refused_short.sum(1),
            f.refused_hdop.sum(1),
            f.hdop.sum(1),
        ],
        axis=1,
    ).astype(float)
    t_fix = s.truth.t_s[m.fix_tick]
    gaps = np.empty(len(s.runs))
    for i in range(len(s.runs)):
        times = np.concatenate([[0.0], t_fix[f.accepted[i]], [t_end_s]])
        gaps[i] = np.max(np.diff(times))
    return stats, gaps


def reduce_block(scn: Paper003Scenario, seed: int, runs: tuple[int, ...]) -> Paper003Block:
    """Simulate a block of runs under every reading it computes and reduce it to accumulators."""
    rds = readings(scn)
    n, R = len(runs), len(rds)
    per_run = np.empty((n, R, len(METHODS), N_RUN_STATS))
    cons = np.empty((n, R, len(CONSISTENCY_ROWS), N_CONS))
    fixes = np.empty((n, R, len(FIXED), N_FIX))
    gaps = np.empty((n, R, len(FIXED)))
    shared: dict[tuple[str, str], tuple[SquareTruth, Seed003Measurements, DeadReckoning]] = {}
    block: Paper003Block | None = None
    t_end = scn.path.n_legs * scn.path.leg_s
    for r, rd in enumerate(rds):
        if rd.geometry not in shared:
            truth = _truth(scn, rd.geometry)
            meas = measure(scn.sensors, truth, seed, runs)
            dr = dead_reckon(meas, truth.follower_m[0], scn.path.tick_s, scn.navigation)
            shared[rd.geometry] = (truth, meas, dr)
        s = simulate(scn, seed, runs, rd, *shared[rd.geometry])
        d = s.distances()
        for m, name in enumerate(METHODS):
            if not np.isfinite(d[name]).all():
                raise ValueError(f"{name}: a non-finite estimate in runs {runs[0]}-{runs[-1]}")
            per_run[:, r, m] = _per_run(d[name])
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


# ----------------------------------------------------------------------------------------------
# Metrics file


class CellStats(BaseModel):
    """Maximum, arithmetic mean and standard deviation of the distance to the reference, m."""

    max_m: float | None
    mean_m: float | None
    std_m: float | None


class MethodCells(BaseModel):
    """A row of Tables 1-3: the single test sample and all runs (pooled 10 Hz samples)."""

    single: CellStats
    all_runs: CellStats


class ReadingResult(BaseModel):
    """Every method under one reading of the paper."""

    label: str
    offset: str
    bearing_of: str
    jacobian: str
    restart: bool
    methods: dict[str, MethodCells]
    ratio_to_paper: dict[str, CellStats] = Field(
        description="all-runs cells divided by the paper's 100-sample cells (GA1, GA2, DR)"
    )


class GaConsistency(BaseModel):
    """A method's stated accuracy at its fixes against its actual error."""

    method: str
    n_fixes: int
    mean_nees: float | None
    band_low: float | None
    band_high: float | None
    stated_rms_m: float | None = Field(description="sqrt(mean trace of the stated covariance)")
    actual_rms_m: float | None = Field(description="sqrt(mean squared error at the fixes)")
    stated_to_actual: float | None
    consistent: bool
    note: str


class FixStats(BaseModel):
    """What the ranges did for one method (all runs)."""

    method: str
    ranges_expected: int
    ranges_received: int
    accepted: int
    refused_short: int
    refused_hdop: int
    mean_hdop: float | None
    median_hdop: float | None = Field(description="median over runs of each run's median HDOP")
    longest_gap_s: float


class ErrorDraw(BaseModel):
    """A simulated error against what the navigation assumes."""

    quantity: str
    distribution: str
    half_width: float
    simulated_std: float
    bias: str
    navigation_sigma: float | None


class Paper003Metrics(BaseModel):
    """``metrics.json`` of ``paper-003/test-*`` (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    single_sample_run: int
    paper_table: str
    reading: str
    methods: dict[str, MethodCells]
    paper: dict[str, MethodCells]
    ratio_to_paper: dict[str, CellStats]
    readings: list[ReadingResult] = Field(description="report.readings = all: every reading")
    consistency: list[GaConsistency]
    fixes: list[FixStats]
    hdop_figure2: dict[str, float] = Field(
        description="HDOP of the Figure 2 set-up at relative bearings 0, 90, 180, 270 deg"
    )
    claims: dict[str, bool] = Field(description="the paper's qualitative claims on these runs")
    error_draws: list[ErrorDraw]
    warnings: list[str]


def _clean(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _pooled(stats: Array) -> CellStats:
    """(runs, 4) per-run sums -> pooled max, mean, std (population) over every sample."""
    count, total, sq, mx = (stats[:, i] for i in range(4))
    N = count.sum()
    if N <= 0:
        return CellStats(max_m=None, mean_m=None, std_m=None)
    mean = total.sum() / N
    var = max(sq.sum() / N - mean * mean, 0.0)
    return CellStats(max_m=_clean(mx.max()), mean_m=_clean(mean), std_m=_clean(math.sqrt(var)))


def _paper_cells(cells: PaperCells) -> dict[str, MethodCells]:
    out = {}
    for k, (single, hundred) in cells.items():
        out[k] = MethodCells(
            single=CellStats(max_m=single[0], mean_m=single[1], std_m=single[2]),
            all_runs=CellStats(max_m=hundred[0], mean_m=hundred[1], std_m=hundred[2]),
        )
    return out


def _ratio(ours: CellStats, paper: CellStats) -> CellStats:
    def r(a: float | None, b: float | None) -> float | None:
        return None if a is None or not b else a / b

    return CellStats(
        max_m=r(ours.max_m, paper.max_m),
        mean_m=r(ours.mean_m, paper.mean_m),
        std_m=r(ours.std_m, paper.std_m),
    )


def hdop_figure2(cfg: HdopMapConfig, points_east_m: Array, points_north_m: Array) -> Array:
    """HDOP of the Figure 2 set-up at follower positions around the leader at (0, 0).

    F has moved ``step_m`` on ``course_deg`` since its DR start and receives the range to L:
    ``start = position - D_r (sin C, cos C)`` (eq. 7-8 via :func:`nav.relative.hdop`).

    Args:
        points_east_m, points_north_m: follower positions, any equal shapes, m.

    Returns:
        HDOP, the same shape.
    """
    p = np.stack([np.ravel(points_east_m), np.ravel(points_north_m)], axis=1)
    c = math.radians(cfg.course_deg)
    start = p - cfg.step_m * np.array([math.sin(c), math.cos(c)])
    h = hdop(start, p, np.zeros_like(p))
    return h.reshape(np.shape(points_east_m))


def _hdop_at_bearings(cfg: HdopMapConfig, distance_m: float) -> dict[str, float]:
    c = math.radians(cfg.course_deg)
    out = {}
    for rb in (0, 90, 180, 270):
        b = c + math.radians(rb)
        h = hdop_figure2(
            cfg, np.array([distance_m * math.sin(b)]), np.array([distance_m * math.cos(b)])
        )
        out[f"{rb}"] = float(h[0])
    return out


def _error_draws(scn: Paper003Scenario) -> list[ErrorDraw]:
    s, n = scn.sensors, scn.navigation
    rows = [
        ("course (deg)", s.ins.heading, n.sigma_course_deg),
        ("speed (m/s)", s.log.speed, n.sigma_speed_m_s),
        ("range (m)", s.modem.range, n.sigma_range_m),
        ("leader broadcast (m)", s.modem.broadcast, None),
    ]
    out = []
    for name, cfg, sigma in rows:
        model = cfg.to_model()
        k = model.uniform_k if model.distribution == "uniform" else float("nan")
        bias = [f"{model.bias / cfg.unit_to_si:g}"]
        if model.sector_bias is not None:
            bias = ["sectors " + ", ".join(f"{b / cfg.unit_to_si:g}" for b in model.sector_bias)]
        out.append(
            ErrorDraw(
                quantity=name,
                distribution=model.distribution,
                half_width=k * model.sigma / cfg.unit_to_si if np.isfinite(k) else 0.0,
                simulated_std=model.noise_std / cfg.unit_to_si,
                bias=bias[0],
                navigation_sigma=sigma,
            )
        )
    return out


# ----------------------------------------------------------------------------------------------
# The experiment


@dataclass(frozen=True)
class SquareExperiment(Experiment):
    """Seed 003 test: N runs of the follower on the square (module docstring)."""

    scenario_type = Paper003Scenario
    metrics_type = Paper003Metrics
    test: str = "test-1"

    def block_size(self, scenario: Paper003Scenario) -> int:
        return block_runs(scenario)

    def check(self, scenario: Paper003Scenario, n_runs: int) -> None:
        if scenario.report.single_sample >= n_runs:
            raise ConfigError(
                f"report.single_sample = {scenario.report.single_sample}: must be < runs = {n_runs}"
            )
        # the truth's own checks (corner time) and the sensors' timing, before anything runs
        for rd in readings(scenario):
            _truth(scenario, rd.geometry)
        measure(scenario.sensors, _truth(scenario, scenario_reading(scenario).geometry), 0, (0,))

    def run_block(self, scenario: Paper003Scenario, seed: int, runs: tuple[int, ...]):
        return reduce_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_paper003(self, ctx)


@dataclass
class _Totals:
    labels: tuple[str, ...]
    per_run: list[Array] = field(default_factory=list)
    consistency: list[Array] = field(default_factory=list)
    fixes: list[Array] = field(default_factory=list)
    gaps: list[Array] = field(default_factory=list)
    hdop_median: list[Array] = field(default_factory=list)
    routes: dict[int, dict[str, NDArray[np.float32]]] = field(default_factory=dict)
    single: dict[int, dict[str, Array]] = field(default_factory=dict)


def _merge(ctx: ReportContext) -> _Totals:
    tot: _Totals | None = None
    for b in ctx.blocks:
        if tot is None:
            tot = _Totals(b.labels)
        elif b.labels != tot.labels:
            raise ValueError("blocks computed different readings")
        tot.per_run.append(b.per_run)
        tot.consistency.append(b.consistency)
        tot.fixes.append(b.fixes)
        tot.gaps.append(b.longest_gap_s)
        tot.hdop_median.append(b.hdop_median)
        tot.routes.update(b.routes)
        tot.single.update(b.single)
    if tot is None:
        raise ValueError("no blocks to report")
    return tot


def _cells(per_run: Array, single_index: int) -> dict[str, MethodCells]:
    """(runs, 4 methods, 4) -> method -> cells."""
    return {
        name: MethodCells(
            single=_pooled(per_run[single_index : single_index + 1, m]),
            all_runs=_pooled(per_run[:, m]),
        )
        for m, name in enumerate(METHODS)
    }


def report_paper003(exp: SquareExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables, figures, metrics, run data and the recording of a seed 003 test."""
    scn: Paper003Scenario = ctx.scenario  # type: ignore[assignment]
    tot = _merge(ctx)
    per_run = np.concatenate(tot.per_run)  # (N, R, M, 4) in run order
    cons = np.concatenate(tot.consistency)
    fixes = np.concatenate(tot.fixes)
    gaps = np.concatenate(tot.gaps)
    hmed = np.concatenate(tot.hdop_median)
    single = scn.report.single_sample
    table_name, paper_cells = PAPER_TABLES[exp.test]
    paper = _paper_cells(paper_cells)
    rds = readings(scn)
    all_cells = [_cells(per_run[:, r], single) for r in range(len(rds))]
    methods = all_cells[0]
    ratio = {k: _ratio(methods[k].all_runs, paper[k].all_runs) for k in paper}
    reading_results = []
    if scn.report.readings == "all":
        for rd, cells in zip(rds, all_cells, strict=True):
            reading_results.append(
                ReadingResult(
                    label=rd.label,
                    offset=rd.offset,
                    bearing_of=rd.bearing_of,
                    jacobian=rd.jacobian,
                    restart=rd.restart,
                    methods=cells,
                    ratio_to_paper={k: _ratio(cells[k].all_runs, paper[k].all_runs) for k in paper},
                )
            )
    # consistency of the stated accuracy (default reading)
    consistency = []
    for m, name in enumerate(CONSISTENCY_ROWS):
        c = cons[:, 0, m].sum(axis=0)
        nf = int(c[0])
        if nf == 0:
            consistency.append(
                GaConsistency(
                    method=name,
                    n_fixes=0,
                    mean_nees=None,
                    band_low=None,
                    band_high=None,
                    stated_rms_m=None,
                    actual_rms_m=None,
                    stated_to_actual=None,
                    consistent=False,
                    note="no fix was accepted: nothing to compare",
                )
            )
            continue
        lo, hi = nees_band(2, nf, scn.report.consistency_probability)
        mean_nees = c[1] / nf
        stated, actual = math.sqrt(c[2] / nf), math.sqrt(c[3] / nf)
        ok = lo <= mean_nees <= hi
        if ok:
            note = "consistent: the mean NEES over the fixes is inside its chi-square band"
        elif mean_nees > hi:
            note = (
                f"over-confident: the actual error is {actual / stated:.1f} x the stated RMS "
                "(the systematic course and speed errors are not in eq. 5)"
            )
        else:
            note = f"pessimistic: the stated RMS is {stated / actual:.1f} x the actual error"
        consistency.append(
            GaConsistency(
                method=name,
                n_fixes=nf,
                mean_nees=mean_nees,
                band_low=lo,
                band_high=hi,
                stated_rms_m=stated,
                actual_rms_m=actual,
                stated_to_actual=stated / actual,
                consistent=ok,
                note=note,
            )
        )
    fix_stats = []
    for m, name in enumerate(FIXED):
        f = fixes[:, 0, m].sum(axis=0)
        med = hmed[:, m]
        fix_stats.append(
            FixStats(
                method=name,
                ranges_expected=int(f[0]),
                ranges_received=int(f[1]),
                accepted=int(f[2]),
                refused_short=int(f[3]),
                refused_hdop=int(f[4]),
                mean_hdop=_clean(f[5] / f[2]) if f[2] else None,
                median_hdop=_clean(float(np.median(med[np.isfinite(med)])))
                if np.isfinite(med).any()
                else None,
                longest_gap_s=float(gaps[:, 0, m].max()),
            )
        )
    warnings = _warnings(scn, fix_stats)
    hd = _hdop_at_bearings(scn.report.hdop_map, scn.formation.distance_m or 10.0)
    mean = {k: methods[k].all_runs.mean_m or 0.0 for k in METHODS}
    claims = {
        "GA1 beats DR (mean, all runs)": mean["GA1"] < mean["DR"],
        "GA2 beats DR (mean, all runs)": mean["GA2"] < mean["DR"],
        "abeam HDOP below astern HDOP (Figure 2 set-up)": hd["90"] < hd["180"],
    }
    metrics = Paper003Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        single_sample_run=single,
        paper_table=table_name,
        reading=rds[0].label,
        methods=methods,
        paper=paper,
        ratio_to_paper=ratio,
        readings=reading_results,
        consistency=consistency,
        fixes=fix_stats,
        hdop_figure2=hd,
        claims=claims,
        error_draws=_error_draws(scn),
        warnings=warnings,
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    tables = _tables(exp, ctx, metrics)
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if scn.report.figures:
        files += _figures(exp, ctx, scn, tot)
    if scn.report.run_data:
        files += _run_data(exp, ctx, scn, per_run[:, 0])
    if (scn.report.recording or scn.report.run_data) and single in tot.single:
        files += record_sample(exp, scn, ctx.seed, single, tot.single[single], ctx.out_dir)
    text = tables[0].to_text()
    if warnings:
        text += "\n" + "\n".join(f"warning: {w}" for w in warnings) + "\n"
    text += f"\nwrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _warnings(scn: Paper003Scenario, fix_stats: list[FixStats]) -> list[str]:
    out = []
    ga = fix_stats[0]
    if ga.ranges_received < ga.ranges_expected:
        m = scn.sensors.modem
        why = []
        if m.max_range_m is not None:
            why.append(f"sensors.modem.max_range_m = {m.max_range_m:g} m")
        if m.dropout_windows_s:
            why.append(f"sensors.modem.dropout_windows_s = {m.dropout_windows_s}")
        if m.range.dropout_probability > 0:
            why.append(f"dropout probability {m.range.dropout_probability:g}")
        out.append(
            f"ranges missing: {ga.ranges_received} of {ga.ranges_expected} received"
            + (f" ({'; '.join(why)})" if why else "")
            + f"; GA and EKF dead-reckon through the gaps (longest {ga.longest_gap_s:g} s "
            "without a fix)"
        )
    for f in fix_stats:
        if f.refused_short:
            out.append(
                f"{f.method}: {f.refused_short} ranges below navigation.min_range_m = "
                f"{scn.navigation.min_range_m:g} m (zero range: the follower on the leader) "
                "made no fix; it dead-reckons instead"
            )
        if f.refused_hdop:
            out.append(
                f"{f.method}: {f.refused_hdop} fixes refused for HDOP above navigation.max_hdop "
                f"= {scn.navigation.max_hdop:g}; it dead-reckons instead"
            )
    for f in fix_stats[:2]:
        if f.median_hdop is not None and f.median_hdop > scn.report.warn_hdop:
            out.append(
                f"poor geometry: median HDOP {f.median_hdop:.1f} of {f.method}'s fixes "
                f"(above report.warn_hdop = {scn.report.warn_hdop:g}): the follower is near the "
                "leader's course line (bow or stern), where the range and the DR segment cross "
                "at a small angle"
            )
    if ga.accepted == 0 and ga.ranges_expected:
        out.append("no GA fix at all: GA1, GA2 and the EKF are pure DR in these runs")
    return out


def _cell_row(name: str, ours: MethodCells, paper: MethodCells | None) -> list:
    row: list = [name]
    for part in ("single", "all_runs"):
        for st in STATS:
            v = getattr(getattr(ours, part), f"{st}_m")
            p = getattr(getattr(paper, part), f"{st}_m") if paper else None
            row += [v, p, (v / p) if (v is not None and p) else None]
    return row


def _tables(exp: SquareExperiment, ctx: ReportContext, m: Paper003Metrics) -> list[Table]:
    cols = ["Method"]
    for part in ("1 sample", f"{ctx.n_runs} samples"):
        for st in ("max", "mean", "std"):
            cols += [f"{st} {part} (m)", "paper", "ratio"]
    rows = [_cell_row(k, m.methods[k], m.paper.get(k)) for k in METHODS]
    main = Table(
        f"{m.paper_table}: distance to the reference position (m), reading {m.reading}; "
        f"single sample = run {m.single_sample_run}, {ctx.n_runs} samples pooled at 10 Hz",
        cols,
        rows,
        digits=2,
        slug="table",
        note="Paper columns: the paper's single sample and 100 samples; EKF is beyond the paper.",
    )
    tables = [main]
    if m.readings:
        rc = ["Reading", "Method"]
        for st in ("max", "mean", "std"):
            rc += [f"{st} (m)", "ratio"]
        rows = []
        for r in m.readings:
            for k in ("GA1", "GA2", "DR"):
                c, q = r.methods[k].all_runs, r.ratio_to_paper[k]
                rows.append([r.label, k, c.max_m, q.max_m, c.mean_m, q.mean_m, c.std_m, q.std_m])
        for k in ("GA1", "GA2", "DR"):
            p = m.paper[k].all_runs
            rows.append(["paper (100 samples)", k, p.max_m, 1.0, p.mean_m, 1.0, p.std_m, 1.0])
        tables.append(
            Table(
                f"Every reading, {ctx.n_runs} samples pooled, against {m.paper_table}",
                rc,
                rows,
                digits=2,
                slug="readings",
                note="reading = offset / whose bearing / A of eq. 2 / DR restart after a fix",
            )
        )
    tables.append(
        Table(
            "Stated accuracy at the fixes against the actual error (mean NEES, 2-D)",
            [
                "Method",
                "Fixes",
                "Mean NEES",
                "Band low",
                "Band high",
                "Stated RMS (m)",
                "Actual RMS (m)",
                "Stated / actual",
                "Verdict",
            ],
            [
                [
                    c.method,
                    c.n_fixes,
                    c.mean_nees,
                    c.band_low,
                    c.band_high,
                    c.stated_rms_m,
                    c.actual_rms_m,
                    c.stated_to_actual,
                    "consistent" if c.consistent else "inconsistent",
                ]
                for c in m.consistency
            ],
            digits=3,
            slug="consistency",
            note=" ".join(f"{c.method}: {c.note}." for c in m.consistency),
        )
    )
    tables.append(
        Table(
            "Ranges and fixes",
            [
                "Method",
                "Expected",
                "Received",
                "Accepted",
                "Too short",
                "HDOP refused",
                "Mean HDOP",
                "Median HDOP",
                "Longest gap (s)",
            ],
            [
                [
                    f.method,
                    f.ranges_expected,
                    f.ranges_received,
                    f.accepted,
                    f.refused_short,
                    f.refused_hdop,
                    f.mean_hdop,
                    f.median_hdop,
                    f.longest_gap_s,
                ]
                for f in m.fixes
            ],
            digits=2,
            slug="fixes",
            note="HDOP of the Figure 2 set-up at relative bearings 0/90/180/270 deg: "
            + " / ".join(f"{v:.2f}" for v in m.hdop_figure2.values()),
        )
    )
    tables.append(
        Table(
            "Simulated errors against the navigation's sigmas",
            ["Quantity", "Draw", "Half-width", "Simulated std", "Bias", "Navigation sigma"],
            [
                [
                    d.quantity,
                    d.distribution,
                    d.half_width,
                    d.simulated_std,
                    d.bias,
                    d.navigation_sigma,
                ]
                for d in m.error_draws
            ],
            digits=3,
            slug="error-draws",
        )
    )
    if m.warnings:
        tables.append(Table("Warnings", ["Warning"], [[w] for w in m.warnings], slug="warnings"))
    return tables


def _words(exp) -> str:
    """The experiment's name in words for figure titles (``paper-003/test-1`` -> ``Seed 003,
    Test 1``)."""
    family, _, test = exp.name.partition("/")
    seed = family.removeprefix("paper-")
    return (
        f"Seed {seed}, Test {test.removeprefix('test-')}" if test.startswith("test-") else exp.name
    )


def _figures(exp, ctx, scn: Paper003Scenario, tot: _Totals) -> list[str]:
    out = ctx.out_dir
    truth = _truth(scn, scenario_reading(scn).geometry)
    every = max(1, round(scn.report.routes_every_s / scn.path.tick_s))
    ref = truth.follower_m[::every]
    leader = truth.leader_m[::every]
    files = []
    hm = scn.report.hdop_map
    axis = np.linspace(-hm.half_width_m, hm.half_width_m, hm.cells)
    E, N = np.meshgrid(axis, axis)
    files.extend(
        figures.field_map(
            out / "hdop.png",
            axis,
            axis,
            hdop_figure2(hm, E, N),
            title=f"HDOP around the leader\n(F on course {hm.course_deg:g}°, $D_r$ = "
            f"{hm.step_m:g} m)",
            label="HDOP",
            marks={"L": np.zeros(2)},
            arrow=(hm.course_deg, hm.step_m),
            vmax=10.0,
        )
    )
    names = ("DR", "GA1", "GA2", "EKF")
    runs = sorted(tot.routes)
    s = scn.report.single_sample
    if s in tot.routes:
        files.extend(
            figures.routes(
                out / "paths-single.png",
                ref,
                {k: [tot.routes[s][k]] for k in names},
                landmarks=None,
                title=f"{_words(exp)}: reference and estimated paths of F (run {s})",
                extra={"leader": leader},
            )
        )
    if runs:
        files.extend(
            figures.routes(
                out / "paths-all.png",
                ref,
                {k: [tot.routes[r][k] for r in runs] for k in ("DR", "GA1", "GA2")},
                title=f"{_words(exp)}: reference and estimated paths of F ({len(runs)} samples)",
                extra={"leader": leader},
            )
        )
    if s in tot.single:
        t = truth.t_s
        d = tot.single[s]
        files.extend(
            figures.distances(
                out / "distance-single.png",
                {k: (t[1:], d[f"distance/{k}"][1:]) for k in names},
                title=f"{_words(exp)}: distance to the reference position (run {s})",
                log=False,
            )
        )
    return files


def _run_data(exp, ctx, scn: Paper003Scenario, per_run: Array) -> list[str]:
    """Parquet: per-run statistics (one row per run) and the single sample's distances."""
    meta = {"experiment": exp.name, "seed": str(ctx.seed), "runs": str(ctx.n_runs)}
    cols = {"run": export.Column(np.arange(ctx.n_runs, dtype=np.int64), "1", "run index")}
    for m, name in enumerate(METHODS):
        st = per_run[:, m]
        mean = st[:, 1] / st[:, 0]
        std = np.sqrt(np.maximum(st[:, 2] / st[:, 0] - mean * mean, 0.0))
        cols[f"{name}.max"] = export.Column(st[:, 3], "m", f"{name}: largest distance to reference")
        cols[f"{name}.mean"] = export.Column(mean, "m", f"{name}: mean distance to reference")
        cols[f"{name}.std"] = export.Column(std, "m", f"{name}: std of the distance (ddof 0)")
    export.write_parquet(ctx.out_dir / "data" / "runs.parquet", cols, meta)
    return ["data/runs.parquet"]


def record_sample(
    exp: Experiment, scn: Paper003Scenario, seed: int, run: int, one: dict, out_dir
) -> list[str]:
    """Write ``recording.rrd`` and the Parquet time series ``data/run-NNNNNN.parquet`` of the
    single sample from its block data (the batch's own numbers)."""
    truth = _truth(scn, scenario_reading(scn).geometry)
    t = truth.t_s
    t_fix = t[periodic_fix_ticks(scn)]

    def z3(p: Array) -> Array:
        return np.concatenate([p, np.zeros((len(p), 1))], axis=1)

    files = []
    if scn.report.recording:
        rec = Recording(out_dir / "recording.rrd", exp.name, f"{exp.name}/seed{seed}/run{run}")
        rec.track("leader", t, z3(truth.leader_m), (120, 120, 120))
        rec.track("truth", t, z3(truth.follower_m), COLORS["truth"])
        for k in METHODS:
            rec.track(k.lower(), t, z3(one[f"track/{k}"]), REC_COLORS[k])
        for k in FIXED:
            ok = one[f"accepted/{k}"]
            rec.fixes(f"{k.lower()}_fix", t_fix[ok], z3(one[f"fix/{k}"][ok]), REC_COLORS[k])
            rec.scalars(f"hdop/{k.lower()}", t_fix[ok], one[f"hdop/{k}"][ok], REC_COLORS[k], k)
        for k in METHODS:
            rec.scalars(f"distance/{k.lower()}", t, one[f"distance/{k}"], REC_COLORS[k], k)
        rec.blueprint("distance", "hdop")
        rec.close()
        files.append("recording.rrd")
    if scn.report.run_data:
        en = ("east", "north")
        cols = {
            "t": export.Column(t, "s", "time"),
            "leader": export.Column(truth.leader_m, "m", "leader reference", en),
            "reference": export.Column(truth.follower_m, "m", "follower reference", en),
        }
        for k in METHODS:
            cols[k] = export.Column(one[f"track/{k}"], "m", f"{k} estimate", en)
            cols[f"{k}.distance"] = export.Column(
                one[f"distance/{k}"], "m", f"{k}: distance to the reference"
            )
        rel = f"data/run-{run:06d}.parquet"
        meta = {"experiment": exp.name, "seed": str(seed), "run": str(run)}
        export.write_parquet(out_dir / rel, cols, meta)
        files.append(rel)
    return files


def periodic_fix_ticks(scn: Paper003Scenario) -> NDArray[np.intp]:
    """Ticks of the ranges, shape (K,)."""
    every = check_multiple(scn.sensors.modem.period_s, scn.path.tick_s, "sensors.modem.period_s")
    return periodic_indices(scn.path.n_ticks, every)


def preset_of(test: str) -> dict:
    """The scenario overrides that make a test (Test 1 is the defaults)."""
    if test == "test-2":
        return {"formation": {"relative_bearing_deg": 180.0}}
    if test == "test-3":
        return {
            "sensors": {
                "ins": {"heading": {"sector_bias_deg": [0.4, 0.8, 0.0, 0.2]}},
                "log": {"speed": {"bias_m_s": 0.005}},
                "modem": {"range": {"bias_m": 0.0025}},
            }
        }
    return {}


def scenario_of(test: str, overrides: dict | None = None) -> Paper003Scenario:
    """The validated scenario of a test, with optional nested overrides (for scripts, tests)."""
    cfg = load_config(Paper003Scenario, preset_of(test))
    if overrides:
        from bauv_sim.config import to_plain

        base = to_plain(cfg)
        _deep_update(base, overrides)
        cfg = load_config(Paper003Scenario, base)
    return cfg


def _deep_update(base: dict, upd: dict) -> None:
    for k, v in upd.items():
        if isinstance(v, dict) and isinstance(base.get(k), dict):
            _deep_update(base[k], v)
        else:
            base[k] = v


_SUMMARIES = {
    "test-1": "seed 003 Test 1: follower abeam (90 deg, 10 m) on the square, uncalibrated; DR, "
    "GA1, GA2, range EKF",
    "test-2": "seed 003 Test 2: follower astern (180 deg, 10 m) on the square, uncalibrated; DR, "
    "GA1, GA2, range EKF",
    "test-3": "seed 003 Test 3: follower abeam (90 deg, 10 m) on the square, calibrated; DR, GA1, "
    "GA2, range EKF",
}
for _test, _summary in _SUMMARIES.items():
    register(
        SquareExperiment(
            name=f"paper-003/{_test}",
            summary=_summary,
            preset=preset_of(_test),
            default_runs=100,
            test=_test,
        )
    )
