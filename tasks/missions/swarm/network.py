"""The team's acoustic network in ``mission/swarm`` (issue 24): its scenario section, the device
on every vehicle's rig, and what each vehicle heard (:mod:`tasks.missions.swarm`).

With ``followers.network.enabled`` every vehicle, the leader too, carries the network's device
(:class:`bauv_sim.acoustics.network.AcousticNetworkDevice`, named :data:`NETWORK` in its rig) in
place of the followers' modem: in its TDMA slot each vehicle transmits, by its own clock, a
packet that carries its broadcast (its navigator's estimate, covariance and clock estimate), and
every other vehicle in reach measures the one-way travel time (OWTT). The leader's rig is the
standard vehicle's (:func:`tasks.closed_loop.world.standard_vehicle`) with a second rig of the
network's device beside it (:class:`NetworkedRig`). Every range a vehicle receives is kept
(:class:`NetworkLog`) whatever its navigation makes of it, and after the flight becomes the
vehicle's ``network`` table (:data:`NETWORK_COLUMNS`): the data the team methods are compared
on (:mod:`tasks.missions.swarm.team`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.acoustics.network import AcousticNetworkConfig
from bauv_sim.sensors.online import Measurement, Peer
from bauv_sim.sensors.rig import RigTick, SensorRig
from tasks.core.export import Column

Array = NDArray[np.float64]

NETWORK = "network"
"""The network device's name in a vehicle's rig."""


class SwarmNetworkConfig(AcousticNetworkConfig):
    """The team's acoustic network (:mod:`bauv_sim.acoustics.network`) in ``mission/swarm``:
    with ``enabled``, every vehicle (the leader too) carries the network's device in place of
    the followers' modem and ranges to every other vehicle by one-way travel time in its TDMA
    slot, each transmission carrying the sender's broadcast (estimate, covariance, clock
    estimate). Defaults for the swarm: a 5 s cycle of 0.5 s slots (ten vehicles), the first at
    5 s, the HS modem's 300 m reach."""

    enabled: bool = Field(
        False,
        description="every vehicle on the acoustic network (OWTT to every other vehicle); off: "
        "the followers' modem ranges from the leader (seed 003)",
    )
    period_s: float = Field(5.0, gt=0, description="TDMA cycle, s")
    slot_s: float = Field(0.5, gt=0, description="length of one sender's slot, s")
    start_s: float = Field(5.0, ge=0, description="local time the first cycle starts, s")
    max_range_m: float = Field(300.0, gt=0, description="no packet beyond this range, m")

    def device_config(self) -> AcousticNetworkConfig:
        """The network's own configuration (without ``enabled``), for the vehicles' rigs."""
        return AcousticNetworkConfig.model_validate(self.model_dump(exclude={"enabled"}))


def network_extra(vehicles: tuple[str, ...], me: str) -> dict[str, Any]:
    """The device's per-vehicle settings (``DeviceBuild.extra``): the team in the scene's order
    (the schedule's) and this vehicle."""
    return {"vehicles": vehicles, "me": me}


class NetworkedRig:
    """A rig and a second rig holding only the network's device, sensed together as one (the
    leader's standard rig stays as :func:`~tasks.closed_loop.world.standard_vehicle` built it).

    Args:
        main: the vehicle's rig.
        network: the rig of its network device (the same vehicle, seed and run).

    Attributes:
        lever_arms_body_m: both rigs' lever arms by device, body FLU, m.
    """

    def __init__(self, main: SensorRig, network: SensorRig):
        self.main, self.network = main, network
        self.lever_arms_body_m = {**main.lever_arms_body_m, **network.lever_arms_body_m}

    def sense(
        self,
        k: int,
        truth,
        commands: Mapping[str, float],
        initial: bool = False,
        peers: Mapping[str, Peer] | None = None,
    ) -> RigTick:
        """Both rigs' records of tick ``k`` (:meth:`bauv_sim.sensors.rig.SensorRig.sense`): the
        main rig's, with the network's measurements arriving after its own."""
        a = self.main.sense(k, truth, commands, initial, peers)
        b = self.network.sense(k, truth, commands, initial, peers)
        if not b.arrived:
            return a
        return RigTick(a.t_s, a.held, a.sampled, a.arrived + b.arrived)


NETWORK_COLUMNS: Mapping[str, tuple] = {
    "t_valid": ("s", "time of validity: the reception (true time)", ()),
    "t_arrival": ("s", "time the range reached the navigator", ()),
    "sender": ("index", "the transmitting vehicle (0 the leader, i the follower f<i>)", ()),
    "tx_local": ("s", "scheduled transmission by the sender's clock", ()),
    "rx_local": ("s", "the reception's timestamp by the receiver's clock", ()),
    "range": ("m", "nominal sound speed x (rx_local - tx_local): the OWTT range", ()),
    "snr": ("dB", "the sonar equation's SNR at the true range", ()),
}
"""Columns of a vehicle's ``network`` table: every range it received, in arrival order."""


class NetworkLog:
    """What one vehicle received from the network (see the module docstring).

    Args:
        vehicles: the team in the scene's order (a sender's index in it is the ``sender``).
    """

    def __init__(self, vehicles: tuple[str, ...]):
        self.vehicles = vehicles
        self.rows: list[list[float]] = []

    def add(self, m: Measurement) -> None:
        """Keep a network measurement (its payload an
        :class:`~bauv_sim.acoustics.network.AcousticRange`)."""
        a = m.payload
        self.rows.append(
            [
                m.t_valid_s,
                m.t_arrival_s,
                float(self.vehicles.index(a.sender)),
                a.tx_local_s,
                a.rx_local_s,
                a.range_m,
                a.snr_db,
            ]
        )

    def outcome(self) -> dict[str, list[list[float]]]:
        """The rows as plain data (columns in :data:`NETWORK_COLUMNS`' order)."""
        return {NETWORK: [list(r) for r in self.rows]}


def network_table(rows: list[list[float]]) -> dict[str, Column]:
    """A vehicle's ``network`` table from its log's rows (:meth:`NetworkLog.outcome`)."""
    a = np.asarray(rows, dtype=float).reshape(len(rows), len(NETWORK_COLUMNS))
    out = {}
    for j, (name, spec) in enumerate(NETWORK_COLUMNS.items()):
        values = a[:, j].astype(np.int64) if name == "sender" else a[:, j]
        out[name] = Column(values, *spec)
    return out
