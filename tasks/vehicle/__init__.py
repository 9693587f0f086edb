"""Experiments on the vehicle itself: ``vehicle/autopilot`` (step responses). The tooling that
measures the model and rewrites its files (acceptance checks, hydrodynamics checks, timestep
presets) is not an experiment and not in the installed package: ``models/bauv/tools/``.
Importing registers the experiments."""

from tasks.vehicle import autopilot

__all__ = ["autopilot"]
