"""Seed 004's published numbers (Miller, Miller & Miller 2019), as data: Table 1's J-bar, m^2, per
filter (``None``: a dash in the paper)."""

PAPER_ROW1: dict[str, float | None] = {"CMNF": 14.89, "UPMF": 14.80, "EKF": 14.93}
"""Table 1, first row (prediction by virtue of the system)."""
PAPER_ROW2: dict[str, float | None] = {"CMNF": 27.25, "UPMF": None, "EKF": None}
"""Table 1, second row (prediction from seabed sensing; dashes for UPMF and EKF)."""
