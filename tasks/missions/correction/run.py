"""One run of ``mission/correction``: seed 001's DRNS beside the EKF, the leg guidance, the
flight design and the metrics of a flight."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import (
    course_of,
    diff_course,
    unit_vector_scalar,
    wrap_pi_scalar,
)
from bauv_sim.sensors.rig import RigTick
from nav.guidance import GuidanceCommand, WaypointGuidance, direct_course
from nav.surfacing import (
    CorrectedDeadReckoning,
    CorrectionEstimate,
    CurrentResponse,
    compensated_course,
)
from tasks.closed_loop.navigation import EkfNavigation, NavOutput, report_of
from tasks.closed_loop.parts import MissionParts, WaypointSteering
from tasks.closed_loop.result import EstimateTrack, MissionRun, VehicleRun
from tasks.closed_loop.world import (
    WaypointMission,
    fly,
    scenario_sea,
    standard_vehicle,
    waypoint_guidance,
)
from tasks.core import store
from tasks.missions.correction.scenario import (
    EN,
    METHODS,
    CorrectionConfig,
    CorrectionScenario,
    leg_courses,
    run_scenario,
)


@dataclass(frozen=True)
class CorrectionReport:
    """What seed 001's DRNS reports at a tick (:class:`CorrectionNavigation`).

    Attributes:
        dr_uncorrected: the DRNS track without correction (east, north), shape (2,), m.
        dr_corrected: the DRNS track, corrected after leg 2, shape (2,), m.
        dr_baseline: the DRNS track, baseline-corrected, shape (2,), m.
        cp_current: the correction's current estimate for the measured heading (east, north),
            shape (2,), m/s, NaN before leg 2.
        n_legs: legs the DRNS has closed with GPS fixes.
        correction: the correction procedure's estimate, or ``None`` before leg 2.
    """

    dr_uncorrected: NDArray[np.float64]
    dr_corrected: NDArray[np.float64]
    dr_baseline: NDArray[np.float64]
    cp_current: NDArray[np.float64]
    n_legs: int
    correction: CorrectionEstimate | None


class CorrectionNavigation:
    """Seed 001's DRNS (:class:`nav.surfacing.CorrectedDeadReckoning`) beside the standard EKF part:
    it dead-reckons on the compass heading and the odometry speed at every tick, takes every GPS
    fix (lever arm removed) and, after leg 2, corrects with the chosen procedure.

    Args:
        ekf: the standard navigation part (its initial estimate starts the DRNS).
        cfg: the correction experiment.
        courses: the three legs' courses, rad.

    The navigation output's ``report`` is a :class:`CorrectionReport`.
    """

    def __init__(self, ekf: EkfNavigation, cfg: CorrectionConfig, courses: tuple[float, ...]):
        self.ekf = ekf
        self.courses = courses
        x0 = ekf.nav.estimate.x
        self.drns = CorrectedDeadReckoning(
            0.0, x0[:2], cfg.procedure, CurrentResponse(tuple(cfg.response_cos_coeffs))
        )
        self.leg3_start_s: float | None = None

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        out = self.ekf.step(tick, initial)
        d = self.drns
        if not initial:
            d.predict(tick.t_s, out.heading_rad, out.odometry_speed_m_s)
        if out.gps_reference_m is not None:
            d.fix(tick.t_s, out.gps_reference_m)
            if len(d.legs) >= 2:
                self.leg3_start_s = tick.t_s  # the last fix before leg 3
        est = d.estimate
        cur = (
            est.current_for_course(np.array([out.heading_rad]))[0]
            if est is not None
            else np.full(2, np.nan)
        )
        report = CorrectionReport(
            dr_uncorrected=d.uncorrected.copy(),
            dr_corrected=d.corrected.copy(),
            dr_baseline=d.baseline.copy(),
            cp_current=cur,
            n_legs=len(d.legs),
            correction=est,
        )
        return dataclasses.replace(out, report=report)

    def outcome(self) -> dict[str, Any]:
        """When leg 3 started, the CP's error message, and its current estimate on the first
        leg's course (m/s, east and north)."""
        est = self.drns.estimate
        return {
            "leg3_start_s": self.leg3_start_s,
            "correction_error": self.drns.correction_error,
            "current_estimate_m_s": (
                None if est is None else est.current_for_course(np.array([self.courses[0]]))[0]
            ),
        }


EXTRA_COLUMNS = {
    "dr_uncorrected": ("dr_uncorrected", "m", "DRNS track without correction", EN, False),
    "dr_corrected": ("dr_corrected", "m", "DRNS track, corrected after leg 2", EN, False),
    "dr_baseline": ("dr_baseline", "m", "DRNS track, baseline-corrected", EN, False),
    "cp_current": ("cp_current", "m/s", "the correction's current estimate", EN, True),
    "n_legs": ("n_legs", "1", "legs the DRNS has closed with GPS fixes", (), False),
}
"""The per-tick columns the correction adds (see :class:`~tasks.closed_loop.parts.
VehicleParts`)."""


class LegGuidance(WaypointSteering):
    """Seed 001's legs: steer on the DRNS (corrected after leg 2) position, depth from pressure.

    Legs 1-2 hold their course (CP2: 45 and 225 deg) for ``leg_length_m`` from where each leg
    starts (the way-point is placed once the turn onto the course is over); leg 3 goes to its
    way-point on the direct course or on the current-compensating course (eq. 22-26). The rest
    (done, way-points as placed, legs) is :class:`~tasks.closed_loop.parts.WaypointSteering`'s.

    Args:
        guidance: the way-point state machine of the run's scenario.
        courses: the three legs' courses, rad.
        leg_length_m: length of a leg, m.
        course_law: ``"direct"`` or ``"compensated"`` (leg 3).
    """

    def __init__(
        self,
        guidance: WaypointGuidance,
        courses: tuple[float, ...],
        leg_length_m: float,
        course_law: str,
    ):
        super().__init__(guidance, steer_on="drns")
        guidance.course_law = self._course_law
        guidance.waypoints = list(guidance.waypoints)
        self.courses, self.leg_length_m, self.course_law = courses, leg_length_m, course_law
        self.placed: set[int] = set()
        self.leg_start: dict[int, NDArray[np.float64]] = {}
        self._nav: NavOutput | None = None

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        if nav.gps_fix:
            self.guidance.gps_fix()
        self._nav = nav
        rep = report_of(nav, CorrectionReport)
        return self.guidance.step(t_s, np.array([*rep.dr_corrected, -nav.depth_m]))

    def _course_law(self, position, wp) -> float:
        nav = self._nav
        leg = self.guidance.index
        p = np.asarray(position, dtype=float)[:2]
        c = self.courses[leg]
        if leg not in self.placed:
            # a leg is 100 m on its course from where it starts (seed 001's legs are defined by
            # course and distance): the way-point goes on the line the vehicle holds once its turn
            # onto the course is over, at the rest of the 100 m from the leg's start
            start = self.leg_start.setdefault(leg, p.copy())
            heading = nav.heading_rad
            if leg == 2 or abs(wrap_pi_scalar(heading - c)) < math.radians(10.0):
                rest = max(self.leg_length_m - float(np.linalg.norm(p - start)), 0.0)
                new = p + rest * np.array(unit_vector_scalar(c))
                self.guidance.waypoints[leg] = dataclasses.replace(
                    self.guidance.waypoints[leg], east_m=float(new[0]), north_m=float(new[1])
                )
                self.placed.add(leg)
                wp = self.guidance.waypoints[leg]
        if leg < 2:
            return c  # CP legs: hold the leg's course
        nu = direct_course(position, wp)
        est = report_of(nav, CorrectionReport).correction
        if self.course_law == "compensated" and est is not None:
            sol = compensated_course(np.array([nu]), np.array([nav.odometry_speed_m_s]), est)
            if bool(sol.feasible[0]):
                return float(sol.course_rad[0])
        return nu


@dataclass(frozen=True)
class CorrectionMission(WaypointMission):
    """The design of one flight: the standard vehicle with seed 001's DRNS and leg guidance.

    Attributes:
        course_law: leg 3's course law, ``"direct"`` or ``"compensated"``.
    """

    course_law: str = "compensated"

    def build(self, scenario: CorrectionScenario, seed: int, run: int, physics) -> MissionParts:
        v = standard_vehicle(scenario, seed, run, physics)
        courses = leg_courses(scenario, seed, run)
        v.navigation = CorrectionNavigation(v.navigation, scenario.correction, courses)
        v.guidance = LegGuidance(
            waypoint_guidance(scenario, v.rig),
            courses,
            scenario.correction.leg_length_m,
            self.course_law,
        )
        v.extra_columns = EXTRA_COLUMNS
        v.estimates = (
            EstimateTrack("ekf_pos", "EKF", "ekf_P"),
            EstimateTrack("dr_uncorrected", "DR"),
            EstimateTrack("dr_corrected", scenario.correction.procedure.upper()),
            EstimateTrack("dr_baseline", "baseline"),
        )
        return MissionParts([v], scenario_sea(scenario, seed, run))


# ---------------------------------------------------------------------------------------------
# Metrics of one run


def leg3_metrics(v: VehicleRun, wp3: NDArray[np.float64]) -> dict[str, float]:
    """Errors of the three DR tracks and the deviation from the desired course on leg 3.

    The deviation is the mean over leg 3 of the angle between the course over ground (averaged
    over 1 s) and the desired course ``nu`` from the true position to way-point 3 (seed 001
    Table 3's "deviation from desired course"), and the mean distance from the straight line
    between the leg's start and way-point 3.
    """
    a = v
    t = a["t"]
    leg3_start_s = v.outcome["leg3_start_s"]
    if leg3_start_s is None:
        return {}
    m = t >= leg3_start_s
    out = {"leg3_duration_s": float(t[m][-1] - t[m][0])}
    truth = a["truth_pos"][m, :2]
    for name in METHODS:
        e = np.linalg.norm(a[f"dr_{name}"][m] - truth, axis=1)
        out[f"{name}_mean_error_m"] = float(e.mean())
        out[f"{name}_max_error_m"] = float(e.max())
        out[f"{name}_final_error_m"] = float(e[-1])
    n = max(1, round(1.0 / float(t[1] - t[0])))
    vel = a["truth_vel"][m, :2]
    kernel = np.ones(n) / n
    vel = np.column_stack([np.convolve(vel[:, i], kernel, mode="same") for i in range(2)])
    cog = course_of(vel)
    nu = course_of(wp3 - truth)
    dev = np.degrees(diff_course(cog, nu))
    far = np.linalg.norm(wp3 - truth, axis=1) > 10.0  # the course to a point is ill-defined near it
    if far.any():  # else undefined: left out (never NaN)
        out["course_deviation_deg"] = float(dev[far].mean())
    p0 = truth[0]
    d = (wp3 - p0) / max(np.linalg.norm(wp3 - p0), 1e-9)
    rel = truth - p0
    out["cross_track_m"] = float(np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]).mean())
    return out


def current_metrics(v: VehicleRun) -> dict[str, float]:
    """The CP's current estimate against the true current at the vehicle over legs 1-2."""
    c, leg3_start_s = v.outcome["current_estimate_m_s"], v.outcome["leg3_start_s"]
    if c is None or leg3_start_s is None:
        return {}
    m = v["t"] < leg3_start_s
    true = v["truth_current"][m, :2].mean(axis=0)
    return {
        "current_true_east_m_s": float(true[0]),
        "current_true_north_m_s": float(true[1]),
        "current_est_east_m_s": float(c[0]),
        "current_est_north_m_s": float(c[1]),
        "current_error_m_s": float(np.linalg.norm(c - true)),
    }


SPANS = ("legs 1-2", "leg 3", "legs 1-3")
"""The spans of a flight the along-track comparison of the current is reduced over."""


def current_along_track(v: VehicleRun) -> dict[str, dict[str, float]]:
    """The correction procedure's estimated current against the true current at the vehicle,
    tick by tick along the track (issue 25 check 4).

    At each control tick the true current is the water's velocity at the vehicle (the run's
    ``truth_current``, east/north) and the estimate is the procedure's: on legs 1-2 the estimate
    made from them when leg 2 closed (``outcome()["current_estimate_m_s"]``, for leg 1's course:
    the same for every course under the physics world's uniform hull response), on leg 3 the
    estimate for the measured heading at the tick (``cp_current``). Per span (:data:`SPANS`):
    the difference ``d = estimate - true`` as the mean, RMS and largest ``|d|`` and the mean
    ``d`` (east, north), and how much the true current varied: the RMS and the largest
    ``|true - mean true|`` over the span, and the mean true speed. All in m/s.

    Returns:
        ``{span: {quantity: value}}``; empty when the procedure made no estimate.
    """
    c, leg3_start_s = v.outcome["current_estimate_m_s"], v.outcome["leg3_start_s"]
    if c is None or leg3_start_s is None:
        return {}
    t = v["t"]
    true = np.asarray(v["truth_current"], dtype=float)[:, :2]
    est = np.array(v["cp_current"], dtype=float)
    before = t < leg3_start_s
    est[before] = np.asarray(c, dtype=float)
    valid = np.isfinite(est).all(axis=1)
    out: dict[str, dict[str, float]] = {}
    for span, m in zip(SPANS, (before, ~before, np.ones_like(before)), strict=True):
        m = m & valid
        if not m.any():
            continue
        d = est[m] - true[m]
        err = np.linalg.norm(d, axis=1)
        dev = np.linalg.norm(true[m] - true[m].mean(axis=0), axis=1)
        out[span] = {
            "mean_error_m_s": float(err.mean()),
            "rms_error_m_s": float(np.sqrt(np.mean(err**2))),
            "max_error_m_s": float(err.max()),
            "bias_east_m_s": float(d[:, 0].mean()),
            "bias_north_m_s": float(d[:, 1].mean()),
            "true_rms_variation_m_s": float(np.sqrt(np.mean(dev**2))),
            "true_max_variation_m_s": float(dev.max()),
            "true_mean_speed_m_s": float(np.linalg.norm(true[m], axis=1).mean()),
        }
    return out


@store.plain_data("missions.correction.CorrectionRunResult")
@dataclass
class CorrectionRunResult:
    """Both flights of one run (compensated and direct course on leg 3), as plain data.

    Attributes:
        run: run index.
        failed: the first flight failure, or ``None``.
        metrics: per course law, the leg-3 and current metrics.
        correction_error: why the correction procedure could not be applied, or ``None``.
        flights: per course law, the flight.
        waypoints: per course law, the way-points as placed: (east m, north m, radius m).
    """

    run: int
    failed: str | None
    metrics: dict[str, dict[str, float]]
    correction_error: str | None
    flights: dict[str, MissionRun]
    waypoints: dict[str, list[tuple[float, float, float]]]


def fly_run(scenario: CorrectionScenario, seed: int, run: int) -> CorrectionRunResult:
    """Both flights of a run (leg 3 on the compensated course, then on the direct one), with the
    same random streams, and their metrics."""
    flight = run_scenario(scenario, seed, run)
    flights, metrics, wps, failed, cp_err = {}, {}, {}, None, None
    for law in ("compensated", "direct"):
        res = fly(CorrectionMission(course_law=law), flight, seed, run)
        v = res.lead
        failed = failed or res.failed
        wps[law] = [(w["east_m"], w["north_m"], w["acceptance_radius_m"]) for w in v.waypoints]
        wp3 = v.waypoints[2]
        metrics[law] = leg3_metrics(v, np.array([wp3["east_m"], wp3["north_m"]])) | current_metrics(
            v
        )
        cp_err = cp_err or v.outcome["correction_error"]
        flights[law] = res
    return CorrectionRunResult(run, failed, metrics, cp_err, flights, wps)
