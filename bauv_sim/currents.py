"""Sea current fields: uniform, seed 001's randomised current, spatially varying fields, and an
ocean model's current from a file (``gridded``, :mod:`bauv_sim.ocean`).

Every field answers one question, :meth:`CurrentField.velocity_world`: the water velocity (world
frame, m/s) at given times and positions. The physics world evaluates it at the vehicle at each
control tick (MuJoCo's ``option wind`` is the velocity of the medium); the kinematic worlds add it
to the vehicle's velocity through water. The current at the vehicle is part of truth.

Directions are *set* directions: the direction the water flows towards, clockwise from north, as in
seed 001 (alpha_c) and nautical practice.
"""

from __future__ import annotations

import datetime as dt
import math
from typing import TYPE_CHECKING, Annotated, Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, field_validator, model_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.frames import velocity_from_course_speed

if TYPE_CHECKING:
    from bauv_sim.geo import LocalFrame


class CurrentField(Protocol):
    """A water-velocity field over time and space."""

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        """Water velocity at the given times and positions.

        Args:
            t_s: simulation time, shape broadcastable with ``pos_world_m[..., 0]``, s.
            pos_world_m: positions, shape (..., 3), m, world frame (z up).

        Returns:
            Water velocity, shape (..., 3), m/s, world frame.
        """
        ...


def _as_pos(pos_world_m: ArrayLike) -> NDArray[np.float64]:
    p = np.asarray(pos_world_m, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"pos_world_m must have a trailing axis of 3, got shape {p.shape}")
    return p


def _horizontal(vel_en: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate([vel_en, np.zeros(vel_en.shape[:-1] + (1,))], axis=-1)


class UniformCurrent:
    """The same horizontal velocity everywhere and always (``steady_uniform``: a world may apply
    it once instead of at every tick).

    Args:
        speed_m_s: current speed, m/s, >= 0.
        direction_rad: set direction (towards), clockwise from north, rad.
    """

    def __init__(self, speed_m_s: float, direction_rad: float) -> None:
        self.speed_m_s = float(speed_m_s)
        self.direction_rad = float(direction_rad)
        self._v = _horizontal(velocity_from_course_speed(self.direction_rad, self.speed_m_s))

    steady_uniform = True

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        p = _as_pos(pos_world_m)
        shape = np.broadcast_shapes(np.shape(t_s), p.shape[:-1])
        return np.broadcast_to(self._v, shape + (3,)).copy()


class RandomisedCurrent:
    """Seed 001's randomised current: a dominant current with held random perturbations.

    Seed 001, section "Conditions of experiments", text around eq. 29: the magnitude and the
    direction of the current are drawn from normal distributions N(|Vc|, sigma_V^2) and
    N(alpha_c, sigma_alpha^2), and the same deviation is held for N_d steps, N_d uniform on
    [1, N_d,max]. Here the hold is expressed in seconds (N_d,max times the paper's step), and the
    paper's hull-angle scaling of |Vc| (eq. 29, rho_s) belongs to the kinematic replica, since in
    the physics world the hull's response to the current comes out of the fluid forces.

    The realisation is piecewise constant in time and uniform in space. Segments are drawn lazily in
    time order from ``rng``, so any sequence of queries sees the same realisation.

    Args:
        mean_speed_m_s: dominant magnitude |Vc|, m/s.
        mean_direction_rad: dominant set direction alpha_c, clockwise from north, rad.
        sigma_speed_m_s: standard deviation of the magnitude sigma_V, m/s.
        sigma_direction_rad: standard deviation of the direction sigma_alpha, rad.
        hold_max_s: longest hold of one perturbation, s (the hold is uniform on
            [hold_step_s, hold_max_s] in whole steps).
        hold_step_s: granularity of the hold, s (seed 001: t = 0.001 s).
        rng: the current's own random stream.
    """

    def __init__(
        self,
        mean_speed_m_s: float,
        mean_direction_rad: float,
        sigma_speed_m_s: float,
        sigma_direction_rad: float,
        hold_max_s: float,
        hold_step_s: float,
        rng: np.random.Generator,
    ) -> None:
        if hold_step_s <= 0 or hold_max_s < hold_step_s:
            raise ValueError(
                f"hold_step_s = {hold_step_s}, hold_max_s = {hold_max_s}: need 0 < step <= max"
            )
        self.mean_speed_m_s = float(mean_speed_m_s)
        self.mean_direction_rad = float(mean_direction_rad)
        self.sigma_speed_m_s = float(sigma_speed_m_s)
        self.sigma_direction_rad = float(sigma_direction_rad)
        self.hold_step_s = float(hold_step_s)
        self.hold_max_steps = max(1, round(hold_max_s / hold_step_s))
        self._rng = rng
        self._ends: list[float] = []  # segment k spans [ends[k-1], ends[k]), ends[-1] = 0
        self._vel: list[NDArray[np.float64]] = []
        self._extend_to(0.0)

    def _extend_to(self, t_max: float) -> None:
        """Draw segments in time order until one covers ``t_max``."""
        while not self._ends or self._ends[-1] <= t_max:
            start = self._ends[-1] if self._ends else 0.0
            speed = self._rng.normal(self.mean_speed_m_s, self.sigma_speed_m_s)
            direction = self._rng.normal(self.mean_direction_rad, self.sigma_direction_rad)
            steps = int(self._rng.integers(1, self.hold_max_steps, endpoint=True))
            self._ends.append(start + steps * self.hold_step_s)
            # a negative magnitude draw is a current set the other way
            self._vel.append(_horizontal(velocity_from_course_speed(direction, speed)))

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        p = _as_pos(pos_world_m)
        t = np.asarray(t_s, dtype=float)
        if np.any(t < 0):
            raise ValueError("RandomisedCurrent is defined for t >= 0 only")
        self._extend_to(float(np.max(t)) if t.size else 0.0)
        idx = np.searchsorted(np.asarray(self._ends), t, side="right")
        vel = np.asarray(self._vel)[idx]
        shape = np.broadcast_shapes(t.shape, p.shape[:-1])
        return np.broadcast_to(vel, shape + (3,)).copy()


class ShearCurrent:
    """A horizontal current whose speed varies linearly with depth (a bottom boundary layer or a
    wind-driven surface layer).

    ``speed(d) = surface_speed + (bottom_speed - surface_speed) * clip(d / bottom_depth, 0, 1)``
    with ``d`` the depth

    Args:
        surface_speed_m_s: speed at the surface, m/s.
        bottom_speed_m_s: speed at ``bottom_depth_m`` and below, m/s.
        bottom_depth_m: depth where the profile reaches ``bottom_speed_m_s``, m (> 0).
        direction_rad: set direction, clockwise from north, rad.
    """

    def __init__(
        self,
        surface_speed_m_s: float,
        bottom_speed_m_s: float,
        bottom_depth_m: float,
        direction_rad: float,
    ) -> None:
        if bottom_depth_m <= 0:
            raise ValueError(f"bottom_depth_m = {bottom_depth_m}: must be > 0")
        self.surface_speed_m_s = float(surface_speed_m_s)
        self.bottom_speed_m_s = float(bottom_speed_m_s)
        self.bottom_depth_m = float(bottom_depth_m)
        self.direction_rad = float(direction_rad)

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        p = _as_pos(pos_world_m)
        frac = np.clip(-p[..., 2] / self.bottom_depth_m, 0.0, 1.0)
        speed = self.surface_speed_m_s + (self.bottom_speed_m_s - self.surface_speed_m_s) * frac
        speed = np.broadcast_to(speed, np.broadcast_shapes(np.shape(t_s), speed.shape))
        return _horizontal(velocity_from_course_speed(self.direction_rad, speed))


class GyreCurrent:
    """A horizontal Rankine vortex (a tidal or topographic gyre), optionally modulated by a tide.

    Inside ``core_radius_m`` the water turns as a solid body; outside, the speed decays as
    ``max_speed * core_radius / r``. The tangential speed is multiplied by
    ``cos(2 pi t / tidal_period_s)`` when a tidal period is given (the gyre reverses with the tide).

    Args:
        center_en_m: gyre centre (east, north), m, world frame.
        core_radius_m: radius of the fastest ring, m (> 0).
        max_speed_m_s: tangential speed at the core radius, m/s.
        clockwise: sense of rotation seen from above.
        tidal_period_s: period of the tidal modulation, s, or ``None`` for a steady gyre.
    """

    def __init__(
        self,
        center_en_m: tuple[float, float],
        core_radius_m: float,
        max_speed_m_s: float,
        clockwise: bool = True,
        tidal_period_s: float | None = None,
    ) -> None:
        if core_radius_m <= 0:
            raise ValueError(f"core_radius_m = {core_radius_m}: must be > 0")
        self.center_en_m = np.asarray(center_en_m, dtype=float)
        self.core_radius_m = float(core_radius_m)
        self.max_speed_m_s = float(max_speed_m_s)
        self.clockwise = bool(clockwise)
        self.tidal_period_s = tidal_period_s

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        p = _as_pos(pos_world_m)
        d = p[..., :2] - self.center_en_m
        r = np.hypot(d[..., 0], d[..., 1])
        rc = self.core_radius_m
        speed = np.where(
            r <= rc, self.max_speed_m_s * r / rc, self.max_speed_m_s * rc / np.maximum(r, rc)
        )
        t = np.asarray(t_s, dtype=float)
        if self.tidal_period_s is not None:
            speed = speed * np.cos(2.0 * math.pi * t / self.tidal_period_s)
        # unit tangent: counter-clockwise is (-dy, dx)/r
        safe_r = np.where(r > 0, r, 1.0)
        sense = -1.0 if self.clockwise else 1.0
        tx, ty = sense * -d[..., 1] / safe_r, sense * d[..., 0] / safe_r
        vx, vy = np.broadcast_arrays(speed * tx, speed * ty)
        return np.stack([vx, vy, np.zeros_like(vx)], axis=-1)


class SumCurrent:
    """The sum of several fields (e.g. a tidal gyre over a uniform drift)."""

    def __init__(self, *fields: CurrentField) -> None:
        self.fields = fields

    def velocity_world(self, t_s: ArrayLike, pos_world_m: ArrayLike) -> NDArray[np.float64]:
        out = np.zeros(np.broadcast_shapes(np.shape(t_s), _as_pos(pos_world_m).shape[:-1]) + (3,))
        for f in self.fields:
            out = out + f.velocity_world(t_s, pos_world_m)
        return out


# --------------------------------------------------------------------------------------------
# Configuration


class UniformCurrentConfig(Config):
    """A uniform current."""

    kind: Literal["uniform"] = "uniform"
    speed_m_s: float = Field(0.0, ge=0, le=5, description="current speed, m/s")
    direction_deg: float = Field(
        0.0, ge=0, lt=360, description="set (towards), clockwise from north, deg"
    )


class RandomisedCurrentConfig(Config):
    """Seed 001's randomised current.

    Defaults are the paper's: sigma_V^2 = 0.02, sigma_alpha^2 = 10 deg^2, N_d,max = 10000 steps of
    0.001 s.
    """

    kind: Literal["randomised"] = "randomised"
    speed_m_s: float = Field(0.3, ge=0, le=5, description="dominant magnitude |Vc|, m/s")
    direction_deg: float = Field(20.0, ge=0, lt=360, description="dominant set alpha_c, deg")
    sigma_speed_m_s: float = Field(math.sqrt(0.02), ge=0, description="sigma_V, m/s")
    sigma_direction_deg: float = Field(math.sqrt(10.0), ge=0, description="sigma_alpha, deg")
    hold_max_s: float = Field(10.0, gt=0, description="N_d,max times the hold step, s")
    hold_step_s: float = Field(0.001, gt=0, description="seed 001's step t, s")

    @model_validator(mode="after")
    def _hold(self) -> RandomisedCurrentConfig:
        if self.hold_max_s < self.hold_step_s:
            raise ValueError(
                f"hold_max_s = {self.hold_max_s} must be >= hold_step_s = {self.hold_step_s}"
            )
        return self


class ShearCurrentConfig(Config):
    """A current varying linearly with depth."""

    kind: Literal["shear"] = "shear"
    surface_speed_m_s: float = Field(0.3, ge=0, le=5)
    bottom_speed_m_s: float = Field(0.05, ge=0, le=5)
    bottom_depth_m: float = Field(30.0, gt=0)
    direction_deg: float = Field(0.0, ge=0, lt=360)


class GyreCurrentConfig(Config):
    """A Rankine gyre, optionally tidal."""

    kind: Literal["gyre"] = "gyre"
    center_east_m: float = 0.0
    center_north_m: float = 0.0
    core_radius_m: float = Field(200.0, gt=0)
    max_speed_m_s: float = Field(0.3, ge=0, le=5)
    clockwise: bool = True
    tidal_period_s: float | None = Field(None, gt=0)


class GriddedCurrentConfig(Config):
    """A current from an ocean model's file: ``u``, ``v`` (and ``w``) on (time, depth, latitude,
    longitude) in a CF-convention netCDF file, interpolated linearly in space and time
    (:class:`bauv_sim.ocean.GriddedCurrent`). The scenario needs a geographic origin (``geo``)
    to place the scene's east/north on the file's latitude and longitude.
    """

    kind: Literal["gridded"] = "gridded"
    file: str = Field(
        description="the netCDF file (a path, relative to the current directory); read once per "
        "process"
    )
    start_time: str | None = Field(
        None,
        description="the date and time of the mission's t = 0, ISO 8601 in UTC "
        "(e.g. 2026-06-01T06:00:00Z; without a zone, UTC; another offset is converted); "
        "default the file's first time",
    )

    @field_validator("start_time")
    @classmethod
    def _iso(cls, v: str | None) -> str | None:
        if v is not None:
            parse_utc(v)
        return v

    def start(self) -> dt.datetime | None:
        """The mission's t = 0 as a naive UTC date and time, or ``None`` (the file's first)."""
        return None if self.start_time is None else parse_utc(self.start_time)


def parse_utc(text: str) -> dt.datetime:
    """An ISO 8601 date and time as a naive UTC datetime (no zone: UTC).

    Raises:
        ValueError: for text that is not ISO 8601.
    """
    try:
        t = dt.datetime.fromisoformat(text.strip().replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(
            f"{text!r} is not an ISO 8601 date and time (e.g. 2026-06-01T06:00:00Z)"
        ) from None
    if t.tzinfo is not None:
        t = t.astimezone(dt.UTC).replace(tzinfo=None)
    return t


CurrentConfig = Annotated[
    UniformCurrentConfig
    | RandomisedCurrentConfig
    | ShearCurrentConfig
    | GyreCurrentConfig
    | GriddedCurrentConfig,
    Field(discriminator="kind"),
]
"""Any current configuration, chosen by its ``kind`` field."""


def make_current(
    cfg: CurrentConfig,
    rng: np.random.Generator | None = None,
    frame: LocalFrame | None = None,
) -> CurrentField:
    """Build a current field from its configuration.

    Args:
        cfg: a current configuration.
        rng: the current's own stream (required for ``randomised``).
        frame: the scene's geographic frame (required for ``gridded``; the other kinds ignore
            it).

    Returns:
        The field.

    Raises:
        ConfigError: a gridded current without a frame, or whose file cannot be used (one line
            naming ``current.file``, the file, the variable and what is wrong).
    """
    if isinstance(cfg, GriddedCurrentConfig):
        return _gridded(cfg, frame)
    if isinstance(cfg, UniformCurrentConfig):
        return UniformCurrent(cfg.speed_m_s, math.radians(cfg.direction_deg))
    if isinstance(cfg, RandomisedCurrentConfig):
        if rng is None:
            raise ValueError("a randomised current needs its random stream")
        return RandomisedCurrent(
            cfg.speed_m_s,
            math.radians(cfg.direction_deg),
            cfg.sigma_speed_m_s,
            math.radians(cfg.sigma_direction_deg),
            cfg.hold_max_s,
            cfg.hold_step_s,
            rng,
        )
    if isinstance(cfg, ShearCurrentConfig):
        return ShearCurrent(
            cfg.surface_speed_m_s,
            cfg.bottom_speed_m_s,
            cfg.bottom_depth_m,
            math.radians(cfg.direction_deg),
        )
    if isinstance(cfg, GyreCurrentConfig):
        return GyreCurrent(
            (cfg.center_east_m, cfg.center_north_m),
            cfg.core_radius_m,
            cfg.max_speed_m_s,
            cfg.clockwise,
            cfg.tidal_period_s,
        )
    raise TypeError(f"unknown current configuration {cfg!r}")


def _gridded(cfg: GriddedCurrentConfig, frame: LocalFrame | None) -> CurrentField:
    from bauv_sim.ocean import GriddedCurrent, load_current_grid

    if frame is None:
        raise ConfigError(
            f"current.file = {cfg.file}: a gridded current needs the scenario's geo origin "
            "(geo.latitude_deg, geo.longitude_deg)"
        )
    try:
        grid = load_current_grid(cfg.file, cfg.start())
    except ConfigError as exc:
        raise ConfigError(f"current.file: {exc}") from None
    return GriddedCurrent(grid, frame, name=f"current.file = {cfg.file}")
