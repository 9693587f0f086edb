"""Acoustic modem: the range between two vehicles' transducers, with the sender's broadcast.

Seed 003 (HS modem, section 3): the leader's transceiver measures the distance D_h to a
follower's transponder and sends it to that follower together with the leader's own position,
every 5 s (f_Dh = 0.2 Hz). The range error is the shared vocabulary's
(:mod:`bauv_sim.sensors.errors`); the default is the seed's: uniform on [-0.1, +0.1] m
(``sigma_m = 0.1``, ``uniform_k = 1``) plus a systematic 0.025 m (Tests 1-2; Test 3: 0.0025 m).

The range is the slant distance between the two vehicles' modem transducers (the ``modem`` site
of the vehicle model unless configured) computed from the truth at the time of validity. A range
is *not produced* (absent, never NaN) when the true range exceeds ``max_range_m``, when the
measured range is not above ``min_range_m`` (zero or degenerate), when the message is lost
(``dropout_probability``), in an outage window (``outages_s``), or, online, when the sender has
nothing to broadcast. It reaches the receiver after the acoustic travel time (true range /
``sound_speed_m_s``) plus ``processing_delay_s``.

**The message.** Each range carries the sender's :class:`~bauv_sim.sensors.online.Broadcast`: by
default its navigator's estimate at the time of sending (position of its reference point and of
its transducer, velocity over ground, its current estimate and, with ``send_covariance``, its
stated covariance); with
``broadcast = "truth"`` the sender's true state, as in the paper's experiment ("the simulated
coordinate values of the position of vehicle L sent to vehicle F are equal to their reference
values"), without a covariance, with the true current at the sender.

**Sharing the channel (TDMA).** Several receivers ranged by one sender take turns: receiver
``slot`` of ``slots`` is ranged at

    t = t0 + slot * period / slots + k * period,   k = 0, 1, 2, ...,   t0 = period

rounded down to the control tick: tick ``every + (slot * every) // slots + k * every`` with
``every = period / tick``. Consecutive slots are at least ``every // slots`` ticks apart; the
device refuses a configuration in which that is shorter than one exchange (``max_range_m /
sound_speed_m_s + processing_delay_s``), so exchanges never overlap on the channel.

:class:`Modem` is the batched form (kinematic truth arrays, any number of runs, the same error
model and streams); :class:`ModemDevice` is the online device of a receiver's rig (event), which
reads the sender from :attr:`~bauv_sim.sensors.online.TickContext.peers`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator

from bauv_sim import rng as rng_mod
from bauv_sim.acoustics.channel import reception_time
from bauv_sim.acoustics.clock import ClockConfig, draw_clocks
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.frames import R_from_quat_wxyz
from bauv_sim.sensors.base import SensorSamples, broadcast_runs, point_world
from bauv_sim.sensors.errors import ErrorProcess, LengthErrorConfig
from bauv_sim.sensors.online import (
    Broadcast,
    DeviceBuild,
    Measurement,
    TickContext,
    lever_arm_from_site,
    register_device,
)
from bauv_sim.truth import Truth
from nav.acoustics import Isovelocity, Propagation

Array = NDArray[np.float64]


def seed003_range_error(bias_m: float = 0.025) -> LengthErrorConfig:
    """Seed 003's range error: uniform on [-0.1, +0.1] m plus a bias (0.025 m in Tests 1-2,
    0.0025 m in Test 3)."""
    return LengthErrorConfig(distribution="uniform", sigma_m=0.1, uniform_k=1.0, bias_m=bias_m)


class ModemConfig(Config):
    """Acoustic modem ranging between vehicles (defaults: seed 003's HS modem)."""

    period_s: float = Field(5.0, gt=0, description="time between ranges to one receiver, s")
    range: LengthErrorConfig = Field(
        default_factory=seed003_range_error,
        description="range error (seed 003: uniform +-0.1 m, bias 0.025 m)",
    )
    max_range_m: float = Field(
        300.0, gt=0, description="no range beyond this true slant range, m (HS class: 300 m)"
    )
    min_range_m: float = Field(
        0.0, ge=0, description="a measured range not above this is not produced, m"
    )
    dropout_probability: float = Field(
        0.0, ge=0, lt=1, description="probability that a message is lost"
    )
    outages_s: tuple[tuple[float, float], ...] = Field(
        (), description="windows [start, end) in which no message gets through, s"
    )
    sound_speed_m_s: float = Field(1500.0, gt=0, description="for the travel-time latency, m/s")
    processing_delay_s: float = Field(
        0.5,
        ge=0,
        description="latency besides the travel time (range computed, message sent), s",
    )
    transducer_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="transducer relative to the reference point, m, body FLU (zero: the "
        "model's 'modem' site); the same on sender and receiver",
    )
    broadcast: Literal["estimate", "truth"] = Field(
        "estimate",
        description="the sender sends its navigator's estimate, or its true state (seed 003)",
    )
    send_covariance: bool = Field(True, description="send the sender's stated covariance")
    ranging: Literal["instant", "owtt"] = Field(
        "instant",
        description="'instant': the distance between the transducers at the slot's tick (seed "
        "003); 'owtt': one-way travel time, the sender transmitting at the slot by its clock "
        "and the receiver timing the arrival by its own (ModemDevice)",
    )
    clocks: dict[str, ClockConfig] = Field(
        default_factory=dict,
        description="'owtt': the vehicles' clocks by name (unlisted: a perfect clock)",
    )

    @field_validator("outages_s")
    @classmethod
    def _outages(cls, v: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float], ...]:
        for a, b in v:
            if not (0 <= a < b):
                raise ValueError(f"each window needs 0 <= start < end, got [{a}, {b})")
        return v

    @property
    def exchange_s(self) -> float:
        """The longest exchange: travel time at the maximum range plus the processing, s."""
        return self.max_range_m / self.sound_speed_m_s + self.processing_delay_s


def slot_offset_ticks(every: int, slot: int, slots: int) -> int:
    """Ticks from the start of a period to receiver ``slot``'s exchange (see the module
    docstring): ``(slot * every) // slots``."""
    return (slot * every) // slots


def slot_indices(n_ticks: int, every: int, slot: int = 0, slots: int = 1) -> NDArray[np.intp]:
    """Tick indices at which receiver ``slot`` of ``slots`` is ranged (TDMA, module docstring).

    Args:
        n_ticks: ticks on the grid (indices 0 .. n_ticks - 1).
        every: the period in ticks.
        slot: the receiver's slot, 0 <= slot < slots.
        slots: receivers sharing the channel.

    Returns:
        Indices, shape (k,): ``every + offset + m * every``.
    """
    if not 0 <= slot < slots:
        raise ValueError(f"slot = {slot}: must be in [0, {slots})")
    start = every + slot_offset_ticks(every, slot, slots)
    return np.arange(start, n_ticks, every, dtype=np.intp)


def check_slots(cfg: ModemConfig, tick_s: float, slots: int, field: str = "sensors.modem") -> int:
    """Check that ``slots`` exchanges fit in a period; returns the period in ticks.

    Raises:
        ConfigError: naming ``<field>.period_s`` if consecutive slots are closer than one
            exchange (:attr:`ModemConfig.exchange_s`) or than one tick.
    """
    ratio = cfg.period_s / tick_s
    every = round(ratio)
    if every < 1 or abs(ratio - every) > 1e-9 * max(1.0, ratio):
        raise ConfigError(
            f"{field}.period_s = {cfg.period_s:g}: must be a whole multiple (>= 1) of the tick "
            f"{tick_s:g} s"
        )
    gap_s = (every // slots) * tick_s
    if every // slots < 1 or gap_s < cfg.exchange_s - 1e-9:
        raise ConfigError(
            f"{field}.period_s = {cfg.period_s:g}: {slots} receivers get slots {gap_s:g} s "
            f"apart, shorter than one exchange ({cfg.exchange_s:g} s = max_range_m / "
            "sound_speed_m_s + processing_delay_s); lengthen the period or shorten the exchange"
        )
    return every


class Modem:
    """Ranges between two vehicles over a batch of runs (the error model of the module).

    Args:
        cfg: configuration.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this link (e.g. ``"f1/modem"``): each link draws its own errors.
        propagation: the sea's true medium (:class:`nav.acoustics.Propagation`), or ``None``:
            straight rays at ``sound_speed_m_s`` (the numbers before sound-speed profiles, bit
            for bit). With a medium, :meth:`sample` measures the nominal speed times the one-way
            travel time along the eigenray from the sender to the receiver (the range a modem
            reports), the range reaches the receiver after the true travel time, and no range is
            produced where no direct ray reaches the receiver (a shadow zone).
    """

    def __init__(
        self,
        cfg: ModemConfig,
        seed: int,
        runs: tuple[int, ...],
        name: str = "modem",
        propagation: Propagation | None = None,
    ):
        self.cfg = cfg
        self.propagation = propagation
        self.n = len(runs)
        base = ("sensor", name)
        self._err = ErrorProcess(cfg.range.to_model(), seed, runs, (*base, "range"))
        self._drop = (
            rng_mod.RunStreams(seed, runs, *base, "message_dropout")
            if cfg.dropout_probability > 0
            else None
        )

    def measure(
        self, true_range_m: Array, t_s: Array, travel_time_s: Array | None = None
    ) -> tuple[Array, NDArray[np.bool_], Array]:
        """Measure true slant ranges.

        Args:
            true_range_m: true ranges between the transducers, shape (n, k), m.
            t_s: times of validity, shape (k,), s.
            travel_time_s: one-way travel times along the eigenrays, shape (n, k), s (NaN: no
                direct ray), or ``None``: straight at ``sound_speed_m_s``. With them, the range
                before its errors is ``sound_speed_m_s * travel_time_s`` and the latency the
                travel time.

        Returns:
            ``(range_m, produced, t_arrival_s)``, each shape (n, k): the measured range (m,
            meaningless where not produced), whether it exists, and when it reaches the
            receiver (s).
        """
        c = self.cfg
        r = np.asarray(true_range_m, dtype=float)
        t = np.asarray(t_s, dtype=float)
        if travel_time_s is not None:
            return self._measure_travel(r, t, np.asarray(travel_time_s, dtype=float))
        meas, produced = self._err.apply(r, t)
        produced = produced & (r <= c.max_range_m) & (meas > c.min_range_m)
        produced &= np.isfinite(meas)
        for a, b in c.outages_s:
            produced &= ~((t >= a) & (t < b))[None, :]
        if self._drop is not None:
            k = r.shape[1]
            lost = self._drop.draw("random", k) < c.dropout_probability
            produced &= ~lost
        t_arr = t[None, :] + r / c.sound_speed_m_s + c.processing_delay_s
        return meas, produced, t_arr

    def _measure_travel(
        self, r: Array, t: Array, travel: Array
    ) -> tuple[Array, NDArray[np.bool_], Array]:
        """:meth:`measure` from travel times: the same errors, streams and losses, applied to
        the nominal speed times the travel time."""
        c = self.cfg
        reached = np.isfinite(travel)
        travel = np.where(reached, travel, r / c.sound_speed_m_s)
        meas, produced = self._err.apply(c.sound_speed_m_s * travel, t)
        produced = produced & reached & (r <= c.max_range_m) & (meas > c.min_range_m)
        produced &= np.isfinite(meas)
        for a, b in c.outages_s:
            produced &= ~((t >= a) & (t < b))[None, :]
        if self._drop is not None:
            lost = self._drop.draw("random", r.shape[1]) < c.dropout_probability
            produced &= ~lost
        t_arr = t[None, :] + travel + c.processing_delay_s
        return meas, produced, t_arr

    def sample(self, sender: Truth, receiver: Truth, index: NDArray[np.intp]) -> SensorSamples:
        """Ranges at the given tick indices from two truth records on the same time grid.

        Args:
            sender: the sender's truth (run axis 1 or n).
            receiver: the receiver's truth (run axis 1 or n).
            index: tick indices, shape (k,) (e.g. :func:`slot_indices`).

        Returns:
            Samples with values the measured range, shape (n, k), m.
        """
        arm = self.cfg.transducer_body_m
        a, b = sender.take(index), receiver.take(index)
        pa = broadcast_runs(point_world(a, arm), self.n)
        pb = broadcast_runs(point_world(b, arm), self.n)
        true_r = np.linalg.norm(pa - pb, axis=-1)
        travel = None
        if self.propagation is not None:
            travel = self.propagation.eigenray(pa, pb).travel_time_s
        meas, produced, t_arr = self.measure(true_r, a.t_s, travel)
        return SensorSamples(a.t_s, meas, produced, t_arr)


@register_device(ModemConfig)
class ModemDevice:
    """The modem of a receiver's rig (event): a range from the sender in the receiver's slot,
    with the sender's broadcast as the measurement's payload.

    Per-vehicle settings come from the mission through ``DeviceBuild.extra``: ``sender`` (the
    sending vehicle's name, default ``"leader"``), ``slot`` and ``slots`` (default 0 of 1).

    Value: the measured slant range between the transducers, shape (1,), m (with the sea's
    medium, ``DeviceBuild.propagation``: the nominal speed times the eigenray's travel time, as
    the batched :class:`Modem`). Payload: a :class:`~bauv_sim.sensors.online.Broadcast`.

    With ``ranging = "owtt"`` the range is a one-way travel time, as on the acoustic network
    (:mod:`bauv_sim.acoustics.network`): the sender transmits when its clock reads the slot's
    time ``T`` (true ``t_tx``, its transducer moved from the tick by its velocity), the sound
    reaches the receiver at ``t_rx`` (the fixed point of
    :func:`bauv_sim.acoustics.channel.reception_time` through the sea's medium,
    ``DeviceBuild.propagation``, or isovelocity at ``sound_speed_m_s``; the receiver moved by its
    velocity), which stamps it by its clock: the range ``sound_speed_m_s * (local(t_rx) - T)``
    then takes the error model and the limits (``max_range_m`` on that range); valid at
    ``t_rx``, arriving ``processing_delay_s`` later. Clocks from ``clocks``, drawn from the
    vehicles' streams ``("clock", <name>)``.

    Raises:
        ConfigError: if the sender is not in the scene, the slot is out of range, or the slots do
            not fit in a period (:func:`check_slots`).
    """

    kind = "event"

    def __init__(self, cfg: ModemConfig, build: DeviceBuild):
        configured = cfg.transducer_body_m
        cfg = build.with_lever_arm(cfg, "transducer_body_m")
        self.cfg = cfg
        self.name = build.name
        self.lever_arm_body_m = np.asarray(cfg.transducer_body_m, dtype=float)
        self.sender = str(build.extra.get("sender", "leader"))
        self.slot = int(build.extra.get("slot", 0))
        self.slots = int(build.extra.get("slots", 1))
        if self.sender not in build.physics.vehicle_names() or self.sender == build.vehicle:
            raise ConfigError(
                f"sensors.{self.name}: sender {self.sender!r} is not another vehicle of the scene "
                f"(vehicles: {', '.join(build.physics.vehicle_names())})"
            )
        if not 0 <= self.slot < self.slots:
            raise ConfigError(f"sensors.{self.name}: slot {self.slot} not in [0, {self.slots})")
        self.every = check_slots(cfg, build.tick_s, self.slots, f"sensors.{self.name}")
        self.first = self.every + slot_offset_ticks(self.every, self.slot, self.slots)
        # the sender's transducer: the configured lever arm, or the sender model's own site
        self.sender_arm = (
            np.asarray(lever_arm_from_site(build.physics, "modem", self.sender), dtype=float)
            if configured == (0.0, 0.0, 0.0)
            else self.lever_arm_body_m
        )
        self._modem = Modem(cfg, build.seed, (build.run,), build.stream, build.propagation)
        if cfg.ranging == "owtt":
            names = build.physics.vehicle_names()
            for name in cfg.clocks:
                if name not in names:
                    raise ConfigError(
                        f"sensors.{self.name}.clocks: {name!r} is not a vehicle of the scene "
                        f"(vehicles: {', '.join(names)})"
                    )
            runs = (build.run,)
            self._clock_rx, self._clock_tx = (
                draw_clocks(cfg.clocks.get(v, ClockConfig()), build.seed, runs, v)
                for v in (build.vehicle, self.sender)
            )
            self._medium = (
                build.propagation
                if build.propagation is not None
                else Isovelocity(cfg.sound_speed_m_s)
            )

    def due(self, k: int) -> bool:
        """Whether tick ``k`` is one of this receiver's slots."""
        return k >= self.first and (k - self.first) % self.every == 0

    def step(self, ctx: TickContext) -> Measurement | None:
        """A range at this receiver's slots (``None`` when none is produced)."""
        if not self.due(ctx.k):
            return None
        peer = ctx.peers.get(self.sender)
        if peer is None:
            return None
        me, other = ctx.truth, peer.truth
        p_me = me.position_world_m + R_from_quat_wxyz(me.quat_wxyz) @ self.lever_arm_body_m
        p_other = other.position_world_m + R_from_quat_wxyz(other.quat_wxyz) @ self.sender_arm
        if self.cfg.ranging == "owtt":
            meas, produced, t_valid, t_arrival = self._one_way(ctx, p_me, p_other, peer)
        else:
            true_r = math.dist(p_me, p_other)
            travel = None
            if self._modem.propagation is not None:
                # the range a modem reports: the nominal speed times the eigenray's travel time
                travel = self._modem.propagation.eigenray(p_other, p_me).travel_time_s
                travel = np.array([[float(travel)]])
            meas, produced, t_arr = self._modem.measure(np.array([[true_r]]), ctx.tt, travel)
            t_valid, t_arrival = ctx.t_s, float(t_arr[0, 0])
        if not produced[0, 0]:
            return None
        if self.cfg.broadcast == "truth":
            payload = Broadcast(
                self.sender,
                other.t_s,
                other.position_world_m.copy(),
                p_other,
                other.velocity_world_m_s[:2].copy(),
                None,
                other.current_world_m_s[:2].copy(),
            )
        else:
            sent = peer.broadcast
            if sent is None:
                return None
            payload = sent
            if not self.cfg.send_covariance and payload.covariance_m2 is not None:
                payload = dataclasses.replace(payload, covariance_m2=None)
        return Measurement(
            self.name,
            t_valid,
            t_arrival,
            meas[0],
            ctx.measured_attitude_rad,
            payload,
        )

    def _one_way(self, ctx: TickContext, p_me, p_other, peer) -> tuple:
        """The one-way range of this slot (class docstring): ``(range (1, 1), produced (1, 1),
        t_valid_s, t_arrival_s)``."""
        T = ctx.t_s
        t_tx = float(self._clock_tx.true_of_local(np.array([T]))[0])
        p_src = p_other + peer.truth.velocity_world_m_s * (t_tx - T)
        v_me = ctx.truth.velocity_world_m_s
        t_rx, _ = reception_time(
            self._medium,
            p_src[None],
            np.array([t_tx]),
            lambda tt: p_me + v_me * (tt - T)[..., None],
        )
        t_rx_s = float(t_rx[0])
        local = float(self._clock_rx.local(np.array([t_rx_s]))[0])
        r = self.cfg.sound_speed_m_s * (local - T)
        meas, produced, _ = self._modem.measure(np.array([[r]]), ctx.tt)
        return meas, produced, t_rx_s, t_rx_s + self.cfg.processing_delay_s
