"""A team of vehicles in formation: the kinematic truth of issue 24's cooperative navigation.

The leader flies a racetrack (a stadium: two straight legs of ``leg_m`` joined by half circles of
``turn_radius_m``) at constant speed over ground and depth. Each follower keeps a station in the
leader's frame (``along_m`` ahead, ``starboard_m`` to the right) plus a slow sinusoidal wander
(a Lissajous figure of amplitude ``wander_m``: ``sin(w t + phi)`` along, ``sin(w t / 2 + phi)``
across, ``w = 2 pi / wander_period_s``), so that the geometry of the ranges changes over the run.
Every vehicle keeps its own constant depth (distinct depths: the ranges are slant ranges). One
uniform current carries the water; every vehicle points along its velocity through the water
(no sideslip), so a log-and-compass dead reckoning that does not know the current drifts with it.

Positions are closed forms of time, sampled every ``tick_s``; the velocity over ground of sample
``k`` is the step's ``(p[k+1] - p[k]) / tick_s`` (the last repeats), so dead reckoning of the
true headings and speeds through the water plus the current reproduces the track exactly (seed
003's convention, :mod:`bauv_sim.kinematic.seed003`).

Leader on the racetrack (heading ``h0`` on the first leg, turning to ``sign`` = +1 right, -1 left,
arc length ``s = V t`` modulo the perimeter ``2 L + 2 pi R``): ``p = s u(h0)`` on the first leg,
then a half circle about ``c1 = L u(h0) + R u(h0 + sign 90 deg)`` with heading ``h0 + sign a``,
``a = (s - L) / R``, and so on around (``u(c) = (sin c, cos c)``, courses clockwise from north).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.frames import unit_vector, wrap_2pi
from bauv_sim.sensors.base import check_multiple
from bauv_sim.truth import Truth

Array = NDArray[np.float64]

LEADER = "leader"
"""The leader's vehicle name (index 0 of every team array)."""


class LeaderTrackConfig(Config):
    """The leader's racetrack (module docstring)."""

    speed_m_s: float = Field(1.5, gt=0, le=10, description="speed over ground, m/s")
    leg_m: float = Field(200.0, ge=0, description="length of a straight leg, m")
    turn_radius_m: float = Field(100.0, gt=0, description="radius of the half circles, m")
    initial_course_deg: float = Field(
        0.0, ge=0, lt=360, description="course of the first leg, deg clockwise from north"
    )
    turn: Literal["right", "left"] = Field("right", description="direction of the half circles")
    start_east_m: float = Field(0.0, description="start of the first leg, east, m, world")
    start_north_m: float = Field(0.0, description="start of the first leg, north, m, world")
    depth_m: float = Field(5.0, ge=0, le=6000, description="the leader's depth, m")

    @property
    def perimeter_m(self) -> float:
        """One lap, m."""
        return 2.0 * self.leg_m + 2.0 * math.pi * self.turn_radius_m


class StationConfig(Config):
    """A follower's station in the leader's frame, its wander and its depth."""

    name: str = Field(min_length=1, max_length=40, description="vehicle name (unique)")
    along_m: float = Field(description="ahead of the leader along its course, m (astern < 0)")
    starboard_m: float = Field(description="to the leader's right, m (port < 0)")
    depth_m: float = Field(ge=0, le=6000, description="the follower's depth, m")
    wander_m: float = Field(10.0, ge=0, description="amplitude of the wander on each axis, m")
    wander_period_s: float = Field(
        200.0, gt=0, description="period of the along-track wander, s (across: twice this)"
    )
    phase_deg: float = Field(0.0, description="phase of the wander, deg")


def _default_followers() -> list[StationConfig]:
    return [
        StationConfig(name="f1", along_m=-40.0, starboard_m=-40.0, depth_m=10.0, phase_deg=0.0),
        StationConfig(name="f2", along_m=-40.0, starboard_m=40.0, depth_m=15.0, phase_deg=120.0),
        StationConfig(name="f3", along_m=-80.0, starboard_m=0.0, depth_m=20.0, phase_deg=240.0),
    ]


class TeamConfig(Config):
    """The team: the leader's racetrack, the followers' stations, the current and the grid."""

    leader: LeaderTrackConfig = Field(default_factory=LeaderTrackConfig)
    followers: list[StationConfig] = Field(
        default_factory=_default_followers,
        min_length=1,
        max_length=32,
        description="the followers' stations (default three: port, starboard and astern)",
    )
    current_east_m_s: float = Field(0.02, ge=-3, le=3, description="current, east, m/s")
    current_north_m_s: float = Field(0.01, ge=-3, le=3, description="current, north, m/s")
    duration_s: float = Field(600.0, gt=0, le=36_000, description="duration of a run, s")
    tick_s: float = Field(0.2, gt=0, le=10, description="time step of the truth, s")

    @model_validator(mode="after")
    def _team(self) -> TeamConfig:
        check_multiple(self.duration_s, self.tick_s, "duration_s")
        names = [LEADER] + [f.name for f in self.followers]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(
                f"followers: the name {dup[0]!r} appears twice (the leader is {LEADER!r})"
            )
        depths = [self.leader.depth_m] + [f.depth_m for f in self.followers]
        for i, f in enumerate(self.followers):
            if f.depth_m in depths[: i + 1]:
                raise ValueError(
                    f"followers[{i}].depth_m = {f.depth_m:g}: another vehicle is at that "
                    "depth; every vehicle keeps its own depth"
                )
        return self

    @property
    def names(self) -> tuple[str, ...]:
        """Vehicle names, the leader first."""
        return (LEADER, *(f.name for f in self.followers))

    @property
    def n_ticks(self) -> int:
        """Samples including t = 0."""
        return round(self.duration_s / self.tick_s) + 1


def racetrack(track: LeaderTrackConfig, t_s: Array) -> tuple[Array, Array]:
    """The leader's position and course on the racetrack at given times (module docstring).

    Args:
        track: the racetrack.
        t_s: times, shape (k,), s.

    Returns:
        ``(position (k, 2) m east/north world, course (k,) rad in [0, 2 pi))``.
    """
    L, R, V = track.leg_m, track.turn_radius_m, track.speed_m_s
    sign = 1.0 if track.turn == "right" else -1.0
    h0 = math.radians(track.initial_course_deg)
    s = np.mod(V * np.asarray(t_s, float), track.perimeter_m)
    half = math.pi * R
    side = unit_vector(h0 + sign * math.pi / 2)  # towards the centres of the turns
    fwd = unit_vector(h0)
    c1 = L * fwd + R * side  # centre of the first turn
    p2 = c1 + R * side  # start of the return leg
    c2 = p2 - L * fwd - R * side  # centre of the second turn
    seg = np.searchsorted(np.array([L, L + half, 2 * L + half]), s, side="right")
    a1 = (s - L) / R
    a3 = (s - 2 * L - half) / R
    pos = np.select(
        [seg[:, None] == j for j in range(4)],
        [
            s[:, None] * fwd,
            c1 - R * unit_vector(h0 + sign * (a1 + math.pi / 2)),
            p2 - (s - L - half)[:, None] * fwd,
            c2 - R * unit_vector(h0 + sign * (a3 + 3 * math.pi / 2)),
        ],
    )
    course = np.select(
        [seg == 0, seg == 1, seg == 2, seg == 3],
        [
            np.full_like(s, h0),
            h0 + sign * a1,
            np.full_like(s, h0 + math.pi),
            h0 + sign * (a3 + math.pi),
        ],
    )
    start = np.array([track.start_east_m, track.start_north_m])
    return start + pos, wrap_2pi(course)


def station(leader_m: Array, course_rad: Array, f: StationConfig, t_s: Array) -> Array:
    """A follower's position: its station in the leader's frame plus the wander.

    ``p_f = p_L + (along + A sin(w t + phi)) u(C) + (starboard + A sin(w t / 2 + phi)) u(C + 90
    deg)``, ``w = 2 pi / wander_period_s``.

    Args:
        leader_m: the leader's positions, shape (k, 2), m.
        course_rad: the leader's course, shape (k,), rad.
        f: the station.
        t_s: times, shape (k,), s.

    Returns:
        Shape (k, 2), m east/north world.
    """
    w = 2.0 * math.pi / f.wander_period_s
    phi = math.radians(f.phase_deg)
    along = f.along_m + f.wander_m * np.sin(w * t_s + phi)
    across = f.starboard_m + f.wander_m * np.sin(0.5 * w * t_s + phi)
    return (
        leader_m
        + along[:, None] * unit_vector(course_rad)
        + across[:, None] * unit_vector(course_rad + math.pi / 2)
    )


def _truth(t_s: Array, pos_en: Array, depth_m: float, current_en: Array) -> Truth:
    """One vehicle's :class:`Truth` (run axis 1) from its horizontal positions: step velocities
    over ground, through the water (minus the current), heading along the latter."""
    dt = t_s[1] - t_s[0]
    v = np.diff(pos_en, axis=0) / dt
    v = np.concatenate([v, v[-1:]])
    k = len(t_s)
    vg = np.zeros((1, k, 3))
    vg[0, :, :2] = v
    cur = np.zeros((1, k, 3))
    cur[0, :, :2] = current_en
    vw = vg - cur
    pos = np.empty((1, k, 3))
    pos[0, :, :2] = pos_en
    pos[0, :, 2] = -depth_m
    heading = wrap_2pi(np.arctan2(vw[..., 0], vw[..., 1]))
    return Truth(
        t_s=t_s,
        pos_world_m=pos,
        vel_ground_world_m_s=vg,
        vel_water_world_m_s=vw,
        heading_rad=heading,
        roll_pitch_rad=np.zeros((1, k, 2)),
        current_world_m_s=cur,
    )


@dataclass(frozen=True)
class TeamTruth:
    """The truth of every vehicle of the team (shared by all runs).

    Attributes:
        names: vehicle names, the leader first, length v.
        vehicles: one :class:`Truth` per vehicle (run axis 1), same time grid.
    """

    names: tuple[str, ...]
    vehicles: tuple[Truth, ...]

    @property
    def t_s(self) -> Array:
        """Sample times, shape (k,), s."""
        return self.vehicles[0].t_s

    @property
    def positions_world_m(self) -> Array:
        """Every vehicle's position, shape (v, 1, k, 3), m, world (z up)."""
        return np.stack([tr.pos_world_m for tr in self.vehicles])

    def min_separation_m(self) -> float:
        """The closest two vehicles come (3-D), m."""
        p = self.positions_world_m[:, 0]
        v = len(p)
        out = math.inf
        for i in range(v):
            for j in range(i + 1, v):
                out = min(out, float(np.linalg.norm(p[i] - p[j], axis=-1).min()))
        return out


def team_truth(cfg: TeamConfig) -> TeamTruth:
    """The team's truth on the grid ``0, tick, ..., duration`` (module docstring).

    Args:
        cfg: the team.

    Returns:
        The truth of the leader and every follower.
    """
    t = cfg.tick_s * np.arange(cfg.n_ticks)
    leader, course = racetrack(cfg.leader, t)
    current = np.array([cfg.current_east_m_s, cfg.current_north_m_s])
    out = [_truth(t, leader, cfg.leader.depth_m, current)]
    for f in cfg.followers:
        out.append(_truth(t, station(leader, course, f, t), f.depth_m, current))
    return TeamTruth(cfg.names, tuple(out))
