"""Seed 004 (Miller, Miller & Miller 2019): ``paper-004/table-1``, ``paper-004/table-1-seabed``
and ``paper-004/near-beacon`` (bearing-only navigation with the EKF, the UPMF and the CMNF steering
the locally optimal control on the kinematic world) and ``paper-004/seabed-shift`` (the
seabed-sensing shift's own error). Importing registers them."""

from tasks.paper004 import seabed_shift, table1

__all__ = ["seabed_shift", "table1"]
