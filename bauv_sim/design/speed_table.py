"""The BAUV's speed table: steady speed through water versus tail-beat frequency.

The table is a design-time product of the model: :func:`measure_speed_table` swims the vehicle
straight and level in still water at each of :data:`SPEED_TABLE_FREQUENCIES_HZ` (one run, each
frequency settling from the previous one) and :func:`write_speed_table` writes the result to
``models/bauv/speed_table.csv`` (``python models/bauv/tools/checks.py cruise`` does both and
rewrites the model README's tables). At run time :func:`load_speed_table` reads it as a
:class:`SpeedTable`: the speed feed-forward of the autopilot and the odometry's frequency-to-speed
law.
"""

from __future__ import annotations

import csv
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import manoeuvres
from bauv_sim.errors import ConfigError
from bauv_sim.hull import MODEL_DIR

SPEED_TABLE_CSV = MODEL_DIR / "speed_table.csv"
"""The model's speed table."""

SPEED_TABLE_COLUMNS: Sequence[str] = ("frequency_hz", "speed_m_s", "power_w", "strouhal")
"""Columns of the CSV file, in order."""

SPEED_TABLE_FREQUENCIES_HZ = (
    *(0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0),
    *(1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0),
)
"""Tail-beat frequencies of the speed table, Hz (3 Hz is the motor's commanded limit): every
0.1 Hz up to 1 Hz, where the vehicle cruises and the odometry interpolates, then every 0.25 Hz."""

LEVEL_FIN_FRACTION = 0.9
"""A straight swim is level while the depth hold's mean fin angle stays below this fraction of its
limit (:class:`bauv_sim.manoeuvres.DepthHold`)."""

LEVEL_DEPTH_CHANGE_M = 0.25
"""... and the depth changes by less than this over the measured window, m."""


@dataclass(frozen=True)
class SpeedTable:
    """Self-propelled straight-swim calibration: steady speed through water versus tail-beat
    frequency (measured by :func:`measure_speed_table`, read by :func:`load_speed_table`).

    Attributes:
        frequency_hz: tail-beat frequencies, increasing, shape (n,), Hz.
        speed_m_s: steady speed through water at each frequency, shape (n,), m/s.
        power_w: mean motor power at each frequency, shape (n,), W.
        strouhal: Strouhal number f A / U at each frequency, shape (n,).
    """

    frequency_hz: NDArray[np.float64]
    speed_m_s: NDArray[np.float64]
    power_w: NDArray[np.float64]
    strouhal: NDArray[np.float64]

    def speed_at(self, frequency_hz: ArrayLike) -> NDArray[np.float64]:
        """Steady speed through water (m/s) at given tail-beat frequencies (Hz), by linear
        interpolation (0 at 0 Hz; clamped at the last row)."""
        f = np.concatenate([[0.0], self.frequency_hz])
        u = np.concatenate([[0.0], self.speed_m_s])
        return np.interp(np.asarray(frequency_hz, dtype=float), f, u)

    @property
    def max_speed_m_s(self) -> float:
        """Largest steady speed in the table, m/s."""
        return float(np.max(self.speed_m_s))

    def frequency_for(self, speed_m_s: ArrayLike) -> NDArray[np.float64]:
        """Tail-beat frequency (Hz) that gives a steady speed through water (m/s): the inverse of
        :meth:`speed_at` on the rows up to the fastest one (beyond it a higher frequency no longer
        makes the vehicle faster); larger speeds are clamped to that row."""
        k = int(np.argmax(self.speed_m_s)) + 1
        f = np.concatenate([[0.0], self.frequency_hz[:k]])
        u = np.concatenate([[0.0], self.speed_m_s[:k]])
        if np.any(np.diff(u) <= 0):
            raise ConfigError("speed table: speed must increase with frequency up to its maximum")
        return np.interp(np.asarray(speed_m_s, dtype=float), u, f)


def load_speed_table(path: str | Path = SPEED_TABLE_CSV) -> SpeedTable:
    """Read a speed table written by :func:`write_speed_table`.

    Args:
        path: CSV file; the model's ``models/bauv/speed_table.csv`` by default.

    Returns:
        The :class:`SpeedTable`.

    Raises:
        ConfigError: if the file is missing or malformed.
    """
    p = Path(path)
    try:
        with p.open() as fh:
            rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    except FileNotFoundError:
        raise ConfigError(
            f"speed table {str(p)!r}: not found (run python models/bauv/tools/checks.py)"
        ) from None
    try:
        cols = {c: np.array([float(r[c]) for r in rows]) for c in SPEED_TABLE_COLUMNS}
    except (KeyError, ValueError) as exc:
        raise ConfigError(f"speed table {str(p)!r}: bad column or value ({exc})") from None
    if cols["frequency_hz"].size < 2 or np.any(np.diff(cols["frequency_hz"]) <= 0):
        raise ConfigError(f"speed table {str(p)!r}: need >= 2 rows with increasing frequency")
    return SpeedTable(**cols)


def is_level(swim: manoeuvres.StraightSwimResult) -> bool:
    """Whether a straight swim was held level by the lateral fins: their mean angle below
    :data:`LEVEL_FIN_FRACTION` of the depth hold's limit and the depth change over the window
    below :data:`LEVEL_DEPTH_CHANGE_M`."""
    limit = manoeuvres.DepthHold(0.0).limit_rad
    return (
        abs(swim.mean_fin_rad) < LEVEL_FIN_FRACTION * limit
        and abs(swim.depth_change_m) < LEVEL_DEPTH_CHANGE_M
    )


def measure_speed_table(
    settle_s: float = 30.0,
    measure_s: float = 20.0,
    frequencies_hz: Sequence[float] = SPEED_TABLE_FREQUENCIES_HZ,
) -> list[manoeuvres.StraightSwimResult]:
    """Measure the speed table: straight swims at increasing tail-beat frequencies, one after the
    other in one run of the open-water scene (:func:`bauv_sim.manoeuvres.open_water_scene`, at
    rest at 20 m depth in still water, the lateral fins holding the depth), up to the first swim
    that the fins cannot hold level (:func:`is_level`): the vehicle pitches up as it swims faster
    (``models/bauv/README.md``, "Speed table and cruise"), and beyond that swim the speed is not
    that of a straight and level swim.

    Args:
        settle_s: settling time per frequency, s.
        measure_s: measured window per frequency, s.
        frequencies_hz: increasing tail-beat frequencies, Hz.

    Returns:
        One :class:`~bauv_sim.manoeuvres.StraightSwimResult` per frequency held level, in order.
    """
    if any(b <= a for a, b in itertools.pairwise(frequencies_hz)):
        raise ConfigError(f"frequencies = {list(frequencies_hz)}: must increase")
    physics = manoeuvres.open_water_scene()
    out = []
    for f in frequencies_hz:
        swim = manoeuvres.straight_swim(physics, f, settle_s, measure_s)
        if not is_level(swim):
            break
        out.append(swim)
    return out


def write_speed_table(
    swims: Sequence[manoeuvres.StraightSwimResult], path: str | Path = SPEED_TABLE_CSV
) -> None:
    """Write measured straight swims as a speed table CSV (read by :func:`load_speed_table`).

    Args:
        swims: from :func:`measure_speed_table`, increasing frequencies.
        path: CSV file; the model's ``models/bauv/speed_table.csv`` by default.
    """
    with Path(path).open("w", newline="") as fh:
        fh.write(
            "# BAUV self-propelled straight swim, still water, depth held by the lateral fins;"
            " written by models/bauv/tools/checks.py\n"
        )
        w = csv.writer(fh)
        w.writerow(SPEED_TABLE_COLUMNS)
        for r in swims:
            w.writerow(
                [
                    f"{r.frequency_hz:.4g}",
                    f"{r.speed_through_water_m_s:.4f}",
                    f"{r.mean_motor_power_w:.3f}",
                    f"{r.strouhal:.4f}",
                ]
            )
