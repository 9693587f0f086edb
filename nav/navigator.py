"""Online navigation of one vehicle: the seed 000 EKF and a dead-reckoning track, in the loop.

At each navigation tick the estimate is predicted from the measured heading and speed (seed 000
eq. 16-18 with course = heading and speed = speed through water, so a current makes it drift).
Position measurements correct it (eq. 19-23): USBL range/azimuth/elevation, GPS fixes at the
surface, pressure depth. An optional chi-square gate on the normalised innovation rejects outliers.

**Latency.** A USBL fix is valid at the moment of the acoustic reply but reaches the vehicle
later (travel time, modem). The navigator keeps a short history of its states and inputs; a late
measurement is applied at the tick it refers to (the last tick at or before its time of validity)
and the estimate is re-predicted to the present with the stored inputs. A measurement older than
the history is refused (:class:`NavInputError`), never silently applied at the wrong time.

The dead-reckoning track uses the same inputs and is never corrected (``reset_dr`` restarts it,
e.g. at a GPS fix when a mission wants DR-with-resets).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nav.ekf import BatchEKF, MeasurementModel, UpdateInfo
from nav.errors import NavInputError
from nav.models import CourseSpeedDepthMotion

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Estimate:
    """A navigation estimate.

    Attributes:
        t_s: time, s.
        x: position (east, north, up), shape (3,), m, world.
        P: covariance, shape (3, 3), m^2.
    """

    t_s: float
    x: Array
    P: Array


@dataclass
class _Slot:
    t_s: float
    x: Array  # (1, 3) after the updates at t_s
    P: Array  # (1, 3, 3)
    u: Array | None  # input that led from the previous slot to this one, (1, 3)
    dt_s: float


class Navigator:
    """EKF + DR for one vehicle, with delayed measurements applied at their time of validity.

    Args:
        t0_s: start time, s.
        x0: initial estimate, shape (3,), m, world.
        P0: initial covariance, shape (3, 3), m^2.
        motion: motion model (inputs heading, speed, depth change).
        history_s: how long states are kept for late measurements, s.
        gate_probability: chi-square gate probability, or ``None`` for no gate.
    """

    def __init__(
        self,
        t0_s: float,
        x0: Array,
        P0: Array,
        motion: CourseSpeedDepthMotion,
        history_s: float = 10.0,
        gate_probability: float | None = None,
    ):
        self.motion = motion
        self.gate_probability = gate_probability
        self.history_s = float(history_s)
        x0 = np.asarray(x0, dtype=float).reshape(1, 3)
        P0 = np.asarray(P0, dtype=float).reshape(1, 3, 3)
        self._hist: deque[_Slot] = deque([_Slot(float(t0_s), x0.copy(), P0.copy(), None, 0.0)])
        self._dr = x0.copy()
        self.n_rejected = 0
        self.n_applied = 0

    # -- queries ------------------------------------------------------------------------------

    @property
    def t_s(self) -> float:
        """Time of the current estimate, s."""
        return self._hist[-1].t_s

    @property
    def estimate(self) -> Estimate:
        """The EKF estimate now."""
        s = self._hist[-1]
        return Estimate(s.t_s, s.x[0].copy(), s.P[0].copy())

    @property
    def dr_position(self) -> Array:
        """The dead-reckoned position now, shape (3,), m, world."""
        return self._dr[0].copy()

    # -- time update --------------------------------------------------------------------------

    def predict(
        self, t_s: float, heading_rad: float, speed_m_s: float, depth_change_m: float = 0.0
    ) -> None:
        """Advance EKF and DR to ``t_s`` with inputs held since the previous tick.

        Args:
            t_s: new time, s (> the current time).
            heading_rad: measured heading, rad clockwise from north.
            speed_m_s: measured speed through water, m/s.
            depth_change_m: depth change over the step, m (positive down).
        """
        last = self._hist[-1]
        dt = t_s - last.t_s
        if not dt > 0:
            raise NavInputError(f"predict to t = {t_s} s: not after the current {last.t_s} s")
        u = np.array([[heading_rad, speed_m_s, depth_change_m]], dtype=float)
        if not np.all(np.isfinite(u)):
            raise NavInputError(f"predict at t = {t_s} s: non-finite input {u[0].tolist()}")
        ekf = BatchEKF(last.x, last.P)
        ekf.predict(self.motion, u, dt)
        ekf.check(t_s)
        self._hist.append(_Slot(float(t_s), ekf.x, ekf.P, u, dt))
        self._dr = self.motion.f(self._dr, u, dt)
        while len(self._hist) > 2 and self._hist[1].t_s < t_s - self.history_s:
            self._hist.popleft()

    def reset_dr(self, x: Array) -> None:
        """Restart the DR track from a position, shape (3,)."""
        self._dr = np.asarray(x, dtype=float).reshape(1, 3).copy()

    # -- measurement update -------------------------------------------------------------------

    def update(
        self, model: MeasurementModel, z: Array, t_valid_s: float | None = None
    ) -> UpdateInfo:
        """Apply a measurement at the tick it refers to and re-predict to now.

        Args:
            model: its measurement model.
            z: the measurement, shape (m,).
            t_valid_s: its time of validity, s (default: now).

        Returns:
            The update diagnostics (NIS, gate decision).

        Raises:
            NavInputError: if the measurement is older than the kept history or not finite.
        """
        z = np.asarray(z, dtype=float).reshape(1, -1)
        if not np.all(np.isfinite(z)):
            raise NavInputError(f"measurement {z[0].tolist()} is not finite")
        t = self.t_s if t_valid_s is None else float(t_valid_s)
        if t > self.t_s + 1e-9:
            raise NavInputError(f"measurement valid at {t} s is in the future (now {self.t_s} s)")
        slots = self._hist
        k = len(slots) - 1
        while k > 0 and slots[k].t_s > t + 1e-9:
            k -= 1
        if slots[k].t_s > t + 1e-9:
            raise NavInputError(
                f"measurement valid at {t:.3f} s is older than the navigation history "
                f"(from {slots[0].t_s:.3f} s); raise history_s"
            )
        ekf = BatchEKF(slots[k].x, slots[k].P)
        info = ekf.update(model, z, gate_probability=self.gate_probability)
        if info.rejected[0]:
            self.n_rejected += 1
            return info
        self.n_applied += 1
        slots[k].x, slots[k].P = ekf.x, ekf.P
        for j in range(k + 1, len(slots)):
            ekf.predict(self.motion, slots[j].u, slots[j].dt_s)
            slots[j].x, slots[j].P = ekf.x, ekf.P
        ekf.check(self.t_s)
        return info
