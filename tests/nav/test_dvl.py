"""Navigation with a DVL (nav.dvl): the attitude rotation against the simulator's, the lever-arm
term against a rigid body's motion, Jacobians against finite differences, one update against
filterpy, and dead reckoning on DVL velocity against the closed-form circle of a turning
vehicle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from scipy.spatial.transform import Rotation

from bauv_sim.frames import R_from_roll_pitch_heading as R_frames
from nav.angles import rotation_world_from_body
from nav.dead_reckoning import DeadReckoning, dead_reckon, track
from nav.dvl import (
    DvlVelocityMeasurement,
    GroundVelocityMotion,
    dvl_increment_covariance,
    dvl_increments,
    dvl_track,
    velocity_world_from_dvl,
)
from nav.ekf import BatchEKF, SingleRunEKF, update_with
from nav.errors import NavInputError
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion, UsblMeasurement
from nav.navigator import Measurement, OnlineNavigator

LEVER = np.array([0.8, -0.15, -0.25])  # transducer: forward, starboard, below the reference


def test_rotation_is_the_simulators():
    rng = np.random.default_rng(1)
    att = np.column_stack(
        [rng.uniform(-np.pi, np.pi, 500), rng.uniform(-1.5, 1.5, 500), rng.uniform(0, 7, 500)]
    )
    R = rotation_world_from_body(att)
    assert np.allclose(R, R_frames(att[:, 0], att[:, 1], att[:, 2]), atol=1e-14, rtol=0)
    # laws: orthonormal, det +1, forward axis along heading and pitch, port up when rolled +
    assert np.allclose(R @ np.swapaxes(R, -1, -2), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(R), 1.0)
    one = rotation_world_from_body([0.2, 0.0, math.radians(90)])
    assert np.allclose(one[:, 0], [1.0, 0.0, 0.0], atol=1e-15)  # heading east: nose east
    assert one[2, 1] > 0  # roll starboard down: the port (body y) axis rises
    with pytest.raises(NavInputError, match="roll_pitch_heading_rad"):
        rotation_world_from_body(np.zeros(2))


def test_velocity_world_removes_the_lever_arm_of_a_rotating_body():
    """A rigid body turning at omega: the transducer's world velocity (finite differences of
    its world position p + R(t) r) seen in body axes, back to the reference point's."""
    rng = np.random.default_rng(2)
    for _ in range(20):
        att = rng.uniform([-0.4, -0.4, 0.0], [0.4, 0.4, 2 * np.pi])
        omega = rng.normal(0.0, 0.3, 3)  # body rates, rad/s
        v_ref = rng.normal(0.0, 1.0, 3)  # reference point's world velocity, m/s
        R0 = R_frames(*att)

        def transducer(t, R0=R0, omega=omega, v_ref=v_ref):
            R_t = R0 @ Rotation.from_rotvec(omega * t).as_matrix()  # body-fixed rotation
            return v_ref * t + R_t @ LEVER

        eps = 1e-6
        v_tr_world = (transducer(eps) - transducer(-eps)) / (2 * eps)
        v_dvl_body = R0.T @ v_tr_world
        got = velocity_world_from_dvl(v_dvl_body, att, omega, LEVER)
        assert np.allclose(got, v_ref, atol=1e-8)
        # without the lever-arm term the answer is off by R (omega x r)
        assert not np.allclose(velocity_world_from_dvl(v_dvl_body, att), v_ref, atol=1e-3)


def _fd_jacobian(fun, x, eps=1e-6):
    cols = []
    for j in range(x.shape[-1]):
        d = np.zeros_like(x)
        d[..., j] = eps
        cols.append((fun(x + d) - fun(x - d)) / (2 * eps))
    return np.stack(cols, axis=-1)


def _model(rng, n=None, **kw):
    shape = (3,) if n is None else (n, 3)
    att = rng.uniform([-0.3, -0.3, 0.0], [0.3, 0.3, 2 * np.pi], shape)
    speed = rng.uniform(0.5, 2.0) if n is None else rng.uniform(0.5, 2.0, n)
    args = dict(
        roll_pitch_heading_rad=att,
        speed_through_water_m_s=speed,
        sigma_m_s=0.01,
        sigma_speed_m_s=0.03,
        vertical_velocity_m_s=0.05,
        sigma_vertical_m_s=0.01,
        angular_velocity_body_rad_s=rng.normal(0, 0.1, shape),
        lever_arm_body_m=LEVER,
    )
    args.update(kw)
    return DvlVelocityMeasurement(**args)


def _args(m):
    return {
        f: getattr(m, f)
        for f in (
            "roll_pitch_heading_rad",
            "speed_through_water_m_s",
            "sigma_m_s",
            "sigma_speed_m_s",
            "vertical_velocity_m_s",
            "sigma_vertical_m_s",
            "angular_velocity_body_rad_s",
            "lever_arm_body_m",
        )
    }


@pytest.mark.parametrize("n", [None, 7])
def test_dvl_jacobian_equals_finite_differences(n):
    rng = np.random.default_rng(3)
    m = _model(rng, n)
    x = rng.normal(0.0, 1.0, (7 if n else 1, 5)) * [50, 50, 10, 0.3, 0.3]
    H = m.H(x)
    assert H.shape == (len(x), 3, 5)
    assert np.allclose(H, _fd_jacobian(m.h, x), atol=1e-8)
    assert np.any(H[..., 3:] != 0) and np.all(H[..., :3] == 0)
    # the Jacobian of the motion model on velocity over ground: F = I, Q = G diag G^T
    g = GroundVelocityMotion(0.02, 0.01)
    u = rng.normal(0.0, 1.0, (4, 3))
    xs = rng.normal(0.0, 5.0, (4, 3))
    dt = 0.2
    assert np.allclose(g.F(xs, u, dt), _fd_jacobian(lambda y: g.f(y, u, dt), xs), atol=1e-9)
    G = _fd_jacobian(lambda v: g.f(xs, v, dt), u)
    want = G @ np.diag([0.02**2, 0.02**2, 0.01**2]) @ np.swapaxes(G, -1, -2)
    assert np.allclose(g.Q(u, dt), want, atol=1e-15)


def test_dvl_prediction_is_the_velocity_over_ground_in_body_axes():
    """h at the true current is the transducer's velocity over ground in body axes,
    independently: R^T (water velocity + current) + omega x r."""
    rng = np.random.default_rng(4)
    m = _model(rng)
    att = m.roll_pitch_heading_rad
    c = np.array([0.2, -0.25])
    s, hd = m.speed_through_water_m_s, att[2]
    v_ground = np.array([s * math.sin(hd) + c[0], s * math.cos(hd) + c[1], 0.05])
    want = R_frames(*att).T @ v_ground + np.cross(m.angular_velocity_body_rad_s, LEVER)
    assert np.allclose(m.h(np.array([[10.0, 20.0, -5.0, *c]]))[0], want, atol=1e-14)
    # and velocity_world_from_dvl inverts it to the reference point's ground velocity
    back = velocity_world_from_dvl(want, att, m.angular_velocity_body_rad_s, LEVER)
    assert np.allclose(back, v_ground, atol=1e-14)


def test_dvl_update_equals_filterpys_kalman_filter():
    rng = np.random.default_rng(5)
    m = _model(rng)
    x = np.array([[3.0, -4.0, -10.0, 0.1, 0.05]])
    A = rng.normal(0.0, 1.0, (5, 5))
    P = (A @ A.T + np.eye(5)) * [[1.0]]
    P[3:, 3:] *= 0.01
    P = 0.5 * (P + P.T)
    z = m.h(x)[0] + np.array([0.05, -0.02, 0.01])
    ours, P_ours, _ = update_with(x, P[None], m, z[None])
    one, P_one, _ = SingleRunEKF(
        CurrentAwareMotion(CourseSpeedDepthMotion(0.01, 0.01, 0.01), 0)
    ).update(x, P[None], m, z[None])
    # filterpy's linear filter on the affine h: z - h(0) = H x
    H = m.H(x)[0]
    offset = m.h(np.zeros((1, 5)))[0]
    kf = KalmanFilter(dim_x=5, dim_z=3)
    kf.x = x[0].reshape(5, 1).copy()
    kf.P = P.copy()
    kf.update((z - offset).reshape(3, 1), R=m.R(), H=H)
    assert np.allclose(ours[0], kf.x[:, 0], atol=1e-12)
    assert np.allclose(P_ours[0], kf.P, atol=1e-12)
    assert np.allclose(one, ours, atol=1e-12) and np.allclose(P_one, P_ours, atol=1e-12)


def test_dvl_noise_and_bad_input():
    rng = np.random.default_rng(6)
    m = _model(rng, sigma_speed_m_s=0.0, sigma_vertical_m_s=0.0)
    assert np.allclose(m.R(), 0.01**2 * np.eye(3))
    m = _model(rng, n=4)
    R = m.R()
    assert R.shape == (4, 3, 3)
    # the log's noise lies along the horizontal heading direction seen in body axes
    b = np.einsum(
        "nji,nj->ni",
        R_frames(*m.roll_pitch_heading_rad.T),
        np.column_stack(
            [
                np.sin(m.roll_pitch_heading_rad[:, 2]),
                np.cos(m.roll_pitch_heading_rad[:, 2]),
                np.zeros(4),
            ]
        ),
    )
    e = R_frames(*m.roll_pitch_heading_rad.T)[:, 2, :]
    want = (
        1e-4 * np.eye(3)
        + 0.03**2 * b[:, :, None] * b[:, None, :]
        + 1e-4 * e[:, :, None] * e[:, None, :]
    )
    assert np.allclose(R, want, atol=1e-16)
    # the heading's term: sigma_h^2 g g^T with g = dh/d heading (finite differences) at the
    # current it is linearised about
    c = np.array([0.25, -0.15])
    m0 = _model(rng, sigma_speed_m_s=0.0, sigma_vertical_m_s=0.0)
    mh = _model(rng, **{**_args(m0), "sigma_heading_rad": 0.02, "current_for_noise_m_s": c})
    x = np.array([[0.0, 0.0, -5.0, *c]])
    eps = 1e-6
    hs = [
        _model(
            rng, **{**_args(m0), "roll_pitch_heading_rad": m0.roll_pitch_heading_rad + [0, 0, d]}
        ).h(x)[0]
        for d in (eps, -eps)
    ]
    g = (hs[0] - hs[1]) / (2 * eps)
    assert np.linalg.norm(g) == pytest.approx(np.linalg.norm(c), rel=1e-6)
    assert np.allclose(mh.R(), m0.R() + 0.02**2 * np.outer(g, g), atol=1e-14)
    with pytest.raises(NavInputError, match="current_for_noise_m_s"):
        _model(rng, current_for_noise_m_s=np.zeros(3))
    with pytest.raises(NavInputError, match="sigma_m_s"):
        _model(rng, sigma_m_s=0.0)
    with pytest.raises(NavInputError, match="roll_pitch_heading_rad"):
        _model(rng, roll_pitch_heading_rad=np.array([0.0, np.nan, 1.0]))
    with pytest.raises(NavInputError, match="current_index"):
        _model(rng).h(np.zeros((1, 3)))


# ----------------------------------------------------------------------------------------------
# Dead reckoning on DVL velocity: a vehicle with a constant body velocity turning at a constant
# rate, the DVL on a lever arm, rolled and pitched: its reference point flies a circle (a helix).

V_BODY = np.array([1.5, 0.1, 0.0])  # reference point's velocity, body FLU, m/s
ATT0 = np.array([0.1, -0.05, 0.3])  # roll, pitch, initial heading, rad
HEADING_RATE = 0.1  # rad/s, clockwise


def _circle(t):
    """Closed form: world position of the reference point (from the origin at t = 0) and the
    DVL's body velocity at the transducer, shapes (k, 3)."""
    roll, pitch, h0 = ATT0
    heading = h0 + HEADING_RATE * t
    att = np.column_stack([np.full_like(t, roll), np.full_like(t, pitch), heading])
    # the body velocity levelled (pitch and roll only), in the heading-aligned frame FLU
    w = R_frames(roll, pitch, math.pi / 2) @ V_BODY  # heading 90 deg: frame x east = forward
    # world velocity: w rotated by the yaw (pi/2 - heading) about z: angle theta(t)
    om = -HEADING_RATE  # yaw rate, counter-clockwise
    th0, th = math.pi / 2 - h0, math.pi / 2 - heading
    # int Rz(theta) ds = (1/om) [[sin, cos], [-cos, sin]] from th0 to th
    e = ((np.sin(th) - math.sin(th0)) * w[0] + (np.cos(th) - math.cos(th0)) * w[1]) / om
    n = (-(np.cos(th) - math.cos(th0)) * w[0] + (np.sin(th) - math.sin(th0)) * w[1]) / om
    pos = np.column_stack([e, n, w[2] * t])
    omega_world = np.array([0.0, 0.0, om])
    R = R_frames(att[:, 0], att[:, 1], att[:, 2])
    omega_body = np.einsum("kji,j->ki", R, omega_world)
    v_dvl = V_BODY + np.cross(omega_body, LEVER)
    return pos, v_dvl, att, omega_body


def _dr_error(dt, lever=True):
    t = np.arange(0.0, 120.0 + 1e-9, dt)
    pos, v_dvl, att, omega = _circle(t)
    v_world = velocity_world_from_dvl(v_dvl, att, omega if lever else None, LEVER)
    tr = dvl_track(np.zeros(3), v_world[None], t, sigma_velocity_m_s=0.01)
    return np.max(np.linalg.norm(tr.position_m[0] - pos, axis=-1)), tr, t


def test_dr_on_dvl_reproduces_the_closed_form_circle():
    dt = 0.2
    err, tr, t = _dr_error(dt)
    speed = np.linalg.norm(V_BODY)
    # the trapezoid rule's error on a vector turning at rate w: |v| w^2 dt^3 / 12 per step
    bound = speed * HEADING_RATE**2 * dt**2 * t[-1] / 12
    assert err < bound, (err, bound)
    err_half, _, _ = _dr_error(dt / 2)
    assert 3.0 < err / err_half < 5.0  # second order
    # the lever-arm term is what keeps it on the circle: without it the track is metres off
    assert _dr_error(dt, lever=False)[0] > 1.0
    # the covariance: dt^2 sigma^2 per step on each axis
    assert np.allclose(tr.cov_m2[0, -1], np.eye(3) * (len(t) - 1) * (dt * 0.01) ** 2)


def test_online_dr_on_dvl_is_the_batched_dr():
    """DeadReckoning, and OnlineNavigator.advance with GroundVelocityMotion, fed the mean of
    consecutive pings (the trapezoid), give the batched track's positions."""
    dt = 0.2
    t = np.arange(0.0, 60.0 + 1e-9, dt)
    pos, v_dvl, att, omega = _circle(t)
    v_world = velocity_world_from_dvl(v_dvl, att, omega, LEVER)
    batched = dvl_track(np.zeros(3), v_world[None], t).position_m[0]
    g = GroundVelocityMotion(0.01, 0.01)
    dr = DeadReckoning(np.zeros(3))
    P0 = np.diag([1.0, 1.0, 0.1])
    navs = [OnlineNavigator(est(g), 0.0, np.zeros(3), P0, g) for est in (SingleRunEKF, BatchEKF)]
    log_motion = CourseSpeedDepthMotion(0.01, 0.01, 0.01)
    log_nav = OnlineNavigator(SingleRunEKF(log_motion), 0.0, np.zeros(3), P0, g)
    log_u = np.column_stack([att[1:, 2], np.full(len(t) - 1, 1.5), np.zeros(len(t) - 1)])
    for k in range(1, len(t)):
        u = 0.5 * (v_world[k - 1] + v_world[k])
        u[2] = -u[2] * dt  # depth change over the step, positive down
        dr.advance(g.increment_one(u, dt))
        for nav in navs:
            nav.advance(t[k], u)
        assert np.allclose(dr.position, batched[k], atol=1e-9)
        log_nav.advance(t[k], np.array([att[k, 2], 1.5, 0.0]), dr_input=u)
    # the EKF on heading and log (through water, no current here), its DR on the DVL
    assert np.allclose(log_nav.dr_position, batched[-1], atol=1e-9)
    log_dr, _ = dead_reckon(np.zeros((1, 3)), log_u[None], dt, log_motion)
    assert np.allclose(log_nav.estimate.x, log_dr[0, -1], atol=1e-9)
    for nav in navs:
        assert np.allclose(nav.estimate.x, batched[-1], atol=1e-9)
        assert np.allclose(nav.dr_position, batched[-1], atol=1e-9)
        assert np.allclose(
            nav.estimate.P,
            P0
            + np.diag([1, 1, 0]) * (len(t) - 1) * (dt * 0.01) ** 2
            + np.diag([0, 0, 1]) * (len(t) - 1) * 1e-4,
        )
    # a USBL fix through the same navigator
    usbl = UsblMeasurement(np.array([0.0, 0.0, 0.0]), 0.5, 0.01, 0.01)
    z = usbl.h(pos[-1][None])[0]
    infos = [nav.fuse(Measurement(z, usbl, t[-1])) for nav in navs]
    assert all(i.applied[0] for i in infos)
    assert np.allclose(navs[0].estimate.x, navs[1].estimate.x, atol=1e-12)


def test_dvl_increments_hold_through_drop_outs_and_refuse_bad_input():
    t = np.array([0.0, 0.2, 0.4, 0.6, 0.8])
    v = np.arange(2 * 5 * 3, dtype=float).reshape(2, 5, 3)
    valid = np.array([[True, False, False, True, True], [False, True, True, True, False]])
    v_bad = np.where(valid[..., None], v, np.nan)  # what an absent ping may hold
    inc = dvl_increments(v_bad, t, valid)
    held = v.copy()
    held[0, 1] = held[0, 2] = v[0, 0]
    held[1, 0] = 0.0
    held[1, 4] = v[1, 3]
    want = np.zeros_like(v)
    want[:, 1:] = 0.1 * (held[:, :-1] + held[:, 1:])
    assert np.allclose(inc, want, atol=1e-14)
    assert np.all(inc[:, 0] == 0)
    assert np.allclose(track(np.zeros((2, 3)), inc)[:, 1:], np.zeros(3) + np.cumsum(want, axis=1))
    with pytest.raises(NavInputError, match="t_s"):
        dvl_increments(v, t[::-1])
    with pytest.raises(NavInputError, match="shapes"):
        dvl_increments(v, t[:4])
    with pytest.raises(NavInputError, match="non-finite"):
        dvl_increments(v_bad, t)


def test_dvl_increment_covariance_is_the_spread_of_displacements_with_white_errors():
    """Monte Carlo of one ping's displacement ``dt R(psi + e_psi) v_body + dt e_v`` (heading
    clockwise from north, white errors): its covariance is the first-order ``Q`` within the
    sampling error of 400,000 draws (and the heading term matters: without it the check
    fails)."""
    rng = np.random.default_rng(11)
    dt, sv, sp = 0.2, 0.01, math.radians(1.0)
    speed, heading = 1.5, math.radians(35.0)
    v = speed * np.array([math.sin(heading), math.cos(heading)])
    n = 400_000
    psi = heading + sp * rng.standard_normal(n)
    d = dt * (
        speed * np.stack([np.sin(psi), np.cos(psi)], axis=1) + sv * rng.standard_normal((n, 2))
    )
    got = np.cov(d.T)
    q = dvl_increment_covariance(v, dt, sv, sp)
    assert q.shape == (2, 2)
    assert np.allclose(got, q, rtol=0.02, atol=2e-4 * np.trace(q))
    assert not np.allclose(got, dvl_increment_covariance(v, dt, sv, 0.0), rtol=0.02)
    batch = dvl_increment_covariance(np.stack([v, 2 * v]), dt, sv, sp)
    assert batch.shape == (2, 2, 2) and np.allclose(batch[0], q)
    with pytest.raises(NavInputError, match="sigma_heading_rad"):
        dvl_increment_covariance(v, dt, sv, -1.0)
