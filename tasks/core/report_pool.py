"""Processes that write parts of a batch's report beside ``bauv run``.

A report's figures and recording take longer than the rest of it (a survey mission's: three
figures about 2.5 s of CPU, the recording 1 s with its first imports, the run data and tables
0.4 s) and each is independent of the others. An experiment that says so
(:meth:`Experiment.report_work <tasks.core.registry.Experiment.report_work>`) gets a
:class:`ReportPool`: local processes started with the batch, which import the report's libraries
(matplotlib, rerun, ...) while the blocks are computed, on a core the computation leaves free,
and then take jobs of the report (:func:`offload`) while ``bauv`` writes the rest. A job reads
the batch's saved blocks from the run folder, in block order, as the report after a batch does
(:func:`tasks.core.run_folder.load_block`: size, sha256 and header checked; the blocks are plain
data, never pickled), and writes its files atomically within the run folder, so its outputs are
the same bytes as if ``bauv`` had written them itself (tested).

Where there is no pool (one usable CPU, no figures asked for, a report called directly) or a
report process died, the job runs in ``bauv`` itself; its outputs are the same.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import importlib
import os
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from bauv_sim.config import Config, to_plain, validate
from tasks.core import files, registry, run_folder
from tasks.core import workers as workers_mod
from tasks.core.plan import BatchPlan, memory_bytes, memory_limit_bytes
from tasks.core.registry import ReportWork

Job = Callable[..., Any]
"""A job of a report: ``job(scenario, blocks, out_dir, *args)``, a function at the top level of
a module (it is named, not sent), with ``blocks`` the batch's block results in block order (as
:meth:`Experiment.run_block <tasks.core.registry.Experiment.run_block>` returned them) and
``out_dir`` the run folder; it returns what the report needs (the names of the files it wrote)."""


def processes_for(work: ReportWork | None) -> int:
    """How many report processes to start: one per job, at most one per usable CPU
    (:func:`tasks.core.workers.usable_cpus`), none on a single CPU (a job would only share it
    with ``bauv``) or without work."""
    cpus = workers_mod.usable_cpus()
    if work is None or work.jobs < 1 or cpus < 2:
        return 0
    return min(work.jobs, cpus)


class ReportPool:
    """Local processes that take jobs of a batch's report (see the module docstring).

    They are started by :meth:`start` (or the first job), so that they import
    :attr:`ReportWork.preload` while the batch computes; each ends with ``bauv``
    (:func:`tasks.core.workers.init_worker`).

    Args:
        plan: the batch.
        out_dir: its run folder.
        work: the experiment's report work.
        processes: how many processes (>= 1).
    """

    def __init__(self, plan: BatchPlan, out_dir: Path, work: ReportWork, processes: int):
        self._plan_data = (
            plan.experiment.name,
            to_plain(plan.scenario),
            plan.seed,
            plan.n_runs,
            plan.blocks,
            plan.scenario_sha256,
        )
        self._out = Path(out_dir)
        self._preload = (type(plan.experiment).__module__, *work.preload)
        self._processes = processes
        self._ex: cf.ProcessPoolExecutor | None = None
        self._closed = False

    def start(self) -> None:
        """Start the processes now (once), so that they import their preload before the report
        hands them jobs: where the batch leaves a core free (this process computes the blocks
        itself, or a worker has no block left to compute)."""
        if self._ex is not None or self._closed:
            return
        ctx = workers_mod.pool_context(self._preload)
        # every process waits at the barrier in its first call, so that the pool starts them all
        # now: a pool that starts processes as calls come (fork server, spawn) could otherwise
        # hand the next call to the first one once it is idle (a guard: not seen measured)
        barrier = ctx.Barrier(self._processes)
        self._ex = cf.ProcessPoolExecutor(
            max_workers=self._processes,
            mp_context=ctx,
            initializer=_init_report_process,
            initargs=(os.getpid(), self._preload, barrier),
        )
        for _ in range(self._processes):
            self._ex.submit(_started)

    def submit(self, job: Job, args: tuple[Any, ...]) -> cf.Future:
        """Hand ``job(scenario, blocks, out_dir, *args)`` to a report process (started now if it
        was not).

        Raises:
            RuntimeError: if the pool is closed (a process of it died: :func:`offload` then runs
                the job in this process).
        """
        self.start()
        if self._ex is None:
            raise RuntimeError("the report pool is closed")
        return self._ex.submit(_run_job, self._plan_data, self._out, job, args)

    def pids(self) -> list[int]:
        """The process ids of the report processes started so far (none once closed)."""
        procs = getattr(self._ex, "_processes", None) or {}
        return sorted(p.pid for p in procs.values() if p.pid is not None)

    def close(self, stop: bool = False) -> None:
        """Let the processes end (after their jobs), or with ``stop`` end them now (the batch was
        interrupted or failed; a file they were writing is left as it was: each is written
        atomically)."""
        ex, self._ex, self._closed = self._ex, None, True
        if ex is None:
            return
        if stop:
            workers_mod.terminate_workers(ex)
        else:
            ex.shutdown(wait=True)


def report_pool(plan: BatchPlan, out_dir: Path, workers: int = 1) -> ReportPool | None:
    """A :class:`ReportPool` (not started) for a batch whose experiment hands out report work,
    or ``None`` (no work or one CPU: the report then does its jobs itself).

    It has :func:`processes_for` processes, fewer where the batch's memory would not allow them:
    each holds what the report holds (the terms of :meth:`Experiment.memory
    <tasks.core.registry.Experiment.memory>` that are not per block), on top of the batch's own
    estimate with ``workers`` processes computing blocks; the limit is
    :func:`tasks.core.plan.memory_limit_bytes`.
    """
    work = plan.experiment.report_work(plan.scenario)
    n = processes_for(work)
    if work is None or n == 0:
        return None
    terms = plan.experiment.memory(plan.scenario, plan.n_runs)
    limit = memory_limit_bytes()
    while n > 0 and memory_bytes(terms, workers, report_copies=1 + n) > limit:
        n -= 1
    if n == 0:
        return None
    return ReportPool(plan, out_dir, work, n)


class Offloaded:
    """A job handed to a report process (or run here), whose result the report waits for.

    Args:
        future: the job's future in the pool, or ``None`` when it ran here.
        rerun: runs the job in this process (when its process died).
        value: its result when it ran here.
    """

    def __init__(self, future: cf.Future | None, rerun: Callable[[], Any], value: Any = None):
        self._future, self._rerun, self._value = future, rerun, value

    def result(self) -> Any:
        """The job's result; its exception is raised here. A job whose process died (killed,
        out of memory) is run again in this process."""
        if self._future is None:
            return self._value
        try:
            return self._future.result()
        except cf.process.BrokenProcessPool:
            return self._rerun()


def offload(
    pool: ReportPool | None,
    job: Job,
    scenario: Config,
    blocks: Sequence[Any],
    out_dir: Path,
    *args: Any,
) -> Offloaded:
    """Run ``job(scenario, blocks, out_dir, *args)`` in a report process if there is a pool,
    else here and now.

    Args:
        pool: the batch's report pool (:attr:`ReportContext.pool
            <tasks.core.registry.ReportContext.pool>`) or ``None``.
        job: the job (see :data:`Job`).
        scenario: the batch's scenario, for a job run here.
        blocks: the block results as this process holds them, for a job run here (a report
            process reads them from the run folder).
        out_dir: the run folder.
        *args: the job's own arguments (plain values).

    Returns:
        The job, whose :meth:`Offloaded.result` waits for it.
    """

    def here() -> Any:
        return job(scenario, blocks, out_dir, *args)

    if pool is not None:
        try:
            return Offloaded(pool.submit(job, args), here)
        # closed, broken, or no process can be started here: this process does it
        except (RuntimeError, OSError, NotImplementedError, cf.process.BrokenProcessPool):
            pass
    return Offloaded(None, here, here())


# -- in a report process ------------------------------------------------------------------------


_BARRIER: Any = None
"""The pool's start barrier, in a report process."""

START_WAIT_S = 60.0
"""How long a report process waits for the others to start, s (then it goes on alone)."""


def _init_report_process(parent_pid: int, preload: Sequence[str], barrier: Any) -> None:
    global _BARRIER
    workers_mod.init_worker(parent_pid)
    for module in preload:
        importlib.import_module(module)
    _BARRIER = barrier


def _started() -> None:
    """The first call of each report process: it returns once every process of the pool has
    started and imported its preload (or after :data:`START_WAIT_S`)."""
    with contextlib.suppress(threading.BrokenBarrierError):
        _BARRIER.wait(START_WAIT_S)


_INPUTS: dict[tuple[str, str], tuple[Config, list[Any]]] = {}
"""The scenario and blocks a report process read, by run folder and scenario sha256: the jobs of
one batch in one process read them once."""


def _inputs(plan_data: tuple[Any, ...], out_dir: Path) -> tuple[Config, list[Any]]:
    name, scenario_data, seed, n_runs, blocks, sha = plan_data
    key = (os.path.abspath(out_dir), sha)
    if key not in _INPUTS:
        exp = registry.get(name)
        plan = BatchPlan(exp, validate(exp.scenario_type, scenario_data), seed, n_runs, blocks, sha)
        _INPUTS.clear()
        _INPUTS[key] = (
            plan.scenario,
            [run_folder.load_block(plan, out_dir, i) for i in range(len(plan.blocks))],
        )
    return _INPUTS[key]


def _run_job(plan_data: tuple[Any, ...], out_dir: Path, job: Job, args: tuple[Any, ...]) -> Any:
    scenario, blocks = _inputs(plan_data, out_dir)
    with files.confined(out_dir):
        return job(scenario, blocks, out_dir, *args)
