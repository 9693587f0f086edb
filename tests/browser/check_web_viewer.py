"""Manual check: `bauv view RUN --web` serves a viewer that loads in headless Chromium.

Not collected by pytest (it needs Debian's chromium and the playwright package, which CI does not
install). Usage, from the project root:

    apt-get install chromium && pip install playwright
    python tests/browser/check_web_viewer.py RUN_DIR OUT.png

It starts ``bauv view RUN_DIR --web`` on free ports, checks that both servers listen on 127.0.0.1
only and that the page is served, opens the page in headless Chromium (software WebGL/WebGPU via
SwiftShader), waits for the viewer to load the recording and saves a screenshot to look at.
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
import urllib.request


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main(run_dir: str, out_png: str, wait_s: float = 40.0) -> None:
    from playwright.sync_api import sync_playwright

    web, grpc = free_port(), free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "tasks.cli",
            "view",
            run_dir,
            "--web",
            "--web-port",
            str(web),
            "--grpc-port",
            str(grpc),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        url = f"http://127.0.0.1:{web}/"
        for _ in range(100):
            try:
                html = urllib.request.urlopen(url, timeout=1).read().decode()
                break
            except OSError:
                time.sleep(0.2)
        else:
            raise SystemExit("the web viewer did not answer")
        assert "re_viewer" in html, "not the rerun web viewer page"
        listening = subprocess.run(["ss", "-ltn"], capture_output=True, text=True).stdout
        for port in (web, grpc):
            binds = [
                ln.split()[3]
                for ln in listening.splitlines()[1:]
                if ln.split()[3].endswith(f":{port}")
            ]
            assert binds and all(b.startswith("127.0.0.1:") for b in binds), (port, binds)
        print(f"HTTP 200 from {url}; ports {web} and {grpc} bound to 127.0.0.1 only")
        with sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path="/usr/bin/chromium",
                headless=True,
                args=[
                    "--no-sandbox",
                    "--disable-quic",
                    "--no-first-run",
                    "--disable-background-networking",
                    "--disable-component-update",
                    "--disable-sync",
                    "--enable-unsafe-swiftshader",
                    "--use-angle=swiftshader",
                    "--ignore-gpu-blocklist",
                ],
            )
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            page.goto(f"{url}?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy")
            time.sleep(wait_s)
            page.screenshot(path=out_png)
            browser.close()
        print(f"screenshot: {out_png}")
    finally:
        proc.terminate()
        proc.wait(timeout=10)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
