"""Seed 003's published numbers (Naus & Piskur 2022, Tables 1-3), as data.

Each table: method -> ((max, mean, std) of the single test sample, (max, mean, std) of the 100
test samples), the distance between the follower's reference position and its estimate, m.
"""

from __future__ import annotations

PaperCells = dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]]
PAPER_TABLES: dict[str, tuple[str, PaperCells]] = {
    "test-1": (
        "Table 1",
        {
            "DR": ((22.31, 14.26, 6.44), (23.70, 14.13, 6.34)),
            "GA1": ((8.39, 3.42, 2.39), (8.57, 3.48, 2.41)),
            "GA2": ((15.36, 7.90, 3.68), (15.36, 7.70, 3.63)),
        },
    ),
    "test-2": (
        "Table 2",
        {
            "DR": ((22.31, 14.25, 6.43), (23.71, 14.13, 6.34)),
            "GA1": ((9.98, 5.78, 3.43), (10.77, 6.57, 3.81)),
            "GA2": ((10.81, 8.12, 2.99), (10.89, 8.20, 2.89)),
        },
    ),
    "test-3": (
        "Table 3",
        {
            "DR": ((2.52, 1.56, 0.72), (3.79, 1.46, 0.78)),
            "GA1": ((0.91, 0.39, 0.21), (2.55, 0.73, 0.50)),
            "GA2": ((1.6, 0.69, 0.40), (3.19, 0.77, 0.52)),
        },
    ),
}
