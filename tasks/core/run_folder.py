"""The run folder on disk: its files, how each is written, and how a saved block is read back.

The folder holds ``run.json`` (:data:`RUN_FILE`: ``state`` is ``incomplete`` until the report is
written, then ``complete``; ``provenance`` is :func:`bauv_sim.provenance.collect` of the process
that started the batch, also in ``provenance.json`` (:data:`PROVENANCE_FILE`), never in
``metrics.json``; ``provenance_completed`` that of a ``--resume`` that completed it elsewhere;
``record_sha256`` is the sha256 of its other fields),
``scenario.toml`` (:data:`SCENARIO_FILE`: the resolved scenario; ``bauv run NAME --scenario FILE``
repeats it), ``blocks/`` and the report's files. A block's result, encoded as plain data
(:mod:`tasks.core.store`, a format that cannot execute code when read), is written to
``blocks/block-NNNNNN.zip``, then its sha256 to ``block-NNNNNN.sha256`` (``sha256sum -c`` reads
it); both are written atomically, and a block counts as saved only when both files are there
(:func:`saved`). Every file is written through :mod:`tasks.core.files` with the run folder
:func:`~tasks.core.files.confined` by the caller: atomically, and never through a symbolic link
inside it. :func:`load_block` checks a saved block's size, sha256, encoding and header before
it hands its result back. No file of a run folder is ever unpickled.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
from pathlib import Path
from typing import Any

from bauv_sim import provenance
from bauv_sim.errors import ConfigError
from tasks.core import files, store
from tasks.core.files import atomic_write_bytes, os_error_text
from tasks.core.plan import BatchPlan, scenario_text, sha256

RUN_FILE = "run.json"
PROVENANCE_FILE = "provenance.json"
SCENARIO_FILE = "scenario.toml"
BLOCK_DIR = "blocks"
BLOCK_SUFFIX = ".zip"
DIGEST_SUFFIX = ".sha256"
FORMAT_VERSION = 3
"""Version of the run folder's layout. 1 kept pickled blocks (never read: a crafted pickle runs
code when loaded); 2 keeps plain-data blocks with a sha256 file each and the scenario's sha256;
3 adds ``record_sha256`` to ``run.json`` (the sha256 of its other fields)."""
STATES = ("incomplete", "complete")


def atomic_write_text(path: Path, text: str) -> None:
    """Write a text file so that it either exists whole or not at all."""
    atomic_write_bytes(path, text.encode("utf-8"))


def block_path(out_dir: Path, index: int) -> Path:
    """The file of block ``index``."""
    return out_dir / BLOCK_DIR / f"block-{index:06d}{BLOCK_SUFFIX}"


def digest_path(out_dir: Path, index: int) -> Path:
    """The sha256 file of block ``index``."""
    return out_dir / BLOCK_DIR / f"block-{index:06d}{DIGEST_SUFFIX}"


def saved(out_dir: Path, index: int) -> bool:
    """Whether block ``index`` is saved: its file and its sha256 file are both there."""
    return block_path(out_dir, index).is_file() and digest_path(out_dir, index).is_file()


def save_block(out_dir: Path, index: int, payload: bytes) -> None:
    """Write a block's bytes, then its sha256 (a crash in between leaves it unsaved)."""
    path = block_path(out_dir, index)
    files.remove(digest_path(out_dir, index))
    atomic_write_bytes(path, payload)
    atomic_write_text(digest_path(out_dir, index), f"{sha256(payload)}  {path.name}\n")


def block_header(plan: BatchPlan, index: int) -> dict[str, Any]:
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


def read_small(path: Path, limit: int) -> bytes:
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
    path, dpath = block_path(out_dir, index), digest_path(out_dir, index)
    line_limit = 64 + 2 + len(path.name) + 1
    try:
        recorded = read_small(dpath, line_limit)
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
    expected = block_header(plan, index)
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


def run_record(
    plan: BatchPlan, state: str, started: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The fields of ``run.json`` (without :data:`RECORD_DIGEST`).

    Args:
        plan: the batch.
        state: ``"incomplete"`` or ``"complete"``.
        started: the provenance of the process that started the batch (default: this one's);
            when it is not this process's, this one's is added as ``provenance_completed``.
    """
    current = provenance.collect()
    started = current if started is None else started
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
        "provenance": started,
    } | ({} if started == current else {"provenance_completed": current})


RECORD_DIGEST = "record_sha256"
"""The field of ``run.json`` that holds the sha256 of its other fields (:func:`record_digest`)."""


def record_digest(record: dict[str, Any]) -> str:
    """sha256 (hex) of ``run.json``'s fields other than :data:`RECORD_DIGEST`: of their JSON with
    sorted keys, no spaces and ASCII escapes (so re-indenting the file does not change it, any
    edit of a value does)."""
    fields = {k: v for k, v in record.items() if k != RECORD_DIGEST}
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return sha256(text.encode("ascii"))


def _started_provenance(out_dir: Path) -> dict[str, Any] | None:
    """``provenance.json`` of a started batch, or ``None`` (none yet, or not a JSON object)."""
    try:
        value = json.loads(read_small(out_dir / PROVENANCE_FILE, MAX_PROVENANCE_BYTES))
    except (OSError, ValueError, ConfigError, RecursionError):
        return None
    return value if type(value) is dict else None


MAX_PROVENANCE_BYTES = 2**14
"""The largest ``provenance.json`` read back (it is about 300 bytes)."""


def write_run_record(out_dir: Path, plan: BatchPlan, state: str) -> None:
    """Write ``run.json`` with ``state``, the batch's provenance and its :data:`RECORD_DIGEST`.

    The provenance is that of the process that started the batch: this one's, written to
    ``provenance.json`` when the folder has none yet (a folder started before provenance was
    recorded gets the completing process's); a ``--resume`` from another environment keeps it
    and adds its own as ``provenance_completed``.
    """
    started = _started_provenance(out_dir)
    if started is None:
        started = provenance.collect()
        atomic_write_text(out_dir / PROVENANCE_FILE, json.dumps(started, indent=2) + "\n")
    record = run_record(plan, state, started)
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
    if sha256(text.encode("utf-8")) != plan.scenario_sha256:
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
            write_run_record(out_dir, plan, "incomplete")
    except OSError as exc:
        with files.confined(out_dir):
            for path in (out_dir / SCENARIO_FILE, out_dir / PROVENANCE_FILE, out_dir / RUN_FILE):
                with contextlib.suppress(OSError):
                    files.remove(path)
        for folder in created:  # deepest first
            with contextlib.suppress(OSError):
                folder.rmdir()
        reason = exc.strerror if exc.filename == str(out_dir) else os_error_text(exc)
        raise ConfigError(f"{where}: cannot create the run folder ({reason})") from None
