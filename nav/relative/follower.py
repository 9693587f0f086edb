"""One follower's online navigation relative to the leader (seed 003): dead reckoning (eq. 1,
5-6) through :class:`nav.dead_reckoning.DeadReckoning` and, at each range, GA1, GA2
(:func:`nav.relative.ga_fix`) or the range EKF (:mod:`nav.ekf`).

Positions are (east, north) in m, courses in rad clockwise from north.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.dead_reckoning import DeadReckoning
from nav.ekf import SingleRunEKF, update_one
from nav.errors import NavInputError
from nav.relative.adjustment import GaOptions, ga_fix, hdop
from nav.relative.motion import CourseSpeedMotion, dr_increment, dr_increment_covariance
from nav.relative.ranging import RangeMeasurement

Array = NDArray[np.float64]
FollowerMethod = Literal["dr", "ga1", "ga2", "ekf"]
FOLLOWER_METHODS: tuple[str, ...] = ("dr", "ga1", "ga2", "ekf")


@dataclass(frozen=True)
class FixOutcome:
    """What one range did to a follower's navigation.

    Attributes:
        accepted: whether the estimate was corrected.
        reason: ``"ok"`` or why not (``"no range"``, ``"range below minimum"``, ``"gate"``,
            ``"dr"`` for the DR method, which ignores ranges).
        position: the estimate after the range, shape (2,), m.
        hdop: eq. 7-8 at the estimate (``inf`` if singular; 0 when not computed).
        criterion: ``V^T P V`` of the adjustment (GA) or the NIS (EKF); 0 otherwise.
    """

    accepted: bool
    reason: str
    position: Array
    hdop: float
    criterion: float


@dataclass
class FollowerNavigator:
    """One follower's online navigation relative to the leader (seed 003): DR (eq. 1, 5-6) and,
    at each range, GA1, GA2 or the range EKF; ``"dr"`` ignores ranges.

    Args:
        method: ``"dr"``, ``"ga1"``, ``"ga2"`` or ``"ekf"``.
        position0: initial position, shape (2,), m (east, north).
        sigma_course_rad: sigma_C of eq. 5, rad.
        sigma_speed_m_s: sigma_S of eq. 5, m/s.
        options: GA readings and guards (``restart``, ``sigma_range_m`` also used by the EKF).
        initial_cov: initial covariance, shape (2, 2), m^2 (default zero: the start is known).
        gate_probability: the EKF's chi-square gate, or ``None``.
    """

    method: FollowerMethod
    position0: ArrayLike
    sigma_course_rad: float
    sigma_speed_m_s: float
    options: GaOptions = field(default_factory=GaOptions)
    initial_cov: ArrayLike | None = None
    gate_probability: float | None = None

    def __post_init__(self) -> None:
        if self.method not in FOLLOWER_METHODS:
            raise NavInputError(f"method must be one of {FOLLOWER_METHODS}, not {self.method!r}")
        p0 = np.array(self.position0, dtype=float).reshape(2)
        P0 = np.zeros((2, 2)) if self.initial_cov is None else np.array(self.initial_cov, float)
        self._motion = CourseSpeedMotion(self.sigma_course_rad, self.sigma_speed_m_s)
        self._ekf = SingleRunEKF(self._motion)
        self._dr = DeadReckoning(p0, P0)  # the pure DR track and its covariance
        self._seg_start = p0.copy()  # X_F(k): start of the DR segment since the last fix
        # X_DR(k+n), the segment's dead-reckoned end, and C_DR(k+n) since the last fix
        self._seg = DeadReckoning(p0, np.zeros((2, 2)))
        # the method's estimate and its covariance (DR from the last fix for GA)
        self._est = DeadReckoning(p0, P0)

    @property
    def position(self) -> Array:
        """The method's current estimate, shape (2,), m."""
        return self._est.position.copy()

    @property
    def covariance(self) -> Array:
        """The method's stated covariance, shape (2, 2), m^2 (for GA: the DR covariance since
        the last fix added to the fix's stated covariance)."""
        return self._est.covariance.copy()

    @property
    def dr_position(self) -> Array:
        """The pure dead-reckoned track, shape (2,), m."""
        return self._dr.position.copy()

    def advance(self, course_rad: float, speed_m_s: float, dt_s: float) -> None:
        """One DR step with the measured course and speed (eq. 1, 5).

        Args:
            course_rad: measured course, rad.
            speed_m_s: measured speed (through water, the log), m/s.
            dt_s: step, s.
        """
        c = np.array([course_rad], dtype=float)
        s = np.array([speed_m_s], dtype=float)
        step = dr_increment(c, s, dt_s)[0]
        q = dr_increment_covariance(c, s, dt_s, self.sigma_course_rad, self.sigma_speed_m_s)[0]
        self._dr.advance(step, q)
        self._seg.advance(step, q)
        est = self._est
        if self.method == "ekf":
            x, P = self._ekf.predict(
                est.position[None], est.covariance[None], np.array([[course_rad, speed_m_s]]), dt_s
            )
            est.reset(x[0], P[0])
        elif self.method == "dr":
            est.reset(self._dr.position, self._dr.covariance)
        else:
            est.advance(step, q)

    def fix(
        self, leader_xy: ArrayLike, range_m: float | None, leader_cov: ArrayLike | None = None
    ) -> FixOutcome:
        """Use one range to the leader's broadcast position.

        Args:
            leader_xy: the leader position sent with the range, shape (2,), m.
            range_m: the measured range, m, or ``None`` when none arrived.
            leader_cov: the leader's stated covariance, shape (2, 2), m^2 (EKF only).

        Returns:
            What happened; the estimate is unchanged unless ``accepted``.
        """
        if self.method == "dr":
            return FixOutcome(False, "dr", self.position, 0.0, 0.0)
        lead = np.asarray(leader_xy, dtype=float).reshape(2)
        if range_m is None or not np.isfinite(range_m) or not np.isfinite(lead).all():
            return FixOutcome(False, "no range", self.position, 0.0, 0.0)
        if range_m < self.options.min_range_m:
            return FixOutcome(False, "range below minimum", self.position, 0.0, 0.0)
        if self.method == "ekf":
            model = RangeMeasurement(
                lead[None],
                self.options.sigma_range_m,
                None if leader_cov is None else np.asarray(leader_cov, float)[None],
            )
            x, P = self._est.position[None], self._est.covariance[None]
            hx = model.h(x)
            y = model.residual(np.array([[range_m]]), hx)
            x2, P2, info = update_one(
                x, P, y, model.H(x), model.R_at(x)[0], model.active(x), self.gate_probability
            )
            h = float(hdop(self._seg_start[None], x2, lead[None])[0])
            self._seg_start = x2[0].copy()
            self._seg.reset(self._seg.position, np.zeros((2, 2)))
            if not info.applied[0]:
                why = "gate" if info.rejected[0] else "no direction"
                return FixOutcome(False, why, self.position, h, float(np.nan_to_num(info.nis[0])))
            self._est.reset(x2[0], P2[0])
            return FixOutcome(True, "ok", self.position, h, float(info.nis[0]))
        res = ga_fix(
            self.method,  # type: ignore[arg-type]
            self._seg_start[None],
            self._seg.position[None],
            lead[None],
            np.array([range_m]),
            self._seg.covariance[None],
            self.options,
        )
        if not res.valid[0]:
            return FixOutcome(False, "no fix", self.position, 0.0, 0.0)
        p = res.position[0]
        self._est.reset(p, res.covariance[0])
        if self.options.restart:
            self._seg_start = p.copy()
        else:
            self._seg_start = self._seg.position.copy()
        self._seg.reset(self._seg_start, np.zeros((2, 2)))
        return FixOutcome(True, "ok", self.position, float(res.hdop[0]), float(res.criterion[0]))
