"""Odometry speed: the speed the drive setting should give, from a calibration table.

Seed 001's BAUV has no log: it dead-reckons with "odometry", the average speed measured for each
drive setting. Here the setting is the commanded tail-beat frequency and the calibration is the
self-propelled speed table of the physics model (``models/bauv/speed_table.csv``). The odometry
knows nothing of the current or of the vehicle's actual motion: its error is the error of the
table plus the shared error vocabulary (a scale factor is a badly calibrated table).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.sensors.base import SensorSamples
from bauv_sim.sensors.errors import ErrorProcess, SpeedErrorConfig
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device


class OdometryConfig(Config):
    """Speed from the drive setting."""

    period_s: float = Field(1.0, gt=0, description="sample period, s")
    frequency_hz: tuple[float, ...] = Field(
        (),
        description="calibration: tail-beat frequencies, Hz (increasing); empty: the "
        "vehicle's own speed table, filled in by the mission",
    )
    speed_m_s: tuple[float, ...] = Field(
        (), description="calibration: steady speed through water at each frequency, m/s"
    )
    speed: SpeedErrorConfig = Field(
        default_factory=SpeedErrorConfig, description="error of the odometry speed"
    )

    @model_validator(mode="after")
    def _table(self) -> OdometryConfig:
        f = np.asarray(self.frequency_hz)
        if len(f) == len(self.speed_m_s) == 0:
            return self
        if len(f) != len(self.speed_m_s) or len(f) < 2:
            raise ValueError(
                "frequency_hz and speed_m_s need the same length (>= 2), or both "
                "empty for the vehicle's speed table"
            )
        if np.any(np.diff(f) <= 0):
            raise ValueError(f"frequency_hz = {self.frequency_hz}: must be strictly increasing")
        return self

    def speed_at(self, frequency_hz: NDArray[np.float64]) -> NDArray[np.float64]:
        """Calibrated speed at a setting, linear between table rows, clamped at the ends, m/s."""
        if not self.frequency_hz:
            raise ValueError("odometry table is empty: fill it from the vehicle's speed table")
        return np.interp(frequency_hz, self.frequency_hz, self.speed_m_s)


class Odometry:
    """Odometry speeds of a batch of runs (see :class:`bauv_sim.sensors.Compass` for the args)."""

    def __init__(
        self, cfg: OdometryConfig, seed: int, runs: tuple[int, ...], name: str = "odometry"
    ):
        self.cfg = cfg
        self._err = ErrorProcess(cfg.speed.to_model(), seed, runs, ("sensor", name, "speed"))

    def sample(self, t_s: NDArray[np.float64], frequency_hz: NDArray[np.float64]) -> SensorSamples:
        """Speeds for commanded tail-beat frequencies.

        Args:
            t_s: sample times, shape (k,), s.
            frequency_hz: commanded tail-beat frequency, shape (n, k), Hz.

        Returns:
            Samples with values = speed, shape (n, k), m/s.
        """
        v, ok = self._err.apply(self.cfg.speed_at(np.asarray(frequency_hz, float)), t_s)
        return SensorSamples(np.asarray(t_s, float), v, ok, np.broadcast_to(t_s, ok.shape))


@register_device(OdometryConfig)
class OdometryDevice:
    """Odometry in a vehicle's rig (held): speed from the commanded tail-beat frequency.

    An empty calibration table is filled from the vehicle's speed table, given by the mission as
    ``extra = {"speed_table": SpeedTable}``.

    Value: speed through water, shape (1,), m/s.
    """

    kind = "held"

    def __init__(self, cfg: OdometryConfig, build: DeviceBuild):
        table = build.extra.get("speed_table")
        if not cfg.frequency_hz:
            if table is None:
                raise ConfigError(
                    f"sensors.{build.name}: empty calibration table and no speed table given"
                )
            cfg = cfg.model_copy(
                update={
                    "frequency_hz": tuple(float(f) for f in table.frequency_hz),
                    "speed_m_s": tuple(float(v) for v in table.speed_m_s),
                }
            )
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._odometry = Odometry(cfg, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement:
        """The speed of the commanded tail-beat frequency."""
        f = np.array([[float(ctx.commands["tail_beat_frequency_hz"])]])
        s = self._odometry.sample(ctx.tt, f)
        return Measurement(self.name, ctx.t_s, ctx.t_s, s.values[0])
