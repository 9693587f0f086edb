"""Start ``bauv view RUN --web`` on free loopback ports and wait for the page (shared by the CLI
test and the headless-browser check ``tests/browser/check_web_viewer.py``)."""

from __future__ import annotations

import contextlib
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass(frozen=True)
class Viewer:
    """A running web viewer: its process, ports and the page it served."""

    proc: subprocess.Popen
    web_port: int
    grpc_port: int
    html: bytes

    @property
    def url(self) -> str:
        """The page that opens the recording."""
        return (
            f"http://127.0.0.1:{self.web_port}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A"
            f"{self.grpc_port}%2Fproxy"
        )


@contextlib.contextmanager
def web_viewer(run_dir: str, timeout_s: float = 30.0) -> Iterator[Viewer]:
    """Run ``bauv view RUN --web`` until the block ends (then stop it with SIGTERM)."""
    web, grpc = free_port(), free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "tasks.core.cli",
            "view",
            str(run_dir),
            "--web",
            "--web-port",
            str(web),
            "--grpc-port",
            str(grpc),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        # as from a terminal: a test run under nohup would hand down SIGHUP ignored, and bauv
        # keeps an ignored SIGHUP ignored (nohup bauv ... must survive the terminal)
        preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_DFL),
    )
    try:
        deadline = time.time() + timeout_s
        html = b""
        while time.time() < deadline:
            try:
                html = urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=1).read()
                break
            except OSError:
                time.sleep(0.2)
        yield Viewer(proc, web, grpc, html)
    finally:
        proc.terminate()
        proc.wait(timeout=10)
