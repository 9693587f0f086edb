"""``mission/seed004``: seed 004 on the physical BAUV: bearings to beacons, locally optimal control.

The BAUV follows seed 004's 3-D nominal path (eq. 3 with section 6's angle laws ``gamma°(t) =
pi/100 cos(pi t / 100)``, ``theta°(t) = pi/3 cos(pi t / 25)``) flown at the vehicle's speed
``V° = 1 m/s`` instead of 2 m/s: with the same angle laws in time the path is the seed's shape
scaled by ``V° / 2`` (so the depth swings by +-1 m instead of +-2 m, inside the scene's 6 m of
water), started at the scenario's start and cut to ``seed004.duration_s``. The four DOA beacons
are the seed's (section 6) scaled by the same factor about the path's start, moored
``seed004.beacon_depth_m`` below the surface (the seed's beacons are at the surface).

Every ``seed004.dt_s`` (the DOA period, seed 004's 1 s) the chosen filter (``navigation.filter``:
EKF, UPMF or CMNF of :mod:`nav.bearings` and :mod:`nav.cmnf`; ``"all"`` flies each in turn on the
same run) predicts with the previous control ("by virtue of the system", eq. 1), takes the
bearing tangents of that tick (eq. 17) and the locally optimal control with box limits
(:func:`nav.local_control.limited_control`, eq. 5-7) is computed on its estimate. The control
``u = (gamma, theta, V)`` (seed 004's angles: theta counter-clockwise from east, gamma up) goes to
the existing autopilot as set-points held for the step: course ``pi/2 - theta`` (clockwise from
north), speed ``V`` (through water) and, since the autopilot holds a depth, not a pitch, the depth
set-point at which its depth loop settles at the vertical rate ``w = V sin(gamma)`` (up): that loop
is a PD on the depth error, ``pitch = kp e - kd w`` with ``w = V pitch``, so it climbs at ``w`` with
the set-point ``e = w (1 + V kd) / (V kp)`` above the measured depth (:func:`depth_setpoint`; 5.3
s of climb at the default gains and 1 m/s). A set-point one step ahead (``w dt``) would be flown at
a fifth of the commanded rate (measured: the vertical residual then adds up to 1.5 m in 160 s).

The CMNF's gains are fitted (CMNF in the loop, :func:`tasks.paper004.sim.train_gains`) on a
kinematic surrogate of the same mission (:mod:`bauv_sim.kinematic.seed004` with the scaled path,
``dt``, beacons, limits, bearing noise and the surrogate's process noise
``seed004.sigma_w_m``) on ``seed004.train_paths`` paths; they are deterministic in (setting,
seed), trained once per process and written to the run folder as plain ``.npz``
(``cmnf-gains.npz``). The report compares the CMNF's J-bar (``max_k E||X°_k - X_k||^2``, seed 004
section 6) on ``seed004.surrogate_test_paths`` fresh surrogate paths with the one on the physics
runs, and gives the physics' own step residual ``X_{k+1} - X_k - V(u_k) dt`` (what the surrogate's
``S^W`` stands for).

**Seabed-sensing prediction** (``navigation.prediction = "seabed"``, Table 1's row 2 on the
vehicle): the rig carries the multibeam (:class:`bauv_sim.sensors.multibeam.MultibeamDevice`,
``multibeam.*``: seed 004's 8 x 8 beams, 0.1 m range noise, an image every filter step), whose
beams MuJoCo casts against the scene's seabed heightfield from the hull's ``sonar`` site. Every
filter predicts with the shift of eq. 15 between the images of ``t_{j-1}`` and ``t_j``
(:class:`SonarShift`: the hull's measured attitudes at the two pings, reading ``"turning"`` with
the exact beam change, Appendix A's fit with ``seed004.slope_basis``, the lever arm's turn
removed) and its stated covariance; the CMNF's alpha is the estimate plus that shift. The CMNF is
trained on a surrogate that images the same heightfield
(:class:`tasks.paper004.seabed.HeightfieldPrediction`, rays by
:meth:`bauv_sim.seabed.Seabed.ray_ranges`, which equal MuJoCo's). The mission's seabed
(:data:`SEABED_PRESET`) has relief at the scale of the multibeam's footprint, and the check
refuses a seabed beyond the multibeam's range along the path. A filter whose estimate leaves the
nominal point by more than ``seed004.diverge_m`` stops its flight with a named divergence
(``failures``); the report gives the shift's own error on the physics and on the surrogate.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim import rng as rng_mod
from bauv_sim import seabed
from bauv_sim.build import BeaconSpec, SceneConfig
from bauv_sim.config import Config
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.frames import R_from_roll_pitch_heading, theta_from_course
from bauv_sim.kinematic.seed004 import NominalPathConfig, Seed004Noise
from bauv_sim.sensors.doa import DoaConfig, DoaSet
from bauv_sim.sensors.multibeam import MultibeamConfig, MultibeamImage
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.bearings import (
    PredictedShift,
    SystemPrediction,
    ekf_update,
    predict,
    upmf_update,
    velocity,
)
from nav.cmnf import CmnfGains, cmnf_step
from nav.guidance import GuidanceCommand
from nav.local_control import ControlLimits
from nav.navigator import Estimate
from tasks.closed_loop import parts as P
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.navigation import EkfNavigation, NavOutput, initial_covariance, report_of
from tasks.closed_loop.result import MissionRun
from tasks.closed_loop.scenario import MissionScenario, NavigationConfig
from tasks.closed_loop.world import fly, place_vehicle, scenario_sea, single_vehicle_scene, streams
from tasks.core import store
from tasks.core.files import atomic_write_bytes
from tasks.core.registry import MemoryTerm, ReportContext, ReportSummary, register

if TYPE_CHECKING:
    from tasks.paper004.sim import LoopSetting

Array = NDArray[np.float64]

FILTERS = ("ekf", "upmf", "cmnf")
SEED_SPEED_M_S = 2.0
"""Seed 004's nominal speed (section 6), m/s: the path and the beacons scale by V° / this."""
SEED_START = np.array([0.0, 0.0, -10.0])
"""Seed 004's nominal start X°_0, m."""
SEED_BEACONS = np.array(
    [[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], [-100.0, -100.0, 0.0]]
)
"""Seed 004's beacons X_B^1..4 (section 6), m."""
SEABED_PRESET = {
    "half_extent_m": 250.0,
    "cell_m": 0.5,
    "relief_std_m": 0.4,
    "min_wavelength_m": 8.0,
    "max_wavelength_m": 40.0,
}
"""The mission's seabed (module docstring): the scene's generated bathymetry (6 m at the origin,
5 m per km) over +-250 m (the beacons are 190 m east and 110 m west of the origin), in cells of
0.5 m, with 0.4 m of relief in wavelengths of 8-40 m, the size of the multibeam's footprint (1-9 m
ahead from 1.8-4.8 m above the seabed): on the default scene's 60-600 m relief in 10 m cells an
image sees one or two planar triangles, which leave the along-seabed shift unobserved."""
SURROGATE_RUN_OFFSET = 1_000_000
"""Run indices of the surrogate's test paths start here (apart from the physics runs)."""


class Seed004Config(Config):
    """The seed-004 mission: scaled path and beacons, control limits, the CMNF's surrogate."""

    speed_m_s: float = Field(1.0, gt=0, le=1.5, description="nominal speed V°, m/s")
    duration_s: float = Field(160.0, gt=0, le=300, description="length of the path, s")
    dt_s: float = Field(1.0, gt=0, le=10, description="filter and control step (DOA period), s")
    beacon_depth_m: float = Field(0.3, ge=0, description="beacons' depth below the surface, m")
    max_turn_rate_deg_s: float = Field(10.0, gt=0, description="box limit on theta's rate")
    max_pitch_rate_deg_s: float = Field(2.0, gt=0, description="box limit on gamma's rate")
    max_gamma_deg: float = Field(10.0, gt=0, lt=90, description="box limit on |gamma|, deg")
    v_min_m_s: float = Field(0.5, ge=0, description="box limit: smallest speed, m/s")
    v_max_m_s: float = Field(1.3, gt=0, le=2, description="box limit: largest speed, m/s")
    sigma_w_m: tuple[float, float, float] = Field(
        (0.3, 0.3, 0.1),
        description="per-step process noise of the surrogate and the filters (S^W), m",
    )
    sigma_x0_m: tuple[float, float, float] = Field(
        (1.0, 1.0, 0.05), description="filters' initial sigma about the nominal start (S_0), m"
    )
    slope_basis: Literal["quadratic", "plane", "harmonic"] = Field(
        "quadratic",
        description="Appendix A's basis of the seabed fit for the seabed-sensing prediction "
        "(the scene's relief is no sum of known harmonics: a local quadratic by default)",
    )
    diverge_m: float = Field(
        50.0,
        gt=0,
        description="a filter whose estimate is farther than this from the nominal point has "
        "diverged: the flight stops with that named failure, m",
    )
    train_paths: int = Field(2000, ge=50, le=100_000, description="CMNF training paths")
    surrogate_test_paths: int = Field(
        2000, ge=10, le=100_000, description="fresh surrogate paths for the CMNF's J-bar"
    )


class Seed004Navigation(NavigationConfig):
    """The standard navigation settings plus the seed-004 filter that steers."""

    filter: Literal["ekf", "upmf", "cmnf", "all"] = Field(
        "all", description="the filter guidance steers on; 'all' flies each in turn per run"
    )
    prediction: Literal["system", "seabed"] = Field(
        "system",
        description="the filters' prediction: by virtue of the system (eq. 1, Table 1 row 1) or "
        "the seabed shift from two multibeam images (eq. 15, row 2)",
    )


class Seed004Scenario(MissionScenario):
    """A mission scenario with seed 004's section and DOA receiver."""

    seed004: Seed004Config = Field(default_factory=Seed004Config)
    doa: DoaConfig = Field(default_factory=DoaConfig, description="DOA receiver (seed 004)")
    multibeam: MultibeamConfig = Field(
        default_factory=MultibeamConfig,
        description="multibeam (seed 004's beams and range noise; used by the seabed prediction)",
    )
    navigation: Seed004Navigation = Field(default_factory=Seed004Navigation)


# ---------------------------------------------------------------------------------------------
# Geometry of the scaled mission


def path_config(scn: Seed004Scenario) -> NominalPathConfig:
    """The nominal path of the mission (seed 004, eq. 3, scaled; module docstring)."""
    c, st = scn.seed004, scn.start
    return NominalPathConfig(
        speed_m_s=c.speed_m_s,
        start_m=(st.east_m, st.north_m, -st.depth_m),
        dt_s=c.dt_s,
        duration_s=c.duration_s,
    )


def beacons_world(scn: Seed004Scenario) -> Array:
    """The beacons: seed 004's scaled by ``V° / 2`` about the start, ``beacon_depth_m`` below the
    surface, shape (4, 3), m, world (x east, y north, z up)."""
    c, st = scn.seed004, scn.start
    k = c.speed_m_s / SEED_SPEED_M_S
    b = np.array([st.east_m, st.north_m, 0.0]) + k * (SEED_BEACONS - [*SEED_START[:2], 0.0])
    b[:, 2] = -c.beacon_depth_m
    return b


def beacon_specs(scn: Seed004Scenario) -> tuple[BeaconSpec, ...]:
    """The beacons as scene sites, moored so that they sit at :func:`beacons_world` (names
    ``beacon_0..3`` in the seed's order, which is also the DOA's name order).

    Raises:
        ConfigError: if the water is not deep enough at a beacon.
    """
    bed = seabed.generate(scn.seabed)
    out = []
    for i, (e, n, z) in enumerate(beacons_world(scn)):
        try:
            floor = float(bed.height_world(e, n))
        except GeometryError as exc:
            raise ConfigError(f"beacon {i} at east {e:g} m, north {n:g} m: {exc}") from None
        if z < floor:
            raise ConfigError(
                f"seed004.beacon_depth_m = {scn.seed004.beacon_depth_m:g}: beacon {i} would be "
                f"below the seabed ({-floor:.2f} m deep there)"
            )
        out.append(
            BeaconSpec(name=f"beacon_{i}", east_m=e, north_m=n, height_above_seabed_m=z - floor)
        )
    return tuple(out)


def limits_of(c: Seed004Config) -> ControlLimits:
    """The control's box (seed 004, section 3)."""
    return ControlLimits(
        max_turn_rate=math.radians(c.max_turn_rate_deg_s),
        max_pitch_rate=math.radians(c.max_pitch_rate_deg_s),
        max_gamma=math.radians(c.max_gamma_deg),
        v_min=c.v_min_m_s,
        v_max=c.v_max_m_s,
    )


def surrogate(scn: Seed004Scenario) -> LoopSetting:
    """The kinematic surrogate of the mission (the CMNF is trained on it): with the seabed
    prediction it images the scene's heightfield with the mission's multibeam
    (``prediction = "heightfield"``).

    ``tasks.paper004`` is imported here, not at module level: importing ``tasks.missions`` must
    register the missions only (its experiments register when it is imported)."""
    from tasks.paper004.sim import LoopSetting

    c = scn.seed004
    az = scn.doa.azimuth.sigma_deg
    return LoopSetting(
        path=path_config(scn),
        noise=Seed004Noise(
            sigma_w_m=c.sigma_w_m,
            sigma_x0_m=c.sigma_x0_m,
            bearing_sigma_deg=az,
            min_rho_m=scn.doa.min_horizontal_m,
            max_tan=scn.doa.max_tangent,
        ),
        beacons=tuple(tuple(float(v) for v in b) for b in beacons_world(scn)),
        limits=limits_of(c),
        train_paths=c.train_paths,
        **(
            {
                "prediction": "heightfield",
                "heightfield": scn.seabed,
                "multibeam": scn.multibeam,
                "slope_basis": c.slope_basis,
            }
            if scn.navigation.prediction == "seabed"
            else {}
        ),
    )


@functools.lru_cache(maxsize=4)
def _gains(key: str, seed: int, s: LoopSetting) -> CmnfGains:
    from tasks.paper004.sim import train_gains

    return train_gains(s, seed)[0]


def gains_for(scn: Seed004Scenario, seed: int) -> CmnfGains:
    """The CMNF gains of the mission's surrogate (trained once per process and setting)."""
    s = surrogate(scn)
    return _gains(s.key(), seed, s)


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
    ``shift_beams`` (beams the seabed shift used; 0: none).

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
        if initial:
            self.depth_cmd = depth_setpoint(out.depth_m, self.u[0], self.ap)
        elif at_step and self.j < j <= self.n_steps:
            y, present = self._bearings(tick)
            self.absent_total += int((~present).sum())
            self.missing_sets += int(not present.any())
            if self.sonar is None:
                shift = self.pred(j - 1, self.x_hat, self.u)
            else:
                shift = self.sonar(self.x_hat, self.u)
            self.shift = shift.displacement_m[0].copy()
            if self.name == "cmnf":
                alpha = self.x_hat + shift.displacement_m
                _, self.x_hat = cmnf_step(
                    self.gains, j, alpha, self.s.correction, y, present, self.beacons
                )
                self.P = self.gains.p_hat[j - 1][None].copy()
            else:
                x_t, p_t = predict(self.x_hat, self.P, shift)
                update = ekf_update if self.name == "ekf" else upmf_update
                self.x_hat, self.P = update(x_t, p_t, y, present, self.beacons, self.s_eps)
            self.j = j
            from nav.errors import NavError

            if not (np.isfinite(self.x_hat).all() and np.isfinite(self.P).all()):
                raise NavError(f"{self.name.upper()} diverged: estimate not finite at step {j}")
            off = float(np.linalg.norm(self.x_hat[0] - self.nominal[j]))
            if off > self.diverge_m:
                raise NavError(
                    f"{self.name.upper()} diverged at step {j}: estimate {off:.0f} m from the "
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
        return dataclasses.replace(out, estimate=est, report=report)

    def outcome(self) -> dict[str, Any]:
        return {"absent_pairs": self.absent_total, "missing_sets": self.missing_sets}


EXTRA_COLUMNS = {
    "control": (
        "control",
        "rad, rad, m/s",
        "locally optimal control (gamma, theta, V)",
        ("gamma", "theta", "speed"),
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
"""Per-tick columns the mission adds."""


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
            devices, physics, "bauv", seed, run, "", extra={"odometry": {"speed_table": table}}
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
        return P.MissionParts([v], scenario_sea(scn, seed, run))


# ---------------------------------------------------------------------------------------------
# Metrics of one flight


def distance_to_polyline(points: Array, line: Array) -> Array:
    """Distance of each point to a polyline.

    Args:
        points: shape (n, 3), m.
        line: vertices, shape (m, 3), m (m >= 2).

    Returns:
        Shape (n,), m: the distance to the nearest point of any segment.
    """
    a, b = line[:-1], line[1:]
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    ap = points[:, None, :] - a[None]
    t = np.clip(np.einsum("nij,ij->ni", ap, ab) / L2, 0.0, 1.0)
    near = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - near, axis=2).min(axis=1)


def flight_metrics(
    run: MissionRun, nominal: Array, dt: float, seabed_shift: bool = False
) -> dict[str, Any]:
    """Path following and estimation of one flight (NaN never: missing data gives ``None``).

    Args:
        run: the flight.
        nominal: the nominal path, shape (N + 1, 3), m.
        dt: filter step, s.
        seabed_shift: the flight predicted with the seabed shift (adds its errors).

    Returns:
        ``path_mean_m`` / ``path_max_m`` (distance of the truth to the nominal path, every
        control tick), ``j_k`` (``||X°_k - X_k||^2`` at the filter steps, list, m^2),
        ``est_rmse_m`` / ``est_max_m`` (``||X_k - X^_k||`` at the filter steps), ``residual_std_m``
        (per axis, of ``X_{k+1} - X_k - V(u_k) dt``), ``steps`` reached, and with
        ``seabed_shift``: ``shift_err_m`` (the seabed shift less the true move of the reference
        point at each filter step with a shift, ``(n, 3)`` float32, m), ``shift_beams_mean`` and
        ``shift_none`` (steps after the first without a shift).
    """
    v = run.lead
    seen = {k: int(v.outcome.get(k, 0)) for k in ("absent_pairs", "missing_sets")}
    c = v.ticks
    x = np.asarray(c["truth_pos"].values, float)
    xh = np.asarray(c["ekf_pos"].values, float)
    k = np.asarray(c["filter_step"].values, float)
    u = np.asarray(c["control"].values, float)
    sel = np.flatnonzero(k >= 0)
    ks = k[sel].astype(int)
    if len(x) < 2 or len(sel) < 2:
        return {"steps": int(ks.max()) if len(ks) else 0, **seen}
    d = distance_to_polyline(x, nominal)
    xk = x[sel]
    e = np.linalg.norm(xk - xh[sel], axis=1)
    jk = np.sum((xk - nominal[ks]) ** 2, axis=1)
    # the control applied over step j is the one logged at step j
    res = xk[1:] - xk[:-1] - velocity(u[sel][:-1]) * dt
    return {
        "steps": int(ks.max()),
        "path_mean_m": float(d.mean()),
        "path_max_m": float(d.max()),
        "j_k": [float(a) for a in jk],
        "est_rmse_m": float(np.sqrt(np.mean(e[1:] ** 2))),
        "est_max_m": float(e[1:].max()),
        "est_rmse_axis_m": [float(a) for a in np.sqrt(np.mean((xk - xh[sel])[1:] ** 2, axis=0))],
        "residual_std_m": [float(a) for a in res.std(axis=0)],
        "residual_mean_m": [float(a) for a in res.mean(axis=0)],
        "track": xk.astype(np.float32),
        **seen,
        **(_shift_errors(c, sel, xk) if seabed_shift else {}),
    }


def _shift_errors(c, sel: NDArray[np.int_], xk: Array) -> dict[str, Any]:
    """The seabed shift's own error at the filter steps that had one (:func:`flight_metrics`)."""
    if "shift_beams" not in c:
        return {}
    beams = np.asarray(c["shift_beams"].values, float)[sel][1:]
    shift = np.asarray(c["shift"].values, float)[sel][1:]
    used = beams > 0
    err = (shift - (xk[1:] - xk[:-1]))[used]
    return {
        "shift_err_m": err.astype(np.float32),
        "shift_beams_mean": float(beams[used].mean()) if used.any() else 0.0,
        "shift_none": int((~used[1:]).sum()),
    }


@store.plain_data("missions.seed004.Seed004RunResult")
@dataclass
class Seed004RunResult:
    """One run: per filter, the flight's metrics (plain data).

    Attributes:
        run: run index.
        failed: per filter, the failure or ``None``.
        metrics: per filter, :func:`flight_metrics`.
    """

    run: int
    failed: dict[str, str | None]
    metrics: dict[str, dict[str, Any]] = field(default_factory=dict)


class FilterSummary(BaseModel):
    """One filter over the batch."""

    runs_ok: int
    path_mean_m: float | None = Field(description="mean over runs of the mean distance, m")
    path_max_m: float | None = Field(description="max over runs of the max distance, m")
    path_max_mean_m: float | None = Field(description="mean over runs of the max distance, m")
    est_rmse_m: float | None = Field(description="RMS estimation error at the filter steps, m")
    est_max_m: float | None = Field(description="max estimation error over runs and steps, m")
    est_rmse_axis_m: list[float] | None = Field(description="RMS error per axis (x, y, z), m")
    j_bar_m2: float | None = Field(description="max_k mean over runs ||X°_k - X_k||^2, m^2")
    j_mean_m2: float | None = Field(description="mean_k mean over runs ||X°_k - X_k||^2, m^2")
    residual_std_m: list[float] | None = Field(description="physics step residual std, m")
    residual_mean_m: list[float] | None = Field(description="physics step residual mean, m")
    diverged_runs: int = Field(0, description="runs whose flight stopped on a named failure")
    shift_steps: int = Field(0, description="filter steps with a seabed shift (all runs)")
    shift_err_median_m: float | None = Field(None, description="median |shift error|, m")
    shift_err_p90_m: float | None = Field(None, description="90th percentile |shift error|, m")
    shift_err_bias_m: list[float] | None = Field(None, description="mean shift error, m")
    shift_beams_mean: float | None = Field(None, description="beams used per shift, mean")
    shift_none_steps: int = Field(0, description="filter steps without a shift (no echoes)")


class Seed004Metrics(BaseModel):
    """``metrics.json`` of ``mission/seed004``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    prediction: Literal["system", "seabed"] = "system"
    filters: dict[str, FilterSummary]
    cmnf_j_bar_surrogate_m2: float | None = Field(description="CMNF J-bar on the surrogate")
    cmnf_j_bar_physics_m2: float | None
    cmnf_gap_m2: float | None = Field(description="physics minus surrogate J-bar, m^2")
    cmnf_j_mean_surrogate_m2: float | None = Field(description="CMNF time-mean J, surrogate")
    cmnf_j_mean_physics_m2: float | None
    cmnf_j_mean_gap_m2: float | None = Field(description="physics minus surrogate mean J, m^2")
    surrogate_shift: dict[str, Any] = Field(
        default_factory=dict,
        description="the seabed shift's error on the CMNF's surrogate paths (median, p90, bias)",
    )
    cmnf_train_paths: int
    failures: list[str]
    warnings: list[str]


def _mean(vals: list[float]) -> float | None:
    return float(np.mean(vals)) if vals else None


def _shift_summary(results: list[Seed004RunResult], name: str) -> dict[str, Any]:
    """The seabed shift's own error pooled over the filter steps of every run (failed ones too:
    the shift does not depend on the filter's success)."""
    all_m = [r.metrics[name] for r in results if name in r.metrics]
    errs = [np.asarray(m["shift_err_m"], float) for m in all_m if "shift_err_m" in m]
    out: dict[str, Any] = {
        "diverged_runs": sum(1 for r in results if r.failed.get(name) is not None),
        "shift_none_steps": sum(int(m.get("shift_none", 0)) for m in all_m),
    }
    err = np.concatenate(errs) if errs else np.zeros((0, 3))
    if len(err):
        norm = np.linalg.norm(err, axis=1)
        beams = [m["shift_beams_mean"] * len(m["shift_err_m"]) for m in all_m if "shift_err_m" in m]
        out |= {
            "shift_steps": len(err),
            "shift_err_median_m": float(np.median(norm)),
            "shift_err_p90_m": float(np.quantile(norm, 0.9)),
            "shift_err_bias_m": [float(a) for a in err.mean(axis=0)],
            "shift_beams_mean": float(sum(beams) / len(err)),
        }
    return out


def summarise_filter(results: list[Seed004RunResult], name: str) -> FilterSummary:
    """A filter's summary over the runs that completed (the seabed shift's error and the
    diverged runs over all)."""
    ms = [r.metrics[name] for r in results if r.failed.get(name) is None and name in r.metrics]
    ms = [m for m in ms if "path_mean_m" in m]
    shift = _shift_summary(results, name)
    if not ms:
        return FilterSummary(
            **shift,
            runs_ok=0,
            path_mean_m=None,
            path_max_m=None,
            path_max_mean_m=None,
            est_rmse_m=None,
            est_max_m=None,
            j_bar_m2=None,
            j_mean_m2=None,
            residual_std_m=None,
            residual_mean_m=None,
            est_rmse_axis_m=None,
        )
    n = min(len(m["j_k"]) for m in ms)
    jk = np.mean([m["j_k"][:n] for m in ms], axis=0)
    jbar, jmean = float(np.max(jk)), float(np.mean(jk))
    return FilterSummary(
        **shift,
        runs_ok=len(ms),
        path_mean_m=_mean([m["path_mean_m"] for m in ms]),
        path_max_m=float(max(m["path_max_m"] for m in ms)),
        path_max_mean_m=_mean([m["path_max_m"] for m in ms]),
        est_rmse_m=float(np.sqrt(np.mean([m["est_rmse_m"] ** 2 for m in ms]))),
        est_max_m=float(max(m["est_max_m"] for m in ms)),
        est_rmse_axis_m=[
            float(a) for a in np.sqrt(np.mean([np.square(m["est_rmse_axis_m"]) for m in ms], 0))
        ],
        j_bar_m2=jbar,
        j_mean_m2=jmean,
        residual_std_m=[float(a) for a in np.mean([m["residual_std_m"] for m in ms], axis=0)],
        residual_mean_m=[float(a) for a in np.mean([m["residual_mean_m"] for m in ms], axis=0)],
    )


def surrogate_j(
    scn: Seed004Scenario, seed: int, gains: CmnfGains
) -> tuple[float | None, float | None, dict[str, Any]]:
    """The CMNF's J-bar (``max_k``) and time-mean J (``mean_k`` of ``E||X°_k - X_k||^2``) on
    fresh surrogate paths, m^2 (the definitions used on physics; ``None`` if a path diverged),
    and with the seabed prediction the surrogate's own shift error (``shift_err_median_m``,
    ``shift_err_p90_m`` to the histogram's 0.05 m bins, ``shift_err_bias_m``)."""

    from tasks.paper004.sim import SHIFT_BIN_M
    from tasks.paper004.sim import fly as fly_surrogate

    s = surrogate(scn)
    n = scn.seed004.surrogate_test_paths
    runs = tuple(range(SURROGATE_RUN_OFFSET, SURROGATE_RUN_OFFSET + n))
    sums = fly_surrogate(s, seed, runs, gains, filters=("CMNF",), sample_runs=0)
    shift: dict[str, Any] = {}
    if sums.shift_n[0] > 0:
        c = np.cumsum(sums.shift_hist[0]) / sums.shift_hist[0].sum()
        shift = {
            "shift_err_median_m": float((np.searchsorted(c, 0.5) + 0.5) * SHIFT_BIN_M),
            "shift_err_p90_m": float((np.searchsorted(c, 0.9) + 0.5) * SHIFT_BIN_M),
            "shift_err_bias_m": [float(v) for v in sums.shift_err[0] / sums.shift_n[0]],
        }
    ok = sums.count[0] > 0
    if not ok.all():
        return None, None, shift
    j = sums.j[0] / sums.count[0]
    return float(np.max(j)), float(np.mean(j)), shift


PITCH_MARGIN_DEG = 5.0
"""Hull pitch beyond ``seed004.max_gamma_deg`` allowed for in :func:`check_multibeam` (the hull
pitches by up to ~13 deg at |gamma| <= 10 deg, the tail beat included)."""


def check_multibeam(scn: Seed004Scenario, bed: seabed.Seabed) -> None:
    """The seabed must be within the multibeam's range all along the nominal path, the sonar
    must image once per filter step, and an image must have more beams than Appendix A's fit
    has unknowns.

    The longest beam of an image is the shallowest, at ``min |gamma^i| - max_gamma -
    PITCH_MARGIN_DEG`` below the horizontal; over the seabed ``h`` below the path it reaches the
    bottom after about ``h / sin`` of that angle.

    Raises:
        ConfigError: naming the field, the value and what is allowed.
    """
    c, mb = scn.seed004, scn.multibeam
    if abs(mb.period_s - c.dt_s) > 1e-9:
        raise ConfigError(
            f"multibeam.period_s = {mb.period_s:g}: must equal seed004.dt_s = {c.dt_s:g} (one "
            "image per filter step)"
        )
    steep = float(np.min(np.abs(mb.elevations_rad())))
    worst = steep - math.radians(c.max_gamma_deg + PITCH_MARGIN_DEG)
    if worst <= math.radians(5.0):
        raise ConfigError(
            f"multibeam.elevation_deg = {mb.elevation_deg}: the shallowest beam must point at "
            f"least seed004.max_gamma_deg + {PITCH_MARGIN_DEG:g} + 5 deg below the hull's axis"
        )
    from nav.seabed import SlopeBasis

    beams = mb.beams_elevation * mb.beams_azimuth
    size = SlopeBasis(c.slope_basis).size  # type: ignore[arg-type]
    if beams <= size:
        raise ConfigError(
            f"multibeam.beams_elevation x multibeam.beams_azimuth = {mb.beams_elevation} x "
            f"{mb.beams_azimuth}: Appendix A's {c.slope_basis} fit (seed004.slope_basis) has "
            f"{size} unknowns; need more than {size} beams"
        )
    p = path_config(scn).path()
    try:
        floor = bed.height_world(p[:, 0], p[:, 1])
    except GeometryError as exc:
        raise ConfigError(f"seabed: the nominal path leaves the seabed grid ({exc})") from None
    reach = (p[:, 2] - floor) / math.sin(worst)
    i = int(np.argmax(reach))
    if reach[i] > mb.max_range_m:
        raise ConfigError(
            f"multibeam.max_range_m = {mb.max_range_m:g}: the seabed is {reach[i]:.1f} m away "
            f"along the shallowest beam at step {i} of the nominal path ({-floor[i]:.2f} m deep "
            f"there); allowed: at least {math.ceil(reach.max())} m"
        )


HEIGHTFIELD_KEPT_BYTES_PER_POINT = 16.0
"""What the surrogate's heightfield keeps per grid point, bytes
(:func:`tasks.paper004.seabed.heightfield`, cached: the depths and MuJoCo's float32 heights
in float64; tracemalloc: 16.4 B per point, 48.4 B at its peak while generated)."""

IMAGE_BYTES_PER_PATH_BEAM = 470.0
"""Peak memory of the surrogate's multibeam images and seabed shift per path and beam, bytes
(:class:`tasks.paper004.seabed.HeightfieldPrediction`: the rays' march over the heightfield,
the two images, eq. 15; tracemalloc: 468-472 B for 8 x 8 to 32 x 32 beams)."""


@dataclass(frozen=True)
class Seed004Experiment(MissionExperiment):
    """Seed 004's filters steering the physical BAUV (one flight per filter and run)."""

    scenario_type = Seed004Scenario
    metrics_type = Seed004Metrics
    report_seabed = False  # its report records no seabed mesh

    def filters(self, scn: Seed004Scenario) -> tuple[str, ...]:
        f = scn.navigation.filter
        return FILTERS if f == "all" else (f,)

    def flight(self, scenario: Seed004Scenario, seed: int, run: int):
        """The flight of the first filter of ``navigation.filter`` (:meth:`run_block` flies
        each)."""
        f = self.filters(scenario)[0]
        return Seed004Mission(f, gains_for(scenario, seed) if f == "cmnf" else None), scenario

    def memory(self, scenario: Seed004Scenario, n_runs: int) -> list[MemoryTerm]:
        """The mission's terms (:meth:`MissionExperiment.memory`), and with the seabed
        prediction and the CMNF the surrogate's (:func:`surrogate`): its heightfield, kept in the
        process while the scene's own grid is generated (:data:`HEIGHTFIELD_KEPT_BYTES_PER_POINT`),
        and the multibeam images of ``seed004.train_paths`` training paths at once
        (:data:`IMAGE_BYTES_PER_PATH_BEAM`), in the worker; in the report too, which trains the
        gains again where the worker's are not at hand and flies
        ``seed004.surrogate_test_paths`` paths."""
        terms = super().memory(scenario, n_runs)
        if scenario.navigation.prediction != "seabed" or "cmnf" not in self.filters(scenario):
            return terms
        bed, mb, c = scenario.seabed, scenario.multibeam, scenario.seed004
        kept = HEIGHTFIELD_KEPT_BYTES_PER_POINT * float(bed.n) ** 2
        beams = mb.beams_elevation * mb.beams_azimuth
        train = IMAGE_BYTES_PER_PATH_BEAM * c.train_paths * beams
        test = IMAGE_BYTES_PER_PATH_BEAM * c.surrogate_test_paths * beams
        images = (
            f"seed004.train_paths = {c.train_paths} imaged with multibeam.beams_elevation x "
            f"beams_azimuth = {mb.beams_elevation} x {mb.beams_azimuth} beams"
        )
        return [
            *terms,
            MemoryTerm(kept, True, f"{bed.grid_text} (the surrogate's heightfield)"),
            MemoryTerm(kept, False, f"{bed.grid_text} (the surrogate's heightfield)"),
            MemoryTerm(train, True, images),
            MemoryTerm(
                train + test,
                False,
                f"{images}, seed004.surrogate_test_paths = {c.surrogate_test_paths}",
            ),
        ]

    def check(self, scenario: Seed004Scenario, n_runs: int) -> None:
        super().check(scenario, n_runs)
        c = scenario.seed004
        if c.v_min_m_s > c.v_max_m_s:
            raise ConfigError(
                f"seed004.v_min_m_s = {c.v_min_m_s:g}: must be <= seed004.v_max_m_s = "
                f"{c.v_max_m_s:g}"
            )
        path_config(scenario)
        beacon_specs(scenario)
        if abs(scenario.doa.period_s - c.dt_s) > 1e-9:
            raise ConfigError(
                f"doa.period_s = {scenario.doa.period_s:g}: must equal seed004.dt_s = {c.dt_s:g} "
                "(one bearing set per filter step)"
            )
        steps = c.dt_s / scenario.timing.control_tick_s
        if abs(steps - round(steps)) > 1e-9:
            raise ConfigError(
                f"seed004.dt_s = {c.dt_s:g}: must be a multiple of timing.control_tick_s = "
                f"{scenario.timing.control_tick_s:g}"
            )
        bed = seabed.generate(scenario.seabed)
        for i, (e, n, z) in enumerate(path_config(scenario).path()):
            try:
                floor = float(bed.height_world(e, n))
            except GeometryError:
                continue
            if z > 0 or z < floor + 1.0:
                raise ConfigError(
                    f"start.depth_m = {scenario.start.depth_m:g}: the nominal path at step {i} "
                    f"is at z = {z:.2f} m, out of the water column ({-floor:.2f} m deep there, "
                    "1 m clearance)"
                )
        if scenario.navigation.prediction == "seabed":
            check_multibeam(scenario, bed)

    def run_block(self, scenario: Seed004Scenario, seed: int, runs: tuple[int, ...]):
        nominal = path_config(scenario).path()
        dt = scenario.seed004.dt_s
        gains = gains_for(scenario, seed) if "cmnf" in self.filters(scenario) else None
        seabed = scenario.navigation.prediction == "seabed"
        out = []
        for r in runs:
            res = Seed004RunResult(r, {})
            for f in self.filters(scenario):
                design = Seed004Mission(f, gains if f == "cmnf" else None)
                flight = fly(design, scenario, seed, r)
                res.failed[f] = flight.failed
                res.metrics[f] = flight_metrics(flight, nominal, dt, seabed)
            out.append(res)
        return out

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_seed004(self, ctx)


def report_seed004(exp: Seed004Experiment, ctx: ReportContext) -> ReportSummary:
    """The per-filter table, the CMNF's surrogate-vs-physics gap, the gains and a figure."""
    from tasks.core.report import Table, write_metrics, write_tables

    scn: Seed004Scenario = ctx.scenario  # type: ignore[assignment]
    results: list[Seed004RunResult] = [r for b in ctx.blocks for r in b]
    names = exp.filters(scn)
    summ = {f: summarise_filter(results, f) for f in names}
    files: list[str] = []
    j_sur = j_phys = gap = m_sur = m_phys = m_gap = None
    sur_shift: dict[str, Any] = {}
    if "cmnf" in names:
        gains = gains_for(scn, ctx.seed)
        atomic_write_bytes(ctx.out_dir / "cmnf-gains.npz", gains.to_bytes())
        files.append("cmnf-gains.npz")
        j_sur, m_sur, sur_shift = surrogate_j(scn, ctx.seed, gains)
        j_phys, m_phys = summ["cmnf"].j_bar_m2, summ["cmnf"].j_mean_m2
        if j_sur is not None and j_phys is not None:
            gap, m_gap = j_phys - j_sur, m_phys - m_sur
    failures = [f"{f}: {m}" for r in results for f, m in r.failed.items() if m]
    warnings = []
    for f in names:
        gaps = [(r.run, r.metrics[f]) for r in results if f in r.metrics]
        absent = sum(m.get("absent_pairs", 0) for _, m in gaps)
        missing = sum(m.get("missing_sets", 0) for _, m in gaps)
        if absent:
            warnings.append(
                f"{f}: {absent} bearing pairs absent (beacon overhead, tangent beyond "
                f"doa.max_tangent, out of range or dropped), {missing} filter steps without any "
                "bearing (prediction only)"
            )
        if summ[f].runs_ok < ctx.n_runs:
            warnings.append(
                f"{f}: {ctx.n_runs - summ[f].runs_ok} of {ctx.n_runs} runs failed or have no "
                "data (see failures)"
            )
        if summ[f].shift_none_steps:
            warnings.append(
                f"{f}: {summ[f].shift_none_steps} filter steps without a seabed shift (too few "
                "beams with an echo in both images): the commanded displacement was predicted"
            )
    metrics = Seed004Metrics(
        experiment=exp.name,
        seed=ctx.seed,
        n_runs=ctx.n_runs,
        prediction=scn.navigation.prediction,
        filters=summ,
        cmnf_j_bar_surrogate_m2=j_sur,
        cmnf_j_bar_physics_m2=j_phys,
        cmnf_gap_m2=gap,
        cmnf_j_mean_surrogate_m2=m_sur,
        cmnf_j_mean_physics_m2=m_phys,
        cmnf_j_mean_gap_m2=m_gap,
        surrogate_shift=sur_shift,
        cmnf_train_paths=scn.seed004.train_paths,
        failures=failures,
        warnings=warnings,
    )
    files.append(write_metrics(ctx.out_dir, metrics))
    c = scn.seed004
    t = Table(
        f"Path following and estimation per filter ({ctx.n_runs} runs, {c.duration_s:g} s, "
        f"V° = {c.speed_m_s:g} m/s, box-limited eq. 7)",
        [
            "Filter",
            "Runs ok",
            "Mean dist. to path (m)",
            "Max dist. to path (m)",
            "Mean of run max (m)",
            "Est. RMSE (m)",
            "Est. max (m)",
            "J-bar physics (m^2)",
            "Mean J physics (m^2)",
        ],
        [
            [
                f.upper(),
                s.runs_ok,
                s.path_mean_m,
                s.path_max_m,
                s.path_max_mean_m,
                s.est_rmse_m,
                s.est_max_m,
                s.j_bar_m2,
                s.j_mean_m2,
            ]
            for f, s in summ.items()
        ],
        digits=2,
        slug="filters",
        note=(
            f"CMNF J-bar: surrogate {_fmt(j_sur)} m^2, physics {_fmt(j_phys)} m^2, gap "
            f"{_fmt(gap)} m^2; mean J: surrogate {_fmt(m_sur)}, physics {_fmt(m_phys)}, gap "
            f"{_fmt(m_gap)} m^2 (gains from {c.train_paths} surrogate paths, J on "
            f"{c.surrogate_test_paths} fresh ones)."
            if "cmnf" in names
            else "No CMNF flown."
        ),
    )
    tables = [t]
    if scn.navigation.prediction == "seabed":
        tables.append(
            Table(
                "Seabed-sensing prediction: the shift's own error (norm of the shift less the "
                "true move of the reference point, every filter step with a shift, all runs) and "
                "the flights that diverged",
                [
                    "Filter",
                    "Diverged runs",
                    "Steps with a shift",
                    "Steps without",
                    "Beams used",
                    "Median error (m)",
                    "P90 error (m)",
                    "Bias x (m)",
                    "Bias y (m)",
                    "Bias z (m)",
                ],
                [
                    [
                        f.upper(),
                        v.diverged_runs,
                        v.shift_steps,
                        v.shift_none_steps,
                        v.shift_beams_mean,
                        v.shift_err_median_m,
                        v.shift_err_p90_m,
                        *(v.shift_err_bias_m or [None] * 3),
                    ]
                    for f, v in summ.items()
                ],
                digits=2,
                slug="seabed-shift",
                note=(
                    f"Multibeam {scn.multibeam.beams_elevation} x {scn.multibeam.beams_azimuth} "
                    f"beams, range noise {scn.multibeam.range.sigma_m:g} m, Appendix A basis "
                    f"{c.slope_basis}; the two images of a shift are aimed from the hull's "
                    "attitudes at their pings (reading 'turning', exact beam change). On the "
                    "CMNF's surrogate paths: median "
                    f"{_fmt(sur_shift.get('shift_err_median_m'))} m, p90 "
                    f"{_fmt(sur_shift.get('shift_err_p90_m'))} m, bias "
                    f"{[round(v, 2) for v in sur_shift.get('shift_err_bias_m', [])]} m."
                ),
            )
        )
    if failures:
        tables.append(Table("Failed flights", ["Failure"], [[f] for f in failures], slug="failed"))
    files += write_tables(ctx.out_dir, tables, heading=f"{exp.name}: {exp.summary}")
    if scn.report.figures:
        rec = next((r for r in results if r.run == scn.report.record_run), None)
        if rec is not None:
            files += seed004_figure(exp.name, scn, rec, ctx.out_dir)
    text = t.to_text() + "\n"
    text += "".join(f"warning: {w}\n" for w in warnings)
    text += f"wrote {len(files)} files to {ctx.out_dir}\n"
    return ReportSummary(text, tuple(files))


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.2f}"


def seed004_figure(name: str, scn: Seed004Scenario, rec: Seed004RunResult, out) -> list[str]:
    """Nominal path, beacons and each filter's true track of the recorded run (plan and depth)."""
    from tasks.core import style

    with style.context():
        fig, (ax, az) = style.subplots("page", 3.2, 1, 2)
        nominal = path_config(scn).path()
        b = beacons_world(scn)
        ax.plot(nominal[:, 0], nominal[:, 1], "k--", lw=1.0, label="nominal")
        az.plot(np.arange(len(nominal)) * scn.seed004.dt_s, -nominal[:, 2], "k--", lw=1.0)
        ax.plot(b[:, 0], b[:, 1], "k^", label="beacons")
        for f, m in rec.metrics.items():
            tr = m.get("track")
            if tr is None:
                continue
            ax.plot(tr[:, 0], tr[:, 1], lw=0.8, label=f.upper())
            az.plot(np.arange(len(tr)) * scn.seed004.dt_s, -tr[:, 2], lw=0.8)
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize="small")
        az.set_xlabel("time (s)")
        az.set_ylabel("depth (m)")
        az.invert_yaxis()
        fig.suptitle(f"{name}: run {rec.run}")
        return style.save(fig, out / "paths.png")


register(
    Seed004Experiment(
        name="mission/seed004",
        summary="seed 004 on the BAUV: bearings to 4 beacons, EKF / UPMF / CMNF, locally optimal "
        "control with limits (160 s)",
        preset={
            "start": {
                "east_m": -60.0,
                "north_m": 0.0,
                "depth_m": 2.5,
                "heading_deg": 30.0,
                "speed_m_s": 1.0,
                "position_sigma_m": 1.0,
                "heading_sigma_deg": 3.0,
            },
            "current": {"kind": "uniform", "speed_m_s": 0.1, "direction_deg": 60.0},
            "seabed": SEABED_PRESET,
            "sensors": {"use_usbl": False, "use_gps": False},
            "guidance": {"waypoints": [{"east_m": 60.0, "north_m": 0.0, "depth_m": 2.5}]},
            "timing": {"max_duration_s": 170.0},
        },
        default_runs=8,
    )
)
