"""DVL-aided terrain-relative navigation online: dead reckoning on the DVL's velocity and TRN
filters predicted with its displacement, updated at a fixed period with the soundings of a
bottom-lock ping.

At every DVL ping (time ``t_k``) the velocity over ground of the reference point (world, from
:func:`nav.dvl.velocity_world_from_dvl`; on water track the caller adds the current it knows),
held since the previous ping, gives the displacement ``d = v (t_k - t_{k-1})`` with covariance
``Q = ((t_k - t_{k-1}) sigma)^2 I`` (``sigma`` the bottom-track or the water-track sigma of
:class:`DvlAidedOptions`: the water track's covers the unknown current). ``d`` and ``Q`` advance
the DVL dead reckoning (:class:`nav.dead_reckoning.DeadReckoning`) and predict every filter
(:class:`nav.trn.ParticleTrn`, :class:`nav.trn.PointMassTrn`), in the order given. Every
``update_period_s`` an update is due: the caller gives the soundings of a bottom-lock ping
(:func:`nav.trn.soundings`) and every filter takes them (:meth:`DvlAidedTrn.update`), or it has
none (no lock, no ping) and the filters only predict. This is the loop of mbtrnav's
``TerrainNav`` (a motion update per navigation sample, a measurement update per sounding) with
the DVL as the motion source.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.dead_reckoning import DeadReckoning
from nav.errors import NavInputError
from nav.trn.map import TerrainMap
from nav.trn.options import TrnUpdate, check_gaussian
from nav.trn.particle import ParticleTrn
from nav.trn.point_mass import PointMassTrn
from nav.trn.soundings import Soundings

Array = NDArray[np.float64]


@dataclass(frozen=True)
class DvlAidedOptions:
    """Options of :class:`DvlAidedTrn`.

    Attributes:
        update_period_s: time between TRN updates, s, > 0.
        sigma_bottom_m_s: noise of each horizontal component of the bottom-track velocity the
            prediction assumes, m/s, > 0.
        sigma_water_m_s: the same on water track (or a held velocity), m/s, > 0: it covers the
            current the water track does not see.
        sounding_sigma_m: each sounding's depth sigma beside the map's own, m, > 0.
    """

    update_period_s: float
    sigma_bottom_m_s: float
    sigma_water_m_s: float
    sounding_sigma_m: float

    def __post_init__(self) -> None:
        for name in ("update_period_s", "sigma_bottom_m_s", "sigma_water_m_s", "sounding_sigma_m"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (
                isinstance(v, int | float | np.floating) and math.isfinite(v) and v > 0.0
            ):
                raise NavInputError(f"DvlAidedOptions.{name} = {v!r}: must be a finite number > 0")


class DvlAidedTrn:
    """DR on the DVL and TRN filters on one clock (module docstring).

    Args:
        options: periods and sigmas.
        t0_s: start time, s (the first update is due at ``t0_s + update_period_s``).
        x0_m: start position (east, north), shape (2,), m (the filters' own means start where
            the caller built them).
        P0_m2: its covariance, shape (2, 2), m^2.
        filters: the TRN filters, predicted and updated in this order.

    Attributes:
        dr: the dead reckoning on the DVL.
        filters: the filters.
    """

    def __init__(
        self,
        options: DvlAidedOptions,
        t0_s: float,
        x0_m: ArrayLike,
        P0_m2: ArrayLike,
        filters: Sequence[ParticleTrn | PointMassTrn],
    ):
        check_gaussian("x0_m", x0_m, "P0_m2", P0_m2)
        if not math.isfinite(t0_s):
            raise NavInputError(f"t0_s = {t0_s}: must be finite")
        self.options = options
        # the start as given (check_gaussian's symmetrised copy is for the filters' draws)
        self.dr = DeadReckoning(np.array(x0_m, dtype=float), np.array(P0_m2, dtype=float))
        self.filters = tuple(filters)
        self._t = float(t0_s)
        self._next = float(t0_s) + options.update_period_s
        self._q = np.zeros((2, 2))

    def advance(self, t_s: float, velocity_world_m_s: ArrayLike, bottom_lock: bool) -> Array | None:
        """Predict to a ping with the velocity held since the previous one.

        Args:
            t_s: the ping's time, s (not before the previous ping).
            velocity_world_m_s: velocity over ground of the reference point, world, shape (2,)
                or (3,) (only east and north are used), m/s.
            bottom_lock: whether it is a bottom-track velocity (else the water-track sigma).

        Returns:
            When an update is due at this ping: the prediction covariance accumulated since the
            previous due time, shape (2, 2), m^2 (then :meth:`update` with the ping's soundings,
            or nothing if it has none); ``None`` otherwise.

        Raises:
            NavInputError: a time before the previous ping, or a non-finite velocity.
        """
        dt = float(t_s) - self._t
        if not dt >= 0.0:
            raise NavInputError(f"DVL ping at t = {t_s} s: before the previous one ({self._t} s)")
        v = np.asarray(velocity_world_m_s, dtype=float)
        if v.shape not in ((2,), (3,)) or not np.all(np.isfinite(v)):
            raise NavInputError(
                f"velocity_world_m_s = {v.tolist()}: must be 2 or 3 finite numbers, m/s"
            )
        self._t = float(t_s)
        d = v[:2] * dt
        sigma = self.options.sigma_bottom_m_s if bottom_lock else self.options.sigma_water_m_s
        q = (dt * sigma) ** 2 * np.eye(2)
        self.dr.advance(d, q)
        for f in self.filters:
            f.predict(d, q)
        self._q = self._q + q
        if t_s + 1e-9 < self._next:
            return None
        self._next += self.options.update_period_s
        q_sum, self._q = self._q, np.zeros((2, 2))
        return q_sum

    def update(self, terrain_map: TerrainMap, soundings: Soundings) -> tuple[TrnUpdate, ...]:
        """Every filter takes a ping's soundings against the navigator's map (an update is due:
        :meth:`advance` said so).

        Returns:
            Each filter's diagnostics, in the filters' order.
        """
        sigma = self.options.sounding_sigma_m
        return tuple(f.update(terrain_map, soundings, sigma) for f in self.filters)
