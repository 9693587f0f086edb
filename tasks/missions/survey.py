"""``mission/survey``: the default mission and the README's main job.

A lawn-mower survey of 100 m x 300 m around a seabed USBL transceiver (all of it within 200 m, well
inside the 500 m USBL range) at 3 m depth, about 20 minutes at 1 m/s through a 0.25 m/s uniform
current setting 60 deg. Guidance steers on the EKF estimate (USBL every 5 s, depth, gated);
``--set navigation.steer_on=dr`` flies the same mission on dead reckoning alone for comparison.
"""

from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.scenario import mission_preset
from tasks.core.registry import register

WAYPOINTS = [
    {"east_m": 150.0, "north_m": -100.0},
    {"east_m": 150.0, "north_m": 0.0},
    {"east_m": -150.0, "north_m": 0.0},
    {"east_m": -150.0, "north_m": 100.0},
    {"east_m": 150.0, "north_m": 100.0},
]

register(
    MissionExperiment(
        name="mission/survey",
        summary="lawn-mower survey around a USBL transceiver, 18 min, 0.25 m/s current (EKF)",
        preset=mission_preset(
            [{**w, "depth_m": 3.0, "acceptance_radius_m": 10.0} for w in WAYPOINTS],
            start={"east_m": -150.0, "north_m": -100.0, "depth_m": 3.0, "heading_deg": 90.0},
            current={"kind": "uniform", "speed_m_s": 0.25, "direction_deg": 60.0},
            timing={"max_duration_s": 2400.0},
        ),
        default_runs=1,
    )
)
