"""Navigation with a Doppler velocity log (DVL): its velocity as a measurement of the EKF and as
the input of dead reckoning.

A DVL in bottom lock reports the velocity over the seabed of its transducer in the vehicle's
body axes (FLU: x forward, y port, z up). The velocity over ground of the vehicle's reference
point in the world frame (ENU) is the reported one with the lever arm's rotation term removed,
rotated by the MEASURED attitude (compass/INS, not the truth):

``v_ref_world = R(att) (v_dvl_body - omega x r)``  (rigid body: ``v_dvl = v_ref + omega x r``)

with ``R = R_world_from_body`` of roll (starboard down +), pitch (nose up +) and heading
(clockwise from north) (:func:`nav.angles.rotation_world_from_body`, the convention of the
simulator's frames reproduced in :mod:`nav`, which imports no simulator), ``omega`` the body
angular velocity (rad/s, body FLU) and ``r`` the transducer's lever arm from the reference point
(m, body FLU).

Three uses:

* **EKF update** (:class:`DvlVelocityMeasurement`): on the state of
  :class:`nav.models.CurrentAwareMotion` (position and current), the predicted DVL velocity is the
  velocity through water (log speed and heading) plus the current, rotated into body axes, plus
  the lever-arm term; the update (:func:`nav.ekf.update`, batched, or
  :meth:`nav.navigator.OnlineNavigator.fuse`, online) estimates the current, and with it the
  drift of the position between fixes, beside USBL, GPS and depth.
* **Dead reckoning, batched** (:func:`dvl_increments`, :func:`dvl_track`): the world velocities
  of a batch of pings integrated by the trapezoid rule through :mod:`nav.dead_reckoning`.
* **Dead reckoning and EKF on velocity over ground** (:class:`GroundVelocityMotion`): a motion
  model whose input is the velocity over ground (``f``, ``F``, ``Q``, ``increment_one``,
  ``predict_one`` like :mod:`nav.models`' models), for :class:`nav.dead_reckoning.DeadReckoning`,
  :class:`nav.ekf.BatchEKF`/:class:`nav.ekf.SingleRunEKF` and
  :meth:`nav.navigator.OnlineNavigator.advance`.

References:
    Rigid-body velocity transport ``v_P = v_O + omega x r_OP`` (the DVL's lever-arm term);
    DVL-aided navigation: Kinsey, Eustice & Whitcomb, "A survey of underwater vehicle
    navigation: recent advances and new challenges", IFAC MCMC 2006; the EKF of seed 000
    (eq. 17-23) with the current in the state as in :class:`nav.models.CurrentAwareMotion`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import rotation_world_from_body
from nav.dead_reckoning import DeadReckonedTrack, track_with_covariance
from nav.errors import NavInputError

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _lever_term(
    angular_velocity_body_rad_s: ArrayLike | None, lever_arm_body_m: ArrayLike | None
) -> Array | float:
    """``omega x r``, shape (..., 3), m/s, body FLU (0.0 when either is absent)."""
    if angular_velocity_body_rad_s is None or lever_arm_body_m is None:
        return 0.0
    w = np.asarray(angular_velocity_body_rad_s, dtype=float)
    r = np.asarray(lever_arm_body_m, dtype=float)
    return np.cross(w, r)


def velocity_world_from_dvl(
    velocity_body_m_s: ArrayLike,
    roll_pitch_heading_rad: ArrayLike,
    angular_velocity_body_rad_s: ArrayLike | None = None,
    lever_arm_body_m: ArrayLike | None = None,
) -> Array:
    """World velocity over ground of the reference point from a DVL velocity:
    ``R(att) (v_dvl - omega x r)``.

    Args:
        velocity_body_m_s: the DVL's velocity over ground at the transducer, shape (..., 3), m/s,
            body FLU (bottom lock; a water-track velocity gives the velocity through water).
        roll_pitch_heading_rad: the measured attitude at the ping, shape (..., 3), rad
            (:func:`nav.angles.rotation_world_from_body`).
        angular_velocity_body_rad_s: body angular velocity (p, q, r), shape (..., 3), rad/s,
            body FLU, or ``None`` (zero).
        lever_arm_body_m: the transducer relative to the reference point, shape (..., 3), m,
            body FLU, or ``None`` (at the reference point).

    Returns:
        Velocity ``(east, north, up)``, shape of the broadcast (..., 3), m/s, world ENU.

    Raises:
        NavInputError: if an array does not end in an axis of 3.
    """
    v = np.asarray(velocity_body_m_s, dtype=float)
    if v.shape[-1:] != (3,):
        raise NavInputError(f"velocity_body_m_s must end in an axis of 3, not shape {v.shape}")
    R = rotation_world_from_body(roll_pitch_heading_rad)
    v_ref = v - _lever_term(angular_velocity_body_rad_s, lever_arm_body_m)
    return np.einsum("...ij,...j->...i", R, v_ref)


@dataclass(frozen=True)
class DvlVelocityMeasurement:
    """The DVL's bottom-track velocity as a measurement of the current (a measurement model of
    :mod:`nav.models`' kind: ``h``, ``H``, ``R``, ``residual``, ``active``).

    On a state ``x = (east, north, up, c_east, c_north, ...)`` (:class:`nav.models.
    CurrentAwareMotion`; the current at ``current_index``), the DVL velocity at the transducer in
    body axes is predicted as

    ``h(x) = R(att)^T (v_water_world + (c_e, c_n, 0)) + omega x r``,
    ``v_water_world = (S sin(heading), S cos(heading), w)``

    with ``S`` the log's horizontal speed through water and the heading at the ping (the inputs
    :class:`nav.models.CurrentAwareMotion` moves the vehicle with), ``w`` the vertical velocity
    (up +, e.g. minus the pressure depth's rate; zero by default), ``att`` the measured attitude.
    ``h`` is linear in the current: ``H = dh/dx`` holds the first two columns of ``R^T`` in the
    current's columns and zeros elsewhere (the velocity says nothing of the position itself; the
    position gains through its correlation with the current).

    The noise is the DVL's (``sigma_m_s`` per body axis) plus the errors of the other inputs of
    ``h``, propagated to first order: the log's and the vertical rate's through
    ``v_water_world``, and the heading's through ``R^T c`` (``R^T v_water_world`` does not depend
    on the heading: both turn with it), ``d(R^T c)/d heading = R^T (e_z x c) = R^T (-c_n, c_e,
    0)``:

    ``R = sigma^2 I + sigma_S^2 b b^T + sigma_w^2 e e^T + sigma_h^2 g g^T``

    with ``b = R^T (sin h, cos h, 0)``, ``e = R^T (0, 0, 1)`` and ``g = R^T (-c_n, c_e, 0)`` at
    ``current_for_noise_m_s`` (``R`` cannot depend on the state in :mod:`nav.ekf`: the caller
    gives the current to linearise about, e.g. the filter's estimate when the ping arrives; the
    term is ``|c| sigma_h``, 5 mm/s for 0.3 m/s and 1 deg). A log whose noise is the same sample
    as the prediction's input correlates the two; it is small beside the DVL's where ``sigma_S``
    is a few cm/s (the NEES test of ``tests/nav/test_dvl_ekf.py`` runs with it).

    Bottom-lock pings only: a water-track ping measures the velocity through water, which holds
    nothing of this state (its ``h`` would not depend on ``x``); through a water-track spell a
    navigator dead-reckons on the water velocity plus its current estimate.

    The attitude, speeds and rates are one run's (shapes (3,) and scalars: ``R()`` is (3, 3), for
    :meth:`nav.navigator.OnlineNavigator.fuse`) or a batch's (shapes (n, 3) and (n,): ``R()`` is
    (n, 3, 3), for :func:`nav.ekf.update_with`).

    Attributes:
        roll_pitch_heading_rad: measured attitude at the ping, shape (3,) or (n, 3), rad.
        speed_through_water_m_s: log speed (horizontal, through water) at the ping, m/s, scalar
            or shape (n,).
        sigma_m_s: DVL velocity standard deviation per body axis, m/s (> 0).
        sigma_speed_m_s: log speed standard deviation, m/s (>= 0).
        vertical_velocity_m_s: vertical velocity at the ping, up +, m/s, scalar or (n,).
        sigma_vertical_m_s: its standard deviation, m/s (>= 0).
        angular_velocity_body_rad_s: body angular velocity, shape (3,) or (n, 3), rad/s, or
            ``None`` (zero).
        lever_arm_body_m: transducer from the reference point, shape (3,), m, body FLU, or
            ``None``.
        current_index: index of ``c_east`` in the state (``c_north`` follows).
        sigma_heading_rad: the measured heading's standard deviation, rad (>= 0).
        current_for_noise_m_s: the current ``(c_east, c_north)`` the heading's term of ``R`` is
            linearised about, shape (2,) or (n, 2), m/s, or ``None`` (no heading term).
    """

    roll_pitch_heading_rad: Array
    speed_through_water_m_s: float | Array
    sigma_m_s: float
    sigma_speed_m_s: float = 0.0
    vertical_velocity_m_s: float | Array = 0.0
    sigma_vertical_m_s: float = 0.0
    angular_velocity_body_rad_s: Array | None = None
    lever_arm_body_m: Array | None = None
    current_index: int = 3
    sigma_heading_rad: float = 0.0
    current_for_noise_m_s: Array | None = None
    _R_wb: Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.sigma_m_s > 0:
            raise NavInputError(f"sigma_m_s = {self.sigma_m_s}: must be > 0")
        for name in ("sigma_speed_m_s", "sigma_vertical_m_s", "sigma_heading_rad"):
            if not getattr(self, name) >= 0:
                raise NavInputError(f"{name} = {getattr(self, name)}: must be >= 0")
        att = np.asarray(self.roll_pitch_heading_rad, dtype=float)
        if att.ndim not in (1, 2) or att.shape[-1] != 3 or not np.isfinite(att).all():
            raise NavInputError(
                f"roll_pitch_heading_rad must be finite, shape (3,) or (n, 3), not {att.tolist()}"
            )
        for name in ("speed_through_water_m_s", "vertical_velocity_m_s"):
            if not np.isfinite(np.asarray(getattr(self, name), dtype=float)).all():
                raise NavInputError(f"{name} = {getattr(self, name)}: must be finite")
        if self.current_for_noise_m_s is not None:
            c = np.asarray(self.current_for_noise_m_s, dtype=float)
            if c.ndim not in (1, 2) or c.shape[-1] != 2 or not np.isfinite(c).all():
                raise NavInputError(
                    f"current_for_noise_m_s must be finite, shape (2,) or (n, 2), not {c.tolist()}"
                )
        object.__setattr__(self, "_R_wb", rotation_world_from_body(att))

    def _water_world(self) -> Array:
        """``v_water_world``, shape (3,) or (n, 3), m/s, world."""
        h = np.asarray(self.roll_pitch_heading_rad, dtype=float)[..., 2]
        s = np.asarray(self.speed_through_water_m_s, dtype=float)
        w = np.asarray(self.vertical_velocity_m_s, dtype=float)
        s, w, h = np.broadcast_arrays(s, w, h)
        return np.stack([s * np.sin(h), s * np.cos(h), w], axis=-1)

    def _check(self, x: Array) -> Array:
        x = np.asarray(x, dtype=float)
        if x.shape[-1] < self.current_index + 2:
            raise NavInputError(
                f"state of length {x.shape[-1]} has no current at current_index = "
                f"{self.current_index} (DvlVelocityMeasurement needs CurrentAwareMotion's state)"
            )
        return x

    def h(self, x: Array) -> Array:
        """Predicted DVL velocity, shape (n, 3), m/s, body FLU at the transducer."""
        x = self._check(x)
        i = self.current_index
        v_ground = self._water_world() + np.concatenate(
            [x[..., i : i + 2], np.zeros((*x.shape[:-1], 1))], axis=-1
        )
        body = np.einsum("...ji,...j->...i", self._R_wb, v_ground)  # R^T v
        return body + _lever_term(self.angular_velocity_body_rad_s, self.lever_arm_body_m)

    def H(self, x: Array) -> Array:
        """Jacobian ``dh/dx``, shape (n, 3, d): ``R^T``'s first two columns in the current's."""
        x = self._check(x)
        i = self.current_index
        H = np.zeros((*x.shape[:-1], 3, x.shape[-1]))
        Rt = np.swapaxes(self._R_wb, -1, -2)
        H[..., :, i : i + 2] = Rt[..., :, :2]
        return H

    def R(self) -> Array:
        """Measurement noise, shape (3, 3) (one run) or (n, 3, 3), (m/s)^2 (class docstring)."""
        Rt = np.swapaxes(self._R_wb, -1, -2)
        h = np.asarray(self.roll_pitch_heading_rad, dtype=float)[..., 2]
        horiz = np.stack([np.sin(h), np.cos(h), np.zeros_like(h)], axis=-1)
        b = np.einsum("...ij,...j->...i", Rt, horiz)
        e = Rt[..., :, 2]
        out = (
            self.sigma_m_s**2 * np.eye(3)
            + self.sigma_speed_m_s**2 * b[..., :, None] * b[..., None, :]
            + self.sigma_vertical_m_s**2 * e[..., :, None] * e[..., None, :]
        )
        if self.current_for_noise_m_s is not None and self.sigma_heading_rad > 0:
            c = np.asarray(self.current_for_noise_m_s, dtype=float)
            ez_x_c = np.stack([-c[..., 1], c[..., 0], np.zeros(c.shape[:-1])], axis=-1)
            g = np.einsum("...ij,...j->...i", Rt, ez_x_c)
            out = out + self.sigma_heading_rad**2 * g[..., :, None] * g[..., None, :]
        return out

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``, shape (n, 3), m/s."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> BoolArray:
        """All three components, shape (n, 3)."""
        return np.ones((*np.shape(x)[:-1], 3), dtype=bool)


def _hold_last_valid(v: Array, valid: BoolArray) -> Array:
    """``v`` (n, k, 3) with each invalid sample replaced by the run's last valid one (zero
    before the first)."""
    k = v.shape[1]
    idx = np.where(valid, np.arange(k)[None, :], -1)
    last = np.maximum.accumulate(idx, axis=1)  # (n, k): last valid sample at or before
    held = np.take_along_axis(v, np.maximum(last, 0)[..., None], axis=1)
    return np.where((last >= 0)[..., None], held, 0.0)


def dvl_increment_covariance(
    velocity_en_m_s: ArrayLike,
    dt_s: float,
    sigma_velocity_m_s: float,
    sigma_heading_rad: float = 0.0,
) -> Array:
    """Covariance of each ping's horizontal DR displacement ``dt v``, m^2.

    The displacement ``dt R(psi) v_body`` (first order in the errors) has the velocity's white
    error ``sigma_v^2 I`` per horizontal component and, from a white heading error, ``sigma_psi^2
    w w^T`` with ``w = d(R v)/d psi = (v_north, -v_east)`` (the heading clockwise from north turns
    east into north): ``Q = dt^2 (sigma_v^2 I + sigma_psi^2 w w^T)``. Independent pings add, so
    the covariance over several pings is the sum of theirs. A bias or a scale factor is not white
    and is not in it.

    Args:
        velocity_en_m_s: (east, north) velocity over ground of each ping, shape (..., 2), m/s.
        dt_s: the ping's duration, s.
        sigma_velocity_m_s: noise of each horizontal velocity component, m/s.
        sigma_heading_rad: white heading noise per ping, rad.

    Returns:
        Shape (..., 2, 2), m^2.

    Raises:
        NavInputError: if the velocity's last axis is not 2 or a value is not finite, or a
            sigma or ``dt_s`` is negative.
    """
    v = np.asarray(velocity_en_m_s, dtype=float)
    if v.shape[-1:] != (2,) or not np.all(np.isfinite(v)):
        raise NavInputError(
            f"velocity_en_m_s of shape {v.shape}: must be (..., 2) finite (east, north), m/s"
        )
    for name, value in (
        ("dt_s", dt_s),
        ("sigma_velocity_m_s", sigma_velocity_m_s),
        ("sigma_heading_rad", sigma_heading_rad),
    ):
        if not (np.isfinite(value) and value >= 0.0):
            raise NavInputError(f"{name} = {value}: must be finite and >= 0")
    w = np.stack([v[..., 1], -v[..., 0]], axis=-1)
    ww = w[..., :, None] * w[..., None, :]
    return dt_s**2 * (sigma_velocity_m_s**2 * np.eye(2) + sigma_heading_rad**2 * ww)


def dvl_increments(
    velocity_world_m_s: ArrayLike, t_s: ArrayLike, valid: ArrayLike | None = None
) -> Array:
    """Displacements between DVL pings by the trapezoid rule, for
    :func:`nav.dead_reckoning.track`.

    ``dx_j = (t_j - t_{j-1}) (v_{j-1} + v_j) / 2`` for ``j >= 1`` and ``dx_0 = 0``, so that
    ``track(x0, inc)[:, 1:]`` (or ``track(x0, inc[:, 1:])``) is the position at each ping. A
    ping without a velocity (``valid`` False: no bottom lock) takes the last valid velocity of its
    run (zero before the first), the usual hold of a DVL navigator through a drop-out.

    Args:
        velocity_world_m_s: world velocity over ground of the reference point at each ping
            (:func:`velocity_world_from_dvl`), shape (n, k, 3), m/s, world ENU.
        t_s: ping times, shape (k,), s, increasing.
        valid: which pings have a velocity, shape (n, k), or ``None`` (all).

    Returns:
        Displacements, shape (n, k, 3), m, world; the first row zero.

    Raises:
        NavInputError: on mismatched shapes, times not increasing, or non-finite valid
            velocities.
    """
    v = np.asarray(velocity_world_m_s, dtype=float)
    t = np.asarray(t_s, dtype=float)
    if v.ndim != 3 or t.shape != (v.shape[1],):
        raise NavInputError(
            f"velocity_world_m_s (n, k, d) and t_s (k,) must match, not shapes {v.shape} "
            f"and {t.shape}"
        )
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise NavInputError("t_s must be strictly increasing")
    if valid is not None:
        ok = np.asarray(valid, dtype=bool)
        if ok.shape != v.shape[:2]:
            raise NavInputError(f"valid must have shape {v.shape[:2]}, not {ok.shape}")
        v = _hold_last_valid(np.where(ok[..., None], v, 0.0), ok)
    if not np.isfinite(v).all():
        raise NavInputError("velocity_world_m_s holds non-finite valid samples")
    inc = np.zeros(v.shape)
    dt = np.diff(t)[None, :, None]
    inc[:, 1:] = 0.5 * dt * (v[:, :-1] + v[:, 1:])
    return inc


def dvl_track(
    start_m: ArrayLike,
    velocity_world_m_s: ArrayLike,
    t_s: ArrayLike,
    sigma_velocity_m_s: float = 0.0,
    valid: ArrayLike | None = None,
    start_cov_m2: ArrayLike | None = None,
) -> DeadReckonedTrack:
    """Dead reckoning on DVL velocity over a batch of runs, one sample per ping.

    The positions are :func:`nav.dead_reckoning.track_with_covariance` of
    :func:`dvl_increments`; the covariance grows by :class:`GroundVelocityMotion`'s ``Q`` per
    step (``dt^2 sigma_v^2`` on each axis: a white velocity error held over the step; a DVL's
    bias, which does not average out, is not in it).

    Args:
        start_m: position at the first ping, shape (n, 3) or (3,), m, world.
        velocity_world_m_s: world velocity over ground at each ping, shape (n, k, 3), m/s.
        t_s: ping times, shape (k,), s.
        sigma_velocity_m_s: velocity standard deviation per axis, m/s (>= 0).
        valid: which pings have a velocity, shape (n, k), or ``None`` (all).
        start_cov_m2: covariance at the first ping, shape (n, 3, 3) or (3, 3), m^2, or ``None``.

    Returns:
        The tracks at the k pings: ``position_m`` (n, k, 3), ``cov_m2`` (n, k, 3, 3).

    Raises:
        NavInputError: as :func:`dvl_increments`, or for a negative sigma.
    """
    if not sigma_velocity_m_s >= 0:
        raise NavInputError(f"sigma_velocity_m_s = {sigma_velocity_m_s}: must be >= 0")
    inc = dvl_increments(velocity_world_m_s, t_s, valid)[:, 1:]
    n, T, d = inc.shape
    dt = np.diff(np.asarray(t_s, dtype=float))
    q = np.zeros((n, T, d, d))
    idx = np.arange(d)
    q[:, :, idx, idx] = (dt**2 * sigma_velocity_m_s**2)[None, :, None]
    start = np.broadcast_to(np.asarray(start_m, dtype=float), (n, d))
    return track_with_covariance(start, inc, q, start_cov_m2)


@dataclass(frozen=True)
class GroundVelocityMotion:
    """Motion driven by the velocity over ground (a DVL's, :func:`velocity_world_from_dvl`).

    ``u = (v_east, v_north, dz)``: the world velocity over ground held over the step (m/s) and
    the depth change over the step (m, positive down; the state's third component is up).
    ``f(x, u) = x + (dt v_e, dt v_n, -dz)``, ``F = I`` and ``Q = diag(dt^2 sigma_v^2,
    dt^2 sigma_v^2, sigma_dz^2)``: no current in the state (the DVL's velocity already holds it).

    Attributes:
        sigma_velocity_m_s: standard deviation of each horizontal velocity component the filter
            assumes, m/s.
        sigma_depth_change_m: depth-change standard deviation per step, m.
    """

    sigma_velocity_m_s: float
    sigma_depth_change_m: float

    dim: ClassVar[int] = 3
    """Length of the state: the position."""
    current_components: ClassVar[slice | None] = None
    """No current in the state."""

    def increment(self, u: Array, dt_s: float | Array) -> Array:
        """Displacement over one step, shape (..., 3), m, world.

        Args:
            u: ``(v_east, v_north, dz)``, shape (..., 3).
            dt_s: step duration, s.
        """
        u = np.asarray(u, dtype=float)
        return np.stack([dt_s * u[..., 0], dt_s * u[..., 1], -u[..., 2]], axis=-1)

    def increment_one(self, u: Array, dt_s: float) -> Array:
        """:meth:`increment` of one run: ``u`` shape (3,), displacement shape (3,), m."""
        return np.array([dt_s * u[0], dt_s * u[1], -u[2]], dtype=float)

    def f(self, x: Array, u: Array, dt_s: float) -> Array:
        """Predicted state, shape (n, 3)."""
        return np.asarray(x, dtype=float) + self.increment(u, dt_s)

    def F(self, x: Array, u: Array, dt_s: float) -> Array:
        """State Jacobian, the identity, shape (n, 3, 3)."""
        return np.broadcast_to(np.eye(3), (np.shape(x)[0], 3, 3))

    def Q(self, u: Array, dt_s: float | Array) -> Array:
        """Process noise, shape (..., 3, 3), m^2."""
        q = np.zeros((*np.shape(u)[:-1], 3, 3))
        q[..., 0, 0] = q[..., 1, 1] = (dt_s * self.sigma_velocity_m_s) ** 2
        q[..., 2, 2] = self.sigma_depth_change_m**2
        return q

    def predict_one(self, x: Array, P: Array, u: Array, dt_s: float) -> tuple[Array, Array]:
        """One prediction of one run in closed form (``F = I``): ``(f(x, u), P + Q)``.

        Args:
            x: state, shape (1, 3), m, world.
            P: covariance, shape (1, 3, 3), m^2.
            u: input ``(v_e, v_n, dz)``, shape (1, 3).
            dt_s: step duration, s.

        Returns:
            ``(x-, P-)``, shapes (1, 3) and (1, 3, 3).
        """
        x_new = x + self.increment_one(u[0], dt_s)[None]
        P_new = P[0].copy()
        qv = (dt_s * self.sigma_velocity_m_s) ** 2
        P_new[0, 0] = P_new[0, 0] + qv
        P_new[1, 1] = P_new[1, 1] + qv
        P_new[2, 2] = P_new[2, 2] + self.sigma_depth_change_m**2
        return x_new, P_new[None]
