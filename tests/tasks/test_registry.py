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


def test_the_catalog_of_bauv_list_is_the_registry():
    from tasks.core import catalog

    assert catalog.load() == catalog.from_registry(), (
        "tasks/core/catalog.json is stale: run python -m tasks.core.catalog"
    )


@pytest.mark.parametrize("family", sorted(registry.FAMILIES))
def test_each_family_is_registered_by_its_own_package_alone(family):
    """get() imports only the name's family package: that package alone must register every
    name of the family (checked in a fresh interpreter, where nothing else is imported)."""
    import subprocess
    import sys

    package = registry.FAMILIES[family]
    code = (
        "import importlib, json; from tasks.core import registry;"
        f"importlib.import_module({package!r});"
        "print(json.dumps(sorted(registry._REGISTRY)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    alone = set(json.loads(out.stdout))
    assert alone == {n for n in NAMES if n.split("/", 1)[0] == family}


def test_a_name_outside_the_families_is_refused():
    with pytest.raises(ValueError, match="family"):
        registry.register(registry.Experiment(name="nofamily/x", summary="x"))
