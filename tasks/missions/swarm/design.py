"""The design of a ``mission/swarm`` flight: the scene, and per run the leader's and the followers'
parts (rigs, navigation, station keeping) and the sea (:mod:`tasks.missions.swarm`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bauv_sim import rng as rng_mod
from bauv_sim.build import SceneConfig, VehicleSpec
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.frames import unit_vector_scalar
from bauv_sim.sensors.online import Broadcast, lever_arm_from_site
from bauv_sim.sensors.rig import SensorRig
from tasks.closed_loop.parts import MissionParts, VehicleParts
from tasks.closed_loop.scenario import StartConfig
from tasks.closed_loop.world import place_vehicle, scenario_sea, standard_vehicle, streams
from tasks.missions.swarm.follower import FOLLOWER_COLUMNS, FollowerNavigation
from tasks.missions.swarm.leader import LeaderNavigation
from tasks.missions.swarm.scenario import FOLLOWERS, LEADER, SwarmScenario, station_offsets
from tasks.missions.swarm.station import StationGuidance


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
        stations = station_offsets(scn)
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
                scn.station, stations[i], tick, lambda g=leader_guidance: g.done
            )
            vehicles.append(
                VehicleParts(name, rig, nav, guidance, fc.autopilot, table, FOLLOWER_COLUMNS)
            )
        return MissionParts(vehicles, scenario_sea(scn, seed, run))
