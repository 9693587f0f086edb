"""The ellipsoid fluid model in the plugin against MuJoCo's own, on the manoeuvres (issue 27).

Since issue 27 the plugin ``bauv.hydro`` applies MuJoCo's ellipsoid fluid model (numeric
``hydro_water``; ``option density`` and ``viscosity`` 0), so that a step computes neither MuJoCo's
fluid model nor its velocity derivatives. The forces are the same (``tests/bauv_sim/
test_hydro_fluid.py``, to 1e-9); what changes is that implicitfast no longer treats them
implicitly. This flies the full model through the manoeuvres of issue 27's check 1 (cruise speed
and power, turns at +-10 and +-20 deg of bias, the +0.2 rad fin step, the autopilot's 5 m depth
step, 0.3 m/s current steps along and across: ``manoeuvring_id.full_results``) at the missions'
4 ms step with the fluid model in the plugin (the model file) and in MuJoCo
(``build_physics(hydrodynamics="mujoco-fluid")``, the model as before), and compares them with the
timestep table's thresholds (``manoeuvring_id.bound``).

Run from the repository root (about 4 minutes on a free machine)::

    python models/bauv/tools/fluid_model.py                # print the table
    python models/bauv/tools/fluid_model.py --write        # and write it into the model README
"""

from __future__ import annotations

import argparse
import time

from checks import cruise_frequency_hz
from manoeuvring_id import bound, full_results, write_readme

from bauv_sim import hydro_native


def render(old: dict[str, float], new: dict[str, float]) -> str:
    """Markdown table: MuJoCo's fluid model against the plugin's, with the thresholds."""
    lines = [
        "| quantity | threshold | MuJoCo fluid model (as before) | plugin fluid model "
        "| difference | holds |",
        "|---|---|---|---|---|---|",
    ]
    for k, x in old.items():
        kind, b = bound(k, old)
        y = new[k]
        diff = (y - x) / abs(x) if kind == "relative" else y - x
        ok = "yes" if abs(diff) <= b else "NO"
        if kind == "relative":
            d = f"{diff * 100:+.3f} %"
            lines.append(f"| {k} | {b * 100:g} % | {x:.6g} | {y:.6g} | {d} | {ok} |")
        else:
            lines.append(f"| {k} | {b:.3g} | {x:.6g} | {y:.6g} | {diff:+.3g} | {ok} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--write", action="store_true", help="write the table into the model README")
    args = ap.parse_args()
    f = cruise_frequency_hz()
    res = {}
    for kind in ("mujoco-fluid", "plugin"):
        t0 = time.perf_counter()
        with hydro_native.formulation(kind):
            res[kind] = full_results(f)
        print(f"{kind}: {time.perf_counter() - t0:.1f} s")
    table = render(res["mujoco-fluid"], res["plugin"])
    print(table)
    if args.write:
        write_readme(table, tag="fluid-model")


if __name__ == "__main__":
    main()
