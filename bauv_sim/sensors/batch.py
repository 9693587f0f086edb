"""Sensor errors of a batch of vehicles sampled online, drawn ahead in blocks of samples (issue 27).

:class:`~bauv_sim.sensors.errors.ErrorProcess` draws each run's streams by swapping its PCG64
state into one generator, a few microseconds per run and call: sampled one tick at a time for a
thousand runs, a compass costs milliseconds per tick. :class:`PrefetchedErrors` draws the error
terms of the next ``block`` samples at once (one swap per run and block) and adds them to the
true values as they come: ``m = (1 + scale_factor) x + e`` with ``e`` the process's value for
a true value of zero (bias, random walk, noise, outlier) and its dropouts. The streams, their
order and so the draws are those of the process sampled one at a time (a run's numbers do not
depend on the block length, the batch or the worker); where the bias is zero and there is no
random walk and no outliers the measurements are those of :meth:`ErrorProcess.apply` bit for
bit, otherwise to rounding (the terms are added in another order). Error models with a
reference angle (sector bias, deviation: terms that depend on the truth) are applied sample by
sample.

:class:`BatchUsbl` does the same for :class:`~bauv_sim.sensors.usbl.Usbl`'s three components and
its fix dropouts, then folds the direction past the zenith as the device does.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import fold_azimuth_elevation, range_azimuth_elevation
from bauv_sim.sensors.errors import ErrorProcess
from bauv_sim.sensors.usbl import Usbl

Array = NDArray[np.float64]


class PrefetchedErrors:
    """An error process of n runs sampled online at a fixed period, its terms drawn ahead.

    Args:
        process: the error process (its streams; it must not be used elsewhere).
        period_s: time between samples, s (for the random walk's steps).
        block: samples drawn at once.
    """

    def __init__(self, process: ErrorProcess, period_s: float, block: int = 256):
        self.process = process
        self.period_s = float(period_s)
        self.block = int(block)
        self._direct = process.model.needs_reference()
        self._e: Array | None = None
        self._ok: NDArray[np.bool_] | None = None
        self._j = 0

    def measure(
        self, true_value: Array, t_s: float, reference_rad: Array | None = None
    ) -> tuple[Array, NDArray[np.bool_]]:
        """One sample of every run.

        Args:
            true_value: true values, shape (n,), SI.
            t_s: the sample's time, s (samples every ``period_s``).
            reference_rad: reference angle of each run (models with a sector bias or
                deviation), shape (n,), rad.

        Returns:
            ``(measured (n,), produced (n,))``.
        """
        if self._direct:
            ref = None if reference_rad is None else reference_rad[:, None]
            v, ok = self.process.apply(true_value[:, None], np.array([t_s]), ref)
            return v[:, 0], ok[:, 0]
        if self._e is None or self._j >= self.block:
            t = np.asarray(t_s + self.period_s * np.arange(self.block), dtype=np.float64)
            self._e, self._ok = self.process.apply(np.zeros((len(true_value), self.block)), t)
            self._j = 0
        assert self._ok is not None
        j = self._j
        self._j += 1
        m = self.process.model
        x = true_value * (1.0 + m.scale_factor) if m.scale_factor else true_value * 1.0
        return x + self._e[:, j], self._ok[:, j]


class BatchUsbl:
    """USBL fixes of n vehicles sampled online every ``period_s`` through straight rays
    (:meth:`bauv_sim.sensors.usbl.Usbl.measure`), their errors drawn ahead (module docstring).

    Args:
        usbl: the device (its configuration, transceiver and streams; not used elsewhere).
        block: fixes drawn at once.
    """

    def __init__(self, usbl: Usbl, block: int = 64):
        self.usbl = usbl
        p = usbl.cfg.period_s
        self._errs = [PrefetchedErrors(e, p, block) for e in usbl._errs]
        self._block = int(block)
        self._lost: NDArray[np.bool_] | None = None
        self._j = 0

    def measure(
        self, t_s: float, transponder_world_m: Array
    ) -> tuple[Array, NDArray[np.bool_], Array]:
        """One fix of every run.

        Args:
            t_s: time of the reply, s.
            transponder_world_m: the transponders, shape (n, 3), m, world.

        Returns:
            ``(values (n, 3): r m, alpha rad in [0, 2 pi), beta rad; produced (n,);
            t_arrival_s (n,))``.
        """
        u = self.usbl
        cfg = u.cfg
        rae = range_azimuth_elevation(transponder_world_m - u.transceiver_world_m)
        produced = np.ones(len(rae), dtype=bool)
        comps = []
        for j, err in enumerate(self._errs):
            v, ok = err.measure(rae[:, j], t_s, rae[:, 1])
            comps.append(v)
            produced &= ok
        meas = np.stack(comps, axis=-1)
        meas[:, 0] = np.abs(meas[:, 0])
        meas[:, 1], meas[:, 2] = fold_azimuth_elevation(meas[:, 1], meas[:, 2])
        if u._drop is not None:
            if self._lost is None or self._j >= self._block:
                draws = u._drop.draw("random", self._block)
                self._lost = draws < cfg.dropout_probability
                self._j = 0
            produced &= ~self._lost[:, self._j]
            self._j += 1
        produced &= rae[:, 0] <= cfg.max_range_m
        produced &= rae[:, 2] >= np.radians(cfg.min_elevation_deg)
        t_arr = t_s + rae[:, 0] / cfg.sound_speed_m_s + cfg.processing_delay_s
        return meas, produced, t_arr
