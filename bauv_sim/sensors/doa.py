"""DOA: bearings from the vehicle to acoustic beacons of known position (seed 004, eq. 17).

Angles are seed 004's: the azimuth ``phi`` from the x (east) axis counter-clockwise, the
elevation ``lambda`` up from the horizontal, of the beacon seen from the vehicle's receiver:

    phi = atan2(Y_B - Y, X_B - X),    lambda = atan2(Z_B - Z, rho),   rho = |(X_B - X, Y_B - Y)|,

and the observation in eq. 17's form is the pair of tangents

    tan(phi) = (Y_B - Y) / (X_B - X),
    tan(lambda) = (Z_B - Z) cos(phi) / (X_B - X) = (Z_B - Z) / rho.

**Errors.** The shared vocabulary (:mod:`bauv_sim.sensors.errors`) on each of the two, either
on the tangents, as the seed (``noise_on = "tangent"``: eq. 17's ``eps``; every angle-valued
parameter of the error model is replaced by its tangent, so ``sigma_deg = 0.5`` gives the seed's
``N(0, tan^2(0.5 deg))``), or on the angles (``noise_on = "angle"``; an elevation carried past
the zenith folds over the top, 180 deg around in azimuth). The measured angles and the measured
tangents are given together: in tangent mode the angles are the arctangents of the measured
tangents, the azimuth in the true half-plane (the receiver knows left from right); in angle
mode the tangents are those of the measured angles. Sector biases and compass deviation are
not defined for a DOA and are refused.

**Bad geometry** degrades clearly, never with a NaN:

* a beacon (nearly) straight above or below the receiver, horizontal distance below
  ``min_horizontal_m``, has no azimuth: the bearing is not produced and flagged ``overhead``;
* where a true tangent exceeds ``max_tangent`` in size (eq. 17's form near phi = +-90 deg,
  where X_B - X vanishes, or near the zenith), the bearing is produced as angles, but its
  tangent pair is flagged (``tangent_ok`` False) and set to 0;
* beyond ``max_range_m`` (slant) or with ``dropout_probability`` no bearing is produced.

:meth:`DoaSamples.warnings` turns the flags into lines a report can print.

:class:`Doa` is the batched form (kinematic truth, any number of runs); :class:`DoaDevice` the
online device of a rig (event), against the scene's beacon sites.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.sensors.base import broadcast_runs, point_world
from bauv_sim.sensors.errors import AngleErrorConfig, ErrorModel, ErrorProcess
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_HUGE = 1e300
"""Stands in for an infinite tangent inside the computation (never output)."""


def _seed004_bearing_error() -> AngleErrorConfig:
    return AngleErrorConfig(sigma_deg=0.5)


class DoaConfig(Config):
    """DOA bearings to beacons (defaults: seed 004 section 6)."""

    period_s: float = Field(1.0, gt=0, description="time between bearing sets, s (seed 004: 1)")
    azimuth: AngleErrorConfig = Field(
        default_factory=_seed004_bearing_error,
        description="error of phi (seed 004: 0.5 deg, on the tangent)",
    )
    elevation: AngleErrorConfig = Field(
        default_factory=_seed004_bearing_error,
        description="error of lambda (seed 004: 0.5 deg, on the tangent)",
    )
    noise_on: Literal["tangent", "angle"] = Field(
        "tangent", description="errors on eq. 17's tangents (seed 004) or on the angles"
    )
    max_range_m: float = Field(5000.0, gt=0, description="no bearing beyond this slant range, m")
    min_horizontal_m: float = Field(
        0.01,
        gt=0,
        description="no bearing (beacon overhead) below this horizontal distance, m",
    )
    max_tangent: float = Field(
        1e3, gt=0, description="a tangent pair beyond this size is flagged, not given"
    )
    dropout_probability: float = Field(0.0, ge=0, lt=1, description="probability a set is lost")
    processing_delay_s: float = Field(0.0, ge=0, description="latency (online rigs), s")
    receiver_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="receiver relative to the reference point, m, body FLU"
    )

    @field_validator("azimuth", "elevation")
    @classmethod
    def _no_reference(cls, v: AngleErrorConfig) -> AngleErrorConfig:
        if v.sector_bias_deg is not None or v.deviation_deg is not None:
            raise ValueError("sector_bias_deg and deviation_deg are not defined for a DOA")
        return v


def tangent_model(model: ErrorModel) -> ErrorModel:
    """An angle error model (rad) carried over to the tangent of the angle: sigma, bias,
    outlier sigma and random walk replaced by their tangents (seed 004's ``tan(0.5 deg)``)."""
    return dataclasses.replace(
        model,
        sigma=math.tan(model.sigma),
        bias=math.tan(model.bias),
        outlier_sigma=math.tan(model.outlier_sigma),
        random_walk=math.tan(model.random_walk),
    )


def true_bearings(rel_world_m: Array) -> tuple[Array, Array, Array, Array]:
    """Seed 004 angles of beacons seen from the receiver.

    Args:
        rel_world_m: beacon minus receiver, shape (..., 3), m, world (z up).

    Returns:
        ``(phi, lambda, rho, slant)``: azimuth from x counter-clockwise in (-pi, pi], elevation
        in [-pi/2, pi/2], rad; horizontal and slant distance, m; each shape (...).
    """
    r = np.asarray(rel_world_m, dtype=float)
    rho = np.hypot(r[..., 0], r[..., 1])
    return (
        np.arctan2(r[..., 1], r[..., 0]),
        np.arctan2(r[..., 2], rho),
        rho,
        np.sqrt(rho**2 + r[..., 2] ** 2),
    )


def _safe_ratio(num: Array, den: Array) -> Array:
    """num / den with a zero denominator giving +-_HUGE (finite), sign of num (+ for 0 / 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        q = num / den
    return np.where(den == 0, np.where(num < 0, -_HUGE, _HUGE), np.clip(q, -_HUGE, _HUGE))


@dataclass(frozen=True)
class DoaSamples:
    """Bearings of a batch of runs to B beacons.

    Attributes:
        t_s: times of validity, shape (k,), s.
        tangents: eq. 17's ``(tan phi, tan lambda)``, shape (n, k, B, 2) (0 where not
            ``tangent_ok``).
        angles_rad: ``(phi, lambda)``, shape (n, k, B, 2), rad (0 where not ``produced``).
        produced: the bearing exists, shape (n, k, B).
        tangent_ok: produced and both true tangents within ``max_tangent``, shape (n, k, B).
        overhead: the beacon is within ``min_horizontal_m`` of straight above or below (no
            bearing), shape (n, k, B).
        t_arrival_s: when the set reaches the vehicle, shape (n, k), s.
    """

    t_s: Array
    tangents: Array
    angles_rad: Array
    produced: BoolArray
    tangent_ok: BoolArray
    overhead: BoolArray
    t_arrival_s: Array

    def warnings(self, names: tuple[str, ...] | None = None) -> list[str]:
        """One line per beacon with degenerate geometry (empty when there is none).

        Args:
            names: beacon names (default ``beacon 0``, ``beacon 1``...).
        """
        out = []
        total = self.produced.shape[0] * self.produced.shape[1]
        for b in range(self.produced.shape[2]):
            name = names[b] if names else f"beacon {b}"
            over = int(self.overhead[..., b].sum())
            ill = int((self.produced[..., b] & ~self.tangent_ok[..., b]).sum())
            if over:
                out.append(
                    f"DOA {name}: {over} of {total} samples with the beacon straight above or "
                    "below the receiver (no bearing)"
                )
            if ill:
                out.append(
                    f"DOA {name}: {ill} of {total} samples with an ill-conditioned eq. 17 form "
                    "(tangent beyond max_tangent; angles only)"
                )
        return out


class Doa:
    """DOA bearings of a batch of runs.

    Args:
        cfg: configuration.
        beacons_world_m: beacon positions, shape (B, 3), m, world.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this device.
    """

    def __init__(
        self,
        cfg: DoaConfig,
        beacons_world_m: Array,
        seed: int,
        runs: tuple[int, ...],
        name: str = "doa",
    ):
        self.cfg = cfg
        self.beacons_world_m = np.asarray(beacons_world_m, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(self.beacons_world_m)):
            raise ConfigError("doa: beacon positions must be finite")
        self.n = len(runs)
        base = ("sensor", name)
        models = [cfg.azimuth.to_model(), cfg.elevation.to_model()]
        if cfg.noise_on == "tangent":
            models = [tangent_model(m) for m in models]
        self._errs = [
            [
                ErrorProcess(models[c], seed, runs, (*base, f"beacon{b}", comp))
                for c, comp in enumerate(("azimuth", "elevation"))
            ]
            for b in range(self.beacons_world_m.shape[0])
        ]
        self._drop = (
            rng_mod.RunStreams(seed, runs, *base, "set_dropout")
            if cfg.dropout_probability > 0
            else None
        )

    def sample(self, truth: Truth, index: NDArray[np.intp]) -> DoaSamples:
        """Bearings at given tick indices of a truth record (receiver at its lever arm)."""
        tr = truth.take(index)
        pos = broadcast_runs(point_world(tr, self.cfg.receiver_body_m), self.n)
        return self.sample_positions(pos, tr.t_s)

    def sample_positions(self, receiver_world_m: Array, t_s: Array) -> DoaSamples:
        """Bearings from given receiver positions.

        Args:
            receiver_world_m: shape (n, k, 3), m, world.
            t_s: times, shape (k,), s.

        Returns:
            The :class:`DoaSamples`.
        """
        cfg = self.cfg
        pos = np.asarray(receiver_world_m, dtype=float)
        n, k, _ = pos.shape
        if n != self.n:
            raise ConfigError(f"doa: {n} rows of positions for {self.n} runs")
        rel = self.beacons_world_m[None, None] - pos[:, :, None, :]  # (n, k, B, 3)
        phi, lam, rho, slant = true_bearings(rel)
        overhead = rho < cfg.min_horizontal_m
        t_phi = _safe_ratio(rel[..., 1], rel[..., 0])  # eq. 17
        t_lam = _safe_ratio(rel[..., 2], rho)  # eq. 17: (Z_B - Z) cos(phi) / (X_B - X)
        B = rel.shape[2]
        meas_t = np.empty((n, k, B, 2))
        meas_a = np.empty((n, k, B, 2))
        produced = ~overhead & (slant <= cfg.max_range_m)
        tt = np.asarray(t_s, dtype=float)
        for b in range(B):
            e_phi, e_lam = self._errs[b]
            if cfg.noise_on == "tangent":
                tp, ok_p = e_phi.apply(t_phi[..., b], tt)
                tl, ok_l = e_lam.apply(t_lam[..., b], tt)
                base = np.arctan(tp)
                left = rel[..., b, 0] < 0  # the true half-plane x < 0
                ap = np.where(left, base + np.where(base <= 0, np.pi, -np.pi), base)
                al = np.arctan(tl)
            else:
                ap, ok_p = e_phi.apply(phi[..., b], tt)
                al, ok_l = e_lam.apply(lam[..., b], tt)
                over = np.abs(al) > np.pi / 2  # past the zenith: over the top
                al = np.where(over, np.sign(al) * np.pi - al, al)
                ap = np.where(over, ap + np.pi, ap)
                ap = np.mod(ap + np.pi, 2 * np.pi) - np.pi
                tp = _safe_ratio(np.sin(ap), np.cos(ap))
                tl = _safe_ratio(np.sin(al), np.cos(al))
            produced[..., b] &= ok_p & ok_l
            meas_t[..., b, 0], meas_t[..., b, 1] = tp, tl
            meas_a[..., b, 0], meas_a[..., b, 1] = ap, al
        if self._drop is not None:
            lost = self._drop.draw("random", k) < cfg.dropout_probability
            produced &= ~lost[..., None]
        tangent_ok = produced & (np.abs(t_phi) <= cfg.max_tangent)
        tangent_ok &= np.abs(t_lam) <= cfg.max_tangent
        tangent_ok &= np.all(np.abs(meas_t) <= cfg.max_tangent, axis=-1)
        meas_t = np.where(tangent_ok[..., None], meas_t, 0.0)
        meas_a = np.where(produced[..., None], meas_a, 0.0)
        t_arr = np.broadcast_to(tt + cfg.processing_delay_s, (n, k)).copy()
        return DoaSamples(tt, meas_t, meas_a, produced, tangent_ok, overhead, t_arr)


@dataclass(frozen=True)
class DoaSet:
    """One bearing set as the vehicle receives it (the payload of the online measurement).

    Attributes:
        beacons: beacon names, length B.
        beacons_world_m: their positions, shape (B, 3), m, world.
        tangents: ``(tan phi, tan lambda)``, shape (B, 2) (0 where not ``tangent_ok``).
        angles_rad: ``(phi, lambda)``, shape (B, 2), rad (0 where not ``produced``).
        produced: shape (B,).
        tangent_ok: shape (B,).
        overhead: shape (B,).
    """

    beacons: tuple[str, ...]
    beacons_world_m: Array
    tangents: Array
    angles_rad: Array
    produced: BoolArray
    tangent_ok: BoolArray
    overhead: BoolArray


@register_device(DoaConfig)
class DoaDevice:
    """The DOA receiver in a vehicle's rig (event): a bearing set to the scene's beacons (sites
    ``beacon_*``) every ``period_s``, valid at the tick and reaching the vehicle after
    ``processing_delay_s``.

    Value: ``(phi, lambda)`` per beacon in name order, shape (2 B,), rad (0 where not produced);
    the payload is the :class:`DoaSet` (tangents and flags). Nothing is delivered when no
    bearing of the set is produced. The receiver is the configured lever arm (default: the
    reference point).
    """

    kind = "event"

    def __init__(self, cfg: DoaConfig, build: DeviceBuild):
        beacons = build.physics.beacons_world()
        if not beacons:
            raise ConfigError(f"sensors.{build.name}: the scene has no beacons (sites beacon_*)")
        self.beacons = tuple(sorted(beacons))
        self.beacons_world_m = np.stack([beacons[b] for b in self.beacons])
        self.lever_arm_body_m = np.asarray(cfg.receiver_body_m, dtype=float)
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._doa = Doa(cfg, self.beacons_world_m, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement | None:
        """A bearing set at the receiver's ticks (``None`` when none is produced)."""
        if ctx.k % self.every:
            return None
        s = self._doa.sample(ctx.record, _FIRST)
        if not s.produced[0, 0].any():
            return None
        payload = DoaSet(
            self.beacons,
            self.beacons_world_m,
            s.tangents[0, 0],
            s.angles_rad[0, 0],
            s.produced[0, 0],
            s.tangent_ok[0, 0],
            s.overhead[0, 0],
        )
        return Measurement(
            self.name,
            ctx.t_s,
            float(s.t_arrival_s[0, 0]),
            s.angles_rad[0, 0].reshape(-1),
            ctx.measured_attitude_rad,
            payload,
        )


_FIRST = np.zeros(1, dtype=np.intp)
