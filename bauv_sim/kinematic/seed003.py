"""Seed 003's kinematic world: a leader and a follower on a square path, and their measurements.

Truth (seed 003, section 3): the leader L moves along the reference path, a square of ``n_legs``
legs of ``leg_s`` seconds at ``speed_m_s``, starting on ``initial_course_deg`` (45 deg) and changing
course by 90 deg at the end of each leg. Its reference positions are dead-reckoned exactly from the
reference course and speed with the constant step ``tick_s`` (0.1 s, the 10 Hz of the course and
speed measurements), as the paper's application does ("simulating successive reference positions
... using the DR method with a constant time step"). The follower F keeps ``distance_m`` (10 m) at a
relative bearing (90 deg in Tests 1 and 3, 180 deg in Test 2).

The paper leaves three things of the geometry open (``../shared/seeds/README.md``, seed 003 notes);
each is an option of :class:`FormationConfig`:

* **which way the square turns** (``SquarePathConfig.turn``): the text says only "a change of the
  course by 90 deg every 120 s". ``"right"`` (45, 135, 225, 315 deg, clockwise) is the default;
  ``"left"`` (45, 315, 225, 135 deg) is the other reading. Either visits each 90-degree sector of
  the course-sector bias once.
* **how the offset is kept** (``offset``): ``"world"`` (default) - L and F follow "the same
  course at the same speed" (the simulation text), so F's velocity is L's and the offset is fixed
  in world axes, set by the relative bearing on the first leg; on the next legs F is no longer
  abeam (or astern). ``"leg"`` - the relative bearing is kept on every leg (the discussion's
  "vehicles moving side by side"): after each turn F moves in a straight line, in ``corner_s``
  seconds, from its old station to the new one (with the default ``corner_s = distance / speed``
  this is a sideways move at the formation's speed), and rides the leg at L's velocity after it.
* **whose relative bearing** (``bearing_of``): ``"follower_from_leader"`` (default, as in Figure
  2: F is seen from L at the relative bearing) or ``"leader_from_follower"`` (L is seen from F at
  the relative bearing, which puts F on the other side, or ahead).

Measurements (seed 003, section 3; errors in the shared vocabulary of
:mod:`bauv_sim.sensors.errors`, drawn from streams addressed by ``(seed, run, path)``):

* F's course at 10 Hz: ``C = C^R + zeta_C^1 + zeta_C^2``, with ``zeta^1`` uniform on
  ``[-sigma, +sigma]`` (``uniform_k = 1``, sigma_C = 2 deg; the seed's reading notes) and
  ``zeta^2`` the course-sector bias (4, 8, 0, 2 deg by 90-degree sector of the true course in
  Tests 1-2; 0.4, 0.8, 0, 0.2 in Test 3);
* F's speed at 10 Hz: ``S = S^R + zeta_S^1 + zeta_S^2``, sigma_S = 0.3 m/s, bias 0.05 m/s (Test 3:
  0.005);
* the range D_h between the reference positions of L and F every 5 s (0.2 Hz), sigma 0.1 m plus
  a range bias 0.025 m (Test 3: 0.0025), with a maximum range, dropout windows and the
  vocabulary's dropout probability; a measured range is never negative (clipped at 0);
* the leader's broadcast position, sent with the range: its true position (the paper: "the
  simulated coordinate values of the position of vehicle L sent to vehicle F are equal to their
  reference values"), or with an optional error per axis.

This module produces truth and measurements only; navigation is :mod:`nav.relative`. The online
modem device of the physics world is :mod:`bauv_sim.sensors.modem`; the batched range here uses
the same error vocabulary directly.

References:
    Naus K., Piskur P. (2022), Applying the geodetic adjustment method for positioning in relation
    to the swarm leader of underwater vehicles based on course, speed, and distance measurements,
    Energies 15, 8472 (seed 003), section 3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.frames import unit_vector, wrap_2pi
from bauv_sim.sensors.base import check_multiple, periodic_indices
from bauv_sim.sensors.compass import Compass, CompassConfig
from bauv_sim.sensors.errors import (
    AngleErrorConfig,
    ErrorProcess,
    LengthErrorConfig,
    SpeedErrorConfig,
)
from bauv_sim.sensors.log import Log, LogConfig
from bauv_sim.truth import Truth

Array = NDArray[np.float64]


class SquarePathConfig(Config):
    """The leader's reference path (seed 003 section 3: one square, 120 s a side at 1 m/s)."""

    speed_m_s: float = Field(1.0, gt=0, le=10, description="reference speed S^R, m/s")
    leg_s: float = Field(120.0, gt=0, description="duration of one leg, s")
    n_legs: int = Field(4, ge=1, le=400, description="number of legs (one square: 4)")
    initial_course_deg: float = Field(
        45.0, ge=0, lt=360, description="reference course C^R of the first leg, deg"
    )
    turn: Literal["right", "left"] = Field(
        "right",
        description="direction of the 90 deg course change: right (clockwise: 45, 135, 225, "
        "315 deg) or left (45, 315, 225, 135 deg); the text does not say",
    )
    tick_s: float = Field(0.1, gt=0, description="time step of truth and of C, S (10 Hz), s")
    start_east_m: float = Field(0.0, description="leader's start, east, m, world")
    start_north_m: float = Field(0.0, description="leader's start, north, m, world")

    @model_validator(mode="after")
    def _grid(self) -> SquarePathConfig:
        check_multiple(self.leg_s, self.tick_s, "path.leg_s")
        return self

    @property
    def ticks_per_leg(self) -> int:
        """Ticks of one leg."""
        return round(self.leg_s / self.tick_s)

    @property
    def n_ticks(self) -> int:
        """Number of ticks including t = 0 (T + 1)."""
        return self.n_legs * self.ticks_per_leg + 1

    def leg_courses_rad(self) -> Array:
        """Reference course of each leg, shape (n_legs,), rad in [0, 2 pi) clockwise from north."""
        sign = 1.0 if self.turn == "right" else -1.0
        deg = self.initial_course_deg + sign * 90.0 * np.arange(self.n_legs)
        return wrap_2pi(np.radians(deg))


class FormationConfig(Config):
    """Where the follower keeps station (the readings are explained in the module docstring)."""

    distance_m: float = Field(
        10.0, ge=0, description="distance between L and F, m (D_h^R = 10 m; 0 provokes zero range)"
    )
    relative_bearing_deg: float = Field(
        90.0, ge=0, lt=360, description="relative bearing, deg clockwise from the bow (Test 2: 180)"
    )
    bearing_of: Literal["follower_from_leader", "leader_from_follower"] = Field(
        "follower_from_leader",
        description="follower_from_leader: F seen from L at the relative bearing (Figure 2); "
        "leader_from_follower: L seen from F at it",
    )
    offset: Literal["world", "leg"] = Field(
        "world",
        description="world: same course and speed, offset fixed in world axes from the first "
        "leg (the simulation text); leg: the relative bearing kept on every leg (the discussion)",
    )
    corner_s: float | None = Field(
        None,
        gt=0,
        description="offset = leg: time F takes to move to its new station after a turn, s "
        "(a multiple of the tick, shorter than a leg; default distance / speed)",
    )


def _offset(course_rad: Array, f: FormationConfig) -> Array:
    """Follower minus leader for legs of the given courses, shape (k, 2), m (east, north)."""
    b = math.radians(f.relative_bearing_deg)
    u = unit_vector(course_rad + b)
    sign = 1.0 if f.bearing_of == "follower_from_leader" else -1.0
    return sign * f.distance_m * u


def corner_ticks(path: SquarePathConfig, f: FormationConfig) -> int:
    """Ticks of F's move to its new station after a turn (reading ``offset = "leg"``).

    Raises:
        ConfigError: if ``formation.corner_s`` is not a whole number of ticks shorter than a leg.
    """
    if f.corner_s is None:
        m = max(1, round(f.distance_m / path.speed_m_s / path.tick_s))
    else:
        m = check_multiple(f.corner_s, path.tick_s, "formation.corner_s")
    if m >= path.ticks_per_leg:
        raise ConfigError(
            f"formation.corner_s = {m * path.tick_s:g}: must be shorter than a leg "
            f"(path.leg_s = {path.leg_s:g} s)"
        )
    return m


@dataclass(frozen=True)
class SquareTruth:
    """Truth of the leader and the follower on the square (shared by all runs).

    Attributes:
        t_s: times, shape (T + 1,), s.
        leader_m: leader's reference positions, shape (T + 1, 2), m (east, north), world.
        follower_m: follower's reference positions, shape (T + 1, 2), m, world.
        follower_course_rad: F's reference course over step k -> k + 1, shape (T,), rad.
        follower_speed_m_s: F's reference speed over step k -> k + 1, shape (T,), m/s.
        leader_course_rad: L's reference course over each step, shape (T,), rad.
        leg: index of L's leg of each step, shape (T,).
    """

    t_s: Array
    leader_m: Array
    follower_m: Array
    follower_course_rad: Array
    follower_speed_m_s: Array
    leader_course_rad: Array
    leg: NDArray[np.intp]

    def follower_truth(self) -> Truth:
        """The follower as a :class:`~bauv_sim.truth.Truth` record (run axis 1, depth 0, no
        current); the velocity at sample k is the one of step k -> k + 1 (the last repeats)."""
        v = self.follower_speed_m_s[:, None] * unit_vector(self.follower_course_rad)
        v = np.concatenate([v, v[-1:]])
        n = len(self.t_s)
        vel = np.zeros((1, n, 3))
        vel[0, :, :2] = v
        pos = np.zeros((1, n, 3))
        pos[0, :, :2] = self.follower_m
        course = np.concatenate([self.follower_course_rad, self.follower_course_rad[-1:]])
        return Truth(
            t_s=self.t_s,
            pos_world_m=pos,
            vel_ground_world_m_s=vel,
            vel_water_world_m_s=vel,
            heading_rad=course[None],
            roll_pitch_rad=np.zeros((1, n, 2)),
            current_world_m_s=np.zeros((1, n, 3)),
        )


def square_truth(path: SquarePathConfig, formation: FormationConfig) -> SquareTruth:
    """Reference motion of L and F (seed 003 section 3; readings in the module docstring).

    Both reference tracks are dead-reckoned exactly (eq. 1 without errors) from their reference
    course and speed: ``x(k+1) = x(k) + dt S sin C``, ``y(k+1) = y(k) + dt S cos C``.

    Returns:
        The truth, shared by every run.
    """
    n_steps = path.n_ticks - 1
    dt = path.tick_s
    per_leg = path.ticks_per_leg
    leg = np.minimum(np.arange(n_steps) // per_leg, path.n_legs - 1)
    courses = path.leg_courses_rad()
    c_leader = courses[leg]
    v_leader = path.speed_m_s * unit_vector(c_leader)  # (T, 2)
    start = np.array([path.start_east_m, path.start_north_m])
    offsets = _offset(courses, formation)  # (legs, 2)
    v_follower = v_leader.copy()
    if formation.offset == "leg" and path.n_legs > 1 and formation.distance_m > 0:
        m = corner_ticks(path, formation)
        for j in range(1, path.n_legs):
            k0 = j * per_leg
            v_follower[k0 : k0 + m] += (offsets[j] - offsets[j - 1]) / (m * dt)
    leader = start + np.concatenate([[[0.0, 0.0]], np.cumsum(v_leader * dt, axis=0)])
    follower = (
        start + offsets[0] + np.concatenate([[[0.0, 0.0]], np.cumsum(v_follower * dt, axis=0)])
    )
    speed_f = np.hypot(v_follower[:, 0], v_follower[:, 1])
    course_f = wrap_2pi(np.arctan2(v_follower[:, 0], v_follower[:, 1]))
    return SquareTruth(
        t_s=np.arange(path.n_ticks) * dt,
        leader_m=leader,
        follower_m=follower,
        follower_course_rad=course_f,
        follower_speed_m_s=speed_f,
        leader_course_rad=c_leader,
        leg=leg,
    )


# ----------------------------------------------------------------------------------------------
# Measurements


def _course_error(sector_bias_deg: tuple[float, float, float, float]) -> AngleErrorConfig:
    return AngleErrorConfig(
        distribution="uniform", uniform_k=1.0, sigma_deg=2.0, sector_bias_deg=sector_bias_deg
    )


class ModemConfig(Config):
    """The acoustic range to the leader with its broadcast position (seed 003: HS modem)."""

    period_s: float = Field(5.0, gt=0, description="range period, s (f_Dh = 0.2 Hz)")
    range: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(
            distribution="uniform", uniform_k=1.0, sigma_m=0.1, bias_m=0.025
        ),
        description="range error: uniform on +-0.1 m plus the bias zeta_Dh^2 = 0.025 m (Tests "
        "1-2; Test 3: 0.0025 m)",
    )
    max_range_m: float | None = Field(
        None, gt=0, description="no range beyond this true distance, m (none: unlimited)"
    )
    dropout_windows_s: list[tuple[float, float]] = Field(
        default_factory=list,
        description="time windows [start, end] (s) in which no range arrives, e.g. [[60, 240]]",
    )
    broadcast: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=0.0),
        description="error of each axis of the leader's broadcast position, m (the paper: none, "
        "the true position is sent)",
    )

    @model_validator(mode="after")
    def _windows(self) -> ModemConfig:
        for a, b in self.dropout_windows_s:
            if not b > a:
                raise ValueError(
                    f"modem.dropout_windows_s: window [{a:g}, {b:g}] must end after it starts"
                )
        return self


class Seed003Sensors(Config):
    """The follower's devices with Test 1's errors (section 3)."""

    ins: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.1, heading=_course_error((4.0, 8.0, 0.0, 2.0))
        ),
        description="INS VN-100 course, 10 Hz: uniform +-2 deg plus the sector bias 4, 8, 0, 2 "
        "deg (Test 3: 0.4, 0.8, 0, 0.2)",
    )
    log: LogConfig = Field(
        default_factory=lambda: LogConfig(
            period_s=0.1,
            speed=SpeedErrorConfig(
                distribution="uniform", uniform_k=1.0, sigma_m_s=0.3, bias_m_s=0.05
            ),
        ),
        description="Alize log, 10 Hz: uniform +-0.3 m/s plus the bias 0.05 m/s (Test 3: 0.005)",
    )
    modem: ModemConfig = Field(default_factory=ModemConfig)


@dataclass(frozen=True)
class Seed003Measurements:
    """What the follower's navigation receives for some runs (no truth).

    Attributes:
        runs: run indices, length n.
        course_rad: measured course of each step k -> k + 1, shape (n, T), rad in [0, 2 pi).
        speed_m_s: measured speed of each step, shape (n, T), m/s.
        fix_tick: tick of each range, shape (K,).
        range_m: measured ranges, shape (n, K), m (>= 0; meaningless where not produced).
        range_produced: shape (n, K).
        leader_m: the leader's broadcast position with each range, shape (n, K, 2), m, world.
    """

    runs: tuple[int, ...]
    course_rad: Array
    speed_m_s: Array
    fix_tick: NDArray[np.intp]
    range_m: Array
    range_produced: NDArray[np.bool_]
    leader_m: Array


def _hold_last(values: Array, produced: NDArray[np.bool_], what: str) -> Array:
    """Fill absent samples with the last produced one (before the first: the first produced)."""
    if produced.all():
        return values
    if not produced.any(axis=1).all():
        raise ConfigError(f"{what}: a run produced no measurement at all (dropout probability?)")
    idx = np.where(produced, np.arange(values.shape[1]), -1)
    idx = np.maximum.accumulate(idx, axis=1)
    idx = np.where(idx < 0, produced.argmax(axis=1)[:, None], idx)
    return np.take_along_axis(values, idx, axis=1)


def measure(
    sensors: Seed003Sensors,
    truth: SquareTruth,
    seed: int,
    runs: tuple[int, ...],
    prefix: str = "follower",
) -> Seed003Measurements:
    """Sample the follower's course, speed and range to the leader for some runs.

    Streams: ``("sensor", f"{prefix}/ins", "heading", component)``, ``("sensor",
    f"{prefix}/log", "speed", ...)``, ``("sensor", f"{prefix}/modem", "range", ...)`` and
    ``(..., "broadcast_east" | "broadcast_north", ...)``: run ``i`` draws the same numbers in any
    block.

    Args:
        sensors: the devices.
        truth: the reference motion.
        seed: batch seed.
        runs: run indices.
        prefix: the vehicle's stream prefix.

    Returns:
        The measurements. A course or speed sample that is not produced (dropout probability)
        holds the last produced one.
    """
    n = len(runs)
    tick = truth.t_s[1] - truth.t_s[0]
    for name in ("ins", "log"):
        period = getattr(sensors, name).period_s
        if abs(period - tick) > 1e-9 * tick:
            raise ConfigError(
                f"sensors.{name}.period_s = {period:g}: the dead-reckoning inputs must be sampled "
                f"every tick (path.tick_s = {tick:g} s)"
            )
    ft = truth.follower_truth()
    steps = np.arange(len(truth.t_s) - 1)
    course = Compass(sensors.ins, seed, runs, f"{prefix}/ins").sample(ft, steps)
    speed = Log(sensors.log, seed, runs, f"{prefix}/log").sample(ft, steps)
    m = sensors.modem
    every = check_multiple(m.period_s, tick, "sensors.modem.period_s")
    fix_tick = periodic_indices(len(truth.t_s), every)
    t_fix = truth.t_s[fix_tick]
    true_range = np.hypot(*(truth.leader_m[fix_tick] - truth.follower_m[fix_tick]).T)
    err = ErrorProcess(m.range.to_model(), seed, runs, ("sensor", f"{prefix}/modem", "range"))
    rng, produced = err.apply(np.broadcast_to(true_range, (n, len(fix_tick))), t_fix)
    rng = np.maximum(rng, 0.0)
    if m.max_range_m is not None:
        produced = produced & (true_range <= m.max_range_m)
    for a, b in m.dropout_windows_s:
        produced = produced & ~((t_fix >= a) & (t_fix <= b))
    leader = np.broadcast_to(truth.leader_m[fix_tick], (n, len(fix_tick), 2)).copy()
    bm = m.broadcast.to_model()
    if bm.sigma > 0 or bm.bias != 0:
        for axis, name in enumerate(("broadcast_east", "broadcast_north")):
            proc = ErrorProcess(bm, seed, runs, ("sensor", f"{prefix}/modem", name))
            leader[..., axis], _ = proc.apply(leader[..., axis], t_fix)
    return Seed003Measurements(
        runs=tuple(runs),
        course_rad=_hold_last(course.values, course.produced, "sensors.ins"),
        speed_m_s=_hold_last(speed.values, speed.produced, "sensors.log"),
        fix_tick=fix_tick,
        range_m=rng,
        range_produced=produced,
        leader_m=leader,
    )
