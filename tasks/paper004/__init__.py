"""Seed 004 (Miller, Miller & Miller 2019): ``paper-004/table-1``, ``paper-004/table-1-seabed``
and ``paper-004/near-beacon`` (bearing-only navigation with the EKF, the UPMF and the CMNF steering
the locally optimal control on the kinematic world) and ``paper-004/seabed-shift`` (the
seabed-sensing shift's own error). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure and recording (tasks.core.style),
# declared before its modules, which may read them when imported
declare(
    __name__,
    {
        "EKF": MethodStyle(P["blue"]),
        "UPMF": MethodStyle(P["bluish_green"], ls="--"),
        "CMNF": MethodStyle(P["orange"]),
        "PCRB": MethodStyle(P["black"], ls=":"),
    },
)

from tasks.paper004 import seabed_shift, table1  # noqa: E402

__all__ = ["seabed_shift", "table1"]
