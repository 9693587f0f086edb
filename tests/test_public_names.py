"""The packages export their public names (``__all__``), each of which exists, and importing a
package stays cheap: the names load their modules on first use."""

import subprocess
import sys

import pytest

PACKAGES = ["bauv_sim", "nav", "tasks", "tasks.core", "tasks.closed_loop", "bauv_sim.sensors"]


def _python(code: str) -> str:
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False
    )
    assert res.returncode == 0, res.stderr
    return res.stdout


@pytest.mark.slow
@pytest.mark.parametrize("package", PACKAGES)
def test_every_exported_name_exists(package):
    out = _python(
        f"""
import importlib
m = importlib.import_module({package!r})
assert len(m.__all__) == len(set(m.__all__)), "no duplicates in __all__"
missing = [n for n in m.__all__ if not hasattr(m, n)]
assert not missing, missing
ns = {{}}
exec("from {package} import *", ns)
assert set(m.__all__) <= set(ns), set(m.__all__) - set(ns)
assert set(m.__all__) <= set(dir(m))
root = {package!r}.split(".")[0]
import inspect
own = [n for n in m.__all__ if inspect.isclass(getattr(m, n)) or inspect.isfunction(getattr(m, n))]
foreign = [n for n in own if getattr(m, n).__module__.split(".")[0] != root]
assert not foreign, foreign
try:
    m.no_such_name
except AttributeError as exc:
    assert "no_such_name" in str(exc)
else:
    raise SystemExit("an unknown name must raise AttributeError")
print(len(m.__all__))
"""
    )
    assert int(out) > 0


def test_importing_the_packages_is_cheap_and_nav_stays_apart():
    out = _python(
        """
import sys
import nav
assert not [k for k in sys.modules if k.split(".")[0] in ("bauv_sim", "mujoco", "tasks")]
import bauv_sim, tasks, tasks.core, tasks.closed_loop
print(sorted(k for k in ("mujoco", "matplotlib", "rerun", "dm_control") if k in sys.modules))
"""
    )
    assert out.strip() == "[]"


@pytest.mark.slow
def test_the_readme_library_example_runs(tmp_path):
    """The README's "Use it as a library" code blocks run as written (with small batches)."""
    import re
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    section = readme.split("## Use it as a library", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert blocks, "no python example in the section"
    code = "\n".join(blocks).replace('"runs/', f'"{tmp_path}/')
    out = _python(code)
    assert "EKF" in out
