"""Pressure depth sensor (WIKA S-20 in seed 000).

Two outputs: ``depth`` (the sensor's reading, for a filter that updates on depth) and
``depth_change`` (seed 000 section 5: the change of submergence Delta z over each sample period,
measured with its own independent error sigma_dz = 0.25 m, which is how the paper's EKF is driven).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.sensors.base import SensorSamples, broadcast_runs
from bauv_sim.sensors.errors import ErrorProcess, LengthErrorConfig
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth


class PressureConfig(Config):
    """Pressure depth sensor."""

    period_s: float = Field(1.0, gt=0, description="sample period, s")
    output: Literal["depth", "depth_change"] = Field(
        "depth", description="depth, or the change of depth since the previous sample"
    )
    depth: LengthErrorConfig = Field(
        default_factory=lambda: LengthErrorConfig(sigma_m=0.25),
        description="error of the output (seed 000: sigma_dz = 0.25 m)",
    )


class Pressure:
    """Depth or depth-change measurements (see :class:`Compass` for the args)."""

    def __init__(
        self, cfg: PressureConfig, seed: int, runs: tuple[int, ...], name: str = "pressure"
    ):
        self.cfg = cfg
        self._err = ErrorProcess(cfg.depth.to_model(), seed, runs, ("sensor", name, "depth"))
        self.n = len(runs)

    def measure(
        self, value: NDArray[np.float64], t_s: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Measure true depths (or depth changes), shape (n, k), m (the online form of
        :meth:`sample`); returns ``(value, produced)``."""
        return self._err.apply(value, t_s)

    def sample(
        self, truth: Truth, index: NDArray[np.intp], previous: NDArray[np.intp] | None = None
    ) -> SensorSamples:
        """Measure at the given tick indices.

        Args:
            truth: truth record.
            index: tick indices of the samples, shape (k,).
            previous: for ``depth_change``, the tick each change starts from (default: the tick
                before each index, minus one sample period of the grid).

        Returns:
            Samples; values are depth (m, positive down) or the depth change (m, positive down)
            from ``previous`` to ``index``, shape (n, k).
        """
        tr = truth.take(index)
        depth = broadcast_runs(tr.depth_m, self.n)
        if self.cfg.output == "depth_change":
            prev = index - 1 if previous is None else previous
            depth = depth - broadcast_runs(truth.take(prev).depth_m, self.n)
        value, produced = self.measure(depth, tr.t_s)
        return SensorSamples(tr.t_s, value, produced, np.broadcast_to(tr.t_s, produced.shape))


@register_device(PressureConfig)
class PressureDevice:
    """The pressure sensor in a vehicle's rig (held; ``output = "depth"``).

    Value: measured depth of the reference point, shape (1,), m (positive down).
    """

    kind = "held"

    def __init__(self, cfg: PressureConfig, build: DeviceBuild):
        if cfg.output != "depth":
            raise ConfigError(
                f"sensors.{build.name}.output = {cfg.output!r}: a vehicle's rig measures 'depth'"
            )
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._pressure = Pressure(cfg, build.seed, (build.run,), build.stream)

    def step(self, ctx: TickContext) -> Measurement:
        """Measure the true depth."""
        # one sample in Python floats: the same bits as measure() (ErrorProcess.apply_one)
        value, _ = self._pressure._err.apply_one(float(ctx.truth.depth_m), ctx.t_s)
        return Measurement(self.name, ctx.t_s, ctx.t_s, np.array([value]))
