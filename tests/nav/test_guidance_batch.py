"""Batched way-point guidance against the scalar one, run by run (issue 27, check 2)."""

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.guidance import Waypoint, WaypointGuidance, horizontal_sigma_m
from nav.guidance_batch import BatchWaypointGuidance, horizontal_sigma_batch_m

WPS = [Waypoint(40, 0, 3, 5), Waypoint(40, 30, 4, 8), Waypoint(0, 30, 2, 3), Waypoint(0, 0, 3, 5)]


def _tracks(rng, n, T, dt):
    """Estimated positions flying towards each way-point in turn at 1-2 m/s with noise, and
    estimate sigmas from 0 to beyond the hopeless limit (R < sigma sqrt(-2 ln 0.05))."""
    pos = np.zeros((T, n, 3))
    p = rng.normal(0, 1, (n, 3))
    target = np.zeros(n, dtype=int)
    speed = rng.uniform(1, 2, n)
    for k in range(T):
        wp = np.array([[WPS[min(j, 3)].east_m, WPS[min(j, 3)].north_m] for j in target])
        d = wp - p[:, :2]
        dist = np.hypot(*d.T)
        step = np.minimum(dist, speed * dt)[:, None] * d / np.maximum(dist, 1e-9)[:, None]
        p[:, :2] += step + rng.normal(0, 0.3, (n, 2))
        target += (dist < 0.5) & (rng.random(n) < 0.5)
        target = np.minimum(target, 3)
        pos[k] = p
    sig = np.abs(rng.normal(0, 1.0, (T, n))) * rng.choice([0.0, 1.0, 3.0], n)
    return pos, sig


@pytest.mark.parametrize("max_leg", [1200.0, 25.0])
def test_each_run_equals_the_scalar_guidance(max_leg):
    rng = np.random.default_rng(5)
    n, T, dt = 12, 600, 0.2
    pos, sig = _tracks(rng, n, T, dt)
    batch = BatchWaypointGuidance(WPS, n, 1.2, max_leg, 0.95, 1.0)
    scalars = [WaypointGuidance(WPS, 1.2, max_leg_time_s=max_leg) for _ in range(n)]
    for k in range(T):
        t = 3.0 + k * dt
        course, depth, speed = batch.step(t, pos[k], sig[k])
        for i, g in enumerate(scalars):
            c = g.step(t, pos[k, i], sig[k, i])
            assert course[i] == pytest.approx(c.course_rad, abs=1e-12), (k, i)
            assert (depth[i], speed[i]) == (c.depth_m, c.speed_m_s), (k, i)
            assert batch.index[i] == c.waypoint, (k, i)
    for i, g in enumerate(scalars):
        for leg in g.legs:
            assert batch.reached[i, leg.waypoint] == leg.reached
            assert batch.leg_end_s[i, leg.waypoint] == leg.t_s
        assert np.isnan(batch.leg_end_s[i, len(g.legs) :]).all()
    ends = np.isfinite(batch.leg_end_s)
    assert batch.done.any() and ends.sum() > n  # legs ended, some runs finished
    if max_leg < 100:
        assert (~batch.reached & ends).any()  # some legs timed out


def test_horizontal_sigma_equals_the_scalar():
    rng = np.random.default_rng(1)
    A = rng.normal(0, 2, (50, 5, 5))
    P = A @ np.swapaxes(A, 1, 2)
    got = horizontal_sigma_batch_m(P)
    want = [horizontal_sigma_m(p) for p in P]
    np.testing.assert_allclose(got, want, rtol=1e-14)
    # the largest eigenvalue of the horizontal block, from numpy
    np.testing.assert_allclose(got**2, np.linalg.eigvalsh(P[:, :2, :2])[:, -1], rtol=1e-10)


def test_bad_plans_are_refused():
    with pytest.raises(NavInputError, match="at least one"):
        BatchWaypointGuidance([], 3)
    with pytest.raises(NavInputError, match=r"waypoints\[1\]: acceptance_radius_m = 0"):
        BatchWaypointGuidance([WPS[0], Waypoint(1, 1, 1, 0.0)], 3)
    with pytest.raises(NavInputError, match=r"waypoints\[0\].surface"):
        BatchWaypointGuidance([Waypoint(1, 1, 1, 5, surface=True)], 3)
