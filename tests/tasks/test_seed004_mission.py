"""``mission/seed004``: seed 004's filters steering the BAUV on bearings to beacons.

Truths used: the beacons read back from the built scene (MuJoCo sites) against the seed's
section-6 beacons scaled by hand; the distance to a polyline against brute force on a dense
sampling; the course hand-over checked by the flight staying near the nominal path (a vehicle
steered with a wrong angle convention leaves it by tens of metres in 20 s)."""

import itertools
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from bauv_sim.build import build_physics
from tasks.core import registry
from tasks.core.runner import plan_batch, run
from tasks.missions.seed004 import (
    Seed004Mission,
    beacons_world,
    depth_setpoint,
    distance_to_polyline,
)

NAME = "mission/seed004"
FAST = [
    "seed004.duration_s=20",
    "timing.max_duration_s=20",
    "seed004.train_paths=200",
    "seed004.surrogate_test_paths=100",
    "report.figures=false",
    "report.recording=false",
]


def _metrics(out):
    return json.loads((out / "metrics.json").read_text())


@pytest.fixture(scope="module")
def short_runs(tmp_path_factory):
    outs = []
    for name in ("a", "b"):
        out = tmp_path_factory.mktemp(name)
        run(NAME, n_runs=1, seed=3, out_dir=out, overrides=FAST, progress=False)
        outs.append(out)
    return outs


def test_short_run_completes_without_nan_and_stays_on_the_path(short_runs):
    m = _metrics(short_runs[0])
    assert m["failures"] == [] and m["warnings"] == []
    assert set(m["filters"]) == {"ekf", "upmf", "cmnf"}
    for f, s in m["filters"].items():
        assert s["runs_ok"] == 1, f
        for k, v in s.items():
            vals = v if isinstance(v, list) else [v]
            assert all(x is not None and math.isfinite(x) for x in vals), (f, k, v)
        # 20 s along a path that turns by +-60 deg: a wrong course convention (theta taken as a
        # course, or its sign flipped) puts the vehicle tens of metres off; the box-limited
        # control on a ~1 m estimate keeps it within a few metres
        assert s["path_max_m"] < 5.0, (f, s["path_max_m"])
        assert s["est_rmse_m"] < 3.0, (f, s["est_rmse_m"])
    assert math.isfinite(m["cmnf_gap_m2"]) and math.isfinite(m["cmnf_j_mean_gap_m2"])
    assert (short_runs[0] / "cmnf-gains.npz").exists()


def test_same_seed_same_numbers(short_runs):
    a, b = ((o / "metrics.json").read_text() for o in short_runs)
    assert a == b


def test_scene_beacons_are_the_seeds_scaled_about_the_start():
    scn = plan_batch(NAME, overrides=FAST).scenario
    st = scn.start
    k = scn.seed004.speed_m_s / 2.0  # seed 004: V° = 2 m/s
    seed_b = [(500, 100), (500, -100), (-100, 100), (-100, -100)]  # section 6, start (0, 0)
    want = np.array([[st.east_m + k * x, st.north_m + k * y, -0.3] for x, y in seed_b])
    assert np.allclose(beacons_world(scn), want, atol=1e-12)
    design = Seed004Mission("ekf")
    physics = build_physics(design.scene(scn), control_tick_s=scn.timing.control_tick_s)
    got = physics.beacons_world()
    assert sorted(got) == [f"beacon_{i}" for i in range(4)]
    # the seabed heightfield is float32 in MuJoCo: mm agreement
    assert np.allclose(np.stack([got[f"beacon_{i}"] for i in range(4)]), want, atol=5e-3)


def test_distance_to_polyline_matches_brute_force():
    rng = np.random.default_rng(0)
    line = np.cumsum(rng.normal(size=(6, 3)), axis=0)
    pts = rng.normal(size=(50, 3)) * 2
    t = np.linspace(0, 1, 20001)[:, None]
    dense = np.concatenate([a + t * (b - a) for a, b in itertools.pairwise(line)])
    brute = np.min(np.linalg.norm(pts[:, None] - dense[None], axis=2), axis=1)
    got = distance_to_polyline(pts, line)
    assert np.all(got <= brute + 1e-12)
    assert np.allclose(got, brute, atol=1e-3)


def test_the_registered_flight_is_the_seed004_design():
    scn = plan_batch(NAME, overrides=[*FAST, "navigation.filter=upmf"]).scenario
    design, _ = registry.get(NAME).flight(scn, 0, 0)
    assert isinstance(design, Seed004Mission) and design.filter == "upmf"


def _bauv(tmp_path, *args):
    return subprocess.run(
        [sys.executable, "-m", "tasks.core.cli", "run", NAME, *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )


@pytest.mark.parametrize(
    "args, pattern",
    [
        (["--set", "navigation.filter=kalman"], "navigation.filter"),
        (["--set", "doa.period_s=2.0"], "doa.period_s = 2"),
        (["--set", "seed004.beacon_depth_m=40"], "seed004.beacon_depth_m = 40"),
        (["--set", "start.depth_m=0.5"], "start.depth_m = 0.5"),
        (["--set", "seed004.v_min_m_s=1.2", "--set", "seed004.v_max_m_s=1.0"], "v_min_m_s"),
    ],
)
def test_bad_input_is_one_line_exit_2(tmp_path, args, pattern):
    out = tmp_path / "bad"
    res = _bauv(tmp_path, "--runs", "1", "--out", str(out), *args)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and pattern in lines[0] and "Traceback" not in res.stderr, lines
    assert not out.exists()


def test_lost_bearings_degrade_with_a_warning_and_no_nan(tmp_path):
    out = tmp_path / "drop"
    over = [*FAST, "doa.dropout_probability=0.5", "navigation.filter=upmf"]
    run(NAME, n_runs=1, seed=3, out_dir=out, overrides=over, progress=False)
    m = _metrics(out)
    assert len(m["warnings"]) == 1 and "bearing pairs absent" in m["warnings"][0]
    s = m["filters"]["upmf"]
    assert s["runs_ok"] == 1 and math.isfinite(s["est_rmse_m"])


@pytest.mark.parametrize("gamma_deg, v", [(5.0, 1.0), (-8.0, 0.7), (2.0, 1.3)])
def test_depth_setpoint_makes_the_depth_loop_fly_the_pitch(gamma_deg, v):
    """The autopilot's own depth PD (integral off) at the set-point, climbing at the commanded
    rate w = V sin(gamma), asks for the pitch that holds that rate (V sin(pitch) = w, to the
    small-angle order the loop's linear law has)."""
    from bauv_sim.autopilot import PID, AutopilotConfig

    ap = AutopilotConfig()
    u = np.array([math.radians(gamma_deg), 0.3, v])
    depth = 2.0
    sp = depth_setpoint(depth, u, ap)
    w_up = v * math.sin(u[0])
    pid = PID(ap.depth_kp, 0.0, ap.depth_kd, -1.0, 1.0)
    pitch = -pid.step(sp - depth, -w_up, 0.2)  # as the autopilot: depth error, depth rate
    assert v * pitch == pytest.approx(w_up, rel=1e-9)
