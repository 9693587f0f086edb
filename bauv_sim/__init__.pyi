# The public names of bauv_sim, read by type checkers and by lazy_loader.attach_stub in
# __init__.py, which imports each from its module on first use (`name as name`: re-exported).

import pathlib  # not `from pathlib import`: attach_stub reads every from-import as a public name

from .autopilot import (
    ActuatorCommand as ActuatorCommand,
    Autopilot as Autopilot,
    AutopilotConfig as AutopilotConfig,
    Measured as Measured,
)
from .autopilot_batch import (
    BatchAutopilot as BatchAutopilot,
    BatchCommand as BatchCommand,
    BatchMeasured as BatchMeasured,
)
from .build import (
    BeaconSpec as BeaconSpec,
    build_physics as build_physics,
    build_scene as build_scene,
    export_scene as export_scene,
    SceneConfig as SceneConfig,
    VehicleSpec as VehicleSpec,
)
from .config import (
    Config as Config,
    load_config as load_config,
    to_plain as to_plain,
    validate as validate,
)
from .currents import (
    CurrentField as CurrentField,
    GyreCurrent as GyreCurrent,
    make_current as make_current,
    RandomisedCurrent as RandomisedCurrent,
    ShearCurrent as ShearCurrent,
    SumCurrent as SumCurrent,
    UniformCurrent as UniformCurrent,
)
from .errors import (
    BauvSimError as BauvSimError,
    ConfigError as ConfigError,
    GeometryError as GeometryError,
    PhysicsError as PhysicsError,
)
from .physics import BauvPhysics as BauvPhysics, VehicleTruth as VehicleTruth
from .rng import generator as generator, generators as generators, seed_sequence as seed_sequence
from .sea import Sea as Sea
from .truth import Truth as Truth

PROJECT_ROOT: pathlib.Path
__version__: str
