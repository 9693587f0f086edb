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

The dead-reckoning track (:class:`nav.dead_reckoning.DeadReckoning`) uses the same inputs
without the current (or its own, :meth:`OnlineNavigator.advance`'s ``dr_input``: e.g. the DVL's
velocity over ground with :class:`nav.dvl.GroundVelocityMotion`) and is never corrected
(``reset_dr`` restarts it, e.g. at a GPS fix when a mission wants DR-with-resets).

**Measurements carry their model.** A :class:`Measurement` is a value, its time of validity and
its measurement model (:mod:`nav.models`: ``h``, ``H``, ``R``, ``residual``, ``active``), as a
Stone Soup detection carries its measurement model: :meth:`OnlineNavigator.fuse` applies any of
them (USBL or GPS fixes, depth, ranges to a known or broadcast position, bearings to beacons)
through the one update of :mod:`nav.ekf`, with no dispatch on what the device was. Which device
gives which measurement is the business of the code that reads the devices (the mission's
adapter), not of the navigator.

**Estimator.** :class:`OnlineNavigator` does the history, the late fixes, the gate, the lock-out
and the DR for any :class:`nav.ekf.Estimator` it is given (with the estimator's motion model);
:class:`Navigator` builds today's configuration in one call: seed 000's motion model, with the
current in the state or not, under :class:`nav.ekf.SingleRunEKF`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from nav.dead_reckoning import DeadReckoning
from nav.ekf import Estimator, MeasurementModel, SingleRunEKF, UpdateInfo
from nav.errors import FilterDivergedError, NavInputError
from nav.models import CourseSpeedDepthMotion, CurrentAwareMotion

Array = NDArray[np.float64]


class StepMotion(Protocol):
    """What the DR track needs from a motion model: one run's displacement over a step,
    ``increment_one(u (p,), dt_s) -> (3,)`` m, world (:class:`nav.models.CourseSpeedDepthMotion`,
    :class:`nav.dvl.GroundVelocityMotion`)."""

    def increment_one(self, u: Array, dt_s: float) -> Array: ...


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


@dataclass(frozen=True)
class Measurement:
    """A measurement with its model: what :meth:`OnlineNavigator.fuse` applies.

    Attributes:
        value: the measured value, shape (m,), in the units of ``model.h`` (e.g. USBL: range m,
            azimuth rad, elevation rad; depth: m).
        model: its measurement model (:class:`nav.ekf.MeasurementModel`, from :mod:`nav.models`):
            the predicted value ``h``, its Jacobian ``H``, the noise ``R``, the ``residual``
            (angles wrapped) and which components are ``active``.
        t_valid_s: its time of validity, s (``None``: now, the navigator's current time).
    """

    value: Array
    model: MeasurementModel
    t_valid_s: float | None = None


@dataclass
class _Slot:
    t_s: float
    x: Array  # (1, d) after the updates at t_s
    P: Array  # (1, d, d)
    u: Array | None  # input that led from the previous slot to this one, (1, p)
    dt_s: float


class OnlineNavigator:
    """EKF (any :class:`~nav.ekf.Estimator`) + DR for one vehicle, with delayed measurements
    applied at their time of validity (see the module docstring).

    The state starts with the position (east, north, up) (:mod:`nav.models`); the estimator's
    motion model takes the inputs ``(heading, speed through water, depth change)`` and says with
    ``current_components`` where a current is in the state (``None``: none).

    Args:
        estimator: the estimator, with its motion model (e.g. ``SingleRunEKF(motion)``).
        t0_s: start time, s.
        x0: initial state, shape (d,) (position in m, world, first).
        P0: initial covariance, shape (d, d).
        dr_motion: the motion model of the dead-reckoning track (its ``increment_one``).
        history_s: how long states are kept for late measurements, s.
        gate_probability: chi-square gate probability, or ``None`` for no gate.
        max_consecutive_rejections: lock-out guard (see the module docstring), or ``None``.
    """

    def __init__(
        self,
        estimator: Estimator,
        t0_s: float,
        x0: Array,
        P0: Array,
        dr_motion: StepMotion,
        history_s: float = 10.0,
        gate_probability: float | None = None,
        max_consecutive_rejections: int | None = None,
    ):
        self.estimator = estimator
        self.dr_motion = dr_motion
        self.gate_probability = gate_probability
        self.history_s = float(history_s)
        self.max_consecutive_rejections = max_consecutive_rejections
        self._rejections: dict[str, int] = {}
        xs = np.array(x0, dtype=float).reshape(1, -1)
        self.dim = xs.shape[1]
        Ps = np.array(P0, dtype=float).reshape(1, self.dim, self.dim)
        self._current = estimator.motion.current_components
        self._dr = DeadReckoning(xs[0, :3])
        self._hist: deque[_Slot] = deque([_Slot(float(t0_s), xs, Ps, None, 0.0)])
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
        c = self._current
        if c is None:
            return None
        s = self._hist[-1]
        return s.x[0, c].copy(), s.P[0, c, c].copy()

    @property
    def dr_position(self) -> Array:
        """The dead-reckoned position now, shape (3,), m, world."""
        return self._dr.position.copy()

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

        Raises:
            NavInputError: if ``t_s`` is not after the current time or an input is not finite.
            FilterDivergedError: if the prediction is not finite.
        """
        self._advance(t_s, np.array([[heading_rad, speed_m_s, depth_change_m]], dtype=float))

    def advance(self, t_s: float, u: Array, dr_input: Array | None = None) -> None:
        """Advance EKF and DR to ``t_s`` with any motion model's input held since the previous
        tick (:meth:`predict` is this with ``u = (heading, speed, depth change)``; a
        :class:`nav.dvl.GroundVelocityMotion` takes ``(v_east, v_north, depth change)``).

        Args:
            t_s: new time, s (> the current time).
            u: the estimator's motion input, shape (p,).
            dr_input: the DR motion model's input, shape (p',), or ``None`` (``u``).

        Raises:
            NavInputError: if ``t_s`` is not after the current time or an input is not finite.
            FilterDivergedError: if the prediction is not finite.
        """
        u2 = np.array(u, dtype=float).reshape(1, -1)
        du = None if dr_input is None else np.array(dr_input, dtype=float).reshape(-1)
        self._advance(t_s, u2, du)

    def _advance(self, t_s: float, u: Array, du: Array | None = None) -> None:
        """:meth:`advance` with ``u`` shape (1, p) and ``du`` shape (p',) (``None``: ``u[0]``)."""
        last = self._hist[-1]
        dt = t_s - last.t_s
        if not dt > 0:
            raise NavInputError(f"predict to t = {t_s} s: not after the current {last.t_s} s")
        for v in (u[0],) if du is None else (u[0], du):
            if not np.all(np.isfinite(v)):
                raise NavInputError(f"predict at t = {t_s} s: non-finite input {v.tolist()}")
        du = u[0] if du is None else du
        x, P = self.estimator.predict(last.x, last.P, u, dt)
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise FilterDivergedError(f"navigation estimate not finite at t = {t_s:g} s")
        self._hist.append(_Slot(float(t_s), x, P, u, dt))
        self._dr.advance(self.dr_motion.increment_one(du, dt))
        while len(self._hist) > 2 and self._hist[1].t_s < t_s - self.history_s:
            self._hist.popleft()

    def reset_dr(self, x: Array) -> None:
        """Restart the DR track from a position, shape (3,), m, world."""
        self._dr.reset(np.asarray(x, dtype=float).reshape(3))

    # -- measurement update -------------------------------------------------------------------

    def fuse(self, measurement: Measurement) -> UpdateInfo:
        """Apply a measurement with its own model at its time of validity (:meth:`update`).

        Args:
            measurement: value, model and time of validity.

        Returns:
            The update diagnostics (NIS, gate decision).

        Raises:
            NavInputError: if the measurement is older than the kept history, in the future or
                not finite.
            FilterDivergedError: if the re-predicted estimate is not finite.
        """
        return self.update(measurement.model, measurement.value, measurement.t_valid_s)

    def update(
        self, model: MeasurementModel, z: Array, t_valid_s: float | None = None
    ) -> UpdateInfo:
        """Apply a measurement at the tick it refers to and re-predict to now.

        Args:
            model: its measurement model (of the position, :mod:`nav.models`).
            z: the measurement, shape (m,).
            t_valid_s: its time of validity, s (default: now).

        Returns:
            The update diagnostics (NIS, gate decision).

        Raises:
            NavInputError: if the measurement is older than the kept history or not finite.
            FilterDivergedError: if the re-predicted estimate is not finite.
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
        key = type(model).__name__
        gate = self.gate_probability
        if (
            self.max_consecutive_rejections is not None
            and self._rejections.get(key, 0) >= self.max_consecutive_rejections
        ):
            gate = None
        x, P, info = self.estimator.update(slots[k].x, slots[k].P, model, z, None, gate)
        if info.rejected[0]:
            self.n_rejected += 1
            self._rejections[key] = self._rejections.get(key, 0) + 1
            return info
        self._rejections[key] = 0
        self.n_applied += 1
        slots[k].x, slots[k].P = x, P
        for j in range(k + 1, len(slots)):
            x, P = self.estimator.predict(x, P, slots[j].u, slots[j].dt_s)
            slots[j].x, slots[j].P = x, P
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            raise FilterDivergedError(f"navigation estimate not finite at t = {self.t_s:g} s")
        return info


class Navigator(OnlineNavigator):
    """Today's navigator in one call: seed 000's motion model driven by heading and speed
    through water, with the current in the state or not, under the single-run EKF, and DR on the
    same inputs without the current.

    Equivalent to ``OnlineNavigator(SingleRunEKF(m), t0_s, x0', P0', motion, history_s,
    gate_probability, max_consecutive_rejections)`` with ``m = motion`` and the position state, or
    with ``m = CurrentAwareMotion(motion, current_walk_m_s_per_sqrt_s)`` and the state extended by
    a zero current of variance ``current_sigma0_m_s**2`` per component.

    Args:
        t0_s: start time, s.
        x0: initial position estimate, shape (3,), m, world.
        P0: initial position covariance, shape (3, 3), m^2.
        motion: motion model (inputs heading, speed, depth change; its sigmas).
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
        x0 = np.asarray(x0, dtype=float).reshape(3)
        P0 = np.asarray(P0, dtype=float).reshape(3, 3)
        if current_sigma0_m_s is None:
            nav_motion: CourseSpeedDepthMotion | CurrentAwareMotion = motion
            xs, Ps = x0, P0
        else:
            nav_motion = CurrentAwareMotion(motion, current_walk_m_s_per_sqrt_s)
            xs = np.concatenate([x0, np.zeros(2)])
            Ps = np.zeros((5, 5))
            Ps[:3, :3] = P0
            Ps[3, 3] = Ps[4, 4] = current_sigma0_m_s**2
        super().__init__(
            SingleRunEKF(nav_motion),
            t0_s,
            xs,
            Ps,
            motion,
            history_s,
            gate_probability,
            max_consecutive_rejections,
        )
