"""The DVL in the kinematic world (batched): bottom-lock velocity against the true velocity over
ground at the transducer, on a plane and on relief; lock, water track and no output; ranges
against the closed-form plane and the analytic heightfield intersection; the error terms; bad
input. The truth here is written out in the test (scipy rotations), not taken from the device."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

from bauv_sim import seabed as sb
from bauv_sim.config import validate
from bauv_sim.errors import BauvSimError, ConfigError
from bauv_sim.sensors import (
    Dvl,
    DvlConfig,
    LengthErrorConfig,
    PlaneSeabed,
    SpeedErrorConfig,
)
from bauv_sim.truth import Truth

pytestmark = pytest.mark.filterwarnings("error")  # a 0/0 on the way to an output fails
EXACT = {"beam": SpeedErrorConfig(), "range": LengthErrorConfig()}  # every error off
RELIEF = sb.SeabedConfig(
    half_extent_m=200.0,
    cell_m=4.0,
    depth_at_origin_m=40.0,
    slope=0.01,
    relief_std_m=3.0,
    n_modes=16,
    min_wavelength_m=20.0,
    max_wavelength_m=120.0,
    min_depth_m=10.0,
    seed=5,
)


def _R_world_from_body(roll, pitch, heading):
    """ENU <- FLU: yaw = 90 deg - heading about z, nose up = negative about y, starboard down =
    positive about x (scipy, intrinsic z-y-x)."""
    ang = np.stack([np.pi / 2 - heading, -pitch, roll], axis=-1)
    return Rotation.from_euler("ZYX", ang.reshape(-1, 3)).as_matrix().reshape(*roll.shape, 3, 3)


def _R_mount(rpy_deg):
    """Right-handed rotations about x, then y, then z (fixed axes): Rz Ry Rx."""
    return Rotation.from_euler("xyz", rpy_deg, degrees=True).as_matrix()


def _janus(a_deg):
    a, phi = np.radians(a_deg), np.radians([0, 90, 180, 270])
    return np.stack([np.sin(a) * np.cos(phi), np.sin(a) * np.sin(phi), -np.cos(a) * np.ones(4)], 1)


def _motion(rng, n, k, depth_m=10.0, spread_m=0.0, tilt_deg=25.0, current=(0.3, -0.2, 0.0)):
    """Random states: position, attitude, velocities (each sample independent) and rates."""
    t = np.arange(k) * 0.2
    pos = np.zeros((n, k, 3))
    pos[..., :2] = rng.uniform(-spread_m, spread_m, (n, k, 2))
    pos[..., 2] = -depth_m + rng.uniform(-1, 1, (n, k))
    vg = rng.normal(0, 1.0, (n, k, 3)) * [1, 1, 0.2]
    cur = np.broadcast_to(np.asarray(current, float), (n, k, 3))
    tilt = np.radians(tilt_deg)
    rp = rng.uniform(-tilt, tilt, (n, k, 2))
    hd = rng.uniform(0, 2 * np.pi, (n, k))
    w = rng.normal(0, 0.3, (n, k, 3))
    truth = Truth(t, pos, vg, vg - cur, hd, rp, cur.copy())
    return truth, w


def _expected(truth, w, r, water=False):
    """v_transducer in body axes: R^T (v + R (omega x r)), and R."""
    R = _R_world_from_body(
        truth.roll_pitch_rad[..., 0], truth.roll_pitch_rad[..., 1], truth.heading_rad
    )
    v = truth.vel_water_world_m_s if water else truth.vel_ground_world_m_s
    v_t_world = v + np.einsum("...ij,...j->...i", R, np.cross(w, r))
    return np.einsum("...ji,...j->...i", R, v_t_world), R


LEVER = (0.4, 0.05, -0.16)


@pytest.mark.parametrize("mount", [(0.0, 0.0, 45.0), (3.0, -5.0, 20.0)])
def test_bottom_lock_is_the_true_velocity_over_ground_on_a_sloping_plane(mount):
    rng = np.random.default_rng(1)
    truth, w = _motion(rng, 3, 60, spread_m=30.0)
    cfg = DvlConfig(transducer_body_m=LEVER, mount_rpy_deg=mount, **EXACT)
    plane = PlaneSeabed(30.0, (0.05, -0.03))
    s = Dvl(cfg, 7, (0, 1, 2)).sample(truth, np.arange(60), plane, w)
    want, R = _expected(truth, w, np.array(LEVER))
    assert np.all(s.mode == 1) and s.beam_echo.all()
    np.testing.assert_allclose(s.velocity_body_m_s, want, rtol=0, atol=1e-9)
    np.testing.assert_allclose(s.true_velocity_body_m_s, want, rtol=0, atol=1e-12)
    # ranges: the closed-form intersection of each beam with the plane z = -(30 + sx x + sy y)
    origin = truth.pos_world_m + np.einsum("...ij,j->...i", R, LEVER)
    d_body = _janus(30.0) @ _R_mount(mount).T
    np.testing.assert_allclose(s.beam_directions_body, d_body, atol=1e-15)
    e = np.einsum("...ij,bj->...bi", R, d_body)
    nrm = np.array([0.05, -0.03, 1.0])  # grad of z + 30 + sx x + sy y
    L = -(origin @ nrm + 30.0)[..., None] / (e @ nrm)
    np.testing.assert_allclose(s.beam_ranges_m, L, rtol=0, atol=1e-9)
    # altitude: mean of range cos(a)
    np.testing.assert_allclose(s.altitude_m, L.mean(-1) * np.cos(np.radians(30)), atol=1e-9)


def test_bottom_lock_is_the_true_velocity_over_ground_on_relief():
    bed = sb.generate(RELIEF)
    rng = np.random.default_rng(2)
    truth, w = _motion(rng, 2, 80, depth_m=20.0, spread_m=150.0)
    cfg = DvlConfig(transducer_body_m=LEVER, **EXACT)
    s = Dvl(cfg, 7, (0, 1)).sample(truth, np.arange(80), bed, w)
    want, R = _expected(truth, w, np.array(LEVER))
    assert np.all(s.mode == 1)
    np.testing.assert_allclose(s.velocity_body_m_s, want, rtol=0, atol=1e-9)
    # ranges: the analytic heightfield intersection from the transducer along the true beams
    origin = truth.pos_world_m + np.einsum("...ij,j->...i", R, LEVER)
    e = np.einsum("...ij,bj->...bi", R, _janus(30.0) @ _R_mount((0, 0, 45)).T)
    L, hit = bed.ray_ranges(origin[..., None, :], e, 60.0 / np.cos(np.radians(30)))
    assert hit.all()
    np.testing.assert_allclose(s.beam_ranges_m, L, rtol=0, atol=1e-9)
    # the relief shows: the four ranges differ by more than on a level plane would
    assert np.ptp(s.beam_ranges_m, axis=-1).max() > 5.0


def _level_descent(z, current=(0.3, -0.2, 0.0)):
    """A level vehicle at the given heights z (k,), moving at (0.8, 0.4, 0.1) over ground."""
    k = len(z)
    pos = np.zeros((1, k, 3))
    pos[0, :, 2] = z
    vg = np.broadcast_to([0.8, 0.4, 0.1], (1, k, 3)).copy()
    cur = np.broadcast_to(np.asarray(current, float), (1, k, 3)).copy()
    return Truth(
        np.arange(k) * 0.2, pos, vg, vg - cur, np.full((1, k), 0.7), np.zeros((1, k, 2)), cur
    )


def test_lock_is_lost_above_the_maximum_altitude_and_regained_below_it():
    # the seabed at 30 m; the vehicle rises from 28 m to 2 m and comes back down
    z = np.r_[np.linspace(-28, -2, 27), np.linspace(-2, -28, 27)]
    truth = _level_descent(z)
    w = np.broadcast_to([0.02, -0.05, 0.1], (1, len(z), 3))
    plane = PlaneSeabed(30.0)
    cfg = DvlConfig(max_altitude_m=15.0, transducer_body_m=LEVER, **EXACT)
    s = Dvl(cfg, 3, (0,)).sample(truth, np.arange(len(z)), plane, w)
    altitude = 30.0 + z + np.cos(np.radians(0)) * LEVER[2]  # level: along the vertical
    below = altitude <= 15.0 - 1e-6
    above = altitude > 15.0 + 1e-6
    assert below.any() and above.any()
    assert np.all(s.mode[0, below] == 1) and np.all(s.mode[0, above] == 2)
    np.testing.assert_allclose(s.altitude_m[0, below], altitude[below], atol=1e-9)
    assert np.all(s.altitude_m[0, above] == 0) and not s.beam_echo[0, above].any()
    assert np.all(s.beam_ranges_m[0, above] == 0)
    ground, _ = _expected(truth, w, np.array(LEVER))
    water, _ = _expected(truth, w, np.array(LEVER), water=True)
    np.testing.assert_allclose(s.velocity_body_m_s[0, below], ground[0, below], atol=1e-9)
    np.testing.assert_allclose(s.velocity_body_m_s[0, above], water[0, above], atol=1e-9)
    assert np.abs(ground - water).max() > 0.2  # the current shows
    # fallback "none": nothing above, zeros, never NaN
    cfg0 = cfg.model_copy(update={"fallback": "none"})
    s0 = Dvl(cfg0, 3, (0,)).sample(truth, np.arange(len(z)), plane, w)
    assert np.all(s0.mode[0, above] == 0) and np.all(s0.velocity_body_m_s[0, above] == 0)
    np.testing.assert_array_equal(s0.mode[0, below], 1)
    # below the minimum altitude: no bottom lock either
    cfg_min = cfg.model_copy(update={"min_altitude_m": 5.0})
    s1 = Dvl(cfg_min, 3, (0,)).sample(truth, np.arange(len(z)), plane, w)
    low = altitude < 5.0 - 1e-6
    assert low.any() and np.all(s1.mode[0, low] == 2)
    assert np.all(s1.mode[0, below & ~low] == 1)


def _rolled(roll_deg, z=-10.0):
    k = 4
    pos = np.broadcast_to([0.0, 0.0, z], (1, k, 3)).copy()
    vg = np.broadcast_to([0.5, -0.3, 0.05], (1, k, 3)).copy()
    return Truth(
        np.arange(k) * 0.2,
        pos,
        vg,
        vg.copy(),
        np.zeros((1, k)),
        np.broadcast_to([np.radians(roll_deg), 0.0], (1, k, 2)).copy(),
        np.zeros((1, k, 3)),
    )


def test_two_beams_are_no_lock_and_three_are_an_exact_velocity():
    plane = PlaneSeabed(30.0)  # altitude 20 m
    # X layout, roll 30 deg: the two port beams point 55 deg off the vertical (34.9 m) and lose
    # the seabed beyond 22 / cos(30 deg) = 25.4 m; the starboard ones see it at 21.6 m
    truth = _rolled(30.0)
    cfg = DvlConfig(max_altitude_m=22.0, **EXACT)
    s = Dvl(cfg, 1, (0,)).sample(truth, np.arange(4), plane)
    assert np.all(s.beam_echo.sum(-1) == 2) and np.all(s.mode == 2) and np.all(s.altitude_m == 0)
    assert np.all(s.beam_ranges_m[s.beam_echo] > 0) and np.all(s.beam_ranges_m[~s.beam_echo] == 0)
    # "+" layout, roll 30 deg, limit 27.7 m: the port beam (40 m) is lost, the fore and aft beams
    # (26.7 m) and the starboard one (20 m) return: bottom lock from three beams, exact
    cfg3 = DvlConfig(max_altitude_m=24.0, mount_rpy_deg=(0, 0, 0), **EXACT)
    s3 = Dvl(cfg3, 1, (0,)).sample(truth, np.arange(4), plane)
    np.testing.assert_array_equal(s3.beam_echo[0, 0], [True, False, True, True])
    assert np.all(s3.mode == 1)
    want, _ = _expected(truth, np.zeros((1, 4, 3)), np.zeros(3))
    np.testing.assert_allclose(s3.velocity_body_m_s, want, atol=1e-9)
    # four beams required: three are not enough
    s4 = Dvl(cfg3.model_copy(update={"min_beams": 4}), 1, (0,)).sample(truth, np.arange(4), plane)
    assert np.all(s4.mode == 2)


def _still(n, k):
    """A level vehicle at rest 20 m above a flat seabed."""
    pos = np.broadcast_to([0.0, 0.0, -10.0], (n, k, 3)).copy()
    v = np.zeros((n, k, 3))
    return Truth(
        np.arange(k) * 0.2, pos, v, v.copy(), np.zeros((n, k)), np.zeros((n, k, 2)), v.copy()
    )


def test_beam_noise_is_recovered_from_many_samples():
    sigma, n, k = 0.05, 20, 400
    cfg = DvlConfig(beam=SpeedErrorConfig(sigma_m_s=sigma), range=LengthErrorConfig(sigma_m=0.1))
    s = Dvl(cfg, 11, tuple(range(n))).sample(_still(n, k), np.arange(k), PlaneSeabed(30.0))
    assert np.all(s.mode == 1)
    a = np.radians(30.0)
    # least squares over 4 Janus beams: cov(v_instr) = sigma^2 diag(1/(2 sin^2 a), same,
    # 1/(4 cos^2 a)); the X mount turns x, y about z and keeps those variances
    var = sigma**2 * np.array(
        [1 / (2 * np.sin(a) ** 2), 1 / (2 * np.sin(a) ** 2), 1 / (4 * np.cos(a) ** 2)]
    )
    m = n * k
    for c in range(3):
        stat = np.sum(s.velocity_body_m_s[..., c] ** 2) / var[c]  # chi-square, m dof
        assert chi2.ppf(0.0005, m) < stat < chi2.ppf(0.9995, m), (c, stat / m)
    # the x and y errors of one ping are uncorrelated (2 sin^2 a D^T D is diagonal)
    r = np.corrcoef(s.velocity_body_m_s[..., 0].ravel(), s.velocity_body_m_s[..., 1].ravel())
    assert abs(r[0, 1]) < 4 / np.sqrt(m)
    # ranges: N(L, 0.1^2) about the true 20 / cos(a)
    err = s.beam_ranges_m - 20.0 / np.cos(a)
    stat = np.sum(err**2) / 0.1**2
    assert chi2.ppf(0.0005, err.size) < stat < chi2.ppf(0.9995, err.size)


def test_scale_factor_bias_and_misalignment_show_as_worked_out():
    rng = np.random.default_rng(4)
    truth, w = _motion(rng, 2, 30)
    plane = PlaneSeabed(40.0)
    true, _ = _expected(truth, w, np.zeros(3))
    # scale factor: every beam reads (1 + s) times its velocity -> the velocity too
    cfg = DvlConfig(beam=SpeedErrorConfig(scale_factor=0.02), range=LengthErrorConfig())
    s = Dvl(cfg, 1, (0, 1)).sample(truth, np.arange(30), plane, w)
    np.testing.assert_allclose(s.velocity_body_m_s, 1.02 * true, atol=1e-9)
    # bias b on every beam: D^T 1 = (0, 0, -4 cos a), D^T D = diag(2 sin^2, 2 sin^2, 4 cos^2)
    # -> v_instr += (0, 0, -b / cos a), which the yaw-only mount keeps on body z
    b = 0.01
    cfg = DvlConfig(beam=SpeedErrorConfig(bias_m_s=b), range=LengthErrorConfig())
    s = Dvl(cfg, 1, (0, 1)).sample(truth, np.arange(30), plane, w)
    np.testing.assert_allclose(
        s.velocity_body_m_s, true + [0, 0, -b / np.cos(np.radians(30))], atol=1e-9
    )
    # misalignment: the beams are R_nom R_mis d_i, the DVL solves with R_nom d_i, so it reports
    # R_nom R_mis^T R_nom^T v
    mis = (1.0, -2.0, 3.0)
    R_nom = _R_mount((5.0, 0.0, 45.0))
    R_mis = _R_mount(mis)
    cfg = DvlConfig(mount_rpy_deg=(5.0, 0.0, 45.0), misalignment_deg=mis, **EXACT)
    s = Dvl(cfg, 1, (0, 1)).sample(truth, np.arange(30), plane, w)
    rot = R_nom @ R_mis.T @ R_nom.T
    np.testing.assert_allclose(s.velocity_body_m_s, true @ rot.T, atol=1e-9)
    assert np.abs(s.velocity_body_m_s - true).max() > 0.02  # and it does show
    # range bias and scale factor
    cfg = DvlConfig(beam=SpeedErrorConfig(), range=LengthErrorConfig(bias_m=0.3, scale_factor=0.01))
    s2 = Dvl(cfg, 1, (0, 1)).sample(truth, np.arange(30), plane, w)
    s1 = Dvl(DvlConfig(**EXACT), 1, (0, 1)).sample(truth, np.arange(30), plane, w)
    np.testing.assert_allclose(s2.beam_ranges_m, 1.01 * s1.beam_ranges_m + 0.3, atol=1e-9)


def test_dropouts_and_outliers_degrade_never_nan_and_runs_are_independent():
    n, k = 4, 300
    cfg = DvlConfig(
        beam=SpeedErrorConfig(
            sigma_m_s=0.01, dropout_probability=0.3, outlier_probability=0.05, outlier_sigma_m_s=1.0
        ),
        range=LengthErrorConfig(sigma_m=0.02, dropout_probability=0.1),
    )
    truth = _still(n, k)
    s = Dvl(cfg, 5, tuple(range(n))).sample(truth, np.arange(k), PlaneSeabed(30.0))
    for a in (s.velocity_body_m_s, s.altitude_m, s.beam_ranges_m):
        assert np.all(np.isfinite(a))
    alive = 0.7 * 0.9
    assert abs(s.beam_echo.mean() - alive) < 0.03
    # lock exactly where >= 3 beams echo; else water track from the beams alive (fewer: none)
    n_echo = s.beam_echo.sum(-1)
    np.testing.assert_array_equal(s.mode == 1, n_echo >= 3)
    assert (s.mode == 2).any() and (s.mode == 0).any()
    assert np.all(s.velocity_body_m_s[s.mode == 0] == 0) and np.all(s.altitude_m[s.mode != 1] == 0)
    # same seed, same numbers; run 2 alone draws what it draws in the batch
    s_again = Dvl(cfg, 5, tuple(range(n))).sample(truth, np.arange(k), PlaneSeabed(30.0))
    np.testing.assert_array_equal(s_again.velocity_body_m_s, s.velocity_body_m_s)
    one = Dvl(cfg, 5, (2,)).sample(_one_run(truth, 2), np.arange(k), PlaneSeabed(30.0))
    np.testing.assert_array_equal(one.velocity_body_m_s[0], s.velocity_body_m_s[2])
    np.testing.assert_array_equal(one.mode[0], s.mode[2])
    # the online form (one ping per call) draws the same numbers as the batch
    d = Dvl(cfg, 5, (2,))
    for j in range(20):
        p = d.sample(_one_run(truth, 2), np.array([j]), PlaneSeabed(30.0))
        np.testing.assert_array_equal(p.velocity_body_m_s[0, 0], s.velocity_body_m_s[2, j])
        np.testing.assert_array_equal(p.beam_ranges_m[0, 0], s.beam_ranges_m[2, j])


def _one_run(truth, i):
    return Truth(
        truth.t_s,
        *(
            getattr(truth, f)[i : i + 1]
            for f in (
                "pos_world_m",
                "vel_ground_world_m_s",
                "vel_water_world_m_s",
                "heading_rad",
                "roll_pitch_rad",
                "current_world_m_s",
            )
        ),
    )


def test_no_echo_geometry_degrades_to_water_track_or_nothing():
    # under the seabed, off the grid, or pointing up: no echo, never NaN
    bed = sb.generate(RELIEF)
    k = 3
    pos = np.array([[[0.0, 0.0, -80.0]] * k, [[199.0, 0.0, -5.0]] * k])  # below; at the edge
    v = np.broadcast_to([0.3, 0.1, 0.0], (2, k, 3)).copy()
    hd = np.full((2, k), np.pi / 2)  # heading east: beams leave the grid
    truth = Truth(
        np.arange(k) * 0.2,
        pos,
        v,
        v - [0.1, 0, 0],
        hd,
        np.zeros((2, k, 2)),
        np.broadcast_to([0.1, 0, 0], (2, k, 3)).copy(),
    )
    s = Dvl(DvlConfig(**EXACT), 1, (0, 1)).sample(truth, np.arange(k), bed)
    assert not s.beam_echo[0].any() and np.all(s.mode[0] == 2)
    assert s.beam_echo[1].sum(-1).max() <= 2 and np.all(s.mode[1] == 2)
    np.testing.assert_allclose(s.velocity_body_m_s[..., 0], [[0.2] * k, [0.2] * k], atol=1e-9)
    upside_down = _rolled(180.0)
    s = Dvl(DvlConfig(fallback="none", **EXACT), 1, (0,)).sample(
        upside_down, np.arange(4), PlaneSeabed(30.0)
    )
    assert np.all(s.mode == 0) and not s.beam_echo.any()
    for a in (s.velocity_body_m_s, s.altitude_m, s.beam_ranges_m):
        assert np.all(a == 0)


@pytest.mark.parametrize(
    ("data", "field", "value"),
    [
        ({"beam_angle_deg": 95.0}, "beam_angle_deg", "95"),
        ({"beam_angle_deg": 0.0}, "beam_angle_deg", "0"),
        ({"min_beams": 2}, "min_beams", "2"),
        ({"fallback": "bottom"}, "fallback", "bottom"),
        ({"period_s": -0.2}, "period_s", "-0.2"),
        ({"min_altitude_m": 70.0}, "min_altitude_m", "70"),
        ({"beam": {"sector_bias_m_s": [0.1, 0, 0, 0]}}, "sector_bias_m_s", ""),
        ({"mount_rpy_deg": [0.0, 0.0]}, "mount_rpy_deg", ""),
    ],
)
def test_bad_configuration_is_one_line_naming_the_field(data, field, value):
    with pytest.raises(ConfigError) as exc:
        validate(DvlConfig, data, "dvl")
    msg = str(exc.value)
    assert "\n" not in msg and field in msg and value in msg, msg


def test_bad_input_is_a_clear_error():
    truth = _still(1, 3)
    dvl = Dvl(DvlConfig(**EXACT), 1, (0,))
    with pytest.raises(ConfigError, match="angular_velocity_body_rad_s"):
        dvl.sample(truth, np.arange(3), PlaneSeabed(30.0), np.zeros((1, 2, 3)))
    bad = Truth(
        truth.t_s,
        truth.pos_world_m * np.nan,
        truth.vel_ground_world_m_s,
        truth.vel_water_world_m_s,
        truth.heading_rad,
        truth.roll_pitch_rad,
        truth.current_world_m_s,
    )
    with pytest.raises(BauvSimError, match="non-finite"):
        dvl.sample(bad, np.arange(3), PlaneSeabed(30.0))
    with pytest.raises(ConfigError, match="PlaneSeabed"):
        PlaneSeabed(float("nan"))
    with pytest.raises(ConfigError, match="shape"):
        dvl.measure(
            np.zeros((1, 3, 3)),
            np.zeros((1, 3, 3), bool),
            np.zeros((1, 3, 3)),
            np.zeros((1, 3, 3)),
            np.arange(3.0),
        )


def test_the_measured_altitude_decides_the_lock_and_echoes_beyond_the_beam_range_do_not_count():
    # true altitude 14.9 m under a 15 m limit: every beam returns; a +0.5 m range bias reads
    # (L + 0.5) cos(a) = 15.33 m: no bottom lock
    truth = _level_descent(np.full(3, -15.1))
    plane = PlaneSeabed(30.0)
    s = Dvl(DvlConfig(max_altitude_m=15.0, **EXACT), 1, (0,)).sample(truth, np.arange(3), plane)
    assert np.all(s.mode == 1)
    biased = DvlConfig(
        max_altitude_m=15.0, beam=SpeedErrorConfig(), range=LengthErrorConfig(bias_m=0.5)
    )
    s = Dvl(biased, 1, (0,)).sample(truth, np.arange(3), plane)
    assert s.beam_echo.all() and np.all(s.mode == 2) and np.all(s.altitude_m == 0)

    # a seabed that answers beyond the range asked for: those echoes are not the DVL's
    class Far:
        def ray_ranges(self, origin_m, directions, max_range_m):
            shape = np.broadcast_shapes(np.shape(origin_m), np.shape(directions))[:-1]
            return np.full(shape, max_range_m + 1.0), np.ones(shape, bool)

    s = Dvl(DvlConfig(**EXACT), 1, (0,)).sample(truth, np.arange(3), Far())
    assert not s.beam_echo.any() and np.all(s.mode == 2)


def test_plane_rays_from_below_or_going_up_have_no_echo():
    plane = PlaneSeabed(30.0, (0.1, 0.0))
    o = np.array([[0.0, 0.0, -10.0], [0.0, 0.0, -40.0], [0.0, 0.0, -10.0], [100.0, 0.0, -35.0]])
    e = np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    L, hit = plane.ray_ranges(o, e, 100.0)
    np.testing.assert_array_equal(hit, [True, False, False, True])
    np.testing.assert_allclose(L, [20.0, 0.0, 0.0, 5.0], atol=1e-12)
    L, hit = plane.ray_ranges(o, e, 10.0)
    np.testing.assert_array_equal(hit, [False, False, False, True])
