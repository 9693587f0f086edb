"""The mission core: closed-loop missions composed of parts, for one or more vehicles.

* :mod:`~tasks.closed_loop.scenario`: the scenario sections of a way-point mission;
* :mod:`~tasks.closed_loop.parts`: the parts and their protocols (navigation, guidance, pilot),
  the action and observation specs, :class:`~tasks.closed_loop.parts.MissionDesign`;
* :mod:`~tasks.closed_loop.navigation`: the standard navigation part (EKF + DR on the rig);
* :mod:`~tasks.closed_loop.world`: the dm_control task of N vehicles, the standard design,
  :func:`~tasks.closed_loop.world.fly`;
* :mod:`~tasks.closed_loop.result`: the run as plain data (typed columns with units);
* :mod:`~tasks.closed_loop.report`: metrics, tables, figures, recording, Parquet;
* :mod:`~tasks.closed_loop.experiment`: :class:`~tasks.closed_loop.experiment.MissionExperiment`.
"""

import lazy_loader

# the public names: those of __init__.pyi, each imported from its module on first use
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)

# the looks of the methods its report draws (tasks.core.style), the same as the missions'
from tasks.core.style import PALETTE as _P  # noqa: E402
from tasks.core.style import MethodStyle as _Style  # noqa: E402
from tasks.core.style import declare as _declare  # noqa: E402

_declare(
    __name__,
    {
        "DR": _Style(_P["vermillion"]),
        "EKF": _Style(_P["blue"]),
        "USBL": _Style(_P["bluish_green"], ls="none", marker="."),
        "GPS": _Style(_P["orange"], ls="none", marker="x"),
    },
)
