"""``acoustics/sound-speed``: what a sound-speed mismatch costs the USBL and the modem, on
kinematic truth (issue 24, acceptance check 5).

The sea has a sound-speed profile (``sound``; default Munk's 1974 thermocline, 3 % faster than
the nominal 1500 m/s near the surface); the USBL and the modem measure in it
(:class:`bauv_sim.sensors.usbl.Usbl`, :class:`bauv_sim.sensors.modem.Modem` with the true
medium: range = nominal speed x travel time along the bent ray, the USBL's elevation the
arrival direction). Two navigators turn the measurements into positions and ranges: with the
nominal speed and straight rays, and with the profile known (:mod:`nav.acoustics.inversion`).
The report gives, for each, the systematic error (devices without their errors) and the Monte
Carlo error over the runs (with them): the USBL's position error along a passage and the
modem's range error over link depths and ranges.

Run: ``bauv run acoustics/sound-speed`` (``--runs N``, ``--set sound.kind=table --set
sound.depths_m=[0, 100] --set sound.speeds_m_s=[1520, 1510]``). Every run draws from its own
streams: the same seed gives the same numbers whatever the blocks or the workers. Modules:
:mod:`tasks.acoustics.scenario`, :mod:`tasks.acoustics.run`, :mod:`tasks.acoustics.report`; this
one registers the experiment.
"""

from __future__ import annotations

from dataclasses import dataclass

from tasks.acoustics.report import SoundSpeedMetrics, report_sound_speed
from tasks.acoustics.run import run_block
from tasks.acoustics.scenario import SoundSpeedScenario
from tasks.core.registry import Experiment, ReportContext, ReportSummary, register

__all__ = ["SoundSpeedExperiment"]


@dataclass(frozen=True)
class SoundSpeedExperiment(Experiment):
    """The cost of a sound-speed mismatch (module docstring)."""

    scenario_type = SoundSpeedScenario
    metrics_type = SoundSpeedMetrics

    def block_size(self, scenario: SoundSpeedScenario) -> int:
        return scenario.runner.block_size

    def run_block(self, scenario: SoundSpeedScenario, seed: int, runs: tuple[int, ...]):
        return run_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_sound_speed(self.name, self.summary, ctx)


register(
    SoundSpeedExperiment(
        name="acoustics/sound-speed",
        summary="kinematic: USBL position and modem range errors with the nominal sound speed "
        "against a profile (Munk 1974), and with the profile known",
        default_runs=100,
    )
)
