"""Seed 003 (Naus & Piskur 2022): ``paper-003/test-1..3`` (a follower positioned relative to the
swarm leader on a square path: DR, GA1, GA2 and a range EKF). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure and recording (tasks.core.style),
# declared before its modules, which may read them when imported
declare(
    __name__,
    {
        "DR": MethodStyle(P["vermillion"]),
        "GA1": MethodStyle(P["reddish_purple"]),
        "GA2": MethodStyle(P["sky_blue"]),
        "EKF": MethodStyle(P["blue"]),
        "leader": MethodStyle(P["grey"], ls="--"),
    },
)

from tasks.paper003 import square  # noqa: E402

__all__ = ["square"]
