"""The registered closed-loop missions on the physical vehicle: ``mission/survey``,
``mission/surfacing``, ``mission/short``, ``mission/correction`` (seed 001 on the BAUV),
``mission/swarm`` (seed 003: followers keeping station on a leader), ``mission/seed004``
(seed 004: bearings to beacons, locally optimal control) and ``mission/trn`` (a DVL and
terrain-relative navigation over relief). Importing declares them; each mission's module is
imported when its name is first asked for (:func:`tasks.core.registry.register_modules`)."""

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

# what every mission is made of (each is a MissionExperiment): imported with the package, so that
# a fork server that preloads the package (tasks.core.workers) holds it for its workers
import tasks.closed_loop.experiment  # noqa: E402, F401
from tasks.core.registry import register_modules  # noqa: E402

# each mission's own module is imported when its name is first asked for (tasks.core.registry): a
# run of one mission does not import the others' (0.18 s of mission/survey's start-up)
register_modules(
    {
        f"mission/{name}": f"{__name__}.{name}"
        for name in ("correction", "seed004", "short", "surfacing", "survey", "swarm", "trn")
    }
)
