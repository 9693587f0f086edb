"""The hydrodynamics checks of issue 11, measured on the physics.

Each ``check_*`` function runs one experiment through the facade and returns its numbers;
:func:`main` runs them, prints them and rewrites the tables of ``models/bauv/README.md`` between
``<!-- BEGIN results:hydro-NAME -->`` and its ``END`` marker, beside the values measured on the
model before the plugin ``bauv.hydro`` (commit 79e14d2, by the same procedures: :data:`BEFORE`).

The checks are in :mod:`hydro_body` (the spheroid, sway mass, broadside drag, side force, roll,
turns) and :mod:`hydro_water` (a step of the current, a sea put around the vehicle, the fins,
plain MuJoCo, a vehicle in water of its own, the caudal spring, the approximations); the tables
and the figures of the models before are :mod:`hydro_report`.

Run from the repository root (the scripts of ``models/bauv/tools`` import each other by name)::

    python models/bauv/tools/hydro.py                 # everything (a few minutes)
    python models/bauv/tools/hydro.py spheroid turns  # some checks only

References: Lamb (1932) *Hydrodynamics* sec. 114-115, 124; Fossen (2021) *Handbook of Marine Craft
Hydrodynamics and Motion Control* ch. 6-7 (added mass, Coriolis, the linear manoeuvring model);
Hoerner (1965) *Fluid-Dynamic Drag* ch. 3 (crossflow); Munk (1924), NACA Report 184 (slender-body
moment); Newman (1977) *Marine Hydrodynamics* sec. 4.13, 7.? (strip theory of added mass).
"""

from __future__ import annotations

import argparse
import time

from checks import README, rewrite_readme
from hydro_body import (
    check_broadside,
    check_roll,
    check_side_force,
    check_spheroid,
    check_sway_mass,
    check_turns,
)
from hydro_report import render
from hydro_water import (
    check_approximations,
    check_current_step,
    check_fins,
    check_own_water,
    check_plain_mujoco,
    check_set_sea,
    check_spring,
)


def check_bauv() -> dict[str, object]:
    """Sway mass, broadside drag, hull side force and the yaw moment, roll."""
    return {
        "sway": check_sway_mass(),
        "broadside": check_broadside(),
        "side": check_side_force(),
        "roll": check_roll(),
    }


CHECKS = {
    "spheroid": check_spheroid,
    "bauv": check_bauv,
    "turns": check_turns,
    "step": check_current_step,
    "sea": check_set_sea,
    "fins": check_fins,
    "plain": check_plain_mujoco,
    "water": check_own_water,
    "spring": check_spring,
    "approximations": check_approximations,
}
"""The checks by name, in the order :func:`main` runs them."""


def main(argv: list[str] | None = None) -> dict[str, object]:
    """Run the checks, print them and rewrite the README tables (``--no-write``: print only)."""
    parser = argparse.ArgumentParser(description="BAUV hydrodynamics checks (issue 11)")
    parser.add_argument("checks", nargs="*", choices=[*CHECKS, []], default=[])
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    results: dict[str, object] = {}
    sections: dict[str, str] = {}
    for name in args.checks or list(CHECKS):
        t0 = time.perf_counter()
        results[name] = CHECKS[name]()
        sections[f"hydro-{name}"] = render(name, results[name])
        print(f"## {name} ({time.perf_counter() - t0:.1f} s wall)\n{sections[f'hydro-{name}']}\n")
    if not args.no_write:
        rewrite_readme(sections, README)
    return results


if __name__ == "__main__":
    main()
