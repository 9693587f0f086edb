"""``mission/surfacing``: way-points with GPS surfacings and no USBL.

A 150 m square flown at 3 m depth through a 0.25 m/s current; the vehicle surfaces at every
way-point for GPS fixes (ascend, hold until three fixes, dive) and dead-reckons between them: the
navigator's EKF takes only the GPS fixes and the depth.
"""

from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.scenario import mission_preset
from tasks.core.registry import register

register(
    MissionExperiment(
        name="mission/surfacing",
        summary="150 m square with a GPS surfacing at every way-point, no USBL, 0.25 m/s current",
        preset=mission_preset(
            [
                {"east_m": 150.0, "north_m": 0.0, "surface": True},
                {"east_m": 150.0, "north_m": 150.0, "surface": True},
                {"east_m": 0.0, "north_m": 150.0, "surface": True},
                {"east_m": 0.0, "north_m": 0.0, "surface": True},
            ],
            start={"east_m": 0.0, "north_m": 0.0, "depth_m": 3.0, "heading_deg": 90.0},
            current={"kind": "uniform", "speed_m_s": 0.25, "direction_deg": 330.0},
            sensors={"use_usbl": False},
            guidance={"hold_s": 10.0, "fixes_needed": 3},
            timing={"max_duration_s": 2400.0},
        ),
        default_runs=1,
    )
)
