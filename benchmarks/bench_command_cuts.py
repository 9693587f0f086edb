"""The cuts of ``bauv run mission/survey``'s own costs (issue 27, check 3), each measured alone.

A cut that saves half a second of a 15 s command cannot be seen in whole commands on a loaded
machine (they swing by 30 % between repeats), so each cut is timed on its own: the code before
and after it, each in a fresh interpreter of this checkout (cold imports, as in the command)
after a preamble of the modules the command has already imported at that point, the region
timed inside the child (wall and CPU). Before and after are interleaved through :mod:`harness`
(repeat r rotates the order), with the load beside each. The whole command against the base
checkout is ``bench_step_profile.py --part compare``.

Usage::

    python benchmarks/bench_command_cuts.py                   # every cut, 7 repeats
    python benchmarks/bench_command_cuts.py --cut stats --repeats 11
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

# name -> (what it is, preamble, before, after). Each snippet runs once, timed.
CUTS: dict[str, tuple[str, str, str, str]] = {
    "stats": (
        "chi-square gate and Rice reach test without scipy.stats (first call, with imports)",
        "import tasks.closed_loop.experiment, bauv_sim.build",
        "from scipy.stats import chi2, rice\n"
        "chi2.ppf(0.99, 2); rice.cdf(9.0, 3.0 / 2.0, scale=2.0)",
        "from nav.distributions import chi2_ppf, rice_cdf\n"
        "chi2_ppf(0.99, 2); rice_cdf(9.0, 3.0 / 2.0, scale=2.0)",
    ),
}

CHILD = """
import json, sys, time
{preamble}
t0, c0 = time.perf_counter(), time.process_time()
{snippet}
print(json.dumps([time.perf_counter() - t0, time.process_time() - c0]))
"""


def _run(preamble: str, snippet: str, sink: list[list[float]]) -> None:
    code = CHILD.format(preamble=preamble, snippet=snippet)
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=HERE.parent, check=True, capture_output=True, text=True
    ).stdout
    sink.append(json.loads(out.strip().splitlines()[-1]))


def bench(name: str, repeats: int) -> None:
    from harness import machine, measure, table

    what, preamble, before, after = CUTS[name]
    got: dict[str, list[list[float]]] = {"before": [], "after": []}
    variants = {
        "before": lambda: _run(preamble, before, got["before"]),
        "after": lambda: _run(preamble, after, got["after"]),
    }
    res = measure(variants, repeats=repeats, warmup=1)
    for k, r in res.items():  # the child's region, not the process: drop the warm-up
        r.seconds = [w for w, _ in got[k][1:]]
    print(f"\n### {name}: {what}\n\n{machine()}\n")
    print(table(res, reference="before", unit="ms", scale=1e3))
    cpu = {k: sorted(c for _, c in v[1:]) for k, v in got.items()}
    print(
        "\nCPU (ms, median): "
        + ", ".join(f"{k} {1e3 * v[len(v) // 2]:.0f}" for k, v in cpu.items())
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cut", choices=[*CUTS, "all"], default="all")
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    sys.path.insert(0, str(HERE))
    for name in CUTS if args.cut == "all" else [args.cut]:
        bench(name, args.repeats)


if __name__ == "__main__":
    main()
