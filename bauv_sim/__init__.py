"""bauv_sim: truth and sensors for a biomimetic AUV.

The world (MuJoCo physics or the seeds' kinematic models) produces truth; sensors turn truth into
measurements. Navigation lives in the separate package :mod:`nav`, which never imports this one.
"""

from pathlib import Path

from bauv_sim.errors import BauvSimError, ConfigError

PROJECT_ROOT = Path(__file__).resolve().parents[1]
"""Root of the source tree (holds ``models/`` and ``assets/``)."""

__all__ = ["PROJECT_ROOT", "BauvSimError", "ConfigError"]
