"""The registered closed-loop missions on the physical vehicle: ``mission/survey``,
``mission/surfacing``, ``mission/short``, ``mission/correction`` (seed 001 on the BAUV) and
``mission/swarm`` (seed 003: followers keeping station on a leader). Importing registers them."""

from tasks.missions import correction, short, surfacing, survey, swarm

__all__ = ["correction", "short", "surfacing", "survey", "swarm"]
