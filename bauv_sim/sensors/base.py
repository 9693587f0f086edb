"""What every sensor shares: sample records, sampling grids and the period check."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.frames import R_from_roll_pitch_heading, world_from_body
from bauv_sim.truth import Truth


@dataclass(frozen=True)
class SensorSamples:
    """Measurements of one sensor over a batch of runs.

    Attributes:
        t_s: times of validity (the moment each measurement refers to), shape (k,), s.
        values: measured values, shape (n, k) for a scalar or (n, k, d), SI units; meaningless
            where ``produced`` is False.
        produced: whether the measurement exists, shape (n, k).
        t_arrival_s: when each measurement reaches the vehicle, shape (n, k), s (>= ``t_s``).
    """

    t_s: NDArray[np.float64]
    values: NDArray[np.float64]
    produced: NDArray[np.bool_]
    t_arrival_s: NDArray[np.float64]


def check_multiple(value_s: float, tick_s: float, field: str) -> int:
    """Check that a period is a whole multiple of the tick.

    Args:
        value_s: the period, s.
        tick_s: the tick, s.
        field: the scenario field name for the message.

    Returns:
        The ratio as an integer >= 1.

    Raises:
        ConfigError: naming the field if the period is not a whole multiple.
    """
    ratio = value_s / tick_s
    if not math.isfinite(ratio):
        raise ConfigError(
            f"{field} = {value_s:g}: {ratio:g} ticks of {tick_s:g} s is not a number of ticks"
        )
    m = round(ratio)
    if m < 1 or abs(ratio - m) > 1e-9 * max(1.0, ratio):
        raise ConfigError(
            f"{field} = {value_s:g}: must be a whole multiple (>= 1) of the tick {tick_s:g} s"
        )
    return m


def periodic_indices(n_ticks: int, every: int, first: int | None = None) -> NDArray[np.intp]:
    """Tick indices of a periodic sensor.

    Args:
        n_ticks: number of ticks on the grid (indices 0 .. n_ticks - 1).
        every: period in ticks, >= 1.
        first: first index (default ``every``: the first sample one period after the start).

    Returns:
        Indices, shape (k,).
    """
    start = every if first is None else first
    return np.arange(start, n_ticks, every, dtype=np.intp)


def broadcast_runs(a: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Broadcast a truth array with a run axis of 1 to ``n`` runs (no copy)."""
    if a.shape[0] == n:
        return a
    if a.shape[0] != 1:
        raise ValueError(f"truth has {a.shape[0]} runs, expected 1 or {n}")
    return np.broadcast_to(a, (n, *a.shape[1:]))


def point_world(truth: Truth, lever_arm_body_m: tuple[float, float, float]) -> NDArray[np.float64]:
    """World position of a point fixed on the vehicle.

    Args:
        truth: the truth samples, run axis n.
        lever_arm_body_m: the point relative to the vehicle reference point, m, body frame.

    Returns:
        Positions, shape (n, T, 3), m, world frame.
    """
    if not any(lever_arm_body_m):
        return truth.pos_world_m
    R = R_from_roll_pitch_heading(
        truth.roll_pitch_rad[..., 0], truth.roll_pitch_rad[..., 1], truth.heading_rad
    )
    return truth.pos_world_m + world_from_body(R, np.asarray(lever_arm_body_m, dtype=float))
