"""The registered closed-loop missions on the physical vehicle: ``mission/survey``,
``mission/surfacing``, ``mission/short``, ``mission/correction`` (seed 001 on the BAUV),
``mission/swarm`` (seed 003: followers keeping station on a leader), ``mission/seed004``
(seed 004: bearings to beacons, locally optimal control) and ``mission/trn`` (a DVL and
terrain-relative navigation over relief). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure and recording (tasks.core.style),
# declared before its modules, which may read them when imported
declare(
    __name__,
    {
        "DR": MethodStyle(P["vermillion"]),
        "EKF": MethodStyle(P["blue"]),
        "USBL": MethodStyle(P["bluish_green"], ls="none", marker="."),
        "GPS": MethodStyle(P["orange"], ls="none", marker="x"),
        "CP1": MethodStyle(P["reddish_purple"]),
        "CP2": MethodStyle(P["sky_blue"]),
        "baseline": MethodStyle(P["olive"], ls="-."),
        "GA1": MethodStyle(P["reddish_purple"]),
        "GA2": MethodStyle(P["sky_blue"]),
        "CMNF": MethodStyle(P["orange"]),
        "UPMF": MethodStyle(P["bluish_green"], ls="--"),
    },
)

from tasks.missions import correction, seed004, short, surfacing, survey, swarm, trn  # noqa: E402

__all__ = ["correction", "seed004", "short", "surfacing", "survey", "swarm", "trn"]
