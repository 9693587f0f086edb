"""``docs/run-data.md`` read by the tests: the units it states for every column, from its tables
and from its paragraphs on the missions' own columns (not a test module)."""

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[2] / "docs" / "run-data.md"


def table_units() -> dict[str, dict[str, str]]:
    """The tables, parsed: table heading -> column name -> unit. A row may name several columns
    (`a`, `b`) with one unit each ("m, rad, rad") or one for all."""
    tables: dict[str, dict[str, str]] = {}
    current = None
    for line in DOC.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            current = tables.setdefault(line[3:].strip(), {})
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if current is None or not line.startswith("| `") or len(cells) < 3:
            continue
        names = re.findall(r"`([^`]+)`", cells[0])
        units = [u.strip() for u in cells[1].split(",")]
        assert len(units) in (1, len(names)), line
        for i, name in enumerate(names):
            current[name] = units[i if len(units) > 1 else 0]
    return tables


def prose_units(lead: str) -> dict[str, str]:
    """The units the paragraph starting with ``lead`` gives to the columns it names: "`a`, `b`
    and `c` (unit, ...)" gives a, b and c that unit."""
    paragraphs = DOC.read_text(encoding="utf-8").split("\n\n")
    text = " ".join(next(p for p in paragraphs if p.startswith(lead)).split())
    units = {}
    for names, unit in re.findall(r"((?:`\w+`(?:, | and )?)+) \(([^,;:)\s]+)", text):
        for name in re.findall(r"`(\w+)`", names):
            units[name] = unit
    return units
