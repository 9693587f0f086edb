"""Bad input: one clear line, exit status 2, no traceback, no folder left looking complete."""

import os
import subprocess
import sys

import pytest

from tasks.core import cli
from tests.tasks.refusal import run_in_process


def bauv(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", *args], capture_output=True, text=True, cwd=cwd
    )


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "pattern"),
    [
        (["--set", "sensors.usbl.bogus=1"], "unknown field 'sensors.usbl.bogus'"),
        (["--set", "sensors.usbl.range.sigma_m=-0.2"], "sensors.usbl.range.sigma_m = -0.2"),
        (["--set", "sensors.usbl.period_s=7.5"], "sensors.usbl.period_s = 7.5: must be a whole"),
        (["--set", "filter.sigma_range_m=nan"], "filter.sigma_range_m = nan"),
        (["--runs", "0"], "runs = 0"),
        (["--set", "report.record_run=10", "--runs", "5"], "report.record_run = 10"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, pattern, tmp_path):
    out = tmp_path / "out"
    res = bauv("run", "paper-000/test-1", "--out", str(out), *args, cwd=tmp_path)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and pattern in lines[0], res.stderr
    assert "Traceback" not in res.stderr
    assert not out.exists() and not (tmp_path / "runs").exists()


@pytest.mark.slow
def test_unknown_experiment(tmp_path):
    res = bauv("run", "paper-000/test-7", cwd=tmp_path)
    assert res.returncode == 2 and "unknown experiment 'paper-000/test-7'" in res.stderr
    assert "paper-000/test-1" in res.stderr and "Traceback" not in res.stderr


@pytest.mark.slow
def test_existing_folder_is_not_overwritten(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "keep.txt").write_text("x")
    res = bauv("run", "paper-000/accuracy", "--out", str(tmp_path / "out"))
    assert res.returncode == 2 and "--resume" in res.stderr
    assert (tmp_path / "out" / "keep.txt").read_text() == "x"


@pytest.mark.slow
def test_list_and_show():
    res = bauv("list")
    assert res.returncode == 0
    for name in ["paper-000/test-1", "paper-000/test-2", "paper-000/test-3", "paper-000/accuracy"]:
        assert name in res.stdout
    res = bauv("show", "paper-000/test-3")
    assert res.returncode == 0 and "period_s = 100.0" in res.stdout


def test_web_viewer_binds_loopback_only(tmp_path):
    cmd = cli.view_command(tmp_path / "recording.rrd", web=True, web_port=9191, grpc_port=9877)
    assert cmd[cmd.index("--bind") + 1] == "127.0.0.1"
    assert "--serve-web" in cmd and cmd[cmd.index("--web-viewer-port") + 1] == "9191"


@pytest.mark.slow
def test_view_web_serves_the_viewer_on_loopback_only(tmp_path):
    """Start `bauv view --web` on a recording and fetch the page over HTTP."""
    import socket
    import time

    from tasks.core.recording import Recording
    from tests.webviewer import web_viewer

    rec = Recording(tmp_path / "recording.rrd", "test", "test")
    rec.point("x", [0.0, 0.0, 0.0], (0, 0, 0), "x")
    rec.close()
    with web_viewer(tmp_path) as v:
        assert b"re_viewer" in v.html
        # nothing answers on the machine's other addresses
        host_ip = socket.gethostbyname(socket.gethostname())
        if not host_ip.startswith("127."):
            with pytest.raises(OSError):
                socket.create_connection((host_ip, v.web_port), timeout=1).close()
    # stopping bauv view stops the rerun server it started (no leaked process)
    time.sleep(1.0)
    assert not _servers(v.web_port)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "pattern"),
    [
        (["--workers", "0"], "workers = 0: must be"),
        (["--address", "tcp://127.0.0.1:8786"], "--address is for --executor dask"),
        (["--executor", "dask", "--address", "notanaddress"], "must be a Dask scheduler address"),
        (["--executor", "dask", "--address", "tcp://127.0.0.1:1"], "no Dask scheduler answered"),
    ],
    ids=["workers-0", "address-local", "address-garbage", "address-silent"],
)
def test_executor_options_are_checked_before_the_folder_is_written(
    args, pattern, tmp_path, capsys, monkeypatch
):
    """Bad executor options: one line, exit 2, no folder; the same --out then works."""
    from tasks.core import executors

    if "dask" in args:
        pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "DASK_CONNECT_TIMEOUT_S", 1.0)
    out = tmp_path / "out"
    code, err = run_in_process(
        capsys, "run", "paper-000/accuracy", "--quiet", "--out", str(out), *args
    )
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and pattern in lines[0], err
    assert not out.exists()
    code, err = run_in_process(capsys, "run", "paper-000/accuracy", "--quiet", "--out", str(out))
    assert code == 0, err


def _no_space(names=None):
    """A stand-in for the runner's atomic write that fails like a full disk (for the files whose
    name starts with one of ``names``, or for every file)."""
    import errno

    from tasks.core import run_folder

    real = run_folder.atomic_write_bytes

    def write(path, data):
        if names is None or path.name.startswith(names):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(path, data)

    return write


def _read_only(path, data):
    import errno

    raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))


@pytest.mark.parametrize(
    ("where", "write", "pattern"),
    [
        ("afile/sub", None, "cannot create the run folder (Not a directory"),
        ("x" * 300, None, "cannot create the run folder (File name too long)"),
        ("out", _read_only, "cannot create the run folder (Read-only file system"),
        ("out", _no_space(), "cannot create the run folder (No space left on device)"),
    ],
    ids=["file-in-path", "name-too-long", "read-only", "disk-full"],
)
def test_an_out_folder_that_cannot_be_written_is_one_line(
    tmp_path, capsys, monkeypatch, where, write, pattern
):
    from tasks.core import run_folder

    (tmp_path / "afile").write_text("x")
    if write is not None:
        monkeypatch.setattr(run_folder, "atomic_write_bytes", write)
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    code, err = run_in_process(capsys, "run", "paper-000/accuracy", "--quiet", "--out", where)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and pattern in lines[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing left behind


def test_a_disk_full_during_the_batch_keeps_the_saved_blocks(tmp_path, capsys, monkeypatch):
    """The disk fills while block 1 is written: one line, exit 1, block 0 kept; once there is room
    --resume completes the batch to the bytes of a batch run straight through."""
    from tasks.core import run_folder

    args = ["paper-000/test-1", "--quiet", "--runs", "10", "--seed", "3"]
    args += [f"--set={s}" for s in ["runner.block_size=5", "passage.duration_s=100"]]
    args += ["--set=passage.closest_approach_time_s=50", "--set=report.figures=false"]
    args += ["--set=report.recording=false"]
    code, err = run_in_process(capsys, "run", *args, "--out", str(tmp_path / "straight"))
    assert code == 0, err
    monkeypatch.setattr(run_folder, "atomic_write_bytes", _no_space(("block-000001",)))
    out = tmp_path / "full"
    code, err = run_in_process(capsys, "run", *args, "--out", str(out))
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1, err
    assert "cannot write block 1 (No space left on device); 1 of 2 blocks are saved" in lines[0]
    monkeypatch.undo()
    code, err = run_in_process(
        capsys, "run", "paper-000/test-1", "--quiet", "--resume", "--out", str(out)
    )
    assert code == 0, err
    metrics = (out / "metrics.json").read_bytes()
    assert metrics == (tmp_path / "straight" / "metrics.json").read_bytes()


def test_a_scenario_file_that_is_not_utf8_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b'[passage]\nname = "\xff\xfe"\n')
    out = tmp_path / "out"
    code, err = run_in_process(
        capsys, "run", "paper-000/test-1", "--out", str(out), "--scenario", str(bad)
    )
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert "bad.toml': not UTF-8 text (byte 0xff at offset 18)" in lines[0]
    assert not out.exists()


PASSAGE_AT_EVERY_TICK = [f"sensors.{d}.period_s=1e-9" for d in ("ins", "log", "pressure")]


@pytest.mark.parametrize(
    ("name", "args", "pattern"),
    [
        ("paper-000/test-1", ["--runs", "99999999999999999999"], "runs = 99999999999999999999: at"),
        (
            "paper-000/test-1",
            ["--runs", "2000000", "--set", "runner.block_size=1"],
            "make 2000000 blocks: at most 1000000",
        ),
        ("paper-000/test-1", ["--set", "passage.duration_s=1e12"], "passage.duration_s = 1e+12"),
        (
            "paper-000/test-1",
            ["--set", "passage.tick_s=1e-9", *(f"--set={s}" for s in PASSAGE_AT_EVERY_TICK)],
            "passage.tick_s = 1e-09 s (6e+11 ticks)",
        ),
        (
            "paper-000/test-1",
            ["--set", "passage.duration_s=1e300", "--set", "passage.tick_s=1e-10"]
            + [f"--set={s.replace('1e-9', '1e-10')}" for s in PASSAGE_AT_EVERY_TICK],
            "passage.duration_s = 1e+300: inf ticks",
        ),
        ("paper-000/test-1", ["--set", "report.histogram_bin_m=1e-9"], "report.histogram_bin_m"),
        ("mission/short", ["--set", "timing.max_duration_s=1e12"], "timing.max_duration_s = 1e+12"),
    ],
    ids=["runs", "blocks", "duration", "tick", "ticks-overflow", "histogram", "mission"],
)
def test_a_batch_too_big_for_memory_is_refused_before_work_starts(
    name, args, pattern, tmp_path, capsys, monkeypatch
):
    """One line naming the field, its value and the limit; nothing written, nothing computed."""
    from tasks.core import registry

    def never(*_):
        raise AssertionError("a block was computed")

    for exp in registry.all_experiments():
        monkeypatch.setattr(type(exp), "run_block", never)
    out = tmp_path / "out"
    code, err = run_in_process(capsys, "run", name, "--quiet", "--out", str(out), *args)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and pattern in lines[0], err
    memory = any(f in pattern for f in ("duration_s = 1e+12", "tick_s", "histogram"))
    assert memory == ("of memory, above the limit of" in lines[0]), err
    assert not out.exists()


@pytest.mark.slow
def test_the_memory_estimate_follows_the_measured_peak():
    """The estimate of a seed 000 block is the measured peak of computing it, within 30%."""
    import tracemalloc

    from bauv_sim.config import load_config
    from tasks.core import registry

    exp = registry.get("paper-000/test-1")
    scn = load_config(exp.scenario_type, exp.preset, (), ["passage.duration_s=2000"])
    tracemalloc.start()
    try:
        exp.run_block(scn, 0, tuple(range(20)))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    block = sum(t.bytes for t in exp.memory(scn, 20) if t.per_block)
    assert 0.7 * peak < block < 1.3 * peak, (block, peak)


@pytest.mark.parametrize(
    ("name", "override", "pattern"),
    [
        (
            "paper-000/test-1",
            "passage.speed_m_s=true",
            "passage.speed_m_s = true: must be a number",
        ),
        ("paper-000/test-1", 'passage.speed_m_s="1.5"', "passage.speed_m_s = '1.5': must be a"),
        ("paper-000/test-1", "runner.block_size=true", "runner.block_size = true: must be an int"),
        (
            "mission/short",
            "sensors.usbl.transponder_body_m=[true, 0, 0]",
            "element 0 must be a number, not a boolean",
        ),
        ("mission/short", "faults.physics_nan_runs=[-1]", "faults.physics_nan_runs = [-1]: run -1"),
        ("mission/short", "faults.physics_nan_runs=[1]", "run 1 is not a run of this batch"),
        (
            "mission/short",
            "guidance.waypoints.0.depth_m=500",
            "guidance.waypoints.0.depth_m = 500: the water is 5.13 m deep at east 0 m, north 50 m",
        ),
        ("mission/short", "start.depth_m=50", "start.depth_m = 50: the water is"),
        (
            "paper-000/test-1",
            "sensors.usbl.processing_delay_s=30",
            "sensors.usbl.processing_delay_s = 30: not used by seed 000's passage",
        ),
        (
            "paper-000/test-2",
            "sensors.usbl.sound_speed_m_s=1450",
            "sensors.usbl.sound_speed_m_s = 1450: not used by seed 000's passage",
        ),
    ],
)
def test_accepted_but_absurd_input_is_refused(name, override, pattern, tmp_path, capsys):
    out = tmp_path / "out"
    code, err = run_in_process(capsys, "run", name, "--quiet", "--out", str(out), "--set", override)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and pattern in lines[0], err
    assert not out.exists()


def test_a_waypoint_within_the_water_is_accepted():
    """The depth check uses the scene's seabed: 4.5 m is allowed where the water is 5.13 m deep,
    and the seabed there is the one the scene is built with."""
    from bauv_sim import seabed
    from bauv_sim.build import VEHICLE_CLEARANCE_M
    from tasks.core.runner import plan_batch

    scn = plan_batch("mission/short", overrides=["guidance.waypoints.0.depth_m=4.5"]).scenario
    w = scn.guidance.waypoints[0]
    water = float(seabed.generate(scn.seabed).depth_at(w.east_m, w.north_m))
    assert water - VEHICLE_CLEARANCE_M > 4.5 and water == pytest.approx(5.13, abs=0.005)


@pytest.mark.slow
def test_view_web_stops_its_server_on_sighup(tmp_path):
    """The terminal that ran `bauv view --web` closes (SIGHUP): the rerun server stops too."""
    import signal
    import socket
    import time

    from tasks.core.recording import Recording
    from tests.webviewer import web_viewer

    rec = Recording(tmp_path / "recording.rrd", "test", "test")
    rec.point("x", [0.0, 0.0, 0.0], (0, 0, 0), "x")
    rec.close()
    with web_viewer(tmp_path) as v:
        try:
            assert b"re_viewer" in v.html
            os.kill(v.proc.pid, signal.SIGHUP)
            v.proc.wait(timeout=10)
            deadline = time.time() + 10
            while _servers(v.web_port) and time.time() < deadline:
                time.sleep(0.2)
            assert not _servers(v.web_port)
            with pytest.raises(OSError):
                socket.create_connection(("127.0.0.1", v.web_port), timeout=1).close()
        finally:
            for pid in _servers(v.web_port):  # a failing run must not leave the server behind
                os.kill(pid, signal.SIGKILL)


def _servers(web_port):
    """Pids of the rerun processes serving ``web_port`` (``ps -ww``: without it, ps cuts its
    lines to 80 columns when its output is not a terminal, and the port would never be seen)."""
    ps = subprocess.run(["ps", "-ww", "-eo", "pid,args"], capture_output=True, text=True).stdout
    return [int(ln.split()[0]) for ln in ps.splitlines() if f"--web-viewer-port {web_port}" in ln]


def test_native_viewer_binds_loopback_only(tmp_path):
    """The native viewer's gRPC server listens on 127.0.0.1 (rerun's default is 0.0.0.0), and the
    installed rerun accepts the options (it may still fail for want of a display)."""
    cmd = cli.view_command(tmp_path / "recording.rrd", web=False, grpc_port=9878)
    assert cmd[cmd.index("--bind") + 1] == "127.0.0.1"
    assert cmd[cmd.index("--port") + 1] == "9878"
    res = subprocess.run(
        [*cmd[:-1], "--help"], capture_output=True, text=True, timeout=60, check=False
    )
    assert res.returncode == 0 and "--bind" in res.stdout, res.stderr


@pytest.mark.slow
def test_nohup_keeps_a_batch_running_when_the_terminal_closes(tmp_path):
    """A SIGHUP ignored at start (``nohup bauv run``) stays ignored: the batch completes."""
    import signal
    import time

    out = tmp_path / "out"
    args = ["run", "paper-000/test-1", "--runs", "40", "--quiet", "--out", str(out)]
    args += ["--set=runner.block_size=5", "--set=report.figures=false"]
    args += ["--set=report.recording=false"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "tasks.core.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN),
    )
    deadline = time.time() + 60
    while time.time() < deadline and not list(out.glob("blocks/*.sha256")):
        time.sleep(0.05)
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert (out / "metrics.json").is_file()
