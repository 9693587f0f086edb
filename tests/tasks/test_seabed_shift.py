"""``paper-004/seabed-shift``: its nominal path and control against eq. 3 and eq. 6 worked out
here, a small measurement, the registered experiment end to end (blocks pooled as one batch),
and its refusal of bad input."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tasks.core.runner import run
from tasks.paper004 import seabed_shift as ss


def test_nominal_path_is_eq3_of_section_6():
    x, _v = ss.nominal_path(300)
    assert x.shape == (301, 3)
    np.testing.assert_allclose(x[0], [0.0, 0.0, -10.0])
    np.testing.assert_allclose(np.linalg.norm(np.diff(x, axis=0), axis=1), 2.0, atol=1e-12)
    t = 7.0
    g, th = np.pi / 100 * np.cos(np.pi / 100 * t), np.pi / 3 * np.cos(np.pi / 25 * t)
    step = x[8] - x[7]
    np.testing.assert_allclose(
        step, 2 * np.array([np.cos(g) * np.cos(th), np.cos(g) * np.sin(th), np.sin(g)])
    )


def test_control_of_eq6_lands_on_the_target():
    rng = np.random.default_rng(0)
    pos, target = rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) + [3.0, 0.0, 0.0]
    att, dist = ss.control_attitude(target, pos)
    g, th = att[:, 0], att[:, 1]
    e = np.column_stack([np.cos(g) * np.cos(th), np.cos(g) * np.sin(th), np.sin(g)])
    np.testing.assert_allclose(pos + dist[:, None] * e, target, atol=1e-12)


def test_a_small_measurement_reports_both_readings():
    res = ss.measure_shift_error(paths=3, seed=1, steps=4)
    assert set(res) == {"one_attitude", "turning"}
    for r in res.values():
        s = r.summary()
        assert s["produced"] == s["samples"] == 12
        assert np.isfinite([s["median_m"], s["p90_m"], *s["bias_m"], s["stated_rms_m"]]).all()
    again = ss.measure_shift_error(paths=3, seed=1, steps=4)
    assert np.array_equal(again["turning"].error_m, res["turning"].error_m)


@pytest.mark.slow
def test_bad_arguments_exit_2_with_one_line(tmp_path):
    out = tmp_path / "out"
    for args, pattern in (
        (["--set", "steps=0"], "steps = 0"),
        (["--set", "estimate_sigma_m=nan"], "estimate_sigma_m = nan"),
        (["--set", "delta_e=cubic"], "delta_e"),
        (["--runs", "0"], "runs = 0"),
    ):
        res = subprocess.run(
            [sys.executable, "-m", "tasks.core.cli", "run", "paper-004/seabed-shift"]
            + ["--out", str(out), *args],
            capture_output=True,
            text=True,
            cwd=tmp_path,
        )
        assert res.returncode == 2, res.stderr
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and pattern in lines[0] and "Traceback" not in res.stderr, lines
        assert not out.exists()


def test_the_registered_experiment_pools_its_blocks_as_one_batch(tmp_path):
    """Blocks of 2 paths pooled by the report give the summary of one measurement over all the
    paths."""
    steps = 40
    out, _ = run(
        "paper-004/seabed-shift",
        n_runs=5,
        seed=2,
        out_dir=tmp_path / "run",
        overrides=[f"steps={steps}", "block_size=2"],
        progress=False,
    )
    m = json.loads((out / "metrics.json").read_text())
    want = ss.measure_shift_error(paths=5, seed=2, steps=steps)
    assert m["experiment"] == "paper-004/seabed-shift" and m["n_runs"] == 5
    for r, e in want.items():
        s = e.summary()
        got = m["readings"][r]
        assert got["samples"] == s["samples"] == 5 * steps
        assert got["produced"] == s["produced"] > 0.9 * 5 * steps
        np.testing.assert_allclose(got["median_m"], s["median_m"], rtol=1e-12)
        np.testing.assert_allclose(got["rms_m"], s["rms_m"], rtol=1e-12)
    text = (out / "tables.md").read_text()
    assert "one_attitude" in text and "turning" in text and "nan" not in text.lower()


def test_a_path_draws_the_same_numbers_whatever_the_batch():
    two = ss.measure_shift_error(paths=2, seed=3, steps=3)
    three = ss.measure_shift_error(paths=3, seed=3, steps=3)
    for r in two:
        assert np.array_equal(two[r].error_m, three[r].error_m[:2])
