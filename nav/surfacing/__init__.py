"""Seed 001 (Praczyk): navigation corrected at surfacing, for a vehicle with compass and odometry.

* :mod:`nav.surfacing.estimate`: what a correction procedure estimates (the vehicle's systematic
  velocity error ``Vs``, its deviation ``beta``, the current ``Vc``) and the hull's response to the
  current that carries ``Vc`` to other courses (eq. 21, 29, 34);
* :mod:`nav.surfacing.procedures`: correction procedures CP1 (eq. 7-12) and CP2 (eq. 13-21) from
  the GPS errors of two legs, and the simple baseline (current = (GPS - DR) / time);
* :mod:`nav.surfacing.drns`: dead reckoning corrected by an estimate (eq. 30-33), batched, and the
  online dead-reckoning navigational system (DRNS) that runs the procedures at its surfacings;
* :mod:`nav.surfacing.course`: the course that compensates the estimated current and vehicle error
  (eq. 22-26, CP2's three-phase fix).
"""

from nav.surfacing.course import CourseSolution, compensated_course, course_through_current
from nav.surfacing.drns import CorrectedDeadReckoning, Leg, Procedure, dr_track, dr_velocity
from nav.surfacing.estimate import (
    DEFAULT_RHO_S_COS_COEFFS,
    CorrectionEstimate,
    CurrentResponse,
    vs_sign,
)
from nav.surfacing.procedures import OnBad, baseline, cp1, cp1_objective, cp2

__all__ = [
    "DEFAULT_RHO_S_COS_COEFFS",
    "CorrectedDeadReckoning",
    "CorrectionEstimate",
    "CourseSolution",
    "CurrentResponse",
    "Leg",
    "OnBad",
    "Procedure",
    "baseline",
    "compensated_course",
    "course_through_current",
    "cp1",
    "cp1_objective",
    "cp2",
    "dr_track",
    "dr_velocity",
    "vs_sign",
]
