"""The navigator's map: bilinear depth and gradient against a plane and by hand, NaN cells and
off-map points flagged (never NaN out), the degraded copy, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.trn import TerrainMap, degraded


def plane_map(cell_m=2.0):
    x = np.arange(-20.0, 40.0 + cell_m / 2, cell_m)
    y = np.arange(10.0, 50.0 + cell_m / 2, cell_m)
    return TerrainMap(x, y, 30.0 + 0.2 * x[None, :] - 0.05 * y[:, None])


def test_bilinear_is_exact_on_a_plane_with_its_gradient():
    m = plane_map()
    rng = np.random.default_rng(0)
    x = rng.uniform(-20.0, 40.0, (7, 5))
    y = rng.uniform(10.0, 50.0, (7, 5))
    d, ok = m.depth(x, y)
    g, gok = m.gradient(x, y)
    assert d.shape == (7, 5) and g.shape == (7, 5, 2)
    assert ok.all() and gok.all()
    np.testing.assert_allclose(d, 30.0 + 0.2 * x - 0.05 * y, atol=1e-12)
    np.testing.assert_allclose(g[..., 0], 0.2, atol=1e-12)
    np.testing.assert_allclose(g[..., 1], -0.05, atol=1e-12)


def test_bilinear_by_hand_in_one_cell_and_its_gradient_by_finite_differences():
    z = np.array([[1.0, 2.0], [4.0, 8.0]])  # rows: y = 0, 1; columns: x = 0, 3
    m = TerrainMap([0.0, 3.0], [0.0, 1.0], z)
    d, ok = m.depth(1.5, 0.5)
    assert ok and d == pytest.approx((1 + 2 + 4 + 8) / 4)
    d, _ = m.depth(3.0, 1.0)  # a corner on the far edges
    assert d == pytest.approx(8.0)
    h = 1e-6
    for px, py in [(0.7, 0.2), (2.1, 0.9)]:
        g, _ = m.gradient(px, py)
        fx = (m.depth(px + h, py)[0] - m.depth(px - h, py)[0]) / (2 * h)
        fy = (m.depth(px, py + h)[0] - m.depth(px, py - h)[0]) / (2 * h)
        np.testing.assert_allclose(g, [fx, fy], rtol=1e-6)


def test_nan_cells_and_off_map_points_are_invalid_and_never_nan():
    x = np.arange(5.0)
    z = np.full((5, 5), 10.0)
    z[2, 2] = np.nan
    m = TerrainMap(x, x, z)
    qx = np.array([1.5, 2.5, 0.5, -0.1, 4.2, np.nan, 3.5])
    qy = np.array([1.5, 2.5, 0.5, 1.0, 5.01, 1.0, 3.5])
    d, ok = m.depth(qx, qy)
    g, gok = m.gradient(qx, qy)
    # the four cells around node (2, 2) have no data; (0.5, 0.5) and (3.5, 3.5) do
    np.testing.assert_array_equal(ok, [False, False, True, False, False, False, True])
    np.testing.assert_array_equal(gok, ok)
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(g))
    assert np.all(d[~ok] == 0.0)
    assert m.extent == (0.0, 4.0, 0.0, 4.0)


def test_degraded_map_is_coarser_noisy_and_offset_never_the_truth():
    truth = plane_map(cell_m=1.0)
    rng = np.random.default_rng(1)
    nav_map = degraded(truth, cell_m=5.0, vertical_sigma_m=0.4, offset_m=1.5, rng=rng)
    assert nav_map.dx_m == pytest.approx(5.0) and nav_map.dy_m == pytest.approx(5.0)
    assert nav_map.sigma_m == pytest.approx(0.4)
    tx, ty = np.meshgrid(nav_map.x_m, nav_map.y_m)
    err = nav_map.depth_m - (30.0 + 0.2 * tx - 0.05 * ty)
    n = err.size
    # mean offset within 4 standard errors, spread within 4 standard errors of a variance
    assert abs(err.mean() - 1.5) < 4 * 0.4 / np.sqrt(n)
    assert abs(err.std(ddof=1) ** 2 / 0.16 - 1.0) < 4 * np.sqrt(2.0 / (n - 1))


def test_degraded_keeps_the_truths_missing_data():
    x = np.arange(0.0, 21.0)
    z = np.full((21, 21), 10.0)
    z[:, 15:] = np.nan
    out = degraded(TerrainMap(x, x, z), 5.0, 0.1, 0.0, np.random.default_rng(0))
    assert np.isnan(out.depth_m[:, -1]).all() and np.isfinite(out.depth_m[:, :3]).all()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"x_m": [0.0, 1.0, 3.0]}, "x_m"),
        ({"y_m": [1.0]}, "y_m"),
        ({"depth_m": np.zeros((3, 3))}, "depth_m"),
        ({"sigma_m": -1.0}, "sigma_m"),
        ({"depth_m": np.full((2, 3), np.inf)}, "depth_m"),
    ],
)
def test_bad_map_input_is_one_clear_error(kwargs, field):
    args = {"x_m": [0.0, 1.0, 2.0], "y_m": [0.0, 1.0], "depth_m": np.zeros((2, 3))} | kwargs
    with pytest.raises(NavInputError, match=field):
        TerrainMap(**args)


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((0.0, 0.1, 0.0), "cell_m"),
        ((1.0, -0.1, 0.0), "vertical_sigma_m"),
        ((1.0, 0.1, np.nan), "offset_m"),
        ((500.0, 0.1, 0.0), "cell_m"),
    ],
)
def test_bad_degradation_is_one_clear_error(args, field):
    with pytest.raises(NavInputError, match=field):
        degraded(plane_map(), *args, rng=np.random.default_rng(0))


def test_interpolation_sigma_is_the_rms_bilinear_error_of_a_parabola_and_of_relief():
    """A parabola z = c x^2 has bilinear error c h^2 u (1 - u) on every cell: RMS over u uniform
    is c h^2 / sqrt(30), which the estimate from the second differences gives exactly. On a sum
    of plane waves it is within 35 % of the error measured against the terrain between nodes."""
    h, c = 2.0, 0.03
    ax = np.arange(-20.0, 20.0 + h / 2, h)
    X, Y = np.meshgrid(ax, ax)
    m = TerrainMap(ax, ax, 10.0 + c * X**2)
    assert m.interpolation_sigma_m() == pytest.approx(c * h * h / np.sqrt(30.0), rel=1e-12)
    x = np.random.default_rng(0).uniform(-19.0, 19.0, 200_000)
    got, ok = m.depth(x, np.zeros_like(x))
    assert ok.all()
    measured = np.sqrt(np.mean((got - (10.0 + c * x**2)) ** 2))
    assert measured == pytest.approx(m.interpolation_sigma_m(), rel=0.01)

    rng = np.random.default_rng(3)
    k = 2 * np.pi / rng.uniform(40.0, 120.0, 12)
    th, ph = rng.uniform(0, 2 * np.pi, 12), rng.uniform(0, 2 * np.pi, 12)

    def terrain(x, y):
        waves = zip(k, th, ph, strict=True)
        return 30.0 + sum(np.cos(kk * (np.cos(t) * x + np.sin(t) * y) + p) for kk, t, p in waves)

    h = 8.0
    ax = np.arange(-400.0, 400.0 + h / 2, h)
    X, Y = np.meshgrid(ax, ax)
    m = TerrainMap(ax, ax, terrain(X, Y))
    x, y = rng.uniform(-390.0, 390.0, (2, 100_000))
    got, _ = m.depth(x, y)
    measured = np.sqrt(np.mean((got - terrain(x, y)) ** 2))
    assert m.interpolation_sigma_m() == pytest.approx(measured, rel=0.35)


def test_interpolation_sigma_of_a_plane_a_tiny_map_and_a_map_of_holes_is_zero():
    ax = np.arange(5.0)
    X, Y = np.meshgrid(ax, ax)
    assert TerrainMap(ax, ax, 3.0 + 0.2 * X - 0.1 * Y).interpolation_sigma_m() == pytest.approx(
        0.0, abs=1e-15
    )
    assert TerrainMap([0.0, 1.0], [0.0, 1.0], np.ones((2, 2))).interpolation_sigma_m() == 0.0
    holes = np.full((4, 4), np.nan)
    assert TerrainMap(ax[:4], ax[:4], holes).interpolation_sigma_m() == 0.0
