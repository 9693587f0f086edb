"""``mission/seed004``'s parts: the seed-004 filter of the bank on the DOA bearings beside the
standard navigation part, the seabed-sensing prediction from the mission's multibeam, and the
guidance that hands the locally optimal control to the autopilot (package docstring)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.build import SceneConfig
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.frames import R_from_roll_pitch_heading, theta_from_course
from bauv_sim.sensors.doa import DoaSet
from bauv_sim.sensors.multibeam import MultibeamConfig, MultibeamImage
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.bearings import PredictedShift, SystemPrediction, bank, velocity
from nav.bearings.cmnf import CmnfGains
from nav.guidance import GuidanceCommand
from nav.navigator import Estimate
from tasks.closed_loop import parts as P
from tasks.closed_loop.navigation import (
    EkfNavigation,
    FixRecord,
    NavOutput,
    initial_covariance,
    report_of,
)
from tasks.closed_loop.result import EstimateTrack
from tasks.closed_loop.world import place_vehicle, scenario_sea, single_vehicle_scene, streams
from tasks.missions.seed004.scenario import Seed004Scenario, beacon_specs, surrogate

if TYPE_CHECKING:
    from tasks.paper004.sim import LoopSetting

Array = NDArray[np.float64]

# ---------------------------------------------------------------------------------------------
# The parts


def depth_setpoint(depth_m: float, u: Array, ap) -> float:
    """The depth set-point that makes the autopilot's depth loop fly the control's pitch.

    Args:
        depth_m: measured depth, m.
        u: the control ``(gamma rad, theta rad, V m/s)``, shape (3,) (seed 004's angles).
        ap: the autopilot's gains (:class:`~bauv_sim.autopilot.AutopilotConfig`).

    Returns:
        ``depth - w (1 + V kd) / (V kp)`` with ``w = V sin(gamma)`` (module docstring), m, at
        least 0.
    """
    gamma, v = float(u[0]), max(float(u[2]), 1e-3)
    w = v * math.sin(gamma)
    return max(depth_m - w * (1.0 + v * ap.depth_kd) / (v * ap.depth_kp), 0.0)


class SonarShift:
    """The seabed-sensing prediction on the vehicle (seed 004, eq. 8-15, row 2 of Table 1).

    The multibeam's beams are fixed to the hull (aimed from its pitch and heading, roll
    stabilised), so the two images of a shift are aimed from the vehicle's attitudes at the two
    pings: the shift uses the reading ``"turning"`` with the exact change of the beams
    (``delta_e="exact"``), the attitudes as the vehicle measures them (INS pitch, compass
    heading: gamma = pitch, theta from the heading), Appendix A's fit on image j-1's feet with
    ``basis`` and the stated residual covariance (:func:`nav.seabed.shift_estimate`). The images
    are the transducer's: the reference point's shift is the transducer's less the turn of the
    lever arm, ``R_j l - R_{j-1} l`` (measured attitudes). A step without two images (the first:
    the sonar has no image at t = 0) or without a shift (too few echoes) predicts the commanded
    displacement ``V(u) dt`` with ``fallback`` (the system's ``S^W``) or the fallback variance
    of :func:`nav.seabed.shift_estimate`.

    Args:
        cfg: the multibeam.
        lever_arm_body_m: transducer from the reference point, body FLU, m.
        basis: Appendix A's basis.
        dt: filter step, s.
        fallback: the covariance of the first step, ``(3, 3)`` m^2.
    """

    def __init__(
        self,
        cfg: MultibeamConfig,
        lever_arm_body_m: Array,
        basis: str,
        dt: float,
        fallback: Array,
    ):
        from nav.seabed import BeamGeometry, SlopeBasis

        self.cfg, self.dt, self.fallback = cfg, dt, np.asarray(fallback, float)
        self.lever = np.asarray(lever_arm_body_m, float)
        self.geometry = BeamGeometry(cfg.elevations_rad(), cfg.azimuths_rad())
        self.basis = SlopeBasis(basis)  # type: ignore[arg-type]
        self.prev: tuple[MultibeamImage, Array] | None = None
        self.image: tuple[MultibeamImage, Array] | None = None
        self.last_ok = False
        self.last_beams = 0

    def take(self, tick: RigTick) -> None:
        """Keep the image arriving at this tick (with the measured attitude at its ping)."""
        for m in tick.arrived:
            if m.device == "multibeam" and m.attitude_rad is not None:
                self.prev, self.image = self.image, (m.payload, np.asarray(m.attitude_rad))

    def __call__(self, x_hat: Array, u: Array) -> PredictedShift:
        """The predicted displacement of the reference point over the step that just ended.

        Args:
            x_hat: the estimate at the step's start, shape (1, 3), m, world.
            u: the control flown over the step ``(gamma, theta, V)``, shape (1, 3).

        Returns:
            The displacement (1, 3) m and its covariance (3, 3) or (1, 3, 3) m^2;
            ``last_ok`` and ``last_beams`` (beams used, 0 without a shift) say how it was made.
        """
        from nav.seabed import shift_estimate

        cmd = velocity(u) * self.dt
        self.last_ok, self.last_beams = False, 0
        if self.prev is None or self.image is None:
            return PredictedShift(cmd, self.fallback)
        (a, rph0), (b, rph1) = self.prev, self.image
        att0 = np.array([[rph0[1], float(theta_from_course(rph0[2]))]])
        att1 = np.array([[rph1[1], float(theta_from_course(rph1[2]))]])
        est = shift_estimate(
            a.ranges_m[None],
            b.ranges_m[None],
            self.geometry,
            att0,
            att1,
            echo=a.echo[None],
            next_echo=b.echo[None],
            reading="turning",
            delta_e="exact",
            basis=self.basis,
            position_m=x_hat,
            sigma_range_m=self.cfg.range.sigma_m,
            commanded_shift_m=cmd,
        )
        self.last_ok = bool(est.ok[0])
        self.last_beams = int(est.beams[0]) if self.last_ok else 0
        if not self.last_ok:
            return PredictedShift(est.shift_m, est.covariance_m2)
        arm = R_from_roll_pitch_heading(*rph1) @ self.lever - R_from_roll_pitch_heading(*rph0) @ (
            self.lever
        )
        return PredictedShift(est.shift_m - arm, est.covariance_m2)


@dataclass(frozen=True)
class BearingReport:
    """What :class:`BearingNavigation` reports at a tick: ``control`` (gamma, theta, V),
    ``depth_cmd`` (m), ``filter_step`` (j, -1 between steps), ``done`` (the last step is
    over), ``shift`` (the predicted displacement, (3,) m) and ``shift_beams`` (beams the seabed
    shift used; 0: none)."""

    control: Array
    depth_cmd: float
    filter_step: float
    done: bool
    shift: Array
    shift_beams: float

    @property
    def control_gamma(self) -> float:
        """The control's gamma (climb angle, up +), rad."""
        return float(self.control[0])

    @property
    def control_theta(self) -> float:
        """The control's theta (counter-clockwise from east), rad."""
        return float(self.control[1])

    @property
    def control_speed(self) -> float:
        """The control's V (speed through water), m/s."""
        return float(self.control[2])


class BearingNavigation:
    """A seed-004 filter on the DOA bearings beside the standard part (heading, depth, speed and
    DR for the autopilot and the log), plus the locally optimal control on its estimate.

    At every filter step ``j`` (``t = j dt``, j = 1..N): predict with ``u_{j-1}`` (eq. 1) or from
    the two multibeam images of ``t_{j-1}`` and ``t_j`` (:class:`SonarShift`), update on the
    bearing set of that tick (absent pairs left out; no set: prediction only), then ``u_j`` from
    the estimate (eq. 7 with the box). An estimate that is not finite, or farther than
    ``diverge_m`` from the nominal point, stops the flight with a named divergence
    (:class:`nav.errors.NavError`). ``report`` holds ``control`` (gamma, theta, V), ``depth_cmd``
    (m), ``filter_step`` (j, -1 between steps), ``shift`` (the predicted displacement, m) and
    ``shift_beams`` (beams the seabed shift used; 0: none). The bearings that arrive are its
    fixes (``device = "doa"``, one per produced bearing, accepted when a filter step took it:
    the run data's ``doa`` table).

    Args:
        base: the standard part.
        name: ``"ekf"``, ``"upmf"`` or ``"cmnf"``.
        setting: the surrogate setting (path, noise the filter assumes, beacons, limits).
        gains: the CMNF's gains (for ``"cmnf"``).
        autopilot: the autopilot's gains (for :func:`depth_setpoint`).
        sonar: the seabed-sensing prediction (``None``: by virtue of the system).
        diverge_m: the divergence distance, m.
    """

    def __init__(
        self,
        base: EkfNavigation,
        name: str,
        setting: LoopSetting,
        gains: CmnfGains | None,
        autopilot,
        sonar: SonarShift | None = None,
        diverge_m: float = math.inf,
    ):
        self.base, self.name, self.s, self.gains = base, name, setting, gains
        self.ap = autopilot
        self.sonar, self.diverge_m = sonar, diverge_m
        self.nominal = setting.path.path()
        self.shift = np.zeros(3)
        from tasks.paper004.sim import Controller

        self.dt = setting.path.dt_s
        self.n_steps = setting.path.n_steps
        self.beacons = setting.b
        self.s_eps = setting.fnoise.s_eps
        self.filter = name.upper()  # the bank's spelling (nav.bearings.bank.FILTERS)
        self.options = bank.BankOptions(self.s_eps, setting.upmf_form, gains, setting.correction)
        self.pred = SystemPrediction(self.dt, setting.fnoise.s_w)
        self.ctl = Controller(setting, 1)
        self.x_hat = np.asarray(setting.path.start_m, float)[None].copy()
        self.P = setting.s0_filter[None].copy()
        self.j = 0
        self.u = self.ctl(0, self.x_hat)
        self.depth_cmd = 0.0
        self.absent_total = 0
        self.missing_sets = 0
        self.warnings: list[str] = []

    def _bearings(self, tick: RigTick) -> tuple[Array, NDArray[np.bool_]]:
        y = np.zeros((1, len(self.beacons), 2))
        present = np.zeros((1, len(self.beacons)), dtype=bool)
        for m in tick.arrived:
            if m.device == "doa":
                d: DoaSet = m.payload
                y[0] = d.tangents
                present[0] = d.produced & d.tangent_ok
        return y, present

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        out = self.base.step(tick, initial)
        j = round(tick.t_s / self.dt)
        at_step = abs(tick.t_s - j * self.dt) < 1e-6
        if self.sonar is not None:
            self.sonar.take(tick)
        updated = False
        if initial:
            self.depth_cmd = depth_setpoint(out.depth_m, self.u[0], self.ap)
        elif at_step and self.j < j <= self.n_steps:
            updated = True
            y, present = self._bearings(tick)
            self.absent_total += int((~present).sum())
            self.missing_sets += int(not present.any())
            if self.sonar is None:
                shift = self.pred(j - 1, self.x_hat, self.u)
            else:
                shift = self.sonar(self.x_hat, self.u)
            self.shift = shift.displacement_m[0].copy()
            res = bank.step(
                self.filter, j, self.x_hat, self.P, shift, y, present, self.beacons, self.options
            )
            self.x_hat, self.P = res.x_hat, res.p_hat
            self.j = j
            from nav.errors import NavError

            if not (np.isfinite(self.x_hat).all() and np.isfinite(self.P).all()):
                raise NavError(f"{self.filter} diverged: estimate not finite at step {j}")
            off = float(np.linalg.norm(self.x_hat[0] - self.nominal[j]))
            if off > self.diverge_m:
                raise NavError(
                    f"{self.filter} diverged at step {j}: estimate {off:.0f} m from the "
                    f"nominal point (seed004.diverge_m = {self.diverge_m:g})"
                )
            if j < self.n_steps:
                self.u = self.ctl(j, self.x_hat)
            self.depth_cmd = depth_setpoint(out.depth_m, self.u[0], self.ap)
        report = BearingReport(
            control=self.u[0].copy(),
            depth_cmd=self.depth_cmd,
            filter_step=0.0 if initial else float(j if at_step and j == self.j else -1),
            done=self.j >= self.n_steps,
            shift=self.shift.copy(),
            shift_beams=float(self.sonar.last_beams if self.sonar is not None else 0),
        )
        est = Estimate(tick.t_s, self.x_hat[0].copy(), self.P[0].copy())
        fixes = out.fixes + self._bearing_fixes(tick, updated)
        return dataclasses.replace(out, estimate=est, report=report, fixes=fixes)

    def _bearing_fixes(self, tick: RigTick, updated: bool) -> tuple[FixRecord, ...]:
        """The bearings that arrived at this tick as fix records (``device = "doa"``, one per
        produced bearing of a set): accepted when the filter's update of this tick took it
        (a filter step, its tangent pair ok). The azimuth is written clockwise from north
        (``pi/2 - phi``), the tangents as eq. 17 has them."""
        out = []
        for m in tick.arrived:
            if m.device != "doa":
                continue
            d: DoaSet = m.payload
            for b in np.flatnonzero(d.produced):
                phi, lam = (float(a) for a in d.angles_rad[b])
                ok = bool(d.tangent_ok[b])
                z = [
                    float(b),
                    (math.pi / 2 - phi) % (2 * math.pi),
                    lam,
                    *(float(a) for a in d.tangents[b]),
                    float(ok),
                    *(float(a) for a in d.beacons_world_m[b]),
                ]
                out.append(
                    FixRecord(
                        "doa",
                        m.t_valid_s,
                        m.t_arrival_s,
                        np.array(z),
                        updated and ok,
                        self.x_hat[0].copy(),
                    )
                )
        return tuple(out)

    def outcome(self) -> dict[str, Any]:
        return {"absent_pairs": self.absent_total, "missing_sets": self.missing_sets}


EXTRA_COLUMNS = {
    "control_gamma": (
        "control_gamma",
        "rad",
        "locally optimal control: gamma, the climb angle (up +)",
        (),
        False,
    ),
    "control_theta": (
        "control_theta",
        "rad",
        "locally optimal control: theta, the horizontal direction counter-clockwise from east",
        (),
        False,
    ),
    "control_speed": (
        "control_speed",
        "m/s",
        "locally optimal control: V, the speed through water",
        (),
        False,
    ),
    "filter_step": ("filter_step", "1", "filter step j at this tick (-1: none)", (), False),
    "shift": (
        "shift",
        "m",
        "predicted displacement of the last filter step (world)",
        ("east", "north", "up"),
        False,
    ),
    "shift_beams": (
        "shift_beams",
        "1",
        "beams the last seabed shift used (0: none, or the prediction by virtue of the system)",
        (),
        False,
    ),
}
"""Per-tick columns the mission adds (the control in three columns: one unit each)."""


def control_of(ticks) -> Array:
    """The control ``(gamma rad, theta rad, V m/s)`` per tick of a flight's tick columns,
    shape (T, 3)."""
    return np.stack(
        [
            np.asarray(ticks[k].values, float)
            for k in ("control_gamma", "control_theta", "control_speed")
        ],
        axis=1,
    )


@dataclass
class ControlGuidance:
    """Hands the control of the navigation part to the autopilot (module docstring)."""

    finished: bool = False

    @property
    def done(self) -> bool:
        return self.finished

    def step(self, t_s: float, nav: NavOutput) -> GuidanceCommand:
        rep = report_of(nav, BearingReport)
        _, theta, v = (float(a) for a in rep.control)
        self.finished = bool(rep.done)
        course = (math.pi / 2 - theta) % (2 * math.pi)
        mode = "done" if self.finished else "transit"
        return GuidanceCommand(course, rep.depth_cmd, v, mode, 0)

    def waypoints(self) -> list[tuple[float, float, float]]:
        return []

    def legs(self) -> list[dict[str, Any]]:
        return []

    def outcome(self) -> dict[str, Any]:
        return {}


@dataclass(frozen=True)
class Seed004Mission:
    """The design of one flight with one filter."""

    filter: str
    gains: CmnfGains | None = None

    def vehicle_names(self, scenario: Seed004Scenario) -> tuple[str, ...]:
        return ("bauv",)

    def scene(self, scenario: Seed004Scenario) -> SceneConfig:
        return single_vehicle_scene(scenario, beacon_specs(scenario))

    def build(self, scn: Seed004Scenario, seed: int, run: int, physics) -> P.MissionParts:
        table = load_speed_table()
        pos = place_vehicle(physics, scn.start, seed, run, "bauv")
        s = scn.sensors
        devices = {"compass": s.compass, "ins": s.ins, "log": s.log, "odometry": s.odometry}
        devices |= {"pressure": s.pressure, "doa": scn.doa}
        seabed_pred = scn.navigation.prediction == "seabed"
        if seabed_pred:
            devices["multibeam"] = scn.multibeam
        rig = SensorRig(
            devices,
            physics,
            "bauv",
            seed,
            run,
            "",
            extra={"odometry": {"speed_table": table}},
            propagation=scn.sound.propagation(),
        )
        n = scn.navigation
        P0 = initial_covariance(n)
        e0 = rng_mod.generator(seed, run, *streams("", "initial")).standard_normal(3) @ np.sqrt(P0)
        base = EkfNavigation(n, pos + e0, physics.transceiver_world(), rig.lever_arms_body_m, False)
        setting = surrogate(scn)
        sonar = None
        if seabed_pred:
            sonar = SonarShift(
                scn.multibeam,
                np.asarray(rig.lever_arms_body_m["multibeam"]),
                scn.seed004.slope_basis,
                scn.seed004.dt_s,
                setting.fnoise.s_w,
            )
        nav = BearingNavigation(
            base, self.filter, setting, self.gains, scn.autopilot, sonar, scn.seed004.diverge_m
        )
        v = P.VehicleParts("bauv", rig, nav, ControlGuidance(), scn.autopilot, table)
        v.extra_columns = EXTRA_COLUMNS
        # ekf_pos / ekf_P hold this flight's filter (the bank's estimate and covariance)
        v.estimates = (
            EstimateTrack("ekf_pos", self.filter.upper(), "ekf_P"),
            EstimateTrack("dr_pos", "DR"),
        )
        return P.MissionParts([v], scenario_sea(scn, seed, run))
