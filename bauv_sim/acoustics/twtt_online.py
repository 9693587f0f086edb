"""Two-way ranging as one interrogator's device follows it, tick by tick (the online counterpart
of :class:`bauv_sim.acoustics.network.AcousticNetwork`'s TWTT; the model is stated in
:mod:`bauv_sim.acoustics.network`).

The interrogator's range to a responder depends on more than its own legs: the reply exists only
if the responder decoded the ping, which depends on what else arrived at the responder (other
interrogators' pings) and on the responder's own transmissions, and the responder's draws
(its ``"ping"`` streams) advance with every ping it hears. :class:`TwttListener` therefore
follows the first leg of every ping at every responder (their draws in the schedule's order, as
the batched class draws them) and the second leg of this vehicle's own pings, and resolves a leg
once no later packet can arrive near it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.acoustics.channel import ReceiverDraws, reception_time
from bauv_sim.acoustics.clock import Clock
from bauv_sim.acoustics.sonar import snr_db
from nav.acoustics import Propagation

if TYPE_CHECKING:
    from bauv_sim.acoustics.network import AcousticNetworkConfig

Array = NDArray[np.float64]

Mover = Callable[[Array], Array]
"""A vehicle's transducer at true times (shape (1,) -> (1, 3)), extrapolated from a tick."""


@dataclass
class PingLeg:
    """A ping's arrival at one responder, and the reply it triggers.

    Attributes:
        responder: the responder's index.
        t1_s: true arrival of the ping, s.
        distance_m: the leg's true distance, m.
        snr_db: its SNR, dB.
        decoded: whether the sonar equation decodes it.
        t2_s: true instant the reply leaves (whether or not it does), s.
        reply_world_m: the responder's transducer at ``t2_s``, shape (3,), m.
        ok: the ping was received (set when resolved; ``None`` before).
    """

    responder: int
    t1_s: float
    distance_m: float
    snr_db: float
    decoded: bool
    t2_s: float
    reply_world_m: Array
    ok: bool | None = None


@dataclass
class TwttEvent:
    """A range of this vehicle to one responder (an event of :class:`NetworkRanges`).

    Attributes:
        responder: the responder's index.
        tx_local_s: the ping's scheduled local time, s.
        turnaround_s: the responder's delay, s.
        leg1: the ping's arrival at the responder.
        t3_s: true arrival of the reply, s.
        distance_m: the reply leg's true distance, m.
        snr_db: the weaker leg's SNR, dB.
        decoded: whether the reply is decoded by the sonar equation.
        rx_local_s: this vehicle's timestamp of the reply, s.
        broadcast: the responder's broadcast at the ping's tick.
        produced: whether the range exists (set when resolved).
    """

    responder: int
    tx_local_s: float
    turnaround_s: float
    leg1: PingLeg
    t3_s: float
    distance_m: float
    snr_db: float
    decoded: bool
    rx_local_s: float
    broadcast: Any
    produced: bool | None = None


class TwttListener:
    """Follows the TWTT exchanges for interrogator ``me`` (module docstring).

    Args:
        cfg: the network.
        clocks: every vehicle's clock (one run).
        draws: this vehicle's draws of the replies it receives.
        ping_draws: every vehicle's draws of the pings it receives (streams ``"ping"``).
        propagation: the true medium.
        me: this vehicle's index.
    """

    def __init__(
        self,
        cfg: AcousticNetworkConfig,
        clocks: Sequence[Clock],
        draws: ReceiverDraws,
        ping_draws: Sequence[ReceiverDraws],
        propagation: Propagation,
        me: int,
    ):
        self.cfg, self.clocks, self.me = cfg, clocks, me
        self.draws, self.ping_draws, self.propagation = draws, ping_draws, propagation
        self.v = len(clocks)
        self._legs: list[PingLeg] = []  # every ping's arrival at every responder, recent
        self._pings: list[tuple[int, float]] = []  # (sender, true t_tx), recent
        self._events: list[TwttEvent] = []  # this vehicle's, not yet resolved
        self._recent: list[TwttEvent] = []  # this vehicle's, resolved, recent

    def ping(
        self,
        sender: int,
        tx_local_s: float,
        t_tx_s: float,
        at: Sequence[Mover],
        broadcasts: Sequence[Any],
    ) -> None:
        """A ping scheduled at ``tx_local_s`` (true ``t_tx_s``) by ``sender``.

        Args:
            sender: the interrogator's index.
            tx_local_s: scheduled local time, s.
            t_tx_s: true transmit time, s.
            at: each vehicle's transducer at true times (``None`` for a vehicle not in the
                scene: nothing reaches it, its draws kept in step).
            broadcasts: each vehicle's broadcast at this tick.
        """
        cfg = self.cfg
        self._pings.append((sender, t_tx_s))
        src = at[sender](np.array([t_tx_s]))[0] if at[sender] is not None else None
        for j in range(self.v):
            if j == sender:
                continue
            draws = self.ping_draws[j]
            noise = draws.timestamp_noise(1)[0, 0]
            if src is None or at[j] is None:
                draws.decoded(np.zeros((1, 1)))
                leg = PingLeg(j, np.inf, np.inf, -np.inf, False, np.inf, np.zeros(3))
            else:
                t1, p1 = reception_time(self.propagation, src[None], np.array([t_tx_s]), at[j])
                d1 = float(np.linalg.norm(p1[0] - src))
                s1 = float(snr_db(d1, cfg.sonar))
                decoded = bool(draws.decoded(np.array([[s1]]))[0, 0])
                rank = j - (j > sender)
                turn = cfg.turnaround_s + rank * cfg.reply_stagger_s
                l1 = float(self.clocks[j].local(t1)[0]) + noise
                t2 = float(self.clocks[j].true_of_local(np.array([l1 + turn]))[0])
                leg = PingLeg(j, float(t1[0]), d1, s1, decoded, t2, at[j](np.array([t2]))[0])
            self._legs.append(leg)
            if sender == self.me:
                self._reply(leg, tx_local_s, at, broadcasts[j])

    def _reply(self, leg: PingLeg, tx_local_s: float, at: Sequence[Mover], broadcast) -> None:
        """The second leg of this vehicle's ping to ``leg.responder`` (its draws are drawn
        whether or not the reply will exist, as in the batched class)."""
        cfg = self.cfg
        noise = self.draws.timestamp_noise(1)[0, 0]
        rank = leg.responder - (leg.responder > self.me)
        turn = cfg.turnaround_s + rank * cfg.reply_stagger_s
        if not np.isfinite(leg.t2_s):
            self.draws.decoded(np.zeros((1, 1)))
            t3, d2, s2, decoded = np.inf, np.inf, -np.inf, False
        else:
            src = leg.reply_world_m
            t3a, p3 = reception_time(self.propagation, src[None], np.array([leg.t2_s]), at[self.me])
            t3, d2 = float(t3a[0]), float(np.linalg.norm(p3[0] - src))
            s2 = float(snr_db(d2, cfg.sonar))
            decoded = bool(self.draws.decoded(np.array([[s2]]))[0, 0])
        local = float(self.clocks[self.me].local(np.array([t3]))[0]) + noise
        self._events.append(
            TwttEvent(
                leg.responder,
                tx_local_s,
                turn,
                leg,
                t3,
                d2,
                min(leg.snr_db, s2),
                decoded,
                local,
                broadcast,
            )
        )

    def _resolve_leg(self, leg: PingLeg) -> None:
        cfg, p = self.cfg, self.cfg.packet_s
        j = leg.responder
        if leg.distance_m > cfg.max_range_m:
            leg.ok = False
        elif any(s == j and abs(t - leg.t1_s) < p for s, t in self._pings):
            leg.ok = False
        elif any(
            o is not leg
            and o.responder == j
            and o.distance_m <= cfg.max_range_m
            and abs(o.t1_s - leg.t1_s) < p
            for o in self._legs
        ):
            leg.ok = False
        else:
            leg.ok = leg.decoded

    def _resolve_event(self, e: TwttEvent) -> None:
        cfg, p, me = self.cfg, self.cfg.packet_s, self.me
        if not e.leg1.ok or e.distance_m > cfg.max_range_m:
            e.produced = False
            return
        own = [t for s, t in self._pings if s == me]
        own += [o.t2_s for o in self._legs if o.responder == me and o.ok]
        if any(abs(t - e.t3_s) < p for t in own):
            e.produced = False
            return
        others = [
            o.t3_s
            for o in (*self._events, *self._recent)
            if o is not e and o.leg1.ok and o.distance_m <= cfg.max_range_m
        ]
        others += [
            o.t1_s for o in self._legs if o.responder == me and o.distance_m <= cfg.max_range_m
        ]
        if any(abs(t - e.t3_s) < p for t in others):
            e.produced = False
            return
        e.produced = e.decoded

    def resolve(self, horizon_s: float, keep_after_s: float) -> list[TwttEvent]:
        """Resolve what no later packet can change (every ping before ``horizon_s`` heard).

        Args:
            horizon_s: true time before which every ping has been passed to :meth:`ping`, s.
            keep_after_s: forget legs and pings older than this, s.

        Returns:
            This vehicle's events resolved now, in the schedule's order (produced or not).
        """
        p = self.cfg.packet_s
        for leg in self._legs:
            if leg.ok is None and leg.t1_s + p < horizon_s:
                self._resolve_leg(leg)
        done, waiting = [], []
        for e in self._events:
            # the reply's neighbours: replies of later pings, and this vehicle's own replies to
            # pings whose first leg is resolved one packet after their arrival
            if e.leg1.ok is not None and e.t3_s + 2 * p < horizon_s:
                done.append(e)
            else:
                waiting.append(e)
        for e in done:
            self._resolve_event(e)
        self._events = waiting
        self._recent = [e for e in (*self._recent, *done) if e.t3_s > keep_after_s]
        self._legs = [g for g in self._legs if g.ok is None or g.t2_s > keep_after_s]
        self._pings = [(s, t) for s, t in self._pings if t > keep_after_s]
        return done
