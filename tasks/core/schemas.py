"""Write the JSON Schema of every experiment's ``metrics.json`` to ``docs/schemas/``.

Run ``python -m tasks.core.schemas`` after changing a metrics model; a test checks that the files
are current.
"""

from __future__ import annotations

import json
from pathlib import Path

from bauv_sim import PROJECT_ROOT
from tasks.core import registry

SCHEMA_DIR = PROJECT_ROOT / "docs" / "schemas"


def schema_files() -> dict[Path, str]:
    """Schema file path -> its JSON text, one per metrics model (shared models written once)."""
    out: dict[Path, str] = {}
    for exp in registry.all_experiments():
        model = exp.metrics_type
        if model is None:
            continue
        text = json.dumps(model.model_json_schema(), indent=2, sort_keys=True) + "\n"
        out[SCHEMA_DIR / f"{model.__name__}.schema.json"] = text
    return out


def main() -> None:
    """Write the schema files."""
    SCHEMA_DIR.mkdir(parents=True, exist_ok=True)
    for path, text in schema_files().items():
        path.write_text(text)
        print(path.relative_to(PROJECT_ROOT))


if __name__ == "__main__":
    main()
