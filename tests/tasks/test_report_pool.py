"""The report's processes (``tasks.core.report_pool``): a mission report whose figures and
recording are written by two other processes equals, byte for byte (the recording: entry for
entry), the report written by ``bauv`` alone; a report process that dies leaves its job to
``bauv``; a job's error reaches ``bauv run`` as the report's; no process outlives the batch."""

import concurrent.futures as cf
import os
import signal
import time

import numpy as np
import pytest
import rerun.chunk as rc

from tasks.core import report_pool, runner
from tasks.core import workers as workers_mod
from tasks.core.errors import OutputError
from tasks.core.registry import ReportWork
from tasks.core.runner import run

SHORT = "mission/short"
OVERRIDES = ["timing.max_duration_s=40"]
# the run's record and provenance hold the time and the machine; a recording's chunks their ids
# and the time they were logged at
NOT_COMPARED = {"run.json", "provenance.json", "recording.rrd"}

pytestmark = pytest.mark.skipif(
    workers_mod.usable_cpus() < 2, reason="report processes are started on two CPUs or more"
)


def recording_entries(path):
    """Every chunk of a recording as ``(entity, static, {column: values})`` without the columns
    that name the chunk or hold the time it was logged at (and the recording's start time),
    sorted."""
    out = []
    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        rb = chunk.to_record_batch()
        cols = {
            n: rb.column(n).to_pylist()
            for n in rb.schema.names
            if not any(k in n for k in ("RowId", "row_id", "log_time", "start_time"))
        }
        out.append((chunk.entity_path, chunk.is_static, repr(sorted(cols.items()))))
    return sorted(out)


def folder_files(out):
    return {p.relative_to(out).as_posix(): p for p in out.rglob("*") if p.is_file()}


def assert_same_report(a, b):
    fa, fb = folder_files(a), folder_files(b)
    assert sorted(fa) == sorted(fb)
    for rel in sorted(set(fa) - NOT_COMPARED):
        assert fa[rel].read_bytes() == fb[rel].read_bytes(), rel
    assert recording_entries(fa["recording.rrd"]) == recording_entries(fb["recording.rrd"])


@pytest.fixture(scope="module")
def alone(tmp_path_factory):
    """The report written by bauv alone (no report process)."""
    out = tmp_path_factory.mktemp("alone") / "run"
    mp = pytest.MonkeyPatch()
    mp.setattr(report_pool, "processes_for", lambda work: 0)
    try:
        _, summary = run(SHORT, seed=2, out_dir=out, overrides=OVERRIDES, progress=False)
    finally:
        mp.undo()
    return out, summary


def same_summary(a, out_a, b, out_b):
    """Two report summaries equal but for the run folder they name."""
    return (a.files, a.failures, a.text.replace(str(out_a), "OUT")) == (
        b.files,
        b.failures,
        b.text.replace(str(out_b), "OUT"),
    )


def spy_submits(monkeypatch):
    calls = []
    submit = report_pool.ReportPool.submit

    def spy(self, job, args):
        calls.append((job.__name__, args))
        return submit(self, job, args)

    monkeypatch.setattr(report_pool.ReportPool, "submit", spy)
    return calls


@pytest.mark.slow
def test_the_report_processes_write_what_bauv_writes_alone(alone, tmp_path, monkeypatch):
    calls = spy_submits(monkeypatch)
    pids = before_the_report(monkeypatch, lambda out_dir, pool: None)
    out = tmp_path / "run"
    _, summary = run(SHORT, seed=2, out_dir=out, overrides=OVERRIDES, progress=False)
    # the jobs went to the report processes: the figures in two groups, the recording with one,
    # the run data of the last (only) block
    assert calls == [
        ("_figures_and_recording", ("mission/short", (("route", "state"), False))),
        ("_figures_and_recording", ("mission/short", (("errors",), True))),
        ("_export_block", ("mission/short", 0)),
    ]
    # the same files in the same order, the same text
    assert same_summary(summary, out, alone[1], alone[0])
    assert_same_report(alone[0], out)
    # the files are listed as bauv alone lists them: the figures in their order, then the
    # recording
    figs = [f for f in summary.files if f.endswith((".png", ".pdf", ".rrd"))]
    assert figs == [
        "route.png",
        "route.pdf",
        "errors.png",
        "errors.pdf",
        "state.png",
        "state.pdf",
        "recording.rrd",
    ]
    assert len(pids) == 2 and gone(pids)  # the report processes ended with the batch


@pytest.mark.slow
def test_with_two_workers_the_report_processes_start_once_a_core_is_free(tmp_path, monkeypatch):
    a, b = tmp_path / "one", tmp_path / "two"
    args = {"n_runs": 3, "seed": 2, "overrides": OVERRIDES, "progress": False}
    with monkeypatch.context() as m:
        m.setattr(report_pool, "processes_for", lambda work: 0)
        _, alone_summary = run(SHORT, out_dir=a, **args)
    calls = spy_submits(monkeypatch)
    started = []
    start = report_pool.ReportPool.start

    def spy_start(self):
        started.append(sorted(p.name for p in (b / "blocks").glob("block-*.sha256")))
        return start(self)

    monkeypatch.setattr(report_pool.ReportPool, "start", spy_start)
    pids = before_the_report(monkeypatch, lambda out_dir, pool: None)
    _, summary = run(SHORT, out_dir=b, workers=2, **args)
    assert len(pids) == 2 and gone(pids)  # both started (from a fork server: threads run here)
    # three blocks of one run on two workers: started once the second block was saved (one
    # block left, a worker idle), not while both workers computed
    assert len(started[0]) == 2, started
    assert [name for name, _ in calls] == ["_figures_and_recording"] * 2 + ["_export_block"]
    assert same_summary(summary, b, alone_summary, a)
    assert_same_report(a, b)


def before_the_report(monkeypatch, action):
    """Run ``action(out_dir, pool)`` in this process when the report starts (the blocks are
    saved and the report processes started); returns the pids of the report processes."""
    write_report = runner._write_report
    pids = []

    def patched(plan, out_dir, progress, overlapped, pool):
        pids.extend(pool.pids() if pool is not None else [])
        action(out_dir, pool)
        return write_report(plan, out_dir, progress, overlapped, pool)

    monkeypatch.setattr(runner, "_write_report", patched)
    return pids


def kill_report_processes(out_dir, pool):
    pids = pool.pids()
    assert len(pids) == 2, "the report processes were not started"
    for pid in pids:
        os.kill(pid, signal.SIGKILL)
    while any(workers_mod.process_alive(pid) and not reaped(pid) for pid in pids):
        time.sleep(0.01)


def reaped(pid):
    """Whether a killed child is gone or a zombie (its parent has not waited for it yet)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(") ")[-1].startswith("Z")
    except FileNotFoundError:
        return True


def gone(pids):
    return not [p for p in pids if workers_mod.process_alive(p) and not reaped(p)]


@pytest.mark.slow
def test_a_report_process_that_dies_leaves_its_job_to_bauv(alone, tmp_path, monkeypatch):
    pids = before_the_report(monkeypatch, kill_report_processes)
    out = tmp_path / "run"
    _, summary = run(SHORT, seed=2, out_dir=out, overrides=OVERRIDES, progress=False)
    assert same_summary(summary, out, alone[1], alone[0])
    assert_same_report(alone[0], out)
    assert len(pids) == 2 and gone(pids)


def block_the_route_figure(out_dir, pool):
    (out_dir / "route.png" / "taken").mkdir(parents=True)


@pytest.mark.slow
def test_a_job_that_cannot_write_fails_the_report_naming_the_batch(tmp_path, monkeypatch):
    calls = spy_submits(monkeypatch)
    # route.png cannot be written (a folder holds its place): the report process's OSError
    pids = before_the_report(monkeypatch, block_the_route_figure)
    out = tmp_path / "run"
    with pytest.raises(OutputError, match=r"cannot write the report .*route\.png.*--resume"):
        run(SHORT, seed=2, out_dir=out, overrides=OVERRIDES, progress=False)
    assert calls, "the jobs were not handed to the report processes"
    assert len(pids) == 2 and gone(pids)
    assert (out / "blocks").is_dir()  # the computed block is kept for --resume


def test_one_process_per_job_and_per_usable_cpu(monkeypatch):
    work = ReportWork(2, ("numpy",))
    for cpus, want in ((1, 0), (2, 2), (8, 2)):
        monkeypatch.setattr(workers_mod, "usable_cpus", lambda cpus=cpus: cpus)
        assert report_pool.processes_for(work) == want
    assert report_pool.processes_for(None) == 0
    assert report_pool.processes_for(ReportWork(0)) == 0


@pytest.mark.slow
def test_no_report_process_where_the_memory_would_not_allow_it(alone, tmp_path, monkeypatch):
    from tasks.core import plan as plan_mod
    from tasks.core.plan import plan_batch

    # the limit just above what the batch needs with bauv alone: no room for a report process
    p = plan_batch(SHORT, seed=2, overrides=OVERRIDES)
    terms = p.experiment.memory(p.scenario, p.n_runs)
    alone_b = sum(t.bytes for t in terms)
    report_b = sum(t.bytes for t in terms if not t.per_block)
    assert report_b > 0
    monkeypatch.setattr(report_pool, "memory_limit_bytes", lambda: alone_b + 1.5 * report_b)
    monkeypatch.setattr(plan_mod, "memory_limit_bytes", lambda: alone_b + 1.5 * report_b)
    pids = before_the_report(monkeypatch, lambda out_dir, pool: None)
    out = tmp_path / "run"
    _, summary = run(SHORT, seed=2, out_dir=out, overrides=OVERRIDES, progress=False)
    assert len(pids) == 1  # one report process fits, not two
    assert same_summary(summary, out, alone[1], alone[0])
    assert_same_report(alone[0], out)


def add(scenario, blocks, out_dir, a, b):
    return float(np.sum(blocks[0])) + a + b


def test_offload_without_a_pool_runs_the_job_here(tmp_path):
    job = report_pool.offload(None, add, None, [np.arange(4.0)], tmp_path, 1.0, 2.0)
    assert job.result() == 9.0


def test_a_job_of_a_broken_pool_runs_here(tmp_path):
    class Broken:
        def submit(self, job, args):
            future = cf.Future()
            future.set_exception(cf.process.BrokenProcessPool("gone"))
            return future

    job = report_pool.offload(Broken(), add, None, [np.arange(4.0)], tmp_path, 1.0, 2.0)
    assert job.result() == 9.0
