"""Seed 001 (Praczyk): ``paper-001/replica`` (Tables 1-3 of the correction procedures in the
kinematic world). Importing registers it."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure and recording (tasks.core.style),
# declared before its modules, which may read them when imported
declare(
    __name__,
    {
        "DR": MethodStyle(P["vermillion"]),
        "GPS": MethodStyle(P["orange"], ls="none", marker="x"),
        "CP1": MethodStyle(P["reddish_purple"]),
        "CP2": MethodStyle(P["sky_blue"]),
        "baseline": MethodStyle(P["olive"], ls="-."),
    },
)

from tasks.paper001 import replica  # noqa: E402

__all__ = ["replica"]
