"""Synthetic sensors: truth in, measurements out, with the shared error vocabulary of
:mod:`bauv_sim.sensors.errors` and one random stream per device and error term."""

from bauv_sim.sensors.base import SensorSamples, check_multiple, periodic_indices
from bauv_sim.sensors.batch import BatchUsbl, PrefetchedErrors
from bauv_sim.sensors.compass import Compass, CompassConfig
from bauv_sim.sensors.doa import Doa, DoaConfig, DoaSamples
from bauv_sim.sensors.dvl import (
    Dvl,
    DvlConfig,
    DvlPing,
    DvlSamples,
    PlaneSeabed,
    RaySeabed,
)
from bauv_sim.sensors.errors import (
    AngleErrorConfig,
    ErrorModel,
    ErrorProcess,
    LengthErrorConfig,
    SpeedErrorConfig,
)
from bauv_sim.sensors.gps import Gps, GpsConfig
from bauv_sim.sensors.log import Log, LogConfig
from bauv_sim.sensors.modem import Modem, ModemConfig
from bauv_sim.sensors.multibeam import (
    HarmonicSeabed,
    Multibeam,
    MultibeamConfig,
    MultibeamImages,
)
from bauv_sim.sensors.odometry import Odometry, OdometryConfig
from bauv_sim.sensors.pressure import Pressure, PressureConfig
from bauv_sim.sensors.usbl import Usbl, UsblConfig

__all__ = [
    "AngleErrorConfig",
    "BatchUsbl",
    "Compass",
    "CompassConfig",
    "Doa",
    "DoaConfig",
    "DoaSamples",
    "Dvl",
    "DvlConfig",
    "DvlPing",
    "DvlSamples",
    "ErrorModel",
    "ErrorProcess",
    "Gps",
    "GpsConfig",
    "HarmonicSeabed",
    "LengthErrorConfig",
    "Log",
    "LogConfig",
    "Modem",
    "ModemConfig",
    "Multibeam",
    "MultibeamConfig",
    "MultibeamImages",
    "Odometry",
    "OdometryConfig",
    "PlaneSeabed",
    "PrefetchedErrors",
    "Pressure",
    "PressureConfig",
    "RaySeabed",
    "SensorSamples",
    "SpeedErrorConfig",
    "Usbl",
    "UsblConfig",
    "check_multiple",
    "periodic_indices",
]
