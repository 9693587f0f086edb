"""The Monte Carlo runner: blocks of runs on an :class:`~concurrent.futures.Executor`, on disk.

A batch is split into blocks of a size fixed by the scenario (:meth:`Experiment.block_size`). Each
block is computed by :meth:`Experiment.run_block` in a worker, encoded there as plain data
(:mod:`tasks.core.store`, a format that cannot execute code when read) and written to
``<out>/blocks/block-NNNNNN.zip`` as soon as it finishes, then its sha256 to
``block-NNNNNN.sha256`` (``sha256sum -c`` reads it); both are written atomically, and a block
counts as saved only when both files are there. :meth:`Experiment.report` reads them back **in
block order** and writes the outputs: after the last block on one local worker, and in a thread
of this process on worker processes (local or Dask), where it reads each block as soon as it and
the blocks before it are saved, so its merge overlaps the later blocks. Because a run's numbers
depend only on ``(scenario, seed, run index)``, blocks are reduced in a fixed order and the
encoding keeps every bit, the outputs are bit-identical whatever the executor and worker count,
and a batch interrupted and resumed with ``--resume`` equals one run straight through.

Executors: ``local`` (in-process for one worker, else a :class:`ProcessPoolExecutor` whose workers
are forked from ``bauv`` itself, which has imported the experiment, before it starts any thread,
or from a fork server with the experiment preloaded where that is not safe, or spawned where
there is neither; :mod:`tasks.core.workers`) and ``dask`` (``distributed.Client(address)``, or a
local cluster with ``workers`` single-threaded processes when no address is given).

The run folder holds ``run.json`` (``state`` is ``incomplete`` until the report is written, then
``complete``; ``record_sha256`` is the sha256 of its other fields), ``scenario.toml`` (the
resolved scenario: ``bauv run NAME --scenario FILE`` repeats it), ``blocks/`` and the report's
files. Every file is written through :mod:`tasks.core.files` with the run folder
:func:`~tasks.core.files.confined`: atomically, and never through a symbolic link inside it.

What ``--resume`` checks before it writes anything (any failure is a :class:`ConfigError`): the
folder holds no symbolic link (a link to a file or folder outside would have the batch read or
write there); ``run.json`` is whole, at most :data:`MAX_RECORD_BYTES`, every field is there with
its type (format version, experiment, seed, runs, block size, number of blocks, the sha256 of
``scenario.toml``, the store version, state) and its ``record_sha256`` is theirs (an edited run
count or seed is refused); the request agrees with it (experiment, seed, runs; no new scenario);
``scenario.toml`` still has its recorded sha256 and gives the recorded block layout; and every
saved block is at most the size such a block can hold (:func:`block_file_limit`, checked before a
byte is read), its bytes have their recorded sha256 (read in chunks), decode, and carry a header
(format version, experiment, seed, block index, run indices, scenario sha256) that agrees with the
batch. No file of a run folder is ever unpickled.
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
import contextlib
import datetime as _dt
import hashlib
import json
import os
import re
import threading
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import tomli_w

from bauv_sim.config import Config, load_config, loads_toml, to_plain, validate
from bauv_sim.errors import ConfigError
from bauv_sim.rng import check_seed
from tasks.core import files, registry, store
from tasks.core import workers as workers_mod
from tasks.core.errors import BatchFailed, BatchInterrupted, OutputError
from tasks.core.files import atomic_write_bytes, os_error_text
from tasks.core.registry import Experiment, ReportContext, ReportSummary

RUN_FILE = "run.json"
SCENARIO_FILE = "scenario.toml"
BLOCK_DIR = "blocks"
BLOCK_SUFFIX = ".zip"
DIGEST_SUFFIX = ".sha256"
FORMAT_VERSION = 3
"""Version of the run folder's layout. 1 kept pickled blocks (never read: a crafted pickle runs
code when loaded); 2 keeps plain-data blocks with a sha256 file each and the scenario's sha256;
3 adds ``record_sha256`` to ``run.json`` (the sha256 of its other fields)."""
STATES = ("incomplete", "complete")
_HEX64 = re.compile(r"[0-9a-f]{64}")


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
    digest = _sha256(scenario_text(scenario).encode("utf-8"))
    return BatchPlan(exp, scenario, seed, n, _blocks(n, exp.block_size(scenario)), digest)


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
MAX_RECORD_BYTES = 2**16
"""The largest ``run.json`` read (it is about 400 bytes)."""
MAX_SCENARIO_BYTES = 2**24
"""The largest ``scenario.toml`` read (a few kB; way-point and beacon lists make it longer)."""


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
    total = sum(t.bytes * (workers if t.per_block else 1) for t in terms)
    limit = memory_limit_bytes()
    if total > limit:
        worst = max(terms, key=lambda t: t.bytes * (workers if t.per_block else 1))
        raise ConfigError(
            f"{worst.fields}: the batch would need about {_gb(total)} of memory, above the limit "
            f"of {_gb(limit)} ({MEMORY_FRACTION:.0%} of this machine's memory)"
        )


def scenario_text(scenario: Config) -> str:
    """The resolved scenario as TOML, as written to ``scenario.toml``."""
    return tomli_w.dumps(to_plain(scenario))


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _blocks(n_runs: int, size: int) -> tuple[tuple[int, ...], ...]:
    return tuple(tuple(range(i, min(i + size, n_runs))) for i in range(0, n_runs, size))


def default_out_dir(name: str, seed: int) -> Path:
    """``runs/<name with / as _>/<UTC timestamp>-seed<seed>``."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%S%f")
    return Path("runs") / name.replace("/", "_") / f"{stamp}-seed{seed}"


def atomic_write_text(path: Path, text: str) -> None:
    """Write a text file so that it either exists whole or not at all."""
    atomic_write_bytes(path, text.encode("utf-8"))


def _block_path(out_dir: Path, index: int) -> Path:
    return out_dir / BLOCK_DIR / f"block-{index:06d}{BLOCK_SUFFIX}"


def _digest_path(out_dir: Path, index: int) -> Path:
    return out_dir / BLOCK_DIR / f"block-{index:06d}{DIGEST_SUFFIX}"


def _saved(out_dir: Path, index: int) -> bool:
    """Whether block ``index`` is saved: its file and its sha256 file are both there."""
    return _block_path(out_dir, index).is_file() and _digest_path(out_dir, index).is_file()


def _save_block(out_dir: Path, index: int, payload: bytes) -> None:
    """Write a block's bytes, then its sha256 (a crash in between leaves it unsaved)."""
    path = _block_path(out_dir, index)
    files.remove(_digest_path(out_dir, index))
    atomic_write_bytes(path, payload)
    atomic_write_text(_digest_path(out_dir, index), f"{_sha256(payload)}  {path.name}\n")


def _block_header(plan: BatchPlan, index: int) -> dict[str, Any]:
    """What a block's file must say about itself."""
    return {
        "format_version": FORMAT_VERSION,
        "experiment": plan.experiment.name,
        "seed": plan.seed,
        "block": index,
        "runs": list(plan.blocks[index]),
        "scenario_sha256": plan.scenario_sha256,
    }


def _same(a: Any, b: Any) -> bool:
    """Equal and of the same types (``True`` is not ``1``)."""
    if type(a) is not type(b):
        return False
    if type(a) is list:
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


HASH_CHUNK_B = 2**20
"""Bytes read at a time to hash a block file."""


def _file_sha256(fh: Any) -> str:
    """sha256 (hex) of an open binary file, read in chunks of :data:`HASH_CHUNK_B` (memory stays
    at one chunk whatever the file's size)."""
    h = hashlib.sha256()
    buf = bytearray(HASH_CHUNK_B)
    view = memoryview(buf)
    while n := fh.readinto(buf):
        h.update(view[:n])
    return h.hexdigest()


def _read_small(path: Path, limit: int) -> bytes:
    """A small file's bytes, at most ``limit`` (one more is read to tell a longer file), without
    following a link.

    Raises:
        OSError: if it cannot be read.
        ConfigError: if it is longer than ``limit``.
    """
    with files.open_for_reading(path) as fh:
        size = os.fstat(fh.fileno()).st_size
        # read() allocates what it is asked for: ask for the file's size, not the limit
        data = b"" if size > limit else fh.read(size + 1)
    if size > limit or len(data) > limit:
        raise ConfigError(f"{str(path)!r}: longer than {limit} bytes; not a file of a run folder")
    return data


def load_block(plan: BatchPlan, out_dir: Path, index: int) -> Any:
    """Read back a saved block, checking its size, its sha256, its encoding and its header.

    The size is checked against :attr:`BatchPlan.block_file_limit_b` before anything is read,
    and the sha256 is computed reading the file in chunks; only a block that passes both is
    decoded (from the same open file).

    Args:
        plan: the batch.
        out_dir: its folder.
        index: the block index.

    Returns:
        The block's result as :meth:`Experiment.run_block` returned it.

    Raises:
        ConfigError: naming the file and what is wrong.
    """
    path, dpath = _block_path(out_dir, index), _digest_path(out_dir, index)
    line_limit = 64 + 2 + len(path.name) + 1
    try:
        recorded = _read_small(dpath, line_limit)
        fh = files.open_for_reading(path)
    except OSError as exc:
        raise ConfigError(f"{exc.filename!r}: cannot read it ({exc.strerror})") from None
    with fh:
        match = re.fullmatch(
            rb"([0-9a-f]{64})  " + re.escape(path.name.encode()) + rb"\n", recorded
        )
        if match is None:
            raise ConfigError(f"{str(dpath)!r}: not a line '<sha256>  {path.name}'")
        size = os.fstat(fh.fileno()).st_size
        if size > plan.block_file_limit_b:
            raise ConfigError(
                f"{str(path)!r}: {size} bytes, more than a block of this batch can hold "
                f"({plan.block_file_limit_b} bytes for {len(plan.blocks[index])} runs); the block "
                "was changed or damaged (delete both files to compute it again)"
            )
        try:
            actual = _file_sha256(fh)
            fh.seek(0)
        except OSError as exc:
            raise ConfigError(f"{str(path)!r}: cannot read it ({os_error_text(exc)})") from None
        expected_digest = match.group(1).decode("ascii")
        if actual != expected_digest:
            raise ConfigError(
                f"{str(path)!r}: its sha256 is {actual[:16]}... but {dpath.name} records "
                f"{expected_digest[:16]}...: the block was changed or damaged (delete both files "
                "to compute it again)"
            )
        try:
            stored = store.load_file(fh, repr(str(path)))
        except store.StoreError as exc:
            raise ConfigError(str(exc)) from None
    expected = _block_header(plan, index)
    if set(stored.header) != set(expected):
        raise ConfigError(
            f"{str(path)!r}: header has fields {sorted(stored.header)}, expected {sorted(expected)}"
        )
    for key, want in expected.items():
        if not _same(stored.header[key], want):
            raise ConfigError(
                f"{str(path)!r}: header says {key} = {stored.header[key]!r} but this batch has "
                f"{want!r}"
            )
    return stored.value


def _run_record(plan: BatchPlan, state: str) -> dict[str, Any]:
    return {
        "format_version": FORMAT_VERSION,
        "experiment": plan.experiment.name,
        "seed": plan.seed,
        "n_runs": plan.n_runs,
        "block_size": len(plan.blocks[0]),
        "n_blocks": len(plan.blocks),
        "scenario_sha256": plan.scenario_sha256,
        "store_version": store.VERSION,
        "state": state,
    }


RECORD_DIGEST = "record_sha256"
"""The field of ``run.json`` that holds the sha256 of its other fields (:func:`record_digest`)."""


def record_digest(record: dict[str, Any]) -> str:
    """sha256 (hex) of ``run.json``'s fields other than :data:`RECORD_DIGEST`: of their JSON with
    sorted keys, no spaces and ASCII escapes (so re-indenting the file does not change it, any
    edit of a value does)."""
    fields = {k: v for k, v in record.items() if k != RECORD_DIGEST}
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return _sha256(text.encode("ascii"))


def _write_run_record(out_dir: Path, plan: BatchPlan, state: str) -> None:
    record = _run_record(plan, state)
    record[RECORD_DIGEST] = record_digest(record)
    atomic_write_text(out_dir / RUN_FILE, json.dumps(record, indent=2) + "\n")


def prepare_out_dir(plan: BatchPlan, out_dir: Path) -> None:
    """Create a fresh run folder with ``run.json`` (incomplete) and ``scenario.toml``.

    Raises:
        ConfigError: if the folder exists and is not empty, is not a folder, or cannot be created
            or written (read-only or full file system, a file in its path, a name too long); a
            folder created here is removed again then.
    """
    text = scenario_text(plan.scenario)
    if _sha256(text.encode("utf-8")) != plan.scenario_sha256:
        raise ValueError("plan.scenario_sha256 is not the digest of plan.scenario")
    where = f"out = {str(out_dir)!r}"
    created: list[Path] = []
    try:
        if out_dir.exists() or out_dir.is_symlink():
            if not out_dir.is_dir():
                raise ConfigError(f"{where}: exists and is not a folder; choose another --out")
            if any(out_dir.iterdir()):
                raise ConfigError(
                    f"{where}: folder exists and is not empty; "
                    "use --resume to complete it or choose another --out"
                )
        created = [p for p in (out_dir, *out_dir.parents) if not p.exists()]
        out_dir.mkdir(parents=True, exist_ok=True)
        with files.confined(out_dir):
            atomic_write_text(out_dir / SCENARIO_FILE, text)
            _write_run_record(out_dir, plan, "incomplete")
    except OSError as exc:
        with files.confined(out_dir):
            for path in (out_dir / SCENARIO_FILE, out_dir / RUN_FILE):
                with contextlib.suppress(OSError):
                    files.remove(path)
        for folder in created:  # deepest first
            with contextlib.suppress(OSError):
                folder.rmdir()
        reason = exc.strerror if exc.filename == str(out_dir) else os_error_text(exc)
        raise ConfigError(f"{where}: cannot create the run folder ({reason})") from None


def _read_record(out_dir: Path) -> dict[str, Any]:
    path = out_dir / RUN_FILE
    if not path.is_file():
        raise ConfigError(f"out = {str(out_dir)!r}: no {RUN_FILE}; nothing to resume")
    try:
        record = json.loads(_read_small(path, MAX_RECORD_BYTES).decode("utf-8"))
    except ConfigError as exc:
        raise ConfigError(f"--resume: {exc}") from None
    except (OSError, ValueError, RecursionError) as exc:
        what = " ".join(str(exc).split())
        raise ConfigError(f"--resume: {str(path)!r} is not valid JSON ({what})") from None
    if type(record) is not dict:
        raise ConfigError(f"--resume: {str(path)!r} is not a JSON object")
    return record


def _record_field(record: dict[str, Any], out_dir: Path, key: str, kind: type) -> Any:
    where = str(out_dir / RUN_FILE)
    if key not in record:
        raise ConfigError(f"--resume: {where!r}: field {key!r} is missing")
    value = record[key]
    if type(value) is not kind:
        must = "an integer" if kind is int else "a string"
        raise ConfigError(f"--resume: {where!r}: {key} = {value!r}: must be {must}")
    return value


def plan_resume(
    out_dir: Path,
    name: str,
    n_runs: int | None,
    seed: int | None,
    overrides: Sequence[str],
    scenario_files: Sequence[str | Path],
) -> BatchPlan:
    """Rebuild the plan of an interrupted batch from its folder, checking the folder first.

    Nothing is written. See the module docstring for the checks.

    Raises:
        ConfigError: if the folder is not a batch of ``name``, holds a symbolic link, the request
            contradicts it, or a file of it was changed, damaged or does not belong to it.
    """
    try:
        link = files.find_link(out_dir) if out_dir.is_dir() else None
    except OSError as exc:
        raise ConfigError(
            f"--resume: cannot read {str(out_dir)!r} ({os_error_text(exc)})"
        ) from None
    if link is not None:
        raise ConfigError(
            f"--resume: {str(link)!r} is a symbolic link: a run folder holds its own files only "
            "(bauv would read or write where it points); remove it, or copy what it points to "
            "in its place"
        )
    record = _read_record(out_dir)
    where = str(out_dir / RUN_FILE)
    version = _record_field(record, out_dir, "format_version", int)
    if version != FORMAT_VERSION:
        raise ConfigError(
            f"--resume: {where!r}: format_version = {version}: this bauv-sim resumes format "
            f"{FORMAT_VERSION} only (format 1 kept pickled blocks, which are never read; format "
            "2 has no sha256 of run.json's fields); start the batch again"
        )
    recorded_digest = _record_field(record, out_dir, RECORD_DIGEST, str)
    if recorded_digest != record_digest(record):
        raise ConfigError(
            f"--resume: {where!r} was changed since the batch started (the sha256 of its fields "
            f"is {record_digest(record)[:16]}..., its {RECORD_DIGEST} records "
            f"{recorded_digest[:16]}...); restore it or start a new batch"
        )
    experiment = _record_field(record, out_dir, "experiment", str)
    if experiment != name:
        raise ConfigError(f"--resume: {str(out_dir)!r} holds {experiment!r}, not {name!r}")
    rec_seed = _record_field(record, out_dir, "seed", int)
    rec_runs = _record_field(record, out_dir, "n_runs", int)
    block_size = _record_field(record, out_dir, "block_size", int)
    n_blocks = _record_field(record, out_dir, "n_blocks", int)
    digest = _record_field(record, out_dir, "scenario_sha256", str)
    store_version = _record_field(record, out_dir, "store_version", int)
    state = _record_field(record, out_dir, "state", str)
    try:
        check_seed(rec_seed)
    except ConfigError as exc:
        raise ConfigError(f"--resume: {where!r}: {exc}") from None
    if rec_runs < 1 or block_size < 1:
        raise ConfigError(
            f"--resume: {where!r}: n_runs = {rec_runs}, block_size = {block_size}: must be >= 1"
        )
    if rec_runs > MAX_RUNS:
        raise ConfigError(f"--resume: {where!r}: n_runs = {rec_runs}: at most {MAX_RUNS}")
    try:
        check_layout(rec_runs, block_size)
    except ConfigError as exc:
        raise ConfigError(f"--resume: {where!r}: {exc}") from None
    layout = _blocks(rec_runs, block_size)
    if n_blocks != len(layout):
        raise ConfigError(
            f"--resume: {where!r}: n_blocks = {n_blocks} but {rec_runs} runs in blocks of "
            f"{block_size} make {len(layout)}"
        )
    if not _HEX64.fullmatch(digest):
        raise ConfigError(f"--resume: {where!r}: scenario_sha256 = {digest!r}: not a sha256")
    if store_version != store.VERSION:
        raise ConfigError(
            f"--resume: {where!r}: store_version = {store_version}: this bauv-sim reads "
            f"version {store.VERSION}"
        )
    if state not in STATES:
        raise ConfigError(f"--resume: {where!r}: state = {state!r}: must be one of {STATES}")
    if overrides or scenario_files:
        raise ConfigError(
            "--resume: the scenario of a started batch cannot change (drop --set/--scenario)"
        )
    if seed is not None and seed != rec_seed:
        raise ConfigError(f"--resume: seed = {seed} but the batch was started with {rec_seed}")
    if n_runs is not None and n_runs != rec_runs:
        raise ConfigError(f"--resume: runs = {n_runs} but the batch was started with {rec_runs}")
    exp = registry.get(name)
    scn_path = out_dir / SCENARIO_FILE
    try:
        scn_bytes = _read_small(scn_path, MAX_SCENARIO_BYTES)
    except ConfigError as exc:
        raise ConfigError(f"--resume: {exc}") from None
    except OSError as exc:
        raise ConfigError(f"--resume: cannot read {str(scn_path)!r}: {exc.strerror}") from None
    if _sha256(scn_bytes) != digest:
        raise ConfigError(
            f"--resume: {str(scn_path)!r} was changed since the batch started (its sha256 is "
            f"{_sha256(scn_bytes)[:16]}..., {RUN_FILE} records {digest[:16]}...); restore it or "
            "start a new batch"
        )
    try:
        text = scn_bytes.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"--resume: {str(scn_path)!r}: {exc}") from None
    # the structure checks before tomllib (which recurses without a limit)
    data = loads_toml(text, f"--resume: {str(scn_path)!r}")
    scenario = validate(exp.scenario_type, data)
    if _blocks(rec_runs, exp.block_size(scenario)) != layout:
        raise ConfigError(
            f"--resume: {where!r}: block_size = {block_size} but the scenario's runner gives "
            f"blocks of {exp.block_size(scenario)}"
        )
    exp.check(scenario, rec_runs)
    plan = BatchPlan(exp, scenario, rec_seed, rec_runs, layout, digest)
    for i in range(len(layout)):
        if _saved(out_dir, i):
            try:
                load_block(plan, out_dir, i)
            except ConfigError as exc:
                raise ConfigError(f"--resume: {exc}") from None
    return plan


def _run_block_in_worker(
    name: str,
    scenario_data: dict[str, Any],
    seed: int,
    runs: tuple[int, ...],
    header: dict[str, Any],
) -> bytes:
    """Worker entry point: re-create the experiment by name, compute one block and encode it
    (with its header) as the bytes of its file (:func:`tasks.core.store.dumps`)."""
    exp = registry.get(name)
    scenario = validate(exp.scenario_type, scenario_data)
    return store.dumps(exp.run_block(scenario, seed, runs), header)


class InlineExecutor(cf.Executor):
    """One local worker: each submitted call runs in the calling thread when its result is asked
    for (:meth:`~concurrent.futures.Future.result` of the returned future), not in ``submit``.

    The runner asks for the blocks one by one in its save loop, so each block is saved and the
    progress bar moves as soon as that block is computed, and Ctrl-C keeps the finished blocks, as
    with a process pool.
    """

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        return _LazyFuture(fn, args, kwargs)


class _LazyFuture(cf.Future):
    """A future whose call runs, in the calling thread, the first time its result is asked for."""

    def __init__(self, fn: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any]):
        super().__init__()
        self._call: tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]] | None = (
            fn,
            args,
            kwargs,
        )

    def _run(self) -> None:
        if self._call is None or not self.set_running_or_notify_cancel():
            return
        fn, args, kwargs = self._call
        self._call = None
        try:
            value = fn(*args, **kwargs)
        except Exception as exc:
            self.set_exception(exc)
        else:
            self.set_result(value)

    def result(self, timeout: float | None = None) -> Any:
        self._run()
        return super().result(timeout)

    def exception(self, timeout: float | None = None) -> BaseException | None:
        self._run()
        return super().exception(timeout)


def _completed(futures: dict[cf.Future, int]) -> Iterator[cf.Future]:
    """The futures as they finish: in submission order for lazy (inline) futures, which run when
    asked for, else in completion order (:func:`concurrent.futures.as_completed`)."""
    if all(isinstance(f, _LazyFuture) for f in futures):
        pending = collections.deque(futures)
        while pending:  # held here only until handed out, so a saved block can be freed
            yield pending.popleft()
    else:
        yield from cf.as_completed(futures)  # which drops its references as it yields


EXECUTORS = ("local", "dask")
DASK_CONNECT_TIMEOUT_S = 10.0
"""How long ``--executor dask --address ...`` waits for the scheduler before giving up, s."""


def check_executor(kind: str, workers: int, address: str | None) -> None:
    """Check the executor options without starting or connecting to anything.

    Args:
        kind: ``"local"`` or ``"dask"``.
        workers: worker processes on this machine, an integer from 1 to
            :func:`tasks.core.workers.usable_cpus` (each computes one block at a time on one
            CPU; more would only share the CPUs and multiply the memory held). Not used with an
            ``address``: the scheduler's workers compute the blocks.
        address: a Dask scheduler address ``[scheme://]host:port`` or ``None``.

    Raises:
        ConfigError: naming the option, its value and what is allowed.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"workers = {workers!r}: must be an integer >= 1")
    if kind not in EXECUTORS:
        raise ConfigError(f"executor = {kind!r}: must be 'local' or 'dask'")
    if address is None:
        cpus = workers_mod.usable_cpus()
        if workers > cpus:
            raise ConfigError(
                f"workers = {workers}: at most {cpus} on this machine (the CPUs this process may "
                "run on; each worker computes one block on one CPU)"
            )
        return
    if kind == "local":
        raise ConfigError(
            f"address = {address!r}: --address is for --executor dask (the local executor "
            "takes none)"
        )
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, where = parse_address(address, strict=False)
        if scheme in ("tcp", "tls"):
            host, port = parse_host_port(where)
            if not host or port is None:
                raise ValueError("no host")
    except (ValueError, TypeError):
        raise ConfigError(
            f"address = {address!r}: must be a Dask scheduler address such as tcp://host:8786"
        ) from None


@contextlib.contextmanager
def make_executor(
    kind: str, workers: int, address: str | None, preload: Sequence[str] = ()
) -> Iterator[cf.Executor]:
    """Open an executor of the given kind.

    Args:
        kind: ``"local"`` or ``"dask"``.
        workers: worker processes (local, and local Dask cluster), >= 1; the runner asks for no
            more than the blocks it has to compute.
        address: a Dask scheduler address (``tcp://host:8786``) or ``None``.
        preload: modules local workers import before they are forked (the experiment's), see
            :func:`tasks.core.workers.pool_context`.

    Yields:
        The executor; it is shut down on exit.

    Raises:
        ConfigError: on invalid options (:func:`check_executor`), or when the Dask scheduler at
            ``address`` does not answer within :data:`DASK_CONNECT_TIMEOUT_S`.
    """
    check_executor(kind, workers, address)
    if kind == "local":
        if workers == 1:
            yield InlineExecutor()
            return
        ex = cf.ProcessPoolExecutor(
            max_workers=workers,
            mp_context=workers_mod.pool_context(preload),
            initializer=workers_mod.init_worker,
            initargs=(os.getpid(),),
        )
        try:
            yield ex
        except BaseException:
            # interrupted or failed: stop the blocks being computed now, not after they finish
            workers_mod.terminate_workers(ex)
            raise
        else:
            ex.shutdown(wait=False, cancel_futures=True)
        return
    import logging

    from distributed import Client, LocalCluster

    logging.getLogger("distributed").setLevel(logging.ERROR)
    cluster = None
    if address is None:
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
        client = Client(cluster)
    else:
        try:
            client = Client(address, timeout=f"{DASK_CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError, ValueError) as exc:
            what = " ".join(str(exc).split())
            raise ConfigError(
                f"address = {address!r}: no Dask scheduler answered within "
                f"{DASK_CONNECT_TIMEOUT_S:g} s ({what})"
            ) from None
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


class _Abandoned(BaseException):
    """Raised in an overlapped report when the batch cannot complete (a block failed or could not
    be saved, or the batch was interrupted): the report stops without writing its outputs. Not an
    :class:`Exception`, so that a report's own ``except Exception`` does not swallow it."""


class _Arrivals:
    """Which blocks are saved, for a report that reads them in block order while the others are
    still being computed (:class:`_OverlappedReport`)."""

    def __init__(self, saved: set[int]):
        self._cond = threading.Condition()
        self._saved = set(saved)
        self._abandoned = False

    def saved(self, index: int) -> None:
        """Block ``index`` is saved (its file and its sha256 file are written)."""
        with self._cond:
            self._saved.add(index)
            self._cond.notify_all()

    def abandon(self) -> None:
        """The batch will not complete: a reader waiting for a block raises :class:`_Abandoned`."""
        with self._cond:
            self._abandoned = True
            self._cond.notify_all()

    def wait(self, index: int) -> None:
        """Wait until block ``index`` is saved.

        Raises:
            _Abandoned: if the batch was abandoned first.
        """
        with self._cond:
            while index not in self._saved and not self._abandoned:
                self._cond.wait()
            if index not in self._saved:
                raise _Abandoned


class _OverlappedReport:
    """:meth:`Experiment.report` in a thread of this process, started when the blocks are handed
    to worker processes: it reads each block as soon as it and the blocks before it are saved,
    so its merge (and whatever it does before the merge) overlaps the computation of the later
    blocks instead of following it (issue 13). It reads the blocks in block order, from their
    files, as the report after the batch does, so its outputs are the same bytes; it holds no
    more blocks than that report (the one it merges)."""

    def __init__(self, plan: BatchPlan, out_dir: Path, progress: bool, arrivals: _Arrivals):
        self._arrivals = arrivals
        self.summary: ReportSummary | None = None
        self.error: BaseException | None = None

        def blocks() -> Iterator[Any]:
            for i in range(len(plan.blocks)):
                arrivals.wait(i)
                yield load_block(plan, out_dir, i)

        ctx = ReportContext(
            plan.scenario, plan.seed, plan.n_runs, out_dir, blocks(), quiet=not progress
        )

        def target() -> None:
            try:
                self.summary = plan.experiment.report(ctx)
            except _Abandoned:
                pass
            except BaseException as exc:  # handed to the main thread
                self.error = exc

        self._thread = threading.Thread(target=target, name="bauv-report", daemon=True)
        self._thread.start()

    def abandon(self) -> None:
        """Stop the report (it is waiting for a block that will not come) and wait for it."""
        self._arrivals.abandon()
        self._thread.join(timeout=ABANDON_WAIT_S)

    def result(self) -> ReportSummary:
        """Wait for the report once every block is saved; its exception is raised here."""
        self._thread.join()
        if self.error is not None:
            raise self.error
        assert self.summary is not None
        return self.summary


ABANDON_WAIT_S = 10.0
"""How long an abandoned overlapped report may take to stop (it is between two blocks), s."""


def execute(
    plan: BatchPlan,
    out_dir: Path,
    executor: str = "local",
    workers: int = 1,
    address: str | None = None,
    progress: bool = True,
    pool: cf.Executor | None = None,
) -> ReportSummary:
    """Compute the missing blocks of a prepared batch and write its report.

    With worker processes (a local pool, Dask) the report runs in a thread of this process
    meanwhile, merging each block once it and the blocks before it are saved
    (:class:`_OverlappedReport`); on one local worker (inline) it follows the blocks. Every file
    is written with the run folder :func:`~tasks.core.files.confined`.

    Args:
        plan: the batch.
        out_dir: its prepared folder (see :func:`prepare_out_dir`).
        executor: ``"local"`` or ``"dask"``.
        workers: number of worker processes; no more than the blocks still to compute are
            started (one block left: it is computed in this process).
        address: Dask scheduler address, if any.
        progress: show a progress bar on a terminal.
        pool: an executor already opened by :func:`make_executor` (then ``executor``,
            ``workers`` and ``address`` are not used), or ``None`` to open one when a block is
            missing.

    Returns:
        The report summary.

    Raises:
        BatchInterrupted: on SIGINT, after the finished blocks are saved.
        BatchFailed: if a block raised (the others are saved).
        OutputError: if a block or the report cannot be written (a full disk, a symbolic link
            planted in the run folder during the batch).
    """
    with files.confined(out_dir):
        return _execute(plan, out_dir, executor, workers, address, progress, pool)


def _execute(
    plan: BatchPlan,
    out_dir: Path,
    executor: str,
    workers: int,
    address: str | None,
    progress: bool,
    pool: cf.Executor | None,
) -> ReportSummary:
    from tqdm import tqdm

    todo = [i for i in range(len(plan.blocks)) if not _saved(out_dir, i)]
    # a worker computes one block at a time: more workers than blocks would only be forked idle
    workers = max(1, min(workers, len(todo)))
    done_runs = plan.n_runs - sum(len(plan.blocks[i]) for i in todo)
    data = to_plain(plan.scenario)
    failures: list[str] = []
    overlapped: _OverlappedReport | None = None
    arrivals = _Arrivals(set(range(len(plan.blocks))) - set(todo))

    def progress_bar() -> Any:
        return tqdm(
            total=plan.n_runs,
            initial=done_runs,
            unit="run",
            desc=plan.experiment.name,
            disable=None if progress else True,
            dynamic_ncols=True,
        )

    bar = None if todo else progress_bar()
    try:
        if todo:
            with (
                contextlib.nullcontext(pool)
                if pool is not None
                else make_executor(executor, workers, address, (type(plan.experiment).__module__,))
            ) as ex:
                # local workers are forked at the first submit (tasks.core.workers): before this
                # process starts a thread of its own (the bar's monitor, the report)
                futures = {
                    ex.submit(
                        _run_block_in_worker,
                        plan.experiment.name,
                        data,
                        plan.seed,
                        plan.blocks[i],
                        _block_header(plan, i),
                    ): i
                    for i in todo
                }
                bar = progress_bar()
                if not isinstance(ex, InlineExecutor):
                    overlapped = _OverlappedReport(plan, out_dir, progress, arrivals)
                try:
                    for fut in _completed(futures):
                        # forget the future once its block is handled: its result (the block)
                        # is then freed, so memory does not grow with the batch
                        i = futures.pop(fut)
                        try:
                            payload = fut.result()
                        except Exception as exc:
                            runs = plan.blocks[i]
                            failures.append(
                                f"block {i} (runs {runs[0]}-{runs[-1]}): "
                                f"{type(exc).__name__}: {exc}"
                            )
                            continue
                        try:
                            _save_block(out_dir, i, payload)
                        except OSError as exc:
                            for f in futures:
                                f.cancel()
                            raise _output_error(plan, out_dir, f"block {i}", exc) from None
                        arrivals.saved(i)
                        bar.update(len(plan.blocks[i]))
                except KeyboardInterrupt:
                    for f in futures:
                        f.cancel()
                    raise
    except KeyboardInterrupt:
        if bar is not None:
            bar.close()
        if overlapped is not None:
            overlapped.abandon()
        n_done = sum(_saved(out_dir, i) for i in range(len(plan.blocks)))
        raise BatchInterrupted(
            f"interrupted: {n_done} of {len(plan.blocks)} blocks are saved in {out_dir}; "
            f"complete the batch with: bauv run {plan.experiment.name} --resume --out {out_dir}"
        ) from None
    except BaseException:
        if overlapped is not None:
            overlapped.abandon()
        raise
    if bar is not None:
        bar.close()
    if failures:
        if overlapped is not None:
            overlapped.abandon()
        raise BatchFailed(
            f"{len(failures)} block(s) failed; the other blocks are saved in {out_dir} and "
            "--resume retries the failed ones:\n  " + "\n  ".join(failures)
        )

    def blocks() -> Iterator[Any]:
        for i in range(len(plan.blocks)):
            yield load_block(plan, out_dir, i)

    try:
        if overlapped is not None:
            summary = overlapped.result()
        else:
            summary = plan.experiment.report(
                ReportContext(
                    plan.scenario, plan.seed, plan.n_runs, out_dir, blocks(), quiet=not progress
                )
            )
    except KeyboardInterrupt:
        if overlapped is not None:
            overlapped.abandon()
        raise BatchInterrupted(
            f"interrupted while writing the report: all {len(plan.blocks)} blocks are saved in "
            f"{out_dir}; write the report with: bauv run {plan.experiment.name} --resume "
            f"--out {out_dir}"
        ) from None
    except OSError as exc:
        raise _output_error(plan, out_dir, "the report", exc) from None
    try:
        _write_run_record(out_dir, plan, "complete")
    except OSError as exc:
        raise _output_error(plan, out_dir, RUN_FILE, exc) from None
    return summary


def _output_error(plan: BatchPlan, out_dir: Path, what: str, exc: OSError) -> OutputError:
    n_done = sum(_saved(out_dir, i) for i in range(len(plan.blocks)))
    fix = "remove the link" if isinstance(exc, files.LinkInRunFolder) else "make room"
    return OutputError(
        f"cannot write {what} ({os_error_text(exc)}); {n_done} of {len(plan.blocks)} blocks are "
        f"saved in {out_dir}; {fix} and complete the batch with: bauv run "
        f"{plan.experiment.name} --resume --out {out_dir}"
    )


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


def run(
    name: str,
    n_runs: int | None = None,
    seed: int | None = None,
    out_dir: str | Path | None = None,
    overrides: Sequence[str] = (),
    scenario_files: Sequence[str | Path] = (),
    executor: str = "local",
    workers: int = 1,
    address: str | None = None,
    resume: bool = False,
    progress: bool = True,
) -> tuple[Path, ReportSummary]:
    """Plan, prepare and execute a batch (the library form of ``bauv run``).

    Returns:
        ``(run folder, report summary)``.

    Raises:
        ConfigError: on any invalid input, including the executor options and a Dask scheduler
            that does not answer, before anything is written.
        BatchInterrupted: on SIGINT (finished blocks are kept).
        BatchFailed: if a block raised.
    """
    overrides, scenario_files = check_run_arguments(
        name, n_runs, seed, out_dir, overrides, scenario_files, address, resume, progress
    )
    check_executor(executor, workers, address)
    if executor == "local" and workers > 1:
        workers_mod.start_fork_server(name)
    if resume:
        if out_dir is None:
            raise ConfigError("--resume needs --out: the folder of the batch to complete")
        out = Path(out_dir)
        try:
            plan = plan_resume(out, name, n_runs, seed, overrides, scenario_files)
        except OSError as exc:
            raise ConfigError(
                f"--resume: cannot read {str(out)!r} ({os_error_text(exc)})"
            ) from None
    else:
        plan = plan_batch(name, n_runs, 0 if seed is None else seed, overrides, scenario_files)
        out = Path(out_dir) if out_dir is not None else default_out_dir(name, plan.seed)
    if executor == "local" or address is None:
        # this machine's workers each hold a block at the same time (no more workers than blocks
        # are started)
        check_memory(plan.experiment, plan.scenario, plan.n_runs, min(workers, len(plan.blocks)))
    with contextlib.ExitStack() as stack:
        pool = None
        if address is not None:
            # connect to the scheduler before anything is written: an address that does not
            # answer leaves no folder behind
            pool = stack.enter_context(make_executor(executor, workers, address))
        if not resume:
            prepare_out_dir(plan, out)
        return out, execute(plan, out, executor, workers, address, progress, pool)
