"""Seed 001's published numbers (Praczyk, Tables 1-3): the DR error at the end of leg 3 (mean and
largest over missions, m) and the course deviation (deg) without correction and with CP1 and CP2,
for each ``beta`` of the grid."""

from __future__ import annotations

import numpy as np

PAPER_COLUMNS = ((0.1, 0.1), (0.1, 0.5), (0.3, 0.1), (0.3, 0.5))
PAPER: dict[str, dict[tuple[str, float | None], tuple[float, ...]]] = {
    "table1": {
        ("nocp", None): (12.84, 47.96, 31.1, 43.19),
        ("cp1", 5.0): (2.58, 10.9, 2.45, 11.4),
        ("cp2", 5.0): (1.17, 4.68, 0.93, 4.42),
        ("cp1", 20.0): (3.39, 8.33, 2.51, 10.6),
        ("cp2", 20.0): (1.21, 4.57, 1.01, 5.4),
    },
    "table2": {
        ("nocp", None): (18.83, 58.7, 38.61, 74.92),
        ("cp1", 5.0): (6.07, 35.64, 15.69, 28.69),
        ("cp2", 5.0): (2.74, 11.57, 1.87, 10.92),
        ("cp1", 20.0): (15.89, 19.51, 8.77, 43.12),
        ("cp2", 20.0): (2.24, 11.04, 2.49, 9.46),
    },
    "table3": {
        ("nocp", None): (4.77, 13.29, 4.68, 16.52),
        ("cp1", 5.0): (0.73, 2.92, 0.65, 3.45),
        ("cp2", 5.0): (0.46, 2.31, 0.25, 2.4),
        ("cp1", 20.0): (0.99, 2.7, 0.63, 4.04),
        ("cp2", 20.0): (0.48, 3.34, 0.29, 2.2),
    },
}


def paper_value(
    table: str, method: str, beta_deg: float | None, vg: float, vc: float
) -> float | None:
    """The paper's value for a cell, or ``None`` where the paper has none."""
    key = (method, None if method == "nocp" else beta_deg)
    try:
        col = next(i for i, c in enumerate(PAPER_COLUMNS) if np.allclose(c, (vg, vc)))
        return PAPER[table][key][col]
    except (StopIteration, KeyError):
        return None
