"""Simulation of a set of seed 000 passages and its reduction to a block: the sensors sampled along
the reference passage, the three navigations of :mod:`nav.usbl` (DR, EKF, USBL alone), and the
statistics a block contributes to the report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.passage import straight_passage
from bauv_sim.sensors import Compass, Log, Pressure, Usbl, periodic_indices
from bauv_sim.truth import Truth
from nav.metrics import Histogram, SeriesSum, batch_stats, distance_3d
from nav.models import CourseSpeedDepthMotion, UsblMeasurement
from nav.usbl import Tracks, horizontal_distance_tm, navigate_passages, nees_tm, passage_ekf, unpack
from nav.usbl import sigma_h as ekf_sigma_h
from tasks.core import store
from tasks.paper000.scenario import Paper000Scenario, ReportConfig

METHODS = ("EKF", "DR", "USBL")
BLOCK_BYTES_PER_RUN_TICK = 200.0
"""Peak memory of :meth:`StraightPassageExperiment.run_block` per passage and tick, bytes:
measured with :mod:`tracemalloc` (201-203 B for 600 and 6000 ticks, 50 and 100 passages, fixes
every 5 s; 194 B with fixes every 100 s): states, covariances, inputs and distances."""

# the block accumulators are plain data (blocks are kept on disk for --resume)
store.plain_data("nav.metrics.SeriesSum")(SeriesSum)
store.plain_data("nav.metrics.Histogram")(Histogram)


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
            :data:`nav.usbl.SYM` (:attr:`ekf_P` gives the full matrices).
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
            "EKF": horizontal_distance_tm(self.ekf_m, ref),
            "DR": horizontal_distance_tm(self.dr_m, ref),
            "USBL": distance_3d(self.usbl_m, ref[self.fix_tick]),
        }

    @property
    def ekf_P(self) -> NDArray[np.float64]:
        """EKF covariances, shape (n, T + 1, 3, 3), m^2 (built on each call)."""
        return unpack(self.ekf_Pp)

    def ekf_nees(self) -> NDArray[np.float64]:
        """NEES of the EKF (3-D state), shape (n, T + 1)."""
        return nees_tm(self.ekf_m.transpose(1, 2, 0), self.ekf_Pp, self.reference_m)


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
    """The EKF of eq. 15-23 over the passages' inputs (:func:`nav.usbl.passage_ekf`).

    Args:
        inp: the passages' inputs.
        tick_s: step duration, s.
        gate_probability: the chi-square gate, or None.
        steps: ``inp.motion.increment_and_packed_Q(inp.u, tick_s)`` if already computed.

    Returns:
        The tracks: states (T + 1, 3, n) and packed covariances (T + 1, 6, n), time-major.
    """
    return passage_ekf(
        inp.x0,
        inp.P0,
        inp.u,
        tick_s,
        inp.fix_tick,
        inp.z,
        inp.z_produced,
        inp.motion,
        inp.usbl,
        gate_probability,
        steps,
    )


def simulate_passages(scn: Paper000Scenario, seed: int, runs: tuple[int, ...]) -> Passages:
    """Simulate measurements and run DR, the EKF and USBL-only fixes for some runs
    (:func:`nav.usbl.navigate_passages`).

    Args:
        scn: the scenario.
        seed: batch seed.
        runs: run indices.

    Returns:
        The passages.
    """
    inp = measure_passages(scn, seed, runs)
    est = navigate_passages(
        inp.x0,
        inp.P0,
        inp.u,
        scn.passage.tick_s,
        inp.fix_tick,
        inp.z,
        inp.z_produced,
        inp.motion,
        inp.usbl,
        scn.filter.gate_probability,
    )
    truth = inp.truth
    return Passages(
        runs,
        truth,
        truth.t_s[inp.fix_tick],
        inp.fix_tick,
        est.ekf.positions(),
        est.ekf.Ps,
        est.dr_m,
        est.usbl_m,
        inp.z_produced,
        est.ekf.nis,
        est.ekf.rejected,
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
        ekf_sigma_h=SeriesSum.of(ekf_sigma_h(p.ekf_Pp).T),
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
                "EKF_sigma_h": ekf_sigma_h(p.ekf_Pp[:, :, i]),
            }
    return block
