"""The Python around ``mission/survey``'s physics: its start-up and its flight, against another
checkout (``--reference DIR``, e.g. the code before a change), whole processes interleaved in one
run through the shared harness.

Two variants per checkout, each a fresh interpreter with the checkout first on ``PYTHONPATH``:

* **start-up**: ``from tasks.core import runner, registry; registry.get("mission/survey")``, the
  imports ``bauv run mission/survey`` makes before its flight (the CLI imports the runner, the
  runner asks the registry for the mission); against ``python -c pass``.
* **flight**: ``bauv run mission/survey --set report.figures=false --set report.recording=false``,
  the whole command without the figures and the recording (its flight, 5,309 control ticks of
  the sensor rig, navigator, guidance, autopilot and world around the MuJoCo steps, and its
  tables and Parquet run data); ``--no-flight`` skips it.

Each variant's wall time (the harness's table, with the load) and its CPU time (user + system of
the child process, less sensitive to a loaded machine) are printed.

Usage::

    python benchmarks/bench_mission_python.py --reference ../main-checkout --repeats 5

The reference checkout needs the compiled plugin beside its ``bauv_sim/plugin/hydro.c``
(``pip install -e`` there, or the ``.so`` copied from this one).
"""

from __future__ import annotations

import argparse
import resource
import statistics
import sys
import tempfile
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path

from harness import command, machine, measure, table

ROOT = Path(__file__).resolve().parents[1]

STARTUP = (
    "from tasks.core import runner, registry; e = registry.get('mission/survey'); "
    "assert e.name == 'mission/survey'"
)


CPU: dict[str, list[float]] = defaultdict(list)
"""CPU time (user + system) of each call of each variant, s: less sensitive to a loaded machine
than its wall time."""


def with_cpu(name: str, f: Callable[[], None]) -> Callable[[], None]:
    """``f`` (which runs a child process), recording the child's CPU time in :data:`CPU`."""

    def run() -> None:
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        f()
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        CPU[name].append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)

    return run


def variants(checkout: Path, label: str, tmp: Path, flight: bool) -> dict:
    env = {"PYTHONPATH": str(checkout)}
    out = {f"start-up ({label})": command([sys.executable, "-c", STARTUP], env, checkout)}
    if flight:
        k = iter(range(10**6))

        def run_flight() -> None:
            command(
                [sys.executable, "-m", "tasks.core.cli", "run", "mission/survey", "--quiet"]
                + ["--set", "report.figures=false", "--set", "report.recording=false"]
                + ["--out", str(tmp / f"{label}-{next(k)}")],
                env,
                checkout,
            )()

        out[f"flight ({label})"] = run_flight
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reference", type=Path, required=True, help="the checkout to compare with")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-flight", action="store_true", help="measure the start-up only")
    a = ap.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s)
        v = {"python -c pass": command([sys.executable, "-c", "pass"])}
        v |= variants(ROOT, "this checkout", tmp, not a.no_flight)
        v |= variants(a.reference.resolve(), "reference", tmp, not a.no_flight)
        res = measure({k: with_cpu(k, f) for k, f in v.items()}, repeats=a.repeats, warmup=1)
        print(table(res, reference="python -c pass", unit="s"))
        print("\n| variant | CPU min (s) | CPU median (s) |\n|---|---|---|")
        for k, cpu in CPU.items():
            timed = cpu[1:]  # the first call is the warm-up
            print(f"| {k} | {min(timed):.3f} | {statistics.median(timed):.3f} |")
        print()
        for what in ("start-up",) + (() if a.no_flight else ("flight",)):
            new, old = res[f"{what} (this checkout)"], res[f"{what} (reference)"]
            cn, co = CPU[f"{what} (this checkout)"][1:], CPU[f"{what} (reference)"][1:]
            print(
                f"{what}: reference / this checkout = {old.median / new.median:.3f}x by the "
                f"median, {old.min / new.min:.3f}x by the minimum; saved "
                f"{old.median - new.median:+.3f} s (median), {old.min - new.min:+.3f} s (min); "
                f"CPU saved {statistics.median(co) - statistics.median(cn):+.3f} s (median), "
                f"{min(co) - min(cn):+.3f} s (min)"
            )


if __name__ == "__main__":
    main()
