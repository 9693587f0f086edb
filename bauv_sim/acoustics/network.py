"""The team's acoustic network: travel-time ranges between vehicles on a TDMA schedule.

**Schedule (TDMA).** Time is divided into cycles of ``period_s``; cycle ``c`` starts at the
*local* time ``start_s + c * period_s`` and its slot ``s`` (``slot_s`` long) at ``start_s + c *
period_s + s * slot_s``. ``order`` lists the senders slot by slot (vehicle names; an entry
``"a+b"`` puts two vehicles in one slot: they transmit together and their packets collide where
they arrive together); by default every vehicle has a slot, in the scene's order (the leader
first). Each sender transmits when *its own clock* reads its slot's start (every vehicle keeps
the schedule by its clock, :mod:`bauv_sim.acoustics.clock`).

**One-way travel time (OWTT).** Sender ``j`` transmits at local time ``T``: at true time
``t_tx = true_of_local_j(T)``, from its transducer's position ``p_j(t_tx)``. Every other vehicle
``i`` hears it (one transmission gives ``v - 1`` events); the sound reaches ``i`` at ``t_rx``,
the solution of

    t_rx = t_tx + tau(p_j(t_tx), p_i(t_rx))

(the receiver moves while the sound travels; ``tau`` the true medium's travel time,
:class:`nav.acoustics.Propagation`), found by fixed-point iteration from ``t_rx = t_tx``: the
map contracts by ``|v_i| / c`` (about 1e-3) per iteration, so :data:`FIXED_POINT_ITERATIONS`
iterations leave ``(1e-3)^6`` of the first guess's error (the guess is off by ``tau |v_i| / c``,
below 1 ms at 1 km and 2 m/s). The receiver stamps the arrival with its clock, ``L = local_i(t_rx)
+ jitter_i * z1 + travel_time_sigma_s * z2`` (timestamp jitter of the receiver's clock and the
detection's noise, ``z`` standard normal), and knowing ``T`` (the schedule) measures the travel
time ``L - T`` and the range

    range = c_nom * (L - T).

Noise off, in an isovelocity medium at ``c_nom``, that is exactly

    range = |p_j(t_tx) - p_i(t_rx)| + c_nom * (offset_i(t_rx) - offset_j(t_tx)):

the true range between the transmitter at its transmit instant and the receiver at its
reception instant, biased by the clocks' offset difference (Eustice et al. 2007; Webster et al.
2012, see :mod:`bauv_sim.acoustics.clock`).

**Two-way travel time (TWTT).** The vehicle of the slot interrogates: it transmits at its local
``T``; every other vehicle ``j`` receives the ping at ``t1`` (as above), stamps it ``L1 =
local_j(t1) + noise`` and replies when its clock reads ``L1 + turnaround_s``, at true time
``t2 = true_of_local_j(L1 + turnaround_s)``; the interrogator receives the reply at ``t3`` and
stamps ``L3 = local_i(t3) + noise``:

    range = c_nom * (L3 - T - turnaround_s) / 2.

The offsets cancel; the drifts leave ``c_nom/2 * (d_i (t3 - t_tx) - d_j turnaround_s / (1 +
d_j))`` (to first order; 1 ppm on a 1 s turnaround and 2 s round trip: 1.5e-3 m). An event of
TWTT has ``receiver`` = the interrogator (who measures) and ``sender`` = the responder; its true
range is the mean of the two legs' true ranges ``(|p_i(t_tx) - p_j(t1)| + |p_j(t2) -
p_i(t3)|) / 2``, to which the TWTT range is equal with noise off in isovelocity at ``c_nom`` (up
to the drift term above).

**Losses** (``lost`` codes, the first that applies, per leg; a TWTT event takes its first lost
leg's code):

* 1 ``range``: the leg's true distance exceeds ``max_range_m`` (the packet is neither decoded
  nor heard: it does not interfere);
* 4 ``half-duplex``: the receiver is transmitting while the packet arrives (its transmission
  ``[t, t + packet_s)`` overlaps the arrival ``[t_rx, t_rx + packet_s)``);
* 3 ``collision``: another packet arrives at the same receiver less than ``packet_s`` before or
  after (both are lost);
* 2 ``sonar``: the packet is not decoded by the sonar equation (:mod:`bauv_sim.acoustics.sonar`;
  only with ``sonar.enabled``): with ``fading_sigma_db = 0`` when the SNR at the leg's true range
  is below the threshold, else with probability ``1 - Phi((SNR - DT) / sigma)`` (a uniform draw
  per leg).

A TWTT reply exists only if its ping was decoded. Replies interfere at the interrogator (with
one another and with pings from other slots arriving there); a reply arriving at a third vehicle
while it receives a ping is not modelled (it needs a slot shorter than a round trip).

**Streams.** Each vehicle's clock draws from ``("clock", <vehicle>)``; the noise of what vehicle
``i`` receives from ``("acoustic", <i>, "jitter" | "travel_time" | "packet")``, one draw per event
(TWTT: two, one per leg) in the order of the schedule, so a receiver's numbers do not depend on
the other receivers, and the online device (:class:`AcousticNetworkDevice`), which receives the
same events one by one, draws the same numbers.

:class:`AcousticNetwork` is the batched form (positions on a time grid, any number of runs);
:class:`AcousticNetworkDevice` the online device of a receiver's rig (OWTT).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim import rng as rng_mod
from bauv_sim.acoustics.clock import Clock, ClockConfig, draw_clocks
from bauv_sim.acoustics.sonar import SonarConfig, snr_db, success_probability
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from nav.acoustics import Isovelocity, Propagation

Array = NDArray[np.float64]

FIXED_POINT_ITERATIONS = 6
"""Iterations of the reception time's fixed point (module docstring)."""

LOST_OK, LOST_RANGE, LOST_SONAR, LOST_COLLISION, LOST_HALF_DUPLEX = 0, 1, 2, 3, 4
"""Codes of :attr:`NetworkRanges.lost`."""


class AcousticNetworkConfig(Config):
    """The acoustic network of a team (defaults: OWTT on perfect clocks, no loss but range)."""

    ranging: Literal["owtt", "twtt"] = Field("owtt", description="one-way or two-way ranging")
    period_s: float = Field(10.0, gt=0, description="TDMA cycle, s")
    slot_s: float = Field(2.0, gt=0, description="length of one sender's slot, s")
    start_s: float = Field(10.0, ge=0, description="local time the first cycle starts, s")
    order: tuple[str, ...] = Field(
        (),
        description="senders slot by slot ('a+b': a shared slot); empty: every vehicle in the "
        "scene's order",
    )
    packet_s: float = Field(
        0.2, ge=0, description="duration of a packet (collision and half-duplex window), s"
    )
    turnaround_s: float = Field(
        0.5, ge=0, description="TWTT: responder's delay, by its own clock, s"
    )
    nominal_sound_speed_m_s: float = Field(
        1500.0, gt=0, description="speed that turns a travel time into a range, m/s"
    )
    travel_time_sigma_s: float = Field(
        0.0, ge=0, description="detection noise of an arrival time (sd), s"
    )
    max_range_m: float = Field(2000.0, gt=0, description="no packet beyond this range, m")
    sonar: SonarConfig = Field(default_factory=SonarConfig, description="the link's sonar equation")
    clock: ClockConfig = Field(
        default_factory=ClockConfig, description="the clock of vehicles not in 'clocks'"
    )
    clocks: dict[str, ClockConfig] = Field(
        default_factory=dict, description="clocks by vehicle name"
    )
    processing_delay_s: float = Field(
        0.5, ge=0, description="from reception to the range reaching the navigator, s"
    )

    @model_validator(mode="after")
    def _slots(self) -> AcousticNetworkConfig:
        if self.slot_s > self.period_s:
            raise ValueError(f"slot_s = {self.slot_s:g}: longer than period_s = {self.period_s:g}")
        if self.packet_s > self.slot_s:
            raise ValueError(f"packet_s = {self.packet_s:g}: longer than slot_s = {self.slot_s:g}")
        return self

    def clock_of(self, vehicle: str) -> ClockConfig:
        """The clock configuration of a vehicle."""
        return self.clocks.get(vehicle, self.clock)

    def horizon_s(self) -> float:
        """The longest exchange after a transmission (last arrival at the maximum range), s."""
        leg = self.max_range_m / self.nominal_sound_speed_m_s
        if self.ranging == "twtt":
            return 2 * leg + self.turnaround_s + self.packet_s
        return leg + self.packet_s


def slot_senders(cfg: AcousticNetworkConfig, vehicles: Sequence[str]) -> list[list[int]]:
    """The senders of each slot, as indices into ``vehicles`` (module docstring: schedule).

    Raises:
        ConfigError: naming ``order`` for an unknown or repeated vehicle, ``slot_s`` when the
            slots do not fit in the cycle, ``clocks`` for a clock of an unknown vehicle.
    """
    names = list(vehicles)
    if len(set(names)) != len(names) or len(names) < 2:
        raise ConfigError(f"network: vehicles {names}: need two or more distinct names")
    for name in cfg.clocks:
        if name not in names:
            raise ConfigError(
                f"network.clocks: {name!r} is not a vehicle (vehicles: {', '.join(names)})"
            )
    entries = cfg.order or tuple(names)
    slots, seen = [], set()
    for entry in entries:
        group = []
        for name in entry.split("+"):
            if name not in names:
                raise ConfigError(
                    f"network.order: {name!r} is not a vehicle (vehicles: {', '.join(names)})"
                )
            if name in seen:
                raise ConfigError(f"network.order: {name!r} has more than one slot")
            seen.add(name)
            group.append(names.index(name))
        slots.append(group)
    if len(slots) * cfg.slot_s > cfg.period_s + 1e-9:
        raise ConfigError(
            f"network.slot_s = {cfg.slot_s:g}: {len(slots)} slots of it do not fit in "
            f"period_s = {cfg.period_s:g}"
        )
    return slots


def schedule(
    cfg: AcousticNetworkConfig, vehicles: Sequence[str], first_s: float, last_s: float
) -> tuple[NDArray[np.intp], Array]:
    """The transmissions with a local time in ``[first_s, last_s]``, in schedule order.

    Returns:
        ``(sender, local_s)``: sender indices into ``vehicles`` and local transmit times (s),
        shape (q,) each, ordered by time, then by the sender's place in its slot.
    """
    slots = slot_senders(cfg, vehicles)
    senders, times = [], []
    c = max(0, math.floor((first_s - cfg.start_s) / cfg.period_s))
    while True:
        t0 = cfg.start_s + c * cfg.period_s
        if t0 > last_s:
            break
        for s, group in enumerate(slots):
            T = t0 + s * cfg.slot_s
            if first_s <= T <= last_s:
                senders += group
                times += [T] * len(group)
        c += 1
    return np.asarray(senders, dtype=np.intp), np.asarray(times, dtype=float)


def reception_time(
    propagation: Propagation,
    source_world_m: Array,
    t_tx_s: Array,
    receiver_at: Callable[[Array], Array],
) -> tuple[Array, Array]:
    """Solve ``t_rx = t_tx + tau(source, receiver(t_rx))`` by fixed-point iteration (module
    docstring).

    Args:
        propagation: the true medium.
        source_world_m: transmitter position at ``t_tx_s``, shape (..., 3), m, world ENU.
        t_tx_s: true transmit times, shape (...), s.
        receiver_at: the receiver's position (shape (..., 3), m) at true times (shape (...)).

    Returns:
        ``(t_rx_s, receiver_world_m)``: the reception time (s) and the receiver's position there
        (m), shapes (...) and (..., 3).
    """
    t = t_tx_s
    for _ in range(FIXED_POINT_ITERATIONS):
        p = receiver_at(t)
        t = t_tx_s + propagation.eigenray(source_world_m, p).travel_time_s
    return t, receiver_at(t)


def interpolate_positions(t_grid_s: Array, positions_world_m: Array, t_s: Array) -> Array:
    """Positions at any times, linear between grid samples (extrapolated from the end segments).

    Args:
        t_grid_s: sample times, shape (k,), s, increasing, k >= 2.
        positions_world_m: positions, shape (n or 1, k, 3), m.
        t_s: query times, shape (n, M), s.

    Returns:
        Positions, shape (n, M, 3), m.
    """
    n = t_s.shape[0]
    pos = positions_world_m
    if pos.shape[0] != n:
        pos = np.broadcast_to(pos, (n, *pos.shape[1:]))
    k = t_grid_s.shape[0]
    idx = np.clip(np.searchsorted(t_grid_s, t_s, side="right") - 1, 0, k - 2)
    t0 = t_grid_s[idx]
    w = (t_s - t0) / (t_grid_s[idx + 1] - t0)
    p0 = np.take_along_axis(pos, idx[..., None], axis=1)
    p1 = np.take_along_axis(pos, idx[..., None] + 1, axis=1)
    return p0 + w[..., None] * (p1 - p0)


@dataclass(frozen=True)
class NetworkRanges:
    """The ranges of one batch (m events, n runs), in schedule order (module docstring).

    Attributes:
        vehicles: the vehicles' names; indices below refer to them.
        kind: ``"owtt"`` or ``"twtt"``.
        sound_speed_m_s: the nominal speed the ranges were computed with, m/s.
        sender: transmitting vehicle (TWTT: the responder), shape (m,).
        receiver: receiving vehicle (TWTT: the interrogator, who measures), shape (m,).
        tx_local_s: scheduled transmit time by the sender's clock (TWTT: the interrogator's
            ping), shape (n, m), s.
        rx_local_s: the receiver's timestamp of the arrival (TWTT: of the reply), shape (n, m),
            s.
        t_tx_s: true transmit time, shape (n, m), s.
        t_rx_s: true reception time, shape (n, m), s.
        true_range_m: ``|p_sender(t_tx) - p_receiver(t_rx)|`` (TWTT: the mean of the two legs),
            shape (n, m), m.
        range_m: the measured range, shape (n, m), m (meaningless where not produced).
        snr_db: the sonar equation's SNR at the true range (TWTT: the weaker leg), shape (n, m),
            dB.
        produced: whether the range exists, shape (n, m).
        lost: why not (:data:`LOST_OK` ... :data:`LOST_HALF_DUPLEX`), shape (n, m).
        t_available_s: true time the range reaches the receiver's navigator (reception plus
            ``processing_delay_s``), shape (n, m), s.
    """

    vehicles: tuple[str, ...]
    kind: str
    sound_speed_m_s: float
    sender: NDArray[np.intp]
    receiver: NDArray[np.intp]
    tx_local_s: Array
    rx_local_s: Array
    t_tx_s: Array
    t_rx_s: Array
    true_range_m: Array
    range_m: Array
    snr_db: Array
    produced: NDArray[np.bool_]
    lost: NDArray[np.int8]
    t_available_s: Array

    @property
    def travel_time_s(self) -> Array:
        """Measured travel time ``rx_local - tx_local`` (TWTT: the round trip less the
        turnaround, halved: ``range / c``), shape (n, m), s."""
        return self.range_m / self.sound_speed_m_s


def neighbour_gaps(
    times: Array, arrivals: NDArray[np.bool_], own: NDArray[np.bool_], packet_s: float
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Which arrivals at one receiver collide, and which meet the receiver's own transmission.

    Args:
        times: arrival and own transmission start times, shape (n, M), s (any order).
        arrivals: the columns that are arrivals that interfere, shape (n, M).
        own: the columns that are the receiver's own transmissions, shape (n, M).
        packet_s: packet duration, s.

    Returns:
        ``(collided, half_duplex)``, shape (n, M): an arrival with another arrival closer than
        ``packet_s``; an arrival closer than ``packet_s`` to an own transmission (their
        intervals of ``packet_s`` overlap). False elsewhere.
    """
    order = np.argsort(times, axis=1, kind="stable")
    st = np.take_along_axis(times, order, axis=1)
    out = []
    for mask in (arrivals, own):
        # an infinite time (a packet never sent) is never near anything: inf - inf is NaN
        sm = np.take_along_axis(mask, order, axis=1)
        before = np.maximum.accumulate(np.where(sm, st, -np.inf), axis=1)
        after = np.minimum.accumulate(np.where(sm, st, np.inf)[:, ::-1], axis=1)[:, ::-1]
        inf = np.full((st.shape[0], 1), np.inf)
        prev = np.concatenate([-inf, before[:, :-1]], axis=1)
        nxt = np.concatenate([after[:, 1:], inf], axis=1)
        with np.errstate(invalid="ignore"):
            near = ((st - prev) < packet_s) | ((nxt - st) < packet_s)
        hit = np.empty_like(near)
        np.put_along_axis(hit, order, near, axis=1)
        out.append(hit & arrivals)
    return out[0], out[1]


class _Receiver:
    """The draws of what one vehicle receives (module docstring: streams)."""

    def __init__(self, cfg: AcousticNetworkConfig, clock: Clock, seed: int, runs, name: str):
        self.cfg, self.clock = cfg, clock
        base = ("acoustic", name)
        self._jitter = (
            rng_mod.RunStreams(seed, runs, *base, "jitter") if clock.jitter_s > 0 else None
        )
        self._tt = (
            rng_mod.RunStreams(seed, runs, *base, "travel_time")
            if cfg.travel_time_sigma_s > 0
            else None
        )
        s = cfg.sonar
        self._packet = (
            rng_mod.RunStreams(seed, runs, *base, "packet")
            if s.enabled and s.fading_sigma_db > 0
            else None
        )
        self.n = len(runs)

    def timestamp_noise(self, m: int) -> Array:
        """Jitter plus detection noise of ``m`` arrivals, shape (n, m), s."""
        e = np.zeros((self.n, m))
        if self._jitter is not None:
            e = e + self.clock.jitter_s * self._jitter.draw("standard_normal", m)
        if self._tt is not None:
            e = e + self.cfg.travel_time_sigma_s * self._tt.draw("standard_normal", m)
        return e

    def decoded(self, snr: Array) -> NDArray[np.bool_]:
        """Whether each of ``m`` packets with SNR ``snr`` (n, m) is decoded (always when the
        sonar is off)."""
        s = self.cfg.sonar
        if not s.enabled:
            return np.ones(snr.shape, dtype=bool)
        p = success_probability(snr, s.detection_threshold_db, s.fading_sigma_db)
        if self._packet is None:
            return p >= 1.0
        return self._packet.draw("random", snr.shape[1]) < p


class AcousticNetwork:
    """The network's ranges over a batch of runs (module docstring).

    Args:
        cfg: configuration.
        vehicles: the vehicles' names, in the scene's order (the leader first).
        seed: batch seed.
        runs: run indices of the rows (n,).
        propagation: the sea's true medium; ``None``: isovelocity at the nominal speed.

    Raises:
        ConfigError: for a schedule or clocks that do not fit the vehicles
            (:func:`slot_senders`).
    """

    def __init__(
        self,
        cfg: AcousticNetworkConfig,
        vehicles: Sequence[str],
        seed: int,
        runs: Sequence[int],
        propagation: Propagation | None = None,
    ):
        self.cfg = cfg
        self.vehicles = tuple(vehicles)
        slot_senders(cfg, self.vehicles)
        self.seed, self.runs = seed, tuple(int(r) for r in runs)
        self.n = len(self.runs)
        self.propagation = (
            propagation if propagation is not None else Isovelocity(cfg.nominal_sound_speed_m_s)
        )
        self.clocks = [draw_clocks(cfg.clock_of(v), seed, self.runs, v) for v in self.vehicles]

    def exchange(self, t_s: Array, positions_world_m: Array) -> NetworkRanges:
        """The ranges of the transmissions scheduled on a time grid.

        Transmissions are those with a local time in ``[t_s[0], t_s[-1] - horizon]``
        (:meth:`AcousticNetworkConfig.horizon_s`), so that their arrivals fall on the grid up to
        the clocks' offsets (positions are extrapolated from the last segment beyond it).

        Args:
            t_s: true sample times, shape (k,), s, increasing, k >= 2.
            positions_world_m: each vehicle's transducer, shape (v, n or 1, k, 3), m, world ENU
                (linear between samples).

        Returns:
            The events (:class:`NetworkRanges`).

        Raises:
            ConfigError: for shapes that do not match.
        """
        t = np.asarray(t_s, dtype=float)
        pos = np.asarray(positions_world_m, dtype=float)
        v = len(self.vehicles)
        if t.ndim != 1 or t.shape[0] < 2 or np.any(np.diff(t) <= 0):
            raise ConfigError(f"network: t_s has shape {t.shape}: need (k,), k >= 2, increasing")
        if (
            pos.ndim != 4
            or pos.shape[0] != v
            or pos.shape[1] not in (1, self.n)
            or (pos.shape[2:] != (t.shape[0], 3))
        ):
            raise ConfigError(
                f"network: positions_world_m has shape {pos.shape}: need ({v}, {self.n} or 1, "
                f"{t.shape[0]}, 3)"
            )
        if not np.all(np.isfinite(pos)):
            raise ConfigError("network: positions_world_m holds non-finite values")
        sender, local = schedule(self.cfg, self.vehicles, t[0], t[-1] - self.cfg.horizon_s())
        if self.cfg.ranging == "twtt":
            return self._twtt(t, pos, sender, local)
        return self._owtt(t, pos, sender, local)

    # ------------------------------------------------------------------------------------------

    def _transmissions(self, t, pos, sender, local) -> tuple[Array, Array]:
        """True times (n, q) and positions (n, q, 3) of the scheduled transmissions."""
        q = sender.shape[0]
        t_tx = np.empty((self.n, q))
        p_tx = np.empty((self.n, q, 3))
        for j in range(len(self.vehicles)):
            sel = np.flatnonzero(sender == j)
            if sel.size:
                tj = self.clocks[j].true_of_local(np.broadcast_to(local[sel], (self.n, sel.size)))
                t_tx[:, sel] = tj
                p_tx[:, sel] = interpolate_positions(t, pos[j], tj)
        return t_tx, p_tx

    def _leg(self, t, pos, i, p_src, t_src):
        """Sound from sources (n, M, 3) at times (n, M) to vehicle ``i``: reception times,
        true distances and SNR, each (n, M)."""
        t_rx, p_rx = reception_time(
            self.propagation, p_src, t_src, lambda tt: interpolate_positions(t, pos[i], tt)
        )
        dist = np.linalg.norm(p_rx - p_src, axis=-1)
        return t_rx, dist, snr_db(dist, self.cfg.sonar)

    def _owtt(self, t, pos, sender, local) -> NetworkRanges:
        cfg, n, v = self.cfg, self.n, len(self.vehicles)
        t_tx, p_tx = self._transmissions(t, pos, sender, local)
        q = sender.shape[0]
        # events in schedule order: transmission by transmission, receivers in scene order
        ev_q = np.repeat(np.arange(q), v - 1)
        ev_rx = np.array([i for j in sender for i in range(v) if i != j], dtype=np.intp).reshape(-1)
        m = ev_q.shape[0]
        shape = (n, m)
        t_rx, rx_local = np.empty(shape), np.empty(shape)
        dist, snr = np.empty(shape), np.empty(shape)
        lost = np.zeros(shape, dtype=np.int8)
        for i in range(v):
            e = np.flatnonzero(ev_rx == i)
            if not e.size:
                continue
            qi = ev_q[e]
            recv = _Receiver(cfg, self.clocks[i], self.seed, self.runs, self.vehicles[i])
            tr, d, s = self._leg(t, pos, i, p_tx[:, qi], t_tx[:, qi])
            t_rx[:, e], dist[:, e], snr[:, e] = tr, d, s
            rx_local[:, e] = self.clocks[i].local(tr) + recv.timestamp_noise(e.size)
            decoded = recv.decoded(s)
            own = np.flatnonzero(sender == i)
            lost[:, e] = self._channel(d, tr, decoded, t_tx[:, own])
        tx_local = np.broadcast_to(local[ev_q], shape).copy()
        c = cfg.nominal_sound_speed_m_s
        return NetworkRanges(
            self.vehicles,
            "owtt",
            c,
            sender[ev_q],
            ev_rx,
            tx_local,
            rx_local,
            t_tx[:, ev_q],
            t_rx,
            dist,
            c * (rx_local - tx_local),
            snr,
            lost == LOST_OK,
            lost,
            t_rx + cfg.processing_delay_s,
        )

    def _channel(self, dist, t_rx, decoded, own_tx, extra_arrivals=None) -> NDArray[np.int8]:
        """Loss codes (n, M) of M arrivals at one receiver (module docstring: losses).

        Args:
            dist: true distances of the arrivals, (n, M), m.
            t_rx: their true times, (n, M), s.
            decoded: whether the sonar equation decodes them, (n, M).
            own_tx: the receiver's own transmission times, (n, B), s.
            extra_arrivals: other interfering arrival times at this receiver, (n, E), s.
        """
        M = t_rx.shape[1]
        in_range = dist <= self.cfg.max_range_m
        extra = np.zeros((t_rx.shape[0], 0)) if extra_arrivals is None else extra_arrivals
        times = np.concatenate([t_rx, extra, own_tx], axis=1)
        arr = np.zeros(times.shape, dtype=bool)
        arr[:, :M] = in_range
        arr[:, M : M + extra.shape[1]] = True
        own = np.zeros(times.shape, dtype=bool)
        own[:, M + extra.shape[1] :] = True
        collided, duplex = neighbour_gaps(times, arr, own, self.cfg.packet_s)
        lost = np.where(decoded, LOST_OK, LOST_SONAR).astype(np.int8)
        lost[collided[:, :M]] = LOST_COLLISION
        lost[duplex[:, :M]] = LOST_HALF_DUPLEX
        lost[~in_range] = LOST_RANGE
        return lost

    def _twtt(self, t, pos, sender, local) -> NetworkRanges:
        cfg, n, v = self.cfg, self.n, len(self.vehicles)
        t_tx, p_tx = self._transmissions(t, pos, sender, local)
        q = sender.shape[0]
        ev_q = np.repeat(np.arange(q), v - 1)
        ev_resp = np.array([j for i in sender for j in range(v) if j != i], dtype=np.intp)
        ev_int = sender[ev_q]
        m = ev_q.shape[0]
        shape = (n, m)
        recvs = [
            _Receiver(cfg, self.clocks[i], self.seed, self.runs, self.vehicles[i]) for i in range(v)
        ]
        # leg 1: pings at the responders
        t1, d1, s1, l1, loss1 = (np.empty(shape) for _ in range(5))
        p_reply = np.empty((n, m, 3))
        t2 = np.empty(shape)
        for j in range(v):
            e = np.flatnonzero(ev_resp == j)
            if not e.size:
                continue
            qe = ev_q[e]
            tr, d, s = self._leg(t, pos, j, p_tx[:, qe], t_tx[:, qe])
            t1[:, e], d1[:, e], s1[:, e] = tr, d, s
            noise = recvs[j].timestamp_noise(e.size)
            l1[:, e] = self.clocks[j].local(tr) + noise
            decoded = recvs[j].decoded(s)
            own = np.flatnonzero(sender == j)
            loss1[:, e] = self._channel(d, tr, decoded, t_tx[:, own])
            t2[:, e] = self.clocks[j].true_of_local(l1[:, e] + cfg.turnaround_s)
            p_reply[:, e] = interpolate_positions(t, pos[j], t2[:, e])
        loss1 = loss1.astype(np.int8)
        replied = loss1 == LOST_OK
        # leg 2: replies at the interrogators
        t3, d2, s2, l3 = (np.empty(shape) for _ in range(4))
        loss2 = np.zeros(shape, dtype=np.int8)
        for i in range(v):
            e = np.flatnonzero(ev_int == i)
            if not e.size:
                continue
            tr, d, s = self._leg(t, pos, i, p_reply[:, e], t2[:, e])
            t3[:, e], d2[:, e], s2[:, e] = tr, d, s
            noise = recvs[i].timestamp_noise(e.size)
            l3[:, e] = self.clocks[i].local(tr) + noise
            decoded = recvs[i].decoded(s)
            # pings of other slots reaching i (as a responder), and i's own pings and replies
            as_resp = np.flatnonzero(ev_resp == i)
            pings_here = np.where(d1[:, as_resp] <= cfg.max_range_m, t1[:, as_resp], np.inf)
            own_pings = t_tx[:, np.flatnonzero(sender == i)]
            own_replies = np.where(replied[:, as_resp], t2[:, as_resp], np.inf)
            # a reply that was never sent must not interfere: its time is moved out of the way
            tr_eff = np.where(replied[:, e], tr, np.inf)
            lost_e = self._channel(
                np.where(replied[:, e], d, np.inf),
                tr_eff,
                decoded,
                np.concatenate([own_pings, own_replies], axis=1),
                pings_here,
            )
            loss2[:, e] = lost_e
        lost = np.where(replied, loss2, loss1).astype(np.int8)
        c = cfg.nominal_sound_speed_m_s
        tx_local = np.broadcast_to(local[ev_q], shape).copy()
        rng_ = c * (l3 - tx_local - cfg.turnaround_s) / 2
        return NetworkRanges(
            self.vehicles,
            "twtt",
            c,
            ev_resp,
            ev_int,
            tx_local,
            np.where(replied, l3, l1),
            t_tx[:, ev_q],
            np.where(replied, t3, t1),
            np.where(replied, (d1 + d2) / 2, d1),
            np.where(replied, rng_, 0.0),
            np.where(replied, np.minimum(s1, s2), s1),
            lost == LOST_OK,
            lost,
            np.where(replied, t3, t1) + cfg.processing_delay_s,
        )
