# The public names of tasks.closed_loop, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

from .experiment import MissionExperiment as MissionExperiment
from .navigation import (
    EkfNavigation as EkfNavigation,
    FixRecord as FixRecord,
    NavOutput as NavOutput,
)
from .parts import (
    MissionDesign as MissionDesign,
    MissionParts as MissionParts,
    Pilot as Pilot,
    VehicleParts as VehicleParts,
    WaypointSteering as WaypointSteering,
)
from .recording import (
    mission_scene as mission_scene,
    record_flights as record_flights,
    RecordingScene as RecordingScene,
)
from .report import (
    export_runs as export_runs,
    mission_figures as mission_figures,
    record_mission as record_mission,
    report_mission as report_mission,
)
from .result import (
    EstimateTrack as EstimateTrack,
    FIX_COLUMNS as FIX_COLUMNS,
    MissionRun as MissionRun,
    STANDARD_ESTIMATES as STANDARD_ESTIMATES,
    TICK_COLUMNS as TICK_COLUMNS,
    VehicleRun as VehicleRun,
)
from .scenario import (
    GuidanceConfig as GuidanceConfig,
    MissionScenario as MissionScenario,
    MissionSensors as MissionSensors,
    NavigationConfig as NavigationConfig,
)
from .world import (
    build_environment as build_environment,
    build_physics_of as build_physics_of,
    check_world as check_world,
    fly as fly,
    MissionWorld as MissionWorld,
    standard_vehicle as standard_vehicle,
    WaypointMission as WaypointMission,
)
