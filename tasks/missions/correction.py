"""``mission/correction``: seed 001's correction procedures on the physical BAUV.

The BAUV of seed 001 has a compass and odometry only (no log, no USBL). It starts from a GPS fix,
swims leg 1 holding course alpha_1, surfaces for GPS fixes, swims leg 2 on alpha_2, surfaces
again; the DRNS (:mod:`nav.surfacing`) turns the two legs' errors into estimates of the vehicle's
systematic velocity error and of the current (CP2 by default: alpha_1 = 45 deg, alpha_2 = 225 deg;
CP1: two random courses at least ``cp1_min_separation_deg`` apart and from opposite), and leg 3
(a random course) is dead-reckoned with and without the correction. Each run flies the mission
twice with the same random streams: leg 3 on the direct course from the corrected DR position to
the way-point, and on the current-compensating course of eq. 22-26 (seed 001 Table 3).

The vehicle's own systematic error is configurable: a compass bias (``sensors.compass.heading
.bias_deg``, default 5 deg: the autopilot holds the compass course, so the vehicle really swims
5 deg off it) and an odometry scale error (``sensors.odometry.speed.scale_factor``, default 0.1:
the odometry believes the vehicle 10 % faster than it swims). The current defaults to a uniform
0.3 m/s setting 20 deg (seed 001's alpha_c); ``--set current.kind=randomised`` gives seed 001's
randomised current and ``current.kind=gyre`` a spatially varying one.

In the physics world the vehicle drifts with the water whatever its course (``models/bauv``
check 5), so CP2's hull response is uniform (``correction.response_cos_coeffs = [1.0]``); the
kinematic replica (``paper-001/replica``) uses the paper's course-dependent rho.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config, load_config, to_plain
from bauv_sim.errors import ConfigError
from bauv_sim.frames import (
    course_of,
    diff_course,
    unit_vector_scalar,
    wrap_2pi_scalar,
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
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.navigation import EkfNavigation, NavOutput, report_of
from tasks.closed_loop.parts import MissionParts, WaypointSteering
from tasks.closed_loop.report import circle, export_runs, record_mission
from tasks.closed_loop.result import MissionRun, VehicleRun
from tasks.closed_loop.scenario import MissionScenario
from tasks.closed_loop.world import (
    WaypointMission,
    fly,
    scenario_sea,
    standard_vehicle,
    waypoint_guidance,
)
from tasks.core import store
from tasks.core.registry import ReportContext, ReportSummary, register

METHODS = ("uncorrected", "corrected", "baseline")
EN = ("east", "north")


class CorrectionConfig(Config):
    """The correction experiment."""

    procedure: Literal["cp1", "cp2", "baseline"] = Field("cp2", description="after leg 2")
    leg_length_m: float = Field(100.0, gt=0, description="seed 001: 100 m between way-points")
    depth_m: float = Field(3.0, gt=0, description="depth of the legs, m")
    cp2_courses_deg: tuple[float, float] = Field((45.0, 225.0), description="CP2's two courses")
    cp1_min_separation_deg: float = Field(
        30.0, gt=0, lt=90, description="CP1's courses differ by this and from opposite, deg"
    )
    third_course_deg: float | None = Field(
        None, ge=0, lt=360, description="leg 3's course, deg (default: random per run)"
    )
    response_cos_coeffs: tuple[float, ...] = Field(
        (1.0,), description="CP2's hull response rho (uniform in the physics world)"
    )
    acceptance_radius_m: float = Field(5.0, gt=0, description="reached by the DR, m")


class CorrectionScenario(MissionScenario):
    """A mission scenario with the correction experiment (its way-points are made per run)."""

    correction: CorrectionConfig = Field(default_factory=CorrectionConfig)


def leg_courses(scn: CorrectionScenario, seed: int, run: int) -> tuple[float, float, float]:
    """The three legs' courses of a run, rad (from the run's own ``legs`` stream)."""
    c = scn.correction
    g = rng_mod.generator(seed, run, "legs")
    if c.procedure == "cp1":
        sep = math.radians(c.cp1_min_separation_deg)
        a1 = g.uniform(0, 2 * math.pi)
        # the second course at least `sep` from the first and from its opposite
        d = g.uniform(sep, math.pi - sep) * (1 if g.random() < 0.5 else -1)
        a2 = wrap_2pi_scalar(a1 + d)
    else:
        a1, a2 = (math.radians(x) for x in c.cp2_courses_deg)
    a3 = g.uniform(0, 2 * math.pi)
    if c.third_course_deg is not None:
        a3 = math.radians(c.third_course_deg)
    return a1, a2, a3


def run_scenario(scn: CorrectionScenario, seed: int, run: int) -> CorrectionScenario:
    """The scenario one run flies: the way-points of its three legs and its start heading."""
    c = scn.correction
    a = leg_courses(scn, seed, run)
    p = np.array([scn.start.east_m, scn.start.north_m])
    wps = []
    for i, course in enumerate(a):
        p = p + c.leg_length_m * np.array(unit_vector_scalar(course))
        wps.append(
            {
                "east_m": float(p[0]),
                "north_m": float(p[1]),
                "depth_m": c.depth_m,
                "acceptance_radius_m": c.acceptance_radius_m,
                "surface": i < 2,
            }
        )
    data = to_plain(scn)
    data["guidance"]["waypoints"] = wps
    data["start"]["heading_deg"] = math.degrees(a[0]) % 360.0
    return load_config(CorrectionScenario, data)


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
    out["course_deviation_deg"] = float(dev[far].mean()) if far.any() else math.nan
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


class CorrectionRunMetrics(BaseModel):
    """One run of ``mission/correction``."""

    run: int
    failed: str | None
    correction_error: str | None
    compensated: dict[str, float]
    direct: dict[str, float]


class CorrectionMetrics(BaseModel):
    """``metrics.json`` of ``mission/correction``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    n_failed: int
    procedure: str
    current_kind: str
    means: dict[str, float] = Field(description="means over successful runs")
    improvement_factor: float = Field(
        description="uncorrected / corrected mean DR error on leg 3 (compensated flights)"
    )
    runs: list[CorrectionRunMetrics]


@dataclass(frozen=True)
class CorrectionExperiment(MissionExperiment):
    """Seed 001's procedures on the physical vehicle (two flights per run)."""

    scenario_type = CorrectionScenario
    metrics_type = CorrectionMetrics

    def flight(self, scenario: CorrectionScenario, seed: int, run: int):
        """The compensated flight of a run (:meth:`run_block` flies the direct one too)."""
        return CorrectionMission(course_law="compensated"), run_scenario(scenario, seed, run)

    def check(self, scenario: CorrectionScenario, n_runs: int) -> None:
        super().check(scenario, n_runs)
        if scenario.sensors.use_usbl:
            raise ConfigError("sensors.use_usbl = true: seed 001's vehicle has no USBL")

    def run_block(self, scenario: CorrectionScenario, seed: int, runs: tuple[int, ...]):
        out = []
        for r in runs:
            flight = run_scenario(scenario, seed, r)
            flights, metrics, wps, failed, cp_err = {}, {}, {}, None, None
            for law in ("compensated", "direct"):
                res = fly(CorrectionMission(course_law=law), flight, seed, r)
                v = res.lead
                failed = failed or res.failed
                wps[law] = [
                    (w["east_m"], w["north_m"], w["acceptance_radius_m"]) for w in v.waypoints
                ]
                wp3 = v.waypoints[2]
                metrics[law] = leg3_metrics(
                    v, np.array([wp3["east_m"], wp3["north_m"]])
                ) | current_metrics(v)
                cp_err = cp_err or v.outcome["correction_error"]
                flights[law] = res
            out.append(CorrectionRunResult(r, failed, metrics, cp_err, flights, wps))
        return out

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_correction(self, ctx)


def report_correction(exp: CorrectionExperiment, ctx: ReportContext) -> ReportSummary:
    """Tables 1 and 3 analogues, the current estimate, figures and the recording."""
    from tasks.core.report import Table, write_metrics, write_tables

    scn: CorrectionScenario = ctx.scenario  # type: ignore[assignment]
    runs: list[CorrectionRunResult] = [r for b in ctx.blocks for r in b]
    ok = [r for r in runs if r.failed is None and r.metrics["compensated"] and r.metrics["direct"]]

    def mean(law: str, key: str) -> float:
        vals = [r.metrics[law][key] for r in ok if key in r.metrics[law]]
        return float(np.nanmean(vals)) if vals else math.nan

    means = {
        f"{law}.{k}": mean(law, k)
        for law in ("compensated", "direct")
        for k in (ok[0].metrics[law] if ok else {})
    }
    factor = mean("compensated", "uncorrected_mean_error_m") / mean(
        "compensated", "corrected_mean_error_m"
    )
    metrics = CorrectionMetrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        n_failed=sum(r.failed is not None for r in runs),
        procedure=scn.correction.procedure,
        current_kind=scn.current.kind,
        means=means,
        improvement_factor=factor,
        runs=[
            CorrectionRunMetrics(
                run=r.run,
                failed=r.failed,
                correction_error=r.correction_error,
                compensated=r.metrics.get("compensated", {}),
                direct=r.metrics.get("direct", {}),
            )
            for r in runs
        ],
    )
    files = [write_metrics(ctx.out_dir, metrics)]
    for law in ("compensated", "direct"):
        files += export_runs(ctx.out_dir, exp.name, [r.flights[law] for r in runs], f"-{law}")
    p = scn.correction.procedure.upper()
    t1 = Table(
        f"Leg 3 dead-reckoning error after {p} ({len(ok)} runs, {scn.current.kind} current; "
        "seed 001 Table 1-2 analogue)",
        ["DR", "Mean error (m)", "Max error (m)", "Final error (m)"],
        [
            [
                name,
                mean("compensated", f"{k}_mean_error_m"),
                mean("compensated", f"{k}_max_error_m"),
                mean("compensated", f"{k}_final_error_m"),
            ]
            for name, k in [
                ("without CP", "uncorrected"),
                (f"{p}-corrected", "corrected"),
                ("baseline (GPS - DR) / T", "baseline"),
            ]
        ],
        digits=2,
        slug="leg3-errors",
        note=f"Improvement of the mean error by the correction: {factor:.1f}x.",
    )
    t3 = Table(
        "Leg 3 deviation from the desired course (seed 001 Table 3 analogue)",
        ["Course law", "Mean deviation (deg)", "Mean cross-track distance (m)"],
        [
            [
                "direct course to the way-point",
                mean("direct", "course_deviation_deg"),
                mean("direct", "cross_track_m"),
            ],
            [
                "compensated (eq. 22-26)",
                mean("compensated", "course_deviation_deg"),
                mean("compensated", "cross_track_m"),
            ],
        ],
        digits=2,
        slug="leg3-course",
    )
    tc = Table(
        f"Current estimated by {p} against the true current at the vehicle (legs 1-2)",
        [
            "Run",
            "True east (m/s)",
            "True north (m/s)",
            "Estimated east (m/s)",
            "Estimated north (m/s)",
            "Error (m/s)",
        ],
        [
            [
                r.run,
                *(
                    r.metrics["compensated"].get(k)
                    for k in (
                        "current_true_east_m_s",
                        "current_true_north_m_s",
                        "current_est_east_m_s",
                        "current_est_north_m_s",
                        "current_error_m_s",
                    )
                ),
            ]
            for r in ok
        ],
        digits=3,
        slug="current",
        note=f"Mean error {mean('compensated', 'current_error_m_s'):.3f} m/s.",
    )
    tables = [t1, t3, tc]
    failures = [r.failed for r in runs if r.failed]
    if failures:
        tables.append(
            Table(
                "Failed runs",
                ["Run", "Reason"],
                [[r.run, r.failed] for r in runs if r.failed],
                slug="failed",
            )
        )
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    rec = next((r for r in runs if r.run == scn.report.record_run and r.failed is None), None)
    if rec is not None:
        flight = rec.flights["compensated"]
        if scn.report.figures:
            files += correction_figure(exp.name, scn, rec, ctx.out_dir)
        if scn.report.recording and flight.vehicles:
            flown = run_scenario(scn, ctx.seed, rec.run)
            files += record_correction(exp.name, flown, flight, ctx.out_dir)
    text = "".join(t.to_text() + "\n" for t in tables[:2])
    text += tc.note + "\n" + f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def correction_figure(
    name: str, scn: CorrectionScenario, rec: CorrectionRunResult, out
) -> list[str]:
    """Tracks of the recorded run: truth, the DR tracks, GPS fixes, numbered way-points, the true
    and the estimated current (PNG and PDF, project style)."""
    from tasks.core import style

    with style.context():
        return _draw_tracks(name, scn, rec, out, style)


def _draw_tracks(name: str, scn: CorrectionScenario, rec: CorrectionRunResult, out, style):
    from tasks.closed_loop.report import current_arrow

    fig, axs = style.subplots("page", 4.0, 1, 2)
    for ax, law in zip(axs, ("direct", "compensated"), strict=True):
        f = rec.flights[law]
        if not f.vehicles:
            continue
        a = f.lead
        ax.plot(a["truth_pos"][:, 0], a["truth_pos"][:, 1], **style.line("truth", lw=1.2))
        ax.plot(
            a["dr_uncorrected"][:, 0],
            a["dr_uncorrected"][:, 1],
            **style.line("DR", label="DR without CP"),
        )
        ax.plot(
            a["dr_corrected"][:, 0],
            a["dr_corrected"][:, 1],
            **style.line(
                scn.correction.procedure.upper(),
                label=f"DR after {scn.correction.procedure.upper()}",
            ),
        )
        gps = a.fixes["gps"]["position"].values if "gps" in a.fixes else np.zeros((0, 3))
        if len(gps):
            ax.plot(gps[:, 0], gps[:, 1], **style.line("GPS", label="GPS fixes", ms=5, zorder=5))
        wcol = style.color("waypoint")
        for i, (e, n, radius) in enumerate(rec.waypoints[law]):
            c = circle(e, n, radius)
            ax.plot(c[:, 0], c[:, 1], color=wcol, lw=0.8, label="way-point" if i == 0 else "_")
            ax.annotate(
                f"WP{i}",
                (e, n),
                ha="center",
                va="center",
                color=wcol,
                fontsize=6.5,
                fontweight="bold",
            )
        true_c = a["truth_current"][:, :2].mean(axis=0)
        est = a["cp_current"][~np.isnan(a["cp_current"][:, 0])]
        current_arrow(ax, true_c, "mean true current", style.color("current"))
        if len(est):
            current_arrow(ax, est.mean(axis=0), "estimated current", style.color("EKF"), "--", 1)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(style.label("east", "m"))
        ax.set_ylabel(style.label("north", "m"))
        style.title(ax, f"leg 3 on the {law} course")
    style.panel_letters(axs)
    fig.suptitle(f"Seed 001 on the vehicle (CP from surfacings), run {rec.run}")
    style.figure_legend(fig, axs, ncol=4)
    return style.save(fig, out / "tracks.png")


def record_correction(name: str, scn: CorrectionScenario, flight: MissionRun, out) -> list[str]:
    """The recordings of the recorded run's compensated flight: the mission recording, and a
    second one with the DR tracks and the estimated current beside the true one."""

    from tasks.core import style
    from tasks.core.recording import Recording

    path = record_mission(name, scn, flight, out)
    a = flight.lead
    rec = Recording(
        out / "recording-correction.rrd", name, f"{name}/seed{flight.seed}/run{flight.run}/dr"
    )
    t = a["t"]
    z = a["truth_pos"][:, 2:3]
    # the figure's looks (tasks.core.style): DR without CP, DR after the procedure, GPS
    cp = style.rgb(scn.correction.procedure.upper())
    rec.track("truth", t, a["truth_pos"], style.rgb("truth"))
    rec.track("dr_uncorrected", t, np.column_stack([a["dr_uncorrected"], z]), style.rgb("DR"))
    rec.track("dr_corrected", t, np.column_stack([a["dr_corrected"], z]), cp)
    gps = a.fixes.get("gps")
    if gps:
        rec.fixes("gps", gps["t_valid"].values, gps["position"].values, style.rgb("GPS"))
    every = max(1, round(1.0 / float(t[1] - t[0])))
    origins = a["truth_pos"][::every] + [0.0, 0.0, 2.0]
    # the current at the vehicle and the correction's estimate of it (x20 to be visible)
    rec.arrows(
        "current/true", t[::every], origins, 20.0 * a["truth_current"][::every], (0, 190, 220)
    )
    rec.arrows(
        "current/estimated",
        t[::every],
        origins + [0.0, 0.0, 1.0],
        20.0 * np.nan_to_num(a["cp_current"][::every]),
        (31, 119, 180),
    )
    for key, color in [("uncorrected", style.rgb("DR")), ("corrected", cp)]:
        rec.scalars(
            f"errors/dr_{key}",
            t,
            np.linalg.norm(a[f"dr_{key}"] - a["truth_pos"][:, :2], axis=1),
            color,
            f"DR {key} horizontal error (m)",
        )
    rec.blueprint("errors")
    rec.close()
    return [path, "recording-correction.rrd"]


register(
    CorrectionExperiment(
        name="mission/correction",
        summary="seed 001 on the physical BAUV: compass + odometry, CP2 from two surfacings, leg 3 "
        "corrected (0.3 m/s current)",
        preset={
            "start": {
                "east_m": 0.0,
                "north_m": 0.0,
                "depth_m": 3.0,
                "heading_deg": 45.0,
                "position_sigma_m": 0.0,
                "heading_sigma_deg": 3.0,
            },
            "current": {"kind": "uniform", "speed_m_s": 0.3, "direction_deg": 20.0},
            "sensors": {
                "use_usbl": False,
                "use_log": False,
                "compass": {"heading": {"bias_deg": 5.0}},
                "odometry": {"speed": {"scale_factor": 0.1}},
            },
            "navigation": {"initial_sigma_m": 2.5},
            "guidance": {
                "waypoints": [{"east_m": 0.0, "north_m": 100.0}],
                "hold_s": 5.0,
                "fixes_needed": 3,
                "max_leg_time_s": 400.0,
            },
            "timing": {"max_duration_s": 900.0},
        },
        default_runs=20,
    )
)
