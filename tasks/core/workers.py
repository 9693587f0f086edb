"""Local worker processes of the runner: how they start, and how they end.

On Linux a local worker is forked from ``bauv`` itself (start method ``fork``) when the pool is
opened: ``bauv`` has by then imported the runner and the experiment to plan the batch, so a worker
starts with them at no cost, and the runner opens the pool before it starts any thread of its own
(the progress bar's monitor, the overlapped report), so that a worker inherits no thread and no
lock held by one. Where ``fork`` is not safe, because the process already runs other threads
(the runner called from a threaded program) or the platform is not Linux, workers are forked from a
fork server (:mod:`multiprocessing.forkserver`) that imported the runner and the experiment's
package once (:func:`start_fork_server` starts it before ``bauv`` imports the project, so that it
imports it on another core meanwhile), and where there is no fork server they are spawned (a
fresh interpreter each). Measured on the project machine (2 cores, 10,000 passages of seed
000's straight-passage test 1, 5 paired runs): 1.69 s with forked workers against 1.82 s from
the fork server, which is ready only after its own interpreter start and imports (issue 13).

This module imports nothing heavy (no numpy, no pydantic; of the project only
:mod:`tasks.core.families`, which reads the entry points that say which package holds an
experiment, and only where a fork server is started), so that ``bauv run --workers K`` can start
a fork server first thing where one is used.

A process that computes blocks (a worker, or ``bauv`` itself on one worker) keeps the memory a
block frees for the next one (:func:`keep_freed_memory`), and ``bauv run`` has numpy leave
transparent huge pages alone (:func:`prepare_batch_process`): measured on the project machine (a
2-core VM), a fresh process's first block of seed 000's straight-passage test 1 (1,000
passages, ~150 MB of arrays) spent 0.4 s of kernel time faulting in huge pages, twice its
computing time, and every later block 0.03-0.2 s faulting in again the pages the previous one
had returned; with 4 KiB pages kept in the process, 0.06 s once and nothing after.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import MutableMapping, Sequence
from concurrent.futures import ProcessPoolExecutor

MMAP_THRESHOLD_B = 32 * 2**20
"""Allocations from this size up get their own mapping, returned to the system when freed (glibc
``M_MMAP_THRESHOLD``, its largest documented value on 64-bit); smaller ones, a block's arrays of
1,000 passages included, come from the heap."""

TRIM_THRESHOLD_B = 2**30
"""Free memory at the top of the heap kept for reuse rather than returned to the system (glibc
``M_TRIM_THRESHOLD``): a worker's heap stays at its peak (that of one block)."""

HUGEPAGE_VARIABLE = "NUMPY_MADVISE_HUGEPAGE"
"""numpy's switch for ``madvise(MADV_HUGEPAGE)`` on its large arrays, read when numpy is
imported; ``bauv run`` sets it to ``0`` unless it is set (:func:`prepare_batch_process`)."""

RUNNER_MODULE = "tasks.core.runner"
"""The module of the workers' entry point, preloaded by the fork server with the experiment's."""

PARENT_POLL_S = 0.5
"""How often a local worker checks that the ``bauv`` process that started it is alive, s."""


def usable_cpus() -> int:
    """The CPUs this process may run on: its affinity mask where the platform has one (a
    container's or ``taskset``'s limit), else :func:`os.cpu_count`; at least 1.

    ``bauv run --workers K`` takes at most this many local workers (each computes one block at
    a time on one CPU), and starts no more than the blocks it has to compute.
    """
    getaffinity = getattr(os, "sched_getaffinity", None)
    if getaffinity is not None:
        with contextlib.suppress(OSError):
            return max(1, len(getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def process_alive(pid: int) -> bool:
    """Whether a process exists (signal 0 delivers nothing, it only checks)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def fork_is_safe() -> bool:
    """Whether local workers can be forked from this process: on Linux, while it runs no thread
    but its main one (a forked child keeps only the thread that forked, and any lock another
    thread held stays held in it)."""
    return (
        sys.platform.startswith("linux")
        and "fork" in multiprocessing.get_all_start_methods()
        and threading.active_count() == 1
    )


def pool_context(preload: Sequence[str]) -> multiprocessing.context.BaseContext:
    """The start method of local workers: ``fork`` where :func:`fork_is_safe` (the worker starts
    with everything this process has imported), else ``forkserver`` with the runner and
    ``preload`` imported by the server where the platform has it, else ``spawn``.

    A spawned worker starts a fresh interpreter and imports the project again (about a second,
    issue 13); the fork server imports the preloaded modules once and forks each worker from
    itself.

    Args:
        preload: modules the fork server imports before it forks a worker (the experiment's
            package); used only when the server is not running yet.
    """
    if fork_is_safe():
        return multiprocessing.get_context("fork")
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload([RUNNER_MODULE, *preload])
        return ctx
    return multiprocessing.get_context("spawn")


def start_fork_server(name: str) -> None:
    """Start the local workers' fork server now, with the package of experiment ``name``'s family
    preloaded, so that it imports the project on another core while this process imports it and
    plans the batch. Nothing happens where workers will be forked from this process
    (:func:`fork_is_safe`), for an unknown family (the plan reports it), where there is no fork
    server, or when it is already running.

    Args:
        name: the experiment's registered name (``family/name``).
    """
    if fork_is_safe() or "forkserver" not in multiprocessing.get_all_start_methods():
        return
    from tasks.core.families import FamilyError, package_of

    try:
        package = package_of(name)
    except FamilyError:  # the plan reports it
        return
    if package is None:
        return
    from multiprocessing import forkserver

    pool_context((package,))
    with contextlib.suppress(OSError):
        forkserver.ensure_running()


def keep_freed_memory() -> bool:
    """Keep the memory a block frees in this process for the next block (glibc's ``mallopt``:
    :data:`MMAP_THRESHOLD_B`, :data:`TRIM_THRESHOLD_B`), instead of returning it to the system
    and faulting it in again (the heap then stays at the peak of one block).

    Returns:
        Whether both settings were applied (False off glibc, where nothing changes).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    m_trim_threshold, m_mmap_threshold = -1, -3  # <malloc.h>
    # both: either alone turns off glibc's own adjustment of the other
    return bool(mallopt(m_mmap_threshold, MMAP_THRESHOLD_B)) and bool(
        mallopt(m_trim_threshold, TRIM_THRESHOLD_B)
    )


def prepare_batch_process(environ: MutableMapping[str, str] | None = None) -> None:
    """Set up ``bauv run``'s process before it imports numpy: :data:`HUGEPAGE_VARIABLE` = ``0``
    unless the user set it (the fork server and its workers inherit it), and
    :func:`keep_freed_memory` (on one worker ``bauv`` computes the blocks itself).

    Args:
        environ: the environment to set it in (default :data:`os.environ`).
    """
    (os.environ if environ is None else environ).setdefault(HUGEPAGE_VARIABLE, "0")
    keep_freed_memory()


def init_worker(parent_pid: int) -> None:
    """Initializer of a local worker process: the default action of SIGTERM and SIGHUP
    (:func:`default_stop_signals`), :func:`keep_freed_memory`, then :func:`die_with_parent`.

    Args:
        parent_pid: pid of the process that created the pool.
    """
    default_stop_signals()
    keep_freed_memory()
    die_with_parent(parent_pid)


def default_stop_signals() -> None:
    """Give SIGTERM and SIGHUP their default action (the process ends) unless they are ignored.

    A worker forked from ``bauv`` inherits its handlers, which turn these signals into
    ``KeyboardInterrupt`` so that ``bauv`` keeps its finished blocks; in a worker that exception
    would be caught by the pool and sent back as the block's result, and the worker would live
    on, whereas the runner stops its workers with SIGTERM (:func:`terminate_workers`) and expects
    them to end. A signal ignored when ``bauv`` started (``nohup``) stays ignored.
    """
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) not in (signal.SIG_IGN, signal.SIG_DFL):
            signal.signal(sig, signal.SIG_DFL)


def die_with_parent(parent_pid: int) -> None:
    """Exit this worker process when the process that started it is gone.

    ``bauv`` may be stopped by a signal it cannot handle (SIGKILL); its workers must not go on
    computing blocks nobody will save (and keep the resource tracker alive with them). On Linux
    the kernel sends the worker SIGKILL when its parent dies (``PR_SET_PDEATHSIG``); everywhere a
    daemon thread also polls the parent's pid every :data:`PARENT_POLL_S` seconds.

    Args:
        parent_pid: pid of the process that created the pool.
    """
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            import ctypes

            # the process that forked this worker: bauv itself, or its fork server, which
            # exits when bauv does
            pr_set_pdeathsig = 1
            ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)
    if not process_alive(parent_pid):  # bauv died before the line above
        os._exit(1)

    def watch() -> None:
        while process_alive(parent_pid):
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="bauv-parent-watch", daemon=True).start()


def terminate_workers(ex: ProcessPoolExecutor) -> None:
    """Shut a process pool down and stop its workers now (their running blocks are lost)."""
    procs = list((getattr(ex, "_processes", None) or {}).values())
    ex.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.terminate()
    for proc in procs:
        with contextlib.suppress(Exception):
            proc.join(timeout=5)
