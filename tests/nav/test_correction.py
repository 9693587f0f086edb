"""Seed 001's correction procedures against forward models written out here (acceptance 1 and 5).

Expected values come from the model ``dS_j / T_j = vs u(alpha_j + beta) + Vc`` evaluated in this
file with explicit sines and cosines, never from the code under test.
"""

import itertools
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from nav import surfacing as corr
from nav.angles import course_of, wrap_pi
from nav.errors import NavInputError

TOL = 1e-9


def unit(c):
    """Course unit vector, written out: x east = sin, y north = cos."""
    c = np.asarray(c, dtype=float)
    return np.stack([np.sin(c), np.cos(c)], axis=-1)


def forward(courses_rad, vs, beta, current, durations):
    """Position errors S_GPS - S_DR of two legs under the model of eq. 5-10."""
    vel = vs[:, None, None] * unit(courses_rad + beta[:, None]) + current[:, None, :]
    return vel * durations[..., None]


def grid_truth(course_pairs_deg):
    """Every combination of course pair, vs, beta and current on the test grid."""
    vss = [-0.3, -0.1, 0.1, 0.3]
    betas = [-60.0, -20.0, 0.0, 5.0, 20.0, 60.0]
    currents = [(0.0, 0.0)] + [(s, d) for s in (0.1, 0.5) for d in (0.0, 20.0, 90.0, 200.0)]
    rows = list(itertools.product(course_pairs_deg, vss, betas, currents))
    courses = np.radians([r[0] for r in rows])
    vs = np.array([r[1] for r in rows])
    beta = np.radians([r[2] for r in rows])
    cur = np.array([r[3][0] * unit(math.radians(r[3][1])) for r in rows])
    durations = np.tile([80.0, 125.0], (len(rows), 1))
    return courses, vs, beta, cur, durations


def assert_recovers(est, vs, beta, cur):
    assert np.all(est.valid)
    assert np.max(np.abs(est.vs_m_s - vs)) < TOL
    assert np.max(np.abs(wrap_pi(est.beta_rad - beta))) < TOL
    assert np.max(np.abs(est.current_world_m_s - cur)) < TOL


# --------------------------------------------------------------------------------------------
# conventions


def test_eq34_sign_rule():
    course = math.radians(45)
    assert corr.vs_sign(unit(math.radians(45 + 80)), course) == 1.0
    assert corr.vs_sign(unit(math.radians(45 + 100)), course) == -1.0
    assert corr.vs_sign(unit(math.radians(45 - 89)), course) == 1.0
    assert corr.vs_sign(unit(math.radians(45 + 180)), course) == -1.0
    assert corr.vs_sign(np.zeros(2), course) == 1.0


def test_current_response_symmetries_and_validation():
    r = corr.CurrentResponse((1.0, 0.15, 0.1, 0.05))
    g = np.linspace(0, math.pi, 37)
    # rho_s: port-starboard symmetric (10 and 350 deg), not bow-stern
    assert np.allclose(r.rho_s(g), r.rho_s(-g)) and np.allclose(r.rho_s(g), r.rho_s(2 * np.pi - g))
    assert not np.allclose(r.rho_s(g), r.rho_s(np.pi - g))
    # rho: symmetric about both axes, the bow-stern average of rho_s
    assert np.allclose(r.rho(g), r.rho(np.pi - g)) and np.allclose(r.rho(g), r.rho(-g))
    assert np.allclose(r.rho(g), 0.5 * (r.rho_s(g) + r.rho_s(np.pi - g)))
    explicit = 1.0 + 0.15 * np.cos(g) + 0.1 * np.cos(2 * g) + 0.05 * np.cos(3 * g)
    assert np.allclose(r.rho_s(g), explicit)
    d = corr.CurrentResponse()
    assert d.cos_coeffs == (1.0, 0.2, 0.15)
    assert d.rho_s(0.0) == pytest.approx(1.35) and d.rho_s(math.pi / 2) == pytest.approx(0.85)
    assert d.rho_s(math.pi) == pytest.approx(0.95) and d.rho(0.0) == pytest.approx(1.15)
    with pytest.raises(NavInputError, match="positive"):
        corr.CurrentResponse((1.0, 1.2))
    with pytest.raises(NavInputError):
        corr.CurrentResponse(())


# --------------------------------------------------------------------------------------------
# acceptance 1: exact recovery on noise-free data


def test_cp2_closed_form_recovers_truth_on_a_grid():
    firsts = [0, 30, 45, 90, 135, 180, 200, 270, 315]
    courses, vs, beta, cur, T = grid_truth([(a, a + 180) for a in firsts])
    est = corr.cp2(forward(courses, vs, beta, cur, T), T, courses)
    assert_recovers(est, vs, beta, cur)
    assert np.all(est.residual_m_s == 0.0)
    assert np.allclose(est.reference_course_rad, courses[:, 0])


@pytest.mark.slow
def test_cp1_descent_recovers_truth_on_a_grid():
    pairs = [(0, 90), (30, 120), (45, 100), (10, 350), (200, 45), (270, 0), (90, 300), (180, 170)]
    courses, vs, beta, cur, T = grid_truth(pairs)
    est = corr.cp1(forward(courses, vs, beta, cur, T), T, courses)
    assert_recovers(est, vs, beta, cur)
    assert np.max(est.residual_m_s) < 1e-12
    assert est.response is None


def test_cp1_multistart_reaches_the_global_minimum_on_arbitrary_data():
    """On data no model produced, eq. 12's global minimum is found by an independent search: for
    each beta on a fine grid the remaining parameters enter linearly (least squares here), and the
    best beta is refined with a scalar minimiser."""
    rng = np.random.default_rng(7)
    n = 40
    courses = rng.uniform(0, 2 * np.pi, (n, 2))
    courses[:, 1] = courses[:, 0] + rng.choice([-1, 1], n) * rng.uniform(0.2, 2.9, n)
    m = rng.normal(0, 0.3, (n, 2, 2))
    T = np.full((n, 2), 100.0)
    est = corr.cp1(m * 100.0, T, courses)
    f_est = est.residual_m_s**2
    params = np.column_stack([est.vs_m_s, est.beta_rad, est.current_world_m_s])
    assert np.allclose(corr.cp1_objective(params, m, courses), f_est, atol=1e-24)

    def projected(b, i):
        """min over (vs, Vc) of eq. 12 at the given betas (array), by linear least squares."""
        b = np.atleast_1d(b)
        A = np.zeros((b.size, 4, 3))
        A[:, 0:2, 0] = unit(courses[i, 0] + b)
        A[:, 2:4, 0] = unit(courses[i, 1] + b)
        A[:, 0, 1] = A[:, 2, 1] = A[:, 1, 2] = A[:, 3, 2] = 1.0
        y = m[i].reshape(4)
        x = np.einsum("gij,j->gi", np.linalg.pinv(A), y)
        return np.sum((np.einsum("gij,gj->gi", A, x) - y) ** 2, axis=-1)

    grid = np.radians(np.arange(-90.0, 90.0, 0.25))
    for i in range(n):
        assert f_est[i] <= projected(grid, i).min() + 1e-12
        # with a shared vs the two legs' four equations have an exact solution at
        # beta* = course(m1 - m2) - (alpha1 + alpha2)/2 - 90 deg (mod 180): F = 0
        d = m[i, 0] - m[i, 1]
        b_star = math.atan2(d[0], d[1]) - courses[i].mean() - math.pi / 2
        assert projected(b_star, i)[0] < 1e-20 and f_est[i] < 1e-20
        # and the estimate reproduces the data
        pred = est.vs_m_s[i] * unit(courses[i] + est.beta_rad[i]) + est.current_world_m_s[i]
        assert np.allclose(pred, m[i], atol=1e-9)


def test_cp1_finds_beta_outside_the_starting_range():
    courses = np.radians([[20.0, 110.0]])
    vs, beta = np.array([0.25]), np.radians([75.0])
    cur = np.array([[0.1, -0.2]])
    T = np.array([[100.0, 100.0]])
    est = corr.cp1(forward(courses, vs, beta, cur, T), T, courses)
    assert_recovers(est, vs, beta, cur)


# --------------------------------------------------------------------------------------------
# eq. 21, eq. 32-33 and the baseline


def test_eq21_carries_the_cp2_current_to_other_courses():
    resp = corr.CurrentResponse((1.0, 0.1, 0.2))
    courses = np.radians([[45.0, 225.0]] * 3)
    cur = np.array([0.3 * unit(math.radians(20.0))] * 3)
    T = np.full((3, 2), 100.0)
    est = corr.cp2(
        forward(courses, np.full(3, 0.1), np.zeros(3), cur, T), T, courses, response=resp
    )
    alpha = np.radians([45.0 + 180.0, 120.0, 300.0])
    got = est.current_for_course(alpha)

    def rho(g):
        return 1.0 + 0.2 * np.cos(2 * g)  # the even part of rho_s

    g1 = math.radians(25.0)  # between set 20 deg and course 45 deg
    g2 = np.radians([155.0, 100.0, 80.0])  # 20 vs 225, 120, 300
    expected = cur * (rho(g2) / rho(g1))[:, None]
    assert np.allclose(got, expected, atol=1e-15)
    assert np.allclose(got[0], cur[0])  # the opposite course sees the same current
    # (n, k) courses broadcast
    assert est.current_for_course(np.tile(alpha[:, None], (1, 4))).shape == (3, 4, 2)
    # a uniform response leaves the current unchanged
    flat = corr.cp2(
        forward(courses, np.zeros(3), np.zeros(3), cur, T),
        T,
        courses,
        response=corr.CurrentResponse((1.0,)),
    )
    assert np.allclose(flat.current_for_course(alpha), cur)


def test_corrected_dr_is_eq32_33():
    courses = np.radians([[30.0, 120.0], [45.0, 225.0]])
    vs, beta = np.array([0.2, -0.1]), np.radians([10.0, -20.0])
    cur = np.array([[0.1, 0.05], [-0.2, 0.1]])
    T = np.full((2, 2), 100.0)
    est = corr.cp1(forward(courses[:1], vs[:1], beta[:1], cur[:1], T[:1]), T[:1], courses[:1])
    alpha = np.radians([[70.0, 71.0, 72.0]])
    v = corr.dr_velocity(alpha, 1.2, est)
    expected = 1.2 * unit(alpha) + vs[0] * unit(alpha + beta[0]) + cur[0]
    assert np.allclose(v, expected, atol=1e-12)
    assert np.allclose(corr.dr_velocity(alpha, 1.2), 1.2 * unit(alpha))
    track = corr.dr_track(np.array([[5.0, -3.0]]), v, 0.5)
    assert track.shape == (1, 4, 2)
    assert np.allclose(track[0, -1], [5.0, -3.0] + 0.5 * expected[0].sum(axis=0))
    with pytest.raises(NavInputError):
        corr.dr_track(np.zeros((1, 2)), v, 0.0)


def test_baseline_is_gps_minus_dr_over_time():
    gps = np.array([[110.0, 5.0], [0.0, 0.0]])
    dr = np.array([[100.0, 0.0], [-20.0, 10.0]])
    est = corr.baseline(gps, dr, np.array([100.0, 50.0]))
    assert np.allclose(est.current_world_m_s, [[0.1, 0.05], [0.4, -0.2]])
    assert np.all(est.vs_m_s == 0) and est.response is None
    assert np.allclose(est.velocity_error(np.array([0.3, 2.0])), est.current_world_m_s)


# --------------------------------------------------------------------------------------------
# eq. 22-26 against an independent search over headings


def _brute_force_course(nu, va, vs, beta, c):
    """Courses whose resulting ground velocity is along nu: roots of the cross product, found on a
    fine grid and refined; the fastest one along nu wins (independent of eq. 22-26's algebra)."""

    def ground(a):
        a = np.asarray(a, dtype=float)
        return va * unit(a) + vs * unit(a + beta) + c

    def cross(a):
        g = ground(a)
        u = unit(nu)
        return g[..., 0] * u[1] - g[..., 1] * u[0]

    grid = np.linspace(0, 2 * np.pi, 7201)
    vals = cross(grid)
    best = None
    for i in np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:])):
        a = brentq(lambda x: float(cross(x)), grid[i], grid[i + 1], xtol=1e-14)
        speed = float(ground(a) @ unit(nu))
        if speed > 0 and (best is None or speed > best[1]):
            best = (a % (2 * np.pi), speed)
    return best


def test_compensated_course_matches_brute_force_including_cardinal_courses():
    rng = np.random.default_rng(3)
    nus = np.concatenate([np.radians([0.0, 90.0, 180.0, 270.0] * 3), rng.uniform(0, 2 * np.pi, 20)])
    n = nus.size
    vs = rng.uniform(-0.3, 0.3, n)
    beta = np.radians(rng.uniform(-30, 30, n))
    cur = rng.uniform(0, 0.6, n)[:, None] * unit(rng.uniform(0, 2 * np.pi, n))  # |Vc| < |Va + Vs|
    cur[:4] = [[0.0, 0.4], [0.4, 0.0], [0.0, -0.4], [-0.3, 0.0]]  # along the cardinal nu
    sol = corr.course_through_current(nus, 1.0, vs, beta, cur)
    assert np.all(sol.feasible)
    for i in range(n):
        a, speed = _brute_force_course(nus[i], 1.0, vs[i], beta[i], cur[i])
        assert abs(wrap_pi(sol.course_rad[i] - a)) < 1e-9
        assert sol.speed_along_m_s[i] == pytest.approx(speed, abs=1e-9)


def test_compensated_course_footnote2_nu_zero():
    # footnote 2 for nu = 0 (corrected): Va^x = -Vc^x, Va^y = sqrt(Va^2 - (Vc^x)^2)
    c = np.array([[0.3, -0.2]])
    sol = corr.course_through_current(np.array([0.0]), 1.0, 0.0, 0.0, c)
    expected = math.atan2(-0.3, math.sqrt(1 - 0.09)) % (2 * math.pi)
    assert sol.course_rad[0] == pytest.approx(expected, abs=1e-12)
    assert sol.speed_along_m_s[0] == pytest.approx(math.sqrt(0.91) - 0.2, abs=1e-12)


def test_cp2_three_phase_course_fix():
    resp = corr.CurrentResponse((1.0, 0.1, 0.3))
    courses = np.radians([[45.0, 225.0]] * 4)
    cur = np.array([0.4 * unit(math.radians(20.0))] * 4)
    T = np.full((4, 2), 100.0)
    est = corr.cp2(
        forward(courses, np.full(4, 0.2), np.radians([10.0] * 4), cur, T), T, courses, response=resp
    )
    nu = np.radians([100.0, 200.0, 300.0, 10.0])
    sol = corr.compensated_course(nu, 1.0, est)
    phase1 = corr.course_through_current(nu, 1.0, est.vs_m_s, est.beta_rad, est.current_world_m_s)
    phase3 = corr.course_through_current(
        nu, 1.0, est.vs_m_s, est.beta_rad, est.current_for_course(phase1.course_rad)
    )
    assert np.allclose(sol.course_rad, phase3.course_rad)

    def miss(alpha):
        g = 1.0 * unit(alpha) + est.velocity_error(alpha)
        return np.abs(wrap_pi(course_of(g) - nu))

    # the predicted track (current for the course actually steered) follows nu better, except
    # on 200 deg, close to the reverse of 45 deg, where eq. 21 leaves the current unchanged
    m3, m1 = miss(sol.course_rad), miss(phase1.course_rad)
    assert np.all(m3 <= m1 + 1e-12) and np.all(m3[[0, 2, 3]] < 0.1 * m1[[0, 2, 3]])
    assert np.max(miss(sol.course_rad)) < math.radians(0.5)


# --------------------------------------------------------------------------------------------
# acceptance 5: bad input gives a clear error or a documented fallback, never NaN


def _finite(est):
    for a in (est.vs_m_s, est.beta_rad, est.current_world_m_s, est.residual_m_s):
        assert np.all(np.isfinite(a))


def test_cp1_rejects_same_and_opposite_courses_naming_them():
    T = np.full((1, 2), 100.0)
    d = np.ones((1, 2, 2))
    for pair in ([30.0, 30.0], [30.0, 210.0], [30.0, 212.0], [30.0, 389.0]):
        with pytest.raises(NavInputError, match=r"courses 30\.000 and") as info:
            corr.cp1(d, T, np.radians([pair]))
        assert "same or opposite" in str(info.value)
    est = corr.cp1(
        np.ones((3, 2, 2)), 100.0, np.radians([[30, 30], [30, 120], [10, 190]]), on_bad="fallback"
    )
    assert est.valid.tolist() == [False, True, False]
    _finite(est)
    assert np.all(est.velocity_error(np.zeros(3))[[0, 2]] == 0.0)


def test_cp2_rejects_courses_that_are_not_opposite():
    with pytest.raises(NavInputError, match=r"45\.000 and 200\.000 deg .* not opposite"):
        corr.cp2(np.ones((1, 2, 2)), 100.0, np.radians([[45.0, 200.0]]))


@pytest.mark.parametrize("proc", [corr.cp1, corr.cp2])
def test_procedures_reject_missing_fix_and_bad_durations(proc):
    courses = np.radians([[45.0, 225.0]]) if proc is corr.cp2 else np.radians([[45.0, 135.0]])
    with pytest.raises(NavInputError, match="no GPS fix"):
        proc(None, 100.0, courses)
    nan = np.full((1, 2, 2), np.nan)
    with pytest.raises(NavInputError, match="no GPS fix"):
        proc(nan, 100.0, courses)
    for T in (0.0, -5.0, np.inf, np.nan):
        with pytest.raises(NavInputError, match="durations"):
            proc(np.ones((1, 2, 2)), np.array([[100.0, T]]), courses)
    with pytest.raises(NavInputError, match="shape"):
        proc(np.ones((2, 2)), 100.0, courses)
    d = np.stack([nan[0], np.ones((2, 2)), np.ones((2, 2))])
    est = proc(
        d,
        np.array([[100.0, 100.0], [100.0, 100.0], [0.0, 100.0]]),
        np.repeat(courses, 3, axis=0),
        on_bad="fallback",
    )
    assert est.valid.tolist() == [False, True, False]
    _finite(est)
    v = corr.dr_velocity(np.zeros(3), 1.0, est)
    assert np.all(np.isfinite(v)) and np.allclose(v[[0, 2]], [[0.0, 1.0], [0.0, 1.0]])


def test_baseline_rejects_missing_fix_and_zero_time():
    with pytest.raises(NavInputError, match="no GPS fix"):
        corr.baseline(None, np.zeros((1, 2)), 10.0)
    with pytest.raises(NavInputError, match="no GPS fix"):
        corr.baseline(np.full((1, 2), np.nan), np.zeros((1, 2)), 10.0)
    with pytest.raises(NavInputError, match="since the last fix"):
        corr.baseline(np.ones((1, 2)), np.zeros((1, 2)), 0.0)
    est = corr.baseline(
        np.array([[np.nan, 1.0], [1.0, 1.0]]), np.zeros((2, 2)), [10.0, 0.0], on_bad="fallback"
    )
    assert not np.any(est.valid)
    _finite(est)


def test_compensated_course_fallbacks_are_finite():
    # cross current stronger than the vehicle: no course holds nu
    sol = corr.course_through_current(np.array([0.0]), 0.5, 0.0, 0.0, np.array([[0.8, 0.0]]))
    assert not sol.feasible[0] and np.isfinite(sol.course_rad[0])
    assert sol.course_rad[0] == pytest.approx(1.5 * math.pi)  # heads straight into the set
    # head current stronger than the vehicle: on the line but drifting back
    sol = corr.course_through_current(np.array([0.0]), 0.5, 0.0, 0.0, np.array([[0.0, -0.8]]))
    assert not sol.feasible[0] and sol.course_rad[0] == pytest.approx(0.0)
    assert sol.speed_along_m_s[0] == pytest.approx(-0.3)
    # no propulsion at all (Vs cancels Va)
    sol = corr.course_through_current(np.array([1.0]), 1.0, -1.0, 0.0, np.array([[0.1, 0.0]]))
    assert not sol.feasible[0] and sol.course_rad[0] == pytest.approx(1.0)
    with pytest.raises(NavInputError):
        corr.compensated_course(np.zeros(2), 1.0, corr.CorrectionEstimate.none(3))
