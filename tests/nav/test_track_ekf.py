"""The structure-of-arrays EKF of seed 000 (nav.usbl.tracks, its updates nav.ekf's fast path
update_packed3) against the stacked-matrix EKF of nav.ekf (itself tested against filterpy), with
inactive components, absent fixes and the gate; and the fast path against nav.ekf.update."""

import numpy as np
import pytest

from nav.ekf import SYM3, BatchEKF, update, update_packed3
from nav.errors import NavInputError
from nav.models import CourseSpeedDepthMotion, UsblMeasurement
from nav.usbl import tracks as track_ekf

MOTION = CourseSpeedDepthMotion(np.radians(8.0), 0.26, 0.05)
# the azimuth is left out within 15 m of the vertical: many fixes have two components
USBL = UsblMeasurement(np.array([0.0, 0.0, -6.0]), 1.0, np.radians(1.0), np.radians(1.0), 15.0)


def _case(n=300, T=40, seed=0):
    g = np.random.default_rng(seed)
    u = np.stack(
        [g.uniform(0, 2 * np.pi, (n, T)), g.uniform(0.5, 1.5, (n, T)), g.normal(0, 0.05, (n, T))],
        axis=-1,
    )
    x0 = g.normal(0.0, 30.0, (n, 3))
    x0[:2, :2] = g.normal(0.0, 0.3, (2, 2))  # two start straight above the transceiver
    fix_tick = np.arange(5, T + 1, 5)
    z = np.stack(
        [
            g.uniform(1, 60, (n, len(fix_tick))),
            g.uniform(0, 2 * np.pi, (n, len(fix_tick))),
            g.uniform(-1.2, 1.2, (n, len(fix_tick))),
        ],
        axis=-1,
    )
    present = g.random((n, len(fix_tick))) < 0.8
    P0 = np.diag([25.0, 16.0, 1.0]) + 2.0
    return u, x0, P0, fix_tick, z, present


def _stacked(u, x0, P0, fix_tick, z, present, gate):
    ekf = BatchEKF(MOTION)
    n, T, _ = u.shape
    x, P = x0.copy(), np.broadcast_to(P0, (n, 3, 3)).copy()
    xs, Ps = [x], [P]
    nis = np.full(present.shape, np.nan)
    rej = np.zeros(present.shape, bool)
    fix = {int(t): j for j, t in enumerate(fix_tick)}
    for k in range(T):
        x, P = ekf.predict(x, P, u[:, k], 1.0)
        j = fix.get(k + 1)
        if j is not None:
            x, P, info = ekf.update(x, P, USBL, z[:, j], present[:, j], gate)
            nis[:, j], rej[:, j] = info.nis, info.rejected
        xs.append(x)
        Ps.append(P)
    return np.stack(xs, 1), np.stack(Ps, 1), nis, rej


@pytest.mark.parametrize("gate", [None, 0.99])
def test_tracks_equal_the_stacked_matrix_ekf(gate):
    u, x0, P0, fix_tick, z, present = _case()
    inc, Q = MOTION.increment_and_packed_Q(u, 1.0)
    tr = track_ekf.ekf_tracks(x0, P0, inc, Q, fix_tick, z, present, USBL, gate)
    xs, Ps, nis, rej = _stacked(u, x0, P0, fix_tick, z, present, gate)
    np.testing.assert_allclose(tr.positions(), xs, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(tr.covariances(), Ps, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(tr.nis, nis, rtol=1e-10)
    assert np.array_equal(np.isnan(tr.nis), ~present)
    assert np.array_equal(tr.rejected, rej)
    if gate is not None:
        assert 0 < rej.sum() < present.sum()  # the gate decided somewhere, not everywhere


def test_packed_process_noise_is_the_full_one():
    u, *_ = _case(n=20, T=30)
    inc, Q = MOTION.increment_and_Q(u, 0.5)
    inc_t, Qp = MOTION.increment_and_packed_Q(u, 0.5)
    np.testing.assert_array_equal(inc_t, np.moveaxis(inc, 0, 2))  # (T, 3, n) from (n, T, 3)
    np.testing.assert_array_equal(track_ekf.unpack(Qp), Q)


def test_packed_nees_equals_a_solve():
    g = np.random.default_rng(3)
    A = g.normal(size=(500, 3, 3))
    P = A @ np.swapaxes(A, 1, 2) + 0.1 * np.eye(3)
    e = g.normal(size=(500, 3))
    want = np.einsum("ni,ni->n", e, np.linalg.solve(P, e[..., None])[..., 0])
    np.testing.assert_allclose(track_ekf.nees_packed(e.T, track_ekf.pack(P)), want, rtol=1e-10)


def test_a_non_diagonal_measurement_noise_is_refused():
    u, x0, P0, fix_tick, z, present = _case(n=4, T=10)
    inc, Q = MOTION.increment_and_packed_Q(u, 1.0)

    class Correlated(UsblMeasurement):
        def R(self):
            return super().R() + 1e-3

    bad = Correlated(np.zeros(3), 1.0, 0.1, 0.1)
    with pytest.raises(NavInputError, match="diagonal R"):
        track_ekf.ekf_tracks(x0, P0, inc, Q, fix_tick, z, present, bad)


def test_usbl_linearisation_at_once_is_h_H_and_active():
    g = np.random.default_rng(8)
    x = g.normal(0.0, 20.0, (200, 3))
    x[:3, :2] = 0.2  # within min_horizontal_m: azimuth inactive
    h, H, act = USBL.linearise(x)
    assert np.array_equal(h, USBL.h(x)) and np.array_equal(H, USBL.H(x))
    assert np.array_equal(act, USBL.active(x)) and not act[:3, 1].any()


def _random_update_case(seed, n=400):
    g = np.random.default_rng(seed)
    A = g.normal(0.0, 3.0, (n, 3, 3))
    P = A @ np.swapaxes(A, 1, 2) + 0.05 * np.eye(3)
    x = g.normal(0.0, 50.0, (n, 3))
    H = np.eye(3) + g.normal(0.0, 0.3, (n, 3, 3))  # well conditioned: S far from singular
    y = g.normal(0.0, 2.0, (n, 3))
    r = g.uniform(0.01, 4.0, 3)
    active = g.random((n, 3)) < 0.7
    active[:5] = False  # runs with no active component
    present = g.random(n) < 0.85
    return x, P, y, H, r, active, present


@pytest.mark.parametrize("gate", [None, 0.9])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_fast_path_equals_the_update_on_random_inputs(seed, gate):
    x, P, y, H, r, active, present = _random_update_case(seed)
    want_x, want_P, want = update(x, P, y, H, np.diag(r), active, present, gate)
    xs = np.ascontiguousarray(x.T)
    Pp = np.stack([P[:, i, j] for i, j in SYM3])
    info = update_packed3(xs, Pp, y, H, r, active, present, gate)
    np.testing.assert_allclose(xs.T, want_x, rtol=1e-12, atol=1e-12 * np.abs(x).max())
    got_P = np.empty_like(P)
    for c, (i, j) in enumerate(SYM3):
        got_P[:, i, j] = got_P[:, j, i] = Pp[c]
    np.testing.assert_allclose(got_P, want_P, rtol=1e-12, atol=1e-12 * np.abs(P).max())
    np.testing.assert_allclose(info.nis, want.nis, rtol=1e-12)
    assert np.array_equal(np.isnan(info.nis), np.isnan(want.nis))
    assert np.array_equal(info.dof, np.where(present, want.dof, 0))  # absent: nothing active
    assert np.array_equal(info.applied, want.applied)
    assert np.array_equal(info.rejected, want.rejected)
    assert want.applied.sum() > n_min(x) and (~want.applied).sum() > 0
    if gate is not None:
        assert 0 < want.rejected.sum() < present.sum()


def n_min(x):
    """At least a quarter of the runs must be updated for the comparison to say something."""
    return len(x) // 4


def test_the_fast_path_refuses_a_non_positive_variance():
    x, P, y, H, _r, active, present = _random_update_case(4, n=10)
    Pp = np.stack([P[:, i, j] for i, j in SYM3])
    with pytest.raises(NavInputError, match="positive variances"):
        update_packed3(x.T.copy(), Pp, y, H, np.array([1.0, 0.0, 1.0]), active, present)
