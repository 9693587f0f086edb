"""The Monte Carlo runner: blocks of runs on an :class:`~concurrent.futures.Executor`, on disk.

A batch is split into blocks of a size fixed by the scenario (:meth:`Experiment.block_size`). Each
block is computed by :meth:`Experiment.run_block` in a worker and written to
``<out>/blocks/block-NNNNNN.pkl`` as soon as it finishes (atomically: a file that exists is whole).
When every block is there, :meth:`Experiment.report` reads them back **in block order** and writes
the outputs. Because a run's numbers depend only on ``(scenario, seed, run index)`` and blocks are
reduced in a fixed order, the outputs are bit-identical whatever the executor and worker count, and
a batch interrupted and resumed with ``--resume`` equals one run straight through.

Executors: ``local`` (in-process for one worker, else a :class:`ProcessPoolExecutor` with the
``spawn`` start method) and ``dask`` (``distributed.Client(address)``, or a local cluster with
``workers`` single-threaded processes when no address is given).

The run folder holds ``run.json`` (``state`` is ``incomplete`` until the report is written, then
``complete``), ``scenario.toml`` (the resolved scenario: ``bauv run NAME --scenario FILE`` repeats
it), ``blocks/`` and the report's files.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import datetime as _dt
import json
import multiprocessing
import os
import pickle
import tempfile
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomli_w

from bauv_sim.config import Config, load_config, read_toml, to_plain, validate
from bauv_sim.errors import BauvSimError, ConfigError
from bauv_sim.rng import check_seed
from tasks.core import registry
from tasks.core.registry import Experiment, ReportContext, ReportSummary

RUN_FILE = "run.json"
SCENARIO_FILE = "scenario.toml"
BLOCK_DIR = "blocks"
FORMAT_VERSION = 1


class BatchInterrupted(BauvSimError):
    """The batch was interrupted (SIGINT); finished blocks are kept; ``--resume`` completes it."""


class BatchFailed(BauvSimError):
    """One or more blocks raised; the others were kept."""


@dataclass(frozen=True)
class BatchPlan:
    """A validated batch, before anything is written.

    Attributes:
        experiment: the registered experiment.
        scenario: the validated scenario.
        seed: the batch seed.
        n_runs: the number of runs.
        blocks: the run indices of each block, in order.
    """

    experiment: Experiment
    scenario: Config
    seed: int
    n_runs: int
    blocks: tuple[tuple[int, ...], ...]


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
    scenario = load_config(exp.scenario_type, exp.preset, scenario_files, overrides)
    exp.check(scenario, n)
    return BatchPlan(exp, scenario, seed, n, _blocks(n, exp.block_size(scenario)))


def _blocks(n_runs: int, size: int) -> tuple[tuple[int, ...], ...]:
    return tuple(tuple(range(i, min(i + size, n_runs))) for i in range(0, n_runs, size))


def default_out_dir(name: str, seed: int) -> Path:
    """``runs/<name with / as _>/<UTC timestamp>-seed<seed>``."""
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%S%f")
    return Path("runs") / name.replace("/", "_") / f"{stamp}-seed{seed}"


def _atomic_write_bytes(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: Path, text: str) -> None:
    """Write a text file so that it either exists whole or not at all."""
    _atomic_write_bytes(path, text.encode("utf-8"))


def _block_path(out_dir: Path, index: int) -> Path:
    return out_dir / BLOCK_DIR / f"block-{index:06d}.pkl"


def _run_record(plan: BatchPlan, state: str) -> dict[str, Any]:
    return {
        "format_version": FORMAT_VERSION,
        "experiment": plan.experiment.name,
        "seed": plan.seed,
        "n_runs": plan.n_runs,
        "block_size": len(plan.blocks[0]),
        "n_blocks": len(plan.blocks),
        "state": state,
    }


def _write_run_record(out_dir: Path, plan: BatchPlan, state: str) -> None:
    atomic_write_text(out_dir / RUN_FILE, json.dumps(_run_record(plan, state), indent=2) + "\n")


def prepare_out_dir(plan: BatchPlan, out_dir: Path) -> None:
    """Create a fresh run folder with ``run.json`` (incomplete) and ``scenario.toml``.

    Raises:
        ConfigError: if the folder exists and is not empty.
    """
    if out_dir.exists() and any(out_dir.iterdir()):
        raise ConfigError(
            f"out = {str(out_dir)!r}: folder exists and is not empty; "
            "use --resume to complete it or choose another --out"
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out_dir / SCENARIO_FILE, tomli_w.dumps(to_plain(plan.scenario)))
    _write_run_record(out_dir, plan, "incomplete")


def plan_resume(
    out_dir: Path,
    name: str,
    n_runs: int | None,
    seed: int | None,
    overrides: Sequence[str],
    scenario_files: Sequence[str | Path],
) -> BatchPlan:
    """Rebuild the plan of an interrupted batch from its folder.

    Raises:
        ConfigError: if the folder is not a batch of ``name`` or the request contradicts it.
    """
    record_path = out_dir / RUN_FILE
    if not record_path.is_file():
        raise ConfigError(f"out = {str(out_dir)!r}: no {RUN_FILE}; nothing to resume")
    record = json.loads(record_path.read_text())
    if record.get("experiment") != name:
        raise ConfigError(
            f"--resume: {str(out_dir)!r} holds {record.get('experiment')!r}, not {name!r}"
        )
    if overrides or scenario_files:
        raise ConfigError(
            "--resume: the scenario of a started batch cannot change (drop --set/--scenario)"
        )
    if seed is not None and seed != record["seed"]:
        raise ConfigError(
            f"--resume: seed = {seed} but the batch was started with {record['seed']}"
        )
    if n_runs is not None and n_runs != record["n_runs"]:
        raise ConfigError(
            f"--resume: runs = {n_runs} but the batch was started with {record['n_runs']}"
        )
    exp = registry.get(name)
    scenario = validate(exp.scenario_type, read_toml(out_dir / SCENARIO_FILE))
    n = int(record["n_runs"])
    return BatchPlan(exp, scenario, int(record["seed"]), n, _blocks(n, int(record["block_size"])))


def _run_block_in_worker(
    name: str, scenario_data: dict[str, Any], seed: int, runs: tuple[int, ...]
) -> bytes:
    """Worker entry point: re-create the experiment by name and compute one block."""
    exp = registry.get(name)
    scenario = validate(exp.scenario_type, scenario_data)
    return pickle.dumps(exp.run_block(scenario, seed, runs), protocol=pickle.HIGHEST_PROTOCOL)


class InlineExecutor(cf.Executor):
    """Runs each submitted call at once in the calling thread (one local worker)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        fut: cf.Future = cf.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            if isinstance(exc, KeyboardInterrupt):
                raise
            fut.set_exception(exc)
        return fut


@contextlib.contextmanager
def make_executor(kind: str, workers: int, address: str | None) -> Iterator[cf.Executor]:
    """Open an executor of the given kind.

    Args:
        kind: ``"local"`` or ``"dask"``.
        workers: worker processes (local, and local Dask cluster), >= 1.
        address: a Dask scheduler address (``tcp://host:8786``) or ``None``.

    Yields:
        The executor; it is shut down on exit.
    """
    if workers < 1:
        raise ConfigError(f"workers = {workers}: must be >= 1")
    if kind == "local":
        if address is not None:
            raise ConfigError("--address is for --executor dask")
        if workers == 1:
            yield InlineExecutor()
            return
        ex = cf.ProcessPoolExecutor(
            max_workers=workers, mp_context=multiprocessing.get_context("spawn")
        )
        try:
            yield ex
        finally:
            ex.shutdown(wait=False, cancel_futures=True)
        return
    if kind == "dask":
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
            client = Client(address)
        try:
            yield client.get_executor(pure=False)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        return
    raise ConfigError(f"executor = {kind!r}: must be 'local' or 'dask'")


def execute(
    plan: BatchPlan,
    out_dir: Path,
    executor: str = "local",
    workers: int = 1,
    address: str | None = None,
    progress: bool = True,
) -> ReportSummary:
    """Compute the missing blocks of a prepared batch and write its report.

    Args:
        plan: the batch.
        out_dir: its prepared folder (see :func:`prepare_out_dir`).
        executor: ``"local"`` or ``"dask"``.
        workers: number of worker processes.
        address: Dask scheduler address, if any.
        progress: show a progress bar on a terminal.

    Returns:
        The report summary.

    Raises:
        BatchInterrupted: on SIGINT, after the finished blocks are saved.
        BatchFailed: if a block raised (the others are saved).
    """
    from tqdm import tqdm

    todo = [i for i in range(len(plan.blocks)) if not _block_path(out_dir, i).is_file()]
    done_runs = plan.n_runs - sum(len(plan.blocks[i]) for i in todo)
    data = to_plain(plan.scenario)
    failures: list[str] = []
    bar = tqdm(
        total=plan.n_runs,
        initial=done_runs,
        unit="run",
        desc=plan.experiment.name,
        disable=None if progress else True,
        dynamic_ncols=True,
    )
    try:
        if todo:
            with make_executor(executor, workers, address) as ex:
                futures = {
                    ex.submit(
                        _run_block_in_worker, plan.experiment.name, data, plan.seed, plan.blocks[i]
                    ): i
                    for i in todo
                }
                try:
                    for fut in cf.as_completed(futures):
                        i = futures[fut]
                        try:
                            payload = fut.result()
                        except Exception as exc:
                            runs = plan.blocks[i]
                            failures.append(
                                f"block {i} (runs {runs[0]}-{runs[-1]}): "
                                f"{type(exc).__name__}: {exc}"
                            )
                            continue
                        _atomic_write_bytes(_block_path(out_dir, i), payload)
                        bar.update(len(plan.blocks[i]))
                except KeyboardInterrupt:
                    for f in futures:
                        f.cancel()
                    raise
    except KeyboardInterrupt:
        bar.close()
        n_done = sum(_block_path(out_dir, i).is_file() for i in range(len(plan.blocks)))
        raise BatchInterrupted(
            f"interrupted: {n_done} of {len(plan.blocks)} blocks are saved in {out_dir}; "
            f"complete the batch with: bauv run {plan.experiment.name} --resume --out {out_dir}"
        ) from None
    bar.close()
    if failures:
        raise BatchFailed(
            f"{len(failures)} block(s) failed; the other blocks are saved in {out_dir} and "
            "--resume retries the failed ones:\n  " + "\n  ".join(failures)
        )

    def blocks() -> Iterator[Any]:
        for i in range(len(plan.blocks)):
            with _block_path(out_dir, i).open("rb") as fh:
                yield pickle.load(fh)

    try:
        summary = plan.experiment.report(
            ReportContext(
                plan.scenario, plan.seed, plan.n_runs, out_dir, blocks(), quiet=not progress
            )
        )
    except KeyboardInterrupt:
        raise BatchInterrupted(
            f"interrupted while writing the report: all {len(plan.blocks)} blocks are saved in "
            f"{out_dir}; write the report with: bauv run {plan.experiment.name} --resume "
            f"--out {out_dir}"
        ) from None
    _write_run_record(out_dir, plan, "complete")
    return summary


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
    """
    if resume:
        if out_dir is None:
            raise ConfigError("--resume needs --out: the folder of the batch to complete")
        out = Path(out_dir)
        plan = plan_resume(out, name, n_runs, seed, overrides, scenario_files)
    else:
        plan = plan_batch(name, n_runs, 0 if seed is None else seed, overrides, scenario_files)
        out = Path(out_dir) if out_dir is not None else default_out_dir(name, plan.seed)
        prepare_out_dir(plan, out)
    return out, execute(plan, out, executor, workers, address, progress)
