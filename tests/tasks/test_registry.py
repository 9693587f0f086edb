"""Contract tests over every registered experiment and mission."""

import json

import pytest

from bauv_sim.config import load_config, to_plain
from tasks.core import registry
from tasks.core.schemas import schema_files

NAMES = registry.names()


@pytest.mark.parametrize("name", NAMES)
def test_defaults_validate_and_round_trip(name):
    exp = registry.get(name)
    scn = load_config(exp.scenario_type, exp.preset)
    again = load_config(exp.scenario_type, to_plain(scn))
    assert again == scn
    assert exp.summary and exp.default_runs >= 1


def test_metrics_schemas_are_current():
    for path, text in schema_files().items():
        assert path.is_file(), f"{path} missing: run python -m tasks.core.schemas"
        assert json.loads(path.read_text()) == json.loads(text), f"{path} stale"


def test_every_registering_module_is_imported_by_its_package():
    """Registration is explicit: importing the experiment packages registers everything, so a
    module that its package forgot to import (and that would silently not register) fails here."""
    import importlib
    import pkgutil

    before = set(registry.names())
    for package in registry.EXPERIMENT_PACKAGES:
        pkg = importlib.import_module(package)
        for info in pkgutil.walk_packages(pkg.__path__, f"{package}."):
            importlib.import_module(info.name)
    assert set(registry.names()) == before
