"""A block of ``coop/team`` runs: the team's truth, every vehicle's measurements, the acoustic
network, the :class:`nav.cooperative.TeamRecord` and every method's tracks, reduced.

Per block (its runs batched; each run draws from its own streams, :mod:`bauv_sim.rng`, and its
range ticks come from the scenario alone, so the numbers of run ``i`` do not depend on its block
or worker, bit for bit):

1. the truth (:func:`bauv_sim.kinematic.team.team_truth`), the same for every run;
2. every vehicle's own measurements (:func:`tasks.coop.measure.own_measurements`): the same in
   every sensitivity setting (but the leader's USBL fixes in a setting of the sea's sound, which
   the USBL hears too);
3. per setting, the acoustic network (:class:`bauv_sim.acoustics.AcousticNetwork`: TDMA
   broadcasts, every other vehicle receives, clocks, sonar equation, collisions) on the true
   positions, through the true medium of the setting;
4. the adapter (:func:`team_record`): ranges and stamps with the sample at or before the
   transmission and at or after the reception, from the clock-free instants widened by the
   clocks' bound (the same ticks for every run, whatever the block);
5. every method (:func:`nav.cooperative.team_tracks`) on that record, the same draws;
6. per run, vehicle and method: the horizontal error's mean over the samples and its final value,
   the RMS error of the clock-offset estimate, the ranges used; pooled over the block: the sums of
   the NEES (2 dof) and of the squared error on the curves' grid.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from bauv_sim.acoustics.clock import ClockConfig, draw_clocks
from bauv_sim.acoustics.network import AcousticNetwork, AcousticNetworkConfig, NetworkRanges
from bauv_sim.errors import BauvSimError, ConfigError
from bauv_sim.kinematic.team import TeamTruth, team_truth
from nav.acoustics import Propagation
from nav.cooperative import TeamRecord, team_tracks
from nav.cooperative.metrics import horizontal_errors, position_nees
from nav.errors import NavInputError
from tasks.coop.measure import OwnMeasurements, own_measurements, usbl_fixes
from tasks.coop.scenario import CoopScenario
from tasks.coop.setting import coop_options, network_config, propagation

Array = NDArray[np.float64]

LOSS_CAUSES = ("received", "range", "sonar", "collision", "half-duplex")
"""The network's codes of a lost range (:class:`bauv_sim.acoustics.NetworkRanges`), 0 first."""


GUARD_SIGMAS = 5.0
"""How many standard deviations of the clocks' per-run spread :func:`clock_guard_s` allows."""


def clock_guard_s(
    cfg: AcousticNetworkConfig, vehicles: tuple[str, ...], duration_s: float
) -> float:
    """A bound on how far any vehicle's transmission or stamped reception can be from its clock-free
    instant over a run, s: the largest ``|offset| + G offset_sigma + (|drift| + G drift_sigma)
    duration + G (jitter + travel_time_sigma)`` over the vehicles' clocks (``G`` =
    :data:`GUARD_SIGMAS`). A function of the scenario only."""
    out = 0.0
    for name in vehicles:
        c = cfg.clock_of(name)
        drift = (abs(c.drift_ppm) + GUARD_SIGMAS * c.drift_sigma_ppm) * 1e-6
        out = max(
            out,
            abs(c.offset_s)
            + GUARD_SIGMAS * (c.offset_sigma_s + c.jitter_s + cfg.travel_time_sigma_s)
            + drift * duration_s,
        )
    return out


def nominal_times(
    cfg: AcousticNetworkConfig,
    vehicles: tuple[str, ...],
    medium: Propagation | None,
    t_s: Array,
    positions_world_m: Array,
) -> tuple[Array, Array]:
    """The network's events as perfect clocks would time them (no offset, drift, jitter or
    detection noise; the same schedule, truth and medium): true transmission and reception
    instants per event, ``(t_tx (m,), t_rx (m,))``, s. The truth is shared by the runs, so these
    are the same for every run and every block."""
    quiet = cfg.model_copy(
        update={"clock": ClockConfig(), "clocks": {}, "travel_time_sigma_s": 0.0}
    )
    r = AcousticNetwork(quiet, vehicles, 0, (0,), medium).exchange(t_s, positions_world_m[:, :1])
    return r.t_tx_s[0], r.t_rx_s[0]


def team_record(
    own: OwnMeasurements,
    ranges: NetworkRanges,
    t_s: Array,
    nominal_s: tuple[Array, Array],
    guard_s: float,
    sigma_m: float,
) -> TeamRecord:
    """The adapter: a block's own measurements and network events -> :class:`TeamRecord`.

    A range's ticks are shared by the runs (:class:`nav.cooperative.TeamRecord`), so they come
    from the clock-free instants of its event (:func:`nominal_times`) widened by the clocks'
    bound (:func:`clock_guard_s`): the sample at or before ``t_tx - guard`` and the one at or
    after ``t_rx + guard``. They then bracket the true transmission and reception in every run
    (but for a clock beyond the bound's sigmas) and never depend on which runs share the block.
    A range is present where the network produced it; one received after the last sample is
    left out.
    """
    dt = float(t_s[1] - t_s[0])
    k = len(t_s)
    t_tx, t_rx = nominal_s
    tx = np.floor((t_tx - guard_s) / dt + 1e-9).astype(np.intp)
    rx = np.ceil((t_rx + guard_s) / dt - 1e-9).astype(np.intp)
    keep = rx <= k - 1
    tx = np.clip(tx, 0, k - 1)
    return TeamRecord(
        t_s=t_s,
        dr_step_m=own.dr_step_m,
        dr_step_cov_m2=own.dr_step_cov_m2,
        depth_m=own.depth_m,
        start_m=own.start_m,
        start_cov_m2=own.start_cov_m2,
        fix_tick=own.fix_tick,
        fix_vehicle=np.zeros(len(own.fix_tick), np.intp),
        fix_m=own.fix_m,
        fix_cov_m2=own.fix_cov_m2,
        fix_present=own.fix_present,
        range_sender=np.asarray(ranges.sender, np.intp)[keep],
        range_receiver=np.asarray(ranges.receiver, np.intp)[keep],
        range_tx_tick=tx[keep],
        range_rx_tick=rx[keep],
        range_m=ranges.range_m[:, keep],
        range_tx_local_s=ranges.tx_local_s[:, keep],
        range_rx_local_s=ranges.rx_local_s[:, keep],
        range_present=ranges.produced[:, keep],
        kind=ranges.kind,
        sound_speed_m_s=ranges.sound_speed_m_s,
        sigma_range_m=sigma_m,
    )


def true_offsets(scn: CoopScenario, what: str, value, truth: TeamTruth, seed, runs) -> Array:
    """Every vehicle's true clock offset on the sample grid, (n, v, k), s: the clocks the
    network draws (:func:`bauv_sim.acoustics.draw_clocks`, same streams)."""
    cfg = network_config(scn, what, value)
    out = np.empty((len(runs), len(truth.names), len(truth.t_s)))
    for i, name in enumerate(truth.names):
        clock = draw_clocks(cfg.clock_of(name), seed, runs, name)
        out[:, i] = clock.offset(truth.t_s[None, :])
    return out


def check(scn: CoopScenario) -> None:
    """Build the filters' options once (their own validation), so that bad options are refused
    before a batch starts."""
    coop_options(scn)


def curve_ticks(scn: CoopScenario) -> NDArray[np.intp]:
    """Sample indices of the error curves against time (every ``report.curve_every_s``)."""
    every = max(1, round(scn.report.curve_every_s / scn.team.tick_s))
    return np.arange(0, scn.team.n_ticks, every, dtype=np.intp)


def run_block(scn: CoopScenario, seed: int, runs: tuple[int, ...]) -> dict[str, Array]:
    """A block of runs, every setting and method (module docstring).

    Returns:
        per run (n, S, M, v): ``mean_m``, ``final_m`` horizontal error, m; ``clock_rms_s`` RMS
        error of the clock-offset estimate over the samples, s (0 for a method without clocks);
        ``ranges_used``; summed over the block's runs: ``nees_sum`` (S, M, v) over every sample
        but the start and ``nees_count`` (S, M, v) of the samples with a positive-definite
        covariance (:func:`nav.cooperative.metrics.position_nees`), ``nees_t_sum`` and
        ``nees_t_count`` (S, M, v, C) on the curves' grid, ``sq_err_sum`` (S, M, v, C) m^2;
        per run (n, S): ``produced``, ``scheduled`` range events; ``lost`` (n, S, 5) by cause
        (:class:`bauv_sim.acoustics.network.NetworkRanges`).
    """
    truth = team_truth(scn.team)
    own = own_measurements(scn, truth, seed, runs)
    n, v, k = len(runs), len(truth.names), len(truth.t_s)
    settings = scn.settings()
    methods = scn.methods
    S, M = len(settings), len(methods)
    cticks = curve_ticks(scn)
    out = {
        "runs": np.asarray(runs, np.int64),
        "mean_m": np.zeros((n, S, M, v)),
        "final_m": np.zeros((n, S, M, v)),
        "clock_rms_s": np.zeros((n, S, M, v)),
        "ranges_used": np.zeros((n, S, M, v), np.int64),
        "nees_sum": np.zeros((S, M, v)),
        "nees_count": np.zeros((S, M, v), np.int64),
        "nees_t_sum": np.zeros((S, M, v, len(cticks))),
        "nees_t_count": np.zeros((S, M, v, len(cticks)), np.int64),
        "sq_err_sum": np.zeros((S, M, v, len(cticks))),
        "produced": np.zeros((n, S), np.int64),
        "scheduled": np.zeros((n, S), np.int64),
        "lost": np.zeros((n, S, 5), np.int64),
    }
    pos = truth.positions_world_m  # (v, 1, k, 3)
    pos_n = np.broadcast_to(pos, (v, n, k, 3))
    truth_n = np.broadcast_to(pos[None, :, 0, :, :2], (n, v, k, 2))
    for s, (_, what, value) in enumerate(settings):
        cfg = network_config(scn, what, value)
        medium = propagation(scn, what, value)
        net = AcousticNetwork(cfg, truth.names, seed, runs, medium)
        ranges = net.exchange(truth.t_s, pos_n)
        out["produced"][:, s] = ranges.produced.sum(axis=1)
        out["scheduled"][:, s] = ranges.produced.shape[1]
        for code in range(1, 5):
            out["lost"][:, s, code] = (ranges.lost == code).sum(axis=1)
        meas = own
        if what in ("sound_speed_m_s", "sound_profile"):  # the USBL hears the same sea
            tick, fix, cov, present = usbl_fixes(scn, truth, seed, runs, medium)
            meas = replace(own, fix_tick=tick, fix_m=fix, fix_cov_m2=cov, fix_present=present)
        nominal = nominal_times(cfg, truth.names, medium, truth.t_s, pos)
        guard = clock_guard_s(cfg, truth.names, scn.team.duration_s)
        record = team_record(meas, ranges, truth.t_s, nominal, guard, scn.filters.sigma_range_m)
        offsets = true_offsets(scn, what, value, truth, seed, runs)
        options = coop_options(scn, what, value)
        for m, method in enumerate(methods):
            try:
                tr = team_tracks(record, method, options)
            except NavInputError as exc:
                raise ConfigError(f"{method}: {exc}") from None
            bad = ~(np.isfinite(tr.position_m).all(axis=(1, 2, 3)))
            bad |= ~np.isfinite(tr.cov_m2).all(axis=(1, 2, 3, 4))
            if bad.any():  # NaN never reaches an output: the block fails, --resume retries it
                raise BauvSimError(
                    f"{method}: run {runs[int(np.argmax(bad))]} ({settings[s][0]}) gave a "
                    "non-finite estimate"
                )
            err = horizontal_errors(tr, truth_n)  # (n, v, k)
            out["mean_m"][:, s, m] = err[..., 1:].mean(axis=-1)
            out["final_m"][:, s, m] = err[..., -1]
            out["sq_err_sum"][s, m] = (err[..., cticks] ** 2).sum(axis=0)
            nees_k, ok = position_nees(tr, truth_n)
            nees_k = np.where(ok, nees_k, 0.0)
            out["nees_t_sum"][s, m] = nees_k[..., cticks].sum(axis=0)
            out["nees_t_count"][s, m] = ok[..., cticks].sum(axis=0)
            out["nees_sum"][s, m] = nees_k[..., 1:].sum(axis=(0, 2))
            out["nees_count"][s, m] = ok[..., 1:].sum(axis=(0, 2))
            if tr.has_clock:
                c = tr.clock_offset_s - offsets
                out["clock_rms_s"][:, s, m] = np.sqrt((c**2).mean(axis=-1))
            out["ranges_used"][:, s, m] = tr.ranges_used
    return out
