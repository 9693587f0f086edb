"""Seed 004's filter bank: one step of the EKF, the UPMF or the CMNF on the bearings, the same
call for the table's batched paths (``paper-004``) and the mission's single vehicle
(``mission/seed004``).

A step takes the estimate of step ``j - 1`` (``x_hat`` ``(n, 3)`` m, ``p_hat`` ``(n, 3, 3)``
m^2), the prediction of the step (a :class:`nav.bearings.model.PredictedShift`: by virtue of the
system or the seabed-sensing shift) and the bearings measured at ``t_j`` (tangents ``(n, B, 2)``,
``present`` ``(n, B)``), and returns the prediction ``X~_j`` and the estimate ``(X^_j, P^_j)``:

* ``"EKF"``: :func:`nav.bearings.filters.predict` (eq. 21, first two lines) and the one Kalman
  update with the bearing model (:func:`nav.bearings.filters.ekf_update`);
* ``"UPMF"``: the same prediction and the pseudo-measurement update (eq. 19-21,
  :func:`nav.bearings.filters.upmf_update`, its form from the options);
* ``"CMNF"``: eq. 22 with fitted gains on the basic prediction ``alpha = X^_{j-1} + shift``
  (eq. 24, :func:`nav.bearings.cmnf.cmnf_step`); its covariance is the one the CMNF states for
  the step (section 5.2, ``gains.p_hat[j - 1]``), the same for every path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nav.bearings.cmnf import CmnfGains, Correction, cmnf_step
from nav.bearings.filters import UPMF_FORMS, ekf_update, predict, upmf_update
from nav.bearings.model import Array, PredictedShift
from nav.errors import NavInputError

FILTERS: tuple[str, ...] = ("EKF", "UPMF", "CMNF")
"""The filters of the bank, in the one spelling every caller uses (seed 004's names)."""


@dataclass(frozen=True)
class BankOptions:
    """What the filters need beyond the step's data.

    Attributes:
        s_eps: ``S^eps``, shape ``(2, 2)``: the covariance of one pair's tangent noise the EKF and
            the UPMF assume.
        upmf_form: ``"unbiased"`` or ``"printed"`` (:func:`nav.bearings.filters.upmf_update`).
        gains: the CMNF's fitted gains (needed by ``"CMNF"`` only).
        correction: the CMNF's basic correction, ``"residual"`` or ``"pseudo"``.
    """

    s_eps: Array
    upmf_form: str = "unbiased"
    gains: CmnfGains | None = None
    correction: Correction = "residual"


@dataclass(frozen=True)
class BankStep:
    """The result of one step of a filter of the bank.

    Attributes:
        x_tilde: the prediction ``X~_j``, shape ``(n, 3)``, m.
        x_hat: the estimate ``X^_j``, shape ``(n, 3)``, m.
        p_hat: its covariance, shape ``(n, 3, 3)``, m^2 (the CMNF: its stated covariance of step
            ``j``, the same for every path).
    """

    x_tilde: Array
    x_hat: Array
    p_hat: Array


def step(
    name: str,
    j: int,
    x_hat: Array,
    p_hat: Array,
    shift: PredictedShift,
    y: Array,
    present: NDArray[np.bool_],
    beacons: Array,
    options: BankOptions,
) -> BankStep:
    """One step of the filter ``name`` of the bank (module docstring).

    Args:
        name: one of :data:`FILTERS`.
        j: the index of the step the new estimate belongs to, 1..N (the CMNF's gains are per
            step).
        x_hat: estimates of step ``j - 1``, shape ``(n, 3)``, m.
        p_hat: their covariances, shape ``(n, 3, 3)``, m^2 (unused by the CMNF).
        shift: the step's predicted displacement and its covariance.
        y: tangents measured at ``t_j``, shape ``(n, B, 2)``.
        present: shape ``(n, B)``: which pairs were measured.
        beacons: shape ``(B, 3)``, m.
        options: the filters' settings.

    Returns:
        The :class:`BankStep`.

    Raises:
        NavInputError: for an unknown filter, an unknown UPMF form, or the CMNF without gains.
    """
    if name == "CMNF":
        gains = options.gains
        if gains is None:
            raise NavInputError("filter 'CMNF': needs fitted gains (BankOptions.gains)")
        alpha = x_hat + shift.displacement_m
        x_t, x_new = cmnf_step(gains, j, alpha, options.correction, y, present, beacons)
        p_new = np.broadcast_to(gains.p_hat[j - 1], (len(x_new), 3, 3)).copy()
        return BankStep(x_t, x_new, p_new)
    if name == "EKF":
        x_t, p_t = predict(x_hat, p_hat, shift)
        x_new, p_new = ekf_update(x_t, p_t, y, present, beacons, options.s_eps)
        return BankStep(x_t, x_new, p_new)
    if name == "UPMF":
        if options.upmf_form not in UPMF_FORMS:
            raise NavInputError(
                f"upmf_form = {options.upmf_form!r}: must be one of {', '.join(UPMF_FORMS)}"
            )
        x_t, p_t = predict(x_hat, p_hat, shift)
        x_new, p_new = upmf_update(
            x_t, p_t, y, present, beacons, options.s_eps, form=options.upmf_form
        )
        return BankStep(x_t, x_new, p_new)
    raise NavInputError(f"filter {name!r}: must be one of {', '.join(FILTERS)}")
