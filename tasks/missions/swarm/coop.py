"""Decentralised cooperative navigation of a follower in ``mission/swarm`` (issue 24): the
follower's navigation part for ``navigation.method = "decentralised"``, and its settings
(:mod:`tasks.missions.swarm`).

The follower runs :class:`nav.cooperative.CoopNavigator` (its position and clock offset, and the
clock's drift with ``coop.estimate_drift``) on the acoustic network (:mod:`tasks.missions.swarm.
network`):

* **prediction**: every tick, the step over ground dead-reckoned from the compass and the log
  with the current the leader sends (as the seed 003 methods of
  :class:`~tasks.missions.swarm.follower.FollowerNavigation` do), its covariance seed 003's eq. 5
  (:func:`nav.relative.dr_increment_covariance`);
* **a range from any vehicle** (the leader or a follower): the one-way travel-time range with the
  sender's broadcast carried by its packet (estimate, covariance, clock offset estimate and its
  variance), fused by covariance intersection (Julier & Uhlmann 1997; ``coop.fusion = "naive"``
  counts the peer as independent, for comparison). The sender's transducer is taken at its
  transmission, ``t_tx = T - b_j`` (its scheduled local time less its clock estimate): its
  broadcast position moved on with its stated velocity from the broadcast's time, less this
  vehicle's own lever arm rotated by its measured attitude (the circle of the reference point, as
  seed 003's follower takes it); the receiver's state, ``lag = now - (L - b_i)`` after the
  reception, is moved back by its velocity over ground inside the measurement model, the DR
  noise over that lag added to the range's variance (the last step's covariance per second times
  the lag, its mean over the two axes). The depths
  are this vehicle's pressure depth at its transducer and the sender's stated transducer depth;
* **its broadcast** at every tick (:class:`~bauv_sim.sensors.online.Broadcast`): its position and
  transducer, velocity over ground, covariance, the leader's current it dead-reckons with, and
  its clock offset estimate with its variance: what its next packet carries.

What it knows of the leader for station keeping is the leader's last broadcast received with a
range, moved on with the leader's velocity (the report of seed 003's follower,
:class:`nav.navigator.FollowerReport`, so that :class:`~tasks.missions.swarm.station.
StationGuidance` steers it unchanged).
"""

from __future__ import annotations

import collections
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import R_from_roll_pitch_heading
from bauv_sim.sensors.online import Broadcast
from bauv_sim.sensors.rig import RigTick
from nav.angles import course_of_scalar, unit_vector_scalar
from nav.cooperative import CoopNavigator, CoopOptions, PeerEstimate
from nav.dead_reckoning import DeadReckoning
from nav.navigator import Estimate, FollowerReport
from nav.relative import dr_increment, dr_increment_covariance, hdop
from tasks.closed_loop.navigation import FixRecord, NavOutput
from tasks.missions.swarm.network import NETWORK, NetworkLog
from tasks.missions.swarm.options import current_covariance
from tasks.missions.swarm.relay import RelayBook, RelayBroadcast, Relayed

Array = NDArray[np.float64]


class CoopFollowerNavigation:
    """A follower's decentralised navigation part (module docstring).

    Args:
        name: this vehicle's name in the scene.
        vehicle: its index in the team (0: the leader; its clock options).
        leader: the leader's name.
        options: the filter's options (:meth:`CoopNavigationConfig.options`).
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.
        current_sigma_m_s: the current's uncertainty in each step (:func:`current_covariance`).
        sigma_range_m: the ranges' standard deviation the filter assumes, m.
        sound_speed_m_s: the network's nominal sound speed, m/s.
        x0: the initial estimate, shape (3,), m, world (up = -depth).
        initial_sigma_m: its standard deviation per axis, m.
        transducer_body_m: this follower's transducer, body FLU, m.
        plan: the leader's planned start as a broadcast at t = 0, used until its first packet.
        log: where every range received is kept.
        history_ticks: ticks between the start of the DR segment the HDOP uses and now.
        depth_sigma_m: standard deviation of the stated depth, m.
        use_leader_current: dead-reckon over ground with the current the leader sends.
        dr_warning_s: an interval without an accepted range this long is a DR gap, s.
        refusal_codes: the modem table's refusal codes by reason.
        relay_window_s: with ``options.relay``, how long a received range is relayed in the
            broadcasts (two TDMA cycles), s (:mod:`tasks.missions.swarm.relay`).
    """

    method = "decentralised"

    def __init__(
        self,
        name: str,
        vehicle: int,
        leader: str,
        options: CoopOptions,
        sigma_course_rad: float,
        sigma_speed_m_s: float,
        current_sigma_m_s: float,
        sigma_range_m: float,
        sound_speed_m_s: float,
        x0: Array,
        initial_sigma_m: float,
        transducer_body_m: Array,
        plan: Broadcast,
        log: NetworkLog,
        history_ticks: int,
        depth_sigma_m: float,
        use_leader_current: bool,
        dr_warning_s: float,
        refusal_codes: dict[str, int],
        relay_window_s: float,
    ):
        self.name, self.leader_name = name, leader
        self.nav = CoopNavigator.for_vehicle(
            vehicle, x0[None, :2], initial_sigma_m**2 * np.eye(2)[None], options
        )
        self.sigma_c, self.sigma_s = sigma_course_rad, sigma_speed_m_s
        self.current_sigma_m_s = current_sigma_m_s
        self.sigma_range_m, self.c = sigma_range_m, sound_speed_m_s
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self.leader = plan
        self.leader_course = course_of_scalar(*plan.velocity_world_m_s)
        self.log = log
        self.depth_sigma_m = depth_sigma_m
        self.use_leader_current = use_leader_current
        self.dr_warning_s = dr_warning_s
        self.codes = refusal_codes
        self.dr = DeadReckoning(np.asarray(x0[:2], dtype=float))
        self.current = np.zeros(2)
        self.velocity = np.zeros(2)
        self._q_rate = np.zeros((2, 2))
        self.relays = RelayBook(name, relay_window_s) if options.relay else None
        self.speed, self.depth = 0.0, -float(x0[2])
        self.t_prev, self.last_fix_s = 0.0, 0.0
        self.gaps: list[tuple[float, float]] = []
        self.counts: collections.Counter[str] = collections.Counter()
        self.fix_hdops: list[float] = []
        self.ci_weights: list[float] = []
        self._hist: collections.deque[Array] = collections.deque(maxlen=history_ticks + 1)

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        t = tick.t_s
        heading = tick.value("compass")
        log_speed, depth = tick.value("log"), tick.value("pressure")
        if log_speed is not None:
            self.speed = log_speed
        if depth is not None:
            self.depth = depth
        e, n = unit_vector_scalar(heading)
        if not initial:
            dt = t - self.t_prev
            self.dr.advance(dt * self.speed * np.array([e, n]))
            v = self.speed * np.array([e, n]) + self.current
            course, speed = np.array([course_of_scalar(*v)]), np.array([math.hypot(*v)])
            q = dr_increment_covariance(course, speed, dt, self.sigma_c, self.sigma_s)
            q = q + current_covariance(dt, self.current_sigma_m_s)
            self.nav.predict(dr_increment(course, speed, dt), q, dt)
            self._q_rate = q[0] / dt
        self.t_prev = t
        self.velocity = self.speed * np.array([e, n]) + self.current
        fixes, accepted_now = [], False
        for m in tick.arrived:
            if m.device == NETWORK:
                self.log.add(m)
                rec = self._range(t, m)
                if rec is not None:
                    fixes.append(rec)
                    accepted_now |= rec.accepted
        est, report = self._end_tick(t, accepted_now)
        x = est.x
        arm = R_from_roll_pitch_heading(*tick.held["ins"][:2], heading) @ self.arm
        offset, var = float(self.nav.clock_offset[0]), float(self.nav.clock_variance[0])
        broadcast = Broadcast(
            self.name,
            t,
            x.copy(),
            x + arm,
            self.velocity.copy(),
            est.P[:2, :2].copy(),
            self.current.copy(),
            offset,
            var,
        )
        if self.relays is not None:
            relayed = self.relays.outgoing(t + offset)
            broadcast = RelayBroadcast(**vars(broadcast), relayed=relayed)
        return NavOutput(
            t_s=t,
            estimate=est,
            dr_position_m=np.array([*self.dr.position, -self.depth]),
            current_m_s=None,
            heading_rad=heading,
            speed_m_s=self.speed,
            speed_from_log=log_speed is not None,
            odometry_speed_m_s=self.speed,
            depth_m=self.depth,
            ins=tick.held["ins"],
            fixes=tuple(fixes),
            gps_fix=False,
            report=report,
            broadcast=broadcast,
        )

    def _range(self, t: float, m) -> FixRecord | None:
        """Fuse one range with the sender's broadcast (module docstring); ``None`` when the
        packet carried no broadcast."""
        a = m.payload
        b: Broadcast | None = a.broadcast
        if b is None:
            self.counts["no broadcast"] += 1
            return None
        if a.sender == self.leader_name:
            self.leader = b
            if self.use_leader_current and b.current_world_m_s is not None:
                self.current = np.asarray(b.current_world_m_s, dtype=float).copy()
            v = b.velocity_world_m_s
            if math.hypot(v[0], v[1]) > 0.05:
                self.leader_course = course_of_scalar(v[0], v[1])
        arm = R_from_roll_pitch_heading(*m.attitude_rad) @ self.arm
        if b.clock_offset_s is None:
            b_j, var_j = 0.0, self.nav.clock.offset_sigma_s**2
        else:
            b_j, var_j = b.clock_offset_s, b.clock_offset_var_s2 or 0.0
        t_tx = a.tx_local_s - b_j
        centre = b.transducer_world_m[:2] + b.velocity_world_m_s * (t_tx - b.t_s) - arm[:2]
        cov = np.zeros((2, 2)) if b.covariance_m2 is None else b.covariance_m2
        peer = PeerEstimate.from_parts(centre[None], cov[None], [b_j], [var_j])
        lag = t - (a.rx_local_s - float(self.nav.clock_offset[0]))
        depth_i = self.depth - arm[2]
        depth_j = -float(b.transducer_world_m[2])
        if self.relays is not None:
            self._relayed(t, a.sender, b, arm, depth_i)
            made = self.nav.broadcast(np.array([-lag]), self.velocity[None])
            mine = PeerEstimate(made.position_m + arm[:2], made.clock_offset_s, made.cov_m2)
            self.relays.keep(
                Relayed(a.sender, a.tx_local_s, a.rx_local_s, a.range_m, mine, depth_i)
            )
        info, w = self.nav.fuse_range(
            np.array([a.range_m]),
            peer,
            sigma_m=self.sigma_range_m,
            depth_m=depth_i,
            peer_depth_m=depth_j,
            kind="owtt",
            sound_speed_m_s=self.c,
            lag_s=lag,
            velocity_m_s=self.velocity[None],
            extra_var_m2=np.array([0.5 * np.trace(self._q_rate) * max(lag, 0.0)]),
        )
        accepted = bool(info.applied[0])
        if accepted:
            reason = "ok"
            self.ci_weights.append(float(w[0]))
        elif bool(info.rejected[0]):
            reason = "gate"
        else:
            reason = "range below minimum"
        self.counts["accepted" if accepted else reason] += 1
        dz = depth_i - depth_j
        horiz = math.sqrt(a.range_m**2 - dz**2) if a.range_m**2 > dz**2 else 0.0
        nis = float(info.nis[0])
        p = self.nav.position[0]
        z = np.array(
            [
                a.range_m,
                horiz,
                centre[0],
                centre[1],
                0.0,
                nis if math.isfinite(nis) else 0.0,
                float(self.codes[reason]),
            ]
        )
        return FixRecord(
            "modem", m.t_valid_s, t, z, accepted, np.array([p[0], p[1], -self.depth]), nis
        )

    def _relayed(self, t: float, relayer: str, b: Broadcast, arm: Array, depth_m: float) -> None:
        """Fuse the ranges this vehicle sent that ``relayer`` relays in its broadcast ``b``
        (:mod:`~tasks.missions.swarm.relay`): this vehicle at its transmission (``T - b_i``, its
        state moved back by its velocity), the relayer's transducer at its reception less this
        vehicle's lever arm."""
        for r in self.relays.incoming(relayer, b):
            e = r.estimate
            peer = PeerEstimate(e.position_m - arm[:2], e.clock_offset_s, e.cov_m2)
            lag = t - (r.tx_local_s - float(self.nav.clock_offset[0]))
            info, _ = self.nav.fuse_range(
                np.array([r.range_m]),
                peer,
                sigma_m=self.sigma_range_m,
                depth_m=depth_m,
                peer_depth_m=r.depth_m,
                kind="owtt",
                sound_speed_m_s=self.c,
                lag_s=lag,
                velocity_m_s=self.velocity[None],
                sent_by_me=True,
                extra_var_m2=np.array([0.5 * np.trace(self._q_rate) * max(lag, 0.0)]),
            )
            self.counts["relayed accepted" if info.applied[0] else "relayed refused"] += 1

    def _end_tick(self, t: float, fix_event: bool) -> tuple[Estimate, FollowerReport]:
        """The estimate and the seed 003 follower's report of this tick."""
        if fix_event:
            if t - self.last_fix_s >= self.dr_warning_s:
                self.gaps.append((self.last_fix_s, t))
            self.last_fix_s = t
        p = self.nav.position[0].copy()
        b = self.leader
        leader_now = b.position_world_m[:2] + b.velocity_world_m_s * (t - b.t_s)
        self._hist.append(p)
        h = float(hdop(self._hist[0][None], p[None], leader_now[None])[0])
        P = np.zeros((3, 3))
        P[:2, :2] = self.nav.covariance[0]
        P[2, 2] = self.depth_sigma_m**2
        report = FollowerReport(
            leader=b,
            leader_est=leader_now,
            leader_course=self.leader_course,
            hdop=min(h, 100.0) if math.isfinite(h) else 100.0,
            since_fix=t - self.last_fix_s,
            fix_event=fix_event,
            current=self.current.copy(),
        )
        return Estimate(t, np.array([p[0], p[1], -self.depth]), P), report

    def outcome(self) -> dict[str, Any]:
        """Range counts by outcome, the mean CI weight of the accepted ranges, the DR gaps (as
        :meth:`FollowerNavigation.outcome`), the final clock estimate and what the network
        delivered (:class:`~tasks.missions.swarm.network.NetworkLog`)."""
        gaps = list(self.gaps)
        if self.t_prev - self.last_fix_s >= self.dr_warning_s:
            gaps.append((self.last_fix_s, self.t_prev))
        return {
            "method": self.method,
            "fix_counts": dict(self.counts),
            "mean_fix_hdop": 0.0,
            "mean_ci_weight": float(np.mean(self.ci_weights)) if self.ci_weights else 0.0,
            "dr_gaps_s": [list(g) for g in gaps],
            "clock_offset_s": float(self.nav.clock_offset[0]),
            **self.log.outcome(),
        }
