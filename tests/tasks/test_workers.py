"""Local worker processes: the memory a block frees is kept for the next block, and ``bauv run``
has numpy leave transparent huge pages alone unless told otherwise (issue 13: page faults were a
fixed cost of every block and a large one of every process's first block)."""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import platform
import resource
import subprocess
import sys

import numpy as np
import pytest

from tasks.core import workers
from tasks.core.runner import make_executor

glibc = pytest.mark.skipif(
    not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc",
    reason="mallopt of glibc",
)

SIZES = (3_000_000, 1_000_000, 500_000, 2_000_000)
"""The arrays of one synthetic block (float64: 24, 8, 4 and 16 MB), allocated and freed."""


def faults_per_round(rounds: int = 4) -> list[int]:
    """Minor page faults of this process while it allocates, fills and frees :data:`SIZES`,
    per round (the kernel's count, an independent witness of memory returned and taken again).
    """
    out = []
    for _ in range(rounds):
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        arrays = [np.ones(n) for n in SIZES]
        del arrays
        out.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
    return out


def _fresh_process(keep: bool) -> list[int]:
    code = (
        "import json\n"
        "from tasks.core import workers\n"
        "from tests.tasks.test_workers import faults_per_round\n"
        f"assert workers.keep_freed_memory() if {keep} else True\n"
        "print(json.dumps(faults_per_round()))\n"
    )
    res = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        env={**os.environ, workers.HUGEPAGE_VARIABLE: "0"},
    )
    return json.loads(res.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@glibc
def test_freed_memory_is_kept_for_the_next_block():
    """After :func:`keep_freed_memory` only the first round faults its pages in; without it
    every round does again (the control: the test can see the difference)."""
    kept, default = _fresh_process(True), _fresh_process(False)
    assert kept[0] > 2000 and default[0] > 2000, (kept, default)  # 4 KiB pages of ~50 MB
    assert max(kept[1:]) < 0.01 * kept[0], kept
    assert min(default[1:]) > 0.5 * default[0], default


@glibc
def test_local_workers_keep_freed_memory(tmp_path):
    """The pool's initializer applies it in every worker process: in each process only the
    first round of its first call faults pages in (one process may run both calls)."""
    with make_executor("local", 2, None, ("tests.tasks.test_workers",)) as ex:
        calls = [ex.submit(pid_and_faults) for _ in range(2)]
        per_process: dict[int, list[int]] = {}
        for fut in calls:  # in submission order, which is each process's order too
            pid, counts = fut.result(timeout=120)
            per_process.setdefault(pid, []).extend(counts)
    # the workers may back the arrays with transparent huge pages (numpy's madvise, decided when
    # the pool's process imported numpy): the first round then faults at least once per 2 MiB
    # page of the arrays (about 25), not once per 4 KiB page (about 12,700)
    first_min = sum(SIZES) * 8 // (2 * 1024**2)
    for counts in per_process.values():
        assert counts[0] >= first_min and max(counts[1:]) < 0.01 * counts[0], per_process


def pid_and_faults() -> tuple[int, list[int]]:
    """:func:`faults_per_round` in a worker, with the worker's pid."""
    return os.getpid(), faults_per_round()


def test_bauv_run_turns_numpy_huge_pages_off_unless_set():
    env: dict[str, str] = {}
    workers.prepare_batch_process(env)
    assert env == {workers.HUGEPAGE_VARIABLE: "0"}
    mine = {workers.HUGEPAGE_VARIABLE: "1"}
    workers.prepare_batch_process(mine)
    assert mine == {workers.HUGEPAGE_VARIABLE: "1"}


_START_PROBE = """
import json, signal, threading
from tasks.core.runner import make_executor

signal.signal(signal.SIGTERM, lambda *_: None)  # as bauv's own handler
signal.signal(signal.SIGHUP, signal.SIG_IGN)  # as under nohup
import tasks.paper000.passage  # bauv has imported the experiment to plan the batch
stop = threading.Event()
if {extra_thread}:
    threading.Thread(target=stop.wait, daemon=True).start()
with make_executor("local", 2, None, ("tasks.paper000",)) as ex:
    got = {{
        "context": ex._mp_context.get_start_method(),
        "sigterm": ex.submit(signal.getsignal, signal.SIGTERM).result().name,
        "sighup": ex.submit(signal.getsignal, signal.SIGHUP).result().name,
        "threads": ex.submit(threading.active_count).result(),
    }}
stop.set()
print(json.dumps(got))
"""


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork is used on Linux")
@pytest.mark.parametrize("extra_thread", [False, True], ids=["one thread", "two threads"])
def test_workers_are_forked_from_bauv_only_when_it_runs_one_thread(extra_thread):
    """A single-threaded ``bauv`` forks its workers (they start with what it imported); one that
    runs another thread uses the fork server (a forked child would keep that thread's locks).
    Either way a worker takes SIGTERM's default action (the runner stops workers with SIGTERM,
    which ``bauv``'s own handler would turn into an exception the pool catches) and keeps
    SIGHUP ignored under ``nohup``."""
    res = subprocess.run(
        [sys.executable, "-c", _START_PROBE.format(extra_thread=extra_thread)],
        capture_output=True,
        text=True,
        check=True,
    )
    got = json.loads(res.stdout.strip().splitlines()[-1])
    assert got["context"] == ("forkserver" if extra_thread else "fork"), got
    assert got["sigterm"] == "SIG_DFL" and got["sighup"] == "SIG_IGN", got
    assert got["threads"] == 2, got  # the worker's parent watch beside its main thread


TWELVE_SET = [
    "passage.duration_s=100",
    "passage.closest_approach_time_s=50",
    "report.figures=false",
    "report.recording=false",
    "runner.block_size=5",
]
"""Short passages in blocks of 5 runs."""


# ---------------------------------------------------------------------------------------------
# Workers: at most the CPUs, never more than the blocks (issue 21)


def test_more_workers_than_cpus_is_one_line_and_writes_nothing(tmp_path, capsys):
    from tasks.core import cli

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    out = tmp_path / "out"
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        cli.main(["run", "paper-000/test-1", "--runs", "4", "--workers", "999", "--out", str(out)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert info.value.code == 2 and len(lines) == 1, lines
    assert f"workers = 999: at most {cpus} on this machine" in lines[0], lines
    assert not out.exists()


@pytest.mark.parametrize(
    ("n_runs", "n_workers", "started"),
    [(5, 2, []), (12, 8, [3])],
    ids=["one-block-two-workers", "three-blocks-eight-workers"],
)
def test_no_more_workers_are_started_than_blocks(tmp_path, monkeypatch, n_runs, n_workers, started):
    """A one-block batch on 2 workers computes its block in this process (before the fix: a pool
    of 2, and 30 processes forked for ``--workers 30``); 3 blocks on 8 workers start 3."""
    from tasks.core import runner

    monkeypatch.setattr(workers, "usable_cpus", lambda: 8, raising=False)  # any machine
    pools = []
    real = cf.ProcessPoolExecutor

    class Counted(real):
        def __init__(self, max_workers=None, **kwargs):
            pools.append(max_workers)
            super().__init__(max_workers, **kwargs)

    monkeypatch.setattr(runner.cf, "ProcessPoolExecutor", Counted)
    out = tmp_path / "a"
    runner.run("paper-000/test-1", n_runs, 2, out, TWELVE_SET, workers=n_workers, progress=False)
    assert pools == started
    assert len(list((out / "blocks").glob("*.sha256"))) == -(-n_runs // 5)


@pytest.mark.parametrize(
    ("name", "preloaded"),
    [("paper-000/test-1", ["tasks.core.runner", "tasks.paper000"]), ("nofamily/x", None)],
)
def test_the_fork_server_preloads_the_package_that_declares_the_family(
    monkeypatch, name, preloaded
):
    """Where workers come from a fork server, bauv starts it first thing with the package that
    declares the name's family (an entry point) preloaded; an undeclared family starts none."""
    import multiprocessing
    from multiprocessing import forkserver

    monkeypatch.setattr(workers, "fork_is_safe", lambda: False)
    monkeypatch.setattr(multiprocessing, "get_all_start_methods", lambda: ["fork", "forkserver"])
    started, preload = [], []
    monkeypatch.setattr(forkserver, "ensure_running", lambda: started.append(True))
    ctx = multiprocessing.get_context("forkserver")
    monkeypatch.setattr(ctx, "set_forkserver_preload", preload.append)
    workers.start_fork_server(name)
    assert preload == ([] if preloaded is None else [preloaded])
    assert started == ([] if preloaded is None else [True])
