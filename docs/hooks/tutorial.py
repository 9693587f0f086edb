"""MkDocs hooks of the documentation site (``mkdocs.yml``: ``hooks``).

* The tutorial (``docs/tutorial.md``) is executed while the site is built: its fenced ``bash``
  and ``python`` blocks run in order in one fresh folder (the ``bash`` blocks with the
  environment's ``bauv`` first on ``PATH``, the ``python`` blocks in one namespace, as a reader
  would run them), each block's output is inserted after it, and each Markdown image whose path
  names a file the blocks wrote is embedded in the page. A block that fails stops the build
  with its output, so a tutorial that no longer runs cannot be published.
* The docstrings' Sphinx roles (``:class:`X```, ``:func:`~a.X```, ...), which mkdocstrings
  renders as the role's text before the code, are reduced to the code.
"""

from __future__ import annotations

import base64
import contextlib
import io
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:
    from mkdocs.exceptions import PluginError
except ImportError:  # tests/test_docs.py reads this file where mkdocs is not installed

    class PluginError(Exception):  # type: ignore[no-redef]
        """A block of the tutorial failed."""


TUTORIAL = "tutorial.md"

BLOCK = re.compile(r"^```(?P<lang>python|bash)[ \t]*\n(?P<code>.*?)^```[ \t]*$", re.M | re.S)
"""A fenced block to execute: its language and code."""

IMAGE = re.compile(r"!\[(?P<alt>[^\]]*)\]\((?P<src>[^)\s]+\.png)\)")

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|data|attr|exc|obj|const|ref|term):(?=<code)")
"""A Sphinx role before the code it marks, as mkdocstrings renders ``:class:`X```."""

TILDE = re.compile(r"<code>~(?=[A-Za-z_])")
"""Sphinx's ``~`` (show the last name only) at the start of a code span."""

MAX_OUTPUT_LINES = 60


def blocks(markdown: str) -> list[tuple[str, str, int]]:
    """The executed blocks of a page: (language, code, end offset in ``markdown``)."""
    return [(m["lang"], m["code"], m.end()) for m in BLOCK.finditer(markdown)]


def _shown(text: str) -> str:
    lines = text.rstrip().splitlines()
    if len(lines) > MAX_OUTPUT_LINES:
        cut = len(lines) - MAX_OUTPUT_LINES
        lines = [*lines[:MAX_OUTPUT_LINES], f"... ({cut} more lines)"]
    return "\n".join(lines)


def _run_bash(code: str, work: Path, env: dict[str, str]) -> str:
    res = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", code],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if res.returncode != 0:
        raise PluginError(
            f"{TUTORIAL}: this bash block exited with status {res.returncode}:\n{code}\n"
            f"{res.stdout}{res.stderr}"
        )
    return res.stdout + res.stderr


def _run_python(code: str, index: int, namespace: dict) -> str:
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            exec(compile(code, f"{TUTORIAL}, python block {index}", "exec"), namespace)
    except Exception as exc:
        raise PluginError(
            f"{TUTORIAL}: python block {index} raised {type(exc).__name__}: {exc}\n{code}\n"
            f"{out.getvalue()}"
        ) from exc
    return out.getvalue()


def execute(markdown: str, work: Path) -> str:
    """Run the page's blocks in ``work`` and return the page with their outputs and images.

    Raises:
        PluginError: a block failed, or an image names a file the blocks did not write.
    """
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env.setdefault("MPLBACKEND", "Agg")
    os.environ.setdefault("MPLBACKEND", "Agg")
    namespace: dict = {"__name__": "__tutorial__"}
    pieces, start = [], 0
    here = Path.cwd()
    os.chdir(work)
    try:
        for i, (lang, code, end) in enumerate(blocks(markdown)):
            t0 = time.perf_counter()
            text = _run_bash(code, work, env) if lang == "bash" else _run_python(code, i, namespace)
            took = time.perf_counter() - t0
            pieces.append(markdown[start:end])
            if text.strip():
                pieces.append(f"\n\n```text\n{_shown(text)}\n```\n")
            pieces.append(f"\n<small>ran in {took:.1f} s while this site was built</small>\n")
            start = end
    finally:
        os.chdir(here)
    pieces.append(markdown[start:])
    page = "".join(pieces)

    def embed(m: re.Match) -> str:
        path = work / m["src"]
        if not path.is_file():
            raise PluginError(f"{TUTORIAL}: image {m['src']!r} was not written by the blocks")
        data = base64.b64encode(path.read_bytes()).decode()
        return f"![{m['alt']}](data:image/png;base64,{data})"

    return IMAGE.sub(embed, page)


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Execute the tutorial; leave every other page as it is."""
    if page.file.src_uri != TUTORIAL:
        return markdown
    work = Path(tempfile.mkdtemp(prefix="bauv-tutorial-"))
    try:
        return execute(markdown, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def on_page_content(html: str, page, config, files) -> str:
    """Reduce the docstrings' Sphinx roles to the code they mark."""
    return TILDE.sub("<code>", ROLE.sub("", html))
