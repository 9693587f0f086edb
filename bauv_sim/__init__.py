"""bauv_sim: truth and sensors for a biomimetic AUV.

The world (MuJoCo physics or the seeds' kinematic models) produces truth; sensors turn truth into
measurements. Navigation lives in the separate package :mod:`nav`, which never imports this one.
"""

from pathlib import Path

from bauv_sim.errors import BauvSimError as BauvSimError
from bauv_sim.errors import ConfigError as ConfigError
from nav._exports import lazy_exports


def _data_root() -> Path:
    """Where ``models/`` and ``assets/`` are: ``bauv_sim/_data`` of an installed wheel (``setup.py``
    copies them there), else the source tree above this package (a checkout, an editable
    install)."""
    here = Path(__file__).resolve().parent
    wheel = here / "_data"
    return wheel if (wheel / "models").is_dir() else here.parent


PROJECT_ROOT = _data_root()
"""Folder holding ``models/`` and ``assets/``: the source tree of a checkout or editable install,
``bauv_sim/_data`` of an installed wheel (which has no ``docs/`` or ``tests/``)."""

_EXPORTS: dict[str, tuple[str, str]] = {
    "ActuatorCommand": ("bauv_sim.autopilot", "ActuatorCommand"),
    "Autopilot": ("bauv_sim.autopilot", "Autopilot"),
    "AutopilotConfig": ("bauv_sim.autopilot", "AutopilotConfig"),
    "BauvPhysics": ("bauv_sim.physics", "BauvPhysics"),
    "BeaconSpec": ("bauv_sim.build", "BeaconSpec"),
    "Config": ("bauv_sim.config", "Config"),
    "CurrentField": ("bauv_sim.currents", "CurrentField"),
    "GeometryError": ("bauv_sim.errors", "GeometryError"),
    "GyreCurrent": ("bauv_sim.currents", "GyreCurrent"),
    "Measured": ("bauv_sim.autopilot", "Measured"),
    "PhysicsError": ("bauv_sim.errors", "PhysicsError"),
    "RandomisedCurrent": ("bauv_sim.currents", "RandomisedCurrent"),
    "SceneConfig": ("bauv_sim.build", "SceneConfig"),
    "Sea": ("bauv_sim.sea", "Sea"),
    "ShearCurrent": ("bauv_sim.currents", "ShearCurrent"),
    "SumCurrent": ("bauv_sim.currents", "SumCurrent"),
    "Truth": ("bauv_sim.truth", "Truth"),
    "UniformCurrent": ("bauv_sim.currents", "UniformCurrent"),
    "VehicleSpec": ("bauv_sim.build", "VehicleSpec"),
    "VehicleTruth": ("bauv_sim.physics", "VehicleTruth"),
    "build_physics": ("bauv_sim.build", "build_physics"),
    "build_scene": ("bauv_sim.build", "build_scene"),
    "export_scene": ("bauv_sim.build", "export_scene"),
    "generator": ("bauv_sim.rng", "generator"),
    "generators": ("bauv_sim.rng", "generators"),
    "load_config": ("bauv_sim.config", "load_config"),
    "make_current": ("bauv_sim.currents", "make_current"),
    "seed_sequence": ("bauv_sim.rng", "seed_sequence"),
    "to_plain": ("bauv_sim.config", "to_plain"),
    "validate": ("bauv_sim.config", "validate"),
}
"""Public name -> (module, attribute), imported on first use."""

__all__, _export, __dir__ = lazy_exports(
    globals(), _EXPORTS, eager=("BauvSimError", "ConfigError", "PROJECT_ROOT")
)


def __getattr__(name: str) -> object:
    """A public name on first use; ``__version__`` is the installed distribution's version
    (:func:`bauv_sim.provenance.package_version`), read only when asked for."""
    if name == "__version__":
        from bauv_sim.provenance import package_version

        return package_version()
    return _export(name)
