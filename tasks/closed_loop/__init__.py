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

from nav._exports import lazy_exports

_EXPORTS: dict[str, tuple[str, str]] = {
    "EkfNavigation": ("tasks.closed_loop.navigation", "EkfNavigation"),
    "FIX_COLUMNS": ("tasks.closed_loop.result", "FIX_COLUMNS"),
    "FixRecord": ("tasks.closed_loop.navigation", "FixRecord"),
    "GuidanceConfig": ("tasks.closed_loop.scenario", "GuidanceConfig"),
    "MissionDesign": ("tasks.closed_loop.parts", "MissionDesign"),
    "MissionExperiment": ("tasks.closed_loop.experiment", "MissionExperiment"),
    "MissionParts": ("tasks.closed_loop.parts", "MissionParts"),
    "MissionRun": ("tasks.closed_loop.result", "MissionRun"),
    "MissionScenario": ("tasks.closed_loop.scenario", "MissionScenario"),
    "MissionSensors": ("tasks.closed_loop.scenario", "MissionSensors"),
    "MissionWorld": ("tasks.closed_loop.world", "MissionWorld"),
    "NavOutput": ("tasks.closed_loop.navigation", "NavOutput"),
    "NavigationConfig": ("tasks.closed_loop.scenario", "NavigationConfig"),
    "Pilot": ("tasks.closed_loop.parts", "Pilot"),
    "TICK_COLUMNS": ("tasks.closed_loop.result", "TICK_COLUMNS"),
    "VehicleParts": ("tasks.closed_loop.parts", "VehicleParts"),
    "VehicleRun": ("tasks.closed_loop.result", "VehicleRun"),
    "WaypointMission": ("tasks.closed_loop.world", "WaypointMission"),
    "WaypointSteering": ("tasks.closed_loop.parts", "WaypointSteering"),
    "build_environment": ("tasks.closed_loop.world", "build_environment"),
    "export_runs": ("tasks.closed_loop.report", "export_runs"),
    "fly": ("tasks.closed_loop.world", "fly"),
    "mission_figures": ("tasks.closed_loop.report", "mission_figures"),
    "record_mission": ("tasks.closed_loop.report", "record_mission"),
    "report_mission": ("tasks.closed_loop.report", "report_mission"),
    "standard_vehicle": ("tasks.closed_loop.world", "standard_vehicle"),
}
"""Public name -> (module, attribute), imported on first use."""

__all__, __getattr__, __dir__ = lazy_exports(globals(), _EXPORTS)

# the looks of the methods its report draws (tasks.core.style), the same as the missions'
from tasks.core.style import PALETTE as _P  # noqa: E402
from tasks.core.style import MethodStyle, declare  # noqa: E402

declare(
    __name__,
    {
        "DR": MethodStyle(_P["vermillion"]),
        "EKF": MethodStyle(_P["blue"]),
        "USBL": MethodStyle(_P["bluish_green"], ls="none", marker="."),
        "GPS": MethodStyle(_P["orange"], ls="none", marker="x"),
    },
)
