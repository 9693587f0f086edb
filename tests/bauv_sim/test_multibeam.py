"""The multibeam: harmonic-seabed root finding against dense sampling, MuJoCo ray casting against
the analytic intersection of the triangulated heightfield, echoes and errors, the online device."""

import numpy as np
import pytest

from bauv_sim import seabed as sb
from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
from bauv_sim.errors import ConfigError
from bauv_sim.sensors import LengthErrorConfig, multibeam
from bauv_sim.sensors.multibeam import (
    HarmonicSeabed,
    Multibeam,
    MultibeamConfig,
    MultibeamImage,
    beam_directions,
)
from bauv_sim.sensors.rig import SensorRig


def _psi(sbd, p, pts):
    """Eq. 24 written out here, for path p at points (..., 3)."""
    w = 2 * np.pi * np.arange(1, sbd.a.shape[1] + 1) / 20.0
    x, y, z = pts[..., 0, None], pts[..., 1, None], pts[..., 2]
    s = sbd.a[p] * np.sin(w * x) + sbd.b[p] * np.cos(w * x)
    s = s + sbd.c[p] * np.sin(w * y) + sbd.d[p] * np.cos(w * y)
    return 30.0 + z + s.sum(-1)


def _dense_first_root(f, lmax, step):
    """First sign change of f on a grid of ``step`` (None if none), refined by bisection."""
    s = np.arange(0.0, lmax + step / 2, step)
    v = f(s)
    neg = np.flatnonzero(v <= 0)
    if neg.size == 0:
        return None
    i = neg[0]
    a, b = s[i - 1], s[i]
    for _ in range(80):
        m = 0.5 * (a + b)
        if f(np.array([m]))[0] > 0:
            a = m
        else:
            b = m
    return 0.5 * (a + b), v[:i]


@pytest.mark.parametrize("steps", [60, 3, 0], ids=["curvature", "mixed", "first-order"])
def test_harmonic_ranges_are_the_first_crossing_found_by_dense_sampling(steps, monkeypatch):
    # the curvature-bounded march alone, handing rays over after 3 steps, and the first-order
    # march alone must all find the same first crossing
    monkeypatch.setattr(multibeam, "CURVATURE_STEPS", steps)
    paths = 4
    bed = HarmonicSeabed.draw(7, tuple(range(paths)))
    cfg = MultibeamConfig()
    rng = np.random.default_rng(2)
    origin = np.column_stack(
        [rng.uniform(-30, 30, paths), rng.uniform(-30, 30, paths), rng.uniform(-12, -8, paths)]
    )
    att = np.column_stack([rng.normal(0, 0.05, paths), rng.uniform(-np.pi, np.pi, paths)])
    e = beam_directions(cfg, att).reshape(paths, 64, 3)
    # add shallow rays (grazing, several crossings possible) and rays going up (no echo)
    shallow = np.stack(
        [
            np.array([np.cos(-0.12) * np.cos(t), np.cos(-0.12) * np.sin(t), np.sin(-0.12)])
            for t in np.linspace(0, 6, 6)
        ]
    )
    up = np.array([[0.0, 0.6, 0.8], [0.3, 0.0, np.sqrt(1 - 0.09)]])
    rays = np.concatenate(
        [e, np.broadcast_to(shallow, (paths, 6, 3)), np.broadcast_to(up, (paths, 2, 3))], axis=1
    )
    L, hit = bed.ray_ranges(origin[:, None, :], rays, max_range_m=200.0)
    assert L.shape == hit.shape == (paths, 72) and np.all(np.isfinite(L))
    assert not hit[:, -2:].any() and np.all(L[:, -2:] == 0)
    checked = 0
    for p in range(paths):
        for r in range(0, 72, 3):
            f = lambda s, p=p, r=r: _psi(bed, p, origin[p] + s[:, None] * rays[p, r])  # noqa: E731
            want = _dense_first_root(f, 200.0, 4e-3)
            if want is None:
                assert not hit[p, r]
                continue
            root, before = want
            assert hit[p, r] and np.all(before > 0)
            assert abs(L[p, r] - root) < 1e-9, (p, r, L[p, r], root)
            checked += 1
    assert checked > 60


def test_an_origin_below_the_seabed_or_a_seabed_beyond_range_has_no_echo():
    bed = HarmonicSeabed.draw(1, (0,))
    down = np.array([[[0.0, 0.0, -1.0]]])
    L, hit = bed.ray_ranges(np.array([[[0.0, 0.0, -60.0]]]), down, 100.0)
    assert not hit.any() and L[0, 0] == 0
    L, hit = bed.ray_ranges(np.array([[[0.0, 0.0, -10.0]]]), down, 5.0)
    assert not hit.any() and L[0, 0] == 0
    L, hit = bed.ray_ranges(np.array([[[0.0, 0.0, -10.0]]]), down, 100.0)
    assert hit.all()
    np.testing.assert_allclose(
        -10 - L[0, 0], bed.height(np.zeros((1,)), np.zeros((1,)))[0], atol=1e-9
    )


def test_range_errors_dropouts_and_max_range_flag_beams_absent_never_nan():
    cfg = MultibeamConfig(
        range=LengthErrorConfig(sigma_m=0.1, dropout_probability=0.2), max_range_m=25.0
    )
    n, k = 200, 5
    mb = Multibeam(cfg, 3, tuple(range(n)))
    true = np.random.default_rng(1).uniform(10, 30, (n, k, 8, 8))
    hit = np.ones_like(true, bool)
    hit[:, :, 0, 0] = False  # no seabed on one beam
    img = mb.measure(np.where(hit, true, 0.0), hit, np.arange(k, dtype=float), np.zeros((n, k, 2)))
    assert np.all(np.isfinite(img.ranges_m))
    assert not img.echo[:, :, 0, 0].any() and np.all(img.ranges_m[~img.echo] == 0)
    assert not img.echo[true > 25.0].any()
    inside = hit & (true <= 25.0)
    frac = img.echo[inside].mean()
    assert abs(frac - 0.8) < 4 * np.sqrt(0.16 / inside.sum())
    err = (img.ranges_m - true)[img.echo]
    assert abs(err.std() - 0.1) < 4 * 0.1 / np.sqrt(2 * err.size)
    # same seed, same numbers
    img2 = Multibeam(cfg, 3, tuple(range(n))).measure(
        np.where(hit, true, 0.0), hit, np.arange(k, dtype=float), np.zeros((n, k, 2))
    )
    assert np.array_equal(img.ranges_m, img2.ranges_m) and np.array_equal(img.echo, img2.echo)


def test_random_walk_on_beams_is_refused():
    with pytest.raises(ValueError, match="random_walk"):
        MultibeamConfig(range=LengthErrorConfig(random_walk_m_per_sqrt_s=0.1))


SMALL = sb.SeabedConfig(
    half_extent_m=80.0,
    cell_m=4.0,
    depth_at_origin_m=20.0,
    slope=0.02,
    relief_std_m=2.0,
    n_modes=12,
    min_wavelength_m=15.0,
    max_wavelength_m=80.0,
    min_depth_m=4.5,
    seed=3,
)
FLAT = sb.SeabedConfig(
    half_extent_m=80.0,
    cell_m=4.0,
    depth_at_origin_m=20.0,
    slope=0.0,
    relief_std_m=0.0,
    min_depth_m=4.5,
)


def _triangulated_range(bed, origin, e, lmax):
    """First crossing of z_ray = height_world (the piecewise-linear triangles) along a ray:
    grid of 1 mm and bisection (height_world is linear on each triangle)."""

    def f(s):
        p = origin + s[:, None] * e
        inside = (np.abs(p[:, 0]) < 80) & (np.abs(p[:, 1]) < 80)
        out = np.ones_like(s)
        out[inside] = p[inside, 2] - bed.height_world(p[inside, 0], p[inside, 1])
        return out

    r = _dense_first_root(f, lmax, 1e-3)
    return None if r is None else r[0]


def test_mujoco_ray_ranges_equal_the_triangulated_heightfield_intersection():
    phys = build_physics(
        SceneConfig(seabed=SMALL, beacons=(), vehicles=(VehicleSpec(depth_m=5.0),))
    )
    bed = sb.generate(SMALL)
    origin = np.array([3.0, -2.0, -6.0])
    rng = np.random.default_rng(4)
    e = rng.normal(size=(40, 3))
    e[:, 2] = -np.abs(e[:, 2]) - 0.3
    e /= np.linalg.norm(e, axis=1)[:, None]
    e[-1] = (0.0, 0.0, 1.0)  # up: nothing
    dist, hit = phys.seabed_ray_distances(origin, e, 150.0)
    assert not hit[-1] and dist[-1] == 0 and np.all(np.isfinite(dist))
    for i in range(39):
        want = _triangulated_range(bed, origin, e[i], 150.0)
        if want is None:
            assert not hit[i]
        else:
            assert hit[i] and abs(dist[i] - want) < 0.01, (i, dist[i], want)
    assert hit[:39].sum() > 30
    # a shorter maximum range removes the far echoes
    d2, h2 = phys.seabed_ray_distances(origin, e, 20.0)
    assert np.array_equal(h2, hit & (dist <= 20.0)) and np.all(d2[~h2] == 0)


def test_analytic_heightfield_ranges_equal_mujoco_and_the_dense_first_crossing():
    # the surrogate's ray cast (Seabed.ray_ranges, triangle by triangle) against MuJoCo's rays on
    # the same heightfield, and against the 1 mm grid and bisection of the triangulated surface
    phys = build_physics(
        SceneConfig(seabed=SMALL, beacons=(), vehicles=(VehicleSpec(depth_m=5.0),))
    )
    bed = sb.generate(SMALL)
    rng = np.random.default_rng(8)
    checked = 0
    for _ in range(3):
        origin = np.array([rng.uniform(-40, 40), rng.uniform(-40, 40), -6.0 - rng.uniform(0, 3)])
        e = rng.normal(size=(60, 3))
        e[:, 2] = -np.abs(e[:, 2]) - 0.1
        e /= np.linalg.norm(e, axis=1)[:, None]
        e[-1] = (0.6, 0.0, 0.8)  # up: no echo
        dist, hit = phys.seabed_ray_distances(origin, e, 150.0)
        L, h = bed.ray_ranges(origin, e, 150.0)
        assert np.array_equal(h, hit) and not h[-1] and L[-1] == 0
        np.testing.assert_allclose(L[h], dist[h], rtol=0, atol=1e-9)
        for i in range(0, 59, 6):
            want = _triangulated_range(bed, origin, e[i], 150.0)
            assert (want is None) == (not h[i])
            if want is not None:
                assert abs(L[i] - want) < 1e-9, (i, L[i], want)
                checked += 1
    assert checked >= 20
    # batched shapes, an origin below the seabed and a ray leaving the grid have no echo
    o = np.array([[[0.0, 0.0, -60.0]], [[79.0, 0.0, -6.0]]])
    L, h = bed.ray_ranges(o, np.array([[[0.0, 0.0, -1.0]], [[1.0, 0.0, -0.01]]]), 150.0)
    assert L.shape == (2, 1) and not h.any() and np.all(L == 0)


def test_mujoco_ray_ranges_on_a_flat_seabed_are_the_plane_intersection():
    phys = build_physics(SceneConfig(seabed=FLAT, beacons=(), vehicles=(VehicleSpec(),)))
    cfg = MultibeamConfig()
    origin = np.array([1.0, 2.0, -3.0])
    e = beam_directions(cfg, np.array([0.02, 0.8])).reshape(-1, 3)
    dist, hit = phys.seabed_ray_distances(origin, e, 100.0)
    assert hit.all()
    np.testing.assert_allclose(dist, (-20.0 - origin[2]) / e[:, 2], atol=1e-6)


def test_online_multibeam_device_images_the_seabed_from_the_sonar_site():
    phys = build_physics(
        SceneConfig(seabed=FLAT, beacons=(), vehicles=(VehicleSpec(depth_m=4.0, heading_deg=30.0),))
    )
    cfg = MultibeamConfig(period_s=0.2, range=LengthErrorConfig(sigma_m=0.0))
    rig = SensorRig({"multibeam": cfg}, phys, "bauv", seed=1, run=0)
    vt = phys.truth()
    assert rig.sense(0, vt, phys.commands(), initial=True).arrived == ()
    tick = rig.sense(2, vt, phys.commands())
    (m,) = tick.arrived
    assert isinstance(m.payload, MultibeamImage) and m.value.shape == (64,)
    sonar = phys.site_position_world("sonar")
    _r, pitch, heading = vt.roll_pitch_heading_rad
    theta = np.pi / 2 - heading  # seed 004's theta from the navigation heading
    e = beam_directions(cfg, np.array([pitch, theta])).reshape(-1, 3)
    np.testing.assert_allclose(m.value, (-20.0 - sonar[2]) / e[:, 2], atol=1e-6)
    assert m.payload.echo.all()
    np.testing.assert_allclose(
        m.payload.attitude_rad, [pitch, np.arctan2(np.sin(theta), np.cos(theta))], atol=1e-12
    )
    # out of range: nothing echoes, the values are zeros, never NaN
    rig2 = SensorRig({"multibeam": cfg.model_copy(update={"max_range_m": 5.0})}, phys, "bauv", 1, 0)
    (m2,) = rig2.sense(2, vt, phys.commands()).arrived
    assert not m2.payload.echo.any() and np.all(m2.value == 0)


def test_harmonic_seabed_refuses_mismatched_rays():
    bed = HarmonicSeabed.draw(1, (0, 1))
    with pytest.raises(ConfigError, match="seabeds"):
        bed.ray_ranges(np.zeros((3, 1, 3)), np.array([[[0.0, 0.0, -1.0]]] * 3), 10.0)


def test_online_multibeam_follows_the_moving_hull():
    """After the physics has stepped (the vehicle swimming, pitching and rolling a little) the
    beams start at the sonar site where MuJoCo puts it and are aimed from the hull's attitude."""
    phys = build_physics(SceneConfig(seabed=FLAT, beacons=(), vehicles=(VehicleSpec(depth_m=4.0),)))
    cfg = MultibeamConfig(range=LengthErrorConfig(sigma_m=0.0))
    rig = SensorRig({"multibeam": cfg}, phys, "bauv", seed=1, run=0)
    phys.set_tail_beat_frequency_hz(1.5)
    phys.advance(2.0)
    vt = phys.truth()
    (m,) = rig.sense(20, vt, phys.commands()).arrived
    sonar = phys.site_position_world("sonar")
    assert np.linalg.norm(sonar - [0.0, 0.0, -4.0]) > 0.05  # it did move
    _r, pitch, heading = vt.roll_pitch_heading_rad
    e = beam_directions(cfg, np.array([pitch, np.pi / 2 - heading])).reshape(-1, 3)
    np.testing.assert_allclose(m.value, (-20.0 - sonar[2]) / e[:, 2], atol=1e-6)
