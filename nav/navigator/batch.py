"""The online navigator of :mod:`nav.navigator.online` over a batch of vehicles at once (issue 27).

:class:`BatchNavigator` is :class:`~nav.navigator.online.Navigator` for n runs that tick
together: seed 000's EKF driven by heading and speed through water (with the current in the
state or not) under :class:`nav.ekf.BatchEKF`, a short history of every run's states and inputs
so that a late measurement is applied at the tick it refers to and re-predicted to the present
(each run with its own time of validity), the chi-square gate, the lock-out after
``max_consecutive_rejections`` rejections of the same model in a row, and dead reckoning on the
same inputs. States ``(n, d)``, covariances ``(n, d, d)``.

Each run's numbers are those of a scalar :class:`Navigator` given the same inputs and
measurements, to rounding (the batched update inverts the innovation covariance from its
adjugate where the scalar one solves; tested run by run to 1e-9 in
``tests/nav/test_navigator_batch.py``, and the update itself against filterpy).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from nav.ekf import BatchEKF, MeasurementModel, gate_limit, update_with
from nav.errors import FilterDivergedError, NavInputError
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


class BatchNavigator:
    """EKF + DR of n runs with late measurements (module docstring).

    Args:
        n: runs.
        t0_s: start time, s.
        x0: initial position estimates, shape (n, 3), m, world.
        P0: initial position covariance, shape (3, 3) or (n, 3, 3), m^2.
        motion: motion model (inputs heading, speed, depth change; its sigmas).
        tick_s: the tick of :meth:`predict` (the history holds whole ticks), s.
        history_s: how long states are kept for late measurements, s.
        gate_probability: chi-square gate probability, or ``None`` for no gate.
        current_sigma0_m_s: initial standard deviation of each current component, m/s, or
            ``None`` for seed 000's three-state filter.
        current_walk_m_s_per_sqrt_s: random-walk intensity of the current, (m/s)/sqrt(s).
        max_consecutive_rejections: lock-out guard, or ``None``.
    """

    def __init__(
        self,
        n: int,
        t0_s: float,
        x0: Array,
        P0: Array,
        motion: CourseSpeedDepthMotion,
        tick_s: float,
        history_s: float = 10.0,
        gate_probability: float | None = None,
        current_sigma0_m_s: float | None = None,
        current_walk_m_s_per_sqrt_s: float = 0.005,
        max_consecutive_rejections: int | None = None,
    ):
        if n < 1:
            raise NavInputError(f"n = {n}: a batch needs at least one run")
        x0 = np.asarray(x0, dtype=float).reshape(n, 3)
        P0 = np.broadcast_to(np.asarray(P0, dtype=float), (n, 3, 3))
        if current_sigma0_m_s is None:
            nav_motion: CourseSpeedDepthMotion | CurrentAwareMotion = motion
            d = 3
        else:
            nav_motion = CurrentAwareMotion(motion, current_walk_m_s_per_sqrt_s)
            d = 5
        self.n, self.dim = n, d
        self.motion = motion
        self.ekf = BatchEKF(nav_motion)
        self._q_current = current_walk_m_s_per_sqrt_s**2
        self.current_components = nav_motion.current_components
        self.gate_probability = gate_probability
        self.max_consecutive_rejections = max_consecutive_rejections
        self.tick_s = float(tick_s)
        self.history_s = float(history_s)
        self.slots = max(2, math.ceil(history_s / tick_s) + 2)
        H = self.slots
        self._x = np.zeros((H, n, d))
        self._P = np.zeros((H, n, d, d))
        self._u = np.zeros((H, n, 3))
        self._t = np.full(H, -np.inf)
        self._dt = np.zeros(H)
        self._k = 0  # slot of the present
        self._x[0, :, :3] = x0
        self._P[0, :, :3, :3] = P0
        if current_sigma0_m_s is not None:
            self._P[0, :, 3, 3] = self._P[0, :, 4, 4] = current_sigma0_m_s**2
        self._t[0] = float(t0_s)
        self._count = 1
        self.dr_position = x0.copy()
        self._rejections: dict[str, NDArray[np.intp]] = {}
        self.n_rejected = np.zeros(n, dtype=np.intp)
        self.n_applied = np.zeros(n, dtype=np.intp)

    # -- queries ------------------------------------------------------------------------------

    @property
    def t_s(self) -> float:
        """Time of the current estimate, s."""
        return float(self._t[self._k])

    @property
    def x(self) -> Array:
        """The present states, shape (n, d) (a view: do not change)."""
        return self._x[self._k]

    @property
    def P(self) -> Array:
        """The present covariances, shape (n, d, d) (a view: do not change)."""
        return self._P[self._k]

    def current_estimate(self) -> Array | None:
        """Estimated current (east, north), m/s, shape (n, 2), or ``None``."""
        c = self.current_components
        return None if c is None else self.x[:, c].copy()

    # -- time update --------------------------------------------------------------------------

    def predict(
        self, t_s: float, heading_rad: Array, speed_m_s: Array, depth_change_m: Array | float = 0.0
    ) -> None:
        """Advance every run's EKF and DR to ``t_s`` with inputs held since the previous tick.

        Args:
            t_s: new time, s (> the current time).
            heading_rad: measured headings, rad clockwise from north, shape (n,).
            speed_m_s: measured speeds through water, m/s, shape (n,).
            depth_change_m: depth changes over the step, m (positive down), shape (n,).

        Raises:
            NavInputError: if ``t_s`` is not after the current time or an input is not finite.
            FilterDivergedError: if a prediction is not finite.
        """
        dt = t_s - self.t_s
        if not dt > 0:
            raise NavInputError(f"predict to t = {t_s} s: not after the current {self.t_s} s")
        u = np.empty((self.n, 3))
        u[:, 0], u[:, 1], u[:, 2] = heading_rad, speed_m_s, depth_change_m
        if not np.isfinite(u).all():
            bad = int(np.flatnonzero(~np.isfinite(u).all(axis=1))[0])
            raise NavInputError(f"predict at t = {t_s} s: non-finite input in batch row {bad}")
        x, P = self._predict(self.x, self.P, u, dt)
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise FilterDivergedError(f"navigation estimate not finite at t = {t_s:g} s")
        k = (self._k + 1) % self.slots
        self._x[k], self._P[k], self._u[k] = x, P, u
        self._t[k], self._dt[k] = float(t_s), dt
        self._k = k
        self._count += 1
        self.dr_position = self.dr_position + self.motion.increment(u, dt)

    def _predict(self, x: Array, P: Array, u: Array, dt: float) -> tuple[Array, Array]:
        """Eq. 17-18 of every run in the motion models' closed form (``F`` the identity, or the
        identity plus ``dt`` on the position-current blocks: ``F P F^T`` is a row and a column
        update), the algebra of their ``predict_one`` over a batch: the numbers of the scalar
        navigator's :class:`nav.ekf.SingleRunEKF` (and of :class:`nav.ekf.BatchEKF` to
        rounding, tested)."""
        _, Q = self.motion.increment_and_Q(u, dt)
        x_new = self.ekf.motion.f(x, u, dt)
        P_new = P.copy()
        if self.dim == 5:
            P_new[:, :2, :] += dt * P_new[:, 3:5, :]  # F P
            P_new[:, :, :2] += dt * P_new[:, :, 3:5]  # (F P) F^T
            P_new[:, 3, 3] += self._q_current * dt
            P_new[:, 4, 4] += self._q_current * dt
        P_new[:, :3, :3] += Q
        return x_new, P_new

    # -- measurement update -------------------------------------------------------------------

    def _gate(self, key: str, rows: NDArray[np.intp]) -> Mask:
        """Whether each of ``rows`` is gated now (not locked out)."""
        if self.gate_probability is None:
            return np.zeros(rows.size, dtype=bool)
        if self.max_consecutive_rejections is None:
            return np.ones(rows.size, dtype=bool)
        rej = self._rejections.setdefault(key, np.zeros(self.n, dtype=np.intp))
        return rej[rows] < self.max_consecutive_rejections

    def fuse(
        self,
        model: MeasurementModel,
        z: Array,
        present: Mask,
        t_valid_s: Array | None = None,
        key: str | None = None,
    ) -> tuple[Array, Mask, Mask]:
        """Apply each present run's measurement at the tick it refers to and re-predict to now
        (:meth:`nav.navigator.online.OnlineNavigator.update`, run by run).

        Args:
            model: the measurement model of every run (its arrays may have a leading run axis
                of n, as a per-run transceiver ``(n, 3)``: rows are taken for each group).
            z: measurements, shape (n, m); rows of absent runs may hold anything.
            present: runs that have a measurement, shape (n,).
            t_valid_s: times of validity, shape (n,), s (default: now).
            key: the lock-out's name for this kind of measurement (default: the model's type).

        Returns:
            ``(nis (n,) NaN where absent, applied (n,), rejected (n,))``.

        Raises:
            NavInputError: if a present measurement is not finite, in the future, or older than
                the kept history.
            FilterDivergedError: if a re-predicted estimate is not finite.
        """
        n = self.n
        z = np.asarray(z, dtype=float).reshape(n, -1)
        present = np.asarray(present, dtype=bool)
        nis_out = np.full(n, np.nan)
        applied_out = np.zeros(n, dtype=bool)
        rejected_out = np.zeros(n, dtype=bool)
        if not present.any():
            return nis_out, applied_out, rejected_out
        if not np.isfinite(z[present]).all():
            raise NavInputError("a present measurement is not finite")
        key = key or type(model).__name__
        held = min(self._count, self.slots)
        order = [(self._k - j) % self.slots for j in range(held)]  # newest first
        t_now = self.t_s
        tv = np.full(n, t_now) if t_valid_s is None else np.asarray(t_valid_s, dtype=float)
        if (tv[present] > t_now + 1e-9).any():
            raise NavInputError(f"a measurement is valid in the future (now {t_now} s)")
        # age of the slot each run's measurement refers to (0: now): the newer slots it skips
        ts = self._t[order]  # decreasing
        if t_valid_s is None:
            age = np.zeros(n, dtype=np.intp)
        else:
            age = (ts[None, :] > tv[:, None] + 1e-9).sum(axis=1)
        if (present & (age >= held)).any():
            raise NavInputError(
                f"a measurement is older than the navigation history (from "
                f"{self._t[order[-1]]:.3f} s); raise history_s"
            )
        # the scalar history keeps slots back to history_s before now, and one more
        for a in np.unique(age[present]):
            rows = np.flatnonzero(present & (age == a))
            s = order[a]
            gated = self._gate(key, rows)
            sub = _take_model(model, rows, n)
            x0, P0 = self._x[s, rows], self._P[s, rows]
            x1, P1, info = update_with(x0, P0, sub, z[rows], None, None)
            rejected = np.zeros(rows.size, dtype=bool)
            if self.gate_probability is not None:
                lim = np.array(
                    [gate_limit(self.gate_probability, int(d)) for d in np.maximum(info.dof, 1)]
                )
                rejected = gated & (info.dof > 0) & (info.nis > lim)
            ok = info.applied & ~rejected
            nis_out[rows] = info.nis
            rejected_out[rows] = rejected
            applied_out[rows] = ok
            if self.max_consecutive_rejections is not None:
                rej = self._rejections.setdefault(key, np.zeros(n, dtype=np.intp))
                rej[rows] = np.where(rejected, rej[rows] + 1, np.where(ok, 0, rej[rows]))
            self.n_rejected[rows] += rejected
            self.n_applied[rows] += ok
            r_ok = rows[ok]
            if r_ok.size == 0:
                continue
            x, P = x1[ok], P1[ok]
            self._x[s, r_ok], self._P[s, r_ok] = x, P
            for j in range(a - 1, -1, -1):  # re-predict to now with the stored inputs
                sj = order[j]
                x, P = self._predict(x, P, self._u[sj, r_ok], float(self._dt[sj]))
                self._x[sj, r_ok], self._P[sj, r_ok] = x, P
            if not (np.isfinite(x).all() and np.isfinite(P).all()):
                raise FilterDivergedError(f"navigation estimate not finite at t = {t_now:g} s")
        return nis_out, applied_out, rejected_out


def _take_model(model: MeasurementModel, rows: NDArray[np.intp], n: int) -> MeasurementModel:
    """``model`` with its per-run arrays (leading axis n, beyond the 1-D ones) cut to ``rows``."""
    import dataclasses

    if not dataclasses.is_dataclass(model):
        return model
    changes = {}
    for f in dataclasses.fields(model):
        v = getattr(model, f.name)
        if isinstance(v, np.ndarray) and v.ndim == 2 and v.shape[0] == n:
            changes[f.name] = v[rows]
    return dataclasses.replace(model, **changes) if changes else model
