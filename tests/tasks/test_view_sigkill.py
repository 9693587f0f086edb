"""`bauv view --web` killed with SIGKILL takes its rerun server with it (issue 21: the server kept
listening). SIGKILL cannot be caught; the viewer is started so that the kernel ends it when bauv
ends (PR_SET_PDEATHSIG). A real process is started, killed, and the port watched."""

import os
import signal
import socket
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's"
)


def _listening(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
    except OSError:
        return False
    return True


def _viewer_pids(web_port: int) -> list[int]:
    ps = subprocess.run(["ps", "-eww", "-o", "pid=,args="], capture_output=True, text=True).stdout
    return [
        int(ln.split()[0])
        for ln in ps.splitlines()
        if f"--web-viewer-port {web_port}" in ln and "tasks.core.cli" not in ln
    ]


@pytest.fixture
def run_dir(tmp_path):
    from tasks.core.recording import Recording

    rec = Recording(tmp_path / "recording.rrd", "test", "test")
    rec.point("x", [0.0, 0.0, 0.0], (0, 0, 0), "x")
    rec.close()
    return tmp_path


def test_sigkill_of_bauv_view_closes_the_rerun_server(run_dir):
    from tests.webviewer import web_viewer

    with web_viewer(run_dir) as v:
        assert b"re_viewer" in v.html, "the viewer did not serve its page"
        servers = _viewer_pids(v.web_port)
        assert servers, "no rerun server process found"
        try:
            os.kill(v.proc.pid, signal.SIGKILL)
            v.proc.wait(timeout=10)
            deadline = time.monotonic() + 15.0
            while time.monotonic() < deadline and (
                _listening(v.web_port) or _listening(v.grpc_port) or _viewer_pids(v.web_port)
            ):
                time.sleep(0.1)
            assert not _listening(v.web_port), "the web viewer port still listens"
            assert not _listening(v.grpc_port), "the gRPC port still listens"
            assert not _viewer_pids(v.web_port), "a rerun process outlived bauv"
        finally:
            for pid in _viewer_pids(v.web_port):  # a failing run must not leave it behind
                os.kill(pid, signal.SIGKILL)
