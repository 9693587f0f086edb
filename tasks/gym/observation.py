"""What a mission's Gymnasium environment observes: a flat vector of named elements.

Three layouts (:data:`LAYOUTS`), each a sequence of elements per vehicle, the vehicles in the
scene's order (:meth:`tasks.closed_loop.parts.MissionDesign.vehicle_names`):

* ``"navigation"`` (the default): what the vehicle's navigation knows, exactly the elements the
  mission's own autopilot reads (:data:`tasks.closed_loop.parts.OBSERVATIONS`): measured heading,
  depth, attitude and rates, the speed through water navigation uses, the EKF estimate and its
  standard deviations, the dead-reckoned position, and the guidance command (course, depth,
  speed) with the guidance mode (index into :data:`tasks.closed_loop.scenario.MODES`);
* ``"truth"``: the vehicle's true state (:class:`bauv_sim.physics_state.VehicleTruth`) and the
  same guidance command and mode (guidance still steers on the vehicle's estimate);
* ``"both"``: the navigation elements followed by the true state.

Every element is float64 (the mode's index too); the vector is unbounded
(``Box(-inf, inf)``): positions are metres in the world frame (east, north, up), angles radians,
headings and courses clockwise from north.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from tasks.closed_loop.parts import OBSERVATIONS

Array = NDArray[np.float64]

TRUTH: Mapping[str, tuple[int, str, str]] = {
    "true_position": (3, "position_world_m", "true position (east, north, up), m, world"),
    "true_velocity": (3, "velocity_world_m_s", "true velocity over ground, m/s, world"),
    "true_velocity_water": (
        3,
        "velocity_through_water_world_m_s",
        "true velocity through the water, m/s, world",
    ),
    "true_attitude": (
        3,
        "roll_pitch_heading_rad",
        "true roll (starboard-down), pitch (nose-up), heading (clockwise from north), rad",
    ),
    "true_angular_velocity": (
        3,
        "angular_velocity_body_rad_s",
        "true angular velocity, rad/s, body (forward, left, up)",
    ),
}
"""The true-state elements: name -> (size, field of the truth record, description)."""

GUIDANCE = ("command", "mode")
"""The navigation elements that are guidance's output (in every layout)."""

LAYOUTS = ("navigation", "truth", "both")
"""The observation layouts (module docstring)."""


def _navigation_elements() -> list[tuple[str, int, str]]:
    return [(k, shape[0], doc) for k, (shape, _, doc) in OBSERVATIONS.items()]


def _truth_elements() -> list[tuple[str, int, str]]:
    return [(k, size, doc) for k, (size, _, doc) in TRUTH.items()]


def elements(layout: str) -> list[tuple[str, int, str]]:
    """One vehicle's elements of a layout, in order: (name, size, description).

    Raises:
        ValueError: for a layout not in :data:`LAYOUTS` (the environment checks it first).
    """
    nav = _navigation_elements()
    if layout == "navigation":
        return nav
    if layout == "truth":
        return _truth_elements() + [e for e in nav if e[0] in GUIDANCE]
    if layout == "both":
        return nav + _truth_elements()
    raise ValueError(f"layout {layout!r} is not one of {LAYOUTS}")


class ObservationLayout:
    """The flat observation of a scene in one layout.

    Args:
        layout: one of :data:`LAYOUTS`.
        vehicles: the scene's vehicle names, in order.

    Attributes:
        names: every element's name, ``"<vehicle>/<element>"``, in the vector's order.
        slices: element name -> its slice of the vector.
        descriptions: element name -> what it is, with units and frame.
        size: the vector's length.
    """

    def __init__(self, layout: str, vehicles: Sequence[str]):
        self.layout = layout
        self.vehicles = tuple(vehicles)
        self._elements = elements(layout)
        self.names: tuple[str, ...] = ()
        self.slices: dict[str, slice] = {}
        self.descriptions: dict[str, str] = {}
        i = 0
        for v in self.vehicles:
            for k, size, doc in self._elements:
                name = f"{v}/{k}"
                self.names += (name,)
                self.slices[name] = slice(i, i + size)
                self.descriptions[name] = doc
                i += size
        self.size = i

    def vector(self, dm_observation: Mapping[str, NDArray], truths: Mapping[str, object]) -> Array:
        """The flat observation.

        Args:
            dm_observation: the mission world's observation (``"<vehicle>/<element>"`` ->
                array, :meth:`tasks.closed_loop.world.MissionWorld.get_observation`).
            truths: vehicle name -> its :class:`~bauv_sim.physics_state.VehicleTruth` now
                (read only by the truth elements).

        Returns:
            A new array of shape (:attr:`size`,), float64.
        """
        out = np.empty(self.size)
        for v in self.vehicles:
            for k, _, _ in self._elements:
                name = f"{v}/{k}"
                if k in TRUTH:
                    value = getattr(truths[v], TRUTH[k][1])
                else:
                    value = dm_observation[name]
                out[self.slices[name]] = value
        return out

    @property
    def needs_truth(self) -> bool:
        """Whether the layout reads the true state."""
        return any(k in TRUTH for k, _, _ in self._elements)
