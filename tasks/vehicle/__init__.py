"""Experiments on the vehicle itself: ``vehicle/autopilot`` (step responses). The model's
acceptance checks (``python -m tasks.vehicle.checks``) are a script, not a registered experiment.
Importing registers the experiments."""

from tasks.vehicle import autopilot

__all__ = ["autopilot"]
