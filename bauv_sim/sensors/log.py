"""Electromagnetic log (ALIZE in seed 000): speed through water along the hull.

An EM log measures the water flowing past the hull, so it cannot see the current: its truth is the
forward (body x) component of the velocity through water. It is blind below a minimum speed (seed
000: sigma_SOG = 0.5 kn, ALIZE datasheet; in seed 000's world STW = SOG).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.frames import KNOT_M_S, unit_vector
from bauv_sim.sensors.base import SensorSamples, broadcast_runs
from bauv_sim.sensors.errors import ErrorProcess, SpeedErrorConfig
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth


def seed003_speed_error() -> SpeedErrorConfig:
    """Seed 003's log (ALIZE): uniform on [-0.3, +0.3] m/s plus Test 3's 0.005 m/s bias."""
    return SpeedErrorConfig(distribution="uniform", uniform_k=1.0, sigma_m_s=0.3, bias_m_s=0.005)


class LogConfig(Config):
    """Speed-through-water log."""

    period_s: float = Field(1.0, gt=0, description="sample period, s")
    speed: SpeedErrorConfig = Field(
        default_factory=lambda: SpeedErrorConfig(sigma_m_s=0.5 * KNOT_M_S),
        description="speed error (ALIZE: sigma 0.5 kn = 0.257 m/s)",
    )
    min_speed_m_s: float = Field(
        0.0, ge=0, description="below this true speed through water the log gives nothing, m/s"
    )


def forward_speed_through_water(truth: Truth) -> NDArray[np.float64]:
    """Body-x component of the velocity through water, shape (n, T), m/s.

    The body x axis in the world is ``(cos p sin h, cos p cos h, sin p)`` for pitch p and heading h
    (roll turns the body about that axis and does not move it).
    """
    p = truth.roll_pitch_rad[..., 1]
    u = unit_vector(truth.heading_rad)
    v = truth.vel_water_world_m_s
    cp = np.cos(p)
    return cp * u[..., 0] * v[..., 0] + cp * u[..., 1] * v[..., 1] + np.sin(p) * v[..., 2]


class Log:
    """Speed-through-water measurements of a batch of runs (see :class:`Compass` for the args)."""

    def __init__(self, cfg: LogConfig, seed: int, runs: tuple[int, ...], name: str = "log"):
        self.cfg = cfg
        self._err = ErrorProcess(cfg.speed.to_model(), seed, runs, ("sensor", name, "speed"))
        self.n = len(runs)

    def measure(
        self, speed_m_s: NDArray[np.float64], t_s: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Measure true forward speeds through water, shape (n, k), m/s (the online form of
        :meth:`sample`); returns ``(speed, produced)``."""
        value, produced = self._err.apply(speed_m_s, t_s)
        return value, produced & (np.abs(speed_m_s) >= self.cfg.min_speed_m_s)

    def sample(self, truth: Truth, index: NDArray[np.intp]) -> SensorSamples:
        """Measure at the given tick indices; values: speed through water, shape (n, k), m/s."""
        tr = truth.take(index)
        value, produced = self.measure(
            broadcast_runs(forward_speed_through_water(tr), self.n), tr.t_s
        )
        return SensorSamples(tr.t_s, value, produced, np.broadcast_to(tr.t_s, produced.shape))


@register_device(LogConfig)
class LogDevice:
    """The EM log in a vehicle's rig (held; nothing held after a sample below the minimum speed).

    Value: speed through water along the hull, shape (1,), m/s.
    """

    kind = "held"

    def __init__(self, cfg: LogConfig, build: DeviceBuild):
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._log = Log(cfg, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement | None:
        """Measure the true forward speed through water; ``None`` when the log is blind."""
        value, ok = self._log.measure(forward_speed_through_water(ctx.record), ctx.tt)
        if not ok[0, 0]:
            return None
        return Measurement(self.name, ctx.t_s, ctx.t_s, value[0])
