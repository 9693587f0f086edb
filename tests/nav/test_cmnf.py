"""Seed 004's CMNF (eq. 22-24) trained on few paths near a beacon, against independent truth: the
correction never worse than the prediction on fresh paths (H = 0 is one of the linear
corrections eq. 22 minimises over), the winsorisation bounds against a Cauchy sample's quantiles,
eq. 22 bit for bit where nothing is clipped, cmnf_step worked out by hand, and the refusals."""

import math

import numpy as np
import pytest

from bauv_sim.kinematic.seed004 import (
    SECTION6_BEACONS,
    NominalPathConfig,
    PathNoise,
    Seed004Noise,
    Seed004World,
    TrainingNoise,
)
from nav.bearings import SystemPrediction, bearings
from nav.bearings.cmnf import CmnfGains, clip_bounds, cmnf_step, top_share, train
from nav.bearings.local_control import optimal_control
from nav.errors import NavInputError

NEAR = np.array([[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], [-5.0, -5.0, 0]])
"""paper-004/near-beacon's beacons: the fourth 7 m beside the start, 10 m above it."""


def _setting(duration_s, var, beacons):
    path = NominalPathConfig(duration_s=duration_s)
    noise = Seed004Noise(sigma_x0_m=(math.sqrt(var),) * 3)
    xn, vn = path.path(), path.velocities()

    def control(k, x_hat):
        return optimal_control(x_hat, xn[k], vn[k], path.dt_s)

    return path, noise, control, SystemPrediction(path.dt_s, noise.s_w)


def _train(path, noise, control, pred, beacons, n, seed, **kw):
    world = Seed004World(path, noise, beacons, TrainingNoise(noise, len(beacons), seed, n))
    return train(world, path.start_m, path.n_steps, control, pred, beacons, **kw)


def _fresh_errors(gains, path, noise, control, pred, beacons, n, seed):
    """Per step k = 1..N on fresh paths: E||X - X^||^2 and E||X - X~||^2, m^2."""
    xn = path.path()
    world = Seed004World(
        path, noise, beacons, PathNoise(noise, path.n_steps, len(beacons), seed, tuple(range(n)))
    )
    x = world.start()
    x_hat = np.broadcast_to(xn[0], x.shape).copy()
    out = []
    for k in range(path.n_steps):
        u = control(k, x_hat)
        alpha = x_hat + pred(k, x_hat, u).displacement_m
        x = world.advance(k, x, u)
        y, present = world.observe(k + 1, x)
        x_tilde, x_hat = cmnf_step(gains, k + 1, alpha, "residual", y, present, beacons)
        out.append((np.mean(np.sum((x - x_hat) ** 2, 1)), np.mean(np.sum((x - x_tilde) ** 2, 1))))
    return np.array(out)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 2])
def test_near_beacon_gains_from_few_paths_never_make_the_estimate_worse_than_the_prediction(seed):
    """Eq. 22's H_k minimises E||X - X~ - H beta - h||^2 over all linear corrections, H = 0
    among them, so on fresh paths E||X - X^||^2 <= E||X - X~||^2 up to the gains' estimation
    error. With the paper's unclipped beta, 2000 training paths near the beacon gave 10 x (seed
    0) and 51 x the prediction's error on 20000 fresh paths: a path passing under the beacon's
    x has a tangent residual beyond anything trained on, and the linear gain extrapolates."""
    path, noise, control, pred = _setting(10.0, 5.0, NEAR)
    gains, trace = _train(path, noise, control, pred, NEAR, 2000, seed)
    err = _fresh_errors(gains, path, noise, control, pred, NEAR, 20_000, 1000 + seed)
    ratio = err[:, 0] / err[:, 1]
    assert ratio.max() < 1.0, ratio
    assert trace.clipped.sum() > 0  # the tangents near the beacon were clipped


def test_clip_bounds_are_the_median_plus_minus_c_robust_sigmas():
    """A Cauchy column (location 1, scale 0.5): its 5th/95th percentiles are 1 -+ 0.5 tan(0.45
    pi), so the robust sigma is 0.5 tan(0.45 pi) / z_0.95 and the bounds 1 +- 6 of it; a
    Gaussian column (sigma 2) gets 0 +- 12 and none of its values is clipped; a column that is 0
    on 95 % of the rows is not clipped at all."""
    rng = np.random.default_rng(4)
    n = 200_000
    cauchy = 1.0 + 0.5 * rng.standard_cauchy(n)
    gauss = 2.0 * rng.standard_normal(n)
    sparse = np.where(rng.random(n) < 0.95, 0.0, rng.standard_cauchy(n))
    b = np.column_stack([cauchy, gauss, sparse])
    lo, hi = clip_bounds(b, 6.0)
    z95 = 1.6448536269514722
    half = 6 * 0.5 * math.tan(0.45 * math.pi) / z95
    np.testing.assert_allclose([lo[0], hi[0]], [1 - half, 1 + half], rtol=0.03)
    np.testing.assert_allclose([lo[1], hi[1]], [-12.0, 12.0], rtol=0.03)
    assert not ((gauss < lo[1]) | (gauss > hi[1])).any()
    assert lo[2] == -np.inf and hi[2] == np.inf
    lo, hi = clip_bounds(b, None)
    assert np.all(lo == -np.inf) and np.all(hi == np.inf)


def test_top_share_is_the_largest_share_of_one_row_in_a_sum_of_squares():
    b = np.array([[0.0, 1.0], [0.0, -1.0], [0.0, 1.0], [10.0, -1.0]])
    # column 0: mean 2.5, squared deviations 6.25 x 3 and 56.25: 56.25 / 75
    assert top_share(b) == pytest.approx(0.75, rel=1e-15)
    assert top_share(np.ones((5, 2))) == 0.0


def test_where_nothing_is_clipped_the_gains_are_eq22_bit_for_bit():
    """Table 1's setting (section 6 beacons, far away): the tangents are near-Gaussian, no value
    of beta lies beyond 6 robust sigmas, and the winsorised filter is the paper's exactly."""
    b = np.array(SECTION6_BEACONS)
    path, noise, control, pred = _setting(40.0, 1.0, b)
    clipped, trace = _train(path, noise, control, pred, b, 3000, 5)
    plain, _ = _train(path, noise, control, pred, b, 3000, 5, clip_sigmas=None)
    assert trace.clipped.sum() == 0
    for k in ("F", "f", "H", "h", "p_tilde", "p_hat"):
        assert np.array_equal(getattr(clipped, k), getattr(plain, k)), k
    assert plain.beta_lo is None and np.all(np.isfinite(clipped.beta_lo))


def test_cmnf_step_clips_beta_to_the_gains_bounds_worked_out_by_hand():
    """One beacon, one step: X~ = F alpha + f, beta = Y - (dy/dx, dz/rho) at X~ (eq. 24),
    clipped to [lo, hi], X^ = X~ + H beta_c + h (eq. 22)."""
    beacon = np.array([[-5.0, -5.0, 0.0]])
    F = np.array([[[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]])
    f = np.array([[1.0, 2.0, -5.0]])
    H = np.array([[[0.3, -0.2], [0.1, 0.4], [0.0, 0.5]]])
    h = np.array([[0.01, -0.02, 0.03]])
    lo, hi = np.array([[-0.5, -1.0]]), np.array([[0.5, 1.0]])
    eye = np.eye(3)[None]
    gains = CmnfGains(F, f, H, h, eye, eye, beta_lo=lo, beta_hi=hi)
    alpha = np.array([[2.0, 4.0, -10.0], [0.0, 0.0, -8.0]])
    y = np.array([[[40.0, 0.9]], [[1.2, -3.0]]])  # the first tan phi far beyond hi
    present = np.ones((2, 1), bool)
    x_t, x_h = cmnf_step(gains, 1, alpha, "residual", y, present, beacon)
    for i in range(2):
        xt = F[0] @ alpha[i] + f[0]
        dx, dy, dz = beacon[0] - xt
        r = y[i, 0] - [dy / dx, dz / math.hypot(dx, dy)]
        rc = np.clip(r, lo[0], hi[0])
        np.testing.assert_allclose(x_t[i], xt, rtol=1e-14)
        np.testing.assert_allclose(x_h[i], xt + H[0] @ rc + h[0], rtol=1e-14)
    assert np.abs(bearings(x_t, beacon)[0][0, 0, 0] - y[0, 0, 0]) > hi[0, 0]  # clipping acted


def test_gains_with_bounds_round_trip_as_plain_npz(tmp_path):
    rng = np.random.default_rng(1)
    lo = rng.normal(size=(4, 8)) - 5
    lo[0, 3] = -np.inf
    hi = -lo
    g = CmnfGains(
        F=rng.normal(size=(4, 3, 3)),
        f=rng.normal(size=(4, 3)),
        H=rng.normal(size=(4, 3, 8)),
        h=rng.normal(size=(4, 3)),
        p_tilde=rng.normal(size=(4, 3, 3)),
        p_hat=rng.normal(size=(4, 3, 3)),
        info={"clip_sigmas": 6.0},
        beta_lo=lo,
        beta_hi=hi,
    )
    back = CmnfGains.load(g.save(tmp_path / "g.npz"))
    assert np.array_equal(back.beta_lo, lo) and np.array_equal(back.beta_hi, hi)
    with np.load(tmp_path / "g.npz", allow_pickle=False) as z:
        fields = {k: z[k] for k in z.files if k != "beta_hi"}
    np.savez(tmp_path / "half.npz", **fields)
    with pytest.raises(NavInputError, match="beta_lo and beta_hi come together"):
        CmnfGains.load(tmp_path / "half.npz")


def test_training_on_no_more_paths_than_a_gain_row_has_unknowns_is_refused():
    """Four beacons: beta has 8 features, H_k's row 8 unknowns and h_k one; the covariance of
    beta from n paths has rank at most n - 1, so 9 paths could only interpolate."""
    path, noise, control, pred = _setting(3.0, 1.0, NEAR)
    with pytest.raises(NavInputError, match=r"9 CMNF training paths for 4 beacons.*more than 9"):
        _train(path, noise, control, pred, NEAR, 9, 0)
    gains, _ = _train(path, noise, control, pred, NEAR, 10, 0)
    assert np.isfinite(gains.H).all()
    with pytest.raises(NavInputError, match="clip_sigmas = 0"):
        _train(path, noise, control, pred, NEAR, 50, 0, clip_sigmas=0)
