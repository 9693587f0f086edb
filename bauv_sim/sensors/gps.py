"""GPS fix, only when the antenna is out of the water.

A GNSS receiver needs its antenna above the surface; after surfacing it needs an acquisition time
before the first fix (a hot start takes seconds). Horizontal errors are gaussian per axis by
default (sigma 2.5 m per axis ~ a CEP of 3 m for a small single-frequency receiver).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.geo import LocalFrame
from bauv_sim.sensors.base import SensorSamples, broadcast_runs, point_world
from bauv_sim.sensors.errors import ErrorProcess, LengthErrorConfig
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth


class GpsConfig(Config):
    """GPS receiver."""

    period_s: float = Field(1.0, gt=0, description="fix period at the surface, s")
    position: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=2.5),
        description="error of each horizontal coordinate",
    )
    max_antenna_depth_m: float = Field(
        0.0, description="a fix needs the antenna shallower than this, m (0: above the surface)"
    )
    acquisition_s: float = Field(5.0, ge=0, description="time at the surface before a fix, s")
    antenna_body_m: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="antenna relative to the vehicle reference point, m, body"
    )


class Gps:
    """GPS fixes of a batch of runs (see :class:`bauv_sim.sensors.Compass` for the args).

    The acquisition clock is kept per run across calls: call :meth:`sample` with consecutive
    samples in time order.
    """

    def __init__(self, cfg: GpsConfig, seed: int, runs: tuple[int, ...], name: str = "gps"):
        self.cfg = cfg
        self.n = len(runs)
        m = cfg.position.to_model()
        self._errs = [ErrorProcess(m, seed, runs, ("sensor", name, axis)) for axis in ("e", "n")]
        self._surfaced_since = np.full(self.n, np.nan)

    def submerged(self) -> None:
        """Tell the receiver the antenna is under water (restarts the acquisition clock), when a
        caller skips :meth:`sample` while the vehicle is deep."""
        self._surfaced_since[:] = np.nan

    def sample(self, truth: Truth, index: NDArray[np.intp]) -> SensorSamples:
        """Fix at the given tick indices.

        Returns:
            Samples with values (east, north), shape (n, k, 2), m, world; produced only while the
            antenna has been out of the water for ``acquisition_s``.
        """
        tr = truth.take(index)
        ant = broadcast_runs(point_world(tr, self.cfg.antenna_body_m), self.n)
        up = -ant[..., 2] <= self.cfg.max_antenna_depth_m
        vals, produced = [], up.copy()
        for j, err in enumerate(self._errs):
            v, ok = err.apply(ant[..., j], tr.t_s)
            vals.append(v)
            produced &= ok
        for i in range(len(index)):
            t = tr.t_s[i]
            since = self._surfaced_since
            since[:] = np.where(up[:, i], np.where(np.isnan(since), t, since), np.nan)
            produced[:, i] &= up[:, i] & (t - since >= self.cfg.acquisition_s)
        return SensorSamples(
            tr.t_s, np.stack(vals, -1), produced, np.broadcast_to(tr.t_s, produced.shape)
        )


@register_device(GpsConfig)
class GpsDevice:
    """The GPS receiver in a vehicle's rig (event): a fix when the antenna has been out of the
    water for the acquisition time.

    The receiver does not try while the vehicle's reference point is deeper than
    ``max_antenna_depth_m`` + the lever arm's length + :data:`DEEP_MARGIN_M` (the antenna is
    surely under water there): its acquisition clock restarts without a sample. The antenna's
    lever arm is the configured one, or the model's site when it is zero.

    Value: the antenna's (east, north), shape (2,), m, world (no lever-arm correction); with the
    scene's geographic frame in the rig's per-device settings (``extra={"gps": {"frame":
    frame}}``, a :class:`bauv_sim.geo.LocalFrame`), the antenna's WGS 84 (latitude, longitude),
    shape (2,), deg, as a receiver reports it: the same fix (errors in metres on the ground)
    through the frame's inverse projection.
    """

    kind = "event"

    def __init__(self, cfg: GpsConfig, build: DeviceBuild):
        cfg = build.with_lever_arm(cfg, "antenna_body_m")
        arm = cfg.antenna_body_m
        self.lever_arm_body_m = np.asarray(arm, dtype=float)
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self.deep_m = cfg.max_antenna_depth_m + DEEP_MARGIN_M + float(np.linalg.norm(arm))
        self._gps = Gps(cfg, build.seed, (build.run,), build.stream)
        self.frame: LocalFrame | None = build.extra.get("frame")

    def step(self, ctx: TickContext) -> Measurement | None:
        """A fix at the GPS's ticks when the antenna is up (``None`` otherwise)."""
        if ctx.truth.depth_m > self.deep_m:
            self._gps.submerged()
            return None
        if ctx.k % self.every:
            return None
        g = self._gps.sample(ctx.record, _FIRST)
        if not g.produced[0, 0]:
            return None
        value = g.values[0, 0]
        if self.frame is not None:
            value = np.concatenate(self.frame.to_geographic(value[0], value[1]), axis=None)
        return Measurement(self.name, ctx.t_s, ctx.t_s, value, ctx.measured_attitude_rad)


DEEP_MARGIN_M = 0.5
"""Margin beyond which the receiver stops trying, m (see :class:`GpsDevice`)."""

_FIRST = np.zeros(1, dtype=np.intp)
