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
map contracts by ``|v_i| / c`` (about 1e-3) per iteration, so
:data:`~bauv_sim.acoustics.channel.FIXED_POINT_ITERATIONS` iterations leave ``(1e-3)^6`` of
the first guess's error (the guess is off by ``tau |v_i| / c``, below 1 ms at 1 km and 2 m/s).
The receiver stamps the arrival with its clock, ``L = local_i(t_rx) + jitter_i * z1 +
travel_time_sigma_s * z2`` (timestamp jitter of the receiver's clock and the
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

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim import rng as rng_mod
from bauv_sim.acoustics.channel import (
    interpolate_positions,
    neighbour_gaps,
    reception_time,
    schedule,
    slot_senders,
)
from bauv_sim.acoustics.clock import Clock, ClockConfig, draw_clocks
from bauv_sim.acoustics.sonar import SonarConfig, snr_db, success_probability
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.frames import R_from_quat_wxyz
from bauv_sim.sensors.online import (
    Broadcast,
    DeviceBuild,
    Measurement,
    TickContext,
    lever_arm_from_site,
    register_device,
)
from nav.acoustics import Isovelocity, Propagation

Array = NDArray[np.float64]

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
    transducer_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="online device: transducer relative to the reference point, m, body FLU "
        "(zero: each vehicle model's 'modem' site); the same on every vehicle",
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


# ----------------------------------------------------------------------------------------------
# The online device


@dataclass(frozen=True)
class AcousticRange:
    """The payload of an acoustic range (:class:`AcousticNetworkDevice`).

    Attributes:
        sender: the transmitting vehicle's name.
        receiver: the receiving vehicle's name (the device's own).
        tx_local_s: scheduled transmit time by the sender's clock, s.
        rx_local_s: the receiver's timestamp of the arrival, by its clock, s.
        travel_time_s: measured travel time ``rx_local_s - tx_local_s``, s.
        range_m: ``nominal_sound_speed_m_s * travel_time_s``, m.
        snr_db: the sonar equation's SNR at the true range, dB.
        kind: ``"owtt"``.
        broadcast: what the sender stated about itself at its transmit tick (its position,
            covariance and clock estimate), or ``None`` when it broadcasts nothing.
    """

    sender: str
    receiver: str
    tx_local_s: float
    rx_local_s: float
    travel_time_s: float
    range_m: float
    snr_db: float
    kind: str
    broadcast: Broadcast | None = None


@dataclass
class _Arrival:
    """A transmission heard by the device, waiting until its collisions are known."""

    sender: int
    tx_local_s: float
    t_tx_s: float
    t_rx_s: float
    distance_m: float
    snr_db: float
    rx_local_s: float
    decoded: bool
    broadcast: Broadcast | None


@register_device(AcousticNetworkConfig)
class AcousticNetworkDevice:
    """The acoustic network as a receiver's rig hears it (event; OWTT; module docstring).

    Per-vehicle settings from the mission (``DeviceBuild.extra``): ``vehicles`` (the team's
    names in the scene's order, the schedule's; default the scene's vehicles) and ``me`` (this
    vehicle's name; default the rig's vehicle).

    At the tick at or before each scheduled transmission's true instant (the senders' clocks are
    drawn from the same streams as :class:`AcousticNetwork`'s) the device takes the sender's
    transducer at that tick, moved by the sender's velocity to the transmit instant, and solves
    the reception time with this vehicle's transducer moved by its velocity from the tick (the
    rotation of the lever arms during the travel is neglected); it draws the event's noise and
    sonar loss from this vehicle's streams, in the schedule's order, as the batched class does,
    so that the same truth gives the same numbers (up to the interpolation against the
    extrapolation: equal on straight lines). Once no later packet can arrive within
    ``packet_s`` it applies the range, half-duplex, collision and sonar losses and emits a
    :class:`~bauv_sim.sensors.online.Measurement` (at most one per tick, the others next ticks)
    valid at the reception, arriving ``processing_delay_s`` later, value ``(range_m,)``, payload
    :class:`AcousticRange`.

    Raises:
        ConfigError: for two-way ranging (the online device ranges one way), a vehicle not in
            ``vehicles``, or a schedule that does not fit (:func:`slot_senders`).
    """

    kind = "event"
    every = 1

    def __init__(self, cfg: AcousticNetworkConfig, build: DeviceBuild):
        self.cfg = cfg
        self.name = build.name
        if cfg.ranging != "owtt":
            raise ConfigError(
                f"sensors.{self.name}.ranging = {cfg.ranging!r}: the online device ranges one "
                "way ('owtt'); two-way ranging is the batched AcousticNetwork's"
            )
        names = build.extra.get("vehicles")
        self.vehicles = tuple(names if names is not None else build.physics.vehicle_names())
        me = str(build.extra.get("me", build.vehicle))
        if me not in self.vehicles:
            raise ConfigError(
                f"sensors.{self.name}: vehicle {me!r} is not in the network "
                f"({', '.join(self.vehicles)})"
            )
        slot_senders(cfg, self.vehicles)
        self.me, self.i = me, self.vehicles.index(me)
        runs = (build.run,)
        self.clocks = [draw_clocks(cfg.clock_of(v), build.seed, runs, v) for v in self.vehicles]
        self._recv = _Receiver(cfg, self.clocks[self.i], build.seed, runs, me)
        self.propagation = (
            build.propagation
            if build.propagation is not None
            else Isovelocity(cfg.nominal_sound_speed_m_s)
        )
        if cfg.transducer_body_m == (0.0, 0.0, 0.0):
            self.arms = {
                v: np.asarray(lever_arm_from_site(build.physics, "modem", v), dtype=float)
                for v in self.vehicles
            }
        else:
            arm = np.asarray(cfg.transducer_body_m, dtype=float)
            self.arms = dict.fromkeys(self.vehicles, arm)
        self.lever_arm_body_m = self.arms[me]
        self.tick_s = build.tick_s
        self._cycle = 0
        self._upcoming: list[tuple[int, float, float]] = []  # (sender, local T, true t_tx)
        self._own: list[float] = []  # own true transmit times
        self._arrivals: list[_Arrival] = []  # heard, in range, recent (for collisions)
        self._waiting: list[_Arrival] = []  # not yet resolved
        self._ready: list[Measurement] = []

    def _extend_schedule(self, until_s: float) -> None:
        """Schedule cycles until one starts (by true time, every sender) after ``until_s``."""
        cfg = self.cfg
        while True:
            first = cfg.start_s + self._cycle * cfg.period_s
            sender, local = schedule(cfg, self.vehicles, first, first + cfg.period_s * (1 - 1e-12))
            self._cycle += 1
            t_tx = [
                float(self.clocks[j].true_of_local(np.array([T]))[0])
                for j, T in zip(sender, local, strict=True)
            ]
            self._upcoming += [
                (int(j), float(T), t) for j, T, t in zip(sender, local, t_tx, strict=True)
            ]
            if t_tx and min(t_tx) > until_s + cfg.period_s:
                return
            if not t_tx and first > until_s + cfg.period_s:
                return

    def _transducer(self, vt, name: str) -> Array:
        return vt.position_world_m + R_from_quat_wxyz(vt.quat_wxyz) @ self.arms[name]

    def _hear(self, ctx: TickContext, j: int, T: float, t_tx: float) -> None:
        """The arrival of sender ``j``'s transmission at local ``T`` (true ``t_tx``)."""
        name = self.vehicles[j]
        peer = ctx.peers.get(name)
        noise = self._recv.timestamp_noise(1)
        dt = t_tx - ctx.t_s
        if peer is None:  # not in the scene: nothing arrives (the draws are kept in step)
            self._recv.decoded(np.zeros((1, 1)))
            return
        p_src = self._transducer(peer.truth, name) + peer.truth.velocity_world_m_s * dt
        p0 = self._transducer(ctx.truth, self.me)
        v0 = ctx.truth.velocity_world_m_s
        t0 = ctx.t_s
        t_rx, p_rx = reception_time(
            self.propagation,
            p_src[None],
            np.array([t_tx]),
            lambda tt: p0 + v0 * (tt - t0)[..., None],
        )
        dist = np.linalg.norm(p_rx - p_src[None], axis=-1)
        snr = snr_db(dist, self.cfg.sonar)
        decoded = bool(self._recv.decoded(snr[None])[0, 0])
        t_rx_s = float(t_rx[0])
        local = float(self.clocks[self.i].local(np.array([t_rx_s]))[0] + noise[0, 0])
        a = _Arrival(
            j, T, t_tx, t_rx_s, float(dist[0]), float(snr[0]), local, decoded, peer.broadcast
        )
        self._waiting.append(a)
        if a.distance_m <= self.cfg.max_range_m:
            self._arrivals.append(a)

    def _resolve(self, a: _Arrival, ctx: TickContext) -> None:
        cfg = self.cfg
        if a.distance_m > cfg.max_range_m:
            return
        p = cfg.packet_s
        if any(abs(t - a.t_rx_s) < p for t in self._own):
            return
        if any(b is not a and abs(b.t_rx_s - a.t_rx_s) < p for b in self._arrivals):
            return
        if not a.decoded:
            return
        c = cfg.nominal_sound_speed_m_s
        travel = a.rx_local_s - a.tx_local_s
        payload = AcousticRange(
            self.vehicles[a.sender],
            self.me,
            a.tx_local_s,
            a.rx_local_s,
            travel,
            c * travel,
            a.snr_db,
            "owtt",
            a.broadcast,
        )
        self._ready.append(
            Measurement(
                self.name,
                a.t_rx_s,
                a.t_rx_s + cfg.processing_delay_s,
                np.array([c * travel]),
                ctx.measured_attitude_rad,
                payload,
            )
        )

    def step(self, ctx: TickContext) -> Measurement | None:
        """Hear the transmissions of this tick, resolve the arrivals whose neighbours are known,
        and hand over the oldest range ready (``None`` if none)."""
        horizon = ctx.t_s + self.tick_s
        self._extend_schedule(horizon)
        later = []
        for j, T, t_tx in self._upcoming:
            if t_tx < horizon:
                if j == self.i:
                    self._own.append(t_tx)
                else:
                    self._hear(ctx, j, T, t_tx)
            else:
                later.append((j, T, t_tx))
        self._upcoming = later
        p = self.cfg.packet_s
        waiting = []
        for a in self._waiting:
            if a.t_rx_s + p < horizon:
                self._resolve(a, ctx)
            else:
                waiting.append(a)
        self._waiting = waiting
        old = ctx.t_s - 2 * p - self.tick_s
        self._own = [t for t in self._own if t > old - p]
        keep_from = min([a.t_rx_s for a in self._waiting], default=ctx.t_s) - 2 * p
        self._arrivals = [a for a in self._arrivals if a.t_rx_s > min(old, keep_from)]
        return self._ready.pop(0) if self._ready else None
