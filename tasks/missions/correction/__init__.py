"""``mission/correction``: seed 001's correction procedures on the physical BAUV.

The BAUV of seed 001 has a compass and odometry only (no log, no USBL). It starts from a GPS fix,
swims leg 1 holding course alpha_1, surfaces for GPS fixes, swims leg 2 on alpha_2, surfaces
again; the DRNS (:mod:`nav.surfacing`) turns the two legs' errors into estimates of the vehicle's
systematic velocity error and of the current (CP2 by default: alpha_1 = 45 deg, alpha_2 = 225 deg;
CP1: two random courses at least ``cp1_min_separation_deg`` apart and from opposite), and leg 3
(a random course) is dead-reckoned with and without the correction. Each run flies the mission
twice with the same random streams: leg 3 on the direct course from the corrected DR position to
the way-point, and on the current-compensating course of eq. 22-26 (seed 001 Table 3).

The vehicle's own systematic error is configurable: a compass bias (``sensors.compass.heading
.bias_deg``, default 5 deg: the autopilot holds the compass course, so the vehicle really swims
5 deg off it) and an odometry scale error (``sensors.odometry.speed.scale_factor``, default 0.1:
the odometry believes the vehicle 10 % faster than it swims). The current defaults to a uniform
0.3 m/s setting 20 deg (seed 001's alpha_c); ``--set current.kind=randomised`` gives seed 001's
randomised current and ``current.kind=gyre`` a spatially varying one.

In the physics world the vehicle drifts with the water whatever its course (``models/bauv``
check 5), so CP2's hull response is uniform (``correction.response_cos_coeffs = [1.0]``); the
kinematic replica (``paper-001/replica``) uses the paper's course-dependent rho.

Modules: :mod:`~tasks.missions.correction.scenario` (the experiment's options, the legs of a run),
:mod:`~tasks.missions.correction.run` (the DRNS beside the EKF, the leg guidance, a run's two
flights and their metrics), :mod:`~tasks.missions.correction.report` (``metrics.json`` and the
tables) and :mod:`~tasks.missions.correction.figures` (figures, the recording).
"""

from __future__ import annotations

from dataclasses import dataclass

from bauv_sim.errors import ConfigError
from tasks.closed_loop.experiment import MissionExperiment, check_current_covers
from tasks.core.registry import ReportContext, ReportSummary, register
from tasks.missions.correction.figures import (
    correction_figure,
    current_figure,
    record_correction,
)
from tasks.missions.correction.report import (
    CorrectionMetrics,
    CorrectionRunMetrics,
    along_track_table,
    report_correction,
)
from tasks.missions.correction.run import (
    EXTRA_COLUMNS,
    SPANS,
    CorrectionMission,
    CorrectionNavigation,
    CorrectionReport,
    CorrectionRunResult,
    LegGuidance,
    current_along_track,
    current_metrics,
    fly_run,
    leg3_metrics,
)
from tasks.missions.correction.scenario import (
    EN,
    METHODS,
    CorrectionConfig,
    CorrectionScenario,
    leg_courses,
    run_scenario,
)

__all__ = [
    "EN",
    "EXTRA_COLUMNS",
    "METHODS",
    "SPANS",
    "CorrectionConfig",
    "CorrectionExperiment",
    "CorrectionMetrics",
    "CorrectionMission",
    "CorrectionNavigation",
    "CorrectionReport",
    "CorrectionRunMetrics",
    "CorrectionRunResult",
    "CorrectionScenario",
    "LegGuidance",
    "along_track_table",
    "correction_figure",
    "current_along_track",
    "current_figure",
    "current_metrics",
    "fly_run",
    "leg3_metrics",
    "leg_courses",
    "record_correction",
    "report_correction",
    "run_scenario",
]


@dataclass(frozen=True)
class CorrectionExperiment(MissionExperiment):
    """Seed 001's procedures on the physical vehicle (two flights per run)."""

    scenario_type = CorrectionScenario
    metrics_type = CorrectionMetrics

    def flight(self, scenario: CorrectionScenario, seed: int, run: int):
        """The compensated flight of a run (:meth:`run_block` flies the direct one too)."""
        return CorrectionMission(course_law="compensated"), run_scenario(scenario, seed, run)

    def check(self, scenario: CorrectionScenario, n_runs: int) -> None:
        super().check(scenario, n_runs)
        # the legs are made per run: a gridded current covers every leg on any course
        st, c = scenario.start, scenario.correction
        reach = 3.0 * c.leg_length_m
        check_current_covers(
            scenario,
            [(st.east_m + sx * reach, st.north_m + sy * reach) for sx in (-1, 1) for sy in (-1, 1)],
            (c.depth_m,),
        )
        if scenario.sensors.use_usbl:
            raise ConfigError("sensors.use_usbl = true: seed 001's vehicle has no USBL")

    def run_block(self, scenario: CorrectionScenario, seed: int, runs: tuple[int, ...]):
        return [fly_run(scenario, seed, r) for r in runs]

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_correction(self, ctx)


register(
    CorrectionExperiment(
        name="mission/correction",
        summary="seed 001 on the physical BAUV: compass + odometry, CP2 from two surfacings, leg 3 "
        "corrected (0.3 m/s current)",
        preset={
            "start": {
                "east_m": 0.0,
                "north_m": 0.0,
                "depth_m": 3.0,
                "heading_deg": 45.0,
                "position_sigma_m": 0.0,
                "heading_sigma_deg": 3.0,
            },
            "current": {"kind": "uniform", "speed_m_s": 0.3, "direction_deg": 20.0},
            "sensors": {
                "use_usbl": False,
                "use_log": False,
                "compass": {"heading": {"bias_deg": 5.0}},
                "odometry": {"speed": {"scale_factor": 0.1}},
            },
            "navigation": {"initial_sigma_m": 2.5},
            "guidance": {
                "waypoints": [{"east_m": 0.0, "north_m": 100.0}],
                "hold_s": 5.0,
                "fixes_needed": 3,
                "max_leg_time_s": 400.0,
            },
            "timing": {"max_duration_s": 900.0},
        },
        default_runs=20,
    )
)
