"""Seed 004's models: the 3-D motion model, the prediction step and the bearings to beacons.

Seed 004 (Miller, Miller & Miller 2019) measures its angles in the mathematical convention: theta
is the azimuth of the velocity from the x axis, counter-clockwise, and gamma its elevation up from
the horizontal plane (z up); the navigation angles of the other seeds are in :mod:`nav.angles`.
Every array carries a leading axis of Monte Carlo paths: positions ``(n, 3)`` m in the world frame
(x, y, z up), covariances ``(n, 3, 3)`` m^2, controls ``(n, 3)`` = (gamma rad, theta rad, V m/s).

Bearings (eq. 17). For each beacon at ``X_B`` the observation is the pair of tangents
``(tan phi, tan lambda)`` with ``tan phi = (Y_B - Y) / (X_B - X)`` and ``tan lambda = (Z_B - Z) cos
phi / (X_B - X)``. This module reads phi as the full bearing of the beacon (its quadrant given by
the sign of ``X_B - X``), so ``cos phi / (X_B - X) = 1 / rho`` with ``rho`` the horizontal
distance, and ``tan lambda = (Z_B - Z) / rho`` is the tangent of the beacon's elevation, the form
eq. 24 writes for the CMNF. A pair is *absent* (no observation) when the beacon is (almost)
straight above or below the vehicle (``rho < min_rho_m``) or when ``|tan phi|`` exceeds ``max_tan``
(the beacon almost abeam of the x axis); the filters leave absent pairs out, so no NaN is made.

The prediction step is pluggable (:class:`Prediction`): "by virtue of the system" (eq. 1,
:class:`SystemPrediction`) or a dead-reckoning shift with its own error covariance (seed 004,
section 4; supplied by another module with the same call signature).

The bearings as a measurement of :mod:`nav.ekf` (:class:`BearingTangents`): the model carries
its beacons, its noise and which pairs were measured, so the EKF on the bearings is
:func:`nav.ekf.update` with this model (:func:`nav.bearings.filters.ekf_update`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from nav import dead_reckoning
from nav.errors import NavInputError

Array = NDArray[np.float64]

MIN_RHO_M = 1e-3
"""Default horizontal distance below which a beacon counts as straight above/below, m."""
MAX_TAN = 1e3
"""Default largest |tan phi| that makes an observation (about 89.94 deg off the x axis)."""


# ----------------------------------------------------------------------------------------------
# Motion (eq. 1-2)


def velocity(u: Array) -> Array:
    """Velocity vector of a control (seed 004, eq. 2).

    Args:
        u: controls, shape ``(..., 3)``: gamma (elevation up from horizontal, rad), theta (from
            the x axis counter-clockwise, rad), V (speed, m/s).

    Returns:
        ``V (cos gamma cos theta, cos gamma sin theta, sin gamma)``, shape ``(..., 3)``, m/s,
        world frame.
    """
    u = np.asarray(u, dtype=float)
    g, th, v = u[..., 0], u[..., 1], u[..., 2]
    cg = np.cos(g)
    return np.stack([v * cg * np.cos(th), v * cg * np.sin(th), v * np.sin(g)], axis=-1)


def step(x: Array, u: Array, dt: float, w: Array | None = None) -> Array:
    """One step of the motion model ``X_{k+1} = X_k + V_k(u_k) dt + W_k`` (seed 004, eq. 1).

    Args:
        x: positions, shape ``(n, 3)``, m.
        u: controls, shape ``(n, 3)`` or ``(3,)`` (see :func:`velocity`).
        dt: step, s.
        w: the disturbance ``W_k``, shape ``(n, 3)``, m (none: the noise-free step).

    Returns:
        The positions at the next step, shape ``(n, 3)``, m.
    """
    out = np.asarray(x, dtype=float) + velocity(u) * dt
    return out if w is None else out + w


def nominal_path(gamma: Array, theta: Array, speed: Array, x0: Array, dt: float) -> Array:
    """The noise-free path of a control sequence (seed 004, eq. 3).

    Args:
        gamma, theta, speed: the nominal controls at t_0 .. t_{N-1}, shape ``(N,)`` (rad, rad,
            m/s).
        x0: the start, shape ``(3,)``, m.
        dt: step, s.

    Returns:
        Positions at t_0 .. t_N, shape ``(N + 1, 3)``, m.
    """
    u = np.stack([np.asarray(gamma), np.asarray(theta), np.asarray(speed)], axis=-1)
    steps = velocity(u) * dt
    return dead_reckoning.track(np.asarray(x0, float)[None], steps[None])[0]


# ----------------------------------------------------------------------------------------------
# Prediction (pluggable)


@dataclass(frozen=True)
class PredictedShift:
    """The prediction of one step: the displacement the filter adds to its estimate.

    Attributes:
        displacement_m: shape ``(n, 3)``, m, world frame: ``X~_{k+1} - X^_k``.
        covariance_m2: error covariance of the displacement, shape ``(3, 3)`` or ``(n, 3, 3)``,
            m^2 (eq. 1's ``S^W`` for the prediction by virtue of the system).
    """

    displacement_m: Array
    covariance_m2: Array


class Prediction(Protocol):
    """A prediction step: ``(k, estimate (n, 3) m, control (n, 3)) -> PredictedShift``.

    ``k`` is the index of the step the estimate belongs to (the prediction is for ``k + 1``).
    The closed loops call it after the truth has moved to ``t_{k+1}``, so an implementation that
    senses the shift (the seabed-sensing dead reckoning of eq. 15-16, which needs the acoustic
    images of ``t_k`` and ``t_{k+1}``) can read its sensor's data of ``t_{k+1}`` through its own
    reference to that sensor; it never sees the truth. Implementations:
    :class:`SystemPrediction` (seed 004, eq. 1, "by virtue of the system"); the seabed DR returns
    its shift estimate (eq. 15) and the covariance of its error.
    """

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift: ...


@dataclass(frozen=True)
class SystemPrediction:
    """Prediction by virtue of the system: displacement ``V_k(u_k) dt``, covariance ``S^W``
    (seed 004, eq. 1 and section 6).

    Attributes:
        dt: step, s.
        s_w: ``S^W``, shape ``(3, 3)``, m^2.
    """

    dt: float
    s_w: Array

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift:
        return PredictedShift(velocity(u) * self.dt, np.asarray(self.s_w, dtype=float))


# ----------------------------------------------------------------------------------------------
# Bearings (eq. 17)


def check_beacons(beacons: Array) -> Array:
    """Beacon positions as a ``(B, 3)`` float array, m.

    Raises:
        NavInputError: if the shape is not ``(B, 3)`` with ``B >= 1`` or a value is not finite.
    """
    b = np.asarray(beacons, dtype=float)
    if b.ndim != 2 or b.shape[1] != 3 or len(b) == 0 or not np.isfinite(b).all():
        raise NavInputError(f"beacons: shape {b.shape} must be (B >= 1, 3), finite, m")
    return b


def _offsets(x: Array, beacons: Array) -> tuple[Array, Array, Array, Array]:
    x = np.asarray(x, dtype=float)
    dx = beacons[:, 0] - x[:, 0:1]  # (n, B), contiguous
    dy = beacons[:, 1] - x[:, 1:2]
    dz = beacons[:, 2] - x[:, 2:3]
    rho = np.sqrt(dx * dx + dy * dy)
    return dx, dy, dz, rho


def observable(
    x: Array, beacons: Array, min_rho_m: float = MIN_RHO_M, max_tan: float = MAX_TAN
) -> NDArray[np.bool_]:
    """Which beacon pairs make an observation at these positions.

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.
        min_rho_m: a beacon closer than this horizontally is straight above/below: absent, m.
        max_tan: ``|tan phi|`` above this is absent.

    Returns:
        Shape ``(n, B)``: True where the pair exists.
    """
    dx, dy, _, rho = _offsets(x, beacons)
    return (rho >= min_rho_m) & (np.abs(dy) <= max_tan * np.abs(dx))


def bearings(x: Array, beacons: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Noise-free bearing tangents (seed 004, eq. 17, phi the full bearing; module docstring).

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.

    Returns:
        ``(h, present)``: h of shape ``(n, B, 2)`` = (tan phi, tan lambda) per beacon (0 where
        absent) and ``present`` of shape ``(n, B)`` (:func:`observable` with its defaults).
    """
    dx, dy, dz, rho = _offsets(x, beacons)
    ok = (rho >= MIN_RHO_M) & (np.abs(dy) <= MAX_TAN * np.abs(dx))
    h = np.empty((*dx.shape, 2))
    if ok.all():
        np.divide(dy, dx, out=h[..., 0])
        np.divide(dz, rho, out=h[..., 1])
        return h, ok
    h[..., 0] = np.where(ok, dy / np.where(ok, dx, 1.0), 0.0)
    h[..., 1] = np.where(ok, dz / np.where(ok, rho, 1.0), 0.0)
    return h, ok


def bearing_jacobian(x: Array, beacons: Array) -> Array:
    """Jacobian of :func:`bearings` with respect to the position.

    Args:
        x: positions, shape ``(n, 3)``, m.
        beacons: shape ``(B, 3)``, m.

    Returns:
        Shape ``(n, B, 2, 3)``, 1/m: rows d(tan phi)/dX and d(tan lambda)/dX per beacon (0 where
        the pair is absent).
    """
    dx, dy, dz, rho = _offsets(x, beacons)
    ok = (rho >= MIN_RHO_M) & (np.abs(dy) <= MAX_TAN * np.abs(dx))
    sdx = np.where(ok, dx, 1.0)
    srho = np.where(ok, rho, 1.0)
    zero = np.zeros_like(dx)
    r1 = np.stack([dy / sdx**2, -1.0 / sdx, zero], axis=-1)
    r3 = srho**3
    r2 = np.stack([dz * dx / r3, dz * dy / r3, -1.0 / srho], axis=-1)
    jac = np.stack([r1, r2], axis=-2)
    return np.where(ok[..., None, None], jac, 0.0)


@dataclass(frozen=True)
class BearingTangents:
    """The bearing tangents of every beacon as a measurement of the one EKF update (a
    :class:`nav.ekf.MeasurementModel`; seed 004, eq. 17).

    The measurement vector of a path stacks the pairs: ``z = (tan phi_1, tan lambda_1, ..., tan
    phi_B, tan lambda_B)``, shape ``(n, 2 B)``. A pair takes part where it was measured
    (``present``) and is observable at the state (:func:`observable` with its defaults); the other
    components are inactive and left out of the update exactly.

    Attributes:
        beacons_m: beacon positions, shape ``(B, 3)``, m, world frame.
        s_eps: ``S^eps``, shape ``(2, 2)``: covariance of one pair's tangent noise.
        present: shape ``(n, B)``: which pairs were measured.
    """

    beacons_m: Array
    s_eps: Array
    present: NDArray[np.bool_]

    def h(self, x: Array) -> Array:
        """Noise-free tangents at the states ``x`` ``(n, 3)`` m, shape ``(n, 2 B)`` (0 where
        absent)."""
        h, _ = bearings(x, self.beacons_m)
        return h.reshape(len(h), -1)

    def H(self, x: Array) -> Array:
        """Jacobian of :meth:`h`, shape ``(n, 2 B, 3)``, 1/m."""
        jac = bearing_jacobian(x, self.beacons_m)
        return jac.reshape(len(jac), -1, 3)

    def R(self) -> Array:
        """Noise covariance, shape ``(2 B, 2 B)``: ``S^eps`` per pair, pairs independent."""
        return np.kron(np.eye(len(self.beacons_m)), np.asarray(self.s_eps, dtype=float))

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``, shape ``(n, 2 B)`` (tangents, no wrapping)."""
        return z - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Components that take part, shape ``(n, 2 B)``: the pair measured and observable."""
        use = observable(x, self.beacons_m) & self.present
        return np.repeat(use, 2, axis=1)
