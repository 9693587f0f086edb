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

from . import multibeam_reference


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


@pytest.mark.slow
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


@pytest.mark.slow
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


def _direction(elevation, azimuth):
    """Unit vectors (..., 3) from elevation (up from the horizontal) and azimuth, rad."""
    ce = np.cos(elevation)
    return np.stack([ce * np.cos(azimuth), ce * np.sin(azimuth), np.sin(elevation)], axis=-1)


def _test_rays(seed, paths):
    """Seed 004's 8 x 8 beams plus random rays over ``paths`` random seabeds: grazing, upward,
    level, vertical, in any direction, un-normalised, from below the seabed and from the surface.
    Returns the seabeds, origins (P, R, 3) m and directions (P, R, 3)."""
    rng = np.random.default_rng(seed)
    bed = HarmonicSeabed.draw(seed, tuple(range(paths)))
    x = rng.uniform(-100, 300, paths)
    y = rng.uniform(-50, 50, paths)
    z = rng.uniform(-26, -5, paths)
    att = np.column_stack([rng.normal(0, 0.05, paths), rng.uniform(-np.pi, np.pi, paths)])
    beams = beam_directions(MultibeamConfig(), att).reshape(paths, 64, 3)
    grazing = _direction(rng.uniform(-0.25, -0.01, (paths, 40)), rng.uniform(-4, 4, (paths, 40)))
    grazing *= rng.uniform(0.2, 5.0, (paths, 40, 1))  # any length: normalised by ray_ranges
    up = _direction(rng.uniform(0.0, 1.5, (paths, 6)), rng.uniform(-4, 4, (paths, 6)))
    vertical = np.broadcast_to([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]], (paths, 2, 3))
    anywhere = rng.normal(size=(paths, 20, 3))
    # tangent to the seabed at a random point, passing 1e-7 m above or below it: on a crest a
    # near-double root, which the curvature march leaves to the first-order march
    px, py = (
        x[:, None] + rng.uniform(-10, 10, (paths, 12)),
        y[:, None] + rng.uniform(-10, 10, (paths, 12)),
    )
    pz = bed.height(px, py)
    az = rng.uniform(-4, 4, (paths, 12))
    gx, gy = bed.gradient(np.stack([px, py, pz], axis=-1))[..., :2].transpose(2, 0, 1)
    tangent = np.stack([np.cos(az), np.sin(az), -(gx * np.cos(az) + gy * np.sin(az))], axis=-1)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    lift = np.where(np.arange(12) % 2, 1e-7, -1e-7)
    touch = np.stack([px, py, pz + lift], axis=-1) - 15.0 * tangent
    e = np.concatenate([beams, grazing, up, vertical, tangent, anywhere], axis=1)
    o = np.repeat(np.column_stack([x, y, z])[:, None], e.shape[1], axis=1)
    o[:, 112:124] = touch
    # the last 10: from below the seabed (no echo) and from the surface (above the slab)
    below = o[:, -10:-5]
    below[..., 2] = bed.height(below[..., 0], below[..., 1]) - rng.uniform(0, 3, (paths, 5))
    o[:, -5:, 2] = 0.0
    return bed, o, e


@pytest.mark.parametrize("steps", [60, 4], ids=["curvature", "handed-over"])
@pytest.mark.parametrize("max_range_m", [100.0, 20.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compiled_march_equals_the_numpy_reference(seed, max_range_m, steps, monkeypatch):
    # the compiled march against the numpy march it replaced
    # (tests/bauv_sim/multibeam_reference.py): the same first crossings to rounding, the same
    # hits; rays unresolved after `steps` go on in the first-order march from where the march
    # stopped, in both
    monkeypatch.setattr(multibeam, "CURVATURE_STEPS", steps)
    handed = []
    first_order = HarmonicSeabed._lipschitz_ranges

    def spy(self, o, *args):
        handed.append(len(o))
        return first_order(self, o, *args)

    bed, o, e = _test_rays(seed, 30)
    want_L, want_hit = multibeam_reference.ray_ranges(bed, o, e, max_range_m)
    monkeypatch.setattr(HarmonicSeabed, "_lipschitz_ranges", spy)
    L, hit = bed.ray_ranges(o, e, max_range_m)
    assert L.shape == hit.shape == o.shape[:2]
    assert np.array_equal(hit, want_hit)
    np.testing.assert_allclose(L, want_L, rtol=0, atol=1e-9)
    assert np.all(L[~hit] == 0)
    # every kind of ray is there: echoes, none within range, none upward or from below
    assert 0.2 < hit.mean() < 0.95
    assert not hit[:, 104:110].any() and not hit[:, -10:-5].any()
    assert sum(handed) > (200 if steps == 4 else 0)


@pytest.mark.parametrize(
    ("origin", "direction", "kwargs"),
    [
        ([0.0, 0.0, -10.0], [0.0, 0.0, 0.0], {}),
        ([0.0, 0.0, -10.0], [np.nan, 0.0, -1.0], {}),
        ([np.inf, 0.0, -10.0], [0.0, 0.0, -1.0], {}),
        ([0.0, 0.0, -10.0], [0.2, 0.0, -1.0], {"max_iterations": 2}),
    ],
    ids=["zero", "nan", "infinite-origin", "unfinished"],
)
def test_compiled_march_refuses_bad_rays_as_the_reference(origin, direction, kwargs, monkeypatch):
    monkeypatch.setattr(multibeam, "CURVATURE_STEPS", 0)  # the first-order march: 2 steps are few
    bed = HarmonicSeabed.draw(3, (0,))
    o, e = np.array([[origin]]), np.array([[direction]])
    with pytest.raises(ConfigError) as want:
        multibeam_reference.ray_ranges(bed, o, e, 100.0, **kwargs)
    with pytest.raises(ConfigError) as got:
        bed.ray_ranges(o, e, 100.0, **kwargs)
    assert str(got.value) == str(want.value)


def test_harmonic_seabed_refuses_inconsistent_or_non_finite_coefficients():
    """b, c, d of one path beside a of four: the C march used to read b[p K] past b's buffer and
    return wrong ranges without a word."""
    good = HarmonicSeabed.draw(0, (0, 1, 2, 3))
    with pytest.raises(ConfigError, match=r"HarmonicSeabed.b: shape \(1, 2\), but a has \(4, 2\)"):
        HarmonicSeabed(good.a, good.b[:1], good.c[:1], good.d[:1])
    with pytest.raises(ConfigError, match=r"HarmonicSeabed.d: shape \(4, 3\), but a has"):
        HarmonicSeabed(good.a, good.b, good.c, np.zeros((4, 3)))
    with pytest.raises(ConfigError, match=r"HarmonicSeabed.a: shape \(2,\); need \(paths"):
        HarmonicSeabed(np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2))
    with pytest.raises(ConfigError, match=r"HarmonicSeabed\.c: non-finite"):
        HarmonicSeabed(good.a, good.b, np.where(good.c > 0.5, np.nan, good.c), good.d)
    with pytest.raises(ConfigError, match=r"HarmonicSeabed\.period_y_m = 0"):
        HarmonicSeabed(good.a, good.b, good.c, good.d, period_y_m=0.0)
    with pytest.raises(ConfigError, match="max_range_m = nan"):
        good.ray_ranges(np.zeros((4, 3)), np.array([0.0, 0.0, -1.0]), float("nan"))
    # the coefficients are the seabed's own copy: a caller's array changed later does not move it
    a = good.a.copy()
    bed = HarmonicSeabed(a, good.b, good.c, good.d)
    a[:] = 0.0
    assert np.array_equal(bed.a, good.a)


def _march_args(bed, o, e, path):
    """The compiled march's arrays for rays (r, 3) of seabed ``bed``, as _curvature_march passes
    them (bauv_sim.sensors.harmonic_march.march), the inputs and the outputs apart (the caller
    can then break either)."""
    wx, wy = bed._w()
    inputs = {
        "o": np.ascontiguousarray(o, float),
        "e": np.ascontiguousarray(e, float),
        "path": np.ascontiguousarray(path, np.int64),
        **{c: np.ascontiguousarray(getattr(bed, c)) for c in "abcd"},
        "wx": wx,
        "wy": wy,
        "top": -bed.a0_m + bed.relief_bound(),
        "cxx": (wx**2 * np.hypot(bed.a, bed.b)).sum(-1),
        "cyy": (wy**2 * np.hypot(bed.c, bed.d)).sum(-1),
    }
    n = len(path)
    outs = {
        "range": np.full(n, -7.0),
        "hit": np.zeros(n, np.uint8),
        "unresolved": np.zeros(n, np.uint8),
        "s": np.full(n, -7.0),
    }
    return inputs, outs


def _march(bed, inputs, outs, steps=60):
    from bauv_sim.sensors import harmonic_march

    names = ("o", "e", "path", "a", "b", "c", "d", "wx", "wy", "top", "cxx", "cyy")
    scalars = (bed.a0_m, bed.period_x_m, bed.period_y_m, 100.0, 1e-9, steps)
    results = (outs[k] for k in ("range", "hit", "unresolved", "s"))
    return harmonic_march.march(*(inputs[k] for k in names), *scalars, *results)


def test_compiled_march_stays_inside_its_arrays_whatever_python_passes():
    """The march checks every array's length and every path index before it reads (numba
    checks no bounds): a seabed whose coefficients were swapped for shorter ones behind the
    constructor's back, a path index past the seabeds, an output shorter than the rays, per-path
    arrays shorter than the coefficients, or no harmonics are refused with nothing written;
    consistent arguments give the ranges of ray_ranges."""
    bed = HarmonicSeabed.draw(2, (0, 1, 2))
    o = np.tile([0.0, 0.0, -10.0], (3, 1))
    e = np.tile([0.2, 0.1, -1.0], (3, 1)) / np.linalg.norm([0.2, 0.1, -1.0])
    path = np.arange(3)
    inputs, outs = _march_args(bed, o, e, path)
    assert _march(bed, inputs, outs) == 0
    np.testing.assert_allclose(outs["range"], bed.ray_ranges(o, e, 100.0)[0], rtol=1e-13)
    for field, value, status in (
        ("path", np.array([0, 1, 3]), -2),  # path 3 of 3 seabeds
        ("b", None, -1),  # b of one path, a of three
        ("wx", None, -1),  # w_l of one harmonic
    ):
        inputs, outs = _march_args(bed, o, e, path)
        inputs[field] = inputs[field][:1].copy() if value is None else value
        assert _march(bed, inputs, outs) == status
        assert np.all(outs["range"] == -7.0) and np.all(outs["s"] == -7.0)  # nothing written
    inputs, outs = _march_args(bed, o, e, path)
    assert _march(bed, inputs | {"top": inputs["top"][:2]}, outs) == -1  # per-path, of 2
    short = outs | {"s": np.full(2, -7.0)}
    assert _march(bed, inputs, short) == -1  # an output shorter than the rays
    assert np.all(short["range"] == -7.0)
    none = {c: np.ascontiguousarray(inputs[c][:, :0]) for c in "abcd"}
    assert _march(bed, inputs | none, outs) == -3  # no harmonics
    assert _march(bed, inputs, outs, steps=-1) == -3
    assert np.all(outs["range"] == -7.0)
    # through the class: coefficients swapped behind the constructor's back
    object.__setattr__(bed, "b", bed.b[:1])
    with pytest.raises(ConfigError, match=r"refused its arguments.*buffer shorter"):
        bed.ray_ranges(o, e, 100.0)


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
