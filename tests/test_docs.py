"""The documentation site's sources (``mkdocs.yml``, ``docs/``), checked without building it:
every page is in the nav, every API page names an importable module, and the tutorial's blocks
are code the build can run (CI builds the site and executes the tutorial)."""

from __future__ import annotations

import ast
import importlib.util
import re
import shlex
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


class _Loader(yaml.SafeLoader):
    """mkdocs.yml may hold ``!!python/name:`` tags (none today): read them as text."""


_Loader.add_multi_constructor("tag:yaml.org,2002:python/", lambda loader, suffix, node: suffix)


def _config() -> dict:
    return yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=_Loader)


def _nav_pages(nav) -> list[str]:
    pages: list[str] = []
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        if isinstance(value, list):
            pages += _nav_pages(value)
        else:
            pages.append(value)
    return pages


def _hooks():
    spec = importlib.util.spec_from_file_location("docs_hooks", DOCS / "hooks" / "tutorial.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_nav_lists_every_page_once_and_only_pages_that_exist():
    cfg = _config()
    assert cfg["docs_dir"] == "docs" and cfg.get("strict") is True
    pages = _nav_pages(cfg["nav"])
    excluded = ("hooks/",)
    on_disk = sorted(
        p.relative_to(DOCS).as_posix()
        for p in DOCS.rglob("*.md")
        if not p.relative_to(DOCS).as_posix().startswith(excluded)
    )
    assert len(pages) == len(set(pages)), pages
    assert sorted(pages) == on_disk


def test_api_pages_name_importable_modules_of_the_three_packages():
    identifiers = []
    for page in sorted((DOCS / "api").glob("*.md")):
        identifiers += re.findall(r"^::: ([\w.]+)", page.read_text(encoding="utf-8"), re.M)
    for top in ("bauv_sim", "nav", "tasks", "tasks.core"):
        assert top in identifiers, top
    for name in identifiers:
        assert importlib.util.find_spec(name) is not None, name


def test_tutorial_blocks_are_valid_code_the_build_runs():
    text = (DOCS / "tutorial.md").read_text(encoding="utf-8")
    blocks = _hooks().blocks(text)
    langs = [lang for lang, _, _ in blocks]
    assert langs.count("bash") >= 2 and langs.count("python") >= 3, langs
    # every fenced block of the page is one the build executes, or plain text
    fences = re.findall(r"^```(\w*)", text, re.M)
    assert set(fences) <= {"python", "bash", ""}, fences
    assert len([f for f in fences if f]) == len(blocks)
    from tasks.core.cli import cli

    for lang, code, _ in blocks:
        if lang == "python":
            ast.parse(code)  # a SyntaxError fails here, before a build
            continue
        for line in code.replace("\\\n", " ").splitlines():
            words = shlex.split(line)
            assert words and words[0] == "bauv", line  # the tutorial's shell is bauv only
            assert words[1] in cli.commands, line


def test_hook_runs_blocks_in_order_and_fails_on_error(tmp_path):
    hooks = _hooks()
    page = "```python\nx = 6 * 7\n```\n\n```bash\necho from-bash\n```\n\n```python\nprint(x)\n```\n"
    out = hooks.execute(page, tmp_path)
    assert "```text\nfrom-bash\n```" in out and "```text\n42\n```" in out
    bad = "```bash\nfalse\n```\n"
    try:
        hooks.execute(bad, tmp_path)
    except hooks.PluginError as exc:
        assert "exited with status 1" in str(exc)
    else:
        raise AssertionError("a failing block must stop the build")


def test_hook_reduces_sphinx_roles_to_code():
    hooks = _hooks()
    html = "see :class:<code>~nav.ekf.BatchEKF</code> and :func:<code>run</code>"
    assert hooks.on_page_content(html, None, None, None) == (
        "see <code>nav.ekf.BatchEKF</code> and <code>run</code>"
    )
