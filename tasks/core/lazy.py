"""Modules imported on first use, so that a run imports only what it needs.

Plotting (matplotlib), recording (rerun) and Parquet (pyarrow) cost a large part of a short run's
start-up and are used only in the report; a module that needs them holds a :class:`LazyModule`
instead of importing them at its top. Unlike :class:`importlib.util.LazyLoader` (which
``lazy_loader.load`` uses), nothing is put in ``sys.modules`` before the first attribute is read,
so ``sys.modules`` tells what was really imported (tests/tasks/test_imports.py checks a kinematic
run), and a module can be set up on its import (matplotlib's backend before ``pyplot``).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from types import ModuleType
from typing import Any


class LazyModule:
    """A module imported the first time one of its attributes is read.

    Args:
        name: the module's full name (``"matplotlib.pyplot"``).
        setup: called with the module right after its import (e.g. to select a backend).
        after: lazy modules to load first (``matplotlib`` with its backend before ``pyplot``).
    """

    def __init__(
        self,
        name: str,
        setup: Callable[[ModuleType], None] | None = None,
        after: tuple[LazyModule, ...] = (),
    ):
        self._name = name
        self._setup = setup
        self._after = after
        self._module: ModuleType | None = None

    def load(self) -> ModuleType:
        """The module, imported now if it was not."""
        if self._module is None:
            for first in self._after:
                first.load()
            module = importlib.import_module(self._name)
            if self._setup is not None:
                self._setup(module)
            self._module = module
        return self._module

    def __getattr__(self, attr: str) -> Any:
        return getattr(self.load(), attr)

    def __repr__(self) -> str:
        state = "loaded" if self._module is not None else "not loaded"
        return f"<lazy module {self._name!r} ({state})>"
