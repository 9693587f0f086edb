"""Compatibility: seed 001's DRNS lives in :mod:`nav.surfacing.drns` (import it from
:mod:`nav.surfacing`); this module only keeps the old import path of code not yet moved working."""

from nav.surfacing.drns import CorrectedDeadReckoning, Leg, Procedure

__all__ = ["CorrectedDeadReckoning", "Leg", "Procedure"]
