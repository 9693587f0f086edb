"""The one benchmark harness of the project's scripts.

Every timing goes through :func:`measure`: the variants are interleaved (repeat r runs them in an
order rotated by r, so A B, B A, A B, ...), each is warmed up first, each repeat records the
machine's 1-minute load average beside its time, and the summary gives the minimum and the median
of each variant and their ratios to a reference variant measured in the same run. A ratio from one
run is comparable across machines and loads; an absolute time is not. Results are written as
Markdown tables by :func:`table` (the scripts paste them into ``benchmarks/README.md``).

Usage::

    from harness import measure, table, machine
    res = measure({"new": f_new, "old": f_old}, repeats=7, warmup=1, per={"new": n, "old": n})
    print(machine())
    print(table(res, reference="old", unit="us", scale=1e6))
"""

from __future__ import annotations

import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field


@dataclass
class Result:
    """The timings of one variant.

    Attributes:
        name: the variant's name.
        per: the amount of work one call does (e.g. path-steps); times are divided by it.
        seconds: wall time of each timed call, s (not divided).
        load: the 1-minute load average just before each timed call.
    """

    name: str
    per: float = 1.0
    seconds: list[float] = field(default_factory=list)
    load: list[float] = field(default_factory=list)

    @property
    def min(self) -> float:
        """Fastest call per unit of work, s."""
        return min(self.seconds) / self.per

    @property
    def median(self) -> float:
        """Median call per unit of work, s."""
        return statistics.median(self.seconds) / self.per

    @property
    def load_range(self) -> tuple[float, float]:
        """Lowest and highest load average seen before this variant's calls."""
        return min(self.load), max(self.load)


def measure(
    variants: Mapping[str, Callable[[], object]],
    *,
    repeats: int = 5,
    warmup: int = 1,
    per: Mapping[str, float] | None = None,
) -> dict[str, Result]:
    """Time interleaved variants.

    Args:
        variants: name -> a call that does the work once.
        repeats: timed calls of each variant.
        warmup: untimed calls of each variant first (imports, caches, allocators).
        per: name -> the amount of work of one call, to report times per unit.

    Returns:
        name -> :class:`Result`, in the order of ``variants``.
    """
    if repeats < 1:
        raise ValueError("repeats must be >= 1")
    names = list(variants)
    out = {n: Result(n, float((per or {}).get(n, 1.0))) for n in names}
    for _ in range(warmup):
        for n in names:
            variants[n]()
    for r in range(repeats):
        order = names[r % len(names) :] + names[: r % len(names)]
        if r % 2:
            order = order[::-1]
        for n in order:
            out[n].load.append(os.getloadavg()[0])
            t0 = time.perf_counter()
            variants[n]()
            out[n].seconds.append(time.perf_counter() - t0)
    return out


def command(
    argv: Sequence[str], env: Mapping[str, str] | None = None, cwd: str | os.PathLike | None = None
) -> Callable[[], None]:
    """A variant that runs a whole command (a fresh process each call, in ``cwd``) and checks its
    status."""

    def run() -> None:
        subprocess.run(
            list(argv),
            check=True,
            cwd=cwd,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            env=None if env is None else {**os.environ, **env},
        )

    return run


def machine() -> str:
    """One line about the machine and the software the numbers were measured with."""
    import numpy

    try:
        import mujoco

        mj = f", MuJoCo {mujoco.__version__}"
    except ImportError:  # pragma: no cover
        mj = ""
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (
        f"{os.cpu_count()} cores ({platform.machine()}), Python {sys.version.split()[0]}, "
        f"numpy {numpy.__version__}{mj}; load average (1, 5, 15 min) at the start: {load}"
    )


def table(
    results: Mapping[str, Result],
    reference: str,
    *,
    unit: str = "s",
    scale: float = 1.0,
    repeats_note: bool = True,
) -> str:
    """A Markdown table: min and median per variant (times ``scale`` in ``unit``), and the
    reference's time over the variant's (so > 1 means faster than the reference), from the
    medians and from the minima, with the load range seen beside each variant.

    Args:
        results: from :func:`measure`.
        reference: the name of the reference variant.
        unit: unit of the scaled times.
        scale: factor from seconds per unit of work to ``unit``.
        repeats_note: add a line with the number of repeats.
    """
    ref = results[reference]
    lines = [
        f"| variant | min ({unit}) | median ({unit}) | {reference} / variant (median) | "
        f"{reference} / variant (min) | load |",
        "|---|---|---|---|---|---|",
    ]
    for r in results.values():
        lo, hi = r.load_range
        lines.append(
            f"| {r.name} | {r.min * scale:.4g} | {r.median * scale:.4g} | "
            f"{ref.median / r.median:.3g} | {ref.min / r.min:.3g} | {lo:.2f}-{hi:.2f} |"
        )
    if repeats_note:
        n = {len(r.seconds) for r in results.values()}
        lines.append("")
        lines.append(f"({'/'.join(map(str, sorted(n)))} interleaved repeats after warm-up)")
    return "\n".join(lines)
