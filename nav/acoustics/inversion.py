"""Travel times back to geometry, with the sound-speed profile known.

Two inversions a navigator makes when it knows the sea's profile instead of assuming one speed:

* the modem: the horizontal range between two known depths (its own pressure depth and the
  sender's broadcast depth) from a one-way travel time, :func:`range_from_travel_time`;
* the USBL: the position of a transponder from the travel time of its reply and the direction
  the reply arrives from at the transceiver's array, :func:`source_from_arrival` (the ray is
  traced back from the transceiver along the arrival direction for the travel time; by
  reciprocity it ends at the source).

Both work with :class:`nav.acoustics.LayeredMedium` (and :class:`nav.acoustics.Isovelocity`,
where they reduce to ``sqrt((c T)^2 - dz^2)`` and ``receiver + c T u``). Frames: world ENU, z
up, depth = -z; azimuth clockwise from north (seed 000 eq. 15, :mod:`nav.angles`), elevation
positive up.

References:
    F. B. Jensen, W. A. Kuperman, M. B. Porter, H. Schmidt, *Computational Ocean Acoustics*,
    2nd ed., Springer (2011), sec. 3.2 (``dT/dX = p`` along the eigenrays between two depths:
    the ray parameter is the horizontal slowness).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.acoustics.profile import SoundSpeedProfile
from nav.acoustics.propagation import Isovelocity
from nav.acoustics.rays import _BISECTION_STEPS, LayeredMedium
from nav.errors import NavInputError

Array = NDArray[np.float64]

_NEWTON_STEPS = 40


def _layered(medium: LayeredMedium | Isovelocity) -> LayeredMedium:
    if isinstance(medium, LayeredMedium):
        return medium
    if isinstance(medium, Isovelocity):
        return LayeredMedium(SoundSpeedProfile.isovelocity(medium.speed_m_s))
    raise NavInputError(
        f"medium: {type(medium).__name__} is not a LayeredMedium or an Isovelocity medium"
    )


def range_from_travel_time(
    medium: LayeredMedium | Isovelocity,
    depth_a_m: ArrayLike,
    depth_b_m: ArrayLike,
    travel_time_s: ArrayLike,
) -> Array:
    """The horizontal range between two depths whose direct eigenray takes ``travel_time_s``.

    Newton's method on ``T(X) = travel_time_s`` with the exact derivative ``dT/dX = p =
    cos(launch) / c(depth_a)`` (Jensen et al. 2011, sec. 3.2), from the harmonic-mean guess
    ``X0 = sqrt((c_h T)^2 - dz^2)``; T grows with X, so the root is unique.

    Args:
        medium: the sea's medium (the profile the navigator knows).
        depth_a_m: one end's depth, shape (...), m, positive down (the sender's).
        depth_b_m: the other end's depth, shape (...), m.
        travel_time_s: measured one-way travel time, shape (...), s, >= 0.

    Returns:
        Horizontal range, shape of the broadcast arguments, m: 0 where the time is not longer
        than the vertical ray's (a measurement shorter than any ray: noise), NaN where the time
        is longer than the longest direct ray's (past a shadow's edge).

    Raises:
        NavInputError: an unsupported medium, a negative or non-finite time.
    """
    layered = _layered(medium)
    za, zb, t = np.broadcast_arrays(
        np.asarray(depth_a_m, dtype=float),
        np.asarray(depth_b_m, dtype=float),
        np.asarray(travel_time_s, dtype=float),
    )
    if not np.all(np.isfinite(t)) or np.any(t < 0.0):
        raise NavInputError("travel_time_s must be finite and >= 0")
    shape = za.shape
    za, zb, t = za.reshape(-1), zb.reshape(-1), t.reshape(-1)
    profile = layered.profile
    t_vertical = np.abs(profile.slowness_integral(za, zb))
    dz = np.abs(zb - za)
    c_h = profile.harmonic_mean_speed(za, zb)
    x = np.sqrt(np.maximum((c_h * t) ** 2 - dz**2, 0.0))
    active = t > t_vertical
    c_a = profile.speed(za)
    for _ in range(_NEWTON_STEPS):
        idx = np.flatnonzero(active)
        if not idx.size:
            break
        tt, launch, _ = layered.between_depths(za[idx], zb[idx], x[idx])
        p = np.cos(launch) / c_a[idx]
        residual = tt - t[idx]
        step = residual / p
        new = np.maximum(x[idx] - step, 0.5 * x[idx])
        bad = ~np.isfinite(new)
        new = np.where(bad, 0.5 * x[idx], new)
        done = np.abs(new - x[idx]) <= 1e-12 * np.maximum(new, 1.0)
        x[idx] = new
        active[idx[done & ~bad]] = False
    x = np.where(t > t_vertical, x, 0.0)
    check, _, _ = layered.between_depths(za, zb, x)
    ok = np.isfinite(check) & (np.abs(check - t) <= 1e-9 * np.maximum(t, 1e-3))
    x = np.where(ok | (t <= t_vertical), x, np.nan)
    return x.reshape(shape)


def source_from_arrival(
    medium: LayeredMedium | Isovelocity,
    receiver_world_m: ArrayLike,
    azimuth_rad: ArrayLike,
    elevation_rad: ArrayLike,
    travel_time_s: ArrayLike,
) -> Array:
    """Where a source is, from the travel time and the arrival direction of its sound.

    The ray is traced back from the receiver with Snell's invariant ``p = cos(elevation) /
    c(receiver depth)``, leaving upwards when the elevation is positive, for the travel time
    (closed-form layer times, bisection on the depth reached; a ray that turns is followed
    through its turning point once: the direct eigenray turns at most once).

    Args:
        medium: the sea's medium.
        receiver_world_m: receiver (transceiver) position, shape (..., 3), m, world ENU.
        azimuth_rad: azimuth of the arrival direction, shape (...), rad clockwise from north.
        elevation_rad: arrival elevation, shape (...), rad, positive up, in [-pi/2, pi/2].
        travel_time_s: one-way travel time, shape (...), s, >= 0.

    Returns:
        Source position, shape (..., 3), m, world ENU; NaN where the time is longer than the
        direct ray can take (a ray turning twice: not a direct eigenray).

    Raises:
        NavInputError: an unsupported medium, bad shapes, a negative or non-finite time.
    """
    layered = _layered(medium)
    rcv = np.asarray(receiver_world_m, dtype=float)
    if rcv.shape[-1:] != (3,):
        raise NavInputError(f"receiver_world_m: shape {rcv.shape}; the last axis must be 3")
    az, el, t = np.broadcast_arrays(
        np.asarray(azimuth_rad, dtype=float),
        np.asarray(elevation_rad, dtype=float),
        np.asarray(travel_time_s, dtype=float),
    )
    shape = np.broadcast_shapes(rcv.shape[:-1], az.shape)
    rcv = np.broadcast_to(rcv, (*shape, 3)).reshape(-1, 3)
    az, el, t = (np.broadcast_to(a, shape).reshape(-1) for a in (az, el, t))
    if not np.all(np.isfinite(t)) or np.any(t < 0.0):
        raise NavInputError("travel_time_s must be finite and >= 0")
    if not np.all(np.isfinite(el)) or np.any(np.abs(el) > 0.5 * np.pi):
        raise NavInputError("elevation_rad must be finite and in [-pi/2, pi/2]")
    horizontal, depth = _trace(layered, -rcv[:, 2], el, t)
    out = np.column_stack(
        [
            rcv[:, 0] + horizontal * np.sin(az),
            rcv[:, 1] + horizontal * np.cos(az),
            -depth,
        ]
    )
    return out.reshape(*shape, 3)


def _trace(
    medium: LayeredMedium, z0: Array, elevation: Array, travel: Array
) -> tuple[Array, Array]:
    """Horizontal distance and depth reached after ``travel`` along the ray leaving depth
    ``z0`` at ``elevation`` (each (N,))."""
    profile = medium.profile
    n = z0.size
    c0 = profile.speed(z0)
    q = c0 / np.cos(elevation)  # 1/p; huge for vertical rays
    zero = np.zeros(n)
    up = elevation > 0.0
    # Horizontal at the start: the ray is at its vertex and heads to the slower side.
    grad = profile.gradient(z0)
    up = np.where(elevation == 0.0, grad > 0.0, up)
    reach = float(np.max(profile.speed_m_s)) * travel + 1.0  # no depth is farther than c T
    z_dn, ex_dn, j_dn = medium._turning_below(q, zero, z0)
    z_up, ex_up, j_up = medium._turning_above(q, zero, z0)
    # Leg 1 from z0 to the turning point (if any) on the side the ray leaves to; leg 2 back
    # from there to the turning point on the other side.
    end1 = np.where(up, np.where(ex_up, z_up, z0 - reach), np.where(ex_dn, z_dn, z0 + reach))
    turns1, j1 = np.where(up, ex_up, ex_dn), np.where(up, j_up, j_dn)
    end2 = np.where(up, np.where(ex_dn, z_dn, z0 + reach), np.where(ex_up, z_up, z0 - reach))
    turns2, j2 = np.where(up, ex_dn, ex_up), np.where(up, j_dn, j_up)
    x1, t1 = _leg(medium, q, z0, end1, turns1, ~up, j1)
    _, t2 = _leg(medium, q, end1, end2, turns2, up, j2)
    in_leg1 = travel <= t1
    in_leg2 = ~in_leg1 & turns1 & (travel <= t1 + t2)
    # Bisection on the depth reached within the leg (time grows with the depth's distance
    # from the leg's start).
    start = np.where(in_leg1, z0, end1)
    stop = np.where(in_leg1, end1, end2)
    goal = np.where(in_leg1, travel, travel - t1)
    turn_start = ~in_leg1 & turns1  # leg 2 starts at leg 1's turning point
    lo, hi = np.zeros(n), np.ones(n)  # fraction of the way from start to stop
    for _ in range(_BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        _, tm = _leg(medium, q, start, start + mid * (stop - start), turn_start, ~up, j1)
        short = tm < goal
        lo = np.where(short, mid, lo)
        hi = np.where(short, hi, mid)
    depth = start + 0.5 * (lo + hi) * (stop - start)
    xm, _ = _leg(medium, q, start, depth, turn_start, ~up, j1)
    horizontal = np.where(in_leg1, xm, x1 + xm)
    # Horizontal ray in a constant-speed layer: straight.
    flat = (elevation == 0.0) & (grad == 0.0)
    horizontal = np.where(flat, c0 * travel, horizontal)
    depth = np.where(flat, z0, depth)
    lost = ~(in_leg1 | in_leg2 | flat)
    return np.where(lost, np.nan, horizontal), np.where(lost, np.nan, depth)


def _leg(
    medium: LayeredMedium,
    q: Array,
    z_a: Array,
    z_b: Array,
    turning: Array,
    turn_below: Array,
    turn_layer: Array,
) -> tuple[Array, Array]:
    """X and T of the ray ``q = 1/p`` between depths ``z_a`` and ``z_b``; where ``turning``,
    the ray turns at the deeper end (``turn_below``) or the shallower one, in ``turn_layer``
    (exact sine 0 there)."""
    zero = np.zeros(q.size)
    top, bottom = np.minimum(z_a, z_b), np.maximum(z_a, z_b)
    x, t = medium._crossing(q, zero, top, bottom)
    for flag in (True, False):
        sub = np.flatnonzero(turning & (turn_below == flag))
        if sub.size:
            x[sub], t[sub] = medium._crossing(
                q[sub], zero[sub], top[sub], bottom[sub], turn_layer[sub], flag
            )
    return x, t
