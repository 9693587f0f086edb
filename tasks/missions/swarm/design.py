"""The design of a ``mission/swarm`` flight: the scene, and per run the leader's and the followers'
parts (rigs, navigation, station keeping) and the sea (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.build import SceneConfig, VehicleSpec
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.frames import unit_vector_scalar
from bauv_sim.sensors.online import Broadcast, lever_arm_from_site
from bauv_sim.sensors.rig import SensorRig
from tasks.closed_loop.parts import MissionParts, VehicleParts
from tasks.closed_loop.result import EstimateTrack
from tasks.closed_loop.scenario import StartConfig
from tasks.closed_loop.world import place_vehicle, scenario_sea, standard_vehicle, streams
from tasks.missions.swarm.coop import CoopFollowerNavigation
from tasks.missions.swarm.follower import FOLLOWER_COLUMNS, FollowerNavigation
from tasks.missions.swarm.leader import LeaderNavigation
from tasks.missions.swarm.network import NETWORK, NetworkedRig, NetworkLog, network_extra
from tasks.missions.swarm.options import coop_options, leader_clock_statement
from tasks.missions.swarm.relay import RelayBook
from tasks.missions.swarm.scenario import (
    DEPTH_SIGMA_M,
    FOLLOWERS,
    LEADER,
    REFUSAL_CODES,
    SwarmScenario,
    station_offsets,
)
from tasks.missions.swarm.station import StationGuidance

Array = NDArray[np.float64]


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
            geo=scn.geo,
            transceiver_east_m=scn.transceiver_east_m,
            transceiver_north_m=scn.transceiver_north_m,
        )

    def build(self, scn: SwarmScenario, seed: int, run: int, physics) -> MissionParts:
        table = load_speed_table()
        tick = scn.timing.control_tick_s
        net = scn.followers.network
        team = self.vehicle_names(scn)
        sea = scn.sound.propagation()
        lead = standard_vehicle(
            scn.leader, seed, run, physics, LEADER, LEADER, speed_table=table, propagation=sea
        )
        acoustic = net if net.enabled else scn.followers.sensors.modem
        arm_l = (
            np.asarray(acoustic.transducer_body_m, dtype=float)
            if any(acoustic.transducer_body_m)
            else np.asarray(lever_arm_from_site(physics, "modem", LEADER), dtype=float)
        )
        window = max(1, round(scn.leader.velocity_window_s / tick))
        if net.enabled:
            lead.rig = NetworkedRig(lead.rig, self._network_rig(scn, seed, run, physics, LEADER))
            relays = RelayBook(LEADER, 2 * net.period_s) if scn.navigation.coop.relay else None
            lead.navigation = LeaderNavigation(
                lead.navigation, arm_l, window, NetworkLog(team), leader_clock_statement(), relays
            )
        else:
            lead.navigation = LeaderNavigation(lead.navigation, arm_l, window)
        leader_guidance = lead.guidance
        st = scn.leader.start
        h = math.radians(st.heading_deg)
        v_plan = scn.leader.guidance.speed_m_s * np.array(unit_vector_scalar(h))
        p_plan = np.array([st.east_m, st.north_m, -st.depth_m])
        plan = Broadcast(f"{LEADER} (plan)", 0.0, p_plan, p_plan, v_plan, None)
        vehicles: list[VehicleParts] = [lead]
        fc = scn.followers
        stations = station_offsets(scn)
        names = team[1:]
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
            devices = {"compass": s.compass, "ins": s.ins, "log": s.log, "pressure": s.pressure}
            if net.enabled:
                devices[NETWORK] = net.device_config()
                extra = {NETWORK: network_extra(team, name)}
            else:
                devices["modem"] = s.modem
                extra = {"modem": {"sender": LEADER, "slot": i, "slots": len(names)}}
            rig = SensorRig(devices, physics, name, seed, run, name, extra, sea)
            g = rng_mod.generator(seed, run, *streams(name, "initial"))
            x0 = pos.copy()
            x0[:2] += scn.navigation.initial_sigma_m * g.standard_normal(2)
            arm = np.asarray(rig.lever_arms_body_m[NETWORK if net.enabled else "modem"])
            period_s = net.period_s if net.enabled else s.modem.period_s
            log = NetworkLog(team) if net.enabled else None
            if self.method == "decentralised":
                nav = decentralised_navigation(scn, name, x0, arm, plan, log, period_s, tick)
            else:
                nav = FollowerNavigation(
                    scn.navigation, self.method, x0, arm, plan, period_s, tick, log
                )
            guidance = StationGuidance(
                scn.station, stations[i], tick, lambda g=leader_guidance: g.done
            )
            vehicles.append(
                VehicleParts(
                    name,
                    rig,
                    nav,
                    guidance,
                    fc.autopilot,
                    table,
                    FOLLOWER_COLUMNS,
                    follower_estimates(self.method),
                )
            )
        return MissionParts(vehicles, scenario_sea(scn, seed, run))

    def _network_rig(self, scn: SwarmScenario, seed: int, run: int, physics, name: str):
        """A rig of the network's device alone, for a vehicle built by the standard sections."""
        net = scn.followers.network
        extra = {NETWORK: network_extra(self.vehicle_names(scn), name)}
        devices = {NETWORK: net.device_config()}
        return SensorRig(devices, physics, name, seed, run, name, extra, scn.sound.propagation())


def decentralised_navigation(
    scn: SwarmScenario,
    name: str,
    x0: Array,
    transducer_body_m: Array,
    plan: Broadcast,
    log: NetworkLog,
    period_s: float,
    tick_s: float,
) -> CoopFollowerNavigation:
    """A follower's decentralised navigation part from the scenario
    (:class:`~tasks.missions.swarm.coop.CoopFollowerNavigation`)."""
    c = scn.navigation
    net = scn.followers.network
    return CoopFollowerNavigation(
        name,
        FOLLOWERS.index(name) + 1,
        LEADER,
        coop_options(scn),
        math.radians(c.sigma_course_deg),
        c.sigma_speed_m_s,
        c.coop.current_sigma_m_s,
        c.sigma_range_m,
        net.nominal_sound_speed_m_s,
        x0,
        c.initial_sigma_m,
        transducer_body_m,
        plan,
        log,
        max(1, round(period_s / tick_s)),
        DEPTH_SIGMA_M,
        c.current == "leader",
        c.dr_warning_s,
        REFUSAL_CODES,
        2 * net.period_s,
    )


METHOD_LABELS = {"ga1": "GA1", "ga2": "GA2", "ekf": "EKF", "dr": "DR", "decentralised": "CI"}
"""The followers' methods as the figures and recordings name them."""


def follower_estimates(method: str) -> tuple[EstimateTrack, ...]:
    """A follower's estimates: its method's position with its covariance (``ekf_pos``,
    ``ekf_P``: the navigator's estimate, whatever the method) and, for a method that uses the
    ranges, its own dead reckoning beside it."""
    label = METHOD_LABELS.get(method, method)
    own = EstimateTrack("ekf_pos", label, "ekf_P")
    return (own,) if method == "dr" else (own, EstimateTrack("dr_pos", "DR"))
