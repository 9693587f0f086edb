"""Relayed ranges on the acoustic network of ``mission/swarm`` (issue 24): a vehicle's broadcast
carries the one-way ranges it received in the last cycle back to their senders
(``navigation.coop.relay``; :mod:`tasks.missions.swarm`).

A one-way range from j to i is ``|p_j - p_i| + c (b_i - b_j)``: alone, i cannot tell the clocks'
offset difference from the distance. Relayed back, the range i received from j, with i's
estimate at its reception, reaches j, which also has the range it received from i: the two
directions of the pair hold the distance with opposite clock terms, and the offsets become
observable (the relay of :func:`nav.cooperative.team_tracks`, ``CoopOptions.relay``; the
original sender fuses it with ``CoopNavigator.fuse_range(..., sent_by_me=True)``). The packet
that carries the relays is the broadcast itself (:class:`RelayBroadcast`, a
:class:`~bauv_sim.sensors.online.Broadcast` with the relayed ranges), so the network device
delivers them unchanged with the relaying vehicle's next transmission.
"""

from __future__ import annotations

from dataclasses import dataclass

from bauv_sim.sensors.online import Broadcast
from nav.cooperative import PeerEstimate


@dataclass(frozen=True)
class Relayed:
    """A one-way range a vehicle received, relayed to the vehicle that sent it.

    Attributes:
        sender: the vehicle that transmitted the range (the one to fuse it).
        tx_local_s: its scheduled transmission, by its clock, s.
        rx_local_s: the relaying vehicle's reception stamp, by its clock, s.
        range_m: the range, ``c_nom (rx_local - tx_local)``, m.
        estimate: the relaying vehicle's transducer (east, north) and clock offset at the
            reception, with their covariance (one run).
        depth_m: the relaying vehicle's transducer depth at the reception, m.
    """

    sender: str
    tx_local_s: float
    rx_local_s: float
    range_m: float
    estimate: PeerEstimate
    depth_m: float


@dataclass(frozen=True)
class RelayBroadcast(Broadcast):
    """A broadcast with the ranges its sender received in the last cycle (module docstring).

    Attributes:
        relayed: the ranges, oldest first.
    """

    relayed: tuple[Relayed, ...] = ()


class RelayBook:
    """One vehicle's relays: those it keeps to send (received in the last ``window_s``) and
    those addressed to it that it has fused (each once).

    Args:
        name: the vehicle's name.
        window_s: how long a received range stays in the broadcasts, s (two TDMA cycles: a
            range that reaches the navigator after the vehicle's slot of this cycle goes with
            its slot of the next one; the receiver fuses each once).
    """

    def __init__(self, name: str, window_s: float):
        self.name, self.window_s = name, window_s
        self.pending: list[Relayed] = []
        self.used: set[tuple[str, float, float]] = set()

    def keep(self, r: Relayed) -> None:
        """Keep a range this vehicle received, to relay it."""
        self.pending.append(r)

    def outgoing(self, now_local_s: float) -> tuple[Relayed, ...]:
        """The ranges to relay now (received within ``window_s`` of ``now_local_s``)."""
        self.pending = [r for r in self.pending if r.rx_local_s > now_local_s - self.window_s]
        return tuple(self.pending)

    def incoming(self, relayer: str, b: Broadcast) -> list[Relayed]:
        """The ranges this vehicle sent that ``relayer`` relays in ``b`` and that it has not
        fused yet (marked fused)."""
        out = []
        for r in getattr(b, "relayed", ()):
            key = (relayer, r.tx_local_s, r.rx_local_s)
            if r.sender == self.name and key not in self.used:
                self.used.add(key)
                out.append(r)
        return out
