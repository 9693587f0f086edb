"""Compatibility: seed 001's correction procedures live in :mod:`nav.surfacing` (estimate,
procedures, corrected DR, compensated course); this module only keeps the old import path of code
not yet moved working."""

from nav.surfacing import (
    DEFAULT_RHO_S_COS_COEFFS,
    CorrectionEstimate,
    CourseSolution,
    CurrentResponse,
    OnBad,
    baseline,
    compensated_course,
    course_through_current,
    cp1,
    cp1_objective,
    cp2,
    dr_track,
    dr_velocity,
    vs_sign,
)

__all__ = [
    "DEFAULT_RHO_S_COS_COEFFS",
    "CorrectionEstimate",
    "CourseSolution",
    "CurrentResponse",
    "OnBad",
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
