"""``mission/seed004``: seed 004's filters steering the BAUV on bearings to beacons.

Truths used: the beacons read back from the built scene (MuJoCo sites) against the seed's
section-6 beacons scaled by hand; the distance to a polyline against brute force on a dense
sampling; the course hand-over checked by the flight staying near the nominal path (a vehicle
steered with a wrong angle convention leaves it by tens of metres in 20 s)."""

import dataclasses
import itertools
import json
import math
import re

import numpy as np
import pyarrow.parquet as pq
import pytest

from bauv_sim.build import build_physics
from nav.bearings import velocity
from tasks.core import registry
from tasks.core.export import open_dataset
from tasks.core.runner import plan_batch, run
from tasks.missions.seed004 import (
    Seed004Mission,
    beacons_world,
    depth_setpoint,
    distance_to_polyline,
    surrogate,
)
from tests.tasks.refusal import assert_refused

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


@pytest.mark.slow
def test_short_run_completes_without_nan_and_stays_on_the_path(short_runs):
    m = _metrics(short_runs[0])
    assert m["failures"] == [] and m["warnings"] == []
    assert set(m["filters"]) == {"ekf", "upmf", "cmnf"}
    for f, s in m["filters"].items():
        assert s["runs_ok"] == 1, f
        for k, v in s.items():
            if k.startswith("shift_") and k not in ("shift_steps", "shift_none_steps"):
                assert v is None, (f, k, v)  # no seabed prediction: no seabed shift
                continue
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
    files = sorted(p.relative_to(short_runs[0]) for p in short_runs[0].rglob("*.parquet"))
    assert len(files) == 6  # ticks and doa of each filter's flight
    for rel in files:
        ta, tb = (pq.read_table(o / rel) for o in short_runs)
        assert ta.equals(tb), rel


def test_every_filters_flight_is_run_data_with_its_own_estimate(short_runs):
    """Each filter's flight is in the Parquet run data as its variant: the truth, that filter's
    estimate and covariance, DR and the commands per tick. Truth: the three flights start from
    the same state (same seed and run); the estimate moves only at the filter's 1 s steps (the
    standard EKF's would move every tick); its error at the filter steps equals the metrics'
    RMSE (computed from the flight in the worker, not from the files); each filter's estimates
    are its own."""
    t = open_dataset(short_runs[0], "ticks").to_pandas()
    m = _metrics(short_runs[0])
    assert sorted(t["variant"].unique()) == ["cmnf", "ekf", "upmf"]
    est, starts = {}, []
    for f, g in t.groupby("variant", observed=True):
        assert len(g) == 101 and g["t"].iloc[-1] == pytest.approx(20.0)  # 20 s at 0.2 s
        for c in ("truth_pos_east", "ekf_pos_east", "ekf_P_east_east", "dr_pos_east"):
            assert g[c].notna().all(), (f, c)
        assert (g["ekf_P_east_east"] > 0).all()
        assert g["cmd_tail_beat_frequency"].max() > 0
        # the filter's estimate moves at its steps only (the standard EKF beside it moves
        # every tick with the dead reckoning)
        x = g[["ekf_pos_east", "ekf_pos_north", "ekf_pos_up", "ekf_P_east_east"]].to_numpy()
        moved = np.any(np.diff(x, axis=0) != 0, axis=1)
        assert moved.any() and (g["filter_step"].to_numpy()[1:][moved] >= 1).all(), f
        steps = g[g["filter_step"] >= 1]
        e = np.linalg.norm(
            [steps[f"ekf_pos_{c}"] - steps[f"truth_pos_{c}"] for c in ("east", "north", "up")],
            axis=0,
        )
        assert np.sqrt(np.mean(e**2)) == pytest.approx(m["filters"][f]["est_rmse_m"], rel=1e-12)
        est[f] = steps[["ekf_pos_east", "ekf_pos_north"]].to_numpy()
        starts.append(g.iloc[0][["truth_pos_east", "truth_pos_north", "truth_pos_up"]])
    for s in starts[1:]:
        np.testing.assert_array_equal(s.to_numpy(float), starts[0].to_numpy(float))
    assert not np.array_equal(est["ekf"], est["cmnf"])


def test_bearings_are_the_geometry_to_the_beacons_within_their_noise(short_runs):
    """The ``doa`` table: per filter flight, one row per bearing of each set (4 beacons, one set
    a second), accepted when the filter took it. Truth: the azimuth (clockwise from north) and
    elevation of each beacon seen from the true position at the bearing's time, by hand; the
    seed's 0.5 deg tangent noise leaves them within 3 deg."""
    d = open_dataset(short_runs[0], "doa").to_pandas()
    t = open_dataset(short_runs[0], "ticks").to_pandas()
    scn = plan_batch(NAME, overrides=FAST).scenario
    b = beacons_world(scn)
    for f, g in d.groupby("variant", observed=True):
        assert len(g) == 4 * 20 and g["accepted"].all() and g["tangent_ok"].all(), f
        tt = t[t["variant"] == f].set_index("t")
        pos = tt.loc[g["t_valid"], ["truth_pos_east", "truth_pos_north", "truth_pos_up"]]
        bb = b[g["beacon"].to_numpy()]
        np.testing.assert_allclose(
            g[["beacon_east", "beacon_north", "beacon_up"]].to_numpy(), bb, atol=5e-3
        )
        de, dn, du = (bb - pos.to_numpy()).T
        az = np.degrees(np.arctan2(de, dn)) % 360
        el = np.degrees(np.arctan2(du, np.hypot(de, dn)))
        err_az = (g["azimuth_deg"].to_numpy() - az + 180) % 360 - 180
        assert np.abs(err_az).max() < 3.0, (f, np.abs(err_az).max())
        assert np.abs(g["elevation_deg"].to_numpy() - el).max() < 3.0
        phi = np.radians(90.0 - g["azimuth_deg"].to_numpy())
        np.testing.assert_allclose(g["tan_phi"], np.tan(phi), rtol=1e-9, atol=1e-12)


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
def test_the_registered_flight_is_the_seed004_design():
    scn = plan_batch(NAME, overrides=[*FAST, "navigation.filter=upmf"]).scenario
    design, _ = registry.get(NAME).flight(scn, 0, 0)
    assert isinstance(design, Seed004Mission) and design.filter == "upmf"


@pytest.mark.slow
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
    assert_refused(tmp_path, NAME, "--runs", "1", *args, pattern=pattern)


@pytest.mark.slow
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


# ---------------------------------------------------------------------------------------------
# The seabed-sensing prediction (navigation.prediction = "seabed")

SEABED = [*FAST, "navigation.prediction=seabed"]


def _flat_image(cfg, origin, pitch, heading, depth_m):
    """The multibeam image of a flat seabed at ``depth_m`` from ``origin``: each beam's range to
    the plane z = -depth written out here (beam elevation g below the axis pitched by ``pitch``,
    azimuth from the heading's seed-004 angle)."""
    from bauv_sim.sensors.multibeam import MultibeamImage

    g = pitch + cfg.elevations_rad()[:, None] + 0 * cfg.azimuths_rad()[None, :]
    L = (origin[2] + depth_m) / -np.sin(g)
    echo = np.ones(L.shape, bool)
    att = np.array([pitch, math.pi / 2 - heading])
    return MultibeamImage(L, echo, att, cfg.elevations_rad(), cfg.azimuths_rad())


def test_sonar_shift_on_a_flat_seabed_is_the_vertical_move_less_the_lever_arms_turn():
    """A flat seabed observes only the vertical move of the transducer (the shift has no
    horizontal component of its own); the reference point's shift is the transducer's less the
    turn of the lever arm between the pings (heading 30 -> 42 deg), worked out here with the
    hull's forward axis (sin h, cos h, 0) at zero roll and pitch."""
    from bauv_sim.sensors.multibeam import MultibeamConfig
    from bauv_sim.sensors.online import Measurement
    from bauv_sim.sensors.rig import RigTick
    from tasks.missions.seed004 import SonarShift

    cfg = MultibeamConfig(range={"sigma_m": 0.0})
    lever = np.array([0.45, 0.0, -0.159])
    fallback = np.diag([0.09, 0.09, 0.01])
    sonar = SonarShift(cfg, lever, "plane", 1.0, fallback)
    u = np.array([[0.0, 0.3, 1.0]])
    h0, h1 = math.radians(30.0), math.radians(42.0)

    def tick(t, head, z):
        fwd = np.array([math.sin(head), math.cos(head), 0.0])
        transducer = np.array([0.0, 0.0, z]) + 0.45 * fwd + np.array([0.0, 0.0, -0.159])
        img = _flat_image(cfg, transducer, 0.0, head, 6.0)
        m = Measurement("multibeam", t, t, img.ranges_m.ravel(), np.array([0.0, 0.0, head]), img)
        return RigTick(t, {}, frozenset(), (m,)), transducer

    tk, p0 = tick(0.0, h0, -2.0)
    sonar.take(tk)
    first = sonar(np.zeros((1, 3)), u)  # one image only: the commanded move, S^W
    assert np.allclose(first.displacement_m, [[math.cos(0.3), math.sin(0.3), 0.0]])
    assert np.array_equal(first.covariance_m2, fallback) and not sonar.last_ok
    tk, p1 = tick(1.0, h1, -2.35)
    sonar.take(tk)
    got = sonar(np.zeros((1, 3)), u)
    assert sonar.last_ok and sonar.last_beams == 64
    arm_turn = (p1 - np.array([0.0, 0.0, -2.35])) - (p0 - np.array([0.0, 0.0, -2.0]))
    want = np.array([0.0, 0.0, -0.35]) - arm_turn  # transducer's vertical move, less the turn
    assert np.allclose(got.displacement_m[0], want, atol=1e-9), (got.displacement_m, want)
    # the horizontal directions are unobserved on a plane: stated with the fallback variance
    assert np.all(np.diag(got.covariance_m2[0])[:2] >= 1e5) and got.covariance_m2[0, 2, 2] < 1e-6


@pytest.mark.slow
def test_surrogate_images_the_scene_heightfield_and_shifts_exactly_on_a_flat_one():
    """The kinematic surrogate's prediction images the scene's heightfield (here flat, 6 m deep,
    no range noise), image k+1 aimed from u_k: from the second step on, its shift's vertical
    component is what eq. 11 gives on a plane with the beams turning between the images (a
    plane observes nothing else), worked out here: each beam states the true vertical move plus
    de_z dL (the product eq. 11 drops), and the least squares averages the beams; the first
    step is the command."""
    from bauv_sim.seabed import SeabedConfig
    from bauv_sim.sensors.multibeam import MultibeamConfig
    from tasks.paper004.seabed import HeightfieldPrediction
    from tasks.paper004.sim import prediction_of

    scn = plan_batch(NAME, overrides=SEABED).scenario
    flat = SeabedConfig(half_extent_m=250.0, cell_m=5.0, relief_std_m=0.0, slope=0.0)
    s = dataclasses.replace(
        surrogate(scn),
        heightfield=flat,
        multibeam=MultibeamConfig(range={"sigma_m": 0.0}),
        slope_basis="plane",
    )

    class Still:
        def start(self):
            return np.array([[0.0, 0.0, -2.0], [5.0, 1.0, -3.0]])

        def advance(self, k, x, u):
            return x + np.array([[0.9, 0.1, -0.2], [1.0, -0.3, 0.25]])

        def observe(self, k, x):
            return None

    pred, world = prediction_of(s, 0, (0, 1), Still(), "test")
    assert isinstance(pred, HeightfieldPrediction)
    elev = MultibeamConfig().elevations_rad()
    x = world.start()
    u_prev = None
    for k in range(4):
        u = np.array([[0.05, 0.2, 1.0], [-0.1, -0.3, 1.1]]) + k * np.array([0.04, -0.15, 0.0])
        x1 = world.advance(k, x, u)
        sh = pred(k, x, u)
        if k == 0:
            assert pred.last is None
            np.testing.assert_allclose(sh.displacement_m, velocity(u))
        else:
            assert pred.last.ok.all()
            ez0 = np.sin(u_prev[:, :1] + elev)  # (paths, Mi): e_z is the same for every azimuth
            ez1 = np.sin(u[:, :1] + elev)
            dl = (x1[:, 2:] + 6.0) / -ez1 - (x[:, 2:] + 6.0) / -ez0
            want = (x1 - x)[:, 2] + ((ez1 - ez0) * dl).mean(axis=1)
            np.testing.assert_allclose(sh.displacement_m[:, 2], want, atol=1e-9)
            assert np.abs(want - (x1 - x)[:, 2]).max() > 1e-3  # the turn matters here
        x, u_prev = x1, u


@pytest.mark.slow
def test_seabed_prediction_flies_every_filter_without_nan_and_reports_the_shift(tmp_path):
    """With the seabed-sensing prediction the CMNF follows the path and the EKF and UPMF may
    fail to (seed 004's dashes in Table 1's row 2; on the physics a few of 20 s flights of EKF or
    UPMF leave the path on any seed: 3 to 5 of 32 over seeds 1-16): a filter that does is a named
    divergence with the time, never a NaN, and the shift is still reported for its steps."""
    outs = []
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        run(NAME, n_runs=2, seed=0, out_dir=out, overrides=SEABED, workers=workers, progress=False)
        outs.append(out)
    a, b = ((o / "metrics.json").read_text() for o in outs)
    assert a == b  # same numbers whatever the worker count
    m = _metrics(outs[0])
    assert m["prediction"] == "seabed"
    assert m["filters"]["cmnf"]["runs_ok"] == 2 and m["filters"]["cmnf"]["diverged_runs"] == 0
    named = re.compile(
        r"^(ekf|upmf): run \d \(seed 0\) failed at t = [\d.]+ s: NavError: "
        r"(EKF|UPMF) diverged at step \d+"
    )
    assert all(named.match(f) for f in m["failures"]), m["failures"]
    for f, s in m["filters"].items():
        assert s["runs_ok"] + s["diverged_runs"] == 2, f
        assert len([x for x in m["failures"] if x.startswith(f"{f}:")]) == s["diverged_runs"]
        # 20 steps: a shift at steps 2..20 (the sonar has no image at t = 0) of a run that
        # completes; a diverged run's until it stopped
        steps = s["shift_steps"] + s["shift_none_steps"]
        assert steps == 2 * 19 if s["diverged_runs"] == 0 else 0 < steps < 2 * 19, (f, steps)
        assert s["shift_beams_mean"] > 40, f
        for k, v in s.items():
            vals = v if isinstance(v, list) else [v]
            assert all(x is not None and math.isfinite(x) for x in vals), (f, k, v)
    sur = m["surrogate_shift"]
    assert set(sur) == {"shift_err_median_m", "shift_err_p90_m", "shift_err_bias_m"}
    assert math.isfinite(m["cmnf_gap_m2"])
    text = (outs[0] / "tables.md").read_text()
    assert "Seabed-sensing prediction" in text and "nan" not in text.lower()


@pytest.mark.slow
def test_a_filter_that_leaves_the_nominal_path_is_a_named_divergence_not_nan(tmp_path):
    out = tmp_path / "div"
    over = [*SEABED, "seed004.diverge_m=0.5", "navigation.filter=ekf"]
    run(NAME, n_runs=1, seed=3, out_dir=out, overrides=over, progress=False)
    m = _metrics(out)
    s = m["filters"]["ekf"]
    assert s["runs_ok"] == 0 and s["diverged_runs"] == 1
    assert len(m["failures"]) == 1 and "EKF diverged at step" in m["failures"][0]
    assert "seed004.diverge_m = 0.5" in m["failures"][0]
    assert "nan" not in (out / "metrics.json").read_text().lower()


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, pattern",
    [
        (["--set", "multibeam.max_range_m=3"], "multibeam.max_range_m = 3"),
        (["--set", "multibeam.period_s=0.5"], "multibeam.period_s = 0.5"),
        (["--set", "navigation.prediction=dvl"], "navigation.prediction"),
    ],
)
def test_bad_seabed_setting_is_one_line_exit_2(tmp_path, args, pattern):
    pred = ["--set", "navigation.prediction=seabed"]
    assert_refused(tmp_path, NAME, "--runs", "1", *pred, *args, pattern=pattern)


@pytest.mark.slow
def test_beams_without_echo_degrade_to_the_command_with_a_warning_and_no_nan(tmp_path):
    out = tmp_path / "noecho"
    over = [*SEABED, "multibeam.range.dropout_probability=0.9", "navigation.filter=cmnf"]
    run(NAME, n_runs=1, seed=3, out_dir=out, overrides=over, progress=False)
    m = _metrics(out)
    s = m["filters"]["cmnf"]
    # P(echo in both images) = 0.01 per beam: a shift needs at least 7 such beams of 64
    assert s["runs_ok"] == 1 and s["shift_none_steps"] >= 15, s
    assert any("without a seabed shift" in w for w in m["warnings"]), m["warnings"]
    assert "nan" not in (out / "metrics.json").read_text().lower()
    assert math.isfinite(s["est_rmse_m"]) and math.isfinite(s["path_max_m"])
