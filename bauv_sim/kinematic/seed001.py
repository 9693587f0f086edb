"""Seed 001's kinematic experiment world: the motion model of eq. 27-29, vectorised over missions.

Truth of leg ``j`` (eq. 27-28, in vector form; x east, y north, courses clockwise from north):

    ``S_j = sum_i (|Va| u(alpha_j) + vs u(alpha_j + beta) + Vc_i + Vr_i) t``

* ``|Va| u(alpha_j)``: the commanded speed and course (odometry and compass: what DR knows);
* ``vs u(alpha_j + beta)``: the vehicle's systematic velocity error (the paper's ``V_s``, whose
  magnitude the tables call ``|V_g|``), constant over a mission;
* ``Vc_i``: the sea current (eq. 29). Stage 1: its mean magnitude depends on the hull angle,
  ``|Vc|_j = |Vc| rho_s(diffCourse(alpha_j + beta, alpha_c)) / rho_s(alpha_c)`` (the normalising
  ``rho_s(alpha_c)`` evaluates the curve at the angle 20 deg, as printed). Stage 2: magnitude and
  direction are drawn from ``N(|Vc|_j, sigma_V^2)`` and ``N(alpha_c, sigma_alpha^2)`` and held for
  ``N_d`` steps of 0.001 s, ``N_d`` uniform on [1, N_d,max]; a negative magnitude sets the current
  the other way (as :class:`bauv_sim.currents.RandomisedCurrent`). That class is not used directly
  because its mean magnitude is fixed while eq. 29's changes with every leg's course; the held
  perturbations here are the same process with the course-dependent mean added per leg.

  **sigma_V^2 = 0.02 is read as a relative variance** (standard deviation 14 % of the leg's mean
  magnitude) by default. Read literally as 0.02 m^2/s^2 (0.14 m/s, more than the 0.1 m/s current
  of half the grid), the held perturbations alone leave about 4 m of error after a 100 m leg
  whatever the current, so CP2 at ``|Vc| = 0.1`` comes out near 4.4 m instead of the paper's
  0.9-1.2 m and its "thirty-fold" improvement (Table 1, ``|Vg| = 0.3, |Vc| = 0.1``) becomes
  seven-fold; the text also says the randomness parameters "were fixed so that they could not
  dominate results". With the default hull response the relative reading puts 27 of the 40
  means of Tables 1 and 3 within 30 % of the paper, the literal one 16 (seed 1, 30 missions; the
  literal reading's 4 m floor does not depend on the hull response). Both are configurable
  (``current_speed_rel_var``, ``current_speed_var_m2_s2``).
* ``Vr_i``: a random velocity drawn at every step ``t``, direction uniform on [0, 2 pi) and
  magnitude uniform on [0, r_max).

The current is piecewise constant in continuous time, so its integral is computed exactly from the
segment boundaries whatever the step; only ``Vr`` is drawn per step. ``Vr`` is white noise: its
contribution to a leg's displacement has variance ``T t r_max^2 / 6`` per axis (0.04 m
standard deviation for T = 100 s at the paper's t = 0.001 s, 0.12 m at 0.01 s), negligible beside
the current's (metres). A coarser ``step_s`` therefore changes the statistics only by that amount;
``tests/bauv_sim/test_kinematic_seed001.py`` checks it on paired missions.

Each leg starts at a GPS fix (the previous leg's true end) and lasts ``T = L / |Va|`` (the time the
uncorrected DR of eq. 30-31 needs for the leg length ``L``); the way-point is at ``L`` on the direct
course ``nu_j`` from the fix. Dead reckoning and the correction procedures are navigation
(:mod:`nav.surfacing`); this module produces truth and the mission geometry only.

References:
    Praczyk T., Correction of navigational information supplied to biomimetic AUV (seed 001),
    eq. 27-31 and section "Conditions of experiments".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.polynomial import chebyshev
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, field_validator, model_validator

from bauv_sim.config import Config
from bauv_sim.frames import diff_course, velocity_from_course_speed, wrap_2pi

Array = NDArray[np.float64]

_SEGMENT_CHUNK = 256
"""Held current segments are drawn in chunks of this many (fixed, so draws never depend on how
many chunks a mission needs)."""
_VR_CHUNK_STEPS = 1 << 18
"""Steps of Vr drawn at a time (bounds memory at about 8 MB per row)."""


class Seed001WorldConfig(Config):
    """The world of seed 001's experiment (defaults: the paper's parameters).

    The grid parameters (``|Vg|``, ``|Vc|``, ``beta``) are per mission and given to the functions
    as arrays; everything here is shared by all missions.
    """

    vehicle_speed_m_s: float = Field(1.0, gt=0, le=10, description="|Va|, m/s")
    leg_length_m: float = Field(100.0, gt=0, description="distance between way-points, m")
    current_direction_deg: float = Field(
        20.0, ge=0, lt=360, description="alpha_c: dominant set (towards), clockwise from north, deg"
    )
    current_speed_rel_var: float = Field(
        0.02,
        ge=0,
        description="sigma_V^2 read as a relative variance (default): magnitude ~ "
        "N(m, sigma_V^2 m^2) with m the leg's mean magnitude; dimensionless (see the module)",
    )
    current_speed_var_m2_s2: float = Field(
        0.0,
        ge=0,
        description="sigma_V^2 read literally as an absolute variance: magnitude ~ "
        "N(m, sigma_V^2), m^2/s^2 (added to the relative part; the literal reading is "
        "rel_var = 0, this = 0.02)",
    )
    current_direction_var_deg2: float = Field(
        10.0, ge=0, description="sigma_alpha^2: variance of the current's direction, deg^2"
    )
    current_hold_max_steps: int = Field(
        10000, ge=1, description="N_d,max: longest hold of one perturbation, steps"
    )
    current_hold_step_s: float = Field(
        0.001, gt=0, description="duration of one hold step (the paper's t), s"
    )
    rho_s_cos_coeffs: tuple[float, ...] = Field(
        (1.0, 0.2, 0.15),
        min_length=1,
        description="rho_s(gamma) = sum_k a_k cos(k gamma), the hull response of eq. 29 "
        "(see nav.surfacing.CurrentResponse for the default)",
    )
    random_speed_max_m_s: float = Field(0.3, ge=0, description="r_max: largest |Vr|, m/s")
    step_s: float = Field(0.001, gt=0, description="t: the step at which Vr is drawn, s")
    sample_s: float = Field(1.0, gt=0, description="spacing of the recorded track, s")

    @field_validator("rho_s_cos_coeffs")
    @classmethod
    def _rho_positive(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        low = float(np.min(rho_s(np.linspace(0.0, np.pi, 3601), v)))
        if low <= 0:
            raise ValueError(f"rho_s must be positive on [0, 180] deg; its minimum is {low:.3g}")
        return v

    @model_validator(mode="after")
    def _grid(self) -> Seed001WorldConfig:
        _ratio(self.sample_s, self.step_s, "sample_s", "step_s")
        _ratio(
            self.leg_duration_s, self.sample_s, "leg duration (leg_length_m / speed)", "sample_s"
        )
        return self

    @property
    def leg_duration_s(self) -> float:
        """``T = L / |Va|``, s."""
        return self.leg_length_m / self.vehicle_speed_m_s

    @property
    def samples_per_leg(self) -> int:
        """Number of track intervals per leg."""
        return round(self.leg_duration_s / self.sample_s)


def _ratio(value: float, unit: float, what: str, unit_name: str) -> int:
    k = round(value / unit)
    if k < 1 or abs(k * unit - value) > 1e-9 * max(1.0, value):
        raise ValueError(f"{what} = {value} must be a whole multiple of {unit_name} = {unit}")
    return k


def rho_s(gamma_rad: ArrayLike, cos_coeffs: Sequence[float]) -> Array:
    """The hull response ``rho_s(gamma) = sum_k a_k cos(k gamma)`` (eq. 29), any shape.

    The same series as :meth:`nav.surfacing.CurrentResponse.rho_s`, repeated here because this
    is the world's truth and that the navigation's model of it (the world shares only
    :mod:`nav.angles` with the navigation package); a test checks they agree.
    """
    return chebyshev.chebval(np.cos(np.asarray(gamma_rad, dtype=float)), np.asarray(cos_coeffs))


@dataclass(frozen=True)
class Seed001Vehicle:
    """The vehicles of a batch of missions (one row per mission).

    Attributes:
        vs_m_s: signed magnitude of the systematic velocity error ``V_s`` (the tables' ``V_g``),
            shape (n,), m/s; positive adds to the progressive speed.
        beta_rad: deviation of ``V_s`` from the course, shape (n,), rad.
    """

    vs_m_s: Array
    beta_rad: Array


@dataclass(frozen=True)
class HeldPerturbations:
    """One realisation per mission of eq. 29's held current perturbations, as exact integrals.

    Segment ``k`` of row ``r`` spans ``[ends_s[r][k-1], ends_s[r][k])`` (from 0), during which the
    current's direction is ``direction_rad[r][k]`` and its magnitude is the leg's mean plus
    ``z[r][k]`` standard deviations. Stored are the cumulative integrals at the segment ends of
    ``u(direction)`` and of ``z u(direction)`` (m/s times s = m per unit speed).

    Attributes:
        ends_s: per row, segment end times, shape (K_r,), s.
        z: per row, standard normal magnitude draws, shape (K_r,).
        direction_rad: per row, set directions, shape (K_r,), rad.
        int_unit_m: per row, ``int_0^t u(dir)`` at ``[0, ends]``, shape (K_r + 1, 2), s.
        int_z_unit_m: per row, ``int_0^t z u(dir)`` at ``[0, ends]``, shape (K_r + 1, 2), s.
    """

    ends_s: list[Array]
    z: list[Array]
    direction_rad: list[Array]
    int_unit_m: list[Array]
    int_z_unit_m: list[Array]

    def integrals(self, t_s: ArrayLike) -> tuple[Array, Array]:
        """``(int_0^t u(dir), int_0^t z u(dir))`` at times ``t_s`` (m,), each shape (n, m, 2), s."""
        t = np.asarray(t_s, dtype=float)
        n = len(self.ends_s)
        a = np.empty((n, t.size, 2))
        b = np.empty((n, t.size, 2))
        for r in range(n):
            knots = np.concatenate([[0.0], self.ends_s[r]])
            if t.size and t.max() > knots[-1] + 1e-9:
                raise ValueError(f"perturbations drawn up to {knots[-1]} s, asked for {t.max()} s")
            for ax in range(2):
                a[r, :, ax] = np.interp(t, knots, self.int_unit_m[r][:, ax])
                b[r, :, ax] = np.interp(t, knots, self.int_z_unit_m[r][:, ax])
        return a, b


def draw_perturbations(
    cfg: Seed001WorldConfig, horizon_s: float, rngs: Sequence[np.random.Generator]
) -> HeldPerturbations:
    """Draw eq. 29's held perturbations of each mission up to ``horizon_s``.

    Args:
        cfg: the world.
        horizon_s: time to cover, s.
        rngs: one generator per mission (the mission's current stream).

    Returns:
        The realisations, one row per generator.
    """
    sigma_dir = math.radians(math.sqrt(cfg.current_direction_var_deg2))
    mean_dir = math.radians(cfg.current_direction_deg)
    out: tuple[list[Array], ...] = ([], [], [], [], [])
    for rng in rngs:
        ends_l, z_l, d_l = [], [], []
        end = 0.0
        while end <= horizon_s:
            steps = rng.integers(1, cfg.current_hold_max_steps, size=_SEGMENT_CHUNK, endpoint=True)
            z_l.append(rng.standard_normal(_SEGMENT_CHUNK))
            d_l.append(rng.normal(mean_dir, sigma_dir, _SEGMENT_CHUNK))
            ends_l.append(end + np.cumsum(steps) * cfg.current_hold_step_s)
            end = float(ends_l[-1][-1])
        ends = np.concatenate(ends_l)
        z = np.concatenate(z_l)
        d = np.concatenate(d_l)
        lengths = np.diff(np.concatenate([[0.0], ends]))
        u = velocity_from_course_speed(d, 1.0)
        int_u = np.concatenate([np.zeros((1, 2)), np.cumsum(u * lengths[:, None], axis=0)])
        int_zu = np.concatenate([np.zeros((1, 2)), np.cumsum(u * (z * lengths)[:, None], axis=0)])
        for lst, val in zip(out, (ends, z, d, int_u, int_zu), strict=True):
            lst.append(val)
    return HeldPerturbations(*out)


def mean_current_speed(
    cfg: Seed001WorldConfig, current_speed_m_s: ArrayLike, hull_course_rad: ArrayLike
) -> Array:
    """Eq. 29, stage 1: the current's mean magnitude for a hull on ``hull_course_rad``.

    ``|Vc| rho_s(diffCourse(alpha_j + beta, alpha_c)) / rho_s(alpha_c)``.

    Args:
        cfg: the world.
        current_speed_m_s: ``|Vc|``, shape (n,), m/s.
        hull_course_rad: ``alpha_j + beta``, shape (n,), rad.

    Returns:
        Shape (n,), m/s.
    """
    ac = math.radians(cfg.current_direction_deg)
    gamma = diff_course(hull_course_rad, ac)
    ratio = rho_s(gamma, cfg.rho_s_cos_coeffs) / rho_s(ac, cfg.rho_s_cos_coeffs)
    return np.asarray(current_speed_m_s, dtype=float) * ratio


@dataclass(frozen=True)
class LegTruth:
    """The true motion over one leg of a batch of missions.

    Attributes:
        t_s: sample times since the leg's start, shape (k + 1,), s.
        pos_world_m: true positions (east, north), shape (n, k + 1, 2), m, world; sample 0 is the
            start fix, sample k the end.
        vel_water_world_m_s: the vehicle's own velocity ``|Va| u(alpha) + vs u(alpha + beta)``,
            shape (n, 2), m/s, world.
        mean_current_world_m_s: the current averaged over the leg, shape (n, 2), m/s, world.
        mean_current_speed_m_s: eq. 29's stage-1 mean magnitude on this leg, shape (n,), m/s.
    """

    t_s: Array
    pos_world_m: Array
    vel_water_world_m_s: Array
    mean_current_world_m_s: Array
    mean_current_speed_m_s: Array

    @property
    def displacement_world_m(self) -> Array:
        """End minus start, shape (n, 2), m, world."""
        return self.pos_world_m[:, -1] - self.pos_world_m[:, 0]


def leg_truth(
    cfg: Seed001WorldConfig,
    vehicle: Seed001Vehicle,
    current_speed_m_s: ArrayLike,
    perturbations: HeldPerturbations,
    start_world_m: ArrayLike,
    t0_s: float,
    course_rad: ArrayLike,
    vr_rngs: Sequence[np.random.Generator],
) -> LegTruth:
    """Truth of one leg of duration ``T = L / |Va|`` on a constant commanded course (eq. 27-29).

    Args:
        cfg: the world.
        vehicle: the missions' vehicles (n rows).
        current_speed_m_s: ``|Vc|`` of each mission, shape (n,), m/s.
        perturbations: the missions' held current perturbations (cover ``t0_s + T``).
        start_world_m: start positions (the last fix), shape (n, 2), m, world.
        t0_s: mission time at the leg's start, s.
        course_rad: commanded course ``alpha_j``, shape (n,), rad.
        vr_rngs: one generator per mission for this leg's ``Vr`` draws.

    Returns:
        The leg's truth.
    """
    course = np.asarray(course_rad, dtype=float)
    start = np.asarray(start_world_m, dtype=float)
    T = cfg.leg_duration_s
    k = cfg.samples_per_leg
    t = np.linspace(0.0, T, k + 1)
    v_water = velocity_from_course_speed(
        course, cfg.vehicle_speed_m_s
    ) + velocity_from_course_speed(course + vehicle.beta_rad, vehicle.vs_m_s)
    m = mean_current_speed(cfg, current_speed_m_s, course + vehicle.beta_rad)
    sig = np.sqrt(cfg.current_speed_var_m2_s2 + cfg.current_speed_rel_var * m * m)
    iu, izu = perturbations.integrals(t0_s + t)
    cur = m[:, None, None] * (iu - iu[:, :1]) + sig[:, None, None] * (izu - izu[:, :1])
    vr = random_velocity_sums(cfg, T, vr_rngs)
    pos = start[:, None, :] + v_water[:, None, :] * t[None, :, None] + cur
    pos[:, 1:] += np.cumsum(vr, axis=1)
    return LegTruth(t, pos, v_water, cur[:, -1] / T, m)


def random_velocity_sums(
    cfg: Seed001WorldConfig, duration_s: float, rngs: Sequence[np.random.Generator]
) -> Array:
    """Displacements due to ``Vr`` over each track interval (eq. 27-28's ``Vr t`` summed).

    ``Vr`` is drawn at every step ``t = cfg.step_s``: direction uniform on [0, 2 pi), magnitude
    uniform on [0, r_max). Drawn in bounded chunks (magnitudes, then directions, per chunk).

    Args:
        cfg: the world.
        duration_s: the leg's duration, s (a whole number of samples).
        rngs: one generator per mission.

    Returns:
        Shape (n, k, 2), m, world: the displacement of each of the ``k`` sample intervals.
    """
    per_sample = round(cfg.sample_s / cfg.step_s)
    k = round(duration_s / cfg.sample_s)
    total = k * per_sample
    out = np.zeros((len(rngs), k, 2))
    if cfg.random_speed_max_m_s == 0.0:
        return out
    chunk = max(per_sample, (_VR_CHUNK_STEPS // per_sample) * per_sample)
    for r, rng in enumerate(rngs):
        done = 0
        while done < total:
            size = min(chunk, total - done)
            mag = rng.random(size) * cfg.random_speed_max_m_s
            ang = rng.random(size) * (2.0 * np.pi)
            step_disp = velocity_from_course_speed(ang, mag * cfg.step_s)
            s0 = done // per_sample
            out[r, s0 : s0 + size // per_sample] = step_disp.reshape(-1, per_sample, 2).sum(axis=1)
            done += size
    return out


def draw_courses(
    procedure: Literal["cp1", "cp2"],
    rngs: Sequence[np.random.Generator],
    *,
    cp1_min_separation_rad: float = math.radians(5.0),
    cp2_courses_rad: tuple[float, float] = (math.radians(45.0), math.radians(225.0)),
) -> Array:
    """Direct courses of the three legs of each mission (section "Conditions of experiments").

    CP1: all three uniform on [0, 2 pi), the first two redrawn until they are at least
    ``cp1_min_separation_rad`` from the same and from the opposite course (CP1's constraint). CP2:
    45 then 225 deg, the third uniform.

    Args:
        procedure: ``"cp1"`` or ``"cp2"``.
        rngs: one generator per mission (its course stream).
        cp1_min_separation_rad: CP1's minimum separation from same / opposite, rad (< pi/2).
        cp2_courses_rad: CP2's first two courses, rad.

    Returns:
        Courses ``nu_1..3``, shape (n, 3), rad in [0, 2 pi).
    """
    if not 0.0 <= cp1_min_separation_rad < np.pi / 2:
        raise ValueError(f"cp1_min_separation_rad = {cp1_min_separation_rad}: must be in [0, pi/2)")
    out = np.empty((len(rngs), 3))
    for r, rng in enumerate(rngs):
        if procedure == "cp1":
            while True:
                a = rng.random(2) * (2.0 * np.pi)
                if abs(math.sin(a[1] - a[0])) >= math.sin(cp1_min_separation_rad):
                    break
            out[r, :2] = a
        elif procedure == "cp2":
            out[r, :2] = cp2_courses_rad
        else:
            raise ValueError(f"procedure = {procedure!r}: must be 'cp1' or 'cp2'")
        out[r, 2] = rng.random() * (2.0 * np.pi)
    return wrap_2pi(out)
