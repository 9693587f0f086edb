"""The registered closed-loop missions on the physical vehicle: ``mission/survey``,
``mission/surfacing``, ``mission/short``, ``mission/correction`` (seed 001 on the BAUV),
``mission/swarm`` (seed 003: followers keeping station on a leader) and ``mission/seed004``
(seed 004: bearings to beacons, locally optimal control). Importing registers them."""

from tasks.missions import correction, seed004, short, surfacing, survey, swarm

__all__ = ["correction", "seed004", "short", "surfacing", "survey", "swarm"]
