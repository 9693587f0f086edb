"""Seed 004's bearing filters (Miller, Miller & Miller 2019): one package per method family.

* :mod:`nav.bearings.model`: the 3-D motion model (eq. 1-3), the pluggable prediction step and
  the bearing tangents to beacons (eq. 17) with their measurement model for the one EKF update;
* :mod:`nav.bearings.filters`: the prediction of eq. 21, the EKF update (:func:`nav.ekf.update`
  with the bearing model) and the UPMF (eq. 19-21, its own algorithm);
* :mod:`nav.bearings.cmnf`: the conditionally minimax nonlinear filter (eq. 22-24) and the Monte
  Carlo fit of its gains (its own algorithm);
* :mod:`nav.bearings.bank`: one step of any filter of the bank (EKF, UPMF, CMNF), used by the
  paper's table and by the mission;
* :mod:`nav.bearings.pcrb`: the posterior Cramer-Rao bound of the bearing problem;
* :mod:`nav.bearings.local_control`: the locally optimal path-following control (eq. 5-7).

The names of the former module ``nav.bearings`` stay importable from the package (``from
nav.bearings import ekf_update``); ``step`` here is the motion model's step (eq. 1), the bank's
is :func:`nav.bearings.bank.step`.
"""

from nav.bearings.filters import (
    UPMF_FORMS,
    ekf_update,
    pinv_floor,
    predict,
    pseudo_measurements,
    pseudo_noise_mean,
    upmf_update,
)
from nav.bearings.model import (
    MAX_TAN,
    MIN_RHO_M,
    BearingTangents,
    PredictedShift,
    Prediction,
    SystemPrediction,
    bearing_jacobian,
    bearings,
    check_beacons,
    nominal_path,
    observable,
    step,
    velocity,
)

__all__ = [
    "MAX_TAN",
    "MIN_RHO_M",
    "UPMF_FORMS",
    "BearingTangents",
    "PredictedShift",
    "Prediction",
    "SystemPrediction",
    "bearing_jacobian",
    "bearings",
    "check_beacons",
    "ekf_update",
    "nominal_path",
    "observable",
    "pinv_floor",
    "predict",
    "pseudo_measurements",
    "pseudo_noise_mean",
    "step",
    "upmf_update",
    "velocity",
]
