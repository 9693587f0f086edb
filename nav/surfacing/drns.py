"""Seed 001's dead reckoning corrected by the procedures' estimates (eq. 30-33): batched
(:func:`dr_velocity`, :func:`dr_track`) and online, the dead-reckoning navigational system (DRNS)
with its correction procedures.

The vehicle has a compass and odometry (the speed its drive setting should give) and no log: it
dead-reckons ``S += |Va| u(alpha) dt`` (eq. 30-31, with the measured heading as alpha). At every
surfacing a GPS fix measures how far the DR has drifted over the leg since the previous fix,
``dS = S_GPS - S_DR`` (eq. 7-10), and the DR restarts at the fix. After the second leg a
correction procedure (:mod:`nav.surfacing.procedures`: CP1, CP2 or the baseline) turns the two
legs' errors into estimates of the vehicle's systematic velocity error ``Vs`` (magnitude,
deviation beta) and of the current ``Vc``; from then on the DR integrates
``|Va| u(alpha) + Vs(alpha) + Vc(alpha)`` (eq. 32-33) and guidance may steer the compensated
course of eq. 22-26.

Three DR tracks run side by side from the same inputs and fixes, so that a mission compares them
on the same truth: ``uncorrected`` (eq. 30-31 throughout), ``corrected`` (the chosen procedure)
and ``baseline`` (the current from the last leg's error, (GPS - DR) / T).

Several fixes at one surfacing (the vehicle waits for a few) restart the DR each time; only the
first fix after a dive ends a leg. A leg's course alpha_j is the direction of the mean heading
vector over the leg (the vehicle holds one course per leg; turns at the ends are part of the
model error the procedures see in reality).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import course_of_scalar, unit_vector_scalar, velocity_from_course_speed
from nav.dead_reckoning import DeadReckoning
from nav.dead_reckoning import track as dead_reckoned_track
from nav.errors import NavInputError
from nav.surfacing.estimate import CorrectionEstimate, CurrentResponse
from nav.surfacing.procedures import baseline, cp1, cp2

Array = NDArray[np.float64]
Procedure = Literal["cp1", "cp2", "baseline", "none"]


# --------------------------------------------------------------------------------------------
# Corrected dead reckoning, batched


def dr_velocity(
    course_rad: ArrayLike, speed_m_s: ArrayLike, estimate: CorrectionEstimate | None = None
) -> Array:
    """The velocity dead reckoning integrates.

    Uncorrected (eq. 30-31): ``|Va| u(alpha)``. Corrected (eq. 32-33):
    ``|Va| u(alpha) + vs u(alpha + beta) + Vc(alpha)`` with the estimate's ``Vc`` carried to
    ``alpha`` by eq. 21 (CP2).

    Args:
        course_rad: compass courses, shape (n,) or (n, k), rad.
        speed_m_s: odometry speed ``|Va|``, broadcastable with ``course_rad``, m/s.
        estimate: a correction estimate for the ``n`` runs, or ``None`` for uncorrected DR.

    Returns:
        Velocity (east, north), shape ``course_rad.shape + (2,)``, m/s, world.
    """
    course = np.asarray(course_rad, dtype=float)
    v = velocity_from_course_speed(course, speed_m_s)
    if estimate is None:
        return v
    return v + estimate.velocity_error(course)


def dr_track(start_world_m: ArrayLike, velocity_world_m_s: ArrayLike, dt_s: float) -> Array:
    """Integrate DR velocities from a start fix (eq. 30-33 as sums over steps;
    :func:`nav.dead_reckoning.track` of the displacements ``v dt``).

    Args:
        start_world_m: positions at the start (the last fix), shape (n, 2), m, world.
        velocity_world_m_s: velocity of each step, shape (n, k, 2), m/s, world; step ``i`` moves
            from sample ``i`` to ``i + 1``.
        dt_s: step duration, s (> 0).

    Returns:
        Positions at samples ``0..k``, shape (n, k + 1, 2), m, world.

    Raises:
        NavInputError: if ``dt_s`` is not > 0.
    """
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise NavInputError(f"dt_s = {dt_s}: must be finite and > 0")
    return dead_reckoned_track(start_world_m, np.asarray(velocity_world_m_s, dtype=float) * dt_s)


# --------------------------------------------------------------------------------------------
# The DRNS, online


@dataclass(frozen=True)
class Leg:
    """One leg between two surfacings.

    Attributes:
        t_start_s: time of the fix the leg started from, s.
        duration_s: time from that fix to the first fix of the next surfacing, s.
        delta_world_m: ``S_GPS - S_DR`` at the end of the leg (DR restarted at its start), (2,), m.
        course_rad: direction of the mean heading vector over the leg, rad clockwise from north.
    """

    t_start_s: float
    duration_s: float
    delta_world_m: Array
    course_rad: float


@dataclass
class CorrectedDeadReckoning:
    """The DRNS of seed 001 (see the module docstring).

    Args:
        t0_s: time of the starting fix, s.
        position_world_m: the starting fix (east, north), shape (2,), m.
        procedure: the correction procedure run after the second leg.
        response: hull response for CP2's eq. 21 (in the physics world the vehicle drifts with the
            water whatever its course: a uniform response ``(1.0,)``).
        new_surfacing_after_s: a fix more than this after the previous one starts a new
            surfacing (ends a leg), s.
    """

    t0_s: float
    position_world_m: Array
    procedure: Procedure = "cp2"
    response: CurrentResponse = field(default_factory=lambda: CurrentResponse((1.0,)))
    new_surfacing_after_s: float = 5.0
    legs: list[Leg] = field(default_factory=list)
    estimate: CorrectionEstimate | None = None
    baseline_estimate: CorrectionEstimate | None = None
    correction_error: str | None = None

    def __post_init__(self) -> None:
        p = np.asarray(self.position_world_m, dtype=float).reshape(2)
        self.t_s = float(self.t0_s)
        self._tracks = {name: DeadReckoning(p) for name in ("uncorrected", "corrected", "baseline")}
        self._leg_start = (self.t_s, p.copy())
        self._leg_dr = DeadReckoning(np.zeros(2))  # uncorrected DR since the leg's start fix
        self._leg_heading = DeadReckoning(np.zeros(2))  # time integral of the heading unit vector
        self._last_fix_s = self.t_s

    @property
    def uncorrected(self) -> Array:
        """The uncorrected DR position (eq. 30-31), shape (2,), m, world."""
        return self._tracks["uncorrected"].position

    @property
    def corrected(self) -> Array:
        """The DR position corrected by the procedure (eq. 32-33), shape (2,), m, world."""
        return self._tracks["corrected"].position

    @property
    def baseline(self) -> Array:
        """The DR position corrected by the baseline's current, shape (2,), m, world."""
        return self._tracks["baseline"].position

    def predict(self, t_s: float, heading_rad: float, speed_m_s: float) -> None:
        """Dead-reckon to ``t_s`` with the heading and odometry speed held since the last call.

        Args:
            t_s: time, s (after the previous call).
            heading_rad: compass heading, rad clockwise from north.
            speed_m_s: odometry speed ``|Va|``, m/s.
        """
        dt = t_s - self.t_s
        if not dt > 0:
            raise NavInputError(f"predict to t = {t_s} s: not after the current {self.t_s} s")
        u = np.array(unit_vector_scalar(heading_rad))
        v = speed_m_s * u  # eq. 30-31
        tracks = self._tracks
        tracks["uncorrected"].advance(dt * v)
        self._leg_dr.advance(dt * v)
        self._leg_heading.advance(dt * u)
        tracks["corrected"].advance(dt * self._velocity(self.estimate, heading_rad, speed_m_s, v))
        tracks["baseline"].advance(
            dt * self._velocity(self.baseline_estimate, heading_rad, speed_m_s, v)
        )
        self.t_s = float(t_s)

    @staticmethod
    def _velocity(est: CorrectionEstimate | None, heading: float, speed: float, v: Array) -> Array:
        if est is None:
            return v
        return dr_velocity(np.array([heading]), np.array([speed]), est)[0]  # eq. 32-33

    def fix(self, t_s: float, gps_world_m: Array) -> Leg | None:
        """A GPS fix at the surface: end the leg if this is a new surfacing, restart the DR.

        Args:
            t_s: time of the fix, s.
            gps_world_m: the fix (east, north), shape (2,), m.

        Returns:
            The leg it ended, or ``None`` (a repeated fix of the same surfacing).
        """
        z = np.asarray(gps_world_m, dtype=float).reshape(2)
        leg = None
        if t_s - self._last_fix_s > self.new_surfacing_after_s:
            t0, p0 = self._leg_start
            leg_dr = self._leg_dr.position
            course = course_of_scalar(*self._leg_heading.position.tolist())
            leg = Leg(t0, t_s - t0, z - (p0 + leg_dr), course)
            self.legs.append(leg)
            if len(self.legs) == 2 and self.estimate is None:
                self._correct()
            if len(self.legs) >= 1:
                last = self.legs[-1]
                self.baseline_estimate = baseline(
                    z[None], (p0 + leg_dr)[None], np.array([last.duration_s])
                )
        self._last_fix_s = float(t_s)
        self._leg_start = (float(t_s), z.copy())
        self._leg_dr.reset(np.zeros(2))
        self._leg_heading.reset(np.zeros(2))
        for track in self._tracks.values():
            track.reset(z)
        return leg

    def _correct(self) -> None:
        """Run the procedure on the first two legs (a bad geometry leaves DR uncorrected and says
        why in :attr:`correction_error`)."""
        legs = self.legs[:2]
        delta = np.array([[leg.delta_world_m for leg in legs]])
        duration = np.array([[leg.duration_s for leg in legs]])
        course = np.array([[leg.course_rad for leg in legs]])
        try:
            if self.procedure == "cp2":
                # the vehicle's courses are 45/225 deg up to the controller's scatter
                self.estimate = cp2(
                    delta,
                    duration,
                    course,
                    response=self.response,
                    opposite_tolerance_rad=math.radians(10.0),
                )
            elif self.procedure == "cp1":
                self.estimate = cp1(delta, duration, course)
            elif self.procedure == "baseline":
                self.estimate = baseline(
                    np.array([legs[1].delta_world_m]),
                    np.zeros((1, 2)),
                    np.array([legs[1].duration_s]),
                )
            else:
                self.estimate = None
        except NavInputError as exc:
            self.estimate = None
            self.correction_error = str(exc)
