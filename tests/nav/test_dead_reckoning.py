"""Dead reckoning: the batched track (alone and with its covariance), seed 000's DR with its
covariance, and the online form."""

import numpy as np
import pytest

from nav.dead_reckoning import DeadReckoning, dead_reckon, step, track, track_with_covariance
from nav.ekf import BatchEKF
from nav.errors import NavInputError
from nav.models import CourseSpeedDepthMotion

RNG = np.random.default_rng(8)
MOTION = CourseSpeedDepthMotion(0.1, 0.2, 0.25)


def _inputs(n=5, T=30):
    return np.stack(
        [RNG.uniform(0, 6, (n, T)), RNG.uniform(0.5, 1.5, (n, T)), RNG.normal(0, 0.2, (n, T))], -1
    )


def test_track_is_the_start_plus_the_displacements_so_far():
    start = RNG.normal(0, 10, (4, 2))
    inc = RNG.normal(0, 1, (4, 6, 2))
    x = track(start, inc)
    assert x.shape == (4, 7, 2) and np.array_equal(x[:, 0], start)
    for k in range(7):  # written out: x_k = x_0 + dx_0 + ... + dx_{k-1}
        expected = start + sum((inc[:, i] for i in range(k)), np.zeros((4, 2)))
        assert np.allclose(x[:, k], expected, atol=1e-12)
    P = track(np.broadcast_to(np.eye(2), (4, 2, 2)), np.ones((4, 3, 2, 2)))
    assert P.shape == (4, 4, 2, 2) and np.allclose(P[:, -1], np.eye(2) + 3.0)


def test_dead_reckoning_equals_stepping_the_ekf_prediction():
    u = _inputs()
    x0 = RNG.normal(0, 10, (5, 3))
    P0 = np.diag([1.0, 2.0, 0.1])
    x, P = dead_reckon(x0, u, 1.0, MOTION, P0)
    ekf = BatchEKF(MOTION)
    xe, Pe = x0, np.broadcast_to(P0, (5, 3, 3))
    for k in range(30):
        xe, Pe = ekf.predict(xe, Pe, u[:, k], 1.0)
    assert np.allclose(x[:, -1], xe, atol=1e-10) and np.allclose(P[:, -1], Pe, atol=1e-10)
    assert dead_reckon(x0, u, 1.0, MOTION)[1] is None


@pytest.mark.parametrize("dt", [0.2, 1.0])
def test_online_dead_reckoning_follows_the_batched_track(dt):
    u = _inputs(n=1, T=200)
    x0 = np.array([[3.0, -4.0, -2.0]])
    x, _ = dead_reckon(x0, u, dt, MOTION)
    dr = DeadReckoning(x0[0])
    for k in range(200):
        dr.advance(MOTION.increment_one(u[0, k], dt))
        assert np.allclose(dr.position, x[0, k + 1], atol=1e-11)
    dr.reset([1.0, 2.0, 3.0])
    assert np.array_equal(dr.position, [1.0, 2.0, 3.0])


def test_track_with_covariance_sums_displacements_and_covariances_from_the_start():
    n, T = 3, 7
    start = RNG.normal(0, 10, (n, 2))
    inc = RNG.normal(0, 1, (n, T, 2))
    B = RNG.normal(0, 0.1, (n, T, 2, 2))
    Q = B @ np.swapaxes(B, -1, -2)
    P0 = np.diag([0.5, 2.0])
    tr = track_with_covariance(start, inc, Q, P0)
    assert tr.position_m.shape == (n, T + 1, 2) and tr.cov_m2.shape == (n, T + 1, 2, 2)
    for i in range(n):  # written out, one run and one sample at a time
        x, P = start[i].copy(), P0.copy()
        for k in range(T + 1):
            np.testing.assert_allclose(tr.position_m[i, k], x, atol=1e-12)
            np.testing.assert_allclose(tr.cov_m2[i, k], P, atol=1e-12)
            if k < T:
                x, P = x + inc[i, k], P + Q[i, k]
    # without a start covariance the start is known; between two samples, per-run samples
    known = track_with_covariance(start, inc, Q)
    assert np.array_equal(known.cov_m2[:, 0], np.zeros((n, 2, 2)))
    k, j = np.array([5, 7, 2]), np.array([1, 3, 2])
    np.testing.assert_allclose(
        known.displacement(k, j), [inc[i, j[i] : k[i]].sum(0) for i in range(n)], atol=1e-12
    )
    np.testing.assert_allclose(
        known.covariance_between(k, j), [Q[i, j[i] : k[i]].sum(0) for i in range(n)], atol=1e-12
    )
    with pytest.raises(NavInputError, match="increment_cov"):
        track_with_covariance(start, inc, Q[:, :, :1])


def test_online_dead_reckoning_with_covariance_and_one_batched_step():
    dr = DeadReckoning([1.0, 2.0], np.eye(2))
    dr.advance(np.array([0.5, -1.0]), np.diag([0.1, 0.2]))
    assert dr.position.tolist() == [1.5, 1.0]
    np.testing.assert_array_equal(dr.covariance, np.diag([1.1, 1.2]))
    with pytest.raises(NavInputError, match="increment_cov"):
        dr.advance(np.array([0.5, -1.0]))
    with pytest.raises(NavInputError, match="increment_cov"):
        DeadReckoning([0.0, 0.0]).advance(np.zeros(2), np.eye(2))
    dr.reset([0.0, 0.0], np.zeros((2, 2)))
    assert dr.position.tolist() == [0.0, 0.0] and not dr.covariance.any()
    np.testing.assert_array_equal(
        step(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[0.5, 0.5], [-1.0, 0.0]])),
        [[1.5, 2.5], [2.0, 4.0]],
    )
