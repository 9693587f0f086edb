"""Same seed, same numbers, bit for bit: repeated, on 1 or N workers, on Dask, after a resume."""

import json
import os
import signal
import subprocess
import sys
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
        if blocks.is_dir() and len(list(blocks.glob("block-*.pkl"))) >= 5:
            break
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "--resume" in err and "Traceback" not in err
    assert not (out / "metrics.json").exists()
    assert json.loads((out / "run.json").read_text())["state"] == "incomplete"
    n_saved = len(list((out / "blocks").glob("block-*.pkl")))
    assert 5 <= n_saved < 100
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "tasks.core.cli",
            "run",
            "paper-000/test-1",
            "--resume",
            "--out",
            str(out),
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stderr
    assert json.loads((out / "run.json").read_text())["state"] == "complete"
    assert _bytes(out) == _bytes(straight)
