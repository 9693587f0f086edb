"""Seed 004's seabed dead reckoning (nav.seabed) against seabeds whose ranges are worked out here:
planes and a three-facet valley intersected analytically, a harmonic surface for the slope fit,
finite differences for eq. 10 and Monte Carlo for the stated covariance."""

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.seabed import BeamGeometry, SlopeBasis, fit_slopes, seabed_track, shift_estimate

GEO = BeamGeometry.seed004()


def _e(gamma, theta):
    """Eq. 8's unit vector, written out here."""
    return np.array([np.cos(gamma) * np.cos(theta), np.cos(gamma) * np.sin(theta), np.sin(gamma)])


class Valley:
    """Seabed z = max_f (a_f x + b_f y + c_f): convex, so a downward ray crosses it once, at the
    nearest facet plane; psi = z - h has the gradient (-a_f, -b_f, 1) on facet f."""

    def __init__(self, planes):
        self.p = np.asarray(planes, dtype=float)  # (F, 3): a, b, c

    def cast(self, origin, dirs):
        """origin (3,), dirs (..., 3) -> ranges (...), facet index (...)."""
        a, b, c = self.p.T
        num = a * origin[0] + b * origin[1] + c - origin[2]  # plane - z at L = 0 (< 0: above)
        den = dirs[..., 2, None] - a * dirs[..., 0, None] - b * dirs[..., 1, None]
        L = num / den  # z_ray - plane = 0
        L = np.where(L > 0, L, np.inf)
        f = np.argmin(L, axis=-1)
        return np.take_along_axis(L, f[..., None], -1)[..., 0], f

    def grad(self, facet):
        a, b = self.p[facet][..., 0], self.p[facet][..., 1]
        return np.stack([-a, -b, np.ones_like(a)], axis=-1)


def _facet(a, b, x=12.0, y=4.0, z=-30.0):
    """A plane of slopes (a, b) through (x, y, z): the three meet under the beams' footprint."""
    return (a, b, z - a * x - b * y)


VALLEY = Valley([_facet(0.3, 0.1), _facet(-0.25, 0.05), _facet(0.02, -0.35)])


def _valley_images(x0, x1, att0, att1, geo=GEO):
    L0, f0 = VALLEY.cast(x0, geo.directions(att0))
    L1, f1 = VALLEY.cast(x1, geo.directions(att1))
    return L0, f0, L1, f1


def test_beams_follow_eq8_and_point_down():
    att = np.array([0.07, -0.4])
    e = GEO.directions(att)
    assert e.shape == (8, 8, 3)
    for i, j in [(0, 0), (3, 5), (7, 7)]:
        want = _e(att[0] + np.radians(-42 - 40 * i / 7), att[1] + np.radians(-10 + 40 * j / 7))
        np.testing.assert_allclose(e[i, j], want, atol=1e-15)
    assert np.all(GEO.directions(np.zeros(2))[..., 2] < -0.6)  # 42..82 deg down, z up


def test_eq10_with_the_corrected_sign_is_the_first_order_change():
    att = np.array([[0.05, 0.9]])
    for d in (1e-3, 2e-3):
        nxt = att + np.array([[0.7 * d, -d]])
        exact = GEO.directions(nxt) - GEO.directions(att)
        lin = GEO.direction_change(att, nxt)
        assert np.abs(lin - exact).max() < 3 * d**2  # second-order remainder
        np.testing.assert_allclose(GEO.direction_change(att, nxt, exact=True), exact, atol=1e-15)
    # the printed sign of the d(theta) term of de^Y would be first-order wrong
    assert np.abs(lin[..., 1] - exact[..., 1]).max() < 1e-5


def test_plane_seabed_noise_free_vertical_motion_is_exact():
    """A flat bed at z = -30 observes only z: a vertical shift comes out exact."""
    x0, x1 = np.array([1.0, 2.0, -10.0]), np.array([1.0, 2.0, -11.7])
    att = np.array([0.02, 0.3])
    e = GEO.directions(att)
    L0, L1 = (-30.0 - x0[2]) / e[..., 2], (-30.0 - x1[2]) / e[..., 2]
    est = shift_estimate(L0[None], L1[None], GEO, att[None], basis=SlopeBasis("plane"))
    assert est.ok[0] and est.rank[0] == 1
    np.testing.assert_allclose(est.shift_m[0], x1 - x0, atol=1e-9)


def test_tilted_plane_gives_the_normal_component_exactly_and_flags_the_rest():
    n = np.array([0.2, -0.1, 1.0])  # psi = n.x + 30
    x0, x1 = np.array([0.0, 0.0, -10.0]), np.array([1.9, 0.6, -10.3])
    att = np.array([-0.03, 0.5])
    e = GEO.directions(att)
    L0 = -(n @ x0 + 30.0) / (e @ n)
    L1 = -(n @ x1 + 30.0) / (e @ n)
    est = shift_estimate(
        L0[None], L1[None], GEO, att[None], basis=SlopeBasis("plane"), fallback_var_m2=1e6
    )
    u = n / np.linalg.norm(n)
    assert est.rank[0] == 1
    np.testing.assert_allclose(est.shift_m[0] @ u, (x1 - x0) @ u, atol=1e-9)
    np.testing.assert_allclose(np.cross(est.shift_m[0], u), 0.0, atol=1e-9)  # minimum norm
    # unobserved directions are stated as such; the normal is not
    # along the normal: the range-noise floor, 2 sigma^2 mean((g.e)^2) / (64 |g|^2) ~ 2e-4 m^2
    ge = GEO.directions(att) @ n
    floor = 2 * 0.1**2 * np.mean(ge**2) / (64 * n @ n)
    np.testing.assert_allclose(u @ est.covariance_m2[0] @ u, floor, rtol=1e-6)
    t = np.cross(u, [0.0, 0.0, 1.0])
    t /= np.linalg.norm(t)
    assert t @ est.covariance_m2[0] @ t > 0.99e6


def test_three_facet_valley_with_true_slopes_gives_the_whole_shift_exactly():
    x0, x1 = np.array([0.5, -0.4, -10.0]), np.array([2.4, 0.3, -10.2])
    att = np.array([0.01, 0.35])
    L0, f0, L1, f1 = _valley_images(x0, x1, att, att)
    same = f0 == f1  # both feet on the same facet: eq. 11 holds exactly
    assert same.sum() > 40 and len(np.unique(f0[same])) == 3
    est = shift_estimate(
        L0[None],
        np.where(same, L1, 1e9)[None],  # a garbage range where there is no echo is ignored
        GEO,
        att[None],
        next_echo=same[None],
        slopes=VALLEY.grad(f0)[None],
    )
    assert est.ok[0] and est.rank[0] == 3 and est.beams[0] == same.sum()
    np.testing.assert_allclose(est.shift_m[0], x1 - x0, atol=1e-9)
    assert est.residual_rms[0] < 1e-9


def test_turning_reading_misses_only_the_dl_de_term():
    """Eq. 11 drops the product dL de of the exact change L1 e1 - L0 e0 = L0 de + e0 dL + dL de.
    With the exact de and the true slopes on the valley, the shift's error is the least-squares
    image of that term, worked out here."""
    x0, x1 = np.array([0.5, -0.4, -10.0]), np.array([1.6, 0.2, -10.1])
    att0, att1 = np.array([0.01, 0.35]), np.array([0.016, 0.37])
    L0, f0, L1, f1 = _valley_images(x0, x1, att0, att1)
    same = f0 == f1
    g = VALLEY.grad(f0)[same]
    est = shift_estimate(
        L0[None],
        L1[None],
        GEO,
        att0[None],
        att1[None],
        next_echo=same[None],
        reading="turning",
        delta_e="exact",
        slopes=VALLEY.grad(f0)[None],
    )
    de = (GEO.directions(att1) - GEO.directions(att0))[same]
    dropped = np.einsum("mc,mc->m", g, (L1 - L0)[same][:, None] * de)
    want = x1 - x0 + np.linalg.lstsq(g, dropped, rcond=None)[0]
    np.testing.assert_allclose(est.shift_m[0], want, atol=1e-9)
    assert np.linalg.norm(est.shift_m[0] - (x1 - x0)) > 1e-3  # the term is not nothing


def test_turning_in_place_is_second_order_in_the_turn():
    """With no translation dL is itself of the order of the turn, so eq. 10 (linear de) and the
    dropped dL de term both give an error quadratic in the turn."""
    x0 = np.array([0.5, -0.4, -10.0])
    att0 = np.array([0.01, 0.35])
    for kind in ("linear", "exact"):
        errs = []
        for d in (0.01, 0.02):
            att1 = att0 + np.array([0.3 * d, d])
            L0, f0, L1, f1 = _valley_images(x0, x0, att0, att1)
            same = f0 == f1
            est = shift_estimate(
                L0[None],
                L1[None],
                GEO,
                att0[None],
                att1[None],
                next_echo=same[None],
                reading="turning",
                delta_e=kind,
                slopes=VALLEY.grad(f0)[None],
            )
            errs.append(np.linalg.norm(est.shift_m[0]))
        assert 0 < errs[0] < 0.05 and 3.0 < errs[1] / errs[0] < 5.0, (kind, errs)
    # one attitude with beams that did turn is first-order wrong
    est = shift_estimate(
        L0[None], L1[None], GEO, att0[None], next_echo=same[None], slopes=VALLEY.grad(f0)[None]
    )
    assert np.linalg.norm(est.shift_m[0]) > 5 * errs[1]


def test_appendix_a_fit_recovers_a_harmonic_seabed_slope():
    rng = np.random.default_rng(3)
    a, b, c, d = rng.random((4, 2))
    w = 2 * np.pi * np.arange(1, 3) / 20.0
    xy = rng.uniform(-15, 15, (64, 2))
    x, y = xy[:, 0], xy[:, 1]
    z = -30.0 - (
        (a * np.sin(w * x[:, None]) + b * np.cos(w * x[:, None])).sum(1)
        + (c * np.sin(w * y[:, None]) + d * np.cos(w * y[:, None])).sum(1)
    )
    gx = (w * (a * np.cos(w * x[:, None]) - b * np.sin(w * x[:, None]))).sum(1)
    gy = (w * (c * np.cos(w * y[:, None]) - d * np.sin(w * y[:, None]))).sum(1)
    pts = np.column_stack([x, y, z])[None]
    valid = np.ones((1, 64), bool)
    valid[0, ::7] = False  # masked points do not enter the fit
    pts_bad = pts.copy()
    pts_bad[0, ::7, 2] = 1e6
    grad, ok = fit_slopes(pts_bad, valid, SlopeBasis.seed004())
    assert ok[0]
    np.testing.assert_allclose(
        grad[0, valid[0]], np.column_stack([gx, gy, np.ones(64)])[valid[0]], atol=1e-8
    )
    assert np.all(grad[0, ~valid[0]] == 0)
    # a shift of every point (an error of the estimated position) leaves the slopes unchanged
    moved = pts_bad + np.array([3.0, -7.0, 0.0])
    g2, _ = fit_slopes(moved, valid, SlopeBasis.seed004())
    np.testing.assert_allclose(g2[0, valid[0]], grad[0, valid[0]], atol=1e-8)


def test_too_few_echoes_give_no_shift_and_no_nan():
    L = np.full((2, 8, 8), 20.0)
    echo = np.zeros((2, 8, 8), bool)
    echo[1, 0, :2] = True  # two beams: not enough
    est = shift_estimate(
        np.where(echo, L, np.nan), L, GEO, np.zeros((2, 2)), echo=echo, fallback_var_m2=1e4
    )
    assert not est.ok.any()
    assert np.all(est.shift_m == 0) and np.all(np.isfinite(est.covariance_m2))
    np.testing.assert_allclose(est.covariance_m2, np.broadcast_to(1e4 * np.eye(3), (2, 3, 3)))
    cmd = np.array([[2.0, 0.1, 0.0], [1.9, -0.3, 0.05]])
    est = shift_estimate(L, L, GEO, np.zeros((2, 2)), echo=echo, commanded_shift_m=cmd)
    assert not est.ok.any() and np.array_equal(est.shift_m, cmd)


def test_bad_input_is_refused_in_words():
    L = np.full((1, 8, 8), 20.0)
    with pytest.raises(NavInputError, match="ranges_m: shape"):
        shift_estimate(L[:, :7], L, GEO, np.zeros((1, 2)))
    with pytest.raises(NavInputError, match="next_attitude_rad"):
        shift_estimate(L, L, GEO, np.zeros((1, 2)), reading="turning")
    with pytest.raises(NavInputError, match="reading"):
        shift_estimate(L, L, GEO, np.zeros((1, 2)), reading="sideways")
    with pytest.raises(NavInputError, match="non-finite"):
        shift_estimate(np.full((1, 8, 8), np.nan), L, GEO, np.zeros((1, 2)))


def test_stated_covariance_matches_monte_carlo_on_the_valley():
    """Range noise 0.1 m on both images, true slopes (a linear problem): the range-noise
    covariance is the empirical one; the residual one agrees on average."""
    x0, x1 = np.array([0.5, -0.4, -10.0]), np.array([2.4, 0.3, -10.2])
    att = np.array([0.01, 0.35])
    L0, f0, L1, f1 = _valley_images(x0, x1, att, att)
    same = f0 == f1
    n, sig = 4000, 0.1
    rng = np.random.default_rng(5)
    est = {}
    for kind in ("range_noise", "residual"):
        est[kind] = shift_estimate(
            L0 + sig * rng.standard_normal((n, 8, 8)),
            L1 + sig * rng.standard_normal((n, 8, 8)),
            GEO,
            np.broadcast_to(att, (n, 2)),
            next_echo=np.broadcast_to(same, (n, 8, 8)),
            slopes=np.broadcast_to(VALLEY.grad(f0), (n, 8, 8, 3)),
            covariance=kind,
            sigma_range_m=sig,
        )
    err = est["range_noise"].shift_m - (x1 - x0)
    emp = err.T @ err / n
    stated = est["range_noise"].covariance_m2[0]
    # 4000 samples: the trace is within ~2-3 % of the truth
    assert abs(np.trace(emp) / np.trace(stated) - 1) < 0.08
    np.testing.assert_allclose(np.diag(emp), np.diag(stated), rtol=0.1)
    assert abs(np.abs(err.mean(0)).max()) < 4 * np.sqrt(np.diag(stated).max() / n)
    ratio = np.trace(est["residual"].covariance_m2.mean(0)) / np.trace(stated)
    assert 0.8 < ratio < 1.25


def test_seabed_track_is_eq16_and_exact_on_the_valley():
    xs = np.array([[0.5, -0.4, -10.0], [1.6, 0.1, -10.1], [2.8, 0.5, -10.0], [3.9, 1.2, -10.2]])
    att = np.broadcast_to([0.0, 0.4], (1, 4, 2))
    L0, L1, ok, g = [], [], [], []
    for k in range(3):
        a, f0, b, f1 = _valley_images(xs[k], xs[k + 1], att[0, k], att[0, k])
        L0.append(a)
        L1.append(b)
        ok.append(f0 == f1)
        g.append(VALLEY.grad(f0))
    L0, L1, ok, g = (np.array(v)[None] for v in (L0, L1, ok, g))
    track, oks = seabed_track(xs[None, 0], L0, L1, GEO, att, next_echo=ok, slopes=g)
    assert oks.all()
    np.testing.assert_allclose(track[0], xs, atol=1e-9)
    # with Appendix A's slopes: the running sum of shift_estimate's shifts (eq. 16)
    basis = SlopeBasis("quadratic")
    track, oks = seabed_track(xs[None, 0], L0, L1, GEO, att, next_echo=ok, basis=basis)
    pos = xs[0].copy()
    for k in range(3):
        s = shift_estimate(
            L0[:, k],
            L1[:, k],
            GEO,
            att[:, k],
            next_echo=ok[:, k],
            basis=basis,
            position_m=pos[None],
        )
        pos = pos + s.shift_m[0]
        np.testing.assert_allclose(track[0, k + 1], pos, atol=1e-12)


def test_slope_fit_least_squares_is_the_pseudo_inverse_solution_also_when_rank_deficient():
    # Appendix A's fit goes through the Gram matrix where it is well conditioned and through the
    # SVD elsewhere: both must give numpy's pinv solution (minimum norm when rank-deficient)
    from nav.seabed.fit import _least_squares

    rng = np.random.default_rng(5)
    a = rng.normal(size=(3, 40, 6))
    a[1, :, 5] = a[1, :, 2]  # two equal columns: rank 5
    a[2, :, 4] = 1e-7 * a[2, :, 0] + a[2, :, 1]  # nearly dependent: condition ~1e7
    a[:, 30:] = 0.0  # masked points
    rhs = rng.normal(size=(3, 40, 1))
    got = _least_squares(a.transpose(0, 2, 1), rhs)
    want = np.linalg.pinv(a, rcond=1e-10) @ rhs
    np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-9)
