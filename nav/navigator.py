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

**Current.** With ``estimate_current`` the EKF state carries the water current
(:class:`~nav.models.CurrentAwareMotion`): heading and speed through water move the vehicle
through the water, the estimated current moves the water, and position fixes correct both. Without
it the EKF is seed 000's three-state filter, whose covariance knows nothing of a current: in a
current its innovations grow beyond what it expects and a gate then rejects every fix.

**Lock-out.** A gate can reject a run of good fixes after the estimate has drifted; after
``max_consecutive_rejections`` rejections in a row of the same measurement model, the next one is
applied without the gate (the practice of IST's farol navigation).

The dead-reckoning track uses the same inputs without the current and is never corrected
(``reset_dr`` restarts it, e.g. at a GPS fix when a mission wants DR-with-resets).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from nav.ekf import MeasurementModel, UpdateInfo, gate_limit
from nav.errors import FilterDivergedError, NavInputError
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion, OnPosition

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
        x0: initial position estimate, shape (3,), m, world.
        P0: initial position covariance, shape (3, 3), m^2.
        motion: motion model (inputs heading, speed, depth change).
        history_s: how long states are kept for late measurements, s.
        gate_probability: chi-square gate probability, or ``None`` for no gate.
        current_sigma0_m_s: initial standard deviation of each current component, m/s, or
            ``None`` for seed 000's three-state filter without current.
        current_walk_m_s_per_sqrt_s: random-walk intensity of the current, (m/s)/sqrt(s).
        max_consecutive_rejections: lock-out guard (see the module docstring), or ``None``.
    """

    def __init__(
        self,
        t0_s: float,
        x0: Array,
        P0: Array,
        motion: CourseSpeedDepthMotion,
        history_s: float = 10.0,
        gate_probability: float | None = None,
        current_sigma0_m_s: float | None = None,
        current_walk_m_s_per_sqrt_s: float = 0.005,
        max_consecutive_rejections: int | None = None,
    ):
        self.dr_motion = motion
        self.gate_probability = gate_probability
        self.history_s = float(history_s)
        self.max_consecutive_rejections = max_consecutive_rejections
        self._rejections: dict[str, int] = {}
        x0 = np.asarray(x0, dtype=float).reshape(1, 3)
        P0 = np.asarray(P0, dtype=float).reshape(1, 3, 3)
        self._dr = x0.copy()
        if current_sigma0_m_s is None:
            self.motion = motion
            self.dim = 3
            xs, Ps = x0, P0
        else:
            self.motion = CurrentAwareMotion(motion, current_walk_m_s_per_sqrt_s)
            self.dim = 5
            xs = np.concatenate([x0, np.zeros((1, 2))], axis=1)
            Ps = np.zeros((1, 5, 5))
            Ps[:, :3, :3] = P0
            Ps[:, 3, 3] = Ps[:, 4, 4] = current_sigma0_m_s**2
        self._hist: deque[_Slot] = deque([_Slot(float(t0_s), xs.copy(), Ps.copy(), None, 0.0)])
        self.n_rejected = 0
        self.n_applied = 0

    # -- queries ------------------------------------------------------------------------------

    @property
    def t_s(self) -> float:
        """Time of the current estimate, s."""
        return self._hist[-1].t_s

    @property
    def estimate(self) -> Estimate:
        """The EKF position estimate now."""
        s = self._hist[-1]
        return Estimate(s.t_s, s.x[0, :3].copy(), s.P[0, :3, :3].copy())

    @property
    def current_estimate(self) -> tuple[Array, Array] | None:
        """Estimated current (east, north), m/s, and its 2x2 covariance, or ``None`` without a
        current state."""
        if self.dim < 5:
            return None
        s = self._hist[-1]
        return s.x[0, 3:5].copy(), s.P[0, 3:5, 3:5].copy()

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
        x, P = self._predict(last.x, last.P, u, dt)
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise FilterDivergedError(f"navigation estimate not finite at t = {t_s:g} s")
        self._hist.append(_Slot(float(t_s), x, P, u, dt))
        # DR: seed 000 eq. 8/16 with the same inputs, no current (scalar form of dr_motion.f)
        h, spd = u[0, 0], u[0, 1]
        self._dr = self._dr + np.array([[dt * spd * math.sin(h), dt * spd * math.cos(h), -u[0, 2]]])
        while len(self._hist) > 2 and self._hist[1].t_s < t_s - self.history_s:
            self._hist.popleft()

    def _predict(self, x: Array, P: Array, u: Array, dt: float) -> tuple[Array, Array]:
        """One prediction (eq. 17-18), exploiting the structure of the two motion models: the
        same numbers as :func:`nav.ekf.predict` with ``F`` and ``Q`` of the model (tested), in a
        fraction of the time for a single vehicle."""
        m = self.motion
        base = m.base if isinstance(m, CurrentAwareMotion) else m
        c, s = math.cos(u[0, 0]), math.sin(u[0, 0])
        spd = u[0, 1]
        sc2, ss2 = base.sigma_course_rad**2, base.sigma_speed_m_s**2
        g00, g01, g10, g11 = dt * spd * c, dt * s, -dt * spd * s, dt * c
        q00 = g00 * g00 * sc2 + g01 * g01 * ss2
        q01 = g00 * g10 * sc2 + g01 * g11 * ss2
        q11 = g10 * g10 * sc2 + g11 * g11 * ss2
        x_new = x.copy()
        x_new[0, 0] += dt * spd * s
        x_new[0, 1] += dt * spd * c
        x_new[0, 2] -= u[0, 2]
        P_new = P[0].copy()
        if isinstance(m, CurrentAwareMotion):
            x_new[0, :2] += dt * x[0, 3:5]
            P_new[:2, :] += dt * P_new[3:5, :]  # F P
            P_new[:, :2] += dt * P_new[:, 3:5]  # (F P) F^T
            q = m.sigma_current_walk_m_s_per_sqrt_s**2 * dt
            P_new[3, 3] += q
            P_new[4, 4] += q
        P_new[0, 0] += q00
        P_new[0, 1] += q01
        P_new[1, 0] += q01
        P_new[1, 1] += q11
        P_new[2, 2] += base.sigma_depth_change_m**2
        return x_new, P_new[None]

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
        if self.dim != 3:
            model = OnPosition(model, self.dim)
        key = type(getattr(model, "model", model)).__name__
        gate = self.gate_probability
        if (
            self.max_consecutive_rejections is not None
            and self._rejections.get(key, 0) >= self.max_consecutive_rejections
        ):
            gate = None
        x, P = slots[k].x, slots[k].P
        hx = model.h(x)
        x, P, info = _update_one(
            x, P, model.residual(z, hx), model.H(x), model.R(), model.active(x), gate
        )
        if info.rejected[0]:
            self.n_rejected += 1
            self._rejections[key] = self._rejections.get(key, 0) + 1
            return info
        self._rejections[key] = 0
        self.n_applied += 1
        slots[k].x, slots[k].P = x, P
        for j in range(k + 1, len(slots)):
            x, P = self._predict(x, P, slots[j].u, slots[j].dt_s)
            slots[j].x, slots[j].P = x, P
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise FilterDivergedError(f"navigation estimate not finite at t = {self.t_s:g} s")
        return info


def _update_one(
    x: Array,
    P: Array,
    y: Array,
    H: Array,
    R: Array,
    active: NDArray[np.bool_],
    gate_probability: float | None,
) -> tuple[Array, Array, UpdateInfo]:
    """The EKF update of :func:`nav.ekf.update` (eq. 19-23, Joseph form, inactive components
    removed, chi-square gate) for a single run, without the batch machinery (tested equal)."""
    idx = np.flatnonzero(active[0])
    if idx.size == 0:
        none = np.array([False])
        return x, P, UpdateInfo(np.array([np.nan]), np.array([0]), none, none)
    Ha, ya, Ra = H[0][idx], y[0][idx], R[np.ix_(idx, idx)]
    P0 = P[0]
    PHt = P0 @ Ha.T
    S = Ha @ PHt + Ra  # eq. 20
    S = 0.5 * (S + S.T)
    nis = float(ya @ np.linalg.solve(S, ya))
    if gate_probability is not None and nis > gate_limit(gate_probability, int(idx.size)):
        return (
            x,
            P,
            UpdateInfo(np.array([nis]), np.array([idx.size]), np.array([False]), np.array([True])),
        )
    K = np.linalg.solve(S, PHt.T).T  # eq. 21
    x_new = x + (K @ ya)[None]  # eq. 22
    I_KH = np.eye(P0.shape[0]) - K @ Ha
    P_new = I_KH @ P0 @ I_KH.T + K @ Ra @ K.T  # eq. 23, Joseph form
    P_new = 0.5 * (P_new + P_new.T)
    return (
        x_new,
        P_new[None],
        UpdateInfo(np.array([nis]), np.array([idx.size]), np.array([True]), np.array([False])),
    )
