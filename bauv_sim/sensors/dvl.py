"""Doppler velocity log: four Janus beams, bottom track over the seabed or water track.

**Beams.** Beam ``i`` (i = 0..3) in the instrument frame is

    d_i = (sin(a) cos(phi_i), sin(a) sin(phi_i), -cos(a)),    phi_i = 0, 90, 180, 270 deg,

``a`` the beam angle off the instrument's -z axis (a Janus layout: two opposed pairs). The
instrument frame is mounted on the body (FLU) by ``R_mount = Rz(yaw) Ry(pitch) Rx(roll)`` of
``mount_rpy_deg`` (right-handed rotations about the body's axes, yaw applied last; the default yaw
45 deg puts the beams at 45, 135, 225 and 315 deg off the bow, an "X" layout). The TRUE mount is
``R_mount @ R_mis`` with ``R_mis`` the same rotation of ``misalignment_deg`` about the
instrument's own axes (for the default yaw-only mount that is exactly the nominal angles plus the
misalignment); the DVL knows only the nominal mount, so a misalignment shows in its output.

**Ranges.** Each beam is a ray from the transducer (``transducer_body_m``; in the physics world the
model's ``dvl`` site when zero) along the true beam direction, cast against the seabed: in the
kinematic world any :class:`RaySeabed` (the generated :class:`bauv_sim.seabed.Seabed`, whose
triangles are MuJoCo's, or the analytic :class:`PlaneSeabed`); in the physics world MuJoCo's rays
against the scene's heightfield (:meth:`bauv_sim.physics.BauvPhysics.seabed_ray_distances`). A beam
**returns** when its ray meets the seabed within the beam's maximum range
``max_altitude_m / cos(a)`` (the slant range of the maximum altitude over a flat seabed with the
instrument level) and neither its velocity nor its range dropped out (a velocity dropout loses
the beam altogether, a range dropout its bottom echo).

**Velocity.** The true beam velocity is ``d_i_true_body . v`` with ``v`` the transducer's velocity
in body axes, over ground ``v = R^T v_ref_world + omega x r`` (bottom track) or through the water
``v = R^T v_water_world + omega x r`` (water track; the water at the vehicle). Each beam's velocity
gets the shared error vocabulary (:class:`SpeedErrorConfig`: noise, bias, scale factor, random
walk, outliers, dropouts; one stream per beam and term), each beam's range the
:class:`LengthErrorConfig` ones (measured ranges are clipped at 0). The velocity is the least
squares solution over the beams used, in the NOMINAL instrument frame,
``v_instr = argmin sum_i (d_i . v_instr - b_i)^2``, rotated to the body by the nominal mount:
with no error and no misalignment it is the true ``v`` to rounding (three beams of a Janus
layout already determine it).

**Modes** (per ping): **bottom lock** (1) when at least ``min_beams`` beams return and the
altitude, the mean over the returning beams of ``range_i cos(a)`` (along the instrument's axis, as
a DVL reports it), lies in ``[min_altitude_m, max_altitude_m]``; else, with ``fallback =
"water"``, **water track** (2) from the beams whose velocity did not drop out (at least
``min_beams``; water track needs no bottom echo); else **none** (0). Without bottom lock the
altitude is 0; the ranges and echo flags of the returning beams are reported in every mode (0 and
False where a beam has no echo). Nothing is NaN: an absent output is flagged (mode 0), its values
are zeros.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, field_validator, model_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.frames import R_from_quat_wxyz, R_from_roll_pitch_heading
from bauv_sim.sensors.base import broadcast_runs
from bauv_sim.sensors.errors import ErrorProcess, LengthErrorConfig, SpeedErrorConfig
from bauv_sim.sensors.online import (
    DeviceBuild,
    Measurement,
    TickContext,
    register_device,
)
from bauv_sim.truth import Truth

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

BEAMS = 4
"""Beams of the Janus layout."""

NONE, BOTTOM_LOCK, WATER_TRACK = 0, 1, 2
"""The DVL's modes (:attr:`DvlSamples.mode`, :attr:`DvlPing.mode`)."""


class DvlConfig(Config):
    """Doppler velocity log (see the module docstring)."""

    period_s: float = Field(0.2, gt=0, description="time between pings, s (5 Hz)")
    beam_angle_deg: float = Field(
        30.0, gt=0, lt=90, description="each beam's angle off the instrument's -z axis, deg"
    )
    mount_rpy_deg: tuple[float, float, float] = Field(
        (0.0, 0.0, 45.0),
        description="nominal mounting of the instrument frame in body FLU: right-handed "
        "rotations about the body's x, y, z (applied x, then y, then z), deg",
    )
    misalignment_deg: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="true mount = nominal mount then these rotations about the instrument's own "
        "x, y, z, deg (the DVL reports in the nominal frame)",
    )
    transducer_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="transducer relative to the reference point, m, body FLU (zero: the "
        "model's 'dvl' site in the physics world, the reference point in a kinematic world)",
    )
    min_altitude_m: float = Field(0.3, ge=0, description="no bottom lock below this altitude, m")
    max_altitude_m: float = Field(
        60.0, gt=0, description="no bottom lock above this altitude, m (beam range / cos(a))"
    )
    min_beams: int = Field(3, ge=3, le=4, description="beams needed for a velocity")
    fallback: Literal["water", "none"] = Field(
        "water", description="without bottom lock: water track, or no output"
    )
    beam: SpeedErrorConfig = Field(
        default_factory=lambda: SpeedErrorConfig(sigma_m_s=0.01),
        description="error of each beam's velocity (a dropout loses the beam)",
    )
    range: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=0.02),
        description="error of each beam's range (a dropout loses the beam's bottom echo)",
    )

    @field_validator("beam", "range")
    @classmethod
    def _no_sector_bias(
        cls, v: SpeedErrorConfig | LengthErrorConfig
    ) -> SpeedErrorConfig | LengthErrorConfig:
        name = f"sector_bias_{type(v).unit_name}"
        if getattr(v, name) is not None:
            raise ValueError(f"{name} needs a reference course; a DVL beam has none")
        return v

    @model_validator(mode="after")
    def _altitudes(self) -> DvlConfig:
        if self.min_altitude_m >= self.max_altitude_m:
            raise ValueError(
                f"min_altitude_m = {self.min_altitude_m:g} must be below max_altitude_m = "
                f"{self.max_altitude_m:g}"
            )
        return self

    @property
    def max_range_m(self) -> float:
        """A beam's maximum slant range, ``max_altitude_m / cos(a)``, m."""
        return self.max_altitude_m / float(np.cos(np.radians(self.beam_angle_deg)))


def rotation_rpy(rpy_deg: ArrayLike) -> Array:
    """``Rz(yaw) Ry(pitch) Rx(roll)``: right-handed rotations about x, then y, then z.

    Args:
        rpy_deg: (roll, pitch, yaw), shape (3,), deg.

    Returns:
        Shape (3, 3): maps vectors of the rotated frame into the reference frame.
    """
    r, p, y = np.radians(np.asarray(rpy_deg, dtype=float))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def beam_directions_instrument(beam_angle_deg: float) -> Array:
    """Unit beam vectors ``d_i`` of the Janus layout, shape (4, 3), instrument frame."""
    a = np.radians(beam_angle_deg)
    phi = np.radians([0.0, 90.0, 180.0, 270.0])
    return np.stack(
        [np.sin(a) * np.cos(phi), np.sin(a) * np.sin(phi), np.full(4, -np.cos(a))], axis=-1
    )


class RaySeabed(Protocol):
    """A seabed that rays can be cast against (:class:`bauv_sim.seabed.Seabed`,
    :class:`PlaneSeabed`)."""

    def ray_ranges(
        self, origin_m: ArrayLike, directions: ArrayLike, max_range_m: float
    ) -> tuple[Array, BoolArray]:
        """Distance along rays (origins (..., 3) m world, directions (..., 3), broadcast) to the
        first crossing of the seabed within ``max_range_m``: ``(range_m, hit)``, shape (...),
        range 0 where no hit."""
        ...


@dataclass(frozen=True)
class PlaneSeabed:
    """An analytic plane seabed: depth (positive down) ``depth_m + slope[0] x + slope[1] y`` at
    horizontal position (x east, y north), m.

    Attributes:
        depth_m: depth at (0, 0), m.
        slope: (d depth / d east, d depth / d north), dimensionless.
    """

    depth_m: float
    slope: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        """Raises: ConfigError for a non-finite depth or slope."""
        vals = np.array([self.depth_m, *self.slope], dtype=float)
        if vals.shape != (3,) or not np.all(np.isfinite(vals)):
            raise ConfigError(
                f"PlaneSeabed: depth_m = {self.depth_m!r}, slope = {self.slope!r}: need a finite "
                "depth (m) and two finite slopes"
            )

    def ray_ranges(
        self, origin_m: ArrayLike, directions: ArrayLike, max_range_m: float
    ) -> tuple[Array, BoolArray]:
        """Closed-form ray-plane intersection (see :class:`RaySeabed`): with the height above the
        seabed ``f(x) = z + depth_m + slope . (x, y)``, the range is ``-f(o) / (grad f . e)``; a ray
        from at or below the seabed, or not coming down onto it, has no echo.

        Raises:
            GeometryError: for a zero or non-finite direction or a non-finite origin.
        """
        o, e = np.broadcast_arrays(np.asarray(origin_m, float), np.asarray(directions, float))
        norm = np.linalg.norm(e, axis=-1)
        if not np.all(np.isfinite(norm) & (norm > 0)) or not np.all(np.isfinite(o)):
            raise GeometryError(
                "ray_ranges: origins must be finite, directions finite and non-zero"
            )
        e = e / norm[..., None]
        sx, sy = self.slope
        f0 = o[..., 2] + self.depth_m + sx * o[..., 0] + sy * o[..., 1]
        rate = e[..., 2] + sx * e[..., 0] + sy * e[..., 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(rate < 0, f0 / -rate, np.inf)
        hit = (f0 > 0) & (rate < 0) & (s <= max_range_m)
        return np.where(hit, s, 0.0), hit


@dataclass(frozen=True)
class DvlSamples:
    """DVL output of a batch of runs.

    Attributes:
        t_s: times of validity, shape (k,), s.
        mode: 0 none, 1 bottom lock, 2 water track, shape (n, k), int8.
        velocity_body_m_s: measured velocity of the transducer, body FLU, shape (n, k, 3), m/s
            (over ground in bottom lock, through water in water track); 0 where mode 0.
        altitude_m: measured altitude, shape (n, k), m; 0 without bottom lock.
        beam_ranges_m: measured slant ranges, shape (n, k, 4), m; 0 where no echo.
        beam_echo: the beam returned, shape (n, k, 4).
        beam_directions_body: the nominal beam unit vectors, shape (4, 3), body FLU.
        true_velocity_body_m_s: the transducer's true velocity over ground, body FLU, shape
            (n, k, 3), m/s.
    """

    t_s: Array
    mode: NDArray[np.int8]
    velocity_body_m_s: Array
    altitude_m: Array
    beam_ranges_m: Array
    beam_echo: BoolArray
    beam_directions_body: Array
    true_velocity_body_m_s: Array


def _rotate(M: Array, v: Array) -> Array:
    """``M @ v`` over broadcast leading axes, as three products summed in a fixed order: the same
    bits for a sample whatever the batch around it (a BLAS product's blocking depends on the
    array sizes, so a batch and a ping alone could differ in the last bit).

    Args:
        M: shape (..., m, 3).
        v: shape (..., 3), broadcast against ``M``'s leading axes.

    Returns:
        Shape (..., m).
    """
    v = np.asarray(v)[..., None, :]
    return M[..., 0] * v[..., 0] + M[..., 1] * v[..., 1] + M[..., 2] * v[..., 2]


def _solve_velocity(D: Array, b: Array, use: BoolArray) -> Array:
    """Least squares ``v = argmin sum_{i used} (D_i . v - b_i)^2`` per sample.

    Args:
        D: beam vectors, shape (4, 3).
        b: beam velocities, shape (..., 4).
        use: beams used, shape (..., 4); samples with fewer than 3 get 0.

    Returns:
        Shape (..., 3).
    """
    w = use.astype(float)
    A = np.zeros((*b.shape[:-1], 3, 3))
    rhs = np.zeros((*b.shape[:-1], 3))
    for i in range(D.shape[0]):  # D^T W D and D^T W b, beam by beam (see _rotate)
        A += w[..., i, None, None] * np.outer(D[i], D[i])
        rhs += (w[..., i] * b[..., i])[..., None] * D[i]
    ok = use.sum(-1) >= 3
    A = np.where(ok[..., None, None], A, np.eye(3))  # 3 Janus beams span R^3: A is regular
    v = np.linalg.solve(A, rhs[..., None])[..., 0]
    return np.where(ok[..., None], v, 0.0)


class Dvl:
    """The DVL of a batch of runs (kinematic worlds, and the online device's errors and modes).

    Args:
        cfg: configuration.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this device; beam ``i``'s velocity draws from ``("sensor", name,
            "beam<i>", term)``, its range from ``("sensor", name, "range<i>", term)``.
    """

    def __init__(self, cfg: DvlConfig, seed: int, runs: tuple[int, ...], name: str = "dvl"):
        self.cfg = cfg
        self.n = len(runs)
        self.name = name
        d = beam_directions_instrument(cfg.beam_angle_deg)
        self.R_mount = rotation_rpy(cfg.mount_rpy_deg)
        self.R_mount_true = self.R_mount @ rotation_rpy(cfg.misalignment_deg)
        self.directions_instrument = d
        self.beam_directions_body = d @ self.R_mount.T
        self.true_directions_body = d @ self.R_mount_true.T
        self.cos_a = float(np.cos(np.radians(cfg.beam_angle_deg)))
        bm, rm = cfg.beam.to_model(), cfg.range.to_model()
        self._beam_err = [
            ErrorProcess(bm, seed, runs, ("sensor", name, f"beam{i}")) for i in range(BEAMS)
        ]
        self._range_err = [
            ErrorProcess(rm, seed, runs, ("sensor", name, f"range{i}")) for i in range(BEAMS)
        ]

    def measure(
        self,
        true_ranges_m: Array,
        hit: BoolArray,
        velocity_ground_body_m_s: Array,
        velocity_water_body_m_s: Array,
        t_s: Array,
    ) -> DvlSamples:
        """Apply the errors, the echo rules and the modes to ray-cast ranges and true velocities.

        Each beam's error streams are drawn once per sample whatever the mode (the errors are
        drawn as additive terms on top of ``(1 + scale_factor) x``), so the mode never shifts the
        numbers of later samples.

        Args:
            true_ranges_m: ray-cast slant ranges, shape (n, k, 4), m.
            hit: the ray met the seabed within :attr:`DvlConfig.max_range_m`, shape (n, k, 4).
            velocity_ground_body_m_s: the transducer's true velocity over ground, body FLU,
                shape (n, k, 3), m/s.
            velocity_water_body_m_s: the same through water, shape (n, k, 3), m/s.
            t_s: times, shape (k,), s (increasing across calls, for random walks).

        Returns:
            The samples.

        Raises:
            ConfigError: for arrays of the wrong shape or non-finite values.
        """
        cfg = self.cfg
        L = np.asarray(true_ranges_m, dtype=float)
        vg = np.asarray(velocity_ground_body_m_s, dtype=float)
        vw = np.asarray(velocity_water_body_m_s, dtype=float)
        t = np.asarray(t_s, dtype=float)
        n = self.n
        k = t.shape[0] if t.ndim == 1 else -1
        for what, arr, shape in (
            ("true_ranges_m", L, (n, k, BEAMS)),
            ("hit", np.asarray(hit), (n, k, BEAMS)),
            ("velocity_ground_body_m_s", vg, (n, k, 3)),
            ("velocity_water_body_m_s", vw, (n, k, 3)),
        ):
            if arr.shape != shape:
                raise ConfigError(f"dvl: {what} has shape {arr.shape}, expected {shape}")
        if not (np.all(np.isfinite(L)) and np.all(np.isfinite(vg)) and np.all(np.isfinite(vw))):
            raise ConfigError("dvl: non-finite true ranges or velocities; need finite values")
        sf_v, sf_r = 1.0 + cfg.beam.scale_factor, 1.0 + cfg.range.scale_factor
        zero = np.zeros((n, k))
        ev, okv, er, okr = [], [], [], []
        for i in range(BEAMS):
            e, ok = self._beam_err[i].apply(zero, t)
            ev.append(e)
            okv.append(ok)
            e, ok = self._range_err[i].apply(zero, t)
            er.append(e)
            okr.append(ok)
        err_v, alive_v = np.stack(ev, -1), np.stack(okv, -1)  # (n, k, 4)
        err_r, alive_r = np.stack(er, -1), np.stack(okr, -1)
        echo = np.asarray(hit, bool) & alive_v & alive_r & (L > 0) & (L <= cfg.max_range_m)
        ranges = np.where(echo, np.maximum(sf_r * L + err_r, 0.0), 0.0)
        n_echo = echo.sum(-1)
        altitude = ranges.sum(-1) * self.cos_a / np.maximum(n_echo, 1)  # 0 without echo
        # the measured altitude (range errors included) decides, as the DVL knows no other
        lock = (
            (n_echo >= cfg.min_beams)
            & (altitude >= cfg.min_altitude_m)
            & (altitude <= cfg.max_altitude_m)
        )
        water = ~lock & (alive_v.sum(-1) >= cfg.min_beams) & (cfg.fallback == "water")
        v_true = np.where(lock[..., None], vg, vw)
        b_true = _rotate(self.true_directions_body, v_true)  # (n, k, 4): d_i . v
        b = sf_v * b_true + err_v
        use = np.where(lock[..., None], echo, alive_v) & (lock | water)[..., None]
        v_instr = _solve_velocity(self.directions_instrument, b, use)  # 0 where no beam is used
        velocity = _rotate(self.R_mount, v_instr)
        mode = np.where(lock, BOTTOM_LOCK, np.where(water, WATER_TRACK, NONE)).astype(np.int8)
        return DvlSamples(
            t_s=t,
            mode=mode,
            velocity_body_m_s=velocity,
            altitude_m=np.where(lock, altitude, 0.0),
            beam_ranges_m=ranges,
            beam_echo=echo,
            beam_directions_body=self.beam_directions_body.copy(),
            true_velocity_body_m_s=vg,
        )

    def sample(
        self,
        truth: Truth,
        index: NDArray[np.intp],
        seabed: RaySeabed,
        angular_velocity_body_rad_s: Array | None = None,
    ) -> DvlSamples:
        """Pings at the given tick indices over a seabed (kinematic world).

        Args:
            truth: the truth (run axis n or 1).
            index: tick indices of the pings, shape (k,), increasing.
            seabed: the seabed the beams are cast against (world frame).
            angular_velocity_body_rad_s: the vehicle's angular velocity, body FLU, rad/s, shape
                (n or 1, T, 3) on the truth's time grid, or (3,) constant; ``None``: zero (the
                truth record carries none).

        Returns:
            The samples (:attr:`DvlSamples.t_s` = ``truth.t_s[index]``).

        Raises:
            ConfigError: for an angular velocity of the wrong shape or non-finite truth.
            GeometryError: from the seabed's ray cast (non-finite rays).
        """
        tr = truth.take(np.asarray(index, dtype=np.intp))
        n, k = self.n, tr.t_s.shape[0]
        pos = broadcast_runs(tr.pos_world_m, n)
        vel_g = broadcast_runs(tr.vel_ground_world_m_s, n)
        vel_w = broadcast_runs(tr.vel_water_world_m_s, n)
        rp = broadcast_runs(tr.roll_pitch_rad, n)
        hd = broadcast_runs(tr.heading_rad, n)
        if not all(np.all(np.isfinite(a)) for a in (pos, vel_g, vel_w, rp, hd)):
            raise ConfigError("dvl: the truth has non-finite values; need finite values")
        R = R_from_roll_pitch_heading(rp[..., 0], rp[..., 1], hd)  # (n, k, 3, 3) world<-body
        if angular_velocity_body_rad_s is None:
            w = np.zeros((n, k, 3))
        else:
            w_all = np.asarray(angular_velocity_body_rad_s, dtype=float)
            T = truth.t_s.shape[0]
            if w_all.shape == (3,):
                w = np.broadcast_to(w_all, (n, k, 3))
            elif w_all.ndim == 3 and w_all.shape[1:] == (T, 3) and w_all.shape[0] in (1, n):
                w = broadcast_runs(w_all[:, np.asarray(index, dtype=np.intp)], n)
            else:
                raise ConfigError(
                    f"dvl: angular_velocity_body_rad_s has shape {w_all.shape}; need (3,) or "
                    f"({n} or 1, {T}, 3) on the truth's time grid"
                )
        r = np.asarray(self.cfg.transducer_body_m, dtype=float)
        lever = np.cross(w, r)  # omega x r, body
        Rt = np.swapaxes(R, -1, -2)
        vg = _rotate(Rt, vel_g) + lever
        vw = _rotate(Rt, vel_w) + lever
        origin = pos + _rotate(R, r)
        dirs = _rotate(R[..., None, :, :], self.true_directions_body)  # (n, k, 4, 3)
        L, hit = seabed.ray_ranges(origin[..., None, :], dirs, self.cfg.max_range_m)
        return self.measure(L, hit, vg, vw, tr.t_s)


@dataclass(frozen=True)
class DvlPing:
    """One DVL output as the vehicle receives it (the payload of the online device's
    measurement).

    Attributes:
        mode: 1 bottom lock, 2 water track (no measurement without output).
        velocity_body_m_s: shape (3,), m/s, body FLU at the transducer.
        altitude_m: m; 0 without bottom lock.
        beam_ranges_m: shape (4,), m; 0 where no echo.
        beam_echo: shape (4,).
        beam_directions_body: nominal beam unit vectors, shape (4, 3), body FLU.
        lever_arm_body_m: transducer from the reference point, shape (3,), m, body FLU.
    """

    mode: int
    velocity_body_m_s: Array
    altitude_m: float
    beam_ranges_m: Array
    beam_echo: BoolArray
    beam_directions_body: Array
    lever_arm_body_m: Array


@register_device(DvlConfig)
class DvlDevice:
    """The DVL in a vehicle's rig (event): a ping every ``period_s``, valid and delivered at the
    ping, its beams cast by MuJoCo against the scene's seabed heightfield from the transducer (the
    configured lever arm, or the model's ``dvl`` site when it is zero).

    Value: the velocity, shape (3,), m/s, body FLU at the transducer; the payload is the
    :class:`DvlPing` (mode, altitude, beams, lever arm). No measurement at a ping without output
    (mode 0).
    """

    kind = "event"

    def __init__(self, cfg: DvlConfig, build: DeviceBuild):
        cfg = build.with_site(cfg, "transducer_body_m", "dvl")
        self.cfg = cfg
        self.lever_arm_body_m = np.asarray(cfg.transducer_body_m, dtype=float)
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._physics = build.physics
        self._dvl = Dvl(cfg, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement | None:
        """A ping at the DVL's ticks; ``None`` between them and at a ping without output."""
        if ctx.k % self.every:
            return None
        vt = ctx.truth
        R = R_from_quat_wxyz(vt.quat_wxyz)
        r = self.lever_arm_body_m
        lever = np.cross(vt.angular_velocity_body_rad_s, r)
        vg = _rotate(R.T, vt.velocity_world_m_s) + lever
        vw = _rotate(R.T, vt.velocity_through_water_world_m_s) + lever
        origin = vt.position_world_m + _rotate(R, r)
        dirs = _rotate(R, self._dvl.true_directions_body)
        dist, hit = self._physics.seabed_ray_distances(origin, dirs, self.cfg.max_range_m)
        s = self._dvl.measure(
            dist[None, None], hit[None, None], vg[None, None], vw[None, None], ctx.tt
        )
        mode = int(s.mode[0, 0])
        if mode == NONE:
            return None
        v = s.velocity_body_m_s[0, 0]
        ping = DvlPing(
            mode=mode,
            velocity_body_m_s=v,
            altitude_m=float(s.altitude_m[0, 0]),
            beam_ranges_m=s.beam_ranges_m[0, 0],
            beam_echo=s.beam_echo[0, 0],
            beam_directions_body=s.beam_directions_body,
            lever_arm_body_m=r.copy(),
        )
        return Measurement(self.name, ctx.t_s, ctx.t_s, v, ctx.measured_attitude_rad, ping)
