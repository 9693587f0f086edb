"""The parts of ``mission/swarm``'s vehicles: the leader's broadcast, a follower's navigation
(the adapter of its rig to :class:`nav.navigator.BroadcastRangeNavigator`) and station keeping,
and the mission's design (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import collections
import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.build import SceneConfig, VehicleSpec
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.frames import (
    R_from_roll_pitch_heading,
    unit_vector_scalar,
    wrap_2pi_scalar,
)
from bauv_sim.sensors.online import Broadcast, lever_arm_from_site
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.guidance import GuidanceCommand
from nav.navigator import BroadcastRangeNavigator, FollowerOptions, FollowerReport
from nav.relative import GaOptions
from tasks.closed_loop.navigation import EkfNavigation, FixRecord, NavOutput, report_of
from tasks.closed_loop.parts import MissionParts, VehicleParts
from tasks.closed_loop.scenario import (
    StartConfig,
)
from tasks.closed_loop.world import place_vehicle, scenario_sea, standard_vehicle, streams
from tasks.missions.swarm.scenario import (
    DEPTH_SIGMA_M,
    FOLLOWERS,
    LEADER,
    REFUSAL_CODES,
    REFUSALS,
    FollowerNavigationConfig,
    StationConfig,
    StationGuidanceConfig,
    SwarmScenario,
    station_offsets,
)

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# The leader's part: the standard EKF and what it broadcasts


class LeaderNavigation:
    """The standard navigation part, and the leader's broadcast at every tick.

    Args:
        ekf: the standard navigation part.
        transducer_body_m: the leader's modem transducer, body FLU, m.
        window_ticks: the broadcast velocity is averaged over this many ticks.
    """

    def __init__(self, ekf: EkfNavigation, transducer_body_m: Array, window_ticks: int):
        self.ekf = ekf
        self.arm = np.asarray(transducer_body_m, dtype=float)
        self._v: collections.deque[tuple[float, float]] = collections.deque(maxlen=window_ticks)

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
        return dataclasses.replace(out, broadcast=b)

    def outcome(self) -> dict[str, Any]:
        return self.ekf.outcome()


# ---------------------------------------------------------------------------------------------
# A follower's parts


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
        self.nav = BroadcastRangeNavigator(options, x0, plan, max(1, round(period_s / tick_s)))

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        t = tick.t_s
        heading = tick.value("compass")
        log_speed = tick.value("log")
        nav = self.nav
        nav.advance(t, heading, log_speed, tick.value("pressure"), initial)
        fixes, accepted_now = [], False
        for m in tick.arrived:
            if m.device == "modem":
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
        return {
            "method": self.method,
            "fix_counts": dict(nav.counts),
            "mean_fix_hdop": nav.mean_fix_hdop,
            "dr_gaps_s": [list(g) for g in nav.dr_gaps_s()],
        }


@dataclass
class StationGuidance:
    """Station keeping on the follower's estimate (module docstring).

    Args:
        cfg: the gains and limits.
        station: the station relative to the leader.
        tick_s: control tick, s.
        leader_done: whether the leader's pattern is over (the mission ends with it).
    """

    cfg: StationGuidanceConfig
    station: StationConfig
    tick_s: float
    leader_done: Callable[[], bool]

    def __post_init__(self) -> None:
        self._integral = np.zeros(2)
        self.bearing = math.radians(self.station.relative_bearing_deg)

    @property
    def done(self) -> bool:
        return self.leader_done()

    def station_point(self, leader_xy: Array, leader_course: float) -> Array:
        """The station for a leader position (2,) m and course (rad), shape (2,), m."""
        return leader_xy + self.station.distance_m * np.array(
            unit_vector_scalar(leader_course + self.bearing)
        )

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        c = self.cfg
        rep = report_of(nav, FollowerReport)
        course_l = rep.leader_course
        speed_l = float(np.hypot(*rep.leader.velocity_world_m_s))
        s = self.station_point(rep.leader_est, course_l)
        e = s - nav.estimate.x[:2]
        corr = c.gain_per_s * e
        norm = float(np.hypot(*corr))
        if norm > c.max_correction_m_s:
            corr *= c.max_correction_m_s / norm
        self._integral += c.integral_gain_per_s2 * e * self.tick_s
        norm = float(np.hypot(*self._integral))
        if norm > c.max_integral_m_s:
            self._integral *= c.max_integral_m_s / norm
        u = np.array(unit_vector_scalar(course_l))
        n = np.array([u[1], -u[0]])  # to starboard of the leader's course
        w = corr + self._integral
        along = max(speed_l + float(w @ u), c.min_speed_m_s)
        cross = float(w @ n)
        lim = math.tan(math.radians(c.max_crossing_deg))
        cross = max(-lim * along, min(lim * along, cross))
        course = wrap_2pi_scalar(course_l + math.atan2(cross, along))
        speed = min(max(math.hypot(along, cross), c.min_speed_m_s), c.max_speed_m_s)
        mode = "done" if self.done else "transit"
        return GuidanceCommand(course, c.depth_m, speed, mode, 0)

    def waypoints(self) -> list[tuple[float, float, float]]:
        return []

    def legs(self) -> list[dict[str, Any]]:
        return []

    def outcome(self) -> dict[str, Any]:
        return {
            "relative_bearing_deg": self.station.relative_bearing_deg,
            "distance_m": self.station.distance_m,
        }


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


@dataclass(frozen=True)
class SwarmMission:
    """The design of one flight: the leader and its followers, each follower navigating with
    ``method``.

    Attributes:
        method: the followers' method (``ga1``, ``ga2``, ``ekf``, ``dr``).
    """

    method: str = "ga1"

    def vehicle_names(self, scn: SwarmScenario) -> tuple[str, ...]:
        return (LEADER, *FOLLOWERS[: scn.followers.count])

    def _nominal(self, scn: SwarmScenario) -> list[tuple[str, float, float]]:
        st = scn.leader.start
        h = math.radians(st.heading_deg)
        out = [(LEADER, st.east_m, st.north_m)]
        for name, s in zip(FOLLOWERS, station_offsets(scn), strict=False):
            e, n = unit_vector_scalar(h + math.radians(s.relative_bearing_deg))
            out.append((name, st.east_m + s.distance_m * e, st.north_m + s.distance_m * n))
        return out

    def scene(self, scn: SwarmScenario) -> SceneConfig:
        st = scn.leader.start
        vehicles = tuple(
            VehicleSpec(
                name=name,
                east_m=e,
                north_m=n,
                depth_m=st.depth_m if name == LEADER else scn.station.depth_m,
                heading_deg=st.heading_deg,
            )
            for name, e, n in self._nominal(scn)
        )
        return SceneConfig(
            vehicles=vehicles,
            seabed=scn.seabed,
            transceiver_east_m=scn.transceiver_east_m,
            transceiver_north_m=scn.transceiver_north_m,
        )

    def build(self, scn: SwarmScenario, seed: int, run: int, physics) -> MissionParts:
        table = load_speed_table()
        tick = scn.timing.control_tick_s
        lead = standard_vehicle(scn.leader, seed, run, physics, LEADER, LEADER, speed_table=table)
        modem = scn.followers.sensors.modem
        arm_l = (
            np.asarray(modem.transducer_body_m, dtype=float)
            if any(modem.transducer_body_m)
            else np.asarray(lever_arm_from_site(physics, "modem", LEADER), dtype=float)
        )
        lead.navigation = LeaderNavigation(
            lead.navigation, arm_l, max(1, round(scn.leader.velocity_window_s / tick))
        )
        leader_guidance = lead.guidance
        st = scn.leader.start
        h = math.radians(st.heading_deg)
        v_plan = scn.leader.guidance.speed_m_s * np.array(unit_vector_scalar(h))
        p_plan = np.array([st.east_m, st.north_m, -st.depth_m])
        plan = Broadcast(f"{LEADER} (plan)", 0.0, p_plan, p_plan, v_plan, None)
        vehicles: list[VehicleParts] = [lead]
        fc = scn.followers
        names = self.vehicle_names(scn)[1:]
        for i, (name, (_, e, n)) in enumerate(zip(names, self._nominal(scn)[1:], strict=True)):
            start = StartConfig(
                east_m=e,
                north_m=n,
                depth_m=scn.station.depth_m,
                heading_deg=st.heading_deg,
                speed_m_s=st.speed_m_s,
                position_sigma_m=fc.position_sigma_m,
                heading_sigma_deg=fc.heading_sigma_deg,
            )
            pos = place_vehicle(physics, start, seed, run, name, name)
            s = fc.sensors
            rig = SensorRig(
                {
                    "compass": s.compass,
                    "ins": s.ins,
                    "log": s.log,
                    "pressure": s.pressure,
                    "modem": s.modem,
                },
                physics,
                name,
                seed,
                run,
                name,
                extra={"modem": {"sender": LEADER, "slot": i, "slots": len(names)}},
            )
            g = rng_mod.generator(seed, run, *streams(name, "initial"))
            x0 = pos.copy()
            x0[:2] += scn.navigation.initial_sigma_m * g.standard_normal(2)
            nav = FollowerNavigation(
                scn.navigation,
                self.method,
                x0,
                np.asarray(rig.lever_arms_body_m["modem"], dtype=float),
                plan,
                s.modem.period_s,
                tick,
            )
            guidance = StationGuidance(
                scn.station, fc.stations[i], tick, lambda g=leader_guidance: g.done
            )
            vehicles.append(
                VehicleParts(name, rig, nav, guidance, fc.autopilot, table, FOLLOWER_COLUMNS)
            )
        return MissionParts(vehicles, scenario_sea(scn, seed, run))
