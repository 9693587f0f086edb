# The public names of tasks, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

from ._aliases import experiment_names as experiment_names, get_experiment as get_experiment
from .closed_loop.result import MissionRun as MissionRun, VehicleRun as VehicleRun
from .closed_loop.scenario import MissionScenario as MissionScenario
from .closed_loop.world import fly as fly, WaypointMission as WaypointMission
from .core.errors import BatchFailed as BatchFailed, BatchInterrupted as BatchInterrupted
from .core.export import (
    Column as Column,
    read_parquet as read_parquet,
    write_parquet as write_parquet,
)
from .core.plan import BatchPlan as BatchPlan, plan_batch as plan_batch
from .core.registry import Experiment as Experiment, register as register
from .core.runner import run as run
