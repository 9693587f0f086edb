"""The leader's part of ``mission/swarm``: the standard EKF and what it broadcasts at every tick
(:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import collections
import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import R_from_roll_pitch_heading, unit_vector_scalar
from bauv_sim.sensors.online import Broadcast
from bauv_sim.sensors.rig import RigTick
from nav.cooperative import PeerEstimate
from tasks.closed_loop.navigation import EkfNavigation, NavOutput
from tasks.missions.swarm.network import NETWORK, NetworkLog
from tasks.missions.swarm.relay import RelayBook, RelayBroadcast, Relayed
from tasks.missions.swarm.scenario import LEADER

Array = NDArray[np.float64]


class LeaderNavigation:
    """The standard navigation part, and the leader's broadcast at every tick.

    Args:
        ekf: the standard navigation part.
        transducer_body_m: the leader's modem transducer, body FLU, m.
        window_ticks: the broadcast velocity is averaged over this many ticks.
        network: on the acoustic network (issue 24), where the ranges it receives are kept
            (:class:`~tasks.missions.swarm.network.NetworkLog`; its EKF does not use them), or
            ``None``.
        clock: what it states of its clock on the network, (offset s, variance s^2): the
            team's time reference (:func:`~tasks.missions.swarm.options.leader_clock_statement`);
            ``None`` off the network.
        relays: on the network with ``navigation.coop.relay``, the ranges it received that its
            broadcast relays to their senders (:mod:`tasks.missions.swarm.relay`), each with its
            transducer at the reception (its EKF's position moved back by its velocity, the
            EKF's covariance, the clock stated), or ``None``.
    """

    def __init__(
        self,
        ekf: EkfNavigation,
        transducer_body_m: Array,
        window_ticks: int,
        network: NetworkLog | None = None,
        clock: tuple[float, float] | None = None,
        relays: RelayBook | None = None,
    ):
        self.ekf = ekf
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self._v: collections.deque[tuple[float, float]] = collections.deque(maxlen=window_ticks)
        self.network = network
        self.clock = clock
        self.relays = relays

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        out = self.ekf.step(tick, initial)
        e, n = unit_vector_scalar(out.heading_rad)
        self._v.append((out.speed_m_s * e, out.speed_m_s * n))
        v = np.mean(self._v, axis=0)
        if out.current_m_s is not None:
            v = v + out.current_m_s
        roll, pitch = out.ins[0], out.ins[1]
        x = out.estimate.x
        R = R_from_roll_pitch_heading(roll, pitch, out.heading_rad)
        cur = None if out.current_m_s is None else np.asarray(out.current_m_s, dtype=float).copy()
        P = out.estimate.P[:2, :2].copy()
        b = Broadcast(LEADER, out.t_s, x.copy(), x + R @ self.arm, v, P, cur)
        if self.network is not None:
            for m in tick.arrived:
                if m.device == NETWORK:
                    self.network.add(m)
                    if self.relays is not None:
                        self._keep(m, b)
        if self.clock is not None:
            b = dataclasses.replace(
                b, clock_offset_s=self.clock[0], clock_offset_var_s2=self.clock[1]
            )
        if self.relays is not None:
            b = RelayBroadcast(**vars(b), relayed=self.relays.outgoing(out.t_s))
        return dataclasses.replace(out, broadcast=b)

    def _keep(self, m, b: Broadcast) -> None:
        """Keep a range it received to relay it, with its transducer at the reception."""
        a = m.payload
        lag = b.t_s - a.rx_local_s  # its clock is the team's time
        at_rx = b.transducer_world_m - np.array([*(b.velocity_world_m_s * lag), 0.0])
        offset, var = self.clock if self.clock is not None else (0.0, 0.0)
        est = PeerEstimate.from_parts(at_rx[None, :2], b.covariance_m2[None], [offset], [var])
        depth = -float(at_rx[2])
        self.relays.keep(Relayed(a.sender, a.tx_local_s, a.rx_local_s, a.range_m, est, depth))

    def outcome(self) -> dict[str, Any]:
        out = self.ekf.outcome()
        return out if self.network is None else {**out, **self.network.outcome()}
