"""Seed 001 (Praczyk): ``paper-001/replica`` (Tables 1-3 of the correction procedures in the
kinematic world). Importing registers it."""

from tasks.paper001 import replica

__all__ = ["replica"]
