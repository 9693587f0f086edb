"""A vehicle's clock: offset and drift against true time, and the jitter of its timestamps.

True time ``t`` is the simulation's. A clock reads

    local(t) = t + offset(t),    offset(t) = offset0 + drift * t

(offset: "local minus true", s; drift: s/s, configured in parts per million) and stamps an event
with ``local(t)`` plus a zero-mean Gaussian jitter of standard deviation ``jitter_s`` drawn per
event (:class:`~bauv_sim.acoustics.network.AcousticNetwork` draws it). A linear clock has an exact
inverse, ``true_of_local(T) = (T - offset0) / (1 + drift)``: the true instant at which the clock
reads ``T`` (when a modem transmits at a scheduled local time).

Typical oscillators (fractional frequency error, i.e. drift): a temperature-compensated crystal
(TCXO) about 1 ppm (1 ms of offset per 1000 s); an oven-controlled crystal (OCXO) about 1e-2 ppm;
a chip-scale atomic clock (CSAC, Microsemi SA.45s: 5e-11 = 5e-5 ppm aging-limited, about 1e-4
ppm over a mission) about 1e-4 ppm. One-way-travel-time ranging between vehicles relies on
clocks synchronised before the dive and drifting little (Eustice, Whitcomb, Singh & Grund,
"Experimental results in synchronous-clock one-way-travel-time acoustic navigation for
autonomous underwater vehicles", ICRA 2007; Webster, Eustice, Singh & Whitcomb, "Advances in
single-beacon one-way-travel-time acoustic navigation for underwater vehicles", IJRR 31(8), 2012:
a residual offset of 1 ms is 1.5 m of range bias at 1500 m/s).

Per-run draws: ``offset0 = offset_s + offset_sigma_s * z1`` and ``drift = (drift_ppm +
drift_sigma_ppm * z2) * 1e-6`` with ``(z1, z2)`` standard normal from the stream ``("clock",
<vehicle>)`` of each run (:func:`draw_clocks`), so a vehicle's clock does not depend on the other
vehicles or on which device reads it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config

Array = NDArray[np.float64]

PPM = 1e-6
"""One part per million, s/s."""


class ClockConfig(Config):
    """A clock (defaults: a perfect clock, reading true time)."""

    offset_s: float = Field(0.0, description="offset at t = 0 (local minus true), s")
    drift_ppm: float = Field(
        0.0, gt=-1e5, lt=1e5, description="drift (rate error), ppm (1 ppm = 1e-6 s/s)"
    )
    offset_sigma_s: float = Field(0.0, ge=0, description="per-run spread of the offset, s")
    drift_sigma_ppm: float = Field(0.0, ge=0, description="per-run spread of the drift, ppm")
    jitter_s: float = Field(0.0, ge=0, description="timestamp noise per event (sd), s")

    @property
    def random(self) -> bool:
        """Whether the clock differs between runs."""
        return self.offset_sigma_s > 0 or self.drift_sigma_ppm > 0


@dataclass(frozen=True)
class Clock:
    """A linear clock, batched over runs (see the module docstring).

    Attributes:
        offset0_s: offset at true time 0 (local minus true), shape (n,) or scalar, s.
        drift: rate error, shape (n,) or scalar, s/s (dimensionless).
        jitter_s: standard deviation of the timestamp noise per event, s.
    """

    offset0_s: Array
    drift: Array
    jitter_s: float = 0.0

    def offset(self, t_s: ArrayLike) -> Array:
        """``offset(t) = offset0 + drift * t``, s; ``t_s`` broadcasts against the run axis
        (shape (n, ...) with the clock's (n,) on the first axis, or scalars)."""
        t = np.asarray(t_s, dtype=float)
        return _col(self.offset0_s, t) + _col(self.drift, t) * t

    def local(self, t_s: ArrayLike) -> Array:
        """The clock's reading at true time ``t_s``: ``t + offset(t)``, s."""
        t = np.asarray(t_s, dtype=float)
        return t + self.offset(t)

    def true_of_local(self, local_s: ArrayLike) -> Array:
        """The true time at which the clock reads ``local_s``: ``(T - offset0) / (1 + drift)``,
        the exact inverse of :meth:`local`, s."""
        T = np.asarray(local_s, dtype=float)
        return (T - _col(self.offset0_s, T)) / (1.0 + _col(self.drift, T))


def _col(a: Array, like: Array) -> Array:
    """A per-run array (n,) shaped to broadcast over ``like`` (n, ...); scalars pass."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 0 or like.ndim <= 1:
        return a
    return a.reshape(a.shape + (1,) * (like.ndim - 1))


def draw_clocks(cfg: ClockConfig, seed: int, runs: tuple[int, ...], vehicle: str) -> Clock:
    """The clock of one vehicle in each run (module docstring: per-run draws).

    Args:
        cfg: the clock's configuration.
        seed: batch seed.
        runs: run indices (n,).
        vehicle: the vehicle's name (its stream ``("clock", vehicle)``).

    Returns:
        A :class:`Clock` with ``offset0_s`` and ``drift`` of shape (n,).
    """
    n = len(runs)
    offset0 = np.full(n, float(cfg.offset_s))
    drift = np.full(n, float(cfg.drift_ppm) * PPM)
    if cfg.random:
        z = rng_mod.RunStreams(seed, runs, "clock", vehicle).draw("standard_normal", 2)
        offset0 = offset0 + cfg.offset_sigma_s * z[:, 0]
        drift = (cfg.drift_ppm + cfg.drift_sigma_ppm * z[:, 1]) * PPM
    return Clock(offset0, drift, float(cfg.jitter_s))
