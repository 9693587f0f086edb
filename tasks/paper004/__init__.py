"""Seed 004 (Miller, Miller & Miller 2019): ``paper-004/table-1`` and ``paper-004/near-beacon``
(bearing-only navigation with the EKF, the UPMF and the CMNF steering the locally optimal control
on the kinematic world). Importing registers them."""

from tasks.paper004 import table1

__all__ = ["table1"]
