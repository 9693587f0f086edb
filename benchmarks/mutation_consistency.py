"""Mutation check of the consistency tests: each must fail when the filter is mis-tuned.

For each mutation (the filters' USBL R scaled by 4 or 1/4, their motion Q scaled by 4 or 1/4) the
consistency tests run with the mutation applied, and the check reports which of them fail. A
mutation that no consistency test catches is a failure of the check (exit status 1); so is a
consistency test that fails without a mutation.

The mutation is applied when the models are built: the sigmas of every
:class:`nav.models.UsblMeasurement` (R = diag(sigma^2), so sigmas x 2 is R x 4), or of every
:class:`nav.models.CourseSpeedDepthMotion` and the current walk of every
:class:`nav.models.CurrentAwareMotion` (Q is quadratic in them) are scaled. The truth is not
touched: the simulated sensors draw from their own configuration.

Usage::

    .venv/bin/python benchmarks/mutation_consistency.py            # all mutations
    .venv/bin/python benchmarks/mutation_consistency.py R*4 Q/4    # some

It is also a pytest plugin (``-p mutation_consistency`` with this folder on the path and
``BAUV_MUTATION`` set), which is how the check applies a mutation inside the test process.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

TESTS = [
    "tests/nav/test_navigator.py::test_navigator_is_consistent_on_a_matched_world",
    "tests/tasks/test_paper000.py::test_matched_gaussian_errors_are_consistent",
    "tests/tasks/test_paper000.py::test_matched_gaussian_innovations_are_white_and_in_band",
    "tests/tasks/test_missions.py::test_mission_navigator_is_consistent",
]
"""The consistency tests (Monte Carlo NEES / NIS against chi-square bands)."""

MUTATIONS = ("R*4", "R/4", "Q*4", "Q/4")

_FIELDS = {
    "R": [("UsblMeasurement", ("sigma_range_m", "sigma_azimuth_rad", "sigma_elevation_rad"))],
    "Q": [
        (
            "CourseSpeedDepthMotion",
            ("sigma_course_rad", "sigma_speed_m_s", "sigma_depth_change_m"),
        ),
        ("CurrentAwareMotion", ("sigma_current_walk_m_s_per_sqrt_s",)),
    ],
}


def apply(mutation: str) -> None:
    """Scale the covariance named by ``mutation`` (``"R*4"``, ``"Q/4"``, ...) in every model built
    from now on (the sigmas by the square root of the factor)."""
    from nav import models

    what, op, factor = mutation[0], mutation[1], float(mutation[2:])
    if what not in _FIELDS or op not in "*/":
        raise ValueError(f"mutation {mutation!r}: expected R*k, R/k, Q*k or Q/k")
    scale = math.sqrt(factor if op == "*" else 1.0 / factor)
    for cls_name, fields in _FIELDS[what]:
        cls = getattr(models, cls_name)
        original = cls.__init__

        def init(self, *args, _original=original, _fields=fields, **kwargs):
            _original(self, *args, **kwargs)
            for f in _fields:
                object.__setattr__(self, f, getattr(self, f) * scale)

        cls.__init__ = init


def pytest_configure(config) -> None:
    """Pytest plugin hook: apply ``BAUV_MUTATION`` before the tests import and build models."""
    mutation = os.environ.get("BAUV_MUTATION")
    if mutation:
        apply(mutation)


def run_tests(mutation: str | None) -> dict[str, bool]:
    """Run the consistency tests in one pytest process; returns test -> passed."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(HERE)])}
    env.pop("BAUV_MUTATION", None)
    if mutation:
        env["BAUV_MUTATION"] = mutation
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "mutation_consistency", "-rA"]
    proc = subprocess.run(
        [*cmd, *TESTS], cwd=ROOT, env=env, capture_output=True, text=True, check=False
    )
    passed = {t: False for t in TESTS}
    for line in proc.stdout.splitlines():
        if line.startswith("PASSED "):
            passed[line.split()[1]] = True
    return passed


def main(argv: list[str] | None = None) -> int:
    names = list(argv if argv is not None else sys.argv[1:]) or list(MUTATIONS)
    status = 0
    baseline = run_tests(None)
    print(
        "no mutation: " + ", ".join(f"{t.split('::')[1]} {_word(ok)}" for t, ok in baseline.items())
    )
    if not all(baseline.values()):
        status = 1
    for name in names:
        result = run_tests(name)
        failed = [t.split("::")[1] for t, ok in result.items() if not ok]
        caught = bool(failed)
        status = status or (0 if caught else 1)
        print(
            f"{name}: {'caught' if caught else 'NOT CAUGHT'} by {len(failed)} of {len(result)}"
            + (": " + ", ".join(failed) if failed else "")
        )
    return status


def _word(ok: bool) -> str:
    return "passes" if ok else "FAILS"


if __name__ == "__main__":
    sys.exit(main())
