"""Compatibility: seed 000's analytic accuracy lives in :mod:`nav.usbl.accuracy` (import it from
:mod:`nav.usbl`); this module only keeps the old import path of code not yet moved working."""

from nav.usbl.accuracy import (
    Ellipse,
    dr_covariance_random_walk,
    dr_covariance_single_step,
    dr_step_covariance,
    ellipse_parameters,
    mean_error,
    usbl_ellipse,
    usbl_mean_error,
    usbl_position_line_errors,
)

__all__ = [
    "Ellipse",
    "dr_covariance_random_walk",
    "dr_covariance_single_step",
    "dr_step_covariance",
    "ellipse_parameters",
    "mean_error",
    "usbl_ellipse",
    "usbl_mean_error",
    "usbl_position_line_errors",
]
