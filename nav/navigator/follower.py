"""A follower navigating on acoustic ranges to another vehicle's broadcast position (seed 003).

The follower dead-reckons on its compass and log and, at each range from its modem, corrects its
estimate with seed 003's GA1 or GA2 fix or the range EKF (:class:`nav.relative.FollowerNavigator`:
eq. 1-8, and :class:`nav.relative.RangeMeasurement`, the range to the leader's broadcast
position), or ignores the ranges (``"dr"``). What it knows of the leader is the leader's last
message (:class:`LeaderState`: its position, its modem transducer's position, its velocity over
ground, its covariance and the current its own navigator estimates), which it moves on with the
stated velocity to the present.

**Geometry of a range.** The modem measures the slant range between the transducers. The
follower turns it into the horizontal range with the depth difference (its own pressure depth,
the leader's stated transducer depth, and its transducer's lever arm in the world frame) and
takes the circle around the leader's transducer, moved on with the leader's velocity over the
latency, less its own lever arm: exact for the reference point. A slant range not longer than the
depth difference has no horizontal solution (``"degenerate"``).

**The current** (beyond the paper; ``use_leader_current``): the follower cannot measure the
current and eq. 1 has none; it dead-reckons over ground with the current the leader sends (the
course and speed of its through-water velocity plus that current). The pure DR track
(:class:`nav.dead_reckoning.DeadReckoning`) is always the compass + log track through water.

The estimate it states is three-dimensional: the method's horizontal position and covariance,
and the pressure depth with the variance ``depth_sigma_m**2`` (:class:`FollowerOptions`).
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from nav.angles import course_of_scalar, unit_vector_scalar
from nav.dead_reckoning import DeadReckoning
from nav.navigator.online import Estimate
from nav.relative import FollowerNavigator, GaOptions, hdop

Array = NDArray[np.float64]


class LeaderState(Protocol):
    """What a leader's message states about it (any object with these attributes).

    Attributes:
        t_s: time of the statement, s.
        position_world_m: its reference point (east, north, up), shape (3,), m, world.
        transducer_world_m: its modem transducer, shape (3,), m, world.
        velocity_world_m_s: its velocity over ground (east, north), shape (2,), m/s.
        covariance_m2: its horizontal position covariance, shape (2, 2), m^2, or ``None``.
        current_world_m_s: the current its navigator estimates (east, north), shape (2,), m/s,
            or ``None``.
    """

    t_s: float
    position_world_m: Array
    transducer_world_m: Array
    velocity_world_m_s: Array
    covariance_m2: Array | None
    current_world_m_s: Array | None


@dataclass(frozen=True)
class FollowerOptions:
    """Settings of :class:`BroadcastRangeNavigator`.

    Attributes:
        method: ``"ga1"``, ``"ga2"`` (seed 003 eq. 3, 4), ``"ekf"`` (the range EKF) or ``"dr"``.
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.
        ga: GA readings and guards (:class:`nav.relative.GaOptions`).
        initial_sigma_m: the start position's standard deviation per axis, m.
        gate_probability: the range EKF's chi-square gate, or ``None``.
        use_leader_covariance: the range EKF adds the leader's stated covariance to the range's.
        use_leader_current: dead-reckon over ground with the current the leader sends.
        dr_warning_s: an interval without an accepted range this long is a DR gap, s.
        depth_sigma_m: standard deviation of the stated depth (the pressure depth), m.
        hdop_cap: HDOP reported in place of a larger or infinite one.
        leader_course_min_speed_m_s: the leader's course is taken from its stated velocity only
            above this speed, m/s.
    """

    method: Literal["ga1", "ga2", "ekf", "dr"]
    sigma_course_rad: float
    sigma_speed_m_s: float
    ga: GaOptions
    initial_sigma_m: float = 1.0
    gate_probability: float | None = None
    use_leader_covariance: bool = True
    use_leader_current: bool = True
    dr_warning_s: float = 60.0
    depth_sigma_m: float = 0.05
    hdop_cap: float = 100.0
    leader_course_min_speed_m_s: float = 0.05


@dataclass(frozen=True)
class RangeFixResult:
    """What one range did.

    Attributes:
        accepted: whether the estimate was corrected.
        reason: ``"ok"`` or why not (:class:`nav.relative.FixOutcome`'s reasons, or
            ``"degenerate"``: a slant range not longer than the depth difference).
        range_m: the slant range, m.
        horizontal_m: the horizontal range (0 when degenerate), m.
        centre_m: the circle's centre for the reference point, shape (2,), m, world.
        hdop: eq. 7-8 at the fix (``inf`` if singular, 0 when not computed).
        criterion: ``V^T P V`` (GA) or the NIS (EKF); 0 otherwise.
        position_m: the estimate after the range, shape (3,), m, world (up = -depth).
    """

    accepted: bool
    reason: str
    range_m: float
    horizontal_m: float
    centre_m: Array
    hdop: float
    criterion: float
    position_m: Array


@dataclass(frozen=True)
class FollowerReport:
    """What the follower's navigation reports at a tick, beside its estimate.

    Attributes:
        leader: the leader's latest message (:class:`LeaderState`).
        leader_est: the leader's position now, dead-reckoned from it, shape (2,), m, world.
        leader_course: the leader's stated course, rad clockwise from north.
        hdop: seed 003 eq. 7-8 for the current geometry (capped at ``hdop_cap``).
        since_fix: time since the last accepted range, s.
        fix_event: whether a range was accepted at this tick.
        current: the current the follower dead-reckons with (east, north), shape (2,), m/s.
    """

    leader: LeaderState
    leader_est: Array
    leader_course: float
    hdop: float
    since_fix: float
    fix_event: bool
    current: Array


class BroadcastRangeNavigator:
    """One follower's online navigation on ranges to a leader's broadcast position (module
    docstring).

    Args:
        options: the method and its settings.
        x0: the initial estimate, shape (3,), m, world (up = -depth).
        plan: the leader's planned start, used until its first message.
        history_ticks: ticks between the start of the DR segment the current geometry's HDOP
            uses and now (one modem period).
    """

    def __init__(self, options: FollowerOptions, x0: Array, plan: LeaderState, history_ticks: int):
        o = self.options = options
        self.method = o.method
        self.nav = FollowerNavigator(
            o.method,
            x0[:2],
            o.sigma_course_rad,
            o.sigma_speed_m_s,
            o.ga,
            initial_cov=o.initial_sigma_m**2 * np.eye(2),
            gate_probability=o.gate_probability,
        )
        self.dr = DeadReckoning(np.asarray(x0[:2], dtype=float))
        self.current = np.zeros(2)
        self.leader = plan
        self.leader_course = course_of_scalar(*plan.velocity_world_m_s)
        self.t_prev = 0.0
        self.speed = 0.0
        self.depth = -float(x0[2])
        self.last_fix_s = 0.0
        self.gaps: list[tuple[float, float]] = []
        self.counts: collections.Counter[str] = collections.Counter()
        self.fix_hdops: list[float] = []
        self._hist: collections.deque[Array] = collections.deque(maxlen=history_ticks + 1)

    def advance(
        self,
        t_s: float,
        heading_rad: float,
        speed_m_s: float | None,
        depth_m: float | None,
        initial: bool = False,
    ) -> None:
        """One tick of dead reckoning (eq. 1) with the measured heading and speed.

        Args:
            t_s: time, s.
            heading_rad: measured heading, rad clockwise from north.
            speed_m_s: measured speed through water, m/s, or ``None`` (a blind log: the last).
            depth_m: measured depth, m, or ``None`` (the last).
            initial: the first tick (nothing to advance).
        """
        if speed_m_s is not None:
            self.speed = speed_m_s
        if depth_m is not None:
            self.depth = depth_m
        if not initial:
            dt = t_s - self.t_prev
            e, n = unit_vector_scalar(heading_rad)
            self.dr.advance(dt * self.speed * np.array([e, n]))
            ve, vn = self.speed * e + self.current[0], self.speed * n + self.current[1]
            self.nav.advance(course_of_scalar(ve, vn), math.hypot(ve, vn), dt)
        self.t_prev = t_s

    def range_fix(
        self,
        t_s: float,
        t_valid_s: float,
        slant_range_m: float,
        leader: LeaderState,
        arm_world_m: Array,
    ) -> RangeFixResult:
        """Use one range and the leader's message that came with it (module docstring).

        Args:
            t_s: arrival time (now), s.
            t_valid_s: the range's time of validity, s.
            slant_range_m: the measured slant range between the transducers, m.
            leader: the leader's message.
            arm_world_m: this vehicle's transducer lever arm rotated into the world frame by its
                measured attitude, shape (3,), m.
        """
        b = self.leader = leader
        o = self.options
        if self.method != "dr" and o.use_leader_current and b.current_world_m_s is not None:
            self.current = np.asarray(b.current_world_m_s, dtype=float).copy()
        v = b.velocity_world_m_s
        if math.hypot(v[0], v[1]) > o.leader_course_min_speed_m_s:
            self.leader_course = course_of_scalar(v[0], v[1])
        arm = arm_world_m
        centre = b.transducer_world_m[:2] + v * (t_s - t_valid_s) - arm[:2]
        r = slant_range_m
        dz = float(b.transducer_world_m[2]) - (-self.depth + arm[2])
        cov = b.covariance_m2 if o.use_leader_covariance else None
        if r * r <= dz * dz:
            accepted, reason, h, crit, horiz = False, "degenerate", 0.0, 0.0, 0.0
        else:
            horiz = math.sqrt(r * r - dz * dz)
            out = self.nav.fix(centre, horiz, cov)
            accepted, reason, h, crit = out.accepted, out.reason, out.hdop, out.criterion
        self.counts["accepted" if accepted else reason] += 1
        if accepted:
            self.fix_hdops.append(h if math.isfinite(h) else o.hdop_cap)
        p = self.nav.position
        return RangeFixResult(
            accepted, reason, r, horiz, centre, h, crit, np.array([p[0], p[1], -self.depth])
        )

    def end_tick(self, t_s: float, fix_event: bool) -> tuple[Estimate, FollowerReport]:
        """Close a tick: the estimate and the report (call once per tick, after its ranges).

        Args:
            t_s: time, s.
            fix_event: whether a range was accepted at this tick.
        """
        if fix_event:
            if t_s - self.last_fix_s >= self.options.dr_warning_s:
                self.gaps.append((self.last_fix_s, t_s))
            self.last_fix_s = t_s
        p = self.nav.position
        b = self.leader
        leader_now = b.position_world_m[:2] + b.velocity_world_m_s * (t_s - b.t_s)
        self._hist.append(p)
        start = self._hist[0]
        h = float(hdop(start[None], p[None], leader_now[None])[0])
        cov = self.nav.covariance
        P = np.zeros((3, 3))
        P[:2, :2] = cov
        P[2, 2] = self.options.depth_sigma_m**2
        x = np.array([p[0], p[1], -self.depth])
        cap = self.options.hdop_cap
        report = FollowerReport(
            leader=b,
            leader_est=leader_now,
            leader_course=self.leader_course,
            hdop=min(h, cap) if math.isfinite(h) else cap,
            since_fix=t_s - self.last_fix_s,
            fix_event=fix_event,
            current=self.current.copy(),
        )
        return Estimate(t_s, x, P), report

    @property
    def dr_position(self) -> Array:
        """The pure compass + log track, shape (3,), m, world (up = -depth)."""
        return np.array([*self.dr.position, -self.depth])

    def dr_gaps_s(self) -> list[tuple[float, float]]:
        """The intervals without an accepted range of ``dr_warning_s`` or longer, s (the last one
        still open now included; none for ``"dr"``)."""
        if self.method == "dr":
            return []
        gaps = list(self.gaps)
        if self.t_prev - self.last_fix_s >= self.options.dr_warning_s:
            gaps.append((self.last_fix_s, self.t_prev))
        return gaps

    @property
    def mean_fix_hdop(self) -> float:
        """Mean HDOP of the accepted fixes (0 without any)."""
        return float(np.mean(self.fix_hdops)) if self.fix_hdops else 0.0
