"""bauv_sim: truth and sensors for a biomimetic AUV.

The world (MuJoCo physics or the seeds' kinematic models) produces truth; sensors turn truth into
measurements. Navigation lives in the separate package :mod:`nav`, which never imports this one.
"""

from pathlib import Path

import lazy_loader

from bauv_sim.errors import BauvSimError as BauvSimError
from bauv_sim.errors import ConfigError as ConfigError


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

# the public names: those of __init__.pyi, each imported from its module on first use
_lazy_getattr, _lazy_dir, _lazy_all = lazy_loader.attach_stub(__name__, __file__)
__all__ = sorted([*_lazy_all, "PROJECT_ROOT"])


def __getattr__(name: str) -> object:
    """A public name on first use; ``__version__`` is the installed distribution's version
    (:func:`bauv_sim.provenance.package_version`), read only when asked for."""
    if name == "__version__":
        from bauv_sim.provenance import package_version

        return package_version()
    return _lazy_getattr(name)


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
