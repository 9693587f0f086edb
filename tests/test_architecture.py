"""The layout issue 22 set, checked on the source: one Kalman update, one dead reckoning, a
framework that names no experiment, no circle of imports and no module over 800 lines.

Each check reads the code (``ast``), never runs it, and fails naming the file and line. The
allowances are explicit lists with the reason of each entry: a new exception is a reviewed change
to this file, never a silent one.
"""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("bauv_sim", "nav", "tasks")
MAX_LINES = 800

KALMAN_HOME = {"nav/ekf.py"}
"""The one Kalman update (seed 000 eq. 19-23): the gain and the Joseph form live here only."""
KALMAN_OWN_ALGORITHMS = {
    "nav/bearings/filters.py::upmf_update": "seed 004's UPMF (eq. 19-21): the gain of the "
    "pseudo-measurements with a pseudo-inverse floor, its own algorithm",
    "nav/bearings/cmnf.py": "seed 004's CMNF (eq. 22-24): gains from Monte Carlo moments of "
    "training paths, not a Kalman update",
}
"""Documented exceptions: a file, or ``file::function``, with why it is not a Kalman update."""
DR_HOME = {"nav/dead_reckoning.py"}
"""The one dead reckoning (seed 000 eq. 8-10, 16; seed 001 eq. 30-33; seed 003 eq. 1)."""


def _modules() -> list[Path]:
    out: list[Path] = []
    for pkg in PACKAGES:
        out += sorted(p for p in (ROOT / pkg).rglob("*.py") if "__pycache__" not in p.parts)
    return out


def _rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def _names_in(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} | {
        n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)
    }


_GAIN_TARGET = re.compile(r"^(K|Kt|KT|k_gain|gain|kalman_gain|.*_gain)$")
_INVERSES = {"solve", "inv", "pinv", "pinv_floor", "inverse_spd_small", "lstsq"}


def _called(node: ast.AST) -> set[str]:
    out = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Call):
            f = n.func
            out.add(f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", ""))
    return out


def _has_products(node: ast.AST) -> bool:
    return any(
        isinstance(n, ast.BinOp) and isinstance(n.op, (ast.MatMult, ast.Mult))
        for n in ast.walk(node)
    )


def _functions(tree: ast.AST) -> dict[int, str]:
    """Line -> name of the innermost function holding it."""
    out: dict[int, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for line in range(node.lineno, (node.end_lineno or node.lineno) + 1):
                # inner functions come later in the walk and overwrite their lines
                out[line] = node.name
    return out


def _allowed(rel: str, line: int, funcs: dict[int, str], allowed: dict[str, str]) -> bool:
    return rel in allowed or f"{rel}::{funcs.get(line, '')}" in allowed


def kalman_sites(path: Path) -> list[str]:
    """Places in one module that compute a Kalman gain or a Joseph-form covariance.

    A gain: an assignment to ``K`` (or a ``*gain`` name) from products or an inverse of the
    innovation covariance. A Joseph form: ``I - K H`` spelled with an identity (``eye``/``1.0``)
    minus a product holding the gain, or ``K @ R @ K^T``.
    """
    sites = []
    for node in ast.walk(_tree(path)):
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names = [t.id for t in targets if isinstance(t, ast.Name)]
            value = node.value
            if value is None:
                continue
            if any(_GAIN_TARGET.match(n) for n in names) and (
                _has_products(value) or _called(value) & _INVERSES
            ):
                sites.append(f"{_rel(path)}:{node.lineno}: Kalman gain {names[0]} = ...")
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Sub):
            left, right = node.left, node.right
            identity = ("eye" in _called(left) or "identity" in _called(left)) or (
                isinstance(left, ast.IfExp)
            )
            if identity and {"K", "Kt", "gain"} & _names_in(right) and _has_products(right):
                sites.append(f"{_rel(path)}:{node.lineno}: Joseph form I - K H")
    return sites


@pytest.mark.slow
def test_no_kalman_gain_or_joseph_form_outside_the_one_update():
    found = []
    for path in _modules():
        rel = _rel(path)
        if rel in KALMAN_HOME:
            continue
        funcs = _functions(_tree(path))
        for site in kalman_sites(path):
            line = int(site.split(":")[1])
            if not _allowed(rel, line, funcs, KALMAN_OWN_ALGORITHMS):
                found.append(site)
    assert not found, "Kalman gain or Joseph form outside nav.ekf:\n" + "\n".join(found)


def test_the_kalman_detector_sees_the_one_update():
    # the detector is not blind: it finds the gain and the Joseph form where they are
    sites = [s for home in KALMAN_HOME for s in kalman_sites(ROOT / home)]
    assert any("Kalman gain" in s for s in sites), sites


CUMSUM_ALLOWED = {
    # file or file::function: why a sum of steps there is not dead reckoning
    "nav/models.py": "the motion models' f(x, u, dt) (seed 000 eq. 16): the filter's prediction",
    "tasks/closed_loop/figures.py::moving_mean": "a moving mean of a plotted series",
    "tasks/missions/swarm/run.py::leader_course_true": "the moving mean of the leader's true "
    "velocity (its course over ground through the tail beat)",
    "tasks/vehicle/autopilot.py::beat_average": "a moving mean over one tail beat",
    "tasks/core/figures.py::histograms": "the empirical CDF of a histogram",
    "tasks/missions/seed004/metrics.py": "the empirical CDF of the shift errors' histogram",
    "tasks/paper004/report.py": "the empirical CDF of the shift errors' histogram",
    "nav/trn/particle.py::systematic_resample": "the cumulative distribution of the particles' "
    "weights that systematic resampling points into",
}
"""Sums of steps in ``nav`` and ``tasks`` that are not dead reckoning, each with its reason (the
truth generators of ``bauv_sim.kinematic`` and the sensors' random walks integrate the truth or an
error, not an estimate, and are not searched)."""


def dr_sites(path: Path) -> list[str]:
    """Places in one module that integrate displacements into positions.

    ``np.cumsum`` of anything (the batched form of dead reckoning), and loops or augmented
    assignments that add a step's displacement to a position (``pos += v * dt``, ``x = x + ...dt``
    on a name of a position).
    """
    sites = []
    pos = re.compile(r"^(pos|position|p|x|xy|dr|dr_pos|dr_position|est|track)(_\w+)?$")
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
            if name == "cumsum":
                sites.append(f"{_rel(path)}:{node.lineno}: cumsum")
        if isinstance(node, ast.AugAssign) and isinstance(node.op, ast.Add):
            t = node.target
            tname = (
                t.id if isinstance(t, ast.Name) else getattr(getattr(t, "value", None), "id", "")
            )
            if pos.match(tname or "") and {"dt", "dt_s", "step_s"} & _names_in(node.value):
                sites.append(f"{_rel(path)}:{node.lineno}: {tname} += ... dt")
    return sites


@pytest.mark.slow
def test_no_dead_reckoning_outside_the_one():
    found = []
    for path in _modules():
        rel = _rel(path)
        if rel in DR_HOME or not rel.startswith(("nav/", "tasks/")):
            continue
        funcs = _functions(_tree(path))
        for site in dr_sites(path):
            line = int(site.split(":")[1])
            if not _allowed(rel, line, funcs, CUMSUM_ALLOWED):
                found.append(site)
    assert not found, (
        "dead reckoning outside nav.dead_reckoning (or a cumulative sum to justify in "
        "CUMSUM_ALLOWED):\n" + "\n".join(found)
    )


def test_the_dead_reckoning_detector_sees_the_one():
    assert any("cumsum" in s for h in DR_HOME for s in dr_sites(ROOT / h))


def _experiment_words() -> set[str]:
    """Every experiment's name and family, and every experiment package's module path."""
    words: set[str] = set()
    catalog = ROOT / "tasks" / "catalog.json"
    for name, _ in json.loads(catalog.read_text(encoding="utf-8")):
        words.add(name)
        words.add(name.split("/")[0] + "/")
    for pkg in (ROOT / "tasks").iterdir():
        if pkg.is_dir() and (pkg / "__init__.py").exists() and pkg.name != "core":
            words.add(f"tasks.{pkg.name}")
    return words


def test_the_framework_names_no_experiment():
    words = _experiment_words()
    assert len(words) > 10, words
    found = []
    for path in sorted((ROOT / "tasks" / "core").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        for w in sorted(words):
            for m in re.finditer(re.escape(w), text):
                line = text.count("\n", 0, m.start()) + 1
                found.append(f"{_rel(path)}:{line}: {w!r}")
    assert not found, "tasks/core names an experiment:\n" + "\n".join(found)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _runtime_nodes(tree: ast.AST):
    """Every node of the tree but those under ``if TYPE_CHECKING:`` (imports for annotations only,
    never executed)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and "TYPE_CHECKING" in _names_in(child.test):
                todo.extend(child.orelse)
                continue
            todo.append(child)


def _import_edges() -> dict[str, set[str]]:
    """Module -> the project's modules it imports when it runs (at any depth of the code: an import
    inside a function is still an import; one under ``if TYPE_CHECKING:`` is not)."""
    paths = _modules()
    mods = {_module_name(p): p for p in paths}
    edges: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        is_pkg = path.name == "__init__.py"
        for node in _runtime_nodes(_tree(path)):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    here = mod.split(".") if is_pkg else mod.split(".")[:-1]
                    up = here[: len(here) - node.level + 1]
                    base = ".".join([*up, base] if base else up)
                targets = [f"{base}.{a.name}" for a in node.names] + [base]
            for t in targets:
                # the longest prefix that is one of the project's modules
                while t and t not in mods:
                    t = t.rpartition(".")[0]
                if t and t != mod:
                    edges[mod].add(t)
                    break
    return edges


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    import sys

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10_000))
    try:
        for v in sorted(edges):
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return out


@pytest.mark.slow
def test_no_circle_of_imports():
    cycles = _cycles(_import_edges())
    assert not cycles, "circles of imports:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_the_circle_detector_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


@pytest.mark.parametrize("pkg", PACKAGES)
def test_no_module_over_800_lines(pkg):
    long = []
    for path in sorted((ROOT / pkg).rglob("*.py")):
        n = len(path.read_text(encoding="utf-8").splitlines())
        if n > MAX_LINES:
            long.append(f"{_rel(path)}: {n} lines")
    assert not long, f"modules over {MAX_LINES} lines:\n" + "\n".join(long)
