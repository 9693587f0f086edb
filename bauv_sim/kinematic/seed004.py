"""Seed 004's kinematic world: a vehicle on a 3-D nominal path and bearings to surface beacons.

Truth (seed 004, section 6). Angles in seed 004's mathematical convention (theta from the x axis
counter-clockwise, gamma up from the horizontal; x, y, z up, m). The nominal path is eq. 3 with
``gamma°_k = pi/100 cos(pi t_k / 100)``, ``theta°_k = pi/3 cos(pi t_k / 25)``, ``V° = 2 m/s``,
``X°_0 = (0, 0, -10)``, ``dt = 1 s``, ``T = 300 s``. The vehicle moves by eq. 1-2,
``X_{k+1} = X_k + V(u_k) dt + W_k`` with ``W_k ~ N(0, S^W)``, ``S^W = I`` m^2, from ``X_0 ~
N(X°_0, S_0)``, ``S_0 = I`` m^2 (the seed's reading notes: the start is spread around the
nominal start, the filters start at ``m_0 = X°_0``). The control ``u_k`` is given by the caller
(the task closes the loop with an estimator and :mod:`nav.bearings.local_control`).

Measurements: the bearing tangents of eq. 17 to each beacon, ``tan phi = (Y_B - Y)/(X_B - X) +
eps^phi`` and ``tan lambda = (Z_B - Z)/rho + eps^lambda`` (phi the full bearing, so ``cos phi /
(X_B - X) = 1/rho``, rho the horizontal distance; :mod:`nav.bearings`), ``eps ~ N(0, sigma^2 I)``
with ``sigma = tan(0.5 deg)`` as stated. A pair is not produced when the beacon is straight
above or below the vehicle (``rho < min_rho_m``) or ``|tan phi| > max_tan``; such pairs are
flagged absent (never NaN).

Streams (:mod:`bauv_sim.rng`). Test paths draw per run: ``(seed, run, "seed004", "x0" | "w" |
"eps")``, so run i draws the same numbers in any block. The CMNF's training paths cannot be drawn
ahead per path (1e5 paths x 300 steps x 11 numbers would be 2.6 GB), so they draw per chunk of
``TRAIN_CHUNK`` paths and per step: ``(seed, chunk, "seed004", "train", part, str(k))``; path j of
chunk c is the same for any number of training paths that includes it.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator, model_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.rng import RunStreams, generator

Array = NDArray[np.float64]

TRAIN_CHUNK = 10_000
"""Training paths per stream chunk (fixed: the draws of a path do not depend on the count)."""

SECTION6_BEACONS = (
    (500.0, 100.0, 0.0),
    (500.0, -100.0, 0.0),
    (-100.0, 100.0, 0.0),
    (-100.0, -100.0, 0.0),
)
"""Beacons X_B^1..4 of seed 004, section 6, m."""


class NominalPathConfig(Config):
    """The nominal path (seed 004, eq. 3 and section 6)."""

    gamma_amplitude_rad: float = Field(math.pi / 100, description="amplitude of gamma°, rad")
    gamma_rate_rad_s: float = Field(math.pi / 100, description="angular frequency of gamma°, rad/s")
    theta_amplitude_rad: float = Field(math.pi / 3, description="amplitude of theta°, rad")
    theta_rate_rad_s: float = Field(math.pi / 25, description="angular frequency of theta°, rad/s")
    speed_m_s: float = Field(2.0, gt=0, le=50, description="nominal speed V°, m/s")
    start_m: tuple[float, float, float] = Field(
        (0.0, 0.0, -10.0), description="X°_0 (x, y, z up), m"
    )
    dt_s: float = Field(1.0, gt=0, le=60, description="time step, s")
    duration_s: float = Field(300.0, gt=0, le=100_000, description="T, s")

    @model_validator(mode="after")
    def _grid(self) -> NominalPathConfig:
        n = self.duration_s / self.dt_s
        if abs(n - round(n)) > 1e-9 * max(1.0, n) or round(n) < 1:
            raise ConfigError(
                f"path.duration_s = {self.duration_s}: must be a positive multiple of path.dt_s "
                f"= {self.dt_s}"
            )
        return self

    @property
    def n_steps(self) -> int:
        """N: steps from t_0 = 0 to t_N = T."""
        return round(self.duration_s / self.dt_s)

    def controls(self) -> Array:
        """Nominal controls at t_0 .. t_{N-1}, shape ``(N, 3)``: gamma rad, theta rad, V m/s."""
        t = np.arange(self.n_steps) * self.dt_s
        g = self.gamma_amplitude_rad * np.cos(self.gamma_rate_rad_s * t)
        th = self.theta_amplitude_rad * np.cos(self.theta_rate_rad_s * t)
        return np.stack([g, th, np.full_like(t, self.speed_m_s)], axis=1)

    def velocities(self) -> Array:
        """Nominal velocities V°_k at t_0 .. t_{N-1}, shape ``(N, 3)``, m/s (eq. 2)."""
        return velocity(self.controls())

    def path(self) -> Array:
        """Nominal positions X°_0 .. X°_N, shape ``(N + 1, 3)``, m (eq. 3)."""
        steps = self.velocities() * self.dt_s
        x0 = np.asarray(self.start_m, dtype=float)
        return np.concatenate([x0[None], x0 + np.cumsum(steps, axis=0)])


class Seed004Noise(Config):
    """Disturbances and bearing noise (seed 004, section 6)."""

    sigma_w_m: tuple[float, float, float] = Field(
        (1.0, 1.0, 1.0), description="standard deviations of W_k per axis (S^W = I), m"
    )
    sigma_x0_m: tuple[float, float, float] = Field(
        (1.0, 1.0, 1.0), description="standard deviations of X_0 about X°_0 per axis (S_0 = I), m"
    )
    bearing_sigma_deg: float = Field(
        0.5,
        gt=0,
        lt=45,
        description="bearing precision: the tangents' noise sigma is tan(this) (section 6: "
        "0.5 deg; the seed README: tan(1 deg) reproduces Table 1)",
    )
    min_rho_m: float = Field(
        1e-3,
        gt=0,
        description="beacon straight above/below within this horizontal distance: no bearing, m",
    )
    max_tan: float = Field(1e3, gt=0, description="no bearing when |tan phi| exceeds this")

    @field_validator("sigma_w_m", "sigma_x0_m")
    @classmethod
    def _positive(cls, v: tuple[float, float, float]) -> tuple[float, float, float]:
        if any(not s >= 0 for s in v):
            raise ValueError(f"{v}: every sigma must be >= 0 m")
        return v

    @property
    def s_w(self) -> Array:
        """S^W, ``(3, 3)`` m^2."""
        return np.diag(np.square(self.sigma_w_m))

    @property
    def s_0(self) -> Array:
        """S_0, ``(3, 3)`` m^2."""
        return np.diag(np.square(self.sigma_x0_m))

    @property
    def tangent_sigma(self) -> float:
        """sigma of the tangents' noise (dimensionless)."""
        return math.tan(math.radians(self.bearing_sigma_deg))

    @property
    def s_eps(self) -> Array:
        """S^eps of one beacon's pair, ``(2, 2)``."""
        return self.tangent_sigma**2 * np.eye(2)


def velocity(u: Array) -> Array:
    """Velocity of controls ``(..., 3)`` (gamma, theta, V) -> ``(..., 3)`` m/s (seed 004, eq. 2)."""
    g, th, v = u[..., 0], u[..., 1], u[..., 2]
    out = np.empty(u.shape)
    vc = v * np.cos(g)
    np.multiply(vc, np.cos(th), out=out[..., 0])
    np.multiply(vc, np.sin(th), out=out[..., 1])
    np.multiply(v, np.sin(g), out=out[..., 2])
    return out


def true_bearings(
    x: Array, beacons: Array, min_rho_m: float, max_tan: float
) -> tuple[Array, NDArray[np.bool_]]:
    """Noise-free eq. 17 tangents ``(n, B, 2)`` and their presence ``(n, B)`` at ``(n, 3)`` m."""
    dx = beacons[:, 0] - x[:, 0:1]  # (n, B)
    dy = beacons[:, 1] - x[:, 1:2]
    dz = beacons[:, 2] - x[:, 2:3]
    rho = np.sqrt(dx * dx + dy * dy)
    ok = (rho >= min_rho_m) & (np.abs(dy) <= max_tan * np.abs(dx))
    h = np.empty((*dx.shape, 2))
    if ok.all():
        np.divide(dy, dx, out=h[..., 0])
        np.divide(dz, rho, out=h[..., 1])
    else:
        h[..., 0] = np.where(ok, dy / np.where(ok, dx, 1.0), 0.0)
        h[..., 1] = np.where(ok, dz / np.where(ok, rho, 1.0), 0.0)
    return h, ok


class PathNoise:
    """The draws of a block of test paths, per run (module docstring).

    Attributes:
        x0: ``(n, 3)`` m, the start's deviation from X°_0; w: ``(n, N, 3)`` m; eps: ``(n, N + 1,
        B, 2)`` tangent noise at t_0 .. t_N.
    """

    def __init__(
        self, noise: Seed004Noise, n_steps: int, n_beacons: int, seed: int, runs: tuple[int, ...]
    ):
        n = len(runs)
        sw = np.asarray(noise.sigma_w_m)
        s0 = np.asarray(noise.sigma_x0_m)

        def normals(part: str, shape: tuple[int, ...]) -> Array:
            size = int(np.prod(shape))
            return (
                RunStreams(seed, runs, "seed004", part)
                .draw("standard_normal", size)
                .reshape(n, *shape)
            )

        self.x0 = s0 * normals("x0", (3,))
        self.w = sw * normals("w", (n_steps, 3))
        self.eps = noise.tangent_sigma * normals("eps", (n_steps + 1, n_beacons, 2))

    def start(self) -> Array:
        """Deviation of X_0 from X°_0, ``(n, 3)`` m."""
        return self.x0

    def w_at(self, k: int) -> Array:
        """W_k, ``(n, 3)`` m."""
        return self.w[:, k]

    def eps_at(self, k: int) -> Array:
        """Tangent noise at t_k, ``(n, B, 2)``."""
        return self.eps[:, k]


class TrainingNoise:
    """The draws of ``n`` CMNF training paths, per chunk of :data:`TRAIN_CHUNK` and step."""

    def __init__(
        self, noise: Seed004Noise, n_beacons: int, seed: int, n: int, stream: str = "train"
    ):
        self.noise, self.nb, self.seed, self.n, self.stream = noise, n_beacons, seed, n, stream
        self.chunks = [
            (c, min(TRAIN_CHUNK, n - c * TRAIN_CHUNK)) for c in range(-(-n // TRAIN_CHUNK))
        ]

    def _draw(self, part: str, k: int, shape: tuple[int, ...]) -> Array:
        out = [
            generator(self.seed, c, "seed004", self.stream, part, str(k)).standard_normal(
                (m, *shape)
            )
            for c, m in self.chunks
        ]
        return np.concatenate(out)

    def start(self) -> Array:
        """Deviation of X_0 from X°_0, ``(n, 3)`` m."""
        return np.asarray(self.noise.sigma_x0_m) * self._draw("x0", 0, (3,))

    def w_at(self, k: int) -> Array:
        """W_k, ``(n, 3)`` m (drawn on each call: call once per step)."""
        return np.asarray(self.noise.sigma_w_m) * self._draw("w", k, (3,))

    def eps_at(self, k: int) -> Array:
        """Tangent noise at t_k, ``(n, B, 2)`` (drawn on each call: call once per step)."""
        return self.noise.tangent_sigma * self._draw("eps", k, (self.nb, 2))


class Seed004World:
    """Truth and bearings of a batch of paths (implements :class:`nav.bearings.cmnf.TrainingWorld`).

    Args:
        path: the nominal path.
        noise: disturbances and bearing noise.
        beacons: ``(B, 3)`` m.
        draws: :class:`PathNoise` (test paths) or :class:`TrainingNoise`.
    """

    def __init__(self, path: NominalPathConfig, noise: Seed004Noise, beacons: Array, draws):
        self.path, self.noise, self.draws = path, noise, draws
        self.beacons = np.asarray(beacons, dtype=float)
        self.x0_nominal = np.asarray(path.start_m, dtype=float)

    def start(self) -> Array:
        """True X_0, ``(n, 3)`` m."""
        return self.x0_nominal + self.draws.start()

    def advance(self, k: int, x: Array, u: Array) -> Array:
        """True X_{k+1} from X_k ``(n, 3)`` and u_k ``(n, 3)`` (eq. 1-2)."""
        return x + velocity(u) * self.path.dt_s + self.draws.w_at(k)

    def observe(self, k: int, x: Array) -> tuple[Array, NDArray[np.bool_]]:
        """Measured tangents ``(n, B, 2)`` and presence ``(n, B)`` at t_k (eq. 17)."""
        h, ok = true_bearings(x, self.beacons, self.noise.min_rho_m, self.noise.max_tan)
        h += self.draws.eps_at(k)
        if not ok.all():
            h[~ok] = 0.0
        return h, ok


def check_beacons(beacons) -> Array:
    """Beacons as ``(B, 3)`` floats (B >= 1), m.

    Raises:
        ConfigError: naming the field and the value.
    """
    b = np.asarray(beacons, dtype=float)
    if b.ndim != 2 or b.shape[1] != 3 or len(b) == 0 or not np.isfinite(b).all():
        raise ConfigError(f"beacons = {beacons!r}: must be a list of one or more [x, y, z] in m")
    return b
