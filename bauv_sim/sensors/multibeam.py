"""Multibeam seabed sonar: M x M ranges to the seabed (seed 004, section 4, eq. 8).

**Beams.** Beam ``(i, j)`` is aimed at ``(gamma_k + gamma^i, theta_k + theta^j)`` relative to the
vehicle's direction of motion ``(gamma_k, theta_k)`` (seed 004 angles: theta from the x/east axis
counter-clockwise, gamma up from the horizontal), with the unit vector (eq. 8)

    e = (cos(g) cos(t), cos(g) sin(t), sin(g)),   g = gamma_k + gamma^i,   t = theta_k + theta^j.

The defaults are seed 004's (section 6): 8 x 8 beams, ``gamma^i`` uniformly over 42 .. 82 deg
*down* (the configuration holds -42 .. -82 deg: z is up, reading notes), ``theta^j`` over
-10 .. 30 deg, range noise 0.1 m.

**Ranges by ray casting.**

* Kinematic world: the seed's harmonic seabed ``psi(x) = 0`` of eq. 24
  (:class:`HarmonicSeabed`), by root finding along each ray (:meth:`HarmonicSeabed.ray_ranges`):
  a march whose steps are the first root of a parabola bounding ``psi`` from below along the ray
  (the curvature of eq. 24 is bounded by its coefficients), so that no step passes the first
  crossing while the steps near it are Newton's, to ``tol_m`` (1e-9 m), compiled by numba
  (:mod:`bauv_sim.sensors.harmonic_march`); grazing rays finish with a Lipschitz march and
  safeguarded Newton-bisection.
* Physics world: MuJoCo's ``mj_multiRay`` against the scene's seabed heightfield, through
  :meth:`bauv_sim.physics.BauvPhysics.seabed_ray_distances` (the only code that reads MuJoCo
  arrays); the beams start at the ``sonar`` site of the vehicle model. The direction of motion
  is the hull's axis (``gamma_k`` = pitch, ``theta_k`` from the heading): the beams are fixed to
  the hull, which is where a real sonar's are.

**Errors.** The shared vocabulary (:mod:`bauv_sim.sensors.errors`) on each beam's range (noise,
bias, scale factor, outliers, per-beam dropouts; a random walk is refused, the beams have no
common time series), plus: a beam with no seabed within ``max_range_m`` has **no echo**; a beam
that drops out has none either. A beam without echo is flagged absent (``echo`` False, range 0),
never NaN. Measured ranges are clipped at 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.frames import R_from_quat_wxyz, theta_from_course
from bauv_sim.sensors.errors import ErrorProcess, LengthErrorConfig
from bauv_sim.sensors.online import (
    DeviceBuild,
    Measurement,
    TickContext,
    register_device,
)

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

CURVATURE_STEPS = 60
"""Steps of :meth:`HarmonicSeabed.ray_ranges`' curvature-bounded march before a ray still
unresolved (grazing a crest) is handed to the first-order march."""


class MultibeamConfig(Config):
    """Multibeam seabed sonar (defaults: seed 004 section 6)."""

    period_s: float = Field(1.0, gt=0, description="time between images, s (seed 004: 1)")
    elevation_deg: tuple[float, float] = Field(
        (-42.0, -82.0),
        description="first and last beam elevation gamma^i relative to the direction of motion, "
        "deg, negative down (seed 004: 42 .. 82 deg down)",
    )
    azimuth_deg: tuple[float, float] = Field(
        (-10.0, 30.0),
        description="first and last beam azimuth theta^j, counter-clockwise from the direction "
        "of motion, deg (seed 004: -10 .. 30)",
    )
    beams_elevation: int = Field(8, ge=1, le=64, description="beams per elevation fan")
    beams_azimuth: int = Field(8, ge=1, le=64, description="beams per azimuth fan")
    range: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=0.1),
        description="range error of each beam (seed 004: 0.1 m)",
    )
    max_range_m: float = Field(100.0, gt=0, description="no echo beyond this range, m")
    min_step_m: float = Field(
        0.02, gt=0, description="smallest step of the kinematic root finder's march, m"
    )
    tol_m: float = Field(1e-9, gt=0, description="root-finding tolerance (kinematic), m")
    transducer_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="transducer relative to the reference point, m, body FLU (zero: the "
        "model's 'sonar' site)",
    )

    @field_validator("range")
    @classmethod
    def _no_walk(cls, v: LengthErrorConfig) -> LengthErrorConfig:
        if v.random_walk_m_per_sqrt_s != 0:
            raise ValueError("random_walk_m_per_sqrt_s must be 0 for the multibeam's beams")
        if v.sector_bias_m is not None:
            raise ValueError("sector_bias_m is not defined for the multibeam's beams")
        return v

    @property
    def shape(self) -> tuple[int, int]:
        """``(Mi, Mj)``: elevations x azimuths."""
        return (self.beams_elevation, self.beams_azimuth)

    def elevations_rad(self) -> Array:
        """``gamma^i``, shape (Mi,), rad (end points included)."""
        return np.radians(np.linspace(*self.elevation_deg, self.beams_elevation))

    def azimuths_rad(self) -> Array:
        """``theta^j``, shape (Mj,), rad (end points included)."""
        return np.radians(np.linspace(*self.azimuth_deg, self.beams_azimuth))


def beam_directions(cfg: MultibeamConfig, attitude_rad: Array) -> Array:
    """Unit beam vectors of seed 004 eq. 8.

    Args:
        cfg: the sonar (its aiming angles).
        attitude_rad: direction of motion ``(gamma_k, theta_k)``, shape (..., 2), rad (seed 004
            angles).

    Returns:
        Shape (..., Mi, Mj, 3), world frame (z up).
    """
    att = np.asarray(attitude_rad, dtype=float)
    g = att[..., 0, None, None] + cfg.elevations_rad()[:, None]
    t = att[..., 1, None, None] + cfg.azimuths_rad()[None, :]
    g, t = np.broadcast_arrays(g, t)
    cg = np.cos(g)
    return np.stack([cg * np.cos(t), cg * np.sin(t), np.sin(g)], axis=-1)


@dataclass(frozen=True)
class HarmonicSeabed:
    """Seed 004's seabed, eq. 24, one per path:

        psi(x) = a0 + z + sum_{l=1..K} (a_l sin(2 pi l x / Px) + b_l cos(2 pi l x / Px)
                                       + c_l sin(2 pi l y / Py) + d_l cos(2 pi l y / Py)),

    the seabed being ``psi = 0`` (water where ``psi > 0``): its height is ``z = -a0 - sum(...)``.

    Attributes:
        a, b, c, d: coefficients, each shape (P, K), m.
        a0_m: the constant, m (seed 004: 30).
        period_x_m: Px, m (seed 004: 20).
        period_y_m: Py, m (seed 004: 20).
    """

    a: Array
    b: Array
    c: Array
    d: Array
    a0_m: float = 30.0
    period_x_m: float = 20.0
    period_y_m: float = 20.0

    def __post_init__(self) -> None:
        """Check the coefficients before anything reads them (the C march indexes them by path).

        Raises:
            ConfigError: if ``a, b, c, d`` are not finite arrays of one shape ``(P >= 1, K >= 1)``,
                ``a0_m`` is not finite, or a period is not finite and positive.
        """
        shape = None
        for name in "abcd":
            v = getattr(self, name)
            try:
                arr = np.array(v, dtype=float)  # a copy: the seabed stays as checked
            except (TypeError, ValueError):
                raise ConfigError(
                    f"HarmonicSeabed.{name}: {type(v).__name__} is not an array of numbers; "
                    "need coefficients of shape (paths, harmonics), m"
                ) from None
            if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] < 1:
                raise ConfigError(
                    f"HarmonicSeabed.{name}: shape {arr.shape}; need (paths >= 1, harmonics >= 1)"
                )
            if shape is None:
                shape = arr.shape
            elif arr.shape != shape:
                raise ConfigError(
                    f"HarmonicSeabed.{name}: shape {arr.shape}, but a has {shape}: the four "
                    "coefficient arrays need one shape (paths, harmonics)"
                )
            if not np.isfinite(arr).all():
                raise ConfigError(f"HarmonicSeabed.{name}: non-finite coefficient; need finite m")
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        for name, positive in (("a0_m", False), ("period_x_m", True), ("period_y_m", True)):
            v = getattr(self, name)
            try:
                f = float(v)
            except (TypeError, ValueError):
                f = float("nan")
            if not (np.isfinite(f) and (f > 0 or not positive)):
                rule = "finite and > 0" if positive else "finite"
                raise ConfigError(f"HarmonicSeabed.{name} = {v!r}: must be {rule}, m")
            object.__setattr__(self, name, f)

    @classmethod
    def draw(
        cls,
        seed: int,
        runs: tuple[int, ...],
        harmonics: int = 2,
        a0_m: float = 30.0,
        period_x_m: float = 20.0,
        period_y_m: float = 20.0,
    ) -> HarmonicSeabed:
        """Seed 004's random seabeds: the coefficients standard uniform, one seabed per run, from
        the run's stream ``("seabed004", "coefficients")``.

        Args:
            seed: batch seed.
            runs: run indices (one seabed each).
            harmonics: K (seed 004: 2).
            a0_m: a0, m.
            period_x_m: Px, m.
            period_y_m: Py, m.
        """
        if harmonics < 1:
            raise ConfigError(f"harmonics = {harmonics}: must be >= 1")
        gens = rng_mod.generators(seed, runs, "seabed004", "coefficients")
        coef = np.stack([g.random((4, harmonics)) for g in gens])  # (P, 4, K)
        return cls(coef[:, 0], coef[:, 1], coef[:, 2], coef[:, 3], a0_m, period_x_m, period_y_m)

    @property
    def paths(self) -> int:
        """Number of seabeds P."""
        return self.a.shape[0]

    def _w(self) -> tuple[Array, Array]:
        lv = np.arange(1, self.a.shape[1] + 1)
        return 2 * np.pi * lv / self.period_x_m, 2 * np.pi * lv / self.period_y_m

    def _c(self, name: str, ndim: int) -> Array:
        """Coefficient array broadcast against points of ``ndim`` dims (P, ..., K)."""
        v = getattr(self, name)
        return v.reshape(v.shape[0], *([1] * (ndim - 1)), v.shape[1])

    def relief(self, x: Array, y: Array) -> Array:
        """The sum of eq. 24 at points, shape (P, ...) (leading axis the path), m."""
        wx, wy = self._w()
        nd = np.ndim(x)
        xs, ys = np.asarray(x)[..., None] * wx, np.asarray(y)[..., None] * wy
        s = self._c("a", nd) * np.sin(xs) + self._c("b", nd) * np.cos(xs)
        s = s + self._c("c", nd) * np.sin(ys) + self._c("d", nd) * np.cos(ys)
        return s.sum(-1)

    def psi(self, points: Array) -> Array:
        """``psi`` of eq. 24 at points, shape (P, ..., 3) -> (P, ...), m."""
        p = np.asarray(points, dtype=float)
        return self.a0_m + p[..., 2] + self.relief(p[..., 0], p[..., 1])

    def gradient(self, points: Array) -> Array:
        """``grad psi`` at points, shape (P, ..., 3) -> (P, ..., 3) (``dpsi/dz = 1``)."""
        p = np.asarray(points, dtype=float)
        wx, wy = self._w()
        nd = p.ndim - 1
        xs, ys = p[..., 0, None] * wx, p[..., 1, None] * wy
        gx = (wx * (self._c("a", nd) * np.cos(xs) - self._c("b", nd) * np.sin(xs))).sum(-1)
        gy = (wy * (self._c("c", nd) * np.cos(ys) - self._c("d", nd) * np.sin(ys))).sum(-1)
        return np.stack([gx, gy, np.ones_like(gx)], axis=-1)

    def height(self, x: Array, y: Array) -> Array:
        """Seabed z at horizontal points, shape (P, ...), m (negative below the surface)."""
        return -self.a0_m - self.relief(x, y)

    def relief_bound(self) -> Array:
        """Bound of ``|sum(...)|`` of eq. 24, shape (P,), m: the seabed lies within
        ``-a0 +- bound``."""
        return (np.hypot(self.a, self.b) + np.hypot(self.c, self.d)).sum(-1)

    def slope_bound(self) -> tuple[Array, Array]:
        """Bounds of ``|dpsi/dx|`` and ``|dpsi/dy|``, each shape (P,)."""
        wx, wy = self._w()
        return (
            (wx * np.hypot(self.a, self.b)).sum(-1),
            (wy * np.hypot(self.c, self.d)).sum(-1),
        )

    def ray_ranges(
        self,
        origin_m: Array,
        directions: Array,
        max_range_m: float,
        min_step_m: float = 0.02,
        tol_m: float = 1e-9,
        max_iterations: int = 10_000,
    ) -> tuple[Array, BoolArray]:
        """Distance along each ray to the first crossing of the seabed (module docstring).

        Along a ray ``x(s) = o + s e`` the function ``f(s) = psi(x(s))`` has ``f'(s) = grad psi .
        e`` and ``|f''(s)| <= M2 = e_x^2 C_x + e_y^2 C_y`` with ``C_x = sum_l w_l^2 hypot(a_l,
        b_l)`` (and the same in y; eq. 24 is separable, so there is no cross term). From a point
        where ``f > 0`` the concave parabola ``f + f' h - M2 h^2 / 2`` bounds ``f(s + h)`` from
        below; its first positive root

            h = 2 f / (sqrt(f'^2 + 2 M2 f) - f')      (= (f' + sqrt(...)) / M2 for f' > 0)

        is a step that cannot pass the first crossing, and near a simple root it is Newton's step to
        second order (quadratic convergence). The upper parabola ``f + f' h + M2 h^2 / 2`` crosses
        zero at ``h_up``, so the first crossing lies in ``[s + h, s + h_up]``: the march takes its
        middle once that interval is at most ``tol_m`` wide (or the step is), and has no echo past
        ``max_range_m``. It starts where the ray enters the slab ``|z + a0| <= sum_l (hypot(a_l,
        b_l) + hypot(c_l, d_l))`` that holds the seabed. The harmonics ``l = 2..K`` come from those
        of ``l = 1`` by the angle-addition recurrence (4 sines and cosines per evaluation). The
        march is compiled by numba, one ray at a time (:meth:`_curvature_march`,
        :func:`bauv_sim.sensors.harmonic_march.march`; the numpy march it replaced, vectorised over
        the rays, is the tests' reference and gives the same ranges). A ray that grazes a crest
        converges slowly (a double root): rays not resolved in :data:`CURVATURE_STEPS` steps finish
        with the first-order march (:meth:`_lipschitz_ranges`, numpy).

        Args:
            origin_m: ray origins, shape (P, ..., 3), m, world.
            directions: ray directions, shape (P, ..., 3) (broadcast with the origins;
                normalised here).
            max_range_m: no echo beyond this distance, m.
            min_step_m: smallest step of the first-order march, m.
            tol_m: step (first-order march: bracket width) at which the root is taken, m.
            max_iterations: cap of the first-order march (an error if reached: the ray is not
                resolved).

        Returns:
            ``(range_m, hit)``: shape (P, ...); ``range_m`` is 0 where ``hit`` is False (no
            seabed within ``max_range_m``, or an origin at or below the seabed).

        Raises:
            ConfigError: for rays of another number of paths, a zero or non-finite direction, a
                non-finite origin, a ``max_range_m``, ``tol_m`` or ``min_step_m`` that is not
                finite and positive, a first-order march that does not finish in
                ``max_iterations`` steps, or a C march that is not built (or refusing its
                arguments' sizes).
        """
        if not (np.isfinite(max_range_m) and max_range_m > 0):
            raise ConfigError(f"ray_ranges: max_range_m = {max_range_m}: must be finite and > 0")
        if not (np.isfinite(tol_m) and tol_m > 0 and np.isfinite(min_step_m) and min_step_m > 0):
            raise ConfigError(
                f"ray_ranges: tol_m = {tol_m}, min_step_m = {min_step_m}: must be finite and > 0"
            )
        o, e = np.broadcast_arrays(np.asarray(origin_m, float), np.asarray(directions, float))
        shape = o.shape[:-1]
        if not shape or shape[0] != self.paths:
            raise ConfigError(f"ray_ranges: rays of shape {o.shape} for {self.paths} seabeds")
        path = np.broadcast_to(
            np.arange(self.paths).reshape(-1, *([1] * (len(shape) - 1))), shape
        ).ravel()
        o, e = o.reshape(-1, 3), e.reshape(-1, 3)
        norm = np.linalg.norm(e, axis=1)
        if not np.all(np.isfinite(norm) & (norm > 0)) or not np.all(np.isfinite(o)):
            raise ConfigError("ray_ranges: origins must be finite, directions finite and non-zero")
        e = e / norm[:, None]
        r, hit, unresolved, si = self._curvature_march(o, e, path, max_range_m, tol_m)
        gid = np.flatnonzero(unresolved)
        if gid.size:  # rays grazing a crest: the first-order march from where the march stopped
            si = si[gid]
            L, h1 = self._lipschitz_ranges(
                o[gid] + si[:, None] * e[gid],
                e[gid],
                path[gid],
                max_range_m - si,
                min_step_m,
                tol_m,
                max_iterations,
            )
            r[gid] = si + L
            hit[gid] = h1
        return np.where(hit, r, 0.0).reshape(shape), hit.reshape(shape)

    def _curvature_march(
        self, o: Array, e: Array, path: NDArray[np.int64], max_range_m: float, tol_m: float
    ) -> tuple[Array, BoolArray, BoolArray, Array]:
        """The curvature-bounded march of :meth:`ray_ranges`, :data:`CURVATURE_STEPS` steps per
        ray, compiled by numba (:func:`bauv_sim.sensors.harmonic_march.march`, one ray at a
        time).

        Args:
            o: ray origins, shape (r, 3), m, world.
            e: unit ray directions, shape (r, 3), world.
            path: each ray's seabed, shape (r,), in ``[0, P)``.
            max_range_m: no echo beyond this distance, m.
            tol_m: width at which the root is taken, m.

        Returns:
            ``(range_m, hit, unresolved, s_m)``, each shape (r,): the range (m, 0 without hit),
            whether the ray found the seabed, whether it is still unresolved after
            :data:`CURVATURE_STEPS` steps, and for those the distance reached (m, else 0).

        Raises:
            ConfigError: if the march refuses its arguments (a programming error).
        """
        from bauv_sim.sensors import harmonic_march  # numba: imported on the first march

        wx, wy = self._w()
        n = path.size
        r = np.zeros(n)
        hit = np.zeros(n, np.uint8)
        unresolved = np.zeros(n, np.uint8)
        s = np.zeros(n)
        a, b, c, d = (np.ascontiguousarray(getattr(self, k), dtype=float) for k in "abcd")
        status = harmonic_march.march(
            np.ascontiguousarray(o, dtype=float).reshape(n, 3),
            np.ascontiguousarray(e, dtype=float).reshape(n, 3),
            np.ascontiguousarray(path, dtype=np.int64).reshape(n),
            a,
            b,
            c,
            d,
            np.ascontiguousarray(wx, dtype=float),
            np.ascontiguousarray(wy, dtype=float),
            np.ascontiguousarray(-self.a0_m + self.relief_bound(), dtype=float),
            np.ascontiguousarray((wx**2 * np.hypot(self.a, self.b)).sum(-1), dtype=float),
            np.ascontiguousarray((wy**2 * np.hypot(self.c, self.d)).sum(-1), dtype=float),
            float(self.a0_m),
            float(self.period_x_m),
            float(self.period_y_m),
            float(max_range_m),
            float(tol_m),
            CURVATURE_STEPS,
            r,
            hit,
            unresolved,
            s,
        )
        if status < 0:
            raise ConfigError(
                f"ray_ranges: the march refused its arguments (status {status}: "
                f"{harmonic_march.STATUS[status]})"
            )
        return r, hit.view(np.bool_), unresolved.view(np.bool_), s

    def _lipschitz_ranges(
        self,
        o: Array,
        e: Array,
        path: Array,
        max_range_m: Array,
        min_step_m: float,
        tol_m: float,
        max_iterations: int,
    ) -> tuple[Array, BoolArray]:
        """The first-order march: a Lipschitz march (steps ``max(psi / Lip, min_step_m)``, which
        cannot pass the first crossing unless the ray dips less than ``Lip * min_step_m / 2``
        into a crest and out again) brackets the first root, then a safeguarded Newton-bisection
        refines it to ``tol_m``. Rays (r, 3) with unit directions (r, 3), their paths (r,) and
        ranges (r,) m; returns ``(range_m, hit)`` (r,)."""
        gx, gy = self.slope_bound()
        lip = np.abs(e[:, 2]) + np.abs(e[:, 0]) * gx[path] + np.abs(e[:, 1]) * gy[path]
        lo = np.zeros(path.size)
        hi = np.zeros(path.size)
        f_lo = self.psi_at(o, path)
        hit = np.zeros(path.size, bool)
        # march: psi(o + s e) >= psi(lo) - lip (s - lo) > 0 for s < lo + psi(lo) / lip
        idx = np.flatnonzero(f_lo > 0)  # an origin at or below the seabed has no echo
        for _ in range(max_iterations):
            if idx.size == 0:
                break
            cand = np.minimum(
                lo[idx] + np.maximum(f_lo[idx] / lip[idx], min_step_m), max_range_m[idx]
            )
            f_c = self.psi_at(o[idx] + cand[:, None] * e[idx], path[idx])
            crossed = f_c <= 0
            go = ~crossed & (cand < max_range_m[idx])
            hi[idx[crossed]] = cand[crossed]
            hit[idx[crossed]] = True
            lo[idx[go]] = cand[go]
            f_lo[idx[go]] = f_c[go]
            idx = idx[go]
        if idx.size:
            raise ConfigError(f"ray_ranges: the march did not finish in {max_iterations} steps")
        # refine: safeguarded Newton inside [lo, hi] with psi(lo) > 0 >= psi(hi)
        x = hi.copy()
        idx = np.flatnonzero(hit)
        for _ in range(200):
            if idx.size == 0:
                break
            a, b, xc = lo[idx], hi[idx], x[idx]
            pts = o[idx] + xc[:, None] * e[idx]
            f = self.psi_at(pts, path[idx])
            df = np.einsum("rc,rc->r", self.gradient_at(pts, path[idx]), e[idx])
            pos = f > 0
            a = np.where(pos, xc, a)
            b = np.where(pos, b, xc)
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = xc - f / df
            inside = np.isfinite(newton) & (newton > a) & (newton < b)
            nxt = np.where(f == 0, xc, np.where(inside, newton, 0.5 * (a + b)))
            lo[idx], hi[idx], x[idx] = a, b, nxt
            done = (b - a <= tol_m) | (f == 0) | (np.abs(nxt - xc) <= 0.5 * tol_m)
            idx = idx[~done]
        return np.where(hit, x, 0.0), hit

    def psi_at(self, points: Array, path: Array) -> Array:
        """``psi`` at points of given paths: points shape (r, 3), path shape (r,) -> (r,)."""
        wx, wy = self._w()
        xs, ys = points[:, 0, None] * wx, points[:, 1, None] * wy
        s = self.a[path] * np.sin(xs) + self.b[path] * np.cos(xs)
        s = s + self.c[path] * np.sin(ys) + self.d[path] * np.cos(ys)
        return self.a0_m + points[:, 2] + s.sum(-1)

    def gradient_at(self, points: Array, path: Array) -> Array:
        """``grad psi`` at points of given paths: (r, 3), (r,) -> (r, 3)."""
        wx, wy = self._w()
        xs, ys = points[:, 0, None] * wx, points[:, 1, None] * wy
        gx = (wx * (self.a[path] * np.cos(xs) - self.b[path] * np.sin(xs))).sum(-1)
        gy = (wy * (self.c[path] * np.cos(ys) - self.d[path] * np.sin(ys))).sum(-1)
        return np.stack([gx, gy, np.ones_like(gx)], axis=-1)


@dataclass(frozen=True)
class MultibeamImages:
    """Acoustic images of a batch of runs.

    Attributes:
        t_s: times of validity, shape (k,), s.
        ranges_m: measured ranges ``L^ij``, shape (n, k, Mi, Mj), m (0 where no echo).
        echo: the beam has an echo, shape (n, k, Mi, Mj).
        true_ranges_m: the ray-cast ranges before errors, shape (n, k, Mi, Mj), m (0 where the
            ray finds no seabed).
        attitude_rad: ``(gamma_k, theta_k)`` the beams were aimed from, shape (n, k, 2), rad.
    """

    t_s: Array
    ranges_m: Array
    echo: BoolArray
    true_ranges_m: Array
    attitude_rad: Array

    def no_echo_fraction(self) -> float:
        """Fraction of beams without echo (0 for an empty batch)."""
        return float(1.0 - self.echo.mean()) if self.echo.size else 0.0


class Multibeam:
    """The multibeam of a batch of runs (kinematic worlds and the online device's errors).

    Args:
        cfg: configuration.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this device.
    """

    def __init__(
        self, cfg: MultibeamConfig, seed: int, runs: tuple[int, ...], name: str = "multibeam"
    ):
        self.cfg = cfg
        self.n = len(runs)
        self._err = ErrorProcess(cfg.range.to_model(), seed, runs, ("sensor", name, "range"))

    def measure(
        self, true_ranges_m: Array, hit: BoolArray, t_s: Array, attitude_rad: Array
    ) -> MultibeamImages:
        """Apply the range errors and the echo rules to ray-cast ranges.

        Args:
            true_ranges_m: shape (n, k, Mi, Mj), m.
            hit: the ray found the seabed within ``max_range_m``, shape (n, k, Mi, Mj).
            t_s: times, shape (k,), s.
            attitude_rad: ``(gamma_k, theta_k)``, shape (n, k, 2), rad.

        Returns:
            The images (draws: one per beam and sample, in beam order within a sample).
        """
        L = np.asarray(true_ranges_m, dtype=float)
        n, k, mi, mj = L.shape
        if (mi, mj) != self.cfg.shape or n != self.n:
            raise ConfigError(
                f"multibeam: ranges of shape {L.shape}, expected ({self.n}, k, {mi}, {mj})"
            )
        t = np.repeat(np.asarray(t_s, dtype=float), mi * mj)
        meas, produced = self._err.apply(L.reshape(n, k * mi * mj), t)
        meas = np.maximum(meas.reshape(L.shape), 0.0)
        echo = np.asarray(hit, bool) & produced.reshape(L.shape)
        echo &= L <= self.cfg.max_range_m
        return MultibeamImages(
            np.asarray(t_s, dtype=float),
            np.where(echo, meas, 0.0),
            echo,
            np.where(hit, L, 0.0),
            np.asarray(attitude_rad, dtype=float),
        )

    def sample_harmonic(
        self,
        seabed: HarmonicSeabed,
        position_m: Array,
        attitude_rad: Array,
        t_s: Array,
    ) -> MultibeamImages:
        """Images over seed 004's harmonic seabed (kinematic world).

        Args:
            seabed: one seabed per run (P = n).
            position_m: transducer positions, shape (n, k, 3), m, world.
            attitude_rad: ``(gamma_k, theta_k)`` of each image, shape (n, k, 2), rad.
            t_s: times, shape (k,), s.
        """
        e = beam_directions(self.cfg, attitude_rad)  # (n, k, Mi, Mj, 3)
        o = np.asarray(position_m, dtype=float)[:, :, None, None, :]
        L, hit = seabed.ray_ranges(
            o, e, self.cfg.max_range_m, min_step_m=self.cfg.min_step_m, tol_m=self.cfg.tol_m
        )
        return self.measure(L, hit, t_s, attitude_rad)


@dataclass(frozen=True)
class MultibeamImage:
    """One image as the vehicle receives it (the payload of the online device's measurement).

    Attributes:
        ranges_m: shape (Mi, Mj), m (0 where no echo).
        echo: shape (Mi, Mj).
        attitude_rad: true ``(gamma_k, theta_k)`` the beams were aimed from (the hull's pitch and
            heading as seed 004's angles), shape (2,), rad.
        elevation_rad: ``gamma^i``, shape (Mi,), rad.
        azimuth_rad: ``theta^j``, shape (Mj,), rad.
    """

    ranges_m: Array
    echo: BoolArray
    attitude_rad: Array
    elevation_rad: Array
    azimuth_rad: Array


@register_device(MultibeamConfig)
class MultibeamDevice:
    """The multibeam in a vehicle's rig (event): an image every ``period_s`` against the scene's
    seabed heightfield (MuJoCo ray casting), valid and delivered at the ping (the two-way travel
    time of tens of metres, tens of milliseconds, is below a control tick).

    Value: the ranges, shape (Mi * Mj,), m, row-major (elevation, azimuth), 0 where no echo; the
    payload is the :class:`MultibeamImage` (echo mask, attitude, beam angles). The transducer is
    the configured lever arm, or the model's ``sonar`` site when it is zero.
    """

    kind = "event"

    def __init__(self, cfg: MultibeamConfig, build: DeviceBuild):
        cfg = build.with_site(cfg, "transducer_body_m", "sonar")
        self.cfg = cfg
        self.lever_arm_body_m = np.asarray(cfg.transducer_body_m, dtype=float)
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._physics = build.physics
        self._mb = Multibeam(cfg, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement | None:
        """An image at the multibeam's ticks."""
        if ctx.k % self.every:
            return None
        vt = ctx.truth
        _roll, pitch, heading = vt.roll_pitch_heading_rad
        att = np.array([pitch, float(theta_from_course(heading))])
        R = R_from_quat_wxyz(vt.quat_wxyz)
        origin = vt.position_world_m + R @ self.lever_arm_body_m
        e = beam_directions(self.cfg, att).reshape(-1, 3)
        dist, hit = self._physics.seabed_ray_distances(origin, e, self.cfg.max_range_m)
        shape = self.cfg.shape
        img = self._mb.measure(
            dist.reshape(1, 1, *shape), hit.reshape(1, 1, *shape), ctx.tt, att[None, None]
        )
        payload = MultibeamImage(
            img.ranges_m[0, 0],
            img.echo[0, 0],
            att,
            self.cfg.elevations_rad(),
            self.cfg.azimuths_rad(),
        )
        return Measurement(
            self.name,
            ctx.t_s,
            ctx.t_s,
            img.ranges_m[0, 0].reshape(-1),
            ctx.measured_attitude_rad,
            payload,
        )
