"""Every registered experiment's name and summary, for ``bauv list`` without importing any
experiment package (the missions import MuJoCo and dm_control), and the package of each family of
names (:data:`FAMILIES`), which the registry imports on demand and a ``bauv run`` on local workers
hands to their fork server (where one is used) before it imports anything heavy
(:mod:`tasks.core.workers`).

The list is data, ``catalog.json`` beside this module, generated from the registry by ``python -m
tasks.core.catalog``; ``tests/tasks/test_registry.py`` fails, saying how to regenerate it, when it
differs from the registry.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

FAMILIES: dict[str, str] = {
    "paper-000": "tasks.paper000",
    "paper-001": "tasks.paper001",
    "paper-003": "tasks.paper003",
    "paper-004": "tasks.paper004",
    "mission": "tasks.missions",
    "vehicle": "tasks.vehicle",
}
"""Family of names (the part before ``/``) -> the package whose import registers them (also
:data:`tasks.core.registry.FAMILIES`)."""

PATH = Path(__file__).with_name("catalog.json")
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
