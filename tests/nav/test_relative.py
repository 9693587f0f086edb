"""Seed 003's positioning relative to the leader, against independent truth: the paper's equations
worked out here in scalar form, brute-force minimisation over the circle, finite differences, a
closed-form HDOP derived here, and filterpy's EKF."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter
from scipy.optimize import minimize_scalar

from nav.errors import NavInputError
from nav.relative import (
    FollowerNavigator,
    GaOptions,
    LeaderRanges,
    RangeEkfOptions,
    RangeMeasurement,
    consistency_sums,
    design_rows,
    distance_sums,
    distances,
    dr_increment_covariance,
    dr_step,
    dr_track,
    ekf_track,
    ga_fix,
    ga_track,
    hdop,
    hdop_after_step,
    longest_gaps,
    pooled_stats,
    range_update,
)


def test_dr_step_is_eq_1_in_the_navigation_convention():
    p = dr_step(np.array([[1.0, 2.0]]), np.array([np.deg2rad(30.0)]), np.array([2.0]), 0.5)
    np.testing.assert_allclose(p, [[1.0 + 0.5, 2.0 + math.sqrt(3) / 2]], atol=1e-15)


@pytest.mark.parametrize("course_deg", [0.0, 37.0, 90.0, 200.0, 315.0])
def test_dr_increment_covariance_is_the_first_order_propagation_of_eq_1(course_deg):
    c, s, dt, sc, ss = np.deg2rad(course_deg), 1.3, 0.1, np.deg2rad(2.0), 0.3

    def step(cs):
        return dr_step(np.zeros((1, 2)), np.array([cs[0]]), np.array([cs[1]]), dt)[0]

    h = 1e-6
    J = np.column_stack(
        [
            (step([c + h, s]) - step([c - h, s])) / (2 * h),
            (step([c, s + h]) - step([c, s - h])) / (2 * h),
        ]
    )
    expected = J @ np.diag([sc**2, ss**2]) @ J.T
    got = dr_increment_covariance(np.array([c]), np.array([s]), dt, sc, ss)[0]
    np.testing.assert_allclose(got, expected, rtol=1e-7, atol=1e-14)


# --- the paper's adjustment written out here, scalar, from eq. 2-4 ---------------------------


def paper_criterion(phi, method, start, end, leader, d_h, cov, sigma_dh, jacobian):
    """V^T P V of eq. 3 (GA1) or eq. 4 (GA2) at the candidate of bearing phi, scalar."""
    xf0 = leader[0] + d_h * math.sin(phi)
    yf0 = leader[1] + d_h * math.cos(phi)
    b_r = math.atan2(start[0] - end[0], start[1] - end[1])
    d_r = math.hypot(start[0] - end[0], start[1] - end[1])
    dx, dy = start[0] - xf0, start[1] - yf0
    b_f0 = math.atan2(dx, dy)
    d_f0 = math.hypot(dx, dy)
    lx, ly = leader[0] - xf0, leader[1] - yf0
    d_l0 = math.hypot(lx, ly)
    l_b = (b_f0 - b_r + math.pi) % (2 * math.pi) - math.pi
    L = [l_b, d_f0 - d_r, d_l0 - d_h]
    m = math.sqrt(max(cov[0][0] + cov[1][1], 1e-6))
    w = [1.0 / math.atan(m / d_r) ** 2, 1.0 / m**2, 1.0 / sigma_dh**2]
    if method == "ga2":
        V = L
    else:
        if jacobian == "printed":  # eq. 2 as printed
            a = [
                [dx / d_f0**2, -dy / d_f0**2],
                [-dy / d_f0, -dx / d_f0],
                [-ly / d_l0, -lx / d_l0],
            ]
        else:  # derivatives of B_F0, D_F0, D_L0 with respect to (x_F0, y_F0), x east
            a = [
                [-dy / d_f0**2, dx / d_f0**2],
                [-dx / d_f0, -dy / d_f0],
                [-lx / d_l0, -ly / d_l0],
            ]
        d = [xf0 - end[0], yf0 - end[1]]
        V = [a[i][0] * d[0] + a[i][1] * d[1] + L[i] for i in range(3)]
    return sum(wi * vi * vi for wi, vi in zip(w, V, strict=True))


def brute_force(method, start, end, leader, d_h, cov, sigma_dh, jacobian):
    """Global minimum over the circle: a fine grid, then bounded Brent around each of the best
    grid points (scipy), keeping the lowest."""
    grid = np.linspace(0.0, 2 * math.pi, 6001)
    f = [paper_criterion(p, method, start, end, leader, d_h, cov, sigma_dh, jacobian) for p in grid]
    best = None
    for i in np.argsort(f)[:5]:
        r = minimize_scalar(
            paper_criterion,
            bounds=(grid[i] - 2e-3, grid[i] + 2e-3),
            args=(method, start, end, leader, d_h, cov, sigma_dh, jacobian),
            method="bounded",
            options={"xatol": 1e-13},
        )
        if best is None or r.fun < best.fun:
            best = r
    phi = best.x
    return np.array([leader[0] + d_h * math.sin(phi), leader[1] + d_h * math.cos(phi)]), best.fun


def _cases(n=20, seed=3):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        leader = rng.uniform(-50, 50, 2)
        bearing = rng.uniform(0, 2 * math.pi)
        truth = leader + 10.0 * np.array([math.sin(bearing), math.cos(bearing)])
        course = rng.uniform(0, 2 * math.pi)
        start = truth - 5.0 * np.array([math.sin(course), math.cos(course)]) + rng.normal(0, 1.0, 2)
        end = truth + rng.normal(0, 2.0, 2)
        d_h = 10.0 + rng.uniform(-0.1, 0.1)
        q = rng.uniform(0.2, 3.0)
        cov = np.array([[q, 0.1 * q], [0.1 * q, 0.7 * q]])
        out.append((start, end, leader, d_h, cov))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("method", ["ga1", "ga2"])
@pytest.mark.parametrize("jacobian", ["printed", "true"])
def test_ga_equals_a_brute_force_minimisation_of_its_criterion_over_the_circle(method, jacobian):
    cases = _cases()
    start, end, leader, d_h, cov = (np.array(v) for v in zip(*cases, strict=True))
    opt = GaOptions(jacobian=jacobian)
    fix = ga_fix(method, start, end, leader, d_h, cov, opt)
    assert fix.valid.all()
    for i, (s, e, ld, r, c) in enumerate(cases):
        pos, fun = brute_force(method, s, e, ld, r, c.tolist(), 0.1, jacobian)
        np.testing.assert_allclose(fix.position[i], pos, atol=1e-6)
        assert fix.criterion[i] == pytest.approx(fun, rel=1e-6, abs=1e-12)
        assert math.hypot(*(fix.position[i] - ld)) == pytest.approx(r, abs=1e-9)


def test_the_true_adjustment_jacobian_agrees_with_finite_differences():
    rng = np.random.default_rng(5)
    start, cand, leader = rng.uniform(-20, 20, (3, 7, 2))

    def f(c):
        d = start - c
        lv = leader - c
        return np.stack(
            [
                np.arctan2(d[:, 0], d[:, 1]),
                np.hypot(d[:, 0], d[:, 1]),
                np.hypot(lv[:, 0], lv[:, 1]),
            ],
            axis=-1,
        )

    h = 1e-6
    fd = np.empty((7, 3, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        fd[:, :, j] = (f(cand + e) - f(cand - e)) / (2 * h)
    np.testing.assert_allclose(design_rows(start, cand, leader, "true"), fd, rtol=1e-6, atol=1e-9)
    # the printed rows are the same derivatives with the two columns swapped (geodetic axes)
    np.testing.assert_allclose(
        design_rows(start, cand, leader, "printed"), fd[:, :, ::-1], rtol=1e-6, atol=1e-9
    )


def _hdop_closed_form(relative_bearing_rad, d_r):
    """Derived by hand: with the DR segment along e_m (length d_r) and the leader direction u at
    relative bearing beta to the motion, A^T A = e_m e_m^T + e_p e_p^T / d_r^2 + u u^T; with
    a = 1/d_r^2, c = cos beta, s = sin beta its determinant is a(1 + c^2) + s^2 and its trace
    2 + a, so HDOP^2 = trace/det = (2 + a) / (a (1 + c^2) + s^2)."""
    a = 1.0 / d_r**2
    c, s = math.cos(relative_bearing_rad), math.sin(relative_bearing_rad)
    return math.sqrt((2 + a) / (a * (1 + c * c) + s * s))


@pytest.mark.parametrize("beta_deg", [90.0, -90.0, 0.0, 180.0, 30.0, 135.0])
def test_hdop_against_an_independently_derived_closed_form(beta_deg):
    # Figure 2 set-up: F moves on course 90 deg (east) for D_r = 10 m, then the leader is at
    # relative bearing beta from F's course, 10 m away.
    end = np.array([[0.0, 0.0]])
    start = np.array([[-10.0, 0.0]])
    course = math.pi / 2
    b = course + math.radians(beta_deg)
    leader = end + 10.0 * np.array([[math.sin(b), math.cos(b)]])
    got = hdop(start, end, leader)[0]
    if beta_deg in (0.0, 180.0):
        assert got == pytest.approx(math.sqrt(100.5), rel=1e-9)  # the notes: 10.0
    if abs(beta_deg) == 90.0:
        assert got == pytest.approx(math.sqrt(2.01 / 1.01), rel=1e-9)  # the notes: 1.41
    assert got == pytest.approx(_hdop_closed_form(math.radians(beta_deg), 10.0), rel=1e-9)


def test_noise_free_fix_returns_the_truth_for_every_reading():
    truth = np.array([[3.0, 10.0]])
    leader = np.array([[3.0, 0.0]])
    start = np.array([[-2.0, 10.0]])
    cov = np.diag([0.5, 0.5])[None]
    for method in ("ga1", "ga2"):
        for jac in ("printed", "true"):
            fix = ga_fix(
                method, start, truth, leader, np.array([10.0]), cov, GaOptions(jacobian=jac)
            )
            np.testing.assert_allclose(fix.position, truth, atol=1e-7)
            assert fix.criterion[0] == pytest.approx(0.0, abs=1e-12)


def test_ga2_weights_cancel_so_its_fix_ignores_the_dr_covariance_scale():
    # the reading notes: as printed, GA2's bearing and distance weights are equivalent. Exactly,
    # w_B / w_D = M^2 / atan(M / D_r)^2 -> D_r^2 as M -> 0: the fix does not depend on the scale
    # of the DR covariance to O((M / D_r)^2).
    (s, e, ld, r, c), *_ = _cases(1, seed=11)
    c = c / np.trace(c) * 0.01**2  # M = 1 cm over a D_r of metres
    a = ga_fix("ga2", s[None], e[None], ld[None], np.array([r]), c[None])
    b = ga_fix("ga2", s[None], e[None], ld[None], np.array([r]), 9.0 * c[None])
    np.testing.assert_allclose(a.position, b.position, atol=1e-6)
    # GA1 does depend on it: its range row's weight is fixed while the others scale
    a1 = ga_fix("ga1", s[None], e[None], ld[None], np.array([r]), 100 * c[None])
    b1 = ga_fix("ga1", s[None], e[None], ld[None], np.array([r]), 900 * c[None])
    assert np.abs(a1.position - b1.position).max() > 1e-3


def test_unusable_ranges_make_no_fix_and_no_nan():
    start = np.zeros((4, 2))
    end = np.array([[0.0, 5.0]] * 4)
    leader = np.array([[10.0, 5.0], [10.0, 5.0], [np.nan, 5.0], [0.0, 5.0]])
    rng = np.array([0.0, np.nan, 10.0, 10.0])
    cov = np.broadcast_to(np.eye(2), (4, 2, 2))
    fix = ga_fix("ga1", start, end, leader, rng, cov, present=np.array([True, True, True, False]))
    assert not fix.valid.any()
    np.testing.assert_array_equal(fix.position, end)
    for v in (fix.position, fix.phi_rad, fix.criterion, fix.hdop):
        assert np.isfinite(v).all()


def test_no_displacement_since_the_last_fix_drops_the_bearing_row():
    # start == end: B_r is undefined; the fix is the candidate nearest in distance and stays finite
    p = np.array([[0.0, 10.5]])
    fix = ga_fix("ga2", p, p, np.zeros((1, 2)), np.array([10.0]), np.zeros((1, 2, 2)))
    assert fix.valid[0]
    assert np.isfinite(fix.position).all()
    np.testing.assert_allclose(np.hypot(*fix.position[0]), 10.0, atol=1e-9)


def test_follower_on_the_leaders_course_line_degrades_gracefully():
    # F astern of L on its course line: the geometry is the worst (HDOP ~10) but finite
    nav = FollowerNavigator("ga1", [0.0, -10.0], math.radians(2), 0.3)
    for _ in range(50):
        nav.advance(0.0, 1.0, 0.1)
    out = nav.fix([0.0, 5.0], 10.0)
    assert out.accepted and np.isfinite(out.position).all()
    assert 5.0 < out.hdop < 20.0


def test_range_update_equals_filterpy():
    rng = np.random.default_rng(8)
    x = rng.uniform(-5, 5, (6, 2))
    A = rng.normal(size=(6, 2, 2))
    P = A @ np.swapaxes(A, 1, 2) + 0.5 * np.eye(2)
    leader = rng.uniform(-20, 20, (6, 2))
    z = np.hypot(*(x - leader).T) + rng.normal(0, 0.3, 6)
    x2, P2, info = range_update(x, P, leader, z, 0.1)
    assert info.applied.all()
    for i in range(6):
        f = ExtendedKalmanFilter(dim_x=2, dim_z=1)
        f.x = x[i].copy()
        f.P = P[i].copy()
        f.R = np.array([[0.01]])

        def H(xx, ld=leader[i]):
            d = xx - ld
            return (d / np.hypot(*d))[None]

        def hx(xx, ld=leader[i]):
            return np.array([np.hypot(*(xx - ld))])

        f.update(np.array([z[i]]), H, hx)
        np.testing.assert_allclose(x2[i], f.x, atol=1e-12)
        np.testing.assert_allclose(P2[i], f.P, atol=1e-12)


def test_range_measurement_adds_the_leaders_covariance_along_the_line_of_sight():
    x = np.array([[0.0, 10.0]])
    m = RangeMeasurement(np.zeros((1, 2)), 0.1, np.array([[[4.0, 0.0], [0.0, 1.0]]]))
    assert m.R_at(x)[0, 0, 0] == pytest.approx(0.01 + 1.0)


def test_online_follower_matches_the_batched_adjustment_and_restarts():
    sc, ss = math.radians(2), 0.3
    nav = FollowerNavigator("ga1", [0.0, 0.0], sc, ss)
    cov = np.zeros((1, 2, 2))
    end = np.zeros((1, 2))
    for k in range(50):
        c, s = math.radians(45 + k * 0.1), 1.0 + 0.01 * k
        nav.advance(c, s, 0.1)
        end = dr_step(end, np.array([c]), np.array([s]), 0.1)
        cov = cov + dr_increment_covariance(np.array([c]), np.array([s]), 0.1, sc, ss)
    leader = np.array([[10.0, -2.0]])
    out = nav.fix(leader[0], 10.0)
    ref = ga_fix("ga1", np.zeros((1, 2)), end, leader, np.array([10.0]), cov)
    assert out.accepted
    np.testing.assert_allclose(out.position, ref.position[0], atol=1e-12)
    # with restart the next segment starts at the fix
    nav.advance(0.0, 1.0, 0.1)
    np.testing.assert_allclose(nav.position, ref.position[0] + [0.0, 0.1], atol=1e-12)
    np.testing.assert_allclose(nav.dr_position, end[0] + [0.0, 0.1], atol=1e-12)


def test_dr_method_ignores_ranges_and_zero_range_is_refused():
    nav = FollowerNavigator("dr", [0.0, 0.0], 0.03, 0.3)
    nav.advance(0.0, 1.0, 1.0)
    assert nav.fix([5.0, 0.0], 5.0).reason == "dr"
    g = FollowerNavigator("ga2", [0.0, 0.0], 0.03, 0.3)
    g.advance(0.0, 1.0, 1.0)
    out = g.fix([5.0, 0.0], 0.0)
    assert not out.accepted and out.reason == "range below minimum"
    assert out.position.tolist() == [0.0, 1.0]
    assert g.fix([5.0, 0.0], None).reason == "no range"


# --- the batched tracks and reductions (nav.relative.tracks, nav.relative.metrics) ------------


def _synthetic_runs(n=3, T=600, every=50, seed=5):
    """Hand-made runs: a follower turning slowly at ~1 m/s, the leader 10 m abeam (starboard),
    course and speed measured with noise and a bias, ranges every ``every`` ticks; run 1 misses
    its second range and gets a zero range at its fourth."""
    rng = np.random.default_rng(seed)
    dt = 0.1
    course = np.radians(30.0) + np.cumsum(np.full((n, T), np.radians(0.02)), axis=1)
    speed = 1.0 + 0.1 * np.sin(np.arange(T) * dt / 7.0) * np.ones((n, 1))
    truth = np.zeros((n, T + 1, 2))
    for k in range(T):
        truth[:, k + 1] = truth[:, k] + dt * speed[:, k, None] * np.stack(
            [np.sin(course[:, k]), np.cos(course[:, k])], axis=-1
        )
    c_meas = course + np.radians(1.0) + rng.normal(0, np.radians(1.0), (n, T))
    s_meas = speed * 1.05 + rng.normal(0, 0.05, (n, T))
    tick = np.arange(every, T + 1, every)
    c_at = course[:, tick - 1] + np.pi / 2
    leader = truth[:, tick] + 10.0 * np.stack([np.sin(c_at), np.cos(c_at)], axis=-1)
    rng_m = np.hypot(*(leader - truth[:, tick]).transpose(2, 0, 1)) + rng.normal(
        0, 0.1, (n, len(tick))
    )
    present = np.ones((n, len(tick)), dtype=bool)
    if len(tick) > 3:
        present[1, 1] = False
        rng_m[1, 3] = 0.0
    return dt, c_meas, s_meas, LeaderRanges(tick, rng_m, present, leader)


def _online(method, dt, c, s, ranges, i, restart=True, initial_cov=None, leader_cov=None):
    nav = FollowerNavigator(
        method,
        [0.0, 0.0],
        math.radians(2.0),
        0.3,
        GaOptions(restart=restart),
        initial_cov=initial_cov,
    )
    at = {int(t): j for j, t in enumerate(ranges.fix_tick)}
    out = [nav.position]
    for k in range(c.shape[1]):
        nav.advance(c[i, k], s[i, k], dt)
        j = at.get(k + 1)
        if j is not None:
            r = ranges.range_m[i, j] if ranges.present[i, j] else None
            nav.fix(ranges.leader_m[i, j], r, leader_cov)
        out.append(nav.position)
    return np.array(out)


def test_dr_track_is_eq_1_summed_with_eq_5_summed():
    dt, c, s, _ = _synthetic_runs(n=2, T=40)
    sc, ss = math.radians(2.0), 0.3
    tr = dr_track(c, s, np.array([1.0, -2.0]), dt, sc, ss)
    for i in range(2):  # written out with math's sine and cosine
        x, P = np.array([1.0, -2.0]), np.zeros((2, 2))
        for k in range(40):
            x = x + dt * s[i, k] * np.array([math.sin(c[i, k]), math.cos(c[i, k])])
            P = P + dr_increment_covariance(c[i, k : k + 1], s[i, k : k + 1], dt, sc, ss)[0]
            np.testing.assert_allclose(tr.position_m[i, k + 1], x, atol=1e-12)
            np.testing.assert_allclose(tr.cov_m2[i, k + 1], P, atol=1e-15)


@pytest.mark.slow
@pytest.mark.parametrize("restart", [True, False])
@pytest.mark.parametrize("method", ["ga1", "ga2"])
def test_ga_track_equals_the_online_follower_stepped_tick_by_tick(method, restart):
    dt, c, s, ranges = _synthetic_runs()
    dr = dr_track(c, s, np.zeros(2), dt, math.radians(2.0), 0.3)
    got = ga_track(method, dr, ranges, GaOptions(restart=restart))
    assert got.accepted.sum() == got.accepted.size - 2  # the missing and the zero range
    assert got.refused_short[1, 3] and not got.accepted[1, 1] and not got.accepted[1, 3]
    for i in range(3):
        online = _online(method, dt, c, s, ranges, i, restart)
        np.testing.assert_allclose(got.position_m[i], online, rtol=0, atol=1e-9)
    # the fixes moved the estimate off the DR track (the comparison above is not DR against DR)
    assert np.abs(got.position_m - dr.position_m).max() > 0.1


def test_ga_track_refuses_fixes_above_max_hdop():
    dt, c, s, ranges = _synthetic_runs()
    dr = dr_track(c, s, np.zeros(2), dt, math.radians(2.0), 0.3)
    free = ga_track("ga2", dr, ranges, GaOptions())
    h = free.hdop[free.accepted]
    limit = float(np.median(h))
    cut = ga_track("ga2", dr, ranges, GaOptions(), max_hdop=limit)
    assert cut.refused_hdop.any() and (cut.hdop[cut.accepted] <= limit).all()
    none = ga_track("ga2", dr, ranges, GaOptions(), max_hdop=0.99 * float(h.min()))
    assert not none.accepted.any()
    np.testing.assert_array_equal(none.position_m, dr.position_m)


def test_ekf_track_equals_the_online_follower_and_uses_the_leaders_covariance():
    dt, c, s, ranges = _synthetic_runs()
    dr = dr_track(c, s, np.zeros(2), dt, math.radians(2.0), 0.3)
    opt = RangeEkfOptions(sigma_range_m=0.1, initial_sigma_m=0.5, leader_sigma_m=0.4)
    got = ekf_track(dr, ranges, opt)
    for i in range(3):
        online = _online(
            "ekf", dt, c, s, ranges, i, initial_cov=np.eye(2) * 0.25, leader_cov=np.eye(2) * 0.16
        )
        np.testing.assert_allclose(got.position_m[i], online, rtol=0, atol=1e-9)
    assert got.refused_short[1, 3] and not got.accepted[1, 1]
    exact = ekf_track(dr, ranges, RangeEkfOptions(sigma_range_m=0.1, initial_sigma_m=0.5))
    ok = got.accepted
    assert (
        np.trace(got.fix_cov_m2, axis1=-2, axis2=-1)[ok]
        > np.trace(exact.fix_cov_m2, axis1=-2, axis2=-1)[ok]
    ).all()


def test_bad_track_inputs_are_refused_with_one_clear_error():
    dt, c, s, ranges = _synthetic_runs(n=2, T=100)
    dr = dr_track(c, s, np.zeros(2), dt, 0.03, 0.3)
    with pytest.raises(NavInputError, match="leader_m"):
        LeaderRanges(ranges.fix_tick, ranges.range_m, ranges.present, ranges.leader_m[:, :, :1])
    late = LeaderRanges(ranges.fix_tick + 60, ranges.range_m, ranges.present, ranges.leader_m)
    with pytest.raises(NavInputError, match="fix_tick"):
        ga_track("ga1", dr, late, GaOptions())
    with pytest.raises(NavInputError, match="leader_sigma_m"):
        RangeEkfOptions(leader_sigma_m=-1.0)
    with pytest.raises(NavInputError, match="sigma_range_m"):
        RangeEkfOptions(sigma_range_m=0.0)


def test_pooled_statistics_of_the_distance_sums_are_those_of_every_sample():
    rng = np.random.default_rng(2)
    d = rng.gamma(2.0, 3.0, (7, 51))
    sums = np.concatenate([distance_sums(d[:3]), distance_sums(d[3:])])  # two blocks
    mx, mean, std = pooled_stats(sums)
    every = d[:, 1:].ravel()  # sample 0 (on the reference) is left out
    assert mx == every.max()
    assert mean == pytest.approx(every.mean(), rel=1e-12)
    assert std == pytest.approx(every.std(), rel=1e-9)
    assert pooled_stats(np.zeros((2, 4))) is None
    est = rng.normal(0, 1, (2, 5, 2))
    np.testing.assert_allclose(
        distances(est, np.zeros((5, 2))), np.sqrt((est**2).sum(-1)), atol=1e-15
    )


def test_consistency_sums_count_only_accepted_fixes_with_a_usable_covariance():
    rng = np.random.default_rng(4)
    e = rng.normal(0, 1, (2, 4, 2))
    B = rng.normal(0, 1, (2, 4, 2, 2))
    C = B @ np.swapaxes(B, -1, -2) + 0.1 * np.eye(2)
    C[0, 1] = np.zeros((2, 2))  # singular
    C[1, 2, 0, 0] = np.inf
    acc = np.ones((2, 4), dtype=bool)
    acc[1, 3] = False
    got = consistency_sums(e, C, acc)
    for i in range(2):
        use = [k for k in range(4) if acc[i, k] and np.isfinite(C[i, k]).all()]
        use = [k for k in use if np.linalg.det(C[i, k]) > 0]
        nees = sum(e[i, k] @ np.linalg.inv(C[i, k]) @ e[i, k] for k in use)
        tr = sum(np.trace(C[i, k]) for k in use)
        e2 = sum(e[i, k] @ e[i, k] for k in use)
        np.testing.assert_allclose(got[i], [len(use), nees, tr, e2], rtol=1e-12)


def test_longest_gaps_between_accepted_fixes():
    t = np.array([5.0, 10.0, 15.0, 20.0])
    acc = np.array([[1, 1, 1, 1], [0, 0, 0, 0], [1, 0, 0, 1], [0, 1, 0, 0]], dtype=bool)
    np.testing.assert_array_equal(longest_gaps(t, acc, 22.0), [5.0, 22.0, 15.0, 12.0])


@pytest.mark.parametrize("beta_deg", [90.0, 0.0, 30.0, 135.0])
def test_hdop_after_a_step_is_the_closed_form(beta_deg):
    course = math.radians(70.0)
    b = course + math.radians(beta_deg)
    leader = np.zeros((1, 2))
    position = -10.0 * np.array([[math.sin(b), math.cos(b)]])  # the leader 10 m at bearing b
    got = hdop_after_step(position, leader, course, 10.0)[0]
    assert got == pytest.approx(_hdop_closed_form(math.radians(beta_deg), 10.0), rel=1e-9)
