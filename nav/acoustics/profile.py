"""The sound-speed profile of a horizontally stratified sea, and Mackenzie's equation.

Depth is positive down (depth = -z of world ENU), metres; speeds m/s. A profile is piecewise
LINEAR in depth between its knots and constant beyond its last knot; above its first knot (the
surface, or the shallowest knot given) it is constant too, so points slightly above the surface
(a transceiver's head, a vehicle on the surface) have a speed.

References:
    K. V. Mackenzie, "Nine-term equation for sound speed in the oceans", J. Acoust. Soc. Am.
    70(3), 807-812 (1981).
    F. B. Jensen, W. A. Kuperman, M. B. Porter, H. Schmidt, *Computational Ocean Acoustics*,
    2nd ed., Springer (2011), ch. 1 (profiles) and ch. 3 (rays in layers of constant gradient).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]


def mackenzie_speed(temperature_c: ArrayLike, salinity_psu: ArrayLike, depth_m: ArrayLike) -> Array:
    """The speed of sound in sea water by Mackenzie's nine-term equation.

    ``c = 1448.96 + 4.591 T - 5.304e-2 T^2 + 2.374e-4 T^3 + 1.340 (S - 35) + 1.630e-2 D
    + 1.675e-7 D^2 - 1.025e-2 T (S - 35) - 7.139e-13 T D^3`` (Mackenzie 1981, eq. 1; valid for
    T 2..30 C, S 25..40 psu, D 0..8000 m; standard error 0.07 m/s; the paper's check value is
    1550.744 m/s at 25 C, 35 psu, 1000 m).

    Args:
        temperature_c: temperature T, deg C, any shape (broadcast with the others).
        salinity_psu: salinity S, practical salinity units.
        depth_m: depth D, m, positive down.

    Returns:
        The sound speed, m/s, shape of the broadcast arguments.
    """
    t = np.asarray(temperature_c, dtype=float)
    s = np.asarray(salinity_psu, dtype=float) - 35.0
    d = np.asarray(depth_m, dtype=float)
    return (
        1448.96
        + 4.591 * t
        - 5.304e-2 * t**2
        + 2.374e-4 * t**3
        + 1.340 * s
        + 1.630e-2 * d
        + 1.675e-7 * d**2
        - 1.025e-2 * t * s
        - 7.139e-13 * t * d**3
    )


@dataclass(frozen=True, eq=False)
class SoundSpeedProfile:
    """Sound speed against depth: piecewise linear between knots, constant outside them.

    Attributes:
        depth_m: knot depths, shape (L,), m, positive down, strictly increasing, L >= 1.
        speed_m_s: sound speed at each knot, shape (L,), m/s, > 0.

    Raises:
        NavInputError: shapes differ, depths not strictly increasing or non-finite, or a speed
            not positive and finite (the message names the field).
    """

    depth_m: Array
    speed_m_s: Array

    def __post_init__(self) -> None:
        depth = np.array(self.depth_m, dtype=float).reshape(-1)
        speed = np.array(self.speed_m_s, dtype=float).reshape(-1)
        if depth.size == 0:
            raise NavInputError("depth_m: at least one knot is needed")
        if depth.shape != speed.shape:
            raise NavInputError(
                f"speed_m_s: {speed.size} speeds for {depth.size} depths; one speed per depth"
            )
        if not np.all(np.isfinite(depth)) or np.any(np.diff(depth) <= 0.0):
            raise NavInputError(f"depth_m: {depth.tolist()} must be finite and strictly increasing")
        if not np.all(np.isfinite(speed)) or np.any(speed <= 0.0):
            raise NavInputError(f"speed_m_s: {speed.tolist()} must be finite and > 0")
        depth.flags.writeable = False
        speed.flags.writeable = False
        object.__setattr__(self, "depth_m", depth)
        object.__setattr__(self, "speed_m_s", speed)

    @classmethod
    def isovelocity(cls, speed_m_s: float) -> SoundSpeedProfile:
        """One speed at every depth (``speed_m_s``, m/s)."""
        return cls(np.array([0.0]), np.array([float(speed_m_s)]))

    @classmethod
    def constant_gradient(
        cls, surface_speed_m_s: float, gradient_per_s: float, max_depth_m: float
    ) -> SoundSpeedProfile:
        """``c(depth) = surface_speed_m_s + gradient_per_s * depth`` from 0 to ``max_depth_m``.

        Args:
            surface_speed_m_s: speed at depth 0, m/s.
            gradient_per_s: dc/d(depth), (m/s)/m = 1/s (positive: faster with depth).
            max_depth_m: the last knot, m (> 0); constant below.
        """
        if not max_depth_m > 0.0:
            raise NavInputError(f"max_depth_m: {max_depth_m} must be > 0")
        bottom = surface_speed_m_s + gradient_per_s * max_depth_m
        return cls(np.array([0.0, float(max_depth_m)]), np.array([surface_speed_m_s, bottom]))

    @classmethod
    def from_temperature_salinity(
        cls, depth_m: ArrayLike, temperature_c: ArrayLike, salinity_psu: ArrayLike
    ) -> SoundSpeedProfile:
        """A profile from a (depth, T, S) table by :func:`mackenzie_speed` at each knot.

        Args:
            depth_m: knot depths, shape (L,), m, strictly increasing.
            temperature_c: temperature at each knot, shape (L,), deg C.
            salinity_psu: salinity at each knot, shape (L,) or scalar, psu.
        """
        depth = np.asarray(depth_m, dtype=float).reshape(-1)
        temp = np.asarray(temperature_c, dtype=float).reshape(-1)
        if temp.shape != depth.shape:
            raise NavInputError(
                f"temperature_c: {temp.size} values for {depth.size} depths; one per depth"
            )
        sal = np.broadcast_to(np.asarray(salinity_psu, dtype=float), depth.shape)
        return cls(depth, mackenzie_speed(temp, sal, depth))

    @property
    def layer_gradient_per_s(self) -> Array:
        """dc/d(depth) of each layer between consecutive knots, shape (L-1,), 1/s."""
        return np.diff(self.speed_m_s) / np.diff(self.depth_m)

    def speed(self, depth_m: ArrayLike) -> Array:
        """The sound speed at ``depth_m`` (any shape, m, positive down), m/s."""
        return np.interp(np.asarray(depth_m, dtype=float), self.depth_m, self.speed_m_s)

    def gradient(self, depth_m: ArrayLike) -> Array:
        """dc/d(depth) at ``depth_m`` (any shape), 1/s; 0 outside the knots; at a knot, the
        gradient of the layer below it."""
        depth = np.asarray(depth_m, dtype=float)
        grad = np.concatenate([[0.0], self.layer_gradient_per_s, [0.0]])
        return grad[np.searchsorted(self.depth_m, depth, side="right")]

    def slowness_integral(self, depth_a_m: ArrayLike, depth_b_m: ArrayLike) -> Array:
        """``integral dz / c(z)`` from ``depth_a_m`` to ``depth_b_m`` (signed), s.

        In a layer of gradient g: ``(1/g) ln(c2/c1)``, computed as
        ``dz/c1 * log1p(x)/x`` with ``x = g dz / c1`` (exact in isovelocity, x = 0).
        """
        a = np.asarray(depth_a_m, dtype=float)
        b = np.asarray(depth_b_m, dtype=float)
        top, bottom = np.minimum(a, b), np.maximum(a, b)
        edges = np.concatenate([[-np.inf], self.depth_m, [np.inf]])
        lo = np.clip(top[..., None], edges[:-1], edges[1:])
        hi = np.clip(bottom[..., None], edges[:-1], edges[1:])
        dz = hi - lo
        c1 = self.speed(lo)
        x = (self.speed(hi) - c1) / c1
        total = np.sum(dz / c1 * _log1p_over_x(x), axis=-1)
        return np.where(b >= a, total, -total)

    def harmonic_mean_speed(self, depth_a_m: ArrayLike, depth_b_m: ArrayLike) -> Array:
        """The effective vertical speed ``|dz| / integral dz/c`` between two depths, m/s.

        The harmonic mean the standard range correction uses (Jensen et al. 2011, ch. 1); equal
        depths give the speed there.
        """
        a = np.asarray(depth_a_m, dtype=float)
        b = np.asarray(depth_b_m, dtype=float)
        dz = np.abs(b - a)
        slowness = np.abs(self.slowness_integral(a, b))
        safe = np.where(dz > 0.0, slowness, 1.0)
        return np.where(dz > 0.0, dz / safe, self.speed(a))


def _log1p_over_x(x: Array) -> Array:
    """``log1p(x) / x``, 1 at x = 0 (elementwise, x > -1)."""
    x = np.asarray(x, dtype=float)
    safe = np.where(x == 0.0, 1.0, x)
    return np.where(x == 0.0, 1.0, np.log1p(safe) / safe)
