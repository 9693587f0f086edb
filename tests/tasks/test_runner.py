"""Same seed, same numbers, bit for bit: repeated, on 1 or N workers, on Dask, after a resume."""

import concurrent.futures as cf
import hashlib
import itertools
import json
import os
import pathlib
import pickle
import shutil
import signal
import subprocess
import sys
import threading
import time

import pytest

from tasks.core.runner import run

SMALL = ["report.figures=false", "report.recording=false", "runner.block_size=7"]


def _bytes(out):
    return (out / "metrics.json").read_bytes()


def _batch(out, seed=5, **executor):
    run(
        "paper-000/test-2",
        n_runs=30,
        seed=seed,
        out_dir=out,
        overrides=SMALL,
        progress=False,
        **executor,
    )
    return _bytes(out)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return _batch(tmp_path_factory.mktemp("ref") / "run")


@pytest.mark.slow
@pytest.mark.parametrize(
    "executor",
    [{}, {"workers": 2}, {"executor": "dask", "workers": 2}],
    ids=["same-seed-again", "two-local-workers", "local-dask-cluster"],
)
def test_same_seed_is_bit_identical_whatever_the_executor(reference, tmp_path, executor):
    if executor.get("executor") == "dask":
        pytest.importorskip("distributed")
    assert _batch(tmp_path / "a", **executor) == reference


def test_different_seed_differs(reference, tmp_path):
    assert _batch(tmp_path / "a", seed=6) != reference


def _resume_in_a_process(out, *extra):
    """``bauv run paper-000/test-1 --resume --out OUT`` as a real CLI process."""
    cmd = [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1", "--resume"]
    return subprocess.run(
        [*cmd, "--out", str(out), *extra], capture_output=True, text=True, check=False
    )


@pytest.mark.slow
def test_interrupted_batch_resumes_to_the_same_result(tmp_path):
    args = [
        "paper-000/test-1",
        "--runs",
        "1000",
        "--seed",
        "2",
        "--quiet",
        "--set",
        "report.figures=false",
        "--set",
        "report.recording=false",
        "--set",
        "runner.block_size=10",
    ]
    straight = tmp_path / "straight"
    subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", *args, "--out", str(straight)],
        check=True,
        capture_output=True,
    )
    out = tmp_path / "interrupted"
    proc = subprocess.Popen(
        [sys.executable, "-m", "tasks.core.cli", "run", *args, "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a shell may start the test runner with SIGINT ignored; the child must see Ctrl-C
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.time() + 60
    while time.time() < deadline:
        blocks = out / "blocks"
        if blocks.is_dir() and len(list(blocks.glob("block-*.sha256"))) >= 5:
            break
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "--resume" in err and "Traceback" not in err
    assert not (out / "metrics.json").exists()
    assert json.loads((out / "run.json").read_text())["state"] == "incomplete"
    n_saved = len(list((out / "blocks").glob("block-*.sha256")))
    assert 5 <= n_saved < 100
    res = _resume_in_a_process(out, "--quiet")
    assert res.returncode == 0, res.stderr
    assert json.loads((out / "run.json").read_text())["state"] == "complete"
    assert _bytes(out) == _bytes(straight)


# ---------------------------------------------------------------------------------------------
# --resume refuses a folder that was changed, damaged or mixed with another batch


RESUME_SET = [
    "passage.duration_s=100",
    "passage.closest_approach_time_s=50",
    "report.figures=false",
    "report.recording=false",
    "runner.block_size=5",
]


def _interrupted(out, seed):
    """A finished 12-run batch (3 blocks) made to look interrupted before its last block."""
    run("paper-000/test-1", 12, seed, out, RESUME_SET, progress=False)
    metrics = _bytes(out)
    for name in ("block-000002.zip", "block-000002.sha256"):
        (out / "blocks" / name).unlink()
    for f in [*out.glob("*.md"), out / "metrics.json", *out.glob("tables/*")]:
        f.unlink()
    _edit_record(out, state="incomplete")  # as the runner writes it before the report
    return metrics


@pytest.fixture(scope="module")
def batches(tmp_path_factory):
    root = tmp_path_factory.mktemp("resume")
    return {
        "metrics": _interrupted(root / "seed2", 2),
        "seed2": root / "seed2",
        "seed3": root / "seed3",
        "metrics3": _interrupted(root / "seed3", 3),
    }


def _snapshot(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _resume(out, capsys, *extra):
    from tasks.core import cli

    capsys.readouterr()
    try:
        cli.main(["run", "paper-000/test-1", "--resume", "--out", str(out), "--quiet", *extra])
        code = 0
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


def _flip_block_byte(out, other):
    path = out / "blocks" / "block-000001.zip"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))


def _sidecar(path):
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    path.with_suffix(".sha256").write_text(f"{digest}  {path.name}\n")


def _pickle_block(out, other):
    path = out / "blocks" / "block-000000.zip"
    path.write_bytes(pickle.dumps(_Touch(out.parent / f"pwned-{out.name}")))
    _sidecar(path)  # its digest recorded too: only the format stops it


def _block_of_another_seed(out, other):
    for name in ("block-000000.zip", "block-000000.sha256"):
        shutil.copy(other / "blocks" / name, out / "blocks" / name)


def _block_of_another_index(out, other):
    path = out / "blocks" / "block-000000.zip"
    shutil.copy(out / "blocks" / "block-000001.zip", path)
    _sidecar(path)


def _truncated_block(out, other):
    path = out / "blocks" / "block-000001.zip"
    path.write_bytes(path.read_bytes()[:100])
    _sidecar(path)  # its digest recorded too: only the decoding stops it


def _garbage_sidecar(out, other):
    (out / "blocks" / "block-000001.sha256").write_text("not a digest\n")


def _edit_scenario(out, other):
    with (out / "scenario.toml").open("a") as fh:
        fh.write("# edited\n")


def _scenario_with_another_layout(out, other):
    path = out / "scenario.toml"
    path.write_text(path.read_text().replace("block_size = 5", "block_size = 4"))
    _edit_record(out, scenario_sha256=hashlib.sha256(path.read_bytes()).hexdigest())


def _deep_scenario(out, other):
    # a hostile scenario.toml with run.json forged to match it: tomllib would recurse 5,000 deep
    path = out / "scenario.toml"
    path.write_text(path.read_text() + "deep = " + "[" * 5000 + "]" * 5000 + "\n")
    _edit_record(out, scenario_sha256=hashlib.sha256(path.read_bytes()).hexdigest())


def _record_digest(record):
    """sha256 of run.json's fields but ``record_sha256``, as documented: their JSON with sorted
    keys, no spaces, ASCII escapes."""
    fields = {k: v for k, v in record.items() if k != "record_sha256"}
    text = json.dumps(fields, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _edit_record(out, sign=True, **fields):
    """Change fields of ``run.json``; with ``sign`` its ``record_sha256`` is made theirs (a forged
    record: the checks behind the digest must still refuse it)."""
    path = out / "run.json"
    record = {**json.loads(path.read_text()), **fields}
    record = {k: v for k, v in record.items() if v is not _DROP}
    if sign and "record_sha256" in record:
        record["record_sha256"] = _record_digest(record)
    path.write_text(json.dumps(record))


_DROP = object()


def _record(text):
    def tamper(out, other):
        (out / "run.json").write_bytes(text if isinstance(text, bytes) else text.encode())

    return tamper


def _truncated_record(out, other):
    path = out / "run.json"
    path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])


def _fields(**fields):
    return lambda out, other: _edit_record(out, **fields)


def _edited(**fields):
    """``run.json`` edited by hand (its ``record_sha256`` left as it was)."""

    def tamper(out, other):
        _edit_record(out, sign=False, **fields)

    tamper.__name__ = "edited_" + "_".join(fields)
    return tamper


class _Touch:
    """A pickle payload that creates a file when it is unpickled."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return (pathlib.Path.touch, (self.path,))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("tamper", "fragment"),
    [
        (_flip_block_byte, "block-000001.zip': its sha256 is"),
        (_pickle_block, "block-000000.zip': not a bauv-sim/plain-data file"),
        (_block_of_another_seed, "header says seed = 3 but this batch has 2"),
        (_block_of_another_index, "header says block = 1 but this batch has 0"),
        (_truncated_block, "block-000001.zip': not a bauv-sim/plain-data file"),
        (_garbage_sidecar, "block-000001.sha256': not a line"),
        (_record(b"\xff\xfe{"), "is not valid JSON"),
        (_edit_scenario, "scenario.toml' was changed since the batch started"),
        (_scenario_with_another_layout, "block_size = 5 but the scenario's runner gives"),
        (_deep_scenario, "nested more than 32 deep at line"),
        (_record("{ this is not json"), "is not valid JSON"),
        (_truncated_record, "is not valid JSON"),
        (_record("[1, 2]"), "is not a JSON object"),
        (_fields(scenario_sha256=_DROP), "field 'scenario_sha256' is missing"),
        (_fields(seed="2"), "seed = '2': must be an integer"),
        (_fields(n_runs=True), "n_runs = True: must be an integer"),
        (_fields(block_size=5.0), "block_size = 5.0: must be an integer"),
        (_fields(n_blocks=2), "n_blocks = 2 but 12 runs in blocks of 5 make 3"),
        (_fields(scenario_sha256="abc"), "scenario_sha256 = 'abc': not a sha256"),
        (_fields(format_version=1), "format_version = 1"),
        (_fields(state="done"), "state = 'done'"),
        (_fields(record_sha256=_DROP), "field 'record_sha256' is missing"),
        # 15 runs in blocks of 5 are still 3 blocks, and block 2 is not saved: without a digest
        # of run.json the batch would silently grow to 15 runs (issue 21)
        (_edited(n_runs=15), "run.json' was changed since the batch started"),
        (_edited(seed=3), "run.json' was changed since the batch started"),
        (_edited(state="complete"), "run.json' was changed since the batch started"),
    ],
    ids=lambda v: getattr(v, "__name__", None) if callable(v) else None,
)
def test_resume_refuses_a_changed_or_mixed_folder(batches, tmp_path, capsys, tamper, fragment):
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    tamper(out, batches["seed3"])
    before = _snapshot(out)
    code, err = _resume(out, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith("error: --resume: ") and fragment in lines[0], err
    assert _snapshot(out) == before  # nothing written
    assert not (tmp_path / "pwned-batch").exists()  # nothing unpickled


def test_resume_refuses_another_seed(batches, tmp_path, capsys):
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    code, err = _resume(out, capsys, "--seed", "9")
    assert code == 2 and "seed = 9 but the batch was started with 2" in err


def test_untouched_folder_resumes_to_the_straight_result(batches, tmp_path, capsys):
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    code, err = _resume(out, capsys)
    assert code == 0, err
    assert _bytes(out) == batches["metrics"]
    assert json.loads((out / "run.json").read_text())["state"] == "complete"


@pytest.mark.slow
def test_resume_refusal_from_the_command_line(batches, tmp_path):
    """The real CLI process: one line on stderr, exit status 2, no traceback."""
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    _flip_block_byte(out, None)
    res = _resume_in_a_process(out)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "its sha256 is" in lines[0] and "Traceback" not in res.stderr


def test_a_block_without_its_sha256_is_computed_again(batches, tmp_path, capsys):
    """A crash between writing a block and its sha256 leaves it unsaved: --resume redoes it, and
    the same block encodes to the same bytes."""
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    block = out / "blocks" / "block-000001.zip"
    original = block.read_bytes()
    (out / "blocks" / "block-000001.sha256").unlink()
    block.write_bytes(b"half-written")
    code, err = _resume(out, capsys)
    assert code == 0, err
    assert block.read_bytes() == original
    assert _bytes(out) == batches["metrics"]


def test_one_worker_saves_each_block_as_it_finishes(reference, tmp_path, monkeypatch):
    """``--workers 1`` (the inline executor) computes the blocks one by one in the save loop: a
    Ctrl-C during the fourth block keeps the three finished ones, and ``--resume`` completes the
    batch to the same bytes as a batch run straight through."""
    from tasks.core import runner

    real = runner._run_block_in_worker
    calls = []

    def interrupt_fourth(*args):
        calls.append(args[3])
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(runner, "_run_block_in_worker", interrupt_fourth)
    out = tmp_path / "a"
    with pytest.raises(runner.BatchInterrupted, match="3 of 5 blocks are saved"):
        _batch(out)
    assert sorted(p.name for p in (out / "blocks").glob("*.sha256")) == [
        f"block-00000{i}.sha256" for i in range(3)
    ]
    monkeypatch.setattr(runner, "_run_block_in_worker", real)
    run("paper-000/test-2", seed=5, out_dir=out, resume=True, progress=False)
    assert _bytes(out) == reference


class _Handshake(cf.Executor):
    """Worker processes played by a thread that computes the blocks in order and starts block
    ``k`` only once the report has read block ``k - 1`` (or :data:`HANDSHAKE_WAIT_S` passed)."""

    def __init__(self, read, log):
        self._calls = []
        self._read, self._log = read, log
        self._thread = threading.Thread(target=self._work, daemon=True)

    def submit(self, fn, /, *args, **kwargs):
        fut = cf.Future()
        self._calls.append((fut, fn, args))
        if len(self._calls) == 1:
            self._thread.start()
        return fut

    def _work(self):
        deadline = time.monotonic() + HANDSHAKE_WAIT_S
        for k in itertools.count():
            while k >= len(self._calls):
                time.sleep(0.001)
            fut, fn, args = self._calls[k]
            if k > 0:
                self._read[k - 1].wait(max(0.0, deadline - time.monotonic()))
            self._log.append(("compute", k))
            fut.set_running_or_notify_cancel()
            fut.set_result(fn(*args))
            if k == N_HANDSHAKE_BLOCKS - 1:
                return


HANDSHAKE_WAIT_S = 10.0
N_HANDSHAKE_BLOCKS = 5


def _planned(out, seed=5):
    from tasks.core import runner

    plan = runner.plan_batch("paper-000/test-2", 30, seed, SMALL)
    assert len(plan.blocks) == N_HANDSHAKE_BLOCKS
    runner.prepare_out_dir(plan, out)
    return plan


def test_the_report_merges_each_block_while_the_next_ones_are_computed(
    reference, tmp_path, monkeypatch
):
    """With worker processes the report reads block ``k`` (in block order) before block ``k + 1``
    is computed: its merge overlaps the batch instead of following it (issue 13); the metrics
    are the bytes of the one-worker batch."""
    from tasks.core import run_folder, runner

    log, read = [], [threading.Event() for _ in range(N_HANDSHAKE_BLOCKS)]
    real_load = run_folder.load_block

    def load(plan, out_dir, index):
        log.append(("read", index))
        read[index].set()
        return real_load(plan, out_dir, index)

    monkeypatch.setattr(run_folder, "load_block", load)
    out = tmp_path / "a"
    runner.execute(_planned(out), out, progress=False, pool=_Handshake(read, log))
    assert _bytes(out) == reference
    for k in range(1, N_HANDSHAKE_BLOCKS):
        assert log.index(("read", k - 1)) < log.index(("compute", k)), log
    assert [i for what, i in log if what == "read"] == list(range(N_HANDSHAKE_BLOCKS))


class _Synchronous(cf.Executor):
    """Worker processes played by the calling thread, at submission (not the inline executor)."""

    def submit(self, fn, /, *args, **kwargs):
        fut = cf.Future()
        fut.set_running_or_notify_cancel()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:
            fut.set_exception(exc)
        return fut


def _report_threads():
    return [t for t in threading.enumerate() if t.name == "bauv-report"]


@pytest.mark.parametrize("fault", ["block-raises", "interrupted"])
def test_a_batch_that_cannot_complete_stops_its_overlapped_report(tmp_path, monkeypatch, fault):
    """A block that raises (or a Ctrl-C while blocks are saved) on worker processes: the
    finished blocks are kept, no report is written, and the report's thread is gone."""
    from tasks.core import run_folder, runner

    if fault == "block-raises":
        real = runner._run_block_in_worker

        def third_raises(*args):
            if args[3][0] == 14:
                raise RuntimeError("block 2 broke")
            return real(*args)

        monkeypatch.setattr(runner, "_run_block_in_worker", third_raises)
        expected = runner.BatchFailed
    else:
        real_save, saves = run_folder.save_block, []

        def interrupt_third(out_dir, index, payload):
            saves.append(index)
            if len(saves) == 3:
                raise KeyboardInterrupt
            real_save(out_dir, index, payload)

        monkeypatch.setattr(run_folder, "save_block", interrupt_third)
        expected = runner.BatchInterrupted
    out = tmp_path / "a"
    with pytest.raises(expected):
        runner.execute(_planned(out), out, progress=False, pool=_Synchronous())
    assert not _report_threads()
    assert not (out / "metrics.json").exists()
    assert json.loads((out / "run.json").read_text())["state"] == "incomplete"
    saved = sorted(p.name for p in (out / "blocks").glob("*.sha256"))
    if fault == "block-raises":  # every block that did not fail
        assert saved == [f"block-00000{i}.sha256" for i in (0, 1, 3, 4)]
    else:  # the two saved before the Ctrl-C (the blocks finish in any order)
        assert saved == sorted(f"block-00000{i}.sha256" for i in saves[:2])


@pytest.mark.parametrize("umask", [0o022, 0o027])
def test_run_folder_files_honour_the_umask(tmp_path, umask):
    """Every file the runner, the report and the Parquet export write has mode 0o666 & ~umask,
    as files made by ``open`` (atomically written files were 0o600 while the PNGs were 0o644)."""
    import numpy as np

    from tasks.core.export import Column, write_parquet

    previous = os.umask(umask)
    try:
        _batch(tmp_path / "a")
        write_parquet(
            tmp_path / "a" / "data" / "x.parquet",
            {"t_s": Column(np.arange(3.0), "s", "time")},
            {"experiment": "x"},
        )
    finally:
        os.umask(previous)
    files = [p for p in (tmp_path / "a").rglob("*") if p.is_file()]
    assert {"run.json", "scenario.toml", "metrics.json", "x.parquet"} <= {p.name for p in files}
    assert any(p.suffix == ".sha256" for p in files) and any(p.suffix == ".zip" for p in files)
    modes = {str(p.relative_to(tmp_path)): oct(p.stat().st_mode & 0o777) for p in files}
    assert set(modes.values()) == {oct(0o666 & ~umask)}, modes
    assert not [p for p in (tmp_path / "a").rglob(".*.tmp")]


def _alive(procs):
    psutil = pytest.importorskip("psutil")
    out = []
    for p in procs:
        try:
            if p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except psutil.NoSuchProcess:
            pass
    return out


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_workers_die_with_bauv(tmp_path, sig):
    """``bauv run --workers 2`` stopped by SIGTERM (handled: blocks kept, exit 130) or SIGKILL
    (not handled) leaves no worker (nor resource tracker, where one runs) running."""
    psutil = pytest.importorskip("psutil")
    args = ["paper-000/test-1", "--runs", "4000", "--workers", "2", "--quiet"]
    args += ["--set=report.figures=false", "--set=report.recording=false"]
    args += ["--set=runner.block_size=10", "--out", str(tmp_path / "out")]
    # output to a file, not a pipe: orphaned workers would hold a pipe open
    with (tmp_path / "stderr.txt").open("w") as err_file:
        proc = subprocess.Popen(
            [sys.executable, "-m", "tasks.core.cli", "run", *args],
            stdout=subprocess.DEVNULL,
            stderr=err_file,
        )
    parent = psutil.Process(proc.pid)
    children = []
    try:
        deadline = time.time() + 60
        while time.time() < deadline:
            children = parent.children(recursive=True)
            if len(children) >= 2 and (tmp_path / "out" / "blocks").is_dir():
                break  # two workers (and a resource tracker where one is used), work under way
            time.sleep(0.1)
        assert len(children) >= 2, children
        os.kill(proc.pid, sig)
        proc.wait(timeout=60)
        deadline = time.time() + 20
        while _alive(children) and time.time() < deadline:
            time.sleep(0.2)
        left = _alive(children)
        assert not left, [p.cmdline() for p in left]
    finally:
        for p in _alive(children):  # a failing run must not leave them behind either
            p.kill()
        if proc.poll() is None:
            proc.kill()
    err = (tmp_path / "stderr.txt").read_text()
    if sig == signal.SIGTERM:
        assert proc.returncode == 130 and "--resume" in err and "Traceback" not in err, err


def test_a_reformatted_run_json_still_resumes(batches, tmp_path, capsys):
    """The digest covers run.json's fields, not its layout: re-indented, it resumes."""
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    record = json.loads((out / "run.json").read_text())
    (out / "run.json").write_text(json.dumps(record, indent=8, sort_keys=True))
    code, err = _resume(out, capsys)
    assert code == 0, err
    assert _bytes(out) == batches["metrics"]


# ---------------------------------------------------------------------------------------------
# A block file is bounded by what a block of the batch can hold, and hashed in chunks (issue 21)


def _sparse(path, size):
    """Make ``path`` ``size`` bytes long without writing them (a hole)."""
    with path.open("r+b") as fh:
        fh.truncate(size)


def _block_file_limit_b():
    """The ceiling of a block file of the ``batches`` fixture, by the documented rule: 64 MiB,
    1 MiB per run of the largest block, 8x the per-block terms of the memory estimate."""
    from tasks.core import runner

    plan = runner.plan_batch("paper-000/test-1", 12, 2, RESUME_SET)
    per_block = sum(t.bytes for t in plan.experiment.memory(plan.scenario, 12) if t.per_block)
    return int(64 * 2**20 + 2**20 * 5 + 8 * per_block)


PEAK_TRACED_B = 4 * 2**20
"""Python memory a refused block may cost: a few chunks of the hash, not the file."""


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (1, "bytes, more than a block of this batch can hold"),  # one byte over: refused unread
        (0, "its sha256 is"),  # at the ceiling: read in chunks, refused by its digest
        (-(2**25), "its sha256 is"),  # 32 MiB under it
    ],
    ids=["ceiling+1", "ceiling", "ceiling-32MiB"],
)
def test_a_huge_block_is_refused_without_being_read_whole(
    batches, tmp_path, capsys, extra, fragment
):
    """A block file grown to tens of MB (a hole: nothing on disk) is refused with one line and
    costs this process a few MB at most: before the fix the file was read whole (3.2 GB of
    memory for a 3 GB file) before its digest was checked."""
    import tracemalloc

    from tasks.core import runner

    limit = _block_file_limit_b()
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    _sparse(out / "blocks" / "block-000001.zip", limit + extra)
    tracemalloc.start()
    try:
        code, err = _resume(out, capsys)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < PEAK_TRACED_B, peak
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert "block-000001.zip': " in lines[0] and fragment in lines[0], err
    plan = runner.plan_resume(batches["seed2"], "paper-000/test-1", None, None, (), ())
    assert plan.block_file_limit_b == limit


def test_a_long_sha256_file_is_refused_unread(batches, tmp_path, capsys):
    out = tmp_path / "batch"
    shutil.copytree(batches["seed2"], out)
    _sparse(out / "blocks" / "block-000000.sha256", 2**30)
    code, err = _resume(out, capsys)
    assert code == 2 and "block-000000.sha256': longer than" in err, err


# ---------------------------------------------------------------------------------------------
# Nothing is written outside the run folder (issue 21)


FIGURED_SET = [
    "passage.duration_s=100",
    "passage.closest_approach_time_s=50",
    "report.recording=false",
    "runner.block_size=5",
]


@pytest.fixture(scope="module")
def figured(tmp_path_factory):
    """A 12-run batch with its figures (3 blocks), made to look interrupted before its last
    block (no report yet), and the bytes of every file of the finished batch."""
    out = tmp_path_factory.mktemp("figured") / "run"
    run("paper-000/test-1", 12, 2, out, FIGURED_SET, progress=False)
    finished = _snapshot(out)
    for name in ("block-000002.zip", "block-000002.sha256"):
        (out / "blocks" / name).unlink()
    shutil.rmtree(out / "tables")
    for f in out.iterdir():
        if f.suffix in (".png", ".pdf", ".md") or f.name == "metrics.json":
            f.unlink()
    _edit_record(out, state="incomplete")
    return out, finished


def _tree(folder):
    """Every entry under ``folder``, links not followed: relative path -> bytes, "dir" or
    ("link", target)."""
    out = {}
    for path in sorted(pathlib.Path(folder).rglob("*")):
        rel = str(path.relative_to(folder))
        if path.is_symlink():
            out[rel] = ("link", os.readlink(path))
        elif path.is_dir():
            out[rel] = "dir"
        else:
            out[rel] = path.read_bytes()
    return out


def _link_a_figure(out, outside):
    (outside / "victim.png").write_bytes(b"victim")
    (out / "routes.png").symlink_to(outside / "victim.png")


def _link_the_tables(out, outside):
    (outside / "tables").mkdir()
    (out / "tables").symlink_to(outside / "tables", target_is_directory=True)


def _link_the_blocks(out, outside):
    shutil.move(out / "blocks", outside / "blocks")
    (out / "blocks").symlink_to(outside / "blocks", target_is_directory=True)


@pytest.mark.slow
@pytest.mark.parametrize("plant", [_link_a_figure, _link_the_tables, _link_the_blocks])
def test_resume_refuses_a_run_folder_with_a_symbolic_link(figured, tmp_path, capsys, plant):
    """``--resume`` on a folder where a figure, ``tables/`` or ``blocks/`` links outside: one
    line, exit 2, nothing written in the folder or where the link points. Before the fix the
    figure's target was overwritten with PNG data, the CSVs and the missing block written into
    the outside folders."""
    out, outside = tmp_path / "batch", tmp_path / "outside"
    shutil.copytree(figured[0], out)
    outside.mkdir()
    plant(out, outside)
    before, before_outside = _tree(out), _tree(outside)
    code, err = _resume(out, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith("error: --resume: ") and "is a symbolic link" in lines[0], err
    assert _tree(outside) == before_outside
    assert _tree(out) == before


@pytest.mark.slow
@pytest.mark.parametrize("where", ["file", "folder"])
def test_a_link_planted_after_the_checks_is_not_written_through(figured, tmp_path, where):
    """A link that appears after ``--resume``'s checks (here: planted between the plan and the
    batch): a figure linked to a file outside is replaced by the figure, its target untouched;
    ``tables/`` linked to a folder outside stops the report (OutputError, the computed block
    kept) with nothing written there."""
    from tasks.core import runner

    out, outside = tmp_path / "batch", tmp_path / "outside"
    shutil.copytree(figured[0], out)
    outside.mkdir()
    plan = runner.plan_resume(out, "paper-000/test-1", None, None, (), ())
    if where == "file":
        _link_a_figure(out, outside)
        runner.execute(plan, out, progress=False)
        assert not (out / "routes.png").is_symlink()
        assert (out / "routes.png").read_bytes() == figured[1][pathlib.Path("routes.png")]
    else:
        _link_the_tables(out, outside)
        with pytest.raises(runner.OutputError) as info:
            runner.execute(plan, out, progress=False)
        msg = str(info.value)
        assert "a symbolic link inside the run folder" in msg and "remove the link" in msg, msg
        assert "3 of 3 blocks are saved" in msg, msg
    assert _tree(outside) == ({"victim.png": b"victim"} if where == "file" else {"tables": "dir"})


# ---------------------------------------------------------------------------------------------
# A write that fails part-way (a full disk) leaves no partial file (issue 21)


FILE_SIZE_LIMIT_B = 60_000
"""Larger than every block and table of the ``figured`` batch, smaller than its figures."""


def _limit_file_size():
    """In the child: files may not grow past FILE_SIZE_LIMIT_B (a write past it fails with
    EFBIG, as on a full disk with ENOSPC, part-way through the file)."""
    import resource

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT_B, FILE_SIZE_LIMIT_B))


@pytest.mark.slow
def test_a_write_failing_part_way_leaves_whole_figures_only(figured, tmp_path):
    """The report's first figure fails part-way: one line, exit status 1, the block computed
    before is kept, every figure there is whole (before the fix a truncated file was left) and
    no temporary file; once the writes succeed ``--resume`` completes the batch to the bytes of
    the straight batch."""
    out = tmp_path / "batch"
    shutil.copytree(figured[0], out)
    finished = figured[1]
    cmd = [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1", "--resume"]
    res = subprocess.run(
        [*cmd, "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=_limit_file_size,
    )
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 1 and len(lines) == 1, res.stderr
    assert "cannot write the report (File too large" in lines[0], res.stderr
    assert "3 of 3 blocks are saved" in lines[0], res.stderr
    assert (out / "blocks" / "block-000002.zip").read_bytes() == finished[
        pathlib.Path("blocks/block-000002.zip")
    ]
    figures = [p for p in out.iterdir() if p.suffix in (".png", ".pdf")]
    for p in figures:
        assert p.read_bytes() == finished[p.relative_to(out)], p.name
    assert len(figures) < sum(p.suffix in (".png", ".pdf") for p in finished)
    assert not [p for p in out.rglob(".*.tmp")]
    res = _resume_in_a_process(out, "--quiet")
    assert res.returncode == 0, res.stderr
    for rel, data in finished.items():
        if rel.suffix in (".png", ".pdf", ".csv") or rel.name == "metrics.json":
            assert (out / rel).read_bytes() == data, rel


@pytest.mark.slow
def test_a_recording_that_cannot_be_written_is_one_line_not_a_hang(tmp_path):
    """The recording fails part-way: one line, exit status 1, the blocks kept and no recording
    left; ``--resume`` then writes a whole one. Before the fix rerun wrote the file itself:
    a truncated recording.rrd was left and bauv hung in rerun's flush (on a full tmpfs too, where
    SIGTERM did not stop it either)."""
    from tasks.core.recording import read_time_series

    out = tmp_path / "batch"
    cmd = [sys.executable, "-m", "tasks.core.cli", "run", "paper-000/test-1", "--runs", "12"]
    sets = [s for s in FIGURED_SET if not s.startswith("report.")] + ["report.figures=false"]
    cmd += [f"--set={s}" for s in sets] + ["--seed", "2", "--quiet", "--out", str(out)]
    try:
        res = subprocess.run(
            cmd,
            capture_output=True,
            text=True,
            check=False,
            preexec_fn=_limit_file_size,
            timeout=RECORDING_TIMEOUT_S,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"bauv hung writing the recording ({RECORDING_TIMEOUT_S:g} s)")
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 1 and len(lines) == 1, res.stderr
    assert "cannot write the report (File too large" in lines[0], res.stderr
    assert "3 of 3 blocks are saved" in lines[0], res.stderr
    assert not (out / "recording.rrd").exists() and not [p for p in out.rglob(".*.tmp")]
    res = _resume_in_a_process(out, "--quiet")
    assert res.returncode == 0, res.stderr
    t, d = read_time_series(out / "recording.rrd", "distance/ekf", "Scalars:scalars")
    assert t[0] == 0.0 and t[-1] == 100.0 and d.shape == (101,)  # every tick of 100 s


RECORDING_TIMEOUT_S = 120.0
"""Ample for a 12-run batch of 100 s passages (about 5 s)."""
