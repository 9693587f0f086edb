"""The registered closed-loop missions on the physical vehicle: ``mission/survey``,
``mission/surfacing``, ``mission/short`` and ``mission/correction`` (seed 001 on the BAUV).
Importing registers them."""

from tasks.missions import correction, short, surfacing, survey

__all__ = ["correction", "short", "surfacing", "survey"]
