"""The Monte Carlo runner: blocks of runs on an :class:`~concurrent.futures.Executor`, on disk.

A batch is split into blocks of a size fixed by the scenario (:meth:`Experiment.block_size`). Each
block is computed by :meth:`Experiment.run_block` in a worker, encoded there as plain data
(:mod:`tasks.core.store`) and saved in the run folder as soon as it finishes
(:mod:`tasks.core.run_folder`). :meth:`Experiment.report` reads the blocks back **in block
order** and writes the outputs: after the last block on one local worker, and in a thread of this
process on worker processes (local or Dask, :mod:`tasks.core.overlapped`), where it reads each
block as soon as it and the blocks before it are saved, so its merge overlaps the later blocks.
Because a run's numbers depend only on ``(scenario, seed, run index)``, blocks are reduced in a
fixed order and the encoding keeps every bit, the outputs are bit-identical whatever the executor
and worker count, and a batch interrupted and resumed with ``--resume`` equals one run straight
through.

The parts, each readable alone:

* :mod:`tasks.core.plan`: the batch validated before anything is written (:func:`plan_batch`,
  :class:`BatchPlan`, the limits on runs, blocks, memory and block files);
* :mod:`tasks.core.run_folder`: the run folder's files (``run.json``, ``scenario.toml``, the
  blocks and their sha256), written atomically, and a saved block read back and checked;
* :mod:`tasks.core.resume`: ``--resume``, the plan of an interrupted batch rebuilt from its folder
  after checking it;
* :mod:`tasks.core.executors`: where blocks are computed (inline, local processes, Dask);
* :mod:`tasks.core.overlapped`: the report written while the blocks are computed;
* :mod:`tasks.core.report_pool`: processes started with the batch that take independent jobs of
  the report (a mission's figures, recording and run data) while this process writes the rest;
* this module: :func:`execute` (compute the missing blocks, save them, write the report) and
  :func:`run`, the library form of ``bauv run`` (plan, prepare, execute).

Its public names are importable from here as before the split.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from bauv_sim.config import to_plain, validate
from bauv_sim.errors import ConfigError
from tasks.core import files, registry, run_folder, store
from tasks.core import workers as workers_mod
from tasks.core.errors import BatchFailed, BatchInterrupted, OutputError
from tasks.core.executors import (
    DASK_CONNECT_TIMEOUT_S,
    EXECUTORS,
    InlineExecutor,
    check_executor,
    completed,
    make_executor,
)
from tasks.core.files import os_error_text
from tasks.core.overlapped import Arrivals, OverlappedReport
from tasks.core.plan import (
    BLOCK_FILE_BASE_B,
    BLOCK_FILE_MEMORY_FACTOR,
    BLOCK_FILE_PER_RUN_B,
    MAX_BLOCKS,
    MAX_RUNS,
    MEMORY_FRACTION,
    BatchPlan,
    block_file_limit,
    check_layout,
    check_memory,
    check_run_arguments,
    default_out_dir,
    memory_limit_bytes,
    plan_batch,
    scenario_text,
)
from tasks.core.registry import ReportContext, ReportSummary
from tasks.core.report_pool import ReportPool, report_pool
from tasks.core.resume import MAX_RECORD_BYTES, MAX_SCENARIO_BYTES, plan_resume
from tasks.core.run_folder import (
    BLOCK_DIR,
    FORMAT_VERSION,
    RECORD_DIGEST,
    RUN_FILE,
    SCENARIO_FILE,
    atomic_write_text,
    load_block,
    prepare_out_dir,
    record_digest,
)

__all__ = [
    "BLOCK_DIR",
    "BLOCK_FILE_BASE_B",
    "BLOCK_FILE_MEMORY_FACTOR",
    "BLOCK_FILE_PER_RUN_B",
    "DASK_CONNECT_TIMEOUT_S",
    "EXECUTORS",
    "FORMAT_VERSION",
    "MAX_BLOCKS",
    "MAX_RECORD_BYTES",
    "MAX_RUNS",
    "MAX_SCENARIO_BYTES",
    "MEMORY_FRACTION",
    "RECORD_DIGEST",
    "RUN_FILE",
    "SCENARIO_FILE",
    "BatchFailed",
    "BatchInterrupted",
    "BatchPlan",
    "InlineExecutor",
    "OutputError",
    "atomic_write_text",
    "block_file_limit",
    "check_executor",
    "check_layout",
    "check_memory",
    "check_run_arguments",
    "default_out_dir",
    "execute",
    "load_block",
    "make_executor",
    "memory_limit_bytes",
    "plan_batch",
    "plan_resume",
    "prepare_out_dir",
    "record_digest",
    "run",
    "scenario_text",
]


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
    (:class:`~tasks.core.overlapped.OverlappedReport`); on one local worker (inline) it follows
    the blocks. Every file is written with the run folder :func:`~tasks.core.files.confined`.

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
        batch = _Computation(plan, out_dir, progress)
        try:
            batch.compute(executor, workers, address, pool)
        except KeyboardInterrupt:
            batch.stop(close_bar=True)
            raise BatchInterrupted(
                f"interrupted: {_n_saved(plan, out_dir)} of {len(plan.blocks)} blocks are saved "
                f"in {out_dir}; complete the batch with: bauv run {plan.experiment.name} "
                f"--resume --out {out_dir}"
            ) from None
        except BaseException:
            batch.stop(close_bar=False)
            raise
        batch.close_bar()
        if batch.failures:
            batch.stop(close_bar=False)
            raise BatchFailed(
                f"{len(batch.failures)} block(s) failed; the other blocks are saved in {out_dir} "
                "and --resume retries the failed ones:\n  " + "\n  ".join(batch.failures)
            )
        batch.open_report_pool(0)  # nothing was computed (--resume of a complete batch)
        try:
            summary = _write_report(plan, out_dir, progress, batch.overlapped, batch.report_pool)
        except BaseException:
            batch.stop(close_bar=False)
            raise
        if batch.report_pool is not None:
            batch.report_pool.close()
        try:
            run_folder.write_run_record(out_dir, plan, "complete")
        except OSError as exc:
            raise _output_error(plan, out_dir, RUN_FILE, exc) from None
        return summary


class _Computation:
    """The blocks of a batch still to compute: computed on an executor and saved as they
    finish, with the progress bar, the overlapped report (on worker processes) and the blocks
    that failed.

    Attributes:
        failures: one line per block that raised.
        overlapped: the report running meanwhile, or ``None`` (inline, or nothing to compute).
    """

    def __init__(self, plan: BatchPlan, out_dir: Path, progress: bool):
        self.plan, self.out_dir, self.progress = plan, out_dir, progress
        self.todo = [i for i in range(len(plan.blocks)) if not run_folder.saved(out_dir, i)]
        self.failures: list[str] = []
        self.overlapped: OverlappedReport | None = None
        self.report_pool: ReportPool | None = None
        self.workers = 1
        """Processes computing blocks (a report process starts once one of them is idle)."""
        self.arrivals = Arrivals(set(range(len(plan.blocks))) - set(self.todo))
        self.bar: Any = None if self.todo else self._progress_bar()

    def open_report_pool(self, workers: int) -> None:
        """The report's processes (:mod:`tasks.core.report_pool`), if the experiment hands out
        report work (``workers``: the processes computing blocks meanwhile, for the memory they
        hold); not started yet."""
        if self.report_pool is None:
            self.report_pool = report_pool(self.plan, self.out_dir, workers)
            self.workers = workers

    def start_report_pool(self) -> None:
        """Start the report's processes, so that they import their libraries on a free core
        while the last blocks are computed."""
        if self.report_pool is not None:
            self.report_pool.start()

    def _progress_bar(self) -> Any:
        from tqdm import tqdm

        plan = self.plan
        return tqdm(
            total=plan.n_runs,
            initial=plan.n_runs - sum(len(plan.blocks[i]) for i in self.todo),
            unit="run",
            desc=plan.experiment.name,
            disable=None if self.progress else True,
            dynamic_ncols=True,
        )

    def compute(
        self, executor: str, workers: int, address: str | None, pool: cf.Executor | None
    ) -> None:
        """Compute the missing blocks and save each as it finishes (a block that raises is
        noted in :attr:`failures`; the others go on).

        Raises:
            KeyboardInterrupt: on SIGINT (the pending blocks are cancelled).
            OutputError: if a block cannot be saved.
        """
        if not self.todo:
            return
        plan = self.plan
        # a worker computes one block at a time: more workers than blocks would only be forked idle
        workers = max(1, min(workers, len(self.todo)))
        with (
            contextlib.nullcontext(pool)
            if pool is not None
            else make_executor(executor, workers, address, (type(plan.experiment).__module__,))
        ) as ex:
            # local workers are forked at the first submit (tasks.core.workers): before this
            # process starts a thread of its own (the bar's monitor, the report)
            data = to_plain(plan.scenario)
            futures = {
                ex.submit(
                    _run_block_in_worker,
                    plan.experiment.name,
                    data,
                    plan.seed,
                    plan.blocks[i],
                    run_folder.block_header(plan, i),
                ): i
                for i in self.todo
            }
            if isinstance(ex, InlineExecutor):
                # forked now, before this process starts a thread or builds a physics: the
                # other core is free while this process computes the blocks
                self.open_report_pool(1)
                self.start_report_pool()
            self.bar = self._progress_bar()
            if not isinstance(ex, InlineExecutor):
                # started once a worker has no block left (_save_as_finished): the cores are
                # busy until then
                self.open_report_pool(workers)
                self.overlapped = OverlappedReport(
                    plan, self.out_dir, self.progress, self.arrivals, self.report_pool
                )
            try:
                self._save_as_finished(futures)
            except KeyboardInterrupt:
                for f in futures:
                    f.cancel()
                raise

    def _save_as_finished(self, futures: dict[cf.Future, int]) -> None:
        plan = self.plan
        for fut in completed(futures):
            # forget the future once its block is handled: its result (the block) is then
            # freed, so memory does not grow with the batch
            i = futures.pop(fut)
            try:
                payload = fut.result()
            except Exception as exc:
                runs = plan.blocks[i]
                self.failures.append(
                    f"block {i} (runs {runs[0]}-{runs[-1]}): {type(exc).__name__}: {exc}"
                )
                continue
            try:
                run_folder.save_block(self.out_dir, i, payload)
            except OSError as exc:
                for f in futures:
                    f.cancel()
                raise _output_error(plan, self.out_dir, f"block {i}", exc) from None
            self.arrivals.saved(i)
            self.bar.update(len(plan.blocks[i]))
            if len(futures) < self.workers:  # a worker has no block left: a core is free
                self.start_report_pool()

    def close_bar(self) -> None:
        """Close the progress bar, if one was opened."""
        if self.bar is not None:
            self.bar.close()

    def stop(self, close_bar: bool) -> None:
        """The batch will not complete: close the bar (if asked), stop the overlapped report and
        the report's processes."""
        if close_bar:
            self.close_bar()
        if self.overlapped is not None:
            self.overlapped.abandon()
        if self.report_pool is not None:
            self.report_pool.close(stop=True)


def _write_report(
    plan: BatchPlan,
    out_dir: Path,
    progress: bool,
    overlapped: OverlappedReport | None,
    pool: ReportPool | None,
) -> ReportSummary:
    """The report of a batch whose blocks are all saved: the overlapped report's result, or
    :meth:`Experiment.report` over the saved blocks, in block order.

    Raises:
        BatchInterrupted: on SIGINT (the blocks are kept; ``--resume`` writes the report).
        OutputError: if a file of the report cannot be written.
    """

    def blocks() -> Iterator[Any]:
        for i in range(len(plan.blocks)):
            yield run_folder.load_block(plan, out_dir, i)

    try:
        if overlapped is not None:
            return overlapped.result()
        return plan.experiment.report(
            ReportContext(
                plan.scenario,
                plan.seed,
                plan.n_runs,
                out_dir,
                blocks(),
                quiet=not progress,
                pool=pool,
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


def _n_saved(plan: BatchPlan, out_dir: Path) -> int:
    return sum(run_folder.saved(out_dir, i) for i in range(len(plan.blocks)))


def _output_error(plan: BatchPlan, out_dir: Path, what: str, exc: OSError) -> OutputError:
    n_done = _n_saved(plan, out_dir)
    fix = "remove the link" if isinstance(exc, files.LinkInRunFolder) else "make room"
    return OutputError(
        f"cannot write {what} ({os_error_text(exc)}); {n_done} of {len(plan.blocks)} blocks are "
        f"saved in {out_dir}; {fix} and complete the batch with: bauv run "
        f"{plan.experiment.name} --resume --out {out_dir}"
    )


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
