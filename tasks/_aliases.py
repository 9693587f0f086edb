"""Public names of :mod:`tasks` that differ from their names in the module defining them (the
package's ``__init__.pyi`` imports them from here): :mod:`tasks.core` exports the registry's
``get`` and ``names``, which read as ``tasks.get_experiment`` and ``tasks.experiment_names``."""

from tasks.core.registry import get as get_experiment
from tasks.core.registry import names as experiment_names

__all__ = ["experiment_names", "get_experiment"]
