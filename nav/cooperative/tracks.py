"""Every navigation method of a team over one :class:`~nav.cooperative.TeamRecord`, batched over
its runs: the comparison of issue 24 on identical data.

Methods (``method`` of :func:`team_tracks`):

* ``"dr"``: each vehicle's dead reckoning from its start (:mod:`nav.dead_reckoning`);
* ``"ga2"``: seed 003's GA2 (:func:`nav.relative.ga_track`) on each follower's ranges from the
  leader only, the range taken as it comes (no clock: the offsets bias it), made horizontal with
  the two depths; the leader navigates on its fixes;
* ``"leader-ekf"``: seed 003's range EKF (:func:`nav.relative.ekf_track`) on the same ranges;
* ``"decentralised"``: one :class:`~nav.cooperative.CoopNavigator` per vehicle, clocks in the
  state, every range fused with the sender's broadcast by covariance intersection (or naively
  with ``CoopOptions.fusion = "naive"``);
* ``"central"``: the :class:`~nav.cooperative.TeamEkf` over the whole team with every range.

The leader's filter in ``ga2``/``leader-ekf`` is its own decentralised navigator with its fixes
and no range; its estimate at a transmission is the broadcast position the followers use, and the
root mean square of its stated sigma is the leader sigma of seed 003's EKF (a scalar there).

Timing. The filters run on the record's sample grid (true time). A range received at sample q
(at or after the reception) is applied there: the receiver's position at the reception is its
state moved back by its DR velocity over ``t_q - t_rx`` and the sender's at the transmission its
state moved back by its DR displacement since ``t_tx`` (centralised), or its broadcast made at
the transmission (decentralised: the sender's estimate at the sample at or before the
transmission, moved ahead by its velocity). True instants come from the stamps with the filter's
clock estimates, ``t = local - b`` (a filter without clocks takes ``b = 0``). The dead
reckoning's noise over those lags (in the state, not in the range) is added to the range's
variance (``extra_var_m2`` of the range models). With ``CoopOptions.relay`` a vehicle's broadcast
carries the one-way ranges it received since its last transmission, each with its estimate at
the reception, and the original sender fuses them too (:mod:`nav.cooperative.decentralised`).

Every method is batched over the runs and gives a run the same numbers whatever the other runs
of its batch (seed 003's EKF takes scalar sigmas: the runs are grouped by their own values).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav import dead_reckoning
from nav.cooperative.decentralised import CoopNavigator, PeerEstimate
from nav.cooperative.record import TeamRecord
from nav.cooperative.team import CoopOptions, TeamEkf
from nav.dead_reckoning import DeadReckonedTrack
from nav.errors import NavInputError
from nav.relative.tracks import LeaderRanges, RangeEkfOptions, ekf_track, ga_track

Array = NDArray[np.float64]

Method = Literal["dr", "ga2", "leader-ekf", "decentralised", "central"]
METHODS: tuple[str, ...] = ("dr", "ga2", "leader-ekf", "decentralised", "central")
"""The methods of :func:`team_tracks`."""


@dataclass(frozen=True)
class TeamTracks:
    """One method's estimates of every vehicle at every sample of every run.

    Attributes:
        method: the method.
        position_m: (east, north), shape (n, v, k, 2), m.
        cov_m2: the method's stated covariance, shape (n, v, k, 2, 2), m^2.
        clock_offset_s: clock offset estimates, shape (n, v, k), s (zeros where the method has
            no clock: ``has_clock`` False).
        clock_var_s2: their variances, shape (n, v, k), s^2 (zeros without clock).
        has_clock: whether the method estimates the clocks.
        ranges_used: ranges each vehicle applied (as receiver), shape (n, v).
    """

    method: str
    position_m: Array
    cov_m2: Array
    clock_offset_s: Array
    clock_var_s2: Array
    has_clock: bool
    ranges_used: NDArray[np.int64]


def team_tracks(record: TeamRecord, method: str, options: CoopOptions | None = None) -> TeamTracks:
    """Run one method over a team's record (the module's methods), batched over runs.

    Args:
        record: the team's measurements.
        method: one of :data:`METHODS`.
        options: the filters' options (default :class:`CoopOptions`).

    Returns:
        The estimates of every vehicle at every sample.

    Raises:
        NavInputError: on an unknown method or a record that is not a :class:`TeamRecord`.
    """
    if not isinstance(record, TeamRecord):
        raise NavInputError(f"record must be a TeamRecord, not {type(record).__name__}")
    if method not in METHODS:
        raise NavInputError(f"method must be one of {', '.join(METHODS)}, not {method!r}")
    opts = CoopOptions() if options is None else options
    if method == "dr":
        return _dr_method(record)
    if method in ("ga2", "leader-ekf"):
        return _leader_only(record, method, opts)
    if method == "central":
        return _central(record, opts)
    return _decentralised(record, opts)


class _Schedule:
    """The record's events grouped by the sample they act at (ranges ordered by reception)."""

    def __init__(self, record: TeamRecord):
        k = record.n_samples
        self.fixes = _group(record.fix_tick, k)
        order = np.lexsort((np.arange(len(record.range_rx_tick)), record.range_rx_tick))
        self.rx = _group(record.range_rx_tick, k, order)
        self.tx = _group(record.range_tx_tick, k)


def _group(ticks: NDArray[np.intp], k: int, order: NDArray[np.intp] | None = None):
    idx = np.argsort(ticks, kind="stable") if order is None else order
    out: list[list[int]] = [[] for _ in range(k)]
    for e in idx:
        out[int(ticks[e])].append(int(e))
    return out


def _dr_tracks(record: TeamRecord, start_cov: Array | None = None) -> DeadReckonedTrack:
    """Every vehicle's DR from its start (rows are run-major (n v)), positions (n v, k, 2)."""
    n, v, k = record.n_runs, record.n_vehicles, record.n_samples
    cov0 = record.start_cov_m2 if start_cov is None else start_cov
    return dead_reckoning.track_with_covariance(
        record.start_m.reshape(n * v, 2),
        record.dr_step_m.reshape(n * v, k - 1, 2),
        record.dr_step_cov_m2.reshape(n * v, k - 1, 2, 2),
        np.broadcast_to(cov0, (n, v, 2, 2)).reshape(n * v, 2, 2),
    )


def _dr_method(record: TeamRecord) -> TeamTracks:
    n, v, k = record.n_runs, record.n_vehicles, record.n_samples
    dr = _dr_tracks(record)
    zeros = np.zeros((n, v, k))
    return TeamTracks(
        "dr",
        dr.position_m.reshape(n, v, k, 2),
        dr.cov_m2.reshape(n, v, k, 2, 2),
        zeros,
        zeros.copy(),
        False,
        np.zeros((n, v), dtype=np.int64),
    )


class _Outputs:
    def __init__(self, n: int, v: int, k: int):
        self.pos = np.empty((n, v, k, 2))
        self.cov = np.empty((n, v, k, 2, 2))
        self.clock = np.empty((n, v, k))
        self.clock_var = np.empty((n, v, k))
        self.used = np.zeros((n, v), dtype=np.int64)

    def tracks(self, method: str) -> TeamTracks:
        return TeamTracks(method, self.pos, self.cov, self.clock, self.clock_var, True, self.used)


def _step_index(q: int, k: int) -> int:
    """The DR interval that starts at sample q (the last one at the last sample)."""
    return min(q, k - 2)


def _stamps(record: TeamRecord, e: int) -> tuple[Array, Array]:
    """Transmission and reception stamps of event e, shape (n,) each, s; where the range is
    absent the reception is stamped at the transmission (anything finite: it is not used)."""
    present = record.range_present[:, e]
    T = np.where(present, record.range_tx_local_s[:, e], 0.0)
    return T, np.where(present, record.range_rx_local_s[:, e], T)


def _motion_since(
    dr: Array, vel: Array, t: Array, vehicle: int, tick: int, instant_s: Array, q: int
) -> tuple[Array, Array]:
    """How long ago and how fast a vehicle was at an instant: ``(lag (n,), velocity (n, 2))``
    with ``lag = t_q - instant`` and ``velocity * lag`` its DR displacement from the instant (in
    the interval after sample ``tick``) to sample q (velocity 0 where the lag is 0).

    Args:
        dr: DR positions, shape (n, v, k, 2), m.
        vel: DR velocities of the intervals, shape (n, v, k - 1, 2), m/s.
        t: sample times, (k,), s.
        vehicle: the vehicle.
        tick: the sample at or before the instant.
        instant_s: the instant, (n,), s.
        q: the sample of the filter.
    """
    lag = t[q] - instant_s
    k = len(t)
    moved = dr[:, vehicle, q] - dr[:, vehicle, tick]
    moved = moved - vel[:, vehicle, _step_index(tick, k)] * (instant_s - t[tick])[:, None]
    moving = np.abs(lag) > 1e-9
    return lag, np.where(moving[:, None], moved / np.where(moving, lag, 1.0)[:, None], 0.0)


class _DrNoise:
    """The dead reckoning's noise between an instant and a sample, per vehicle: the variance per
    axis (half the trace) of the DR covariance accumulated over that time, the part of a step
    taken in proportion to its time."""

    def __init__(self, record: TeamRecord):
        n, v, k = record.n_runs, record.n_vehicles, record.n_samples
        cov = _dr_tracks(record).cov_m2.reshape(n, v, k, 2, 2)
        self.acc = 0.5 * (cov[..., 0, 0] + cov[..., 1, 1])  # (n, v, k)
        step = record.dr_step_cov_m2
        self.step = 0.5 * (step[..., 0, 0] + step[..., 1, 1])  # (n, v, k - 1)
        self.t = record.t_s
        self.rows = np.arange(n)

    def between(self, vehicle: int, instant_s: Array, q: int) -> Array:
        """Variance per axis of the DR noise from ``instant_s`` (n,) to sample q (either order),
        shape (n,), m^2."""
        t, k = self.t, len(self.t)
        lo, hi = np.minimum(instant_s, t[q]), np.maximum(instant_s, t[q])
        a = np.clip(np.searchsorted(t, lo, side="right") - 1, 0, k - 2)
        b = np.clip(np.searchsorted(t, hi, side="right") - 1, 0, k - 2)
        dt = np.diff(t)
        acc = self.acc[:, vehicle]
        step = self.step[:, vehicle]
        frac_a = np.clip((lo - t[a]) / dt[a], 0.0, 1.0)
        frac_b = np.clip((hi - t[b]) / dt[b], 0.0, 1.0)
        rows = self.rows
        total = acc[rows, b] - acc[rows, a] + step[rows, b] * frac_b - step[rows, a] * frac_a
        return np.maximum(total, 0.0)


def _widened(peer: PeerEstimate, var_m2: Array) -> PeerEstimate:
    """A broadcast with ``var_m2`` (n,) added to its position variances (its extrapolation)."""
    cov = peer.cov_m2.copy()
    cov[:, 0, 0] += var_m2
    cov[:, 1, 1] += var_m2
    return PeerEstimate(peer.position_m, peer.clock_offset_s, cov)


def _central(record: TeamRecord, opts: CoopOptions) -> TeamTracks:
    n, v, k = record.n_runs, record.n_vehicles, record.n_samples
    sched = _Schedule(record)
    t, dt = record.t_s, np.diff(record.t_s)
    vel = record.velocity_m_s()
    dr = _dr_tracks(record).position_m.reshape(n, v, k, 2)
    team = TeamEkf(record.start_m, record.start_cov_m2, opts)
    noise = _DrNoise(record)
    out = _Outputs(n, v, k)
    for q in range(k):
        if q > 0:
            team.predict(
                record.dr_step_m[:, :, q - 1], record.dr_step_cov_m2[:, :, q - 1], dt[q - 1]
            )
        for f in sched.fixes[q]:
            team.update_position(
                int(record.fix_vehicle[f]),
                record.fix_m[:, f],
                record.fix_cov_m2[:, f],
                record.fix_present[:, f],
            )
        for e in sched.rx[q]:
            i, j = int(record.range_receiver[e]), int(record.range_sender[e])
            tx = int(record.range_tx_tick[e])
            T, L = _stamps(record, e)
            b_i = team.clock_offset(i)
            if record.kind == "owtt":
                t_rx, t_tx = L - b_i, T - team.clock_offset(j)
            else:
                t_rx = t_tx = 0.5 * (T + L) - b_i
            lag_r = t[q] - t_rx
            lag_s, sender_velocity = _motion_since(dr, vel, t, j, tx, t_tx, q)
            info = team.update_range(
                i,
                j,
                record.range_m[:, e],
                kind=record.kind,
                sound_speed_m_s=record.sound_speed_m_s,
                sigma_m=record.sigma_range_m,
                dz_m=record.depth_m[:, i, q] - record.depth_m[:, j, tx],
                receiver_lag_s=lag_r,
                sender_lag_s=lag_s,
                receiver_velocity_m_s=vel[:, i, max(q - 1, 0)],
                sender_velocity_m_s=sender_velocity,
                present=record.range_present[:, e],
                extra_var_m2=noise.between(i, t_rx, q) + noise.between(j, t_tx, q),
            )
            out.used[:, i] += info.applied
        for i in range(v):
            out.pos[:, i, q] = team.position(i)
            out.cov[:, i, q] = team.covariance(i)
            out.clock[:, i, q] = team.clock_offset(i)
            out.clock_var[:, i, q] = team.clock_variance(i)
    return out.tracks("central")


def _run_navigators(
    record: TeamRecord, opts: CoopOptions, vehicles: tuple[int, ...], use_ranges: bool
) -> tuple[_Outputs, dict[int, PeerEstimate]]:
    """The decentralised navigators of ``vehicles`` over the record; returns their outputs and
    every broadcast made for a range (by event)."""
    n, k = record.n_runs, record.n_samples
    sched = _Schedule(record)
    t, dt = record.t_s, np.diff(record.t_s)
    vel = record.velocity_m_s()
    navs = {
        i: CoopNavigator.for_vehicle(i, record.start_m[:, i], record.start_cov_m2[:, i], opts)
        for i in vehicles
    }
    out = _Outputs(n, len(vehicles), k)
    sent: dict[int, PeerEstimate] = {}
    owtt = record.kind == "owtt"
    relay = owtt and opts.relay
    relays: dict[tuple[int, int], list[tuple[int, PeerEstimate]]] = {}
    dr = _dr_tracks(record).position_m.reshape(n, record.n_vehicles, k, 2)
    noise = _DrNoise(record)
    for q in range(k):
        if q > 0:
            for i, nav in navs.items():
                nav.predict(
                    record.dr_step_m[:, i, q - 1], record.dr_step_cov_m2[:, i, q - 1], dt[q - 1]
                )
        for f in sched.fixes[q]:
            i = int(record.fix_vehicle[f])
            if i in navs:
                navs[i].fuse_position(
                    record.fix_m[:, f], record.fix_cov_m2[:, f], record.fix_present[:, f]
                )
        for e in sched.tx[q]:
            i, j = int(record.range_receiver[e]), int(record.range_sender[e])
            if j not in navs:
                continue
            T, L = _stamps(record, e)
            if owtt:
                t_tx = T - navs[j].clock_offset
            else:  # the responder replies at the exchange's mid-time (interrogator's clock)
                b_i = navs[i].clock_offset if i in navs else 0.0
                t_tx = 0.5 * (T + L) - b_i
            ahead = np.where(record.range_present[:, e], t_tx - t[q], 0.0)
            made = navs[j].broadcast(ahead, vel[:, j, _step_index(q, k)])
            sent[e] = _widened(made, noise.between(j, t[q] + ahead, q))
        for e in sched.rx[q] if use_ranges else ():
            i, j = int(record.range_receiver[e]), int(record.range_sender[e])
            if i not in navs or e not in sent:
                continue
            nav = navs[i]
            T, L = _stamps(record, e)
            for e0, relayed in relays.pop((j, i), []) if relay else ():
                # ranges i sent to j before j's transmission e, relayed in it
                if record.range_rx_tick[e0] > record.range_tx_tick[e]:
                    relays.setdefault((j, i), []).append((e0, relayed))
                    continue
                T0, _ = _stamps(record, e0)
                tx0 = int(record.range_tx_tick[e0])
                lag, velocity = _motion_since(dr, vel, t, i, tx0, T0 - nav.clock_offset, q)
                info, _ = nav.fuse_range(
                    record.range_m[:, e0],
                    relayed,
                    sigma_m=record.sigma_range_m,
                    depth_m=record.depth_m[:, i, tx0],
                    peer_depth_m=record.depth_m[:, j, record.range_rx_tick[e0]],
                    sound_speed_m_s=record.sound_speed_m_s,
                    lag_s=lag,
                    velocity_m_s=velocity,
                    present=record.range_present[:, e0] & record.range_present[:, e],
                    sent_by_me=True,
                    extra_var_m2=noise.between(i, t[q] - lag, q),
                )
                out.used[:, vehicles.index(i)] += info.applied
            t_rx = L - nav.clock_offset if owtt else 0.5 * (T + L) - nav.clock_offset
            if relay and j in navs:  # i's estimate at the reception, before it uses the range
                ahead = np.where(record.range_present[:, e], t_rx - t[q], 0.0)
                made = nav.broadcast(ahead, vel[:, i, max(q - 1, 0)])
                relays.setdefault((i, j), []).append(
                    (e, _widened(made, noise.between(i, t[q] + ahead, q)))
                )
            info, _ = nav.fuse_range(
                record.range_m[:, e],
                sent.pop(e),
                sigma_m=record.sigma_range_m,
                depth_m=record.depth_m[:, i, q],
                peer_depth_m=record.depth_m[:, j, record.range_tx_tick[e]],
                kind=record.kind,
                sound_speed_m_s=record.sound_speed_m_s,
                lag_s=t[q] - t_rx,
                velocity_m_s=vel[:, i, max(q - 1, 0)],
                present=record.range_present[:, e],
                extra_var_m2=noise.between(i, t_rx, q),
            )
            out.used[:, vehicles.index(i)] += info.applied
        for a, i in enumerate(vehicles):
            nav = navs[i]
            out.pos[:, a, q] = nav.position
            out.cov[:, a, q] = nav.covariance
            out.clock[:, a, q] = nav.clock_offset
            out.clock_var[:, a, q] = nav.clock_variance
    return out, sent


def _decentralised(record: TeamRecord, opts: CoopOptions) -> TeamTracks:
    out, _ = _run_navigators(record, opts, tuple(range(record.n_vehicles)), True)
    return out.tracks("decentralised")


def _cov_since_fixes(
    dr_cov: Array, fix_tick: NDArray[np.intp], fix_cov: Array, used: NDArray[np.bool_]
) -> Array:
    """Stated covariance at every sample: the covariance of the last used fix at or before the
    sample plus the DR covariance accumulated since (before any fix: the DR covariance), shape
    (n, k, 2, 2)."""
    n, k = dr_cov.shape[:2]
    last = np.full((n, k), -1, dtype=np.intp)
    for fix, tick in enumerate(fix_tick):
        last[used[:, fix], tick] = fix
    last = np.maximum.accumulate(last, axis=1)
    rows = np.arange(n)[:, None]
    j = np.maximum(last, 0)
    since = dr_cov - dr_cov[rows, fix_tick[j]] if len(fix_tick) else dr_cov
    with_fix = fix_cov[rows, j] + since if len(fix_tick) else dr_cov
    return np.where((last >= 0)[..., None, None], with_fix, dr_cov)


def _leader_only(record: TeamRecord, method: str, opts: CoopOptions) -> TeamTracks:
    n, v, k = record.n_runs, record.n_vehicles, record.n_samples
    leader, sent = _run_navigators(record, opts, (0,), False)
    pos = np.empty((n, v, k, 2))
    cov = np.empty((n, v, k, 2, 2))
    used = np.zeros((n, v), dtype=np.int64)
    pos[:, 0], cov[:, 0] = leader.pos[:, 0], leader.cov[:, 0]
    from_leader = np.flatnonzero(record.range_sender == 0)
    # seed 003's EKF takes scalar sigmas: each run's own (so that a run's numbers do not depend
    # on the other runs of its batch), the runs sharing a value filtered together
    leader_var = np.zeros(n)
    for e in from_leader:
        leader_var += np.trace(sent[int(e)].cov_m2[:, :2, :2], axis1=1, axis2=2) / 2
    leader_sigma = np.sqrt(leader_var / max(len(from_leader), 1))
    start_var = np.diagonal(record.start_cov_m2, 0, 2, 3).reshape(n, -1).max(axis=1)
    start_sigma = np.sqrt(np.maximum(start_var, 0.0))
    start_cov = np.eye(2) * (start_sigma**2)[:, None, None, None]
    dr_all = _dr_tracks(record, start_cov)
    dr_pos = dr_all.position_m.reshape(n, v, k, 2)
    dr_cov = dr_all.cov_m2.reshape(n, v, k, 2, 2)
    for i in range(1, v):
        events = [e for e in from_leader if record.range_receiver[e] == i]
        events.sort(key=lambda e: (record.range_rx_tick[e], e))
        keep, seen = [], set()
        for e in events:  # seed 003 takes one range per sample: the first
            if int(record.range_rx_tick[e]) not in seen:
                seen.add(int(record.range_rx_tick[e]))
                keep.append(e)
        ev = np.array(keep, dtype=np.intp)
        dr = DeadReckonedTrack(dr_pos[:, i], dr_cov[:, i])
        if ev.size == 0:
            pos[:, i], cov[:, i] = dr_pos[:, i], dr_cov[:, i]
            continue
        dz = record.depth_m[:, i][:, record.range_rx_tick[ev]]
        dz = dz - record.depth_m[:, 0][:, record.range_tx_tick[ev]]
        slant = record.range_m[:, ev]
        present = record.range_present[:, ev] & np.isfinite(slant)
        horizontal = np.sqrt(np.maximum(np.nan_to_num(slant) ** 2 - dz**2, 0.0))
        broadcast = np.stack([sent[int(e)].position_m for e in ev], axis=1)
        ranges = LeaderRanges(record.range_rx_tick[ev], horizontal, present, broadcast)
        if method == "ga2":
            ga = replace(opts.ga, sigma_range_m=record.sigma_range_m)
            track = ga_track("ga2", dr, ranges, ga)
            track_pos, fix_cov, accepted = track.position_m, track.fix_cov_m2, track.accepted
            fix_used = accepted
        else:
            track_pos, fix_cov, accepted = _leader_ekf(
                record, opts, dr, ranges, start_sigma, leader_sigma
            )
            fix_used = np.ones_like(accepted)
        pos[:, i] = track_pos
        cov[:, i] = _cov_since_fixes(dr_cov[:, i], ranges.fix_tick, fix_cov, fix_used)
        used[:, i] = accepted.sum(axis=1)
    zeros = np.zeros((n, v, k))
    return TeamTracks(method, pos, cov, zeros, zeros.copy(), False, used)


def _leader_ekf(
    record: TeamRecord,
    opts: CoopOptions,
    dr: DeadReckonedTrack,
    ranges: LeaderRanges,
    start_sigma: Array,
    leader_sigma: Array,
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Seed 003's range EKF (:func:`nav.relative.ekf_track`) on groups of runs with equal sigmas
    (start, leader; per run, shape (n,)): positions (n, k, 2), posterior at each range
    (n, K, 2, 2), accepted (n, K)."""
    n, k = dr.position_m.shape[:2]
    n_fix = len(ranges.fix_tick)
    pos, fix_cov = np.empty((n, k, 2)), np.empty((n, n_fix, 2, 2))
    accepted = np.zeros((n, n_fix), dtype=bool)
    keys, group = np.unique(
        np.stack([start_sigma, leader_sigma], axis=1), axis=0, return_inverse=True
    )
    for g, (s0, sl) in enumerate(keys):
        rows = np.flatnonzero(group.ravel() == g)
        options = RangeEkfOptions(
            sigma_range_m=record.sigma_range_m,
            min_range_m=opts.min_range_m,
            initial_sigma_m=float(s0),
            leader_sigma_m=float(sl),
        )
        part = ekf_track(
            DeadReckonedTrack(dr.position_m[rows], dr.cov_m2[rows]),
            LeaderRanges(
                ranges.fix_tick, ranges.range_m[rows], ranges.present[rows], ranges.leader_m[rows]
            ),
            options,
        )
        pos[rows], fix_cov[rows], accepted[rows] = part.position_m, part.fix_cov_m2, part.accepted
    return pos, fix_cov, accepted
