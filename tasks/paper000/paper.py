"""Seed 000's published numbers (Naus & Nowak 2016, Tables 1-12): the minimum, maximum and mean
distance to the reference position, m, of EKF, DR and USBL, for single passages and for 100
passages of each test (USBL fix every 5, 20 and 100 s)."""

from __future__ import annotations

# The paper's tables: (min, max, mean) distance to the reference position, m, for EKF, DR, USBL.
PaperRow = tuple[float, float, float]


def _rows(ekf: PaperRow, dr: PaperRow, usbl: PaperRow) -> dict[str, PaperRow]:
    return {"EKF": ekf, "DR": dr, "USBL": usbl}


PAPER_TABLES: dict[str, dict[str, object]] = {
    "test-1": {
        "usbl_period_s": 5.0,
        "single": [
            ("Table 1", _rows((0.1, 6.6, 2.2), (0.7, 25.8, 15.9), (0.3, 75.2, 22.6))),
            ("Table 2", _rows((0.1, 6.4, 2.3), (0.1, 22.6, 11.8), (0.2, 81.6, 23.6))),
            ("Table 3", _rows((0.1, 5.3, 1.8), (0.2, 14.0, 4.7), (0.7, 86.1, 21.6))),
        ],
        "hundred": ("Table 4", _rows((0.6, 3.3, 2.2), (0.6, 20.1, 10.6), (1.3, 57.0, 23.4))),
    },
    "test-2": {
        "usbl_period_s": 20.0,
        "single": [
            ("Table 5", _rows((0.2, 7.3, 3.4), (0.7, 34.9, 10.9), (0.4, 68.0, 24.3))),
            ("Table 6", _rows((0.1, 7.5, 2.5), (0.1, 26.7, 9.7), (1.4, 64.3, 21.0))),
            ("Table 7", _rows((0.3, 6.1, 2.2), (0.3, 15.3, 6.2), (1.3, 72.6, 21.1))),
        ],
        "hundred": ("Table 8", _rows((0.7, 4.4, 2.9), (0.7, 19.1, 10.8), (1.3, 55.9, 22.7))),
    },
    "test-3": {
        "usbl_period_s": 100.0,
        "single": [
            ("Table 9", _rows((0.1, 11.6, 4.0), (0.3, 33.8, 22.0), (3.4, 37.5, 18.7))),
            ("Table 10", _rows((0.5, 11.4, 4.9), (0.5, 28.7, 12.0), (7.6, 20.0, 14.0))),
            ("Table 11", _rows((0.2, 9.1, 4.0), (0.2, 20.3, 8.9), (3.5, 22.0, 11.7))),
        ],
        "hundred": ("Table 12", _rows((0.6, 6.4, 4.4), (0.6, 18.9, 10.7), (4.8, 43.0, 20.5))),
    },
}
