"""Online devices: what a device of a vehicle's sensor rig is (:class:`Device`), what it gets to
build itself (:class:`DeviceBuild`) and at each tick (:class:`TickContext`), what it hands over
(:class:`Measurement`), and the registry of device classes (:data:`DEVICE_TYPES`) that each device
module adds itself to with :func:`register_device` (see :mod:`bauv_sim.sensors.rig`).

Devices that measure between vehicles (the acoustic modem, :mod:`bauv_sim.sensors.modem`) read
the other vehicles of the scene from :attr:`TickContext.peers`: each peer's true state at this
tick and what it broadcasts (:class:`Broadcast`, its navigator's view of itself), which the world
hands to every rig (:class:`Peer`). A measurement may carry what its sender attached
(:attr:`Measurement.payload`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from bauv_sim.config import Config
from bauv_sim.sensors.base import check_multiple
from bauv_sim.truth import Truth
from nav.acoustics import Propagation

if TYPE_CHECKING:
    from bauv_sim.physics import BauvPhysics, VehicleTruth

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Measurement:
    """One measurement record as the vehicle receives it.

    Attributes:
        device: the device's name in the rig (``"usbl"``, ``"gps"``, ``"compass"``...).
        t_valid_s: time of validity (the instant the measurement refers to), s.
        t_arrival_s: time it reaches the vehicle (>= ``t_valid_s``), s.
        value: the measured values, shape (m,), SI units (see the device).
        attitude_rad: the vehicle's own measured (roll, pitch, heading) at ``t_valid_s``, shape
            (3,), rad (INS roll and pitch, compass heading), for lever-arm corrections; ``None``
            for held devices.
        payload: what the sender attached to an acoustic message (the modem's
            :class:`Broadcast`), else ``None``.
    """

    device: str
    t_valid_s: float
    t_arrival_s: float
    value: Array
    attitude_rad: Array | None = None
    payload: Any = None


@dataclass(frozen=True)
class Broadcast:
    """What a vehicle states about itself in an acoustic message (seed 003: the leader sends its
    position with each range).

    Attributes:
        sender: the sending vehicle's name in the scene.
        t_s: time the statement refers to, s.
        position_world_m: the sender's position of its reference point, shape (3,), m, world ENU
            (its navigator's estimate, or the truth when the modem is set to send it).
        transducer_world_m: the same for its modem transducer, shape (3,), m, world ENU.
        velocity_world_m_s: its velocity over ground (east, north), shape (2,), m/s.
        covariance_m2: the stated horizontal covariance of ``position_world_m``, shape (2, 2),
            m^2, or ``None`` when none is sent (a true position has none).
        current_world_m_s: the water current at the sender as it estimates it (east, north),
            shape (2,), m/s, or ``None``.
        clock_offset_s: the sender's estimate of its clock's offset (local minus true time) at
            ``t_s``, s, or ``None`` when it estimates none.
        clock_offset_var_s2: the variance of that estimate, s^2, or ``None``.
    """

    sender: str
    t_s: float
    position_world_m: Array
    transducer_world_m: Array
    velocity_world_m_s: Array
    covariance_m2: Array | None = None
    current_world_m_s: Array | None = None
    clock_offset_s: float | None = None
    clock_offset_var_s2: float | None = None


@dataclass(frozen=True)
class Peer:
    """Another vehicle of the scene as a device may see it at a tick.

    Attributes:
        truth: its true state at this tick.
        broadcast: its latest broadcast (``None`` if it sends none): of this tick for vehicles
            earlier in the scene's order, of the previous tick for later ones.
    """

    truth: VehicleTruth
    broadcast: Broadcast | None = None


class TickContext:
    """What a device may read at a tick besides the truth.

    Args:
        k: tick index (0 at the start).
        t_s: time, s.
        truth: the vehicle's true state.
        commands: the actuator settings in force (``tail_beat_frequency_hz`` ...), by name.
        held: the rig's held values (the held devices are sampled before the event devices).
        peers: the other vehicles of the scene, by name (empty for a vehicle alone).

    Attributes:
        tt: the time as a sample grid, shape (1,), s.
    """

    __slots__ = ("_held", "_record", "commands", "k", "peers", "t_s", "truth", "tt")

    def __init__(
        self,
        k: int,
        t_s: float,
        truth: VehicleTruth,
        commands: Mapping[str, float],
        held: Mapping[str, Array | None],
        peers: Mapping[str, Peer] | None = None,
    ):
        self.k, self.t_s, self.truth, self.commands = k, t_s, truth, commands
        self.peers: Mapping[str, Peer] = peers if peers is not None else {}
        self.tt = np.array([t_s])
        self._held = held
        self._record: Truth | None = None

    @property
    def measured_attitude_rad(self) -> Array | None:
        """(roll, pitch, heading) as the vehicle measures them now (INS and compass), shape (3,),
        rad, or ``None`` without both devices."""
        att, heading = self._held.get("ins"), self._held.get("compass")
        if att is None or heading is None:
            return None
        return np.array([att[0], att[1], heading[0]])

    @property
    def record(self) -> Truth:
        """The truth as a one-run, one-sample record (built once per tick, on demand)."""
        if self._record is None:
            self._record = truth_record(self.truth)
        return self._record


class Device(Protocol):
    """An online device of a rig (see the module docstring).

    Attributes:
        name: device name in the rig.
        kind: ``"held"`` or ``"event"``.
        every: sampling period in control ticks.
    """

    name: str
    kind: Literal["held", "event"]
    every: int

    def step(self, ctx: TickContext) -> Measurement | None:
        """Sample at this tick if due (or always, for devices that watch the truth every tick).

        Returns:
            A held device: its new value at a sampling tick, ``None`` when it produced nothing
            (not called between its sampling ticks). An event device: a measurement to queue, or
            ``None``.
        """
        ...


C = TypeVar("C", bound=Config)
"""A configuration type: a device's, returned as given or updated."""


@dataclass(frozen=True)
class DeviceBuild:
    """What a device class receives to build itself.

    Attributes:
        name: device name in the rig.
        stream: stream name of the device (``name``, or ``"<prefix>/<name>"``).
        seed: batch seed.
        run: run index.
        tick_s: control tick, s.
        lever_arm_body_m: the device's lever arm from the model's site (body FLU, m), if it has
            a site in :data:`bauv_sim.sensors.rig.LEVER_ARM_SITES`.
        physics: the physics facade (scene geometry such as the USBL transceiver).
        vehicle: the vehicle's name in the scene.
        extra: per-device settings the mission supplies (e.g. the odometry's speed table).
        propagation: the true acoustic medium of the sea (:class:`nav.acoustics.Propagation`),
            or ``None``: an acoustic device then keeps its configured ``sound_speed_m_s`` as the
            true, isovelocity speed (the behaviour before sound-speed profiles).
    """

    name: str
    stream: str
    seed: int
    run: int
    tick_s: float
    lever_arm_body_m: tuple[float, float, float] | None
    physics: BauvPhysics
    vehicle: str
    extra: Mapping[str, Any] = field(default_factory=dict)
    propagation: Propagation | None = None

    def with_lever_arm(self, cfg: C, field_name: str) -> C:
        """The configuration with its lever-arm field (body FLU, m) set to the model's site
        when the configuration leaves it at zero."""
        if getattr(cfg, field_name) == (0.0, 0.0, 0.0) and self.lever_arm_body_m is not None:
            return cfg.model_copy(update={field_name: self.lever_arm_body_m})
        return cfg

    def with_site(self, cfg: C, field_name: str, site: str) -> C:
        """The configuration with its lever-arm field (body FLU, m) set to the model's ``site``
        when the configuration leaves it at zero (a device whose site does not depend on its
        name in the rig: the multibeam's ``sonar``, the DVL's ``dvl``)."""
        if getattr(cfg, field_name) == (0.0, 0.0, 0.0):
            arm = lever_arm_from_site(self.physics, site, self.vehicle)
            return cfg.model_copy(update={field_name: arm})
        return cfg

    def every(self, period_s: float) -> int:
        """The period in ticks (a whole multiple of the tick, else :class:`ConfigError`)."""
        return check_multiple(period_s, self.tick_s, f"sensors.{self.name}.period_s")


DEVICE_TYPES: dict[type[Config], Callable[[Config, DeviceBuild], Device]] = {}
"""The rig's registry: configuration type -> online device factory."""


def register_device(cfg_type: type[Config]) -> Callable[[type], type]:
    """Class decorator adding an online device class to :data:`DEVICE_TYPES`."""

    def add(cls: type) -> type:
        DEVICE_TYPES[cfg_type] = cls
        return cls

    return add


def lever_arm_from_site(
    physics: BauvPhysics, site: str, vehicle: str
) -> tuple[float, float, float]:
    """A site's position relative to the vehicle's reference point, body FLU, m."""
    R = physics.R_world_from_body(vehicle)
    rel = physics.site_position_world(site, vehicle) - physics.position_world(vehicle)
    x, y, z = (float(c) for c in R.T @ rel)
    return x, y, z


def truth_record(vt: VehicleTruth) -> Truth:
    """A one-run, one-sample truth record (run axis 1, time axis 1) of a vehicle's state."""
    return Truth(
        t_s=np.array([vt.t_s]),
        pos_world_m=vt.position_world_m[None, None],
        vel_ground_world_m_s=vt.velocity_world_m_s[None, None],
        vel_water_world_m_s=vt.velocity_through_water_world_m_s[None, None],
        heading_rad=np.array([[vt.roll_pitch_heading_rad[2]]]),
        roll_pitch_rad=vt.roll_pitch_heading_rad[None, None, :2],
        current_world_m_s=vt.current_world_m_s[None, None],
    )
