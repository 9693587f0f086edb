"""Seed 003 (Naus & Piskur 2022): ``paper-003/test-1..3`` (a follower positioned relative to the
swarm leader on a square path: DR, GA1, GA2 and a range EKF). Importing registers them."""

from tasks.paper003 import square

__all__ = ["square"]
