"""Seed 001's DRNS online: legs, procedures and corrected DR against a noise-free world."""

import math

import numpy as np
import pytest

from nav.errors import NavInputError
from nav.surfacing import CorrectedDeadReckoning, CurrentResponse


def fly(drns, truth, t, course_deg, seconds, speed_odo, vel_true, dt=0.1):
    """Move truth with ``vel_true`` and feed the DRNS the compass course and odometry speed."""
    for _ in range(round(seconds / dt)):
        t += dt
        truth = truth + dt * vel_true
        drns.predict(t, math.radians(course_deg), speed_odo)
    return truth, t


def u(deg):
    return np.array([math.sin(math.radians(deg)), math.cos(math.radians(deg))])


@pytest.mark.slow
@pytest.mark.parametrize("bias_deg", [0.0, 5.0, -12.0])
def test_cp2_from_two_surfacings_recovers_the_errors_and_corrects_dr(bias_deg):
    # the vehicle holds compass course C but really swims C - bias at 0.9 of its odometry speed,
    # in a uniform current: Vs = 0.9 u(C - bias) - u(C) rotates with the course (seed 001 eq. 5-6)
    current = 0.3 * u(20.0)
    speed_odo = 1.0

    def v_true(c):
        return 0.9 * speed_odo * u(c - bias_deg) + current

    truth = np.array([10.0, -5.0])
    drns = CorrectedDeadReckoning(0.0, truth, "cp2", CurrentResponse((1.0,)))
    t = 0.0
    for course in (45.0, 225.0):
        truth, t = fly(drns, truth, t, course, 100.0, speed_odo, v_true(course))
        drns.fix(t, truth)  # surfaced: the fix is exact
        # drifting at the surface for 3 s; the last fix before diving starts the next leg
        truth, t = fly(drns, truth, t, course, 3.0, 0.0, current)
        assert drns.fix(t, truth) is None  # a second fix of the same surfacing ends no leg
    assert len(drns.legs) == 2 and drns.estimate is not None
    est = drns.estimate
    assert np.allclose(est.current_world_m_s[0], current, atol=1e-9)
    vs_true = v_true(45.0) - current - speed_odo * u(45.0)
    assert np.allclose(est.vs_world(np.array([math.radians(45.0)]))[0], vs_true, atol=1e-9)
    # leg 3 on a new course: corrected DR follows the truth, uncorrected drifts
    start = truth.copy()
    truth, t = fly(drns, truth, t, 300.0, 100.0, speed_odo, v_true(300.0))
    assert np.allclose(drns.corrected, truth, atol=1e-6)
    drift = np.linalg.norm(drns.uncorrected - truth)
    assert drift == pytest.approx(100.0 * np.linalg.norm(v_true(300.0) - u(300.0)), rel=1e-6)
    # the baseline takes the whole leg-2 error for a current fixed in the world
    assert np.linalg.norm(drns.baseline - truth) > 1.0 or bias_deg == 0.0
    assert np.allclose(drns.corrected - start, truth - start, atol=1e-6)


def test_cp1_needs_different_courses_and_says_why():
    drns = CorrectedDeadReckoning(0.0, np.zeros(2), "cp1")
    truth, t = np.zeros(2), 0.0
    for course in (30.0, 30.0):
        truth, t = fly(drns, truth, t, course, 50.0, 1.0, 1.0 * u(course) + [0.1, 0.0])
        drns.fix(t, truth)
        truth, t = fly(drns, truth, t, course, 10.0, 0.0, np.array([0.1, 0.0]))
    assert drns.estimate is None and "30.000" in drns.correction_error
    # uncorrected DR continues: nothing is NaN
    truth, t = fly(drns, truth, t, 90.0, 10.0, 1.0, u(90.0))
    assert np.all(np.isfinite(drns.corrected))


def test_predict_refuses_time_going_backwards():
    drns = CorrectedDeadReckoning(5.0, np.zeros(2))
    with pytest.raises(NavInputError, match="not after"):
        drns.predict(4.0, 0.0, 1.0)
