"""The sea around the vehicles at run time: the current and the free surface, applied to the physics
once per control tick.

MuJoCo has one water velocity for the whole scene (``option wind``) and no free surface: the
buoyancy of ``models/bauv`` (gravity compensation of its float bodies) would hold above z = 0 too.
A :class:`Sea` makes up for both at the start of every control tick, acting on the physics only
through the facade's primitives (it indexes no MuJoCo array):

* **current**: the current field (:mod:`bauv_sim.currents`) is evaluated at every vehicle's
  reference point now and, at the position the vehicle will reach, at the end of the tick; the
  water at the vehicle then changes linearly over the tick (a step of the field becomes a ramp
  over one tick), and the facade applies it at every physics step
  (:meth:`~bauv_sim.physics.BauvPhysics.set_water_world`): MuJoCo's water velocity for the first
  vehicle, the change of the fluid forces in their own water for the others, and the
  Froude-Krylov and added-mass reaction to the water's acceleration for all
  (:mod:`bauv_sim.hydro`).
* **free surface** at z = 0: each vehicle's buoyancy is scaled by the submerged fraction of its
  hull (:func:`submerged_fraction`), held for the tick.

A mission constructs its sea from its scenario and injects it into the physics
(:meth:`bauv_sim.physics.BauvPhysics.set_sea`, which carries every vehicle with the change of the
water at it: Galilean invariance, the motion of a neutrally buoyant body when the whole sea changes
its velocity; a vehicle placed with its speed through still water starts moving with the
water); the physics applies it at the start of every
control tick of :meth:`~bauv_sim.physics.BauvPhysics.advance`, and a ``dm_control`` task that steps
the physics itself calls :meth:`~bauv_sim.physics.BauvPhysics.apply_sea` in ``before_step``.
Frames: world ENU (x east, y north, z up), depth positive down from the surface z = 0.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from bauv_sim.currents import CurrentField

if TYPE_CHECKING:
    from bauv_sim.physics import BauvPhysics

HULL_HALF_HEIGHT_M = 0.17
"""Half-height of the hull's largest section, m (``bauv_sim.hull.HullProfile``: 0.34 m high),
used by the free-surface model."""


def submerged_fraction(depth_m: float) -> float:
    """Fraction of a vehicle's displacement under water at a depth of its reference point.

    The hull is taken as an elliptic section of half-height :data:`HULL_HALF_HEIGHT_M` h centred
    at the reference point's depth d: with u = clip(d / h, -1, 1) the submerged fraction is
    ``1/2 + (u sqrt(1 - u^2) + asin u) / pi`` (1 when the hull top is under water, 0 when its keel
    is out). Pitch, roll, waves and the shift of the centre of buoyancy are ignored.

    Args:
        depth_m: depth of the reference point below the surface z = 0, m (positive down).

    Returns:
        The fraction, in [0, 1].
    """
    u = min(1.0, max(-1.0, depth_m / HULL_HALF_HEIGHT_M))
    return 0.5 + (u * math.sqrt(1.0 - u * u) + math.asin(u)) / math.pi


class Sea:
    """The water the vehicles swim in: a current field (or still water) and the free surface z = 0.

    A sea is a description: it keeps no state of the physics it is applied to (the water applied
    to each vehicle is recorded by the facade), so it can be built before the physics and injected
    into it with :meth:`~bauv_sim.physics.BauvPhysics.set_sea`. Its current field may keep state of
    its own (a randomised current draws its realisation as time goes on): give every run its own.

    Args:
        current: the current field; None for still water.
    """

    def __init__(self, current: CurrentField | None = None) -> None:
        self._current = current

    @property
    def current(self) -> CurrentField | None:
        """The current field, or None for still water."""
        return self._current

    def apply(self, physics: BauvPhysics, *, again: bool = False) -> None:
        """Evaluate the sea at every vehicle now and apply it until the next call: the current, then
        the free surface.

        Args:
            physics: the physics the vehicles are in.
            again: whether this sea was applied to this physics before since it was injected (or
                the model reloaded), which :meth:`~bauv_sim.physics.BauvPhysics.apply_sea` knows;
                a current that is the same everywhere and always (``steady_uniform``) is then left
                as it was applied.
        """
        if not (again and getattr(self._current, "steady_uniform", False)):
            self._apply_current(physics)
        for name in physics.vehicle_names():
            physics.set_buoyancy_scale(submerged_fraction(physics.depth_m(name)), name)

    def _apply_current(self, physics: BauvPhysics) -> None:
        names = physics.vehicle_names()
        if self._current is None:
            for name in names:
                physics.set_water_world(np.zeros(3), np.zeros(3), name)
            return
        t = physics.time_s()
        tick = physics.control_tick_s
        steady = getattr(self._current, "steady_uniform", False)
        for name in names:
            p = physics.position_world(name)
            w0 = np.asarray(self._current.velocity_world(t, p), dtype=float)
            if steady:
                a = np.zeros(3)
            else:
                # the water at the vehicle at the end of the tick, where it will be: the water
                # changes linearly in between (a step of the field is spread over one tick)
                p1 = p + physics.velocity_world(name) * tick
                w1 = np.asarray(self._current.velocity_world(t + tick, p1), dtype=float)
                a = (w1 - w0) / tick
            physics.set_water_world(w0, a, name)
