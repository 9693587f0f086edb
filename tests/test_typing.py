"""The packages' type information: each public package's ``__init__.pyi`` (which type checkers
read, and from which ``lazy_loader.attach_stub`` loads the names at runtime) names exactly the
package's runtime public names, each resolving to the object of the module it names; the renamed
public names stay the functions they name; each top-level package carries ``py.typed``."""

from __future__ import annotations

import ast
import importlib
import inspect
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
STUBBED = ["bauv_sim", "nav", "nav.navigator", "tasks", "tasks.core", "tasks.closed_loop"]


def _stub(package: str) -> Path:
    return ROOT / package.replace(".", "/") / "__init__.pyi"


def _stub_imports(package: str) -> dict[str, tuple[str, str, str | None]]:
    """Public name -> (module, attribute, as-name) of each ``from .module import`` of the stub."""
    names: dict[str, tuple[str, str, str | None]] = {}
    for node in ast.parse(_stub(package).read_text()).body:
        if isinstance(node, ast.ImportFrom):
            assert node.level == 1 and node.module, ast.unparse(node)
            for alias in node.names:
                assert alias.name not in names, f"{alias.name} imported twice"
                names[alias.name] = (f"{package}.{node.module}", alias.name, alias.asname)
    return names


def _stub_annotations(package: str) -> set[str]:
    tree = ast.parse(_stub(package).read_text())
    return {
        n.target.id
        for n in tree.body
        if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
    }


def test_every_package_with_an_init_stub_is_listed():
    found = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for top in ("bauv_sim", "nav", "tasks")
        for p in (ROOT / top).rglob("__init__.pyi")
    }
    assert found == set(STUBBED)


@pytest.mark.parametrize("package", STUBBED)
def test_every_stub_name_resolves_to_the_object_of_its_module(package):
    pkg = importlib.import_module(package)
    for name, (module, attr, asname) in _stub_imports(package).items():
        # `name as name`: a stub re-exports an imported name only so (PEP 484)
        assert asname == name, f"{package}: write `{name} as {name}` in the stub"
        assert getattr(pkg, name) is getattr(importlib.import_module(module), attr), name
    for name in _stub_annotations(package):
        assert getattr(pkg, name) is not None, name


@pytest.mark.parametrize("package", STUBBED)
def test_the_stub_names_exactly_the_runtime_public_names(package):
    """``__all__`` is the stub's names, and every public name the package's ``__init__`` defines
    or imports itself (not loaded through the stub) is in the stub too; names of other
    distributions (``pathlib.Path``) and submodules are not public names."""
    pkg = importlib.import_module(package)
    declared = set(_stub_imports(package)) | (_stub_annotations(package) - {"__version__"})
    assert set(pkg.__all__) == declared
    root = package.split(".")[0]
    own = {
        name
        for name, value in vars(pkg).items()
        if not name.startswith("_")
        and not isinstance(value, types.ModuleType)
        and not (
            (inspect.isclass(value) or inspect.isfunction(value))
            and value.__module__.split(".")[0] != root
        )
    }
    assert own <= declared, own - declared


def test_the_renamed_public_names_are_the_functions_they_name():
    import nav
    import tasks
    from nav.bearings import bank, cmnf, filters
    from nav.trn import degraded
    from tasks.core import registry

    assert nav.bearing_ekf_update is filters.ekf_update
    assert nav.degraded_map is degraded
    assert nav.filter_bank_step is bank.step
    assert nav.train_cmnf is cmnf.train
    assert tasks.get_experiment is registry.get
    assert tasks.experiment_names is registry.names
    assert tasks.get_experiment("mission/short").name == "mission/short"


def test_the_version_is_a_string():
    import bauv_sim

    assert isinstance(bauv_sim.__version__, str) and bauv_sim.__version__


@pytest.mark.parametrize("package", ["bauv_sim", "nav", "tasks"])
def test_each_top_level_package_is_marked_typed(package):
    assert (ROOT / package / "py.typed").is_file()


def test_the_error_configs_declared_for_type_checkers_are_the_runtime_models():
    """:mod:`bauv_sim.sensors.errors` builds its three error models with ``create_model`` and
    spells them out for type checkers under ``TYPE_CHECKING``: the same fields, defaults and
    types (``_Sector`` is the sector bias's four-tuple)."""
    from bauv_sim.sensors import errors

    tree = ast.parse((ROOT / "bauv_sim/sensors/errors.py").read_text())
    block = next(
        n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING"
    )
    declared = {n.name: n for n in block.body if isinstance(n, ast.ClassDef)}
    assert set(declared) == {"AngleErrorConfig", "LengthErrorConfig", "SpeedErrorConfig"}
    base = set(errors._ErrorConfigBase.model_fields)
    for name, cls in declared.items():
        fields = {
            n.target.id: (
                ast.unparse(n.annotation).replace("_Sector", "tuple[float, float, float, float]"),
                ast.literal_eval(n.value),
            )
            for n in cls.body
            if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
        }
        runtime = getattr(errors, name).model_fields
        assert set(fields) == set(runtime) - base, name
        for field, (annotation, default) in fields.items():
            assert default == runtime[field].default, (name, field)
            assert annotation == str(runtime[field].annotation).replace(
                "<class 'float'>", "float"
            ), (name, field)
