"""Every registered experiment's name and summary, for ``bauv list`` without importing any
experiment package (the missions import MuJoCo and dm_control) and without reading the installed
distributions' metadata (:mod:`importlib.metadata` alone would add a third to ``bauv list``'s
start-up).

The list is data, ``catalog.json`` in the ``tasks`` package (beside the experiment packages, not
in the framework, which names no experiment), generated from the registry by ``python -m
tasks.core.catalog``; ``tests/tasks/test_registry.py`` fails, saying how to regenerate it, when it
differs from the registry (every family declared by the installed distributions,
:mod:`tasks.core.families`).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

PATH = Path(__file__).resolve().parents[1] / "catalog.json"
"""The catalog file: a JSON list of ``[name, summary]`` pairs sorted by name."""


def load() -> list[tuple[str, str]]:
    """``(name, summary)`` of every experiment, sorted by name, from :data:`PATH`."""
    return [(str(n), str(s)) for n, s in json.loads(PATH.read_text(encoding="utf-8"))]


def from_registry() -> list[tuple[str, str]]:
    """``(name, summary)`` of every registered experiment, sorted by name (imports them all)."""
    from tasks.core import registry

    return [(e.name, e.summary) for e in registry.all_experiments()]


def main() -> None:
    """Rewrite :data:`PATH` from the registry."""
    entries = from_registry()
    PATH.write_text(json.dumps(entries, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {len(entries)} entries to {PATH.name}", file=sys.stderr)


if __name__ == "__main__":
    main()
