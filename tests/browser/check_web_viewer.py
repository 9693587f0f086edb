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

import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from tests.webviewer import web_viewer


def main(run_dir: str, out_png: str, wait_s: float = 40.0) -> None:
    from playwright.sync_api import sync_playwright

    with web_viewer(run_dir) as v:
        if b"re_viewer" not in v.html:
            raise SystemExit("the web viewer did not answer")
        listening = subprocess.run(["ss", "-ltn"], capture_output=True, text=True).stdout
        for port in (v.web_port, v.grpc_port):
            binds = [
                ln.split()[3]
                for ln in listening.splitlines()[1:]
                if ln.split()[3].endswith(f":{port}")
            ]
            assert binds and all(b.startswith("127.0.0.1:") for b in binds), (port, binds)
        print(
            f"HTTP 200 from http://127.0.0.1:{v.web_port}/; ports {v.web_port} and "
            f"{v.grpc_port} bound to 127.0.0.1 only"
        )
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
            page.goto(v.url)
            time.sleep(wait_s)
            page.screenshot(path=out_png)
            browser.close()
        print(f"screenshot: {out_png}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
