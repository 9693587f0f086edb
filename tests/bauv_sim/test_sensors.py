"""The error vocabulary and the devices, against the statistics they are defined by."""

import math

import numpy as np
import pytest

from bauv_sim.errors import ConfigError
from bauv_sim.sensors import (
    AngleErrorConfig,
    Compass,
    CompassConfig,
    ErrorModel,
    ErrorProcess,
    LengthErrorConfig,
    Log,
    LogConfig,
    Pressure,
    PressureConfig,
    Usbl,
    UsblConfig,
    check_multiple,
    periodic_indices,
)
from bauv_sim.truth import Truth

N, K = 400, 500  # runs x samples: 200,000 draws per statistic


def _apply(model, x=None, ref=None, runs=N, k=K, path=("s",), seed=11):
    p = ErrorProcess(model, seed, tuple(range(runs)), path)
    x = np.zeros((runs, k)) if x is None else x
    return p.apply(x, np.arange(k, dtype=float), ref)


def test_uniform_draws_are_bounded_with_sqrt3_sigma_std():
    v, ok = _apply(ErrorModel("uniform", sigma=0.5))
    assert ok.all()
    assert np.abs(v).max() <= 1.5 and np.abs(v).max() > 1.49
    se = 0.5 * math.sqrt(3) / math.sqrt(v.size)
    assert abs(v.mean()) < 5 * se
    assert v.std() == pytest.approx(0.5 * math.sqrt(3), rel=0.01)
    assert ErrorModel("uniform", sigma=0.5).noise_std == pytest.approx(0.5 * math.sqrt(3))


def test_gaussian_bias_and_scale():
    x = np.full((N, K), 10.0)
    v, _ = _apply(ErrorModel("gaussian", sigma=0.2, bias=0.3, scale_factor=0.01), x)
    assert v.mean() == pytest.approx(10.0 * 1.01 + 0.3, abs=5 * 0.2 / math.sqrt(v.size))
    assert v.std() == pytest.approx(0.2, rel=0.01)


def test_sector_bias_and_compass_deviation():
    ref = np.tile(np.radians([10.0, 100.0, 190.0, 280.0]), (3, 1))
    v, _ = _apply(ErrorModel(sector_bias=(4.0, 8.0, 0.0, 2.0)), np.zeros((3, 4)), ref, runs=3, k=4)
    assert np.allclose(v, [4, 8, 0, 2])
    dev = (0.1, 0.2, 0.3, 0.4, 0.5)
    v, _ = _apply(ErrorModel(deviation=dev), np.zeros((3, 4)), ref, runs=3, k=4)
    psi = ref
    want = (
        0.1 + 0.2 * np.sin(psi) + 0.3 * np.cos(psi) + 0.4 * np.sin(2 * psi) + 0.5 * np.cos(2 * psi)
    )
    assert np.allclose(v, want)


def test_random_walk_variance_grows_linearly_and_continues_across_calls():
    m = ErrorModel(random_walk=0.1)
    p = ErrorProcess(m, 3, tuple(range(2000)), ("w",))
    t = np.arange(1.0, 101.0)
    v1, _ = p.apply(np.zeros((2000, 100)), t)
    v2, _ = p.apply(np.zeros((2000, 100)), t + 100.0)
    assert v1[:, -1].var() == pytest.approx(0.01 * 99, rel=0.1)  # first sample starts the walk
    assert v2[:, -1].var() == pytest.approx(0.01 * 199, rel=0.1)


def test_outliers_and_dropouts_rates_and_stream_independence():
    base = ErrorModel("gaussian", sigma=1.0)
    noisy, _ = _apply(base)
    with_outliers, ok = _apply(
        ErrorModel(
            "gaussian",
            sigma=1.0,
            outlier_probability=0.05,
            outlier_sigma=50.0,
            dropout_probability=0.1,
        )
    )
    hit = np.abs(with_outliers - noisy) > 0
    assert hit.mean() == pytest.approx(0.05, abs=0.003)
    assert (~ok).mean() == pytest.approx(0.1, abs=0.003)
    # switching outliers and dropouts on leaves the noise of the other samples untouched
    assert np.array_equal(noisy[~hit], with_outliers[~hit])


def test_a_runs_numbers_do_not_depend_on_its_batch():
    m = ErrorModel("uniform", sigma=1.0, outlier_probability=0.1, outlier_sigma=5)
    whole, _ = ErrorProcess(m, 9, tuple(range(10)), ("x",)).apply(
        np.zeros((10, 50)), np.arange(50.0)
    )
    part, _ = ErrorProcess(m, 9, (7, 3), ("x",)).apply(np.zeros((2, 50)), np.arange(50.0))
    assert np.array_equal(part, whole[[7, 3]])


def test_config_units_convert_to_si():
    m = AngleErrorConfig(sigma_deg=3.0, bias_deg=1.0, random_walk_deg_per_sqrt_s=0.5).to_model()
    assert m.sigma == pytest.approx(math.radians(3)) and m.bias == pytest.approx(math.radians(1))
    assert m.random_walk == pytest.approx(math.radians(0.5))
    assert LengthErrorConfig(sigma_m=0.2).to_model().sigma == 0.2


def _truth(pos, vel_ground, current, heading):
    n, T = pos.shape[:2]
    return Truth(
        np.arange(T, dtype=float),
        pos,
        vel_ground,
        vel_ground - current,
        heading,
        np.zeros((n, T, 2)),
        current,
    )


def test_log_reads_speed_through_water_and_is_blind_when_slow():
    T = 5
    vel = np.tile([0.0, 1.0, 0.0], (1, T, 1))  # north at 1 m/s over ground
    cur = np.tile([0.0, 0.3, 0.0], (1, T, 1))  # 0.3 m/s current from astern
    cur[0, 4] = [0.0, 0.95, 0.0]  # nearly drifting with the water
    tr = _truth(np.zeros((1, T, 3)), vel, cur, np.zeros((1, T)))
    s = Log(LogConfig(speed={"sigma_m_s": 0.0}, min_speed_m_s=0.1), 0, (0,)).sample(
        tr, np.arange(T)
    )
    assert np.allclose(s.values[0, :4], 0.7)
    assert s.produced[0].tolist() == [True, True, True, True, False]


def test_compass_and_pressure_depth_change():
    T = 4
    pos = np.zeros((1, T, 3))
    pos[0, :, 2] = -np.array([3.0, 3.5, 4.5, 4.0])
    tr = _truth(pos, np.zeros((1, T, 3)), np.zeros((1, T, 3)), np.full((1, T), 6.2))
    c = Compass(CompassConfig(heading={"sigma_deg": 0.0, "bias_deg": 10.0}), 0, (0,)).sample(
        tr, np.arange(T)
    )
    assert np.allclose(c.values, (6.2 + math.radians(10)) % (2 * math.pi))
    d = Pressure(PressureConfig(output="depth_change", depth={"sigma_m": 0.0}), 0, (0,)).sample(
        tr, np.arange(1, T), previous=np.arange(T - 1)
    )
    assert np.allclose(d.values, [0.5, 1.0, -0.5])


def test_usbl_range_limit_field_of_view_and_latency():
    T = 4
    pos = np.array([[[100.0, 0, -3], [600.0, 0, -3], [0.0, 50, -3], [0.0, 50, -10]]])
    tr = _truth(pos, np.zeros((1, T, 3)), np.zeros((1, T, 3)), np.zeros((1, T)))
    cfg = UsblConfig(
        range={"sigma_m": 0.0},
        azimuth={"sigma_deg": 0.0},
        elevation={"sigma_deg": 0.0},
        min_elevation_deg=0.0,
        processing_delay_s=0.5,
    )
    s = Usbl(cfg, np.array([0.0, 0.0, -6.0]), 0, (0,)).sample(tr, np.arange(T))
    assert s.produced[0].tolist() == [True, False, True, False]  # beyond 500 m; below the horizon
    r = math.sqrt(100**2 + 9)
    assert s.values[0, 0, 0] == pytest.approx(r)
    assert s.t_arrival_s[0, 0] == pytest.approx(0.0 + r / 1500 + 0.5)


def test_period_checks_and_indices():
    assert check_multiple(20.0, 1.0, "usbl.period_s") == 20
    with pytest.raises(ConfigError, match=r"usbl\.period_s = 2\.5"):
        check_multiple(2.5, 1.0, "usbl.period_s")
    assert periodic_indices(601, 100).tolist() == [100, 200, 300, 400, 500, 600]


def test_gps_only_at_the_surface_after_acquisition():
    from bauv_sim.sensors import Gps, GpsConfig

    T = 12
    pos = np.zeros((1, T, 3))
    pos[0, :, 2] = [-2, -1, 0.1, 0.1, 0.1, 0.1, 0.1, -0.5, 0.1, 0.1, 0.1, 0.1]
    tr = _truth(pos, np.zeros((1, T, 3)), np.zeros((1, T, 3)), np.zeros((1, T)))
    g = Gps(GpsConfig(position={"sigma_m": 0.0}, acquisition_s=2.0), 0, (0,))
    s1 = g.sample(tr, np.arange(6))
    s2 = g.sample(tr, np.arange(6, T))  # consecutive call keeps the acquisition clock
    produced = np.concatenate([s1.produced[0], s2.produced[0]]).tolist()
    # surfaced at t=2: fixes from t=4; dived at t=7; surfaced again at t=8: fixes from t=10
    assert produced == [False] * 4 + [True] * 3 + [False] * 3 + [True] * 2
    assert np.allclose(s1.values[0, 4], [0.0, 0.0])


def test_odometry_reads_the_calibration_not_the_motion():
    from bauv_sim.sensors import Odometry, OdometryConfig

    cfg = OdometryConfig(
        frequency_hz=(0.0, 1.0, 2.0), speed_m_s=(0.0, 0.6, 1.0), speed={"scale_factor": 0.1}
    )
    s = Odometry(cfg, 0, (0, 1)).sample(np.arange(3.0), np.array([[0.5, 1.5, 3.0]] * 2))
    assert np.allclose(s.values, [[0.33, 0.88, 1.1]] * 2)
    with pytest.raises(Exception, match="strictly increasing"):
        OdometryConfig(frequency_hz=(1.0, 0.5), speed_m_s=(0.0, 1.0))


def test_usbl_elevation_past_the_zenith_is_the_direction_over_the_top():
    """Right above the transceiver half the elevation errors carry the direction past 90 deg.
    Each fix must be the point the perturbed direction gives, ``(r + e_r)(cos b sin a, cos b cos
    a, sin b)`` with ``b = 90 deg + e_b``, ``a = e_a`` (continuous through the pole), and the
    horizontal error must follow the error model: mean ``r sigma_b sqrt(2 / pi)`` for gaussian
    elevation errors. Clipping the elevation at 90 deg put half the fixes straight above the
    transceiver (a mean about half as large)."""
    from bauv_sim.frames import rel_from_range_azimuth_elevation, wrap_pi

    n, h = 4000, 30.0
    runs = tuple(range(n))
    tx = np.array([0.0, 0.0, -33.0])
    sigma_b = math.radians(3.0)
    cfg = UsblConfig(
        range={"sigma_m": 0.2}, azimuth={"sigma_deg": 3.0}, elevation={"sigma_deg": 3.0}
    )

    def sample(rel):
        pos = np.broadcast_to(tx + rel, (n, 1, 3)).copy()
        zeros = np.zeros((n, 1, 3))
        return Usbl(cfg, tx, 7, runs).sample(
            _truth(pos, zeros, zeros, np.zeros((n, 1))), np.arange(1)
        )

    # the same streams at elevation 0, azimuth 0 (no fold there): the drawn errors
    level = sample(np.array([0.0, h, 0.0])).values[:, 0]
    e_r, e_a, e_b = level[:, 0] - h, wrap_pi(level[:, 1]), level[:, 2]
    assert np.mean(e_b > 0) == pytest.approx(0.5, abs=0.05)
    above = sample(np.array([0.0, 0.0, h])).values[:, 0]
    assert np.all(np.abs(above[:, 2]) <= np.pi / 2)
    assert np.all((above[:, 1] >= 0) & (above[:, 1] < 2 * np.pi))
    b = np.pi / 2 + e_b
    expected = (h + e_r)[:, None] * np.stack(
        [np.cos(b) * np.sin(e_a), np.cos(b) * np.cos(e_a), np.sin(b)], axis=-1
    )
    assert np.allclose(rel_from_range_azimuth_elevation(above), expected, atol=1e-9)
    horizontal = np.hypot(*rel_from_range_azimuth_elevation(above)[:, :2].T)
    mean, sd = h * sigma_b * math.sqrt(2 / math.pi), h * sigma_b * math.sqrt(1 - 2 / math.pi)
    assert abs(horizontal.mean() - mean) < 4 * sd / math.sqrt(n), (horizontal.mean(), mean)


def test_compass_default_is_seed_000s_three_degree_gaussian_heading():
    """The default compass is seed 000's INS heading (section 3: "determined arbitrarily sigma_COG
    = 3 deg for INS VN-200"), unbiased gaussian: the configuration says 3 deg, and 200,000
    headings measured by the default compass scatter about the truth with a standard deviation
    within the chi-square band of their sample size (5 sigma: 3 deg +- 0.8 %) and no bias."""
    cfg = CompassConfig()
    assert cfg.heading.sigma_deg == 3.0 and cfg.heading.bias_deg == 0.0
    assert cfg.heading.distribution == "gaussian"
    T = K
    heading = np.tile(np.linspace(0.3, 6.0, T), (N, 1))
    tr = _truth(np.zeros((N, T, 3)), np.zeros((N, T, 3)), np.zeros((N, T, 3)), heading)
    s = Compass(cfg, 5, tuple(range(N))).sample(tr, np.arange(T))
    e = np.degrees(np.angle(np.exp(1j * (s.values - heading))))
    n = e.size
    assert abs(e.mean()) < 5 * 3.0 / math.sqrt(n)
    assert e.std() == pytest.approx(3.0, rel=5 * math.sqrt(1 / (2 * n)))


def test_usbl_log_and_pressure_defaults_are_seed_000s_device_figures():
    """Seed 000 section 6: "sigma_r = 0.2 m, sigma_alpha = sigma_beta = 3 deg for the USBL
    MicronNav", "sigma_dz = 0.25 m for the hydrostatic pressure sensor WIKA S-20", and (section
    3) "sigma_SOG = 0.5 kn" for the ALIZE log (1 kn = 1852 / 3600 m/s), the MicronNav's 500 m
    limit; all gaussian and unbiased by default. The configurations say so, and the default
    devices' errors over 200,000 draws have these standard deviations (5-sigma chi-square bands
    of their sample size) and no bias."""
    usbl, log, pressure = UsblConfig(), LogConfig(), PressureConfig()
    assert usbl.range.sigma_m == 0.2 and usbl.max_range_m == 500.0
    assert usbl.azimuth.sigma_deg == 3.0 and usbl.elevation.sigma_deg == 3.0
    assert pressure.depth.sigma_m == 0.25
    assert log.speed.sigma_m_s == pytest.approx(0.5 * 1852.0 / 3600.0, rel=1e-12)
    for e in (usbl.range, usbl.azimuth, usbl.elevation, pressure.depth, log.speed):
        assert e.distribution == "gaussian"
    T = K
    rel = np.array([80.0, 60.0, 10.0])  # 100.5 m slant, 5.7 deg above the transceiver
    tx = np.array([0.0, 0.0, -20.0])
    vel = np.tile([0.0, 1.2, 0.0], (N, T, 1))
    tr = _truth(np.broadcast_to(tx + rel, (N, T, 3)).copy(), vel, 0 * vel, np.zeros((N, T)))
    r0 = np.linalg.norm(rel)
    want = [r0, math.atan2(rel[0], rel[1]), math.asin(rel[2] / r0)]
    z = Usbl(usbl, tx, 3, tuple(range(N))).sample(tr, np.arange(T)).values
    d = Pressure(pressure, 3, tuple(range(N))).sample(tr, np.arange(T)).values
    s = Log(log, 3, tuple(range(N))).sample(tr, np.arange(T)).values
    cases = [
        (z[..., 0] - want[0], 0.2),
        (np.angle(np.exp(1j * (z[..., 1] - want[1]))), math.radians(3.0)),
        (z[..., 2] - want[2], math.radians(3.0)),
        (d - (20.0 - rel[2]), 0.25),
        (s - 1.2, 0.5 * 1852.0 / 3600.0),
    ]
    for err, sigma in cases:
        n = err.size
        assert abs(err.mean()) < 5 * sigma / math.sqrt(n), (err.mean(), sigma)
        assert err.std() == pytest.approx(sigma, rel=5 * math.sqrt(1 / (2 * n)))


def test_log_reads_the_velocity_through_water_along_the_pitched_hull():
    """The EM log measures the velocity through water along the body x axis, which points
    ``(cos p sin h, cos p cos h, sin p)`` for nose-up pitch p and heading h: a hull pitched 10 deg
    nose up, heading 30 deg, climbing along its axis at 1.5 m/s through a 0.3 m/s current from
    the north reads 1.5 m/s; sinking at 0.2 m/s with a level velocity reads the projection."""
    p, h = math.radians(10.0), math.radians(30.0)
    axis = np.array([math.cos(p) * math.sin(h), math.cos(p) * math.cos(h), math.sin(p)])
    cur = np.array([0.0, -0.3, 0.0])
    water = np.stack([1.5 * axis, np.array([0.4, 0.9, -0.2])])  # (2, 3): along the axis; other
    T = 2
    tr = Truth(
        np.arange(T, dtype=float),
        np.zeros((1, T, 3)),
        (water + cur)[None],
        water[None],
        np.full((1, T), h),
        np.tile([0.0, p], (1, T, 1)),
        np.tile(cur, (1, T, 1)),
    )
    s = Log(LogConfig(speed={"sigma_m_s": 0.0}), 0, (0,)).sample(tr, np.arange(T))
    np.testing.assert_allclose(s.values[0], [1.5, water[1] @ axis], rtol=1e-12)


@pytest.mark.parametrize(
    "model",
    [
        ErrorModel("gaussian", sigma=0.3, bias=0.1, scale_factor=0.01),
        ErrorModel("uniform", sigma=0.2, uniform_k=3.0, bias=-0.05),
        ErrorModel(
            "gaussian",
            sigma=1.0,
            scale_factor=-0.02,
            bias=0.4,
            random_walk=0.07,
            outlier_probability=0.2,
            outlier_sigma=5.0,
            dropout_probability=0.3,
        ),
        ErrorModel("uniform", sigma=0.5, random_walk=0.2, outlier_probability=0.5, outlier_sigma=2),
        ErrorModel(deviation=(0.01, 0.02, -0.03, 0.004, 0.005), sigma=0.1),
        ErrorModel(),
    ],
)
def test_apply_one_is_apply_of_one_sample_bit_for_bit(model):
    """The per-tick devices' scalar form gives the same bits as apply() of one sample at a time,
    with the random walk carried across samples and every stream drawn in the same order."""
    gen = np.random.default_rng(5)
    t = np.cumsum(gen.uniform(0.05, 0.5, 300))
    x = gen.normal(0.0, 10.0, 300)
    arrays = ErrorProcess(model, 17, (4,), ("sensor", "dev", "q"))
    scalars = ErrorProcess(model, 17, (4,), ("sensor", "dev", "q"))
    for ti, xi in zip(t, x, strict=True):
        v, ok = arrays.apply(np.array([[xi]]), np.array([ti]), np.array([[0.3 * xi]]))
        if model.needs_reference():  # through apply(), which needs the reference angle
            with pytest.raises(ValueError, match="reference angle"):
                scalars.apply_one(float(xi), float(ti))
            return
        w, produced = scalars.apply_one(float(xi), float(ti))
        assert type(w) is float and type(produced) is bool
        assert w == v[0, 0] and np.signbit(w) == np.signbit(v[0, 0]) and produced == ok[0, 0]
    with pytest.raises(ValueError, match="one run"):
        ErrorProcess(model, 17, (4, 5), ("q",)).apply_one(0.0, 0.0)
