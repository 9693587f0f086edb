"""Planning a batch: everything about it validated before anything is written.

:func:`plan_batch` resolves an experiment's scenario (its preset, TOML files, ``--set``
overrides) and checks the batch against the limits here: runs (:data:`MAX_RUNS`), blocks
(:data:`MAX_BLOCKS`), the memory it is estimated to need (:func:`check_memory`, from
:meth:`Experiment.memory`) and the largest block file it may write or read
(:func:`block_file_limit`). The result is a :class:`BatchPlan`: the experiment, the validated
scenario, the seed, the runs and their block layout (fixed by the scenario, never by the worker
count) and the sha256 of the scenario as written to ``scenario.toml``.
:func:`check_run_arguments` checks the types of :func:`tasks.core.runner.run`'s arguments.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import tomli_w

from bauv_sim.config import Config, load_config, to_plain
from bauv_sim.errors import ConfigError
from bauv_sim.rng import check_seed
from tasks.core import registry
from tasks.core.registry import Experiment, MemoryTerm


@dataclass(frozen=True)
class BatchPlan:
    """A validated batch, before anything is written.

    Attributes:
        experiment: the registered experiment.
        scenario: the validated scenario.
        seed: the batch seed.
        n_runs: the number of runs.
        blocks: the run indices of each block, in order.
        scenario_sha256: sha256 (hex) of the scenario as written to ``scenario.toml``.
    """

    experiment: Experiment
    scenario: Config
    seed: int
    n_runs: int
    blocks: tuple[tuple[int, ...], ...]
    scenario_sha256: str
    block_file_limit_b: int = field(init=False, repr=False, compare=False)
    """The largest block file this batch can write or read, bytes (:func:`block_file_limit`)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "block_file_limit_b", block_file_limit(self))


def plan_batch(
    name: str,
    n_runs: int | None = None,
    seed: int = 0,
    overrides: Sequence[str] = (),
    scenario_files: Sequence[str | Path] = (),
) -> BatchPlan:
    """Validate everything about a batch before any file is written.

    Args:
        name: registered experiment name.
        n_runs: number of Monte Carlo runs (``None``: the experiment's default).
        seed: batch seed.
        overrides: ``dotted.key=value`` scenario overrides.
        scenario_files: TOML files merged over the experiment's preset before the overrides.

    Returns:
        The plan.

    Raises:
        ConfigError: on any invalid input, naming it.
    """
    exp = registry.get(name)
    seed = check_seed(seed)
    n = exp.default_runs if n_runs is None else n_runs
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ConfigError(f"runs = {n!r}: must be an integer >= 1")
    if exp.max_runs is not None and n > exp.max_runs:
        raise ConfigError(f"runs = {n}: {name} allows at most {exp.max_runs}")
    if n > MAX_RUNS:
        raise ConfigError(
            f"runs = {n}: at most {MAX_RUNS} runs in one batch (its layout and per-run results "
            "are held in memory); run several batches with different seeds"
        )
    scenario = load_config(exp.scenario_type, exp.preset, scenario_files, overrides)
    exp.check(scenario, n)
    check_layout(n, exp.block_size(scenario))
    check_memory(exp, scenario, n)
    digest = sha256(scenario_text(scenario).encode("utf-8"))
    return BatchPlan(exp, scenario, seed, n, block_layout(n, exp.block_size(scenario)), digest)


MAX_RUNS = 10_000_000
"""The largest batch: its block layout (~36 bytes per run) and per-run results stay in memory."""
MAX_BLOCKS = 1_000_000
"""The most blocks in a batch (each is two files in ``blocks/``)."""
MEMORY_FRACTION = 0.5
"""Share of the machine's physical memory a batch may be estimated to use."""


BLOCK_FILE_BASE_B = 64 * 2**20
"""What any block file may hold besides its runs (manifest, per-tick sums, histograms), bytes."""
BLOCK_FILE_PER_RUN_B = 2**20
"""What a block file may hold per run, bytes: 9x the most measured per run of the experiments
that do not estimate their memory, at their defaults (110 kB: the autopilot step responses on the
vehicle; 51 kB: seed 001's replica; 22 kB: seed 003's test 1)."""
BLOCK_FILE_MEMORY_FACTOR = 8
"""Multiple of a block's estimated memory (the per-block terms of :meth:`Experiment.memory`) a
block file may hold: the estimate of a mission counts one vehicle (500 B per control tick), and
seed 003's swarm mission with 4 followers writes 2.4 kB per tick (4.8x)."""


def block_file_limit(plan: BatchPlan) -> int:
    """The largest block file a batch can have written, bytes: what its largest block may
    legitimately hold, from the plan alone (runs per block, the scenario's memory estimate).

    ``BLOCK_FILE_BASE_B + BLOCK_FILE_PER_RUN_B * runs per block + BLOCK_FILE_MEMORY_FACTOR *
    (the per-block terms of Experiment.memory)``. A block file above it is refused before a
    byte of it is read (a corrupt or planted file is not read whole into memory).

    Args:
        plan: the batch.
    """
    terms = plan.experiment.memory(plan.scenario, plan.n_runs)
    per_block = sum(t.bytes for t in terms if t.per_block)
    runs = max(len(b) for b in plan.blocks)
    return int(
        BLOCK_FILE_BASE_B + BLOCK_FILE_PER_RUN_B * runs + BLOCK_FILE_MEMORY_FACTOR * per_block
    )


def memory_limit_bytes() -> float:
    """The memory a batch may use: :data:`MEMORY_FRACTION` of the machine's physical memory,
    bytes (8 GiB when the platform does not say)."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        total = 16 * 2**30
    return MEMORY_FRACTION * total


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_layout(n_runs: int, block_size: int) -> None:
    """Refuse a layout with more than :data:`MAX_BLOCKS` blocks.

    Raises:
        ConfigError: naming the runs, the block size and the limit.
    """
    n_blocks = -(-n_runs // block_size)
    if n_blocks > MAX_BLOCKS:
        raise ConfigError(
            f"runs = {n_runs} in blocks of {block_size} make {n_blocks} blocks: at most "
            f"{MAX_BLOCKS} (each block is two files); raise runner.block_size"
        )


def memory_bytes(terms: Sequence[MemoryTerm], workers: int, report_copies: int = 1) -> float:
    """A batch's estimated peak memory from the parts of :meth:`Experiment.memory`, bytes: each
    part held per block by every one of ``workers`` processes, or else (what the report holds)
    by ``report_copies`` processes (``bauv`` and its report processes,
    :mod:`tasks.core.report_pool`)."""
    return sum(t.bytes * (workers if t.per_block else report_copies) for t in terms)


def check_memory(exp: Experiment, scenario: Config, n_runs: int, workers: int = 1) -> None:
    """Refuse a batch whose estimated memory (:meth:`Experiment.memory`) exceeds
    :func:`memory_limit_bytes`, before anything is computed or written.

    Args:
        exp: the experiment.
        scenario: its validated scenario.
        n_runs: the number of runs.
        workers: processes that hold a block at the same time on this machine.

    Raises:
        ConfigError: naming the field (and value) of the largest part, the estimate and the
            limit.
    """
    terms = exp.memory(scenario, n_runs)
    if not terms:
        return
    total = memory_bytes(terms, workers)
    limit = memory_limit_bytes()
    if total > limit:
        worst = max(terms, key=lambda t: memory_bytes([t], workers))
        raise ConfigError(
            f"{worst.fields}: the batch would need about {_gb(total)} of memory, above the limit "
            f"of {_gb(limit)} ({MEMORY_FRACTION:.0%} of this machine's memory)"
        )


def scenario_text(scenario: Config) -> str:
    """The resolved scenario as TOML, as written to ``scenario.toml``."""
    return tomli_w.dumps(to_plain(scenario))


def sha256(data: bytes) -> str:
    """sha256 of ``data``, hex."""
    return hashlib.sha256(data).hexdigest()


def block_layout(n_runs: int, size: int) -> tuple[tuple[int, ...], ...]:
    """The run indices of each block, in order: blocks of ``size`` runs, the last one shorter."""
    return tuple(tuple(range(i, min(i + size, n_runs))) for i in range(0, n_runs, size))


def default_out_dir(name: str, seed: int) -> Path:
    """``runs/<name with / as _>/<UTC timestamp>-seed<seed>``."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%S%f")
    return Path("runs") / name.replace("/", "_") / f"{stamp}-seed{seed}"


def check_run_arguments(
    name: Any,
    n_runs: Any,
    seed: Any,
    out_dir: Any,
    overrides: Any,
    scenario_files: Any,
    address: Any,
    resume: Any,
    progress: Any,
) -> tuple[tuple[str, ...], tuple[str | Path, ...]]:
    """The types of :func:`run`'s arguments, checked before anything starts (the executor
    options are :func:`check_executor`'s): a ``None`` or a wrong type is a :class:`ConfigError`
    naming the argument, its type and what is allowed, never an ``AttributeError`` from deep
    inside; a single string given for ``overrides`` or ``scenario_files`` (which take lists) is
    refused, not read one character at a time.

    Returns:
        ``(overrides, scenario_files)`` as tuples.

    Raises:
        ConfigError: on the first argument of the wrong type.
    """
    import numbers

    from bauv_sim.config import check_files, check_overrides

    def refuse(arg: str, value: Any, allowed: str) -> None:
        raise ConfigError(f"{arg} = {value!r:.60} ({type(value).__name__}): must be {allowed}")

    if not isinstance(name, str):
        refuse("name", name, "an experiment name (a str), 'family/name'")
    for arg, value in (("n_runs", n_runs), ("seed", seed)):
        if value is not None and (
            isinstance(value, bool) or not isinstance(value, numbers.Integral)
        ):
            refuse(arg, value, "an integer or None (the default)")
    if out_dir is not None and not isinstance(out_dir, str | os.PathLike):
        refuse("out_dir", out_dir, "a folder path (str or Path) or None (the default folder)")
    if address is not None and not isinstance(address, str):
        refuse("address", address, "a Dask scheduler address (a str) or None")
    for arg, value in (("resume", resume), ("progress", progress)):
        if not isinstance(value, bool):
            refuse(arg, value, "True or False")
    return check_overrides(overrides, "overrides"), check_files(scenario_files, "scenario_files")
