"""The registry of experiments and missions, loaded by name.

Experiments live in experiment packages, one per family of names (the part of a name before
``/``), each declared by its distribution as an entry point (:mod:`tasks.core.families`). A module
builds :class:`Experiment` instances and passes them to :func:`register` at import time, the way
dm_control's suite domains add themselves with ``@SUITE.add``; its package's ``__init__`` imports
it, so importing the package registers all of its experiments. :func:`get` imports only the package
of the name's family (a kinematic run never imports MuJoCo for the missions); :func:`names` and
:func:`all_experiments` import every package. Registration is explicit: a module that its package
does not import is not registered, whatever its file name.

A package whose experiments are costly to import may instead name, for each experiment, the
module that registers it (:func:`register_modules`) and import none of them: importing the package
then declares every name, and :func:`get` imports the one module of the name asked for (``bauv run``
of one mission does not import the others). :mod:`tasks.core.catalog` holds every
name with its summary for ``bauv list`` without importing any experiment (a test keeps it equal
to the registry).

An experiment is split in two pure parts so that the runner can distribute it:

* :meth:`Experiment.run_block` computes a block of Monte Carlo runs (a tuple of run indices) and
  returns its result as plain data (:mod:`tasks.core.store`: numbers, strings, arrays, lists,
  tuples, dicts and registered dataclasses), which the runner keeps on disk. It must depend only on
  ``(scenario, seed, runs)``: each run draws from its own streams (:mod:`bauv_sim.rng`), so a
  block's result does not depend on which worker ran it.
* :meth:`Experiment.report` turns the block results, in block order, into ``metrics.json``, tables,
  figures and the recording of one run.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import BaseModel

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from tasks.core.families import families

if TYPE_CHECKING:
    from tasks.core.report_pool import ReportPool

_REGISTRY: dict[str, Experiment] = {}
_MODULES: dict[str, str] = {}
"""Name -> the module whose import registers it, for names declared by :func:`register_modules`
and not yet registered."""
_LOADED = False


@dataclass(frozen=True)
class ReportContext:
    """What :meth:`Experiment.report` receives.

    Attributes:
        scenario: the validated scenario.
        seed: the batch seed.
        n_runs: number of Monte Carlo runs in the batch.
        out_dir: the run folder to write into.
        blocks: the block results, in block order (an iterator: read once).
        quiet: whether to keep the console quiet (tests).
        pool: the batch's report processes, if any.
    """

    scenario: Config
    seed: int
    n_runs: int
    out_dir: Path
    blocks: Iterator[Any]
    quiet: bool = False
    pool: ReportPool | None = None
    """Processes that take jobs of the report (:func:`tasks.core.report_pool.offload`), or
    ``None``: the report does them itself."""


@dataclass(frozen=True)
class ReportSummary:
    """What :meth:`Experiment.report` returns.

    Attributes:
        text: printed to the console.
        files: the files written, paths relative to the run folder.
        failures: one line per run that failed (``bauv run`` then exits with status 1).
        diverged: one line per estimate that ran away from the truth in a run that completed
            (the experiment's divergence rule; ``bauv run`` then exits with status 1 too).
    """

    text: str
    files: tuple[str, ...] = ()
    failures: tuple[str, ...] = ()
    diverged: tuple[str, ...] = ()


@dataclass(frozen=True)
class ReportWork:
    """What of an experiment's report may be written in other processes
    (:mod:`tasks.core.report_pool`).

    Attributes:
        jobs: how many jobs the report hands out at most (no more processes are started).
        preload: modules a report process imports as it starts, while the blocks are computed
            (the report's libraries and modules).
    """

    jobs: int
    preload: tuple[str, ...] = ()


@dataclass(frozen=True)
class MemoryTerm:
    """One part of a batch's estimated memory, with the fields that drive it.

    Attributes:
        bytes: estimated peak memory of this part, bytes.
        per_block: whether every worker holds it while it computes a block (else it is held once,
            by the process that writes the report).
        fields: the scenario fields (and values) that make it, as the user typed them, e.g.
            ``"passage.duration_s = 1e+12 (1e+12 ticks of passage.tick_s = 1 s)"``.
    """

    bytes: float
    per_block: bool
    fields: str


@dataclass(frozen=True)
class Experiment:
    """Base of every registered experiment or mission.

    Attributes:
        name: registry name, ``family/name`` (e.g. ``my-family/test-1``).
        summary: one line for ``bauv list``.
        preset: nested overrides of the scenario defaults that make this experiment (the same
            scenario type can serve several experiments).
        default_runs: number of runs when the user does not say.
        max_runs: the largest batch allowed, or ``None``.
    """

    scenario_type: ClassVar[type[Config]]
    metrics_type: ClassVar[type[BaseModel] | None] = None
    """The pydantic model of the experiment's ``metrics.json`` (its JSON Schema is kept in
    ``docs/schemas/``)."""

    name: str
    summary: str
    preset: Mapping[str, Any] = field(default_factory=dict)
    default_runs: int = 1
    max_runs: int | None = None

    def block_size(self, scenario: Config) -> int:
        """Runs per block: fixed by the scenario, never by the worker count (so that results are
        identical for any number of workers)."""
        return 1

    def check(self, scenario: Config, n_runs: int) -> None:
        """Checks that involve the batch size (raise :class:`ConfigError`); none by default."""

    def memory(self, scenario: Config, n_runs: int) -> list[MemoryTerm]:
        """The batch's estimated peak memory, in parts, so that the runner can refuse a batch that
        cannot fit before any work starts (:func:`tasks.core.plan.check_memory`). None by
        default (an experiment whose size is bounded by its fields' ranges)."""
        return []

    def run_block(self, scenario: Config, seed: int, runs: tuple[int, ...]) -> Any:
        """Compute the runs of one block; see the module docstring."""
        raise NotImplementedError

    def report(self, ctx: ReportContext) -> ReportSummary:
        """Write the outputs of a finished batch; see the module docstring."""
        raise NotImplementedError

    def report_work(self, scenario: Config) -> ReportWork | None:
        """The jobs of :meth:`report` that other processes may do while this one writes the
        rest (:mod:`tasks.core.report_pool`); none by default."""
        return None


MAX_BLOCK_RUNS = 100_000
"""The largest block any experiment's ``runner.block_size`` accepts."""


def block_by_work(block_size: int | None, steps_per_run: int, steps_per_block: int) -> int:
    """Runs per block sized by work: ``block_size`` when the scenario sets one, else as many runs
    as make ``steps_per_block`` run-steps (at least 1, at most :data:`MAX_BLOCK_RUNS`); a
    function of the scenario only, so the layout never depends on the worker count.

    Args:
        block_size: the scenario's ``runner.block_size``, or None for the default.
        steps_per_run: time steps of one run.
        steps_per_block: the work of a default block, run-steps.
    """
    if block_size is not None:
        return block_size
    return max(1, min(MAX_BLOCK_RUNS, steps_per_block // max(1, steps_per_run)))


def _check_family(name: str) -> None:
    family = name.split("/", 1)[0]
    declared = families()
    if family not in declared:
        raise ValueError(
            f"experiment name {name!r}: family {family!r} is not declared (declared: "
            f"{', '.join(declared)}); a package declares its family as an entry point of group "
            "'bauv_sim.experiments' in its pyproject.toml"
        )


def register(experiment: Experiment) -> Experiment:
    """Add an experiment to the registry.

    Raises:
        ValueError: if the name is taken by another experiment, or its family (the part before
            ``/``) is not declared (:func:`tasks.core.families.families`).
        ConfigError: if ``experiment`` is not an :class:`Experiment` (a ``ValueError`` too).
    """
    if not isinstance(experiment, Experiment):
        raise ConfigError(
            f"experiment = {experiment!r:.60} ({type(experiment).__name__}): must be an "
            "Experiment instance (tasks.core.registry.Experiment or a subclass)"
        )
    _check_family(experiment.name)
    if experiment.name in _REGISTRY and _REGISTRY[experiment.name] is not experiment:
        raise ValueError(f"experiment name {experiment.name!r} is registered twice")
    _REGISTRY[experiment.name] = experiment
    _MODULES.pop(experiment.name, None)
    return experiment


def register_modules(modules: Mapping[str, str]) -> None:
    """Declare experiments by the modules that register them, without importing those modules:
    :func:`get` imports a name's module when the name is first asked for, :func:`names` lists the
    names at once, and :func:`all_experiments` imports every module. For a package whose
    experiments are costly to import, called from its ``__init__`` instead of importing them.

    Args:
        modules: experiment name (``family/name``) -> the dotted path of the module whose import
            registers it (with :func:`register`).

    Raises:
        ValueError: if a name's family is not declared, or a name is declared with another
            module than before.
    """
    for name, module in modules.items():
        _check_family(name)
        if _MODULES.get(name, module) != module:
            raise ValueError(
                f"experiment name {name!r} is declared by two modules: {_MODULES[name]!r} and "
                f"{module!r}"
            )
        if name not in _REGISTRY:
            _MODULES[name] = module


def _import_module_of(name: str) -> None:
    """Import the module that :func:`register_modules` named for ``name``; it must register it."""
    module = _MODULES.get(name)
    if module is None:
        return
    importlib.import_module(module)
    if name not in _REGISTRY:
        raise ValueError(
            f"experiment name {name!r}: module {module!r} was declared to register it "
            "(register_modules) but its import did not"
        )


def experiment_packages() -> tuple[str, ...]:
    """The packages whose import registers every experiment and mission (one per declared
    family, :func:`tasks.core.families.families`)."""
    return tuple(dict.fromkeys(families().values()))


def _load_all() -> None:
    global _LOADED
    if _LOADED:
        return
    for package in experiment_packages():
        importlib.import_module(package)
    _LOADED = True


def names() -> list[str]:
    """All registered names (and those declared by :func:`register_modules`), sorted."""
    _load_all()
    return sorted({*_REGISTRY, *_MODULES})


def get(name: str) -> Experiment:
    """The experiment registered under ``name``.

    Only the package of the name's family is imported (all of them for an unknown name, to list
    the known ones).

    Raises:
        ConfigError: naming the unknown name and listing the known ones, or a ``name`` that is not
            a string.
    """
    if not isinstance(name, str):
        raise ConfigError(
            f"name = {name!r:.60} ({type(name).__name__}): must be an experiment name (a str), "
            "'family/name'; experiment_names() lists them"
        )
    if name not in _REGISTRY:
        package = families().get(name.split("/", 1)[0])
        if package is not None:
            importlib.import_module(package)
        _import_module_of(name)
    if name not in _REGISTRY:
        _load_all()
        _import_module_of(name)
    try:
        return _REGISTRY[name]
    except KeyError:
        known = ", ".join(sorted({*_REGISTRY, *_MODULES})) or "(none)"
        raise ConfigError(f"unknown experiment {name!r}; known: {known}") from None


def all_experiments() -> list[Experiment]:
    """Every registered experiment, sorted by name."""
    return [get(n) for n in names()]
