"""Contract tests over every registered experiment and mission."""

import json

import pytest

from bauv_sim.config import load_config, to_plain
from tasks.core import families, registry
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
    for package in registry.experiment_packages():
        pkg = importlib.import_module(package)
        for info in pkgutil.walk_packages(pkg.__path__, f"{package}."):
            importlib.import_module(info.name)
    assert set(registry.names()) == before


def test_the_catalog_of_bauv_list_is_the_registry():
    from tasks.core import catalog

    assert catalog.load() == catalog.from_registry(), (
        "tasks/catalog.json is stale: run python -m tasks.core.catalog"
    )


@pytest.mark.slow
@pytest.mark.parametrize("family", sorted(families.families()))
def test_each_family_is_registered_by_its_own_package_alone(family):
    """get() imports only the name's family package: that package alone must register every
    name of the family (checked in a fresh interpreter, where nothing else is imported)."""
    import subprocess
    import sys

    package = families.families()[family]
    code = (
        "import importlib, json; from tasks.core import registry;"
        f"importlib.import_module({package!r});"
        "print(json.dumps(sorted({*registry._REGISTRY, *registry._MODULES})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    alone = set(json.loads(out.stdout))
    assert alone == {n for n in NAMES if n.split("/", 1)[0] == family}


@pytest.mark.slow
def test_getting_a_mission_imports_its_module_alone():
    """The missions' package names each mission's module (register_modules) instead of importing
    them all: get() of one mission imports that module and no other mission's (checked in a fresh
    interpreter); every mission is still listed and found."""
    import subprocess
    import sys

    code = (
        "import json, sys; from tasks.core import registry;"
        "e = registry.get('mission/short');"
        "print(json.dumps([e.name, sorted(m for m in sys.modules "
        "if m.startswith('tasks.missions.'))]))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    name, loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert name == "mission/short"
    assert loaded == ["tasks.missions.short"]
    missions = [n for n in NAMES if n.startswith("mission/")]
    assert len(missions) == 7 and all(registry.get(n).name == n for n in missions)


def test_a_declared_module_must_register_its_name(monkeypatch, tmp_path):
    """A name declared with register_modules whose module does not register it is an error
    naming both, not an unknown name."""
    import sys

    (tmp_path / "user_module_r29.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        registry.register_modules({"mission/not-registered-r29": "user_module_r29"})
        assert "mission/not-registered-r29" in registry.names()
        with pytest.raises(ValueError, match=r"user_module_r29.*did not"):
            registry.get("mission/not-registered-r29")
        with pytest.raises(ValueError, match="two modules"):
            registry.register_modules({"mission/not-registered-r29": "another_module_r29"})
        with pytest.raises(ValueError, match="not declared"):
            registry.register_modules({"no-such-family-r29/x": "user_module_r29"})
    finally:
        registry._MODULES.pop("mission/not-registered-r29", None)
        sys.modules.pop("user_module_r29", None)


def test_a_name_outside_the_families_is_refused():
    with pytest.raises(ValueError, match="family"):
        registry.register(registry.Experiment(name="nofamily/x", summary="x"))


def test_the_families_are_the_entry_points_of_pyproject():
    """The installed metadata declares this project's families as its pyproject.toml does (a stale
    install, or an entry point lost from pyproject.toml, fails here), and every family has names."""
    import tomllib
    from pathlib import Path

    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    declared = tomllib.loads(pyproject.read_text())["project"]["entry-points"][families.GROUP]
    assert families.families() == declared
    assert {n.split("/", 1)[0] for n in NAMES} == set(declared)


class _EntryPoint:
    def __init__(self, name, value):
        self.name, self.value = name, value


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([], "no experiment package is declared"),
        ([("Paper 9", "pkg.a")], "the family must be lower-case"),
        ([("x", "pkg.a:attr")], "must name a package"),
        ([("x", "pkg.a"), ("x", "pkg.b")], "already declared by package 'pkg.a'"),
    ],
)
def test_a_bad_declaration_is_refused_naming_it(monkeypatch, points, message):
    import importlib.metadata

    def entry_points(group):
        assert group == families.GROUP
        return [_EntryPoint(n, v) for n, v in points]

    monkeypatch.setattr(importlib.metadata, "entry_points", entry_points)
    families.families.cache_clear()
    try:
        with pytest.raises(families.FamilyError, match=message):
            families.families()
    finally:
        families.families.cache_clear()


def test_another_distributions_family_is_loaded_on_demand(monkeypatch, tmp_path):
    """A family declared by another package (as a user's distribution would) is imported by get()
    and its experiment registered, with no change to the framework."""
    import importlib.metadata
    import sys

    pkg = tmp_path / "user_experiments_r22"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        "from tasks.core.registry import Experiment, register\n"
        "register(Experiment(name='user-family/demo', summary='a user experiment'))\n"
    )
    real = importlib.metadata.entry_points

    def entry_points(group):
        return [*real(group=group), _EntryPoint("user-family", "user_experiments_r22")]

    monkeypatch.setattr(importlib.metadata, "entry_points", entry_points)
    monkeypatch.syspath_prepend(str(tmp_path))
    families.families.cache_clear()
    try:
        assert families.package_of("user-family/demo") == "user_experiments_r22"
        assert registry.get("user-family/demo").summary == "a user experiment"
    finally:
        families.families.cache_clear()
        registry._REGISTRY.pop("user-family/demo", None)
        sys.modules.pop("user_experiments_r22", None)


def test_the_framework_names_no_experiment():
    """tasks/core names no family, no experiment package and no experiment (code, docstrings and
    data alike): an experiment is added in its own package."""
    from pathlib import Path

    core = Path(registry.__file__).parent
    words = set(families.families()) | set(families.families().values()) | set(NAMES)
    for path in sorted(core.iterdir()):
        if path.suffix not in (".py", ".json", ".toml", ".md"):
            continue
        text = path.read_text(encoding="utf-8")
        for word in sorted(words):
            if "/" in word or "." in word:
                found = word in text
            else:  # a family: as a name's prefix or a quoted word
                found = f"{word}/" in text or f'"{word}"' in text or f"'{word}'" in text
                if (path.name, word) == ("export.py", "vehicle"):  # the run data's key column
                    found = f"{word}/" in text or text.count(f'"{word}"') != 1
            assert not found, f"{path.name} names {word!r}"
