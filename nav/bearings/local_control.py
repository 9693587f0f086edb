"""Seed 004: the locally optimal path-following control (eq. 5-7), unbounded and with box limits.

The control ``u = (gamma, theta, V)`` (seed 004's mathematical angles: theta from the x axis
counter-clockwise, gamma up from the horizontal; :mod:`nav.bearings`) that minimises the expected
squared distance to the next nominal point, ``J(u) = E ||X°_{k+1} - X_{k+1}(u)||^2`` (eq. 4),
aims at ``d = X°_k - X_k + dt V°_k`` (eq. 6; with the estimate in place of the position, eq. 7):
``theta = atan2(d_y, d_x)``, ``gamma = atan2(d_z, sqrt(d_x^2 + d_y^2))``, ``V = |d| / dt``. The
printed ``gamma = atan2(d_z, d_x / cos theta)`` equals this only for ``cos theta > 0``; the
horizontal distance is right in every quadrant (seed README).

With limits (a real vehicle), theta and gamma may move at most a turn rate and a pitch rate from
the previous command, gamma stays within ``+-max_gamma`` and V within ``[v_min, v_max]``. The
problem then still has an exact solution: ``||d - V dt e||^2 = |d|^2 - 2 V dt (d . e) + V^2 dt^2``,
so for any ``V > 0`` the best direction maximises ``d . e = cos(gamma) rho cos(theta - theta_d) +
sin(gamma) d_z``; with ``cos(gamma) > 0`` the best theta is the point of its interval nearest to
``theta_d`` (circularly), then ``d . e = R cos(gamma - gamma_0)`` is unimodal in gamma and the best
gamma is ``gamma_0`` clipped to its interval, and finally ``V = clip(d . e / dt, v_min, v_max)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]


def aim(x_hat: Array, x_nominal: Array, v_nominal: Array, dt: float) -> Array:
    """The vector the locally optimal control covers in one step (seed 004, eq. 6-7).

    Args:
        x_hat: positions or estimates at t_k, shape ``(n, 3)``, m.
        x_nominal: the nominal position at t_k, shape ``(3,)`` or ``(n, 3)``, m.
        v_nominal: the nominal velocity at t_k, shape ``(3,)`` or ``(n, 3)``, m/s.
        dt: step, s.

    Returns:
        ``d = X°_k - X^_k + dt V°_k``, shape ``(n, 3)``, m.
    """
    return np.asarray(x_nominal, float) - np.asarray(x_hat, float) + dt * np.asarray(v_nominal)


def optimal_control(x_hat: Array, x_nominal: Array, v_nominal: Array, dt: float) -> Array:
    """The unbounded locally optimal control (seed 004, eq. 6 with the estimate: eq. 7).

    Args:
        x_hat: estimates at t_k, shape ``(n, 3)``, m.
        x_nominal: the nominal position at t_k, shape ``(3,)`` or ``(n, 3)``, m.
        v_nominal: the nominal velocity at t_k, shape ``(3,)`` or ``(n, 3)``, m/s.
        dt: step, s (> 0).

    Returns:
        ``u* = (gamma rad, theta rad, V m/s)``, shape ``(n, 3)``; ``x_hat + V(u*) dt`` is the
        nominal point at t_{k+1}.
    """
    if not dt > 0:
        raise NavInputError(f"dt = {dt}: must be > 0 s")
    d = aim(x_hat, x_nominal, v_nominal, dt)
    rho = np.hypot(d[:, 0], d[:, 1])
    theta = np.arctan2(d[:, 1], d[:, 0])
    gamma = np.arctan2(d[:, 2], rho)
    speed = np.linalg.norm(d, axis=1) / dt
    return np.stack([gamma, theta, speed], axis=1)


@dataclass(frozen=True)
class ControlLimits:
    """Box limits of the locally optimal control (seed 004, section 3: "limits on the
    instantaneous course and speed change").

    Attributes:
        max_turn_rate: largest change of theta per second, rad/s.
        max_pitch_rate: largest change of gamma per second, rad/s.
        max_gamma: largest |gamma|, rad (< pi/2).
        v_min: smallest speed, m/s (>= 0).
        v_max: largest speed, m/s.
    """

    max_turn_rate: float
    max_pitch_rate: float
    max_gamma: float
    v_min: float
    v_max: float

    def __post_init__(self) -> None:
        for name in ("max_turn_rate", "max_pitch_rate"):
            if not getattr(self, name) >= 0:
                raise NavInputError(f"{name} = {getattr(self, name)}: must be >= 0 rad/s")
        if not 0 <= self.max_gamma < np.pi / 2:
            raise NavInputError(f"max_gamma = {self.max_gamma}: must be in [0, pi/2) rad")
        if not 0 <= self.v_min <= self.v_max:
            raise NavInputError(
                f"v_min = {self.v_min}, v_max = {self.v_max}: need 0 <= v_min <= v_max m/s"
            )


def _wrap(a: Array) -> Array:
    return (a + np.pi) % (2 * np.pi) - np.pi


def limited_control(
    x_hat: Array,
    x_nominal: Array,
    v_nominal: Array,
    dt: float,
    u_prev: Array,
    limits: ControlLimits,
) -> Array:
    """The locally optimal control under box limits (seed 004, section 3; exact, module
    docstring).

    Args:
        x_hat: estimates at t_k, shape ``(n, 3)``, m.
        x_nominal: nominal position at t_k, ``(3,)`` or ``(n, 3)``, m.
        v_nominal: nominal velocity at t_k, ``(3,)`` or ``(n, 3)``, m/s.
        dt: step, s (> 0).
        u_prev: the previous command, shape ``(n, 3)`` or ``(3,)`` (gamma, theta, V).
        limits: the box.

    Returns:
        ``(gamma, theta, V)``, shape ``(n, 3)``, minimising eq. 4 inside the box.
    """
    if not dt > 0:
        raise NavInputError(f"dt = {dt}: must be > 0 s")
    d = aim(x_hat, x_nominal, v_nominal, dt)
    n = len(d)
    up = np.broadcast_to(np.asarray(u_prev, float), (n, 3))
    rho = np.hypot(d[:, 0], d[:, 1])
    theta_d = np.arctan2(d[:, 1], d[:, 0])
    dth = limits.max_turn_rate * dt
    off = _wrap(theta_d - up[:, 1])
    theta = up[:, 1] + np.clip(off, -dth, dth)
    a = rho * np.cos(theta - theta_d)  # horizontal part of d . e per cos(gamma)
    gamma0 = np.arctan2(d[:, 2], a)
    dga = limits.max_pitch_rate * dt
    lo = np.clip(up[:, 0] - dga, -limits.max_gamma, limits.max_gamma)
    hi = np.clip(up[:, 0] + dga, -limits.max_gamma, limits.max_gamma)
    inside = (gamma0 >= lo) & (gamma0 <= hi)
    near_lo = np.abs(_wrap(gamma0 - lo)) <= np.abs(_wrap(gamma0 - hi))
    gamma = np.where(inside, gamma0, np.where(near_lo, lo, hi))
    de = np.cos(gamma) * a + np.sin(gamma) * d[:, 2]
    speed = np.clip(de / dt, limits.v_min, limits.v_max)
    return np.stack([gamma, theta, speed], axis=1)
