"""A follower's navigation part in ``mission/swarm``: the adapter of its rig to
:class:`nav.navigator.BroadcastRangeNavigator` (seed 003's methods on ranges to the leader's
broadcast), and the per-tick columns a follower adds (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import R_from_roll_pitch_heading
from bauv_sim.sensors.online import Broadcast
from bauv_sim.sensors.rig import RigTick
from nav.navigator import BroadcastRangeNavigator, FollowerOptions
from nav.relative import GaOptions
from tasks.closed_loop.navigation import FixRecord, NavOutput
from tasks.missions.swarm.network import NETWORK, NetworkLog
from tasks.missions.swarm.scenario import (
    DEPTH_SIGMA_M,
    LEADER,
    REFUSAL_CODES,
    REFUSALS,
    FollowerNavigationConfig,
)

Array = NDArray[np.float64]


class FollowerNavigation:
    """A follower's navigation part: the rig's compass, log, pressure and modem records fed to
    :class:`nav.navigator.BroadcastRangeNavigator` (seed 003's methods on ranges to the leader's
    broadcast position; see the module docstring).

    Args:
        cfg: the followers' navigation settings.
        method: ``ga1``, ``ga2``, ``ekf`` or ``dr``.
        x0: the initial estimate, shape (3,), m, world (up = -depth).
        transducer_body_m: this follower's modem transducer, body FLU, m.
        plan: the leader's planned start (position, velocity) as a broadcast at t = 0, used
            until the first message.
        period_s: the modem period (the HDOP of the current geometry takes the estimate one
            period ago as the start of the DR segment), s.
        tick_s: control tick, s.
        network: on the acoustic network (issue 24), where the ranges it receives are kept
            (:class:`~tasks.missions.swarm.network.NetworkLog`), or ``None`` (the modem). On the
            network the method uses the ranges from the leader alone, with the leader's
            broadcast its packet carries, as the modem's: the clocks' offsets are not modelled
            (they bias the range by the sound speed times their difference).

    The output's ``report`` is a :class:`nav.navigator.FollowerReport` (the leader's latest
    message and its position now, its course, the HDOP, the time since the last accepted range,
    whether one was accepted at this tick, the current dead-reckoned with).

    Beyond the paper (``cfg.current = "leader"``): the follower cannot measure the current, and
    the paper's DR (eq. 1) has none. An unmodelled cross current (0.2 m/s: 1 m between two
    ranges) reads, through the anisotropic DR covariance of eq. 5 (sigma_S along the track,
    S sigma_C across), as an along-track error that a range abeam cannot observe, and the fixes
    drag the estimate along the track (measured: the estimates run away within minutes). The
    leader's EKF estimates the current in the same water and sends it with each range; the
    follower dead-reckons over ground with it (course and speed of its through-water velocity
    plus that current). Learning the current from the follower's own corrections was tried and
    fails the same way: in a turn the along-track position error becomes observable and is read
    as current. The ``dr`` method uses no message at all (the paper's DR); the output's
    ``dr_position_m`` is always the pure compass + log track.
    """

    def __init__(
        self,
        cfg: FollowerNavigationConfig,
        method: str,
        x0: Array,
        transducer_body_m: Array,
        plan: Broadcast,
        period_s: float,
        tick_s: float,
        network: NetworkLog | None = None,
    ):
        self.cfg = cfg
        self.method = method
        sigma_c = cfg.sigma_course_deg
        if method == "ekf" and cfg.ekf_sigma_course_deg is not None:
            sigma_c = cfg.ekf_sigma_course_deg
        options = FollowerOptions(
            method=method,  # type: ignore[arg-type]
            sigma_course_rad=math.radians(sigma_c),
            sigma_speed_m_s=cfg.sigma_speed_m_s,
            ga=GaOptions(
                jacobian=cfg.jacobian,
                restart=cfg.restart,
                sigma_range_m=cfg.sigma_range_m,
                min_range_m=cfg.min_range_m,
            ),
            initial_sigma_m=cfg.initial_sigma_m,
            gate_probability=cfg.gate_probability,
            use_leader_covariance=cfg.use_leader_covariance,
            use_leader_current=cfg.current == "leader",
            dr_warning_s=cfg.dr_warning_s,
            depth_sigma_m=DEPTH_SIGMA_M,
        )
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self.network = network
        self.nav = BroadcastRangeNavigator(options, x0, plan, max(1, round(period_s / tick_s)))

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        t = tick.t_s
        heading = tick.value("compass")
        log_speed = tick.value("log")
        nav = self.nav
        nav.advance(t, heading, log_speed, tick.value("pressure"), initial)
        fixes, accepted_now = [], False
        for m in tick.arrived:
            if m.device == NETWORK and self.network is not None:
                self.network.add(m)
                a = m.payload
                if a.sender != LEADER or a.broadcast is None:
                    continue
                m = dataclasses.replace(m, t_valid_s=a.rx_local_s, payload=at_transmission(a))
            elif m.device != "modem":
                continue
            rec = self._range(t, m)
            fixes.append(rec)
            accepted_now |= rec.accepted
        est, report = nav.end_tick(t, accepted_now)
        return NavOutput(
            t_s=t,
            estimate=est,
            dr_position_m=nav.dr_position,
            current_m_s=None,
            heading_rad=heading,
            speed_m_s=nav.speed,
            speed_from_log=log_speed is not None,
            odometry_speed_m_s=nav.speed,
            depth_m=nav.depth,
            ins=tick.held["ins"],
            fixes=tuple(fixes),
            gps_fix=False,
            report=report,
        )

    def _range(self, t: float, m) -> FixRecord:
        """Apply one modem message (see the module docstring for the geometry)."""
        roll, pitch, heading = m.attitude_rad
        arm = R_from_roll_pitch_heading(roll, pitch, heading) @ self.arm
        res = self.nav.range_fix(t, m.t_valid_s, float(m.value[0]), m.payload, arm)
        h, crit, centre = res.hdop, res.criterion, res.centre_m
        z = np.array(
            [
                res.range_m,
                res.horizontal_m,
                centre[0],
                centre[1],
                min(h, 100.0) if math.isfinite(h) else 100.0,
                crit if math.isfinite(crit) else 0.0,
                float(REFUSAL_CODES.get(res.reason, len(REFUSALS))),
            ]
        )
        return FixRecord("modem", m.t_valid_s, t, z, res.accepted, res.position_m)

    def outcome(self) -> dict[str, Any]:
        """Fix counts by outcome, the mean HDOP of accepted fixes, and the intervals without an
        accepted range longer than ``dr_warning_s`` (the last one still open at the end)."""
        nav = self.nav
        out = {
            "method": self.method,
            "fix_counts": dict(nav.counts),
            "mean_fix_hdop": nav.mean_fix_hdop,
            "dr_gaps_s": [list(g) for g in nav.dr_gaps_s()],
        }
        return out if self.network is None else {**out, **self.network.outcome()}


EN = ("east", "north")
FOLLOWER_COLUMNS = {
    "hdop": (
        "hdop",
        "1",
        "HDOP of the current geometry (seed 003 eq. 7-8; capped at 100)",
        (),
        False,
    ),
    "since_fix": ("since_fix", "s", "time since the last accepted range", (), False),
    "fix_event": ("fix_event", "bool", "a range was accepted at this tick", (), False),
    "leader_est": (
        "leader_est",
        "m",
        "the leader's position as the follower knows it now (last message, dead-reckoned)",
        EN,
        False,
    ),
    "leader_course": ("leader_course", "rad", "the leader's stated course", (), False),
    "current_est": ("current", "m/s", "the follower's current estimate (zero: none)", EN, False),
}
"""The per-tick columns a follower adds (see :class:`~tasks.closed_loop.parts.VehicleParts`)."""


def at_transmission(a) -> Broadcast:
    """The leader's broadcast a network packet carries (made at the tick at or before the
    transmission) moved on with its stated velocity to the transmission's scheduled time, the
    leader's clock being the team's time (``a``: an
    :class:`~bauv_sim.acoustics.network.AcousticRange`)."""
    b = a.broadcast
    dt = a.tx_local_s - b.t_s
    move = np.array([*(b.velocity_world_m_s * dt), 0.0])
    return dataclasses.replace(
        b,
        t_s=a.tx_local_s,
        position_world_m=b.position_world_m + move,
        transducer_world_m=b.transducer_world_m + move,
    )
