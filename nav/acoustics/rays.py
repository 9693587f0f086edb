"""Eigenrays through a horizontally stratified sea of piecewise-linear sound speed.

In a layer where the speed is linear in depth, ``c(z) = c1 + g (z - z1)``, a ray keeps Snell's
invariant ``p = cos(theta) / c`` (theta the grazing angle) and is an arc of a circle of radius
``1 / (|g| p)`` centred at the depth where ``c`` would be 0; in a layer of constant speed it is
straight. With ``s = sin(theta) = sqrt(1 - p^2 c^2)``, the horizontal distance and the travel
time across a layer from ``c1`` to ``c2`` are, in closed form (Jensen, Kuperman, Porter &
Schmidt, *Computational Ocean Acoustics*, 2nd ed. 2011, sec. 3.2; Medwin & Clay, *Fundamentals
of Acoustical Oceanography* 1998, sec. 2.6),

    X = (s1 - s2) / (g p) = p dz (c1 + c2) / (s1 + s2),
    T = (1/g) ln[c2 (1 + s1) / (c1 (1 + s2))] = dz A log1p(g dz A) / (g dz A),
    A = [1 + (c1 + c2) / (c2 s1 + c1 s2)] / (c1 (1 + s2)),

the second forms being the first rewritten without the 0/0 of an isovelocity layer (g = 0:
``X = dz cot(theta)``, ``T = dz / (c sin(theta))``).

The direct eigenray between two points at horizontal distance X solves ``X(p) = X``. Three
families of rays join two depths without a reflection: the ray that goes monotonically from one
depth to the other (``p < 1 / c_max`` over the interval; X grows with p), the ray that turns
below the deeper point (where ``c = 1/p``) and the ray that turns above the shallower point;
:class:`LayeredMedium` solves each by vectorised bisection and keeps the first arrival. Where
none reaches the receiver (the shadow of a refracting layer: the real sound then arrives only
reflected or diffracted), the travel time and the angles are NaN.

The ray parameter is carried as ``q = 1/p = c_ref + delta`` (``c_ref`` the fastest speed the
ray passes, ``delta >= 0``), so that ``s^2 = ((c_ref - c) + delta)(q + c) / q^2`` keeps its
precision for rays grazing a speed maximum, where ``1 - p^2 c^2`` would cancel.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.acoustics.profile import SoundSpeedProfile, _log1p_over_x
from nav.acoustics.propagation import Eigenray
from nav.errors import NavInputError

Array = NDArray[np.float64]

_BISECTION_STEPS = 64
_RANGE_TOLERANCE = 1e-7
_T_MAX = 1.0 - 2.0**-53  # the largest double below 1: the steepest ray the bisection takes


@dataclass(frozen=True, eq=False)
class LayeredMedium:
    """A sea of piecewise-linear sound speed in depth: the direct eigenray between points.

    Implements :class:`nav.acoustics.Propagation`. The eigenray of a stratified medium lies in
    the vertical plane through its ends, so only the horizontal distance and the two depths
    matter. Reciprocity holds: swapping source and receiver gives the same travel time with the
    launch and arrival elevations exchanged.

    Attributes:
        profile: the sound-speed profile (constant above its first and below its last knot).
        chunk: rays solved per block of the vectorised bisection (memory bound only).
    """

    profile: SoundSpeedProfile
    chunk: int = 16384
    _edges: Array = field(init=False, repr=False)
    _base: Array = field(init=False, repr=False)
    _ctop: Array = field(init=False, repr=False)
    _grad: Array = field(init=False, repr=False)
    _c_top_edge: Array = field(init=False, repr=False)
    _c_bottom_edge: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.profile, SoundSpeedProfile):
            raise NavInputError(
                f"profile: {type(self.profile).__name__} is not a SoundSpeedProfile"
            )
        if int(self.chunk) < 1:
            raise NavInputError(f"chunk: {self.chunk} must be >= 1")
        d, c = self.profile.depth_m, self.profile.speed_m_s
        # Layers: (-inf, d0), (d0, d1), ..., (d_{L-1}, inf); c = ctop + grad * (z - base).
        object.__setattr__(self, "_edges", np.concatenate([[-np.inf], d, [np.inf]]))
        object.__setattr__(self, "_base", np.concatenate([[d[0]], d]))
        object.__setattr__(self, "_ctop", np.concatenate([[c[0]], c]))
        object.__setattr__(
            self, "_grad", np.concatenate([[0.0], self.profile.layer_gradient_per_s, [0.0]])
        )
        object.__setattr__(self, "_c_top_edge", np.concatenate([[c[0]], c]))
        object.__setattr__(self, "_c_bottom_edge", np.concatenate([c, [c[-1]]]))

    # ------------------------------------------------------------------ public
    def eigenray(self, source_world_m: ArrayLike, receiver_world_m: ArrayLike) -> Eigenray:
        """The direct (refracted, unreflected) eigenray, first arrival.

        Args:
            source_world_m: source positions, shape (..., 3), m, world ENU (depth = -z).
            receiver_world_m: receiver positions, shape (..., 3), broadcast with the source.

        Returns:
            :class:`Eigenray` with shapes (...): travel time (s), launch elevation at the source
            and arrival elevation at the receiver (rad, positive up; the arrival elevation
            points from the receiver back along the arriving ray). NaN where no direct ray
            reaches the receiver (shadow zone).
        """
        src = np.asarray(source_world_m, dtype=float)
        rcv = np.asarray(receiver_world_m, dtype=float)
        if src.shape[-1:] != (3,) or rcv.shape[-1:] != (3,):
            raise NavInputError(
                f"source_world_m/receiver_world_m: shapes {src.shape} and {rcv.shape}; "
                "the last axis must be 3 (east, north, up)"
            )
        src, rcv = np.broadcast_arrays(src, rcv)
        shape = src.shape[:-1]
        horizontal = np.hypot(rcv[..., 0] - src[..., 0], rcv[..., 1] - src[..., 1]).reshape(-1)
        travel, launch, arrival = self.between_depths(
            -src[..., 2].reshape(-1), -rcv[..., 2].reshape(-1), horizontal
        )
        return Eigenray(travel.reshape(shape), launch.reshape(shape), arrival.reshape(shape))

    def between_depths(
        self, source_depth_m: ArrayLike, receiver_depth_m: ArrayLike, horizontal_m: ArrayLike
    ) -> tuple[Array, Array, Array]:
        """The eigenray between two depths at a horizontal distance.

        Args:
            source_depth_m: source depth, shape (...), m, positive down.
            receiver_depth_m: receiver depth, shape (...), m.
            horizontal_m: horizontal distance, shape (...), m, >= 0.

        Returns:
            ``(travel_time_s, launch_elevation_rad, arrival_elevation_rad)``, each of the
            broadcast shape; NaN in the shadow (see :meth:`eigenray`).
        """
        zs, zr, x = np.broadcast_arrays(
            np.asarray(source_depth_m, dtype=float),
            np.asarray(receiver_depth_m, dtype=float),
            np.asarray(horizontal_m, dtype=float),
        )
        if not (np.all(np.isfinite(zs)) and np.all(np.isfinite(zr)) and np.all(np.isfinite(x))):
            raise NavInputError("source/receiver positions must be finite")
        if np.any(x < 0.0):
            raise NavInputError("horizontal_m must be >= 0")
        shape = zs.shape
        zs, zr, x = zs.reshape(-1), zr.reshape(-1), x.reshape(-1)
        out = np.empty((3, zs.size))
        step = int(self.chunk)
        for start in range(0, zs.size, step):
            sl = slice(start, start + step)
            out[:, sl] = self._solve(zs[sl], zr[sl], x[sl])
        return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)

    def ray_parameter(self, depth_m: ArrayLike, elevation_rad: ArrayLike) -> Array:
        """Snell's invariant ``p = cos(elevation) / c(depth)`` (s/m) of a ray through a point."""
        return np.cos(np.asarray(elevation_rad, dtype=float)) / self.profile.speed(depth_m)

    # ---------------------------------------------------------------- kernels
    def _speed(self, z: Array) -> Array:
        """Speed at depths ``z`` (N, L+1): one column per layer (z already clipped to it)."""
        return self._ctop + self._grad * (z - self._base)

    def _crossing(
        self,
        c_ref: Array,
        delta: Array,
        za: Array,
        zb: Array,
        turn_layer: Array | None = None,
        turn_below: bool = True,
    ) -> tuple[Array, Array]:
        """Horizontal distance and travel time of the ray ``q = c_ref + delta`` from depth
        ``za`` to depth ``zb >= za`` (each (N,)), summed over the layers in closed form.

        With ``turn_layer`` (N,), the ray turns in that layer at ``zb`` (``turn_below``) or at
        ``za``: there ``c = q`` and ``sin(theta) = 0`` exactly, and the layer's thickness is
        ``(q - c) / g`` from the other end, so rounding of the turning depth does not leak into
        the near-singular sine."""
        lo = np.clip(za[:, None], self._edges[:-1], self._edges[1:])
        hi = np.clip(zb[:, None], self._edges[:-1], self._edges[1:])
        dz = hi - lo
        c1, c2 = self._speed(lo), self._speed(hi)
        q = (c_ref + delta)[:, None]
        s1 = _sine(c_ref, delta, c1, q)
        s2 = _sine(c_ref, delta, c2, q)
        if turn_layer is not None:
            rows = np.arange(za.size)
            j = turn_layer
            g = self._grad[j]
            if turn_below:
                gap = (c_ref - c1[rows, j]) + delta
                with np.errstate(divide="ignore", invalid="ignore"):
                    thick = np.where(g > 0.0, np.maximum(gap, 0.0) / g, dz[rows, j])
                c2[rows, j], s2[rows, j], dz[rows, j] = q[:, 0], 0.0, thick
            else:
                gap = (c_ref - c2[rows, j]) + delta
                with np.errstate(divide="ignore", invalid="ignore"):
                    thick = np.where(g < 0.0, np.maximum(gap, 0.0) / -g, dz[rows, j])
                c1[rows, j], s1[rows, j], dz[rows, j] = q[:, 0], 0.0, thick
        crossed = dz > 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(crossed, dz * (c1 + c2) / (q * (s1 + s2)), 0.0)
            a = (1.0 + (c1 + c2) / (c2 * s1 + c1 * s2)) / (c1 * (1.0 + s2))
            t = np.where(
                crossed, dz * a * _log1p_over_x(np.where(crossed, self._grad * dz * a, 0.0)), 0.0
            )
        return x.sum(axis=1), t.sum(axis=1)

    def _turning_below(self, c_ref: Array, delta: Array, zb: Array) -> tuple[Array, Array, Array]:
        """Depth where the ray ``q`` going down from ``zb`` first meets ``c = q``, whether it
        does, and the layer it turns in."""
        q = c_ref + delta
        lo = np.clip(zb[:, None], self._edges[:-1], self._edges[1:])
        cond = (self._edges[1:] >= zb[:, None]) & (self._c_bottom_edge >= q[:, None])
        exists = cond.any(axis=1)
        j = cond.argmax(axis=1)
        rows = np.arange(zb.size)
        lo_j = lo[rows, j]
        c_lo = self._ctop[j] + self._grad[j] * (lo_j - self._base[j])
        g = self._grad[j]
        with np.errstate(divide="ignore", invalid="ignore"):
            rise = ((c_ref - c_lo) + delta) / g
        z_t = np.where(c_lo >= q, lo_j, lo_j + np.where(g > 0.0, rise, 0.0))
        return np.minimum(z_t, self._edges[1:][j]), exists, j

    def _turning_above(self, c_ref: Array, delta: Array, za: Array) -> tuple[Array, Array, Array]:
        """Depth where the ray ``q`` going up from ``za`` first meets ``c = q``, whether it
        does, and the layer it turns in."""
        q = c_ref + delta
        hi = np.clip(za[:, None], self._edges[:-1], self._edges[1:])
        cond = (self._edges[:-1] <= za[:, None]) & (self._c_top_edge >= q[:, None])
        exists = cond.any(axis=1)
        n_layers = cond.shape[1]
        j = n_layers - 1 - cond[:, ::-1].argmax(axis=1)
        rows = np.arange(za.size)
        hi_j = hi[rows, j]
        c_hi = self._ctop[j] + self._grad[j] * (hi_j - self._base[j])
        g = self._grad[j]
        with np.errstate(divide="ignore", invalid="ignore"):
            fall = ((c_ref - c_hi) + delta) / g
        z_t = np.where(c_hi >= q, hi_j, hi_j + np.where(g < 0.0, fall, 0.0))
        return np.maximum(z_t, self._edges[:-1][j]), exists, j

    def _turning(
        self, c_ref: Array, delta: Array, ztop: Array, zbot: Array, below: bool
    ) -> tuple[Array, Array, Array]:
        """X and T of the ray turning below ``zbot`` (or above ``ztop``), and whether it turns."""
        x_in, t_in = self._crossing(c_ref, delta, ztop, zbot)
        if below:
            z_t, exists, j = self._turning_below(c_ref, delta, zbot)
            x_out, t_out = self._crossing(c_ref, delta, zbot, z_t, j, True)
        else:
            z_t, exists, j = self._turning_above(c_ref, delta, ztop)
            x_out, t_out = self._crossing(c_ref, delta, z_t, ztop, j, False)
        return x_in + 2.0 * x_out, t_in + 2.0 * t_out, exists

    def _max_speed(self, za: Array, zb: Array) -> Array:
        """Fastest speed over the depths ``[za, zb]`` (each (N,))."""
        knots = self.profile.depth_m
        inside = (knots >= za[:, None]) & (knots <= zb[:, None])
        c_knots = np.where(inside, self.profile.speed_m_s, -np.inf).max(axis=1)
        return np.maximum(np.maximum(self.profile.speed(za), self.profile.speed(zb)), c_knots)

    def _solve(self, zs: Array, zr: Array, x: Array) -> Array:
        """Travel time, launch and arrival elevation (3, N) of rays between depths."""
        n = zs.size
        ztop, zbot = np.minimum(zs, zr), np.maximum(zs, zr)
        c_max = self._max_speed(ztop, zbot)
        inf = np.full(n, np.inf)
        # Candidates: (travel time, c_ref, delta) per family; inf time = no ray.
        cand_t = np.stack([inf, inf, inf, inf])
        cand_ref = np.stack([c_max] * 4)
        cand_delta = np.zeros((4, n))

        # a) monotone ray between the depths, parametrised by t in (0, 1):
        #    delta = c_max t^2 / (r (1 + r)), r = sqrt(1 - t^2) (t = 0 grazing, 1 vertical).
        sel = np.flatnonzero((zbot > ztop) & (x > 0.0))
        if sel.size:
            x_max, _ = self._crossing(c_max[sel], np.zeros(sel.size), ztop[sel], zbot[sel])
            ok = x[sel] <= x_max
            sel = sel[ok]
        if sel.size:
            cr, zt_, zb_, xs = c_max[sel], ztop[sel], zbot[sel], x[sel]
            t_lo, t_hi = np.zeros(sel.size), np.ones(sel.size)
            for _ in range(_BISECTION_STEPS):
                mid = np.minimum(0.5 * (t_lo + t_hi), _T_MAX)
                xm, _ = self._crossing(cr, _delta_of_t(cr, mid), zt_, zb_)
                farther = xm > xs
                t_lo = np.where(farther, mid, t_lo)
                t_hi = np.where(farther, t_hi, mid)
            delta = _delta_of_t(cr, np.minimum(0.5 * (t_lo + t_hi), _T_MAX))
            _, tt = self._crossing(cr, delta, zt_, zb_)
            cand_t[0, sel], cand_delta[0, sel] = tt, delta

        # b) turning below the deeper point; c) turning above the shallower one.
        for fam, below in ((1, True), (2, False)):
            if below:
                knots_side = self.profile.depth_m >= zbot[:, None]
                c_side = np.maximum(
                    self.profile.speed(zbot),
                    np.where(knots_side, self.profile.speed_m_s, -np.inf).max(axis=1),
                )
            else:
                knots_side = self.profile.depth_m <= ztop[:, None]
                c_side = np.maximum(
                    self.profile.speed(ztop),
                    np.where(knots_side, self.profile.speed_m_s, -np.inf).max(axis=1),
                )
            span = c_side - c_max
            sel = np.flatnonzero((x > 0.0) & (span > 0.0) & ~np.isfinite(cand_t[0]))
            if not sel.size:
                continue
            cr, zt_, zb_, xs, sp = c_max[sel], ztop[sel], zbot[sel], x[sel], span[sel]
            d_lo, d_hi = np.zeros(sel.size), sp.copy()
            for _ in range(_BISECTION_STEPS):
                mid = 0.5 * (d_lo + d_hi)
                xm, _, _ = self._turning(cr, mid, zt_, zb_, below)
                short = xm < xs
                d_lo = np.where(short, mid, d_lo)
                d_hi = np.where(short, d_hi, mid)
            delta = 0.5 * (d_lo + d_hi)
            xm, tt, exists = self._turning(cr, delta, zt_, zb_, below)
            good = exists & (np.abs(xm - xs) <= _RANGE_TOLERANCE * np.maximum(xs, 1.0))
            cand_t[fam, sel] = np.where(good, tt, np.inf)
            cand_delta[fam, sel] = delta

        # h) two points at one depth in a layer of constant speed: the straight horizontal ray.
        depth_grid = self.profile.depth_m
        grad = np.concatenate([[0.0], self.profile.layer_gradient_per_s, [0.0]])
        g_below = grad[np.searchsorted(depth_grid, zs, side="right")]
        g_above = grad[np.searchsorted(depth_grid, zs, side="left")]
        flat = (zbot == ztop) & (x > 0.0) & ((g_below == 0.0) | (g_above == 0.0))
        cand_t[3] = np.where(flat, x / self.profile.speed(zs), cand_t[3])

        best = np.argmin(cand_t, axis=0)
        cols = np.arange(n)
        travel = cand_t[best, cols]
        c_ref, delta = cand_ref[best, cols], cand_delta[best, cols]
        q = c_ref + delta
        cs, cr_ = self.profile.speed(zs), self.profile.speed(zr)
        theta_s = np.arctan2(_sine(c_ref, delta, cs[:, None], q[:, None])[:, 0], cs / q)
        theta_r = np.arctan2(_sine(c_ref, delta, cr_[:, None], q[:, None])[:, 0], cr_ / q)
        down = zr > zs
        launch = np.select(
            [best == 0, best == 1, best == 2],
            [np.where(down, -theta_s, theta_s), -theta_s, theta_s],
            0.0,
        )
        arrival = np.select(
            [best == 0, best == 1, best == 2],
            [np.where(down, theta_r, -theta_r), -theta_r, theta_r],
            0.0,
        )
        # Vertical rays and coincident points.
        vertical = x == 0.0
        if np.any(vertical):
            slow = np.abs(self.profile.slowness_integral(zs, zr))
            half_pi = 0.5 * np.pi
            travel = np.where(vertical, slow, travel)
            launch = np.where(
                vertical, np.where(zr > zs, -half_pi, np.where(zr < zs, half_pi, 0.0)), launch
            )
            arrival = np.where(
                vertical, np.where(zr > zs, half_pi, np.where(zr < zs, -half_pi, 0.0)), arrival
            )
        shadow = ~np.isfinite(travel)
        travel = np.where(shadow, np.nan, travel)
        launch = np.where(shadow, np.nan, launch)
        arrival = np.where(shadow, np.nan, arrival)
        return np.stack([travel, launch, arrival])


def _sine(c_ref: Array, delta: Array, c: Array, q: Array) -> Array:
    """``sin(theta) = sqrt(1 - c^2 / q^2)`` at speed ``c`` (N, K) of the ray ``q = c_ref +
    delta`` (each (N,)), from ``((c_ref - c) + delta)(q + c) / q^2`` without cancellation."""
    gap = np.maximum((c_ref[:, None] - c) + delta[:, None], 0.0)
    return np.sqrt(gap * (q + c)) / q


def _delta_of_t(c_ref: Array, t: Array) -> Array:
    """``delta = q - c_ref`` of the ray whose grazing sine at ``c_ref`` is ``t`` (in [0, 1))."""
    r = np.sqrt((1.0 - t) * (1.0 + t))
    return c_ref * t * t / (r * (1.0 + r))
