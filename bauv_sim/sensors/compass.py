"""Compass / INS heading (VectorNav VN-100 / VN-200 in the seeds).

Seed 000 uses the INS course with sigma_COG = 3 deg in its analysis (section 3) and 8 deg in its
experiment (section 6); in a world without current and drift angle the heading is the course over
ground. Compass deviation (A + B sin psi + C cos psi + D sin 2 psi + E cos 2 psi) and the
course-sector bias of seed 003 are part of the error vocabulary (:mod:`bauv_sim.sensors.errors`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.frames import course_of_scalar, wrap_2pi, wrap_2pi_scalar
from bauv_sim.sensors.base import SensorSamples, broadcast_runs
from bauv_sim.sensors.errors import AngleErrorConfig, ErrorProcess
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device
from bauv_sim.truth import Truth


def seed003_heading_error() -> AngleErrorConfig:
    """Seed 003's compass (VN-100): uniform on [-2, +2] deg plus Test 3's calibrated
    course-sector bias (0.4, 0.8, 0, 0.2 deg)."""
    return AngleErrorConfig(
        distribution="uniform", uniform_k=1.0, sigma_deg=2.0, sector_bias_deg=(0.4, 0.8, 0.0, 0.2)
    )


class CompassConfig(Config):
    """Compass / INS heading sensor."""

    period_s: float = Field(1.0, gt=0, description="sample period, s (a multiple of the tick)")
    heading: AngleErrorConfig = Field(
        default_factory=lambda: AngleErrorConfig(sigma_deg=3.0),
        description="heading error (seed 000 section 3: sigma 3 deg)",
    )


class Compass:
    """Heading measurements of a batch of runs.

    Args:
        cfg: configuration.
        seed: batch seed.
        runs: run indices of the rows.
        name: stream name of this device.
    """

    def __init__(self, cfg: CompassConfig, seed: int, runs: tuple[int, ...], name: str = "compass"):
        self.cfg = cfg
        self._err = ErrorProcess(cfg.heading.to_model(), seed, runs, ("sensor", name, "heading"))
        self.n = len(runs)

    def measure(
        self,
        heading_rad: NDArray[np.float64],
        t_s: NDArray[np.float64],
        course_rad: NDArray[np.float64] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Measure true headings (the online form of :meth:`sample`).

        Args:
            heading_rad: true heading, shape (n, k), rad.
            t_s: times, shape (k,), s.
            course_rad: true course over ground, shape (n, k), rad (only for error models with a
                course-sector bias or deviation).

        Returns:
            ``(heading (n, k) rad in [0, 2 pi), produced (n, k))``.
        """
        value, produced = self._err.apply(heading_rad, t_s, reference_rad=course_rad)
        return wrap_2pi(value), produced

    def sample(self, truth: Truth, index: NDArray[np.intp]) -> SensorSamples:
        """Measure at the given tick indices of ``truth``.

        Returns:
            Samples with values = heading, shape (n, k), rad in [0, 2 pi) clockwise from north.
        """
        tr = truth.take(index)
        heading = broadcast_runs(tr.heading_rad, self.n)
        course = None
        if self._err.model.needs_reference():
            course = broadcast_runs(tr.course_over_ground_rad, self.n)
        value, produced = self.measure(heading, tr.t_s, course)
        return SensorSamples(tr.t_s, value, produced, np.broadcast_to(tr.t_s, produced.shape))


@register_device(CompassConfig)
class CompassDevice:
    """The compass in a vehicle's rig (held; sampled every ``period_s``).

    Value: measured heading, shape (1,), rad in [0, 2 pi) clockwise from north.
    """

    kind = "held"

    def __init__(self, cfg: CompassConfig, build: DeviceBuild):
        self.name = build.name
        self.every = build.every(cfg.period_s)
        self._compass = Compass(cfg, build.seed, (build.run,), build.stream)
        self._needs_course = cfg.heading.to_model().needs_reference()

    def step(self, ctx: TickContext) -> Measurement:
        """Measure the true heading (and pass the course over ground to sector-bias models)."""
        vt = ctx.truth
        if not self._needs_course:  # one sample in Python floats: the same bits as measure()
            value, _ = self._compass._err.apply_one(float(vt.roll_pitch_heading_rad[2]), ctx.t_s)
            return Measurement(self.name, ctx.t_s, ctx.t_s, np.array([wrap_2pi_scalar(value)]))
        v = vt.velocity_world_m_s
        course = np.array([[course_of_scalar(v[0], v[1])]])
        heading = self._compass.measure(np.array([[vt.roll_pitch_heading_rad[2]]]), ctx.tt, course)
        return Measurement(self.name, ctx.t_s, ctx.t_s, heading[0][0])
