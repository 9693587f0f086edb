"""A real Dask cluster: the scheduler and the workers as their own processes on 127.0.0.1 (the way a
cluster is run, docs/cluster.md), and the CLI sending a batch to it: ``metrics.json`` must equal
the local run's byte for byte."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[2]
ARGS = [
    "paper-000/test-2",
    "--runs",
    "40",
    "--seed",
    "9",
    "--quiet",
    "--set",
    "report.figures=false",
    "--set",
    "report.recording=false",
    "--set",
    "runner.block_size=7",
]


def _dask(*args: str) -> list[str]:
    exe = Path(sys.executable).with_name("dask")
    if exe.exists():
        return [str(exe), *args]
    return [sys.executable, "-m", "distributed.cli.dask_" + args[0], *args[1:]]


def _env() -> dict[str, str]:
    path = os.environ.get("PYTHONPATH", "")
    return {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{path}" if path else str(ROOT)}


def _wait_for(path: Path, what: str, proc: subprocess.Popen, timeout_s: float = 60.0) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if path.exists() and path.stat().st_size > 0:
            return
        if proc.poll() is not None:
            raise RuntimeError(f"{what} exited with {proc.returncode}")
        time.sleep(0.1)
    raise TimeoutError(f"{what} did not start within {timeout_s} s")


def _workers_connected(scheduler_file: Path, n: int, timeout_s: float = 60.0) -> None:
    from distributed import Client

    with Client(scheduler_file=str(scheduler_file), timeout="20s") as client:
        client.wait_for_workers(n, timeout=timeout_s)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two single-threaded workers, each its own process, on loopback only."""
    sched_file = tmp_path / "scheduler.json"
    procs: list[subprocess.Popen] = []
    log = open(tmp_path / "cluster.log", "w")
    try:
        procs.append(
            subprocess.Popen(
                _dask(
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(sched_file),
                ),
                cwd=ROOT,
                env=_env(),
                stdout=log,
                stderr=subprocess.STDOUT,
            )
        )
        _wait_for(sched_file, "the scheduler", procs[0])
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    _dask(
                        "worker",
                        "--scheduler-file",
                        str(sched_file),
                        "--host",
                        "127.0.0.1",
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--no-dashboard",
                    ),
                    cwd=ROOT,
                    env=_env(),
                    stdout=log,
                    stderr=subprocess.STDOUT,
                )
            )
        _workers_connected(sched_file, 2)
        yield json.loads(sched_file.read_text())["address"]
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        log.close()


def _run(out: Path, *extra: str) -> bytes:
    cmd = [sys.executable, "-m", "tasks.core.cli", "run", *ARGS, "--out", str(out), *extra]
    res = subprocess.run(cmd, cwd=ROOT, env=_env(), capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr
    return (out / "metrics.json").read_bytes()


@pytest.mark.slow
def test_a_batch_on_a_real_cluster_equals_the_local_run_byte_for_byte(cluster, tmp_path):
    assert cluster.startswith("tcp://127.0.0.1:")
    local = _run(tmp_path / "local")
    remote = _run(tmp_path / "cluster", "--executor", "dask", "--address", cluster)
    assert remote == local
    shutil.rmtree(tmp_path / "local")
