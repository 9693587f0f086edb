"""Size and cost of a mission's recording (issue 28, check 3): a 4-vehicle ``mission/swarm``
(the leader and 3 followers, its default method), the whole ``bauv run`` with the recording on
against the same command with it off, interleaved through the shared harness; the recording's
own write timed in-process on the same flight beside them; its size per simulated minute and
vehicle from two mission lengths (the slope) with what does not grow with time (the hulls'
meshes, the seabed: the intercept), and where the bytes go.

Usage: ``python benchmarks/bench_recording.py [--minutes 4] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import collections
import itertools
import subprocess
import sys
import tempfile
from pathlib import Path

from harness import machine, measure, table

NAME = "mission/swarm"
VEHICLES = 4
BASE = ["followers.count=3", "report.figures=false"]


def bauv_run(out: Path, minutes: float, recording: bool) -> None:
    """``bauv run mission/swarm`` once, one run, into ``out``."""
    sets = [*BASE, f"timing.max_duration_s={60 * minutes:g}"]
    sets.append(f"report.recording={str(recording).lower()}")
    argv = [str(Path(sys.executable).parent / "bauv"), "run", NAME, "--runs", "1", "--quiet"]
    argv += ["--out", str(out)]
    for s in sets:
        argv += ["--set", s]
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def breakdown(path: Path) -> dict[str, int]:
    """Arrow bytes of a recording by what they draw (the entity path's first parts, the
    flight and vehicle left out)."""
    import rerun.chunk as rc

    out: collections.Counter[str] = collections.Counter()
    for ch in rc.RrdReader(str(path)).stream().to_chunks():
        parts = ch.entity_path.strip("/").split("/")
        if parts[0] != "world" or len(parts) < 2:
            key = parts[0] + ("" if parts[0] in ("world", "__properties") else " (time series)")
        elif parts[1] in ("seabed", "scene"):
            key = "world/" + parts[1]
        elif "body" in parts:
            key = "world/<vehicle>/body (hull, fins, tail)"
        else:  # world/[<flight>/]<vehicle>/<what>/<part>
            key = "world/<vehicle>/" + "/".join(parts[-2:])
        out[key] += ch.to_record_batch().nbytes
    return dict(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--minutes", type=float, default=4.0, help="simulated minutes of the timed run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--size-only", action="store_true", help="the size part alone (no timing)")
    a = ap.parse_args()
    print(machine())
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s)
        k = itertools.count()
        if not a.size_only:
            timings(a, tmp, k)
        sizes(a, tmp)


def timings(a, tmp: Path, k) -> None:
    """The whole command with the recording on and off, and the write alone."""
    res = measure(
        {
            "recording on": lambda: bauv_run(tmp / f"on{next(k)}", a.minutes, True),
            "recording off": lambda: bauv_run(tmp / f"off{next(k)}", a.minutes, False),
        },
        repeats=a.repeats,
        warmup=1,
    )
    print(f"\nwhole `bauv run {NAME}` ({VEHICLES} vehicles, {a.minutes:g} simulated min):")
    print(table(res, reference="recording off", unit="s"))
    on, off = res["recording on"], res["recording off"]
    print(
        f"recording's share of the command (1 - off/on): median "
        f"{100 * (1 - off.median / on.median):.1f} %, min {100 * (1 - off.min / on.min):.1f} %"
    )
    # the write itself, in-process, on the flight of the same scenario
    from tasks.core.registry import get
    from tasks.core.runner import plan_batch
    from tasks.missions.swarm.figures import record_swarm

    exp = get(NAME)
    scn = plan_batch(NAME, overrides=[*BASE, f"timing.max_duration_s={60 * a.minutes:g}"])
    rec = exp.run_block(scn.scenario, 0, (0,))[0]
    w = measure(
        {"record_swarm": lambda: record_swarm(NAME, scn.scenario, rec.flights, tmp)},
        repeats=max(a.repeats, 3),
        warmup=1,
    )["record_swarm"]
    print(
        f"record_swarm alone: min {w.min:.2f} s, median {w.median:.2f} s "
        f"(load {w.load_range[0]:.2f}-{w.load_range[1]:.2f}); share of the command with "
        f"the recording on (median): {100 * w.median / on.median:.1f} %"
    )


def sizes(a, tmp: Path) -> None:
    """The recording's size at 1 min and ``--minutes``: per simulated minute and vehicle, what
    does not grow with time, and where the bytes go."""
    # size: two lengths, the slope per simulated minute and vehicle, and the intercept
    size = {}
    for minutes in (1.0, a.minutes):
        out = tmp / f"size{minutes:g}"
        bauv_run(out, minutes, True)
        size[minutes] = (out / "recording.rrd").stat().st_size
    (m1, s1), (m2, s2) = sorted(size.items())
    slope = (s2 - s1) / (m2 - m1) / VEHICLES
    static = s1 - slope * VEHICLES * m1
    print(
        f"\nrecording size: {s1 / 1e6:.2f} MB at {m1:g} min, {s2 / 1e6:.2f} MB at {m2:g} min: "
        f"{slope / 1e3:.0f} kB per simulated minute and vehicle, {static / 1e6:.2f} MB that "
        f"does not grow with time"
    )
    parts = breakdown(out / "recording.rrd")
    total = sum(parts.values())
    print(f"\nwhere the bytes go ({m2:g} min, Arrow bytes before the file's compression):")
    print("| part | kB | share |\n|---|---:|---:|")
    for key, b in sorted(parts.items(), key=lambda kv: -kv[1]):
        print(f"| {key} | {b / 1e3:.0f} | {100 * b / total:.1f} % |")


if __name__ == "__main__":
    main()
