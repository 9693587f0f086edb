"""Seed 000 (Naus & Nowak 2016): USBL positioning with dead reckoning.

* :mod:`nav.usbl.accuracy`: the analytic accuracy of USBL fixes and of dead reckoning (sections
  2-3, eq. 1-14);
* :mod:`nav.usbl.tracks`: the EKF over many passages at once (eq. 17-23 on a structure of arrays,
  its updates :func:`nav.ekf.update_packed3`) and the reductions of its tracks that are metrics;
* :mod:`nav.usbl.passage`: the three navigations of a batch of passages (DR, EKF, USBL alone).
"""

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
from nav.usbl.passage import PassageEstimates, navigate_passages, passage_ekf
from nav.usbl.tracks import (
    SYM,
    ThreeComponentMeasurement,
    Tracks,
    ekf_tracks,
    horizontal_distance_tm,
    nees_packed,
    nees_tm,
    pack,
    sigma_h,
    unpack,
)

__all__ = [
    "SYM",
    "Ellipse",
    "PassageEstimates",
    "ThreeComponentMeasurement",
    "Tracks",
    "dr_covariance_random_walk",
    "dr_covariance_single_step",
    "dr_step_covariance",
    "ekf_tracks",
    "ellipse_parameters",
    "horizontal_distance_tm",
    "mean_error",
    "navigate_passages",
    "nees_packed",
    "nees_tm",
    "pack",
    "passage_ekf",
    "sigma_h",
    "unpack",
    "usbl_ellipse",
    "usbl_mean_error",
    "usbl_position_line_errors",
]
