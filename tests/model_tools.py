"""The model's tooling for the tests: the scripts of ``models/bauv/tools`` (outside the installed
package; they import each other by name, as when run as ``python models/bauv/tools/NAME.py``)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

TOOLS = Path(__file__).resolve().parents[1] / "models" / "bauv" / "tools"
"""``models/bauv/tools`` of this checkout."""


def tool(name: str) -> ModuleType:
    """Import one script of ``models/bauv/tools`` by its module name (``"timestep"``)."""
    if str(TOOLS) not in sys.path:
        sys.path.insert(0, str(TOOLS))
    return importlib.import_module(name)
