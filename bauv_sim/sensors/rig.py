"""A vehicle's sensor rig: its devices, their lever arms, rates and latency, in the loop.

The rig turns the true state of one vehicle at each control tick (:class:`~bauv_sim.physics.
VehicleTruth`) into time-stamped measurement records (:class:`Measurement`: time of validity and
time of arrival), the way the vehicle's computer would receive them:

* **held** devices (compass, INS attitude, log, odometry, pressure) are sampled every
  ``period_s`` (a whole number of ticks) and their latest value is held in between; a device that
  produces nothing at a sampling tick (the log below its minimum speed) holds nothing until its
  next good sample;
* **event** devices (USBL, GPS, the acoustic modem, DOA bearings, the multibeam, the DVL) deliver
  measurements that are valid at one instant and reach the vehicle later (acoustic travel time
  and modem delay): the
  rig queues them and hands each one over at the first tick at or after its arrival, with its
  time of validity and the vehicle's own measured attitude at that time (for the lever arm of the
  transponder or antenna). Event devices are silent on the initial tick. Devices that measure
  between vehicles (the modem) read the other vehicles from the ``peers`` the world passes to
  :meth:`SensorRig.sense`.

Devices are built from their configurations through the registry
:data:`~bauv_sim.sensors.online.DEVICE_TYPES` (configuration type -> online device class, each
class in its device's module, added by :func:`~bauv_sim.sensors.online.register_device`; this
module imports the device modules). Adding a device type touches the device's module and the
import line of this registry, nothing else. Lever arms that a configuration leaves at zero
are read from the vehicle model's sites through the physics facade (:data:`LEVER_ARM_SITES`).

Every device draws from its own streams, addressed by ``(seed, run, "sensor", <stream name>,
...)``; a rig built with a ``stream_prefix`` (for a second vehicle in the same scene) names its
streams ``"<prefix>/<device>"``, so that vehicles draw independent errors and a vehicle draws the
same errors whatever other vehicles share its sea.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError

# the rig's registry of device types: each device module adds its online class to DEVICE_TYPES
from bauv_sim.sensors import (  # noqa: F401
    compass,
    doa,
    dvl,
    gps,
    ins,
    log,
    modem,
    multibeam,
    odometry,
    pressure,
    usbl,
)
from bauv_sim.sensors.online import (
    DEVICE_TYPES,
    Device,
    DeviceBuild,
    Measurement,
    Peer,
    TickContext,
    lever_arm_from_site,
)
from nav.acoustics import Propagation

if TYPE_CHECKING:
    from bauv_sim.physics import BauvPhysics, VehicleTruth

Array = NDArray[np.float64]

LEVER_ARM_SITES: Mapping[str, str] = {
    "usbl": "usbl_transponder",
    "gps": "gps_antenna",
    "modem": "modem",
}
"""Device name -> the vehicle model's site of its transponder or antenna."""


@dataclass(frozen=True)
class RigTick:
    """What the rig gives the vehicle at one control tick.

    Attributes:
        t_s: the tick's time, s.
        held: latest value of each held device (``None`` where it has none), by device name.
        sampled: held devices sampled at this tick.
        arrived: event measurements reaching the vehicle at this tick, in arrival-queue order.
    """

    t_s: float
    held: Mapping[str, Array | None]
    sampled: frozenset[str]
    arrived: tuple[Measurement, ...]

    def value(self, device: str) -> float | None:
        """The held scalar of a device, or ``None``."""
        v = self.held.get(device)
        return None if v is None else float(v[0])


class SensorRig:
    """The devices of one vehicle, sampled in the loop (see the module docstring).

    Args:
        devices: device name -> configuration (held devices are sampled before event
            devices at each tick, each group in this order).
        physics: the physics facade, with the vehicle placed at its start pose.
        vehicle: the vehicle's name in the scene.
        seed: batch seed.
        run: run index.
        stream_prefix: prefix of the device streams ("" for the scene's only or first vehicle).
        extra: per-device settings, by device name (see :class:`DeviceBuild`).
        propagation: the sea's true acoustic medium for the acoustic devices (see
            :class:`DeviceBuild`), or ``None``.

    Raises:
        ConfigError: for a configuration type without a device class, or a period that is not
            a whole number of ticks.
    """

    def __init__(
        self,
        devices: Mapping[str, Config],
        physics: BauvPhysics,
        vehicle: str,
        seed: int,
        run: int,
        stream_prefix: str = "",
        extra: Mapping[str, Mapping[str, Any]] | None = None,
        propagation: Propagation | None = None,
    ):
        tick = physics.control_tick_s
        self.devices: list[Device] = []
        self.lever_arms_body_m: dict[str, tuple[float, float, float]] = {}
        for name, cfg in devices.items():
            factory = DEVICE_TYPES.get(type(cfg))
            if factory is None:
                known = ", ".join(sorted(t.__name__ for t in DEVICE_TYPES))
                raise ConfigError(
                    f"sensors.{name}: {type(cfg).__name__} has no online device (known: {known})"
                )
            site = LEVER_ARM_SITES.get(name)
            arm = lever_arm_from_site(physics, site, vehicle) if site else None
            build = DeviceBuild(
                name=name,
                stream=f"{stream_prefix}/{name}" if stream_prefix else name,
                seed=seed,
                run=run,
                tick_s=tick,
                lever_arm_body_m=arm,
                physics=physics,
                vehicle=vehicle,
                extra=(extra or {}).get(name, {}),
                propagation=propagation,
            )
            dev = factory(cfg, build)
            self.devices.append(dev)
            arm_used = getattr(dev, "lever_arm_body_m", None)
            if arm_used is not None:
                self.lever_arms_body_m[name] = tuple(float(c) for c in arm_used)
        self._held_devices = [d for d in self.devices if d.kind == "held"]
        self._event_devices = [d for d in self.devices if d.kind == "event"]
        self._held: dict[str, Array | None] = {d.name: None for d in self._held_devices}
        self._pending: list[Measurement] = []

    def sense(
        self,
        k: int,
        truth: VehicleTruth,
        commands: Mapping[str, float],
        initial: bool = False,
        peers: Mapping[str, Peer] | None = None,
    ) -> RigTick:
        """Sample the devices due at tick ``k`` and hand over what arrives now.

        Args:
            k: tick index (0 on the initial tick).
            truth: the vehicle's true state at the tick.
            commands: actuator settings in force, by name.
            initial: the initial tick (event devices stay silent).
            peers: the other vehicles of the scene (their truth and broadcasts), for devices
                that measure between vehicles (:attr:`TickContext.peers`).

        Returns:
            The tick's records.
        """
        t = truth.t_s
        held = self._held
        ctx = TickContext(k, t, truth, commands, held, peers)
        sampled = []
        for dev in self._held_devices:
            if k % dev.every == 0:
                m = dev.step(ctx)
                held[dev.name] = None if m is None else m.value
                sampled.append(dev.name)
        if not initial:
            for dev in self._event_devices:
                m = dev.step(ctx)
                if m is not None:
                    self._pending.append(m)
        arrived = ()
        if self._pending:
            due = [m for m in self._pending if m.t_arrival_s <= t + 1e-9]
            if due:
                arrived = tuple(due)
                self._pending = [m for m in self._pending if m.t_arrival_s > t + 1e-9]
        return RigTick(t, dict(held), frozenset(sampled), arrived)
