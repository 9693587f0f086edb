"""The parts a mission is composed of, and the protocols they meet.

A mission is a sea and, per vehicle, a sensor rig, a navigation part, a guidance part and a pilot
(the autopilot as a policy). The mission module declares them (:class:`MissionDesign`); the world
(:mod:`tasks.closed_loop.world`) wires them together at every control tick:

    truth --rig--> RigTick --navigation--> NavOutput --guidance--> GuidanceCommand --pilot--> action

Any object with the methods of :class:`Navigation` or :class:`Guidance` can stand in for the
standard parts (:class:`~tasks.closed_loop.navigation.EkfNavigation`, :class:`WaypointSteering`);
nothing is reached through private hooks.
"""

from __future__ import annotations

import collections
import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from dm_env import specs
from numpy.typing import NDArray

from bauv_sim.autopilot import Autopilot, AutopilotConfig, Measured
from bauv_sim.build import SceneConfig
from bauv_sim.sea import Sea
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.guidance import GuidanceCommand, WaypointGuidance, horizontal_sigma_m
from tasks.closed_loop.navigation import NavOutput
from tasks.closed_loop.result import STANDARD_ESTIMATES, EstimateTrack

ACTIONS = (
    ("tail_beat_frequency_hz", "Hz"),
    ("tail_bias_rad", "rad"),
    ("fin_port_rad", "rad"),
    ("fin_starboard_rad", "rad"),
    ("battery_position_m", "m"),
)
"""A vehicle's action elements, in order, with their units (the physics setters' units)."""


class Navigation(Protocol):
    """A vehicle's navigation part."""

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        """Rig records of one tick in, estimate out."""
        ...

    def outcome(self) -> dict[str, Any]:
        """Plain data about the whole run (for the run result), read once at the end."""
        ...


class Guidance(Protocol):
    """A vehicle's guidance part."""

    @property
    def done(self) -> bool:
        """Whether the vehicle's mission is over."""
        ...

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        """The command for now from the navigation output."""
        ...

    def waypoints(self) -> list[tuple[float, float, float]]:
        """The way-points as flown: (east m, north m, acceptance radius m) (empty if none)."""
        ...

    def legs(self) -> list[dict[str, Any]]:
        """How each leg ended: ``{"waypoint", "reached", "t_s"}`` (empty if none)."""
        ...

    def outcome(self) -> dict[str, Any]:
        """Plain data about the whole run (for the run result), read once at the end."""
        ...


@dataclass
class WaypointSteering:
    """The standard guidance part: way-point guidance on the EKF estimate with its uncertainty
    (the reach test uses the worst horizontal sigma) or on dead reckoning (no covariance: the bare
    acceptance circle). A GPS fix is reported to guidance before it steers (surfacing counts
    fixes).

    Args:
        guidance: the way-point state machine.
        steer_on: ``"ekf"`` or ``"dr"`` (a subclass that overrides :meth:`step` names its own).
    """

    guidance: WaypointGuidance
    steer_on: str = "ekf"

    @property
    def done(self) -> bool:
        return self.guidance.done

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        if nav.gps_fix:
            self.guidance.gps_fix()
        if self.steer_on == "ekf":
            est = nav.estimate
            return self.guidance.step(t_s, est.x, horizontal_sigma_m(est.P))
        return self.guidance.step(t_s, nav.dr_position_m)

    def waypoints(self) -> list[tuple[float, float, float]]:
        return [(w.east_m, w.north_m, w.acceptance_radius_m) for w in self.guidance.waypoints]

    def legs(self) -> list[dict[str, Any]]:
        return [
            {"waypoint": leg.waypoint, "reached": leg.reached, "t_s": leg.t_s}
            for leg in self.guidance.legs
        ]

    def outcome(self) -> dict[str, Any]:
        return {}


OBSERVATIONS: Mapping[str, tuple[tuple[int, ...], type, str]] = {
    "heading": ((1,), np.float64, "measured heading, rad clockwise from north"),
    "yaw_rate": ((1,), np.float64, "heading rate (INS), rad/s clockwise"),
    "depth": ((1,), np.float64, "measured depth, m"),
    "pitch": ((1,), np.float64, "pitch (INS), rad nose-up"),
    "pitch_rate": ((1,), np.float64, "pitch rate (INS), rad/s"),
    "roll": ((1,), np.float64, "roll (INS), rad starboard-down"),
    "roll_rate": ((1,), np.float64, "roll rate (INS), rad/s"),
    "speed": ((1,), np.float64, "speed through water used by navigation, m/s"),
    "estimate": ((3,), np.float64, "EKF position (east, north, up), m, world"),
    "estimate_std": ((3,), np.float64, "EKF standard deviations, m"),
    "dr": ((3,), np.float64, "dead-reckoned position, m, world"),
    "command": ((3,), np.float64, "guidance: course rad, depth m, speed m/s"),
    "mode": ((1,), np.int64, "guidance mode (index into MODES)"),
}
"""A vehicle's observation elements (the world prefixes them with ``"<vehicle>/"``)."""


class Pilot:
    """A vehicle's autopilot as a policy: its observation elements -> its five actuator settings.

    Args:
        cfg: autopilot gains.
        speed_table: speed calibration for the speed feed-forward.
        tick_s: control tick, s.
        lower, upper: the action bounds of the vehicle, shape (5,).
        prefix: the vehicle's observation prefix (``"<vehicle>/"``).
    """

    def __init__(
        self,
        cfg: AutopilotConfig,
        speed_table,
        tick_s: float,
        lower: NDArray[np.float64],
        upper: NDArray[np.float64],
        prefix: str,
    ):
        self.ap = Autopilot(
            cfg, functools.lru_cache(maxsize=128)(lambda v: float(speed_table.frequency_for(v)))
        )
        self.tick_s = tick_s
        self.lo, self.hi = lower, upper
        self.keys = [prefix + k for k in OBSERVATIONS]

    def __call__(self, obs: Mapping[str, NDArray]) -> NDArray[np.float64]:
        heading, yaw_rate, depth, pitch, pitch_rate, roll, roll_rate, speed = (
            float(obs[k][0]) for k in self.keys[:8]
        )
        m = Measured(heading, yaw_rate, depth, pitch, pitch_rate, roll, roll_rate, speed)
        course, depth_cmd, speed_cmd = (float(v) for v in obs[self.keys[11]])
        c = self.ap.step(self.tick_s, course, depth_cmd, speed_cmd, m)
        a = np.array(
            [c.tail_beat_hz, c.tail_bias_rad, c.fin_port_rad, c.fin_starboard_rad, c.battery_m]
        )
        return np.clip(a, self.lo, self.hi)


@dataclass
class VehicleParts:
    """One vehicle of a mission, assembled.

    Attributes:
        name: the vehicle's name in the scene (its MJCF namespace).
        rig: its sensor rig.
        navigation: its navigation part.
        guidance: its guidance part.
        autopilot: its autopilot gains.
        speed_table: its speed calibration (pilot feed-forward).
        extra_columns: per-tick columns a mission adds from the navigation output's typed
            report (:attr:`~tasks.closed_loop.navigation.NavOutput.report`): column name ->
            (field of the report, unit, description, components, nullable).
        estimates: the position estimates its navigation part yields, by their per-tick
            columns (the standard part's: the EKF with its covariance, and DR); the recording
            draws each as this vehicle's track of that method
            (:mod:`tasks.closed_loop.recording`).
    """

    name: str
    rig: SensorRig
    navigation: Navigation
    guidance: Guidance
    autopilot: AutopilotConfig
    speed_table: Any
    extra_columns: Mapping[str, tuple[str, str, str, tuple[str, ...], bool]] = field(
        default_factory=dict
    )
    estimates: Sequence[EstimateTrack] = STANDARD_ESTIMATES


@dataclass
class MissionParts:
    """Everything a run of a mission flies with.

    Attributes:
        vehicles: the vehicles, in action order.
        sea: the water they swim in (current field, free surface).
    """

    vehicles: Sequence[VehicleParts]
    sea: Sea


class MissionDesign(Protocol):
    """What a mission module declares (see :class:`~tasks.closed_loop.world.WaypointMission`).

    The world calls :meth:`scene` to build the physics, then :meth:`build` at the start of every
    episode, with the physics reset: it places the vehicles and returns the parts and the sea.
    """

    def vehicle_names(self, scenario: Any) -> tuple[str, ...]:
        """The vehicles of the scene, in action order (known before any episode)."""
        ...

    def scene(self, scenario: Any) -> SceneConfig:
        """The scene: vehicles, seabed, transceiver, beacons."""
        ...

    def build(self, scenario: Any, seed: int, run: int, physics) -> MissionParts:
        """Place the vehicles and assemble the parts (and the sea) of one run."""
        ...


def action_spec(names: Sequence[str], limits: Sequence[Mapping[str, tuple[float, float]]]):
    """The action spec of a scene: each vehicle's five elements, in order, named with units.

    Args:
        names: vehicle names.
        limits: each vehicle's ``command_limits()``.

    Returns:
        A ``BoundedArray`` of shape (5 n,) whose name lists ``<vehicle>/<element> [unit]``.
    """
    lo = [lim[k][0] for lim in limits for k, _ in ACTIONS]
    hi = [lim[k][1] for lim in limits for k, _ in ACTIONS]
    label = ", ".join(f"{v}/{k} [{u}]" for v in names for k, u in ACTIONS)
    return specs.BoundedArray((len(lo),), np.float64, lo, hi, name=label)


def observation_spec(names: Sequence[str]) -> collections.OrderedDict:
    """The observation spec of a scene: :data:`OBSERVATIONS` of every vehicle, prefixed."""
    out = collections.OrderedDict()
    for v in names:
        for k, (shape, dtype, _) in OBSERVATIONS.items():
            out[f"{v}/{k}"] = specs.Array(shape, dtype, name=f"{v}/{k}")
    return out
