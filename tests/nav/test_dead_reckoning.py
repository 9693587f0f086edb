"""Dead reckoning: the batched track, seed 000's DR with its covariance, and the online form."""

import numpy as np
import pytest

from nav.dead_reckoning import DeadReckoning, dead_reckon, track
from nav.ekf import BatchEKF
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
