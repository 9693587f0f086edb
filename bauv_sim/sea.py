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

The physics owns no sea: whoever runs it applies one. :meth:`Sea.immerse` puts the vehicles in a
sea (it carries every vehicle with the change of the water at it: Galilean invariance, the motion of
a neutrally buoyant body when the whole sea changes its velocity; a vehicle placed with its speed
through still water starts moving with the water) and installs :meth:`Sea.apply` as the physics'
tick hook, so that :meth:`~bauv_sim.physics.BauvPhysics.advance` applies the sea at the start of
every control tick; a ``dm_control`` task that steps the physics itself (a mission's world) calls
:meth:`Sea.apply` in ``before_step``. The primitives the sea acts through are the actuation
part's (:class:`bauv_sim.physics_actuation.Actuation`: the water at each vehicle, the scale of its
buoyancy, a vehicle carried with the water); the physics does not import this module.
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

    A sea is a description: the water applied to each vehicle is the physics'
    (:meth:`~bauv_sim.physics.BauvPhysics.set_water_world`), so a sea can be built before the
    physics and put around its vehicles with :meth:`immerse`. It remembers only the simulation it
    was last applied to, so that a steady uniform current is written once per immersion (and again
    after the model is reloaded), not at every tick. Its current field may keep state of its own (a
    randomised current draws its realisation as time goes on): give every run its own.

    Args:
        current: the current field; None for still water.
    """

    def __init__(self, current: CurrentField | None = None) -> None:
        self._current = current
        self._applied_to: object | None = None  # the MuJoCo data last applied to

    @property
    def current(self) -> CurrentField | None:
        """The current field, or None for still water."""
        return self._current

    def immerse(self, physics: BauvPhysics) -> None:
        """Put the vehicles of a physics in this sea: apply it now, and at the start of every
        control tick of :meth:`~bauv_sim.physics.BauvPhysics.advance` (this sea's :meth:`apply`
        becomes the physics' tick hook, :meth:`~bauv_sim.physics.BauvPhysics.set_tick_hook`).

        The vehicles are carried by the change of the water: each vehicle's velocity over ground
        changes by the water velocity at it in this sea minus the water it was in, so that its
        motion relative to the water (and its angular velocity and joints) is what it was. This is
        Galilean invariance, the motion of a neutrally buoyant body in a sea whose velocity changes
        as a whole: the Froude-Krylov force ``rho V a`` and the added mass's reaction ``M_A a``
        accelerate the body's mass and added mass with the water (``models/bauv/README.md``,
        "Current"). A vehicle placed with its speed through the water in still water (a physics
        fresh from its model) and then put in a current therefore starts moving with the water, and
        a steady uniform current put around it during a run carries it at once. (A current field
        that changes in time during a run is different water accelerating: that acts through the
        plugin's Froude-Krylov and added-mass forces over the tick.) To release a vehicle at rest
        over ground in a current that was always there, set its pose after immersing it.

        Args:
            physics: the physics whose vehicles swim in this sea.
        """
        names = physics.vehicle_names()
        before = [physics.current_at_vehicle_world(n) for n in names]
        physics.set_tick_hook(self.apply)
        self._applied_to = None  # a new immersion: the current is written anew
        self.apply(physics)
        carried = False
        for name, w_before in zip(names, before, strict=True):
            change = physics.current_at_vehicle_world(name) - w_before
            if np.any(change != 0.0):
                physics.shift_velocity_world(change, name)
                carried = True
        if carried:
            # the sea's first tick saw the velocities before the carry (where a vehicle will be at
            # the tick's end): evaluate it again from the carried state
            self.apply(physics)

    def apply(self, physics: BauvPhysics) -> None:
        """Evaluate the sea at every vehicle now and apply it until the next call: the current, then
        the free surface. A current that is the same everywhere and always (``steady_uniform``) is
        left as it was applied when this sea was applied to the same simulation before since it
        was immersed (:meth:`immerse`) and the model was (re)loaded.

        Args:
            physics: the physics the vehicles are in.
        """
        data = physics.data.ptr  # a model reload gives the physics new data
        again = self._applied_to is data
        if not (again and getattr(self._current, "steady_uniform", False)):
            self._apply_current(physics)
        self._applied_to = data
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
