"""Seed 000 (Naus & Nowak 2016): DR, EKF and USBL-only positioning on a straight passage.

Registers ``paper-000/test-1``, ``test-2`` and ``test-3``: the BAUV passes a seabed USBL
transceiver (section 6, Figure 7) while COG, SOG and the depth change are measured every second and
USBL range, azimuth and elevation every 5, 20 or 100 s. Each passage is positioned three ways:

* **DR**: dead reckoning from the measured course, speed and depth change (eq. 8, 16);
* **EKF**: the extended Kalman filter of eq. 15-23 fusing the same inputs with the USBL fixes;
* **USBL**: the position computed from each USBL measurement alone (inverse of eq. 15).

The report gives the paper's tables: for single passages the minimum, maximum and mean distance to
the reference position; for N passages the same statistics of zeta(k), the mean over passages of the
distance at moment k (eq. 24 writes a sum; the figures and the tables' values are a mean). Distances
are horizontal for EKF and DR and three-dimensional for USBL (its elevation error dominates; see
``../shared/seeds/README.md``). Statistics run over ticks 1..T (the paper's tables start after the
first measurement: their smallest DR and EKF distances are the one-step error, not the zero initial
error) and over the fix times for USBL.

Reading of the paper where it is silent (documented in the scenario fields):

* sensor errors are uniform on +-3 sigma (section 6) while the filter is tuned with sigma itself;
* the initial estimate is the reference start (the tables' minima show DR and EKF start on it),
  while the filter's initial covariance has the "mean error of about 3 m" of section 6;
* sigma_COG = 8 deg in the experiment (section 6), not the 3 deg of the analysis (section 3).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field, model_validator

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config, load_config, to_plain
from bauv_sim.errors import ConfigError
from bauv_sim.frames import KNOT_M_S
from bauv_sim.kinematic.passage import (
    StraightPassageConfig,
    TransceiverConfig,
    straight_passage,
)
from bauv_sim.sensors import (
    AngleErrorConfig,
    Compass,
    CompassConfig,
    LengthErrorConfig,
    Log,
    LogConfig,
    Pressure,
    PressureConfig,
    SpeedErrorConfig,
    Usbl,
    UsblConfig,
    check_multiple,
    periodic_indices,
)
from bauv_sim.truth import Truth
from nav.ekf import gate_limit
from nav.metrics import (
    Histogram,
    SeriesSum,
    batch_stats,
    chi2_ppf,
    distance_3d,
    nees_band,
    series_stats,
)
from nav.models import TIME_CHUNK, CourseSpeedDepthMotion, UsblMeasurement
from nav.track_ekf import Tracks, ekf_tracks, nees_packed, unpack
from tasks.core import figures, store
from tasks.core.recording import COLORS, Recording
from tasks.core.registry import (
    Experiment,
    MemoryTerm,
    ReportContext,
    ReportSummary,
    block_by_work,
    register,
)
from tasks.core.report import Table, write_metrics, write_tables

METHODS = ("EKF", "DR", "USBL")
BLOCK_BYTES_PER_RUN_TICK = 200.0
"""Peak memory of :meth:`StraightPassageExperiment.run_block` per passage and tick, bytes:
measured with :mod:`tracemalloc` (201-203 B for 600 and 6000 ticks, 50 and 100 passages, fixes
every 5 s; 194 B with fixes every 100 s): states, covariances, inputs and distances."""
LATENCY_FIELDS = ("processing_delay_s", "sound_speed_m_s")
"""USBL fields seed 000's batched passage does not use: it applies a fix at the tick it is valid
for (the paper's model), so a latency set here is refused rather than silently ignored."""
SIGMA_SOG_M_S = 0.5 * KNOT_M_S
"""Seed 000 section 3: ALIZE log, sigma_SOG = 0.5 kn."""

# The paper's tables: (min, max, mean) distance to the reference position, m, for EKF, DR, USBL.
PaperRow = tuple[float, float, float]

# the block accumulators are plain data (blocks are kept on disk for --resume)
store.plain_data("nav.metrics.SeriesSum")(SeriesSum)
store.plain_data("nav.metrics.Histogram")(Histogram)


def _rows(ekf: PaperRow, dr: PaperRow, usbl: PaperRow) -> dict[str, PaperRow]:
    return {"EKF": ekf, "DR": dr, "USBL": usbl}


PAPER_TABLES: dict[str, dict[str, object]] = {
    "test-1": {
        "usbl_period_s": 5.0,
        "single": [
            ("Table 1", _rows((0.1, 6.6, 2.2), (0.7, 25.8, 15.9), (0.3, 75.2, 22.6))),
            ("Table 2", _rows((0.1, 6.4, 2.3), (0.1, 22.6, 11.8), (0.2, 81.6, 23.6))),
            ("Table 3", _rows((0.1, 5.3, 1.8), (0.2, 14.0, 4.7), (0.7, 86.1, 21.6))),
        ],
        "hundred": ("Table 4", _rows((0.6, 3.3, 2.2), (0.6, 20.1, 10.6), (1.3, 57.0, 23.4))),
    },
    "test-2": {
        "usbl_period_s": 20.0,
        "single": [
            ("Table 5", _rows((0.2, 7.3, 3.4), (0.7, 34.9, 10.9), (0.4, 68.0, 24.3))),
            ("Table 6", _rows((0.1, 7.5, 2.5), (0.1, 26.7, 9.7), (1.4, 64.3, 21.0))),
            ("Table 7", _rows((0.3, 6.1, 2.2), (0.3, 15.3, 6.2), (1.3, 72.6, 21.1))),
        ],
        "hundred": ("Table 8", _rows((0.7, 4.4, 2.9), (0.7, 19.1, 10.8), (1.3, 55.9, 22.7))),
    },
    "test-3": {
        "usbl_period_s": 100.0,
        "single": [
            ("Table 9", _rows((0.1, 11.6, 4.0), (0.3, 33.8, 22.0), (3.4, 37.5, 18.7))),
            ("Table 10", _rows((0.5, 11.4, 4.9), (0.5, 28.7, 12.0), (7.6, 20.0, 14.0))),
            ("Table 11", _rows((0.2, 9.1, 4.0), (0.2, 20.3, 8.9), (3.5, 22.0, 11.7))),
        ],
        "hundred": ("Table 12", _rows((0.6, 6.4, 4.4), (0.6, 18.9, 10.7), (4.8, 43.0, 20.5))),
    },
}


# ----------------------------------------------------------------------------------------------
# Scenario


def _uniform_angle(sigma_deg: float) -> AngleErrorConfig:
    return AngleErrorConfig(distribution="uniform", sigma_deg=sigma_deg)


class Paper000Sensors(Config):
    """The four devices of section 6 with the paper's errors (uniform on +-3 sigma)."""

    ins: CompassConfig = Field(
        default_factory=lambda: CompassConfig(period_s=1.0, heading=_uniform_angle(8.0)),
        description="INS VN-200 course: sigma_COG = 8 deg (section 6)",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=1.0, speed=SpeedErrorConfig(distribution="uniform", sigma_m_s=SIGMA_SOG_M_S)
        ),
        description="ALIZE log: sigma_SOG = 0.5 kn",
    )
    pressure: PressureConfig = Field(
        default_factory=lambda: PressureConfig(
            period_s=1.0,
            output="depth_change",
            depth=LengthErrorConfig(distribution="uniform", sigma_m=0.25),
        ),
        description="WIKA S-20: depth change with sigma_dz = 0.25 m",
    )
    usbl: UsblConfig = Field(
        default_factory=lambda: UsblConfig(
            period_s=5.0,
            range=LengthErrorConfig(distribution="uniform", sigma_m=0.2),
            azimuth=_uniform_angle(3.0),
            elevation=_uniform_angle(3.0),
        ),
        description="MicronNav: sigma_r = 0.2 m, sigma_alpha = sigma_beta = 3 deg, 500 m",
    )


class FilterConfig(Config):
    """What DR and the EKF assume (section 6: the devices' sigmas)."""

    sigma_course_deg: float = Field(8.0, gt=0)
    sigma_speed_m_s: float = Field(SIGMA_SOG_M_S, gt=0)
    sigma_depth_change_m: float = Field(0.25, gt=0)
    sigma_range_m: float = Field(0.2, gt=0)
    sigma_azimuth_deg: float = Field(3.0, gt=0)
    sigma_elevation_deg: float = Field(3.0, gt=0)
    initial_mean_error_m: float = Field(
        3.0,
        gt=0,
        description="horizontal mean error of the initial fix (GNSS before diving), m; "
        "split equally between east and north",
    )
    initial_sigma_depth_m: float = Field(0.25, gt=0, description="initial depth sigma, m")
    azimuth_min_horizontal_m: float = Field(
        1.0, gt=0, description="below this horizontal distance the USBL azimuth is not used, m"
    )
    gate_probability: float | None = Field(
        None, gt=0, lt=1, description="chi-square innovation gate (e.g. 0.99), or none"
    )

    def P0(self) -> NDArray[np.float64]:
        """Initial covariance, shape (3, 3), m^2 (east, north, up)."""
        s2 = self.initial_mean_error_m**2 / 2.0
        return np.diag([s2, s2, self.initial_sigma_depth_m**2])


class InitialErrorConfig(Config):
    """How the initial estimate differs from the reference start."""

    distribution: Literal["none", "gaussian"] = Field(
        "none",
        description="none: start on the reference (the paper); gaussian: draw from the "
        "filter's initial covariance",
    )


class ReportConfig(Config):
    """What the report draws and records."""

    single_passages: int = Field(3, ge=0, le=10, description="passages with their own tables")
    routes_max: int = Field(100, ge=0, le=1000, description="passages drawn in the routes figure")
    record_run: int = Field(0, ge=0, description="run written to recording.rrd")
    recording: bool = True
    figures: bool = True
    histogram_bin_m: float = Field(1.0, gt=0)
    histogram_max_m: float = Field(150.0, gt=0)
    consistency_probability: float = Field(0.95, gt=0, lt=1)
    consistency_min_fraction: float = Field(
        0.9, gt=0, le=1, description="fraction of steps in band to call the filter consistent"
    )


BLOCK_PASSAGE_TICKS = 600_000
"""The work of a default block, passage-ticks (see :class:`RunnerConfig`)."""


def block_passages(scn: Paper000Scenario) -> int:
    """Passages per block: ``runner.block_size``, or by work (:data:`BLOCK_PASSAGE_TICKS`)."""
    return block_by_work(scn.runner.block_size, scn.passage.n_ticks - 1, BLOCK_PASSAGE_TICKS)


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int | None = Field(
        None,
        ge=1,
        le=100_000,
        description=(
            "passages per block; default: sized by work, as many passages as make "
            f"{BLOCK_PASSAGE_TICKS:,} passage-ticks (1,000 passages of the paper's 600 ticks), "
            "enough to amortise numpy's per-call cost and small enough to stay in memory"
        ),
    )


class Paper000Scenario(Config):
    """Scenario of seed 000's tests."""

    passage: StraightPassageConfig = Field(default_factory=StraightPassageConfig)
    transceiver: TransceiverConfig = Field(default_factory=TransceiverConfig)
    sensors: Paper000Sensors = Field(default_factory=Paper000Sensors)
    filter: FilterConfig = Field(default_factory=FilterConfig)
    initial_error: InitialErrorConfig = Field(default_factory=InitialErrorConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)

    @model_validator(mode="after")
    def _timing(self) -> Paper000Scenario:
        tick = self.passage.tick_s
        for name in ("ins", "log", "pressure"):
            period = getattr(self.sensors, name).period_s
            if abs(period - tick) > 1e-9 * tick:
                raise ValueError(
                    f"sensors.{name}.period_s = {period:g}: the dead-reckoning inputs must be "
                    f"sampled every tick (passage.tick_s = {tick:g} s)"
                )
        check_multiple(self.sensors.usbl.period_s, tick, "sensors.usbl.period_s")
        usbl, default = self.sensors.usbl, UsblConfig()
        for name in LATENCY_FIELDS:
            value = getattr(usbl, name)
            if value != getattr(default, name):
                raise ValueError(
                    f"sensors.usbl.{name} = {value:g}: not used by seed 000's passage, which "
                    "applies each fix at its time of validity as the paper does (no latency); "
                    f"leave it at {getattr(default, name):g}, or fly a mission (mission/*), "
                    "where fixes arrive after the travel time and the processing delay"
                )
        return self


# ----------------------------------------------------------------------------------------------
# Simulation of a set of passages


def _track_distance(pos: NDArray[np.float64], ref: NDArray[np.float64]) -> NDArray[np.float64]:
    """Horizontal distance of tracks to the reference, ``sqrt(de^2 + dn^2)``, shape (n, T + 1), m.

    Args:
        pos: positions, shape (n, T + 1, 3), m: a view of time-major (T + 1, 3, n) tracks.
        ref: the reference, shape (T + 1, 3), m.

    A few dozen ticks at a time on the time-major layout, so the temporaries stay in cache (the
    numbers of :func:`nav.metrics.horizontal_distance` to rounding: a square root of the sum of
    squares rather than ``hypot``, 5x faster).
    """
    tm = pos.transpose(1, 2, 0)  # (T + 1, 3, n)
    out = np.empty(tm.shape[::2])
    for a in range(0, len(out), TIME_CHUNK):
        b = a + TIME_CHUNK
        de = tm[a:b, 0] - ref[a:b, 0, None]
        dn = tm[a:b, 1] - ref[a:b, 1, None]
        de *= de
        dn *= dn
        de += dn
        np.sqrt(de, out=out[a:b])
    return out.T


@dataclass(frozen=True)
class Passages:
    """Everything about some passages (runs) of a batch.

    Attributes:
        runs: run indices, length n.
        truth: the reference motion (run axis 1).
        t_fix_s: USBL fix times, shape (k,), s.
        fix_tick: tick index of each fix, shape (k,).
        ekf_m: EKF positions, shape (n, T + 1, 3), m, world (a view of time-major tracks).
        ekf_Pp: EKF covariances' upper triangles, shape (T + 1, 6, n), m^2, in the order of
            :data:`nav.track_ekf.SYM` (:attr:`ekf_P` gives the full matrices).
        dr_m: DR positions, shape (n, T + 1, 3), m, world.
        usbl_m: USBL-only fixes, shape (n, k, 3), m, world; meaningless where not produced.
        usbl_produced: shape (n, k).
        nis: NIS of each USBL update, shape (n, k) (NaN where none).
        gate_rejected: shape (n, k).
    """

    runs: tuple[int, ...]
    truth: Truth
    t_fix_s: NDArray[np.float64]
    fix_tick: NDArray[np.intp]
    ekf_m: NDArray[np.float64]
    ekf_Pp: NDArray[np.float64]
    dr_m: NDArray[np.float64]
    usbl_m: NDArray[np.float64]
    usbl_produced: NDArray[np.bool_]
    nis: NDArray[np.float64]
    gate_rejected: NDArray[np.bool_]

    @property
    def reference_m(self) -> NDArray[np.float64]:
        """Reference positions, shape (T + 1, 3), m."""
        return self.truth.pos_world_m[0]

    def distances(self) -> dict[str, NDArray[np.float64]]:
        """Distance to the reference: EKF and DR horizontal (n, T + 1), USBL 3-D (n, k)."""
        ref = self.reference_m
        return {
            "EKF": _track_distance(self.ekf_m, ref),
            "DR": _track_distance(self.dr_m, ref),
            "USBL": distance_3d(self.usbl_m, ref[self.fix_tick]),
        }

    @property
    def ekf_P(self) -> NDArray[np.float64]:
        """EKF covariances, shape (n, T + 1, 3, 3), m^2 (built on each call)."""
        return unpack(self.ekf_Pp)

    def ekf_nees(self) -> NDArray[np.float64]:
        """NEES of the EKF (3-D state), shape (n, T + 1)."""
        xs, Pp, ref = self.ekf_m.transpose(1, 2, 0), self.ekf_Pp, self.reference_m  # time-major
        out = np.empty(xs.shape[::2])
        for a in range(0, len(out), TIME_CHUNK):  # a few dozen ticks at a time: in the cache
            b = a + TIME_CHUNK
            err = np.moveaxis(xs[a:b] - ref[a:b, :, None], 1, 0)  # (3, ticks, n)
            out[a:b] = nees_packed(err, np.moveaxis(Pp[a:b], 1, 0))
        return out.T


def _hold_last(values: NDArray[np.float64], produced: NDArray[np.bool_], what: str):
    """Fill absent samples with the last produced one (the first ones with the first produced)."""
    if produced.all():
        return values
    if not produced.any(axis=1).all():
        raise ConfigError(f"{what}: a run produced no measurement at all (dropout probability?)")
    idx = np.where(produced, np.arange(values.shape[1]), -1)
    idx = np.maximum.accumulate(idx, axis=1)
    first = produced.argmax(axis=1)
    idx = np.where(idx < 0, first[:, None], idx)
    return np.take_along_axis(values, idx, axis=1)


@dataclass(frozen=True)
class PassageInputs:
    """What the estimators of some passages receive (no truth except the start for DR/EKF).

    Attributes:
        truth: the reference motion (run axis 1), for scoring only.
        u: DR inputs (course rad, speed m/s, depth change m) of each step, shape (n, T, 3).
        fix_tick: tick index of each USBL fix, shape (k,).
        z: USBL measurements (r, alpha, beta), shape (n, k, 3).
        z_produced: shape (n, k).
        x0: initial estimates, shape (n, 3), m, world.
        P0: initial covariance, shape (3, 3), m^2.
        motion: the filter's motion model.
        usbl: the filter's USBL model.
    """

    truth: Truth
    u: NDArray[np.float64]
    fix_tick: NDArray[np.intp]
    z: NDArray[np.float64]
    z_produced: NDArray[np.bool_]
    x0: NDArray[np.float64]
    P0: NDArray[np.float64]
    motion: CourseSpeedDepthMotion
    usbl: UsblMeasurement


def measure_passages(scn: Paper000Scenario, seed: int, runs: tuple[int, ...]) -> PassageInputs:
    """Sample the sensors along the reference passage for some runs (seed 000 section 6).

    Every run draws from its own streams, so a run's numbers do not depend on the other runs.
    """
    truth = straight_passage(scn.passage, scn.transceiver)
    n, n_ticks, tick = len(runs), scn.passage.n_ticks, scn.passage.tick_s
    steps = np.arange(n_ticks - 1)
    s = scn.sensors
    course = Compass(s.ins, seed, runs, "ins").sample(truth, steps)
    speed = Log(s.log, seed, runs, "log").sample(truth, steps)
    dz = Pressure(s.pressure, seed, runs, "pressure").sample(truth, steps + 1, previous=steps)
    u = np.stack(
        [
            _hold_last(course.values, course.produced, "sensors.ins"),
            _hold_last(speed.values, speed.produced, "sensors.log"),
            _hold_last(dz.values, dz.produced, "sensors.pressure"),
        ],
        axis=-1,
    )
    tx = scn.transceiver.position_world_m()
    fix_tick = periodic_indices(n_ticks, round(s.usbl.period_s / tick))
    fixes = Usbl(s.usbl, tx, seed, runs, "usbl").sample(truth, fix_tick)
    f = scn.filter
    motion = CourseSpeedDepthMotion(
        math.radians(f.sigma_course_deg), f.sigma_speed_m_s, f.sigma_depth_change_m
    )
    usbl_model = UsblMeasurement(
        tx,
        f.sigma_range_m,
        math.radians(f.sigma_azimuth_deg),
        math.radians(f.sigma_elevation_deg),
        f.azimuth_min_horizontal_m,
    )
    P0 = f.P0()
    x0 = np.broadcast_to(truth.pos_world_m[0, 0], (n, 3)).copy()
    if scn.initial_error.distribution == "gaussian":
        L = np.linalg.cholesky(P0)
        draws = rng_mod.RunStreams(seed, runs, "initial").draw("standard_normal", 3)
        x0 = x0 + draws @ L.T
    return PassageInputs(
        truth, u, fix_tick, fixes.values, fixes.produced, x0, P0, motion, usbl_model
    )


def run_ekf(
    inp: PassageInputs,
    tick_s: float,
    gate_probability: float | None = None,
    steps: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> Tracks:
    """The EKF of eq. 15-23 over the passages, batched over runs
    (:func:`nav.track_ekf.ekf_tracks`: F = I, so a prediction adds the step's displacement and
    process noise, computed for all steps in one pass).

    Args:
        inp: the passages' inputs.
        tick_s: step duration, s.
        gate_probability: the chi-square gate, or None.
        steps: ``inp.motion.increment_and_packed_Q(inp.u, tick_s)`` if already computed.

    Returns:
        The tracks: states (T + 1, 3, n) and packed covariances (T + 1, 6, n), time-major.
    """
    inc, Q = inp.motion.increment_and_packed_Q(inp.u, tick_s) if steps is None else steps
    limits = None
    if gate_probability is not None:
        limits = np.array([np.inf, *(gate_limit(gate_probability, d) for d in (1, 2, 3))])
    return ekf_tracks(inp.x0, inp.P0, inc, Q, inp.fix_tick, inp.z, inp.z_produced, inp.usbl, limits)


def simulate_passages(scn: Paper000Scenario, seed: int, runs: tuple[int, ...]) -> Passages:
    """Simulate measurements and run DR, the EKF and USBL-only fixes for some runs.

    Args:
        scn: the scenario.
        seed: batch seed.
        runs: run indices.

    Returns:
        The passages.
    """
    inp = measure_passages(scn, seed, runs)
    tick = scn.passage.tick_s
    # DR and the EKF's predictions add the same displacements (eq. 8 and 17), computed once
    steps = inp.motion.increment_and_packed_Q(inp.u, tick)
    dr = np.empty((steps[0].shape[0] + 1, 3, len(runs)))  # time-major, as the EKF's states
    dr[0] = inp.x0.T
    np.cumsum(steps[0], axis=0, out=dr[1:])
    dr[1:] += dr[0]
    tracks = run_ekf(inp, tick, scn.filter.gate_probability, steps)
    truth = inp.truth
    return Passages(
        runs,
        truth,
        truth.t_s[inp.fix_tick],
        inp.fix_tick,
        tracks.positions(),
        tracks.Ps,
        dr.transpose(2, 0, 1),
        inp.usbl.invert(inp.z),
        inp.z_produced,
        tracks.nis,
        tracks.rejected,
    )


# ----------------------------------------------------------------------------------------------
# Block reduction


@store.plain_data("paper000.Paper000Block")
@dataclass
class Paper000Block:
    """What a block of passages contributes to the report (no full paths except a few).

    Attributes:
        runs: run indices of the block.
        zeta: method -> sum over runs of the distance at each tick (EKF, DR: T + 1; USBL: k).
        nees_ekf: sum over runs of the EKF NEES at each tick.
        nis: sum over runs of the NIS at each fix.
        per_run: shape (n, 3 methods, 3 (min, max, mean)), m.
        hist: method -> histogram of the distances (ticks 1..T, fixes).
        routes: run -> method -> positions (float32) for runs below ``routes_max``.
        single: run -> method -> distance series for runs below ``single_passages``.
        fixes_produced: number of USBL fixes produced.
        fixes_expected: number of USBL fixes scheduled.
        gate_rejected: number of fixes the gate rejected.
        ekf_sigma_h: sum over runs of the EKF's own horizontal standard deviation
            ``sqrt(P_ee + P_nn)`` at each tick, m (its 1-sigma radius, for the figures).
    """

    runs: tuple[int, ...]
    zeta: dict[str, SeriesSum]
    nees_ekf: SeriesSum
    nis: SeriesSum
    per_run: NDArray[np.float64]
    hist: dict[str, Histogram]
    routes: dict[int, dict[str, NDArray[np.float32]]] = field(default_factory=dict)
    single: dict[int, dict[str, NDArray[np.float64]]] = field(default_factory=dict)
    fixes_produced: int = 0
    fixes_expected: int = 0
    gate_rejected: int = 0
    ekf_sigma_h: SeriesSum | None = None


def _ekf_sigma_h(Pp: NDArray[np.float64]) -> NDArray[np.float64]:
    """The horizontal 1-sigma radius ``sqrt(P_ee + P_nn)`` of packed covariance tracks
    (T + 1, 6, ...), shape (T + 1, ...), m."""
    return np.sqrt(np.maximum(Pp[:, 0] + Pp[:, 3], 0.0))


def _edges(cfg: ReportConfig) -> NDArray[np.float64]:
    return np.arange(0.0, cfg.histogram_max_m + cfg.histogram_bin_m / 2, cfg.histogram_bin_m)


def reduce_block(scn: Paper000Scenario, p: Passages) -> Paper000Block:
    """Reduce simulated passages to the block's statistics."""
    d = p.distances()
    prod = p.usbl_produced
    edges = _edges(scn.report)
    per_run = np.stack(
        [
            batch_stats(d[name], prod) if name == "USBL" else batch_stats(d[name][:, 1:])
            for name in METHODS
        ],
        axis=1,
    )
    block = Paper000Block(
        runs=p.runs,
        zeta={
            "EKF": SeriesSum.of(d["EKF"]),
            "DR": SeriesSum.of(d["DR"]),
            "USBL": SeriesSum.of(d["USBL"], prod),
        },
        nees_ekf=SeriesSum.of(p.ekf_nees()),
        nis=SeriesSum.of(p.nis, np.isfinite(p.nis)),
        per_run=per_run,
        hist={
            "EKF": Histogram.of(d["EKF"][:, 1:], edges),
            "DR": Histogram.of(d["DR"][:, 1:], edges),
            "USBL": Histogram.of(d["USBL"], edges, prod),
        },
        fixes_produced=int(prod.sum()),
        fixes_expected=int(prod.size),
        gate_rejected=int(p.gate_rejected.sum()),
        ekf_sigma_h=SeriesSum.of(_ekf_sigma_h(p.ekf_Pp).T),
    )
    for i, run in enumerate(p.runs):
        if run < scn.report.routes_max:
            block.routes[run] = {
                "EKF": p.ekf_m[i].astype(np.float32),
                "DR": p.dr_m[i].astype(np.float32),
                "USBL": p.usbl_m[i][prod[i]].astype(np.float32),
            }
        if run < scn.report.single_passages:
            block.single[run] = {
                "EKF": d["EKF"][i],
                "DR": d["DR"][i],
                "USBL": np.where(prod[i], d["USBL"][i], np.nan),
                "EKF_sigma_h": _ekf_sigma_h(p.ekf_Pp[:, :, i]),
            }
    return block


# ----------------------------------------------------------------------------------------------
# Metrics file


class MethodStats(BaseModel):
    """Minimum, maximum and mean distance to the reference position, m."""

    min_m: float | None
    max_m: float | None
    mean_m: float | None


class SinglePassage(BaseModel):
    """Statistics of one passage."""

    run: int
    methods: dict[str, MethodStats]
    paper_table: str | None = None
    paper: dict[str, MethodStats] | None = None


class Consistency(BaseModel):
    """EKF consistency: average NEES over the runs against its chi-square band."""

    nees_dim: int
    n_runs: int
    probability: float
    band_low: float
    band_high: float
    fraction_in_band: float = Field(description="fraction of ticks 1..T with the mean NEES in band")
    mean_nees: float
    consistent: bool
    note: str


class ErrorDraw(BaseModel):
    """How a simulated error compares with what the filter assumes."""

    quantity: str
    distribution: str
    simulated_std: float
    filter_sigma: float
    ratio: float


class Paper000Metrics(BaseModel):
    """``metrics.json`` of ``paper-000/test-*`` (schema in ``docs/schemas/``)."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    usbl_period_s: float
    passages: dict[str, MethodStats] = Field(
        description="min / max / mean over ticks 1..T of zeta(k), the mean over runs (eq. 24)"
    )
    paper_table: str | None = Field(
        description="the paper's table of this test, or null when the scenario is not the "
        "paper's setting (see paper_setting)"
    )
    paper: dict[str, MethodStats] | None
    mean_ratio_to_paper: dict[str, float | None] = Field(
        description="mean distance over the paper's; null when the method has no data or the "
        "scenario is not the paper's setting"
    )
    paper_setting: str = Field(
        description="'paper' when the scenario is the paper's setting (report and runner "
        "fields aside), else the fields that differ"
    )
    no_data: dict[str, str] = Field(
        description="methods without a single sample, each with the reason (their statistics "
        "are null)"
    )
    single_passages: list[SinglePassage]
    per_run_mean_m: dict[str, MethodStats] = Field(
        description="min / max / mean over runs of each run's mean distance"
    )
    consistency: Consistency
    error_draws: list[ErrorDraw]
    usbl_fix_availability: float
    gate_rejections: int


def _stats(mn: float, mx: float, mean: float) -> MethodStats:
    def clean(v: float) -> float | None:
        return None if not np.isfinite(v) else float(v)

    return MethodStats(min_m=clean(mn), max_m=clean(mx), mean_m=clean(mean))


def _error_draws(scn: Paper000Scenario) -> list[ErrorDraw]:
    s, f = scn.sensors, scn.filter
    rows = [
        ("COG (deg)", s.ins.heading, f.sigma_course_deg),
        ("SOG (m/s)", s.log.speed, f.sigma_speed_m_s),
        ("dz (m)", s.pressure.depth, f.sigma_depth_change_m),
        ("r (m)", s.usbl.range, f.sigma_range_m),
        ("alpha (deg)", s.usbl.azimuth, f.sigma_azimuth_deg),
        ("beta (deg)", s.usbl.elevation, f.sigma_elevation_deg),
    ]
    out = []
    for name, cfg, sigma in rows:
        std = cfg.to_model().noise_std / cfg.unit_to_si
        out.append(
            ErrorDraw(
                quantity=name,
                distribution=cfg.distribution,
                simulated_std=std,
                filter_sigma=sigma,
                ratio=std / sigma,
            )
        )
    return out


# ----------------------------------------------------------------------------------------------
# The experiment


def _paper_stats(rows: dict[str, PaperRow]) -> dict[str, MethodStats]:
    return {k: _stats(*v) for k, v in rows.items()}


@dataclass(frozen=True)
class StraightPassageExperiment(Experiment):
    """Seed 000 test: N passages with USBL fixes every ``usbl_period_s``."""

    scenario_type = Paper000Scenario
    metrics_type = Paper000Metrics
    test: str = "test-1"

    def block_size(self, scenario: Paper000Scenario) -> int:
        return block_passages(scenario)

    def check(self, scenario: Paper000Scenario, n_runs: int) -> None:
        if scenario.report.record_run >= n_runs:
            raise ConfigError(
                f"report.record_run = {scenario.report.record_run}: must be < runs = {n_runs}"
            )

    def run_block(self, scenario: Paper000Scenario, seed: int, runs: tuple[int, ...]):
        return reduce_block(scenario, simulate_passages(scenario, seed, runs))

    def memory(self, scenario: Paper000Scenario, n_runs: int) -> list[MemoryTerm]:
        """Estimated peak memory of a batch, bytes, in parts (see :class:`MemoryTerm`).

        A block holds every passage's paths for every tick (:data:`BLOCK_BYTES_PER_RUN_TICK`),
        and its histograms; the report holds the per-tick sums of every method, the routes and
        single passages it draws, the histograms and a few numbers per run.
        """
        p, rep = scenario.passage, scenario.report
        ticks = p.duration_s / p.tick_s + 1
        block = min(block_passages(scenario), n_runs)
        bins = rep.histogram_max_m / rep.histogram_bin_m
        timing = (
            f"passage.duration_s = {p.duration_s:g} with passage.tick_s = {p.tick_s:g} s "
            f"({ticks:.3g} ticks)"
        )
        paths = min(rep.routes_max, n_runs) * 36 + rep.single_passages * 24 + 160
        return [
            MemoryTerm(
                BLOCK_BYTES_PER_RUN_TICK * block * ticks,
                True,
                f"{timing} in blocks of runner.block_size = {block} passages",
            ),
            MemoryTerm(paths * ticks, False, timing),
            MemoryTerm(
                2 * len(METHODS) * 8 * bins,
                True,
                f"report.histogram_bin_m = {rep.histogram_bin_m:g} ({bins:.3g} bins up to "
                f"report.histogram_max_m = {rep.histogram_max_m:g})",
            ),
            MemoryTerm(110.0 * n_runs, False, f"runs = {n_runs}"),
        ]

    def off_paper_fields(self, scenario: Paper000Scenario) -> list[str]:
        """The scenario fields that differ from the paper's setting of this test.

        The ``report`` and ``runner`` sections do not change the numbers and are left out. The
        paper's tables are compared (labelled, with a ratio) only when this list is empty.

        Returns:
            Dotted field names, sorted.
        """
        paper = _flat(to_plain(load_config(Paper000Scenario, self.preset)))
        mine = _flat(to_plain(scenario))
        return sorted(
            k
            for k in set(paper) | set(mine)
            if k.split(".")[0] not in ("report", "runner") and paper.get(k) != mine.get(k)
        )

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_paper000(self, ctx)


def _flat(data: dict, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for k, v in data.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _no_data_reasons(scn: Paper000Scenario, tot: Paper000Block) -> dict[str, str]:
    """Why a method has no sample at all (only the USBL can have none: EKF and DR always have a
    position)."""
    reasons = {}
    if not np.any(tot.zeta["USBL"].count > 0):
        usbl = scn.sensors.usbl
        reasons["USBL"] = (
            f"no USBL fix was produced in {tot.fixes_expected} attempts (the vehicle stays beyond "
            f"sensors.usbl.max_range_m = {usbl.max_range_m:g} m or below "
            f"sensors.usbl.min_elevation_deg = {usbl.min_elevation_deg:g}, or every fix dropped "
            "out)"
        )
    return reasons


def _per_run_stats(values: NDArray[np.float64]) -> MethodStats:
    """Min / max / mean over runs of each run's mean distance, ignoring runs without data."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return MethodStats(min_m=None, max_m=None, mean_m=None)
    return _stats(float(v.min()), float(v.max()), float(v.mean()))


def _merge_blocks(ctx: ReportContext) -> Paper000Block:
    """The blocks summed in block order (so the sums are the same whatever the block layout of a
    resume). Linear in the number of blocks: the per-run arrays are gathered and concatenated
    once, the accumulators of fixed size are summed pairwise."""
    total: Paper000Block | None = None
    runs: list[tuple[int, ...]] = []
    per_run: list[NDArray[np.float64]] = []
    for b in ctx.blocks:
        runs.append(b.runs)
        per_run.append(b.per_run)
        if total is None:
            total = b
            continue
        total = Paper000Block(
            runs=(),
            zeta={k: total.zeta[k].merge(b.zeta[k]) for k in METHODS},
            nees_ekf=total.nees_ekf.merge(b.nees_ekf),
            nis=total.nis.merge(b.nis),
            per_run=per_run[0],
            hist={k: total.hist[k].merge(b.hist[k]) for k in METHODS},
            routes={**total.routes, **b.routes},
            single={**total.single, **b.single},
            fixes_produced=total.fixes_produced + b.fixes_produced,
            fixes_expected=total.fixes_expected + b.fixes_expected,
            gate_rejected=total.gate_rejected + b.gate_rejected,
            ekf_sigma_h=None
            if total.ekf_sigma_h is None or b.ekf_sigma_h is None
            else total.ekf_sigma_h.merge(b.ekf_sigma_h),
        )
    if total is None:
        raise ValueError("no blocks to report")
    return dataclasses.replace(
        total,
        runs=tuple(r for block in runs for r in block),
        per_run=np.concatenate(per_run) if len(per_run) > 1 else per_run[0],
    )


def report_paper000(exp: StraightPassageExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables, figures, metrics and the recording of a seed 000 test."""
    scn: Paper000Scenario = ctx.scenario  # type: ignore[assignment]
    lo, hi = nees_band(3, ctx.n_runs, scn.report.consistency_probability)
    tot = _merge_blocks(ctx)
    ref = PAPER_TABLES[exp.test]
    truth = straight_passage(scn.passage, scn.transceiver)
    n_ticks = scn.passage.n_ticks
    fix_tick = periodic_indices(n_ticks, round(scn.sensors.usbl.period_s / scn.passage.tick_s))
    zeta = {k: tot.zeta[k].mean() for k in METHODS}
    zeta_window = {"EKF": zeta["EKF"][1:], "DR": zeta["DR"][1:], "USBL": zeta["USBL"]}
    passages = {
        k: _stats(*(lambda s: (s.min, s.max, s.mean))(series_stats(v, np.isfinite(v))))
        for k, v in zeta_window.items()
    }
    no_data = _no_data_reasons(scn, tot)
    off_paper = exp.off_paper_fields(scn)
    on_paper = not off_paper
    paper_name, paper_rows = ref["hundred"]  # type: ignore[misc]
    ratio: dict[str, float | None] = {
        k: float(passages[k].mean_m / paper_rows[k][2])
        if on_paper and passages[k].mean_m is not None
        else None
        for k in METHODS
    }
    singles = []
    for run in sorted(tot.single):
        d = tot.single[run]
        methods = {}
        for k in METHODS:
            v = d[k] if k == "USBL" else d[k][1:]
            st = series_stats(v, np.isfinite(v))
            methods[k] = _stats(st.min, st.max, st.mean)
        tab = (
            ref["single"][run]  # type: ignore[index]
            if on_paper and run < len(ref["single"])  # type: ignore[arg-type]
            else None
        )
        singles.append(
            SinglePassage(
                run=run,
                methods=methods,
                paper_table=tab[0] if tab else None,
                paper=_paper_stats(tab[1]) if tab else None,
            )
        )
    per_run_mean = {k: _per_run_stats(tot.per_run[:, m, 2]) for m, k in enumerate(METHODS)}
    # consistency of the EKF
    mean_nees = tot.nees_ekf.mean()
    window = mean_nees[1:]
    frac = float(np.mean((window >= lo) & (window <= hi)))
    consistent = frac >= scn.report.consistency_min_fraction
    draws = _error_draws(scn)
    mismatched = [d for d in draws if abs(d.ratio - 1.0) > 0.05]
    if consistent:
        note = "consistent: the mean NEES stays inside its chi-square band"
    elif mismatched:
        what = ", ".join(f"{d.quantity} std {d.ratio:.2f}x the filter's sigma" for d in mismatched)
        note = (
            "inconsistent: the filter is mis-tuned for the simulated errors (" + what + "); "
            "seed 000 draws errors uniform on +-3 sigma, whose standard deviation is "
            "sqrt(3) sigma"
        )
    else:
        note = (
            "inconsistent although the simulated errors match the filter's sigmas: "
            "linearisation or the initial covariance dominate"
        )
    consistency = Consistency(
        nees_dim=3,
        n_runs=ctx.n_runs,
        probability=scn.report.consistency_probability,
        band_low=lo,
        band_high=hi,
        fraction_in_band=frac,
        mean_nees=float(np.mean(window)),
        consistent=consistent,
        note=note,
    )
    metrics = Paper000Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        usbl_period_s=scn.sensors.usbl.period_s,
        passages=passages,
        paper_table=paper_name if on_paper else None,
        paper=_paper_stats(paper_rows) if on_paper else None,
        mean_ratio_to_paper=ratio,
        paper_setting="paper" if on_paper else ", ".join(off_paper),
        no_data=no_data,
        single_passages=singles,
        per_run_mean_m=per_run_mean,
        consistency=consistency,
        error_draws=draws,
        usbl_fix_availability=tot.fixes_produced / max(tot.fixes_expected, 1),
        gate_rejections=tot.gate_rejected,
    )
    files = [write_metrics(ctx.out_dir, metrics)]

    # tables in the paper's layout, with the paper's values beside
    cols = [
        "Positioning method",
        "Minimum distance (m)",
        "Maximum distance (m)",
        "Average distance (m)",
        "Paper min",
        "Paper max",
        "Paper average",
    ]
    if not on_paper:
        cols = cols[:4]
    no_data_note = "".join(f"\n{k}: no data: {why}." for k, why in no_data.items())
    off_note = (
        ""
        if on_paper
        else f"Not the paper's setting (changed: {', '.join(off_paper)}): no comparison with the "
        "paper's tables."
    )
    tables = []
    for sp in singles:
        rows = []
        for k in METHODS:
            paper = sp.paper[k] if sp.paper else MethodStats(min_m=None, max_m=None, mean_m=None)
            rows.append(
                [
                    k,
                    sp.methods[k].min_m,
                    sp.methods[k].max_m,
                    sp.methods[k].mean_m,
                    paper.min_m,
                    paper.max_m,
                    paper.mean_m,
                ][: len(cols)]
            )
        title = f"Single passage {sp.run + 1}" + (
            f" (paper: {sp.paper_table})" if sp.paper_table else ""
        )
        tables.append(
            Table(
                title,
                cols,
                rows,
                slug=f"single-passage-{sp.run + 1}",
                note=(off_note + no_data_note).strip(),
            )
        )
    rows = [
        [k, passages[k].min_m, passages[k].max_m, passages[k].mean_m, *paper_rows[k]][: len(cols)]
        for k in METHODS
    ]
    ratio_note = (
        "Mean ratio to the paper: "
        + ", ".join(f"{k} {ratio[k]:.2f}" for k in METHODS if ratio[k] is not None)
        + "".join(f", {k} none (no data)" for k in METHODS if ratio[k] is None)
        if on_paper
        else off_note
    )
    main = Table(
        f"{ctx.n_runs} passages: statistics of zeta(k)"
        + (f" (paper: {paper_name}, 100 passages)" if on_paper else ""),
        cols,
        rows,
        slug="passages",
        note=ratio_note + no_data_note,
    )
    tables.append(main)
    tables.append(
        Table(
            "Simulated errors against the filter's assumptions",
            ["Quantity", "Draw", "Simulated std", "Filter sigma", "Ratio"],
            [[d.quantity, d.distribution, d.simulated_std, d.filter_sigma, d.ratio] for d in draws],
            digits=3,
            slug="error-draws",
        )
    )
    tables.append(
        Table(
            "EKF consistency (average NEES over runs, 3-D state)",
            ["Runs", "Band low", "Band high", "Fraction of ticks in band", "Mean NEES", "Verdict"],
            [
                [
                    ctx.n_runs,
                    lo,
                    hi,
                    frac,
                    consistency.mean_nees,
                    "consistent" if consistent else "inconsistent",
                ]
            ],
            digits=3,
            slug="consistency",
            note=note,
        )
    )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")

    if scn.report.figures:
        files += _figures(exp, ctx, scn, tot, truth, zeta, fix_tick, mean_nees, (lo, hi))
    if scn.report.recording:
        files.append(record_passage(exp, scn, ctx.seed, scn.report.record_run, ctx.out_dir))
    text = main.to_text() + "\n" + tables[-1].to_text()
    text += f"\nwrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _test_words(exp: StraightPassageExperiment) -> str:
    """The test's name in words: ``"Seed 000 Test 1 (USBL fix every 5 s)"``."""
    n = exp.test.split("-")[-1]
    return f"Seed 000 Test {n}"


def _figures(exp, ctx, scn, tot, truth, zeta, fix_tick, mean_nees, band) -> list[str]:
    """The test's figures (PNG and PDF), for any valid batch: one run, no route kept."""
    out = ctx.out_dir
    t = truth.t_s
    ref = truth.pos_world_m[0]
    tx = scn.transceiver.position_world_m()
    words = f"{_test_words(exp)}, USBL fix every {scn.sensors.usbl.period_s:g} s"
    n = ctx.n_runs
    passages = f"{n} passage{'s' * (n != 1)}"
    k = 2.0
    files: list[str] = []
    runs = sorted(tot.routes)
    if runs:
        files += figures.routes(
            out / "routes.png",
            ref,
            {
                "DR": [tot.routes[r]["DR"] for r in runs],
                "EKF": [tot.routes[r]["EKF"] for r in runs],
            },
            {"USBL": [tot.routes[r]["USBL"] for r in runs]},
            {"transceiver": tx},
            title=f"{words}: routes of {len(runs)} passage{'s' * (len(runs) != 1)}",
        )
    bounds = {}
    if tot.ekf_sigma_h is not None:
        bounds["EKF"] = (t[1:], k * tot.ekf_sigma_h.mean()[1:], f"EKF {k:g}$\\sigma$ radius")
    files += figures.distances(
        out / "distance.png",
        {
            "EKF": (t[1:], zeta["EKF"][1:]),
            "DR": (t[1:], zeta["DR"][1:]),
            "USBL": (t[fix_tick], zeta["USBL"]),
        },
        title=f"{words}: mean distance to the reference over {passages}",
        bounds=bounds,
    )
    for run in sorted(tot.single):
        d = tot.single[run]
        sb = {}
        if "EKF_sigma_h" in d:
            sb["EKF"] = (t[1:], k * d["EKF_sigma_h"][1:], f"EKF {k:g}$\\sigma$ radius")
        files += figures.distances(
            out / f"distance-passage-{run + 1}.png",
            {
                "EKF": (t[1:], d["EKF"][1:]),
                "DR": (t[1:], d["DR"][1:]),
                "USBL": (t[fix_tick], d["USBL"]),
            },
            title=f"{words}: passage {run + 1}",
            bounds=sb,
        )
    files += figures.histograms(
        out / "histogram.png",
        tot.hist,
        title=f"{words}: distance to the reference, {passages}",
    )
    files += figures.consistency(
        out / "nees.png",
        t[1:],
        mean_nees[1:],
        band,
        3,
        n,
        title=f"{words}: EKF consistency (position NEES)",
        probability=scn.report.consistency_probability,
        method="EKF",
    )
    return files


def record_passage(exp: Experiment, scn: Paper000Scenario, seed: int, run: int, out_dir) -> str:
    """Write ``recording.rrd`` for one passage (re-simulated: identical to its batch numbers).

    The recording holds the reference, DR and EKF tracks (the EKF's covariance ellipsoids), the
    USBL fixes split into those the filter applied and those its gate rejected, the distances,
    the EKF's NEES against the chi-square band of one run and the NIS of each fix, an event log
    (fixes rejected, fixes not produced, the closest approach) and a 3-D view that rides with
    the vehicle (the hull drawn on the reference, heading along the course).
    """
    import rerun as rr
    import rerun.blueprint as rrb

    from bauv_sim.frames import R_from_roll_pitch_heading, quat_wxyz_from_R, quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR

    p = simulate_passages(scn, seed, (run,))
    t = p.truth.t_s
    rec = Recording(out_dir / "recording.rrd", exp.name, f"{exp.name}/seed{seed}/run{run}")
    tx = scn.transceiver.position_world_m()
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    rec.track("truth", t, p.reference_m, COLORS["truth"])
    rec.track("dr", t, p.dr_m[0], COLORS["dr"])
    rec.track("ekf", t, p.ekf_m[0], COLORS["ekf"])
    rec.ellipsoids("ekf", t, p.ekf_m[0], p.ekf_P[0], COLORS["ekf"])
    heading = np.broadcast_to(p.truth.heading_rad, (1, len(t)))[0]
    R = np.stack([R_from_roll_pitch_heading(0.0, 0.0, float(h)) for h in heading])
    rec.rec.send_columns(
        "world/vehicle",
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Transform3D.columns(
            translation=p.reference_m, quaternion=quat_wxyz_to_xyzw(quat_wxyz_from_R(R))
        ),
    )
    rec.rec.log(
        "world/vehicle/hull", rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"), static=True
    )
    ok = p.usbl_produced[0]
    rej = p.gate_rejected[0] & ok
    applied = ok & ~rej
    rec.fixes("usbl/accepted", p.t_fix_s[applied], p.usbl_m[0][applied], COLORS["usbl"])
    rec.fixes("usbl/rejected", p.t_fix_s[rej], p.usbl_m[0][rej], (230, 0, 0))
    rec.scalars(
        "fixes/usbl_accepted",
        p.t_fix_s[ok],
        applied[ok].astype(float),
        COLORS["usbl"],
        "USBL fix applied (1) or rejected by the gate (0)",
    )
    d = p.distances()
    rec.scalars("distance/ekf", t, d["EKF"][0], COLORS["ekf"], "EKF (horizontal, m)")
    rec.scalars("distance/dr", t, d["DR"][0], COLORS["dr"], "DR (horizontal, m)")
    rec.scalars("distance/usbl", p.t_fix_s[ok], d["USBL"][0][ok], COLORS["usbl"], "USBL (3-D, m)")
    rec.scalars("consistency/nees_ekf", t, p.ekf_nees()[0], COLORS["ekf"], "EKF NEES (dof 3)")
    q = scn.report.consistency_probability
    lo, hi = chi2_ppf(np.array([(1 - q) / 2, (1 + q) / 2]), 3)
    for name, val in (("low", lo), ("high", hi)):
        rec.scalars(
            f"consistency/nees_band_{name}",
            t[[0, -1]],
            np.full(2, val),
            (0, 158, 115),
            f"{100 * q:g} % chi-square band, one run ({val:.2f})",
        )
    nis = p.nis[0]
    rec.scalars("consistency/nis_usbl", p.t_fix_s, nis, COLORS["usbl"], "USBL NIS (dof 3)")
    times, texts, levels = [float(t[0])], ["start of the passage"], ["INFO"]
    for k in range(len(p.t_fix_s)):
        if not ok[k]:
            times.append(float(p.t_fix_s[k]))
            texts.append("no USBL fix (range, field of view or dropout)")
            levels.append("WARN")
        elif rej[k]:
            n = f" (NIS {nis[k]:.1f})" if np.isfinite(nis[k]) else ""
            times.append(float(p.t_fix_s[k]))
            texts.append(f"USBL fix rejected by the gate{n}")
            levels.append("WARN")
    kc = int(np.argmin(np.linalg.norm(p.reference_m[:, :2] - tx[:2], axis=1)))
    times.append(float(t[kc]))
    texts.append("closest approach to the transceiver")
    levels.append("INFO")
    times.append(float(t[-1]))
    texts.append("end of the passage")
    levels.append("INFO")
    rec.events("events", times, texts, levels)
    rec.blueprint(
        "distance",
        "consistency",
        "fixes",
        follow="/world/vehicle",
        eye_controls=rrb.EyeControls3D(
            position=[-60.0, 30.0, 40.0], look_target=[0.0, 0.0, 0.0], eye_up=[0.0, 0.0, 1.0]
        ),
        log="events",
        world_name="world (camera rides with the vehicle)",
    )
    rec.close()
    return "recording.rrd"


_SUMMARY = "seed 000 Test {n}: straight passage, USBL fix every {p:g} s; DR vs EKF vs USBL"
for _n, _test in enumerate(("test-1", "test-2", "test-3"), start=1):
    _period = PAPER_TABLES[_test]["usbl_period_s"]
    register(
        StraightPassageExperiment(
            name=f"paper-000/{_test}",
            summary=_SUMMARY.format(n=_n, p=_period),
            preset={"sensors": {"usbl": {"period_s": _period}}},
            default_runs=100,
            test=_test,
        )
    )
