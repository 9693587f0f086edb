"""``mission/short``: a two-leg, two-minute mission for tests and quick checks."""

from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.scenario import mission_preset
from tasks.core.registry import register

register(
    MissionExperiment(
        name="mission/short",
        summary="two legs near the transceiver in two minutes (tests, quick checks)",
        preset=mission_preset(
            [
                {"east_m": 0.0, "north_m": 50.0, "acceptance_radius_m": 8.0},
                {"east_m": 40.0, "north_m": 80.0, "acceptance_radius_m": 8.0},
            ],
            start={"east_m": 0.0, "north_m": -20.0, "depth_m": 3.0, "heading_deg": 0.0},
            current={"kind": "uniform", "speed_m_s": 0.2, "direction_deg": 90.0},
            timing={"max_duration_s": 240.0},
        ),
        default_runs=1,
    )
)
