"""``--resume``: the plan of an interrupted batch, rebuilt from its folder after checking it.

What :func:`plan_resume` checks before anything is written (any failure is a
:class:`ConfigError`): the folder holds no symbolic link (a link to a file or folder outside
would have the batch read or write there); ``run.json`` is whole, at most
:data:`MAX_RECORD_BYTES`, every field is there with its type (format version, experiment, seed,
runs, block size, number of blocks, the sha256 of ``scenario.toml``, the store version, state)
and its ``record_sha256`` is theirs (an edited run count or seed is refused); the request agrees
with it (experiment, seed, runs; no new scenario); ``scenario.toml`` still has its recorded
sha256 and gives the recorded block layout; and every saved block is at most the size such a
block can hold (:func:`tasks.core.plan.block_file_limit`, checked before a byte is read), its
bytes have their recorded sha256 (read in chunks), decode, and carry a header (format version,
experiment, seed, block index, run indices, scenario sha256) that agrees with the batch
(:func:`tasks.core.run_folder.load_block`). No file of a run folder is ever unpickled.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bauv_sim.config import loads_toml, validate
from bauv_sim.errors import ConfigError
from bauv_sim.rng import check_seed
from tasks.core import files, registry, store
from tasks.core.files import os_error_text
from tasks.core.plan import MAX_RUNS, BatchPlan, block_layout, check_layout, sha256
from tasks.core.run_folder import (
    FORMAT_VERSION,
    RECORD_DIGEST,
    RUN_FILE,
    SCENARIO_FILE,
    STATES,
    load_block,
    read_small,
    record_digest,
    saved,
)

_HEX64 = re.compile(r"[0-9a-f]{64}")

MAX_RECORD_BYTES = 2**16
"""The largest ``run.json`` read (it is about 400 bytes)."""
MAX_SCENARIO_BYTES = 2**24
"""The largest ``scenario.toml`` read (a few kB; way-point and beacon lists make it longer)."""


def _read_record(out_dir: Path) -> dict[str, Any]:
    path = out_dir / RUN_FILE
    if not path.is_file():
        raise ConfigError(f"out = {str(out_dir)!r}: no {RUN_FILE}; nothing to resume")
    try:
        record = json.loads(read_small(path, MAX_RECORD_BYTES).decode("utf-8"))
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
    layout = block_layout(rec_runs, block_size)
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
        scn_bytes = read_small(scn_path, MAX_SCENARIO_BYTES)
    except ConfigError as exc:
        raise ConfigError(f"--resume: {exc}") from None
    except OSError as exc:
        raise ConfigError(f"--resume: cannot read {str(scn_path)!r}: {exc.strerror}") from None
    if sha256(scn_bytes) != digest:
        raise ConfigError(
            f"--resume: {str(scn_path)!r} was changed since the batch started (its sha256 is "
            f"{sha256(scn_bytes)[:16]}..., {RUN_FILE} records {digest[:16]}...); restore it or "
            "start a new batch"
        )
    try:
        text = scn_bytes.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"--resume: {str(scn_path)!r}: {exc}") from None
    # the structure checks before tomllib (which recurses without a limit)
    data = loads_toml(text, f"--resume: {str(scn_path)!r}")
    scenario = validate(exp.scenario_type, data)
    if block_layout(rec_runs, exp.block_size(scenario)) != layout:
        raise ConfigError(
            f"--resume: {where!r}: block_size = {block_size} but the scenario's runner gives "
            f"blocks of {exp.block_size(scenario)}"
        )
    exp.check(scenario, rec_runs)
    plan = BatchPlan(exp, scenario, rec_seed, rec_runs, layout, digest)
    for i in range(len(layout)):
        if saved(out_dir, i):
            try:
                load_block(plan, out_dir, i)
            except ConfigError as exc:
                raise ConfigError(f"--resume: {exc}") from None
    return plan
