"""Seed 004 (Miller, Miller & Miller 2019): ``paper-004/table-1`` and ``paper-004/near-beacon``
(bearing-only navigation with the EKF, the UPMF and the CMNF steering the locally optimal control
on the kinematic world). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare
from tasks.paper004 import table1

__all__ = ["table1"]

# the looks of this package's methods in every figure and recording (tasks.core.style)
declare(
    __name__,
    {
        "EKF": MethodStyle(P["blue"]),
        "UPMF": MethodStyle(P["bluish_green"], ls="--"),
        "CMNF": MethodStyle(P["orange"]),
        "PCRB": MethodStyle(P["black"], ls=":"),
    },
)
