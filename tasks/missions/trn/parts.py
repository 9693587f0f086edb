"""``mission/trn``'s parts: the navigation part that runs every method side by side on one
flight, and the design that gives the vehicle its DVL (package docstring)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.build import SceneConfig
from bauv_sim.design.speed_table import load_speed_table
from bauv_sim.sensors.rig import RigTick, SensorRig
from nav.dvl import velocity_world_from_dvl
from nav.errors import NavError
from nav.navigator import Estimate
from nav.trn import (
    DvlAidedOptions,
    DvlAidedTrn,
    ParticleTrn,
    PointMassTrn,
    TerrainMap,
    TrnOptions,
    soundings,
)
from tasks.closed_loop import parts as P
from tasks.closed_loop.navigation import EkfNavigation, NavOutput, initial_covariance
from tasks.closed_loop.result import EstimateTrack
from tasks.closed_loop.world import (
    place_vehicle,
    scenario_sea,
    single_vehicle_scene,
    streams,
    waypoint_guidance,
)
from tasks.missions.trn.scenario import LABELS, METHODS, TrnScenario
from tasks.missions.trn.terrain import navigator_map

Array = NDArray[np.float64]

MODES = {0: "none", 1: "bottom", 2: "water"}
"""The DVL's modes (:class:`bauv_sim.sensors.dvl.DvlPing`)."""


@dataclass(frozen=True)
class TrnReport:
    """What :class:`TrnNavigation` reports at a tick (the per-tick columns of
    :data:`EXTRA_COLUMNS`): each method's position (east, north, up), m, world; the particle
    filter's horizontal covariance, m^2 (and the other methods', ``<method>_P``, but the log DR's);
    the DVL's mode (0 none, 1 bottom lock, 2 water track);
    whether a TRN update was made at this tick, the beams it used (particle filter), and the
    prediction covariance accumulated since the previous update (2 x 2, m^2)."""

    dr_log: Array
    dr_dvl: Array
    trn_pf: Array
    trn_pmf: Array
    ekf_log: Array
    usbl_ekf: Array
    trn_pf_P: Array
    dvl_mode: float
    trn_update: float
    trn_beams: float
    trn_q: Array
    trn_pmf_P: Array
    dr_dvl_P: Array
    ekf_log_P: Array
    usbl_ekf_P: Array


class TrnNavigation:
    """Every method of the mission on the same rig records (package docstring).

    * ``base`` (the standard part, :class:`~tasks.closed_loop.navigation.EkfNavigation`) gets the
      rig's records with the USBL fixes dropped from ``t_dive_s`` on: its EKF is the vehicle's
      navigator before the dive (USBL, log, compass, pressure) and the log EKF without fixes
      after it (``ekf_log``); its DR track restarts at the dive from the EKF's estimate:
      dead reckoning on the log (``dr_log``, heading + speed through water).
    * ``reference`` (another standard part with its own navigator, the same settings and start)
      gets every record, the USBL fixes after the dive included (the rig's USBL keeps pinging:
      only the vehicle's own navigator stops hearing it): the reference ``usbl_ekf``.
    * From the dive on, dead reckoning on the DVL (``dr_dvl``) and the two TRN filters start from
      the EKF's estimate and covariance; each DVL ping's velocity (bottom track, or water track
      when the DVL says so) is rotated to the world with the measured attitude
      (:func:`nav.dvl.velocity_world_from_dvl`, lever-arm term with the INS rates; the water
      track plus the current the log EKF learnt before the dive) and held over
      the interval since the previous ping: that displacement, with covariance ``(dt
      sigma)^2 I`` (``trn.sigma_velocity_m_s`` on bottom lock, ``sigma_water_track_m_s``
      without: the current is unknown), advances the DVL DR and predicts both filters; every
      ``update_period_s`` a bottom-lock ping's beams become soundings
      (:func:`nav.trn.soundings`, measured attitude, pressure depth) that update both filters
      against the navigator's map (that clock is :class:`nav.trn.DvlAidedTrn`'s). A ping
      without bottom lock updates nothing; a ping with neither mode holds the last velocity
      (counted).

    Args:
        base: the vehicle's standard part.
        reference: the reference's standard part.
        scn: the scenario.
        terrain_map: the navigator's map.
        seed: batch seed (the filters' stream).
        run: run index (the filters' stream).
    """

    def __init__(
        self,
        base: EkfNavigation,
        reference: EkfNavigation,
        scn: TrnScenario,
        terrain_map: TerrainMap,
        seed: int,
        run: int,
    ):
        self.base, self.reference, self.scn, self.map = base, reference, scn, terrain_map
        c = scn.trn
        self.t_dive = c.t_dive_s
        self.aided_options = DvlAidedOptions(
            update_period_s=c.update_period_s,
            sigma_bottom_m_s=c.sigma_velocity_m_s,
            sigma_water_m_s=c.sigma_water_track_m_s,
            sounding_sigma_m=c.sounding_sigma_m,
        )
        self.options = TrnOptions(
            particles=c.particles,
            grid_points=c.grid_points,
            sigma_bias_m=c.sigma_bias_m,
            reinit_sigma_m=c.reinit_sigma_m,
            reinitialise=c.reinitialise,
            divergence_probability=c.divergence_probability,
            nis_window=c.nis_window,
        )
        self.rng = rng_mod.generator(seed, run, "trn")
        self.started = False
        self.aided: DvlAidedTrn | None = None
        self.pf: ParticleTrn | None = None
        self.pmf: PointMassTrn | None = None
        self.velocity = np.zeros(3)
        self.counts = {k: 0 for k in ("pings", "bottom", "water", "none", "held", "updates")}
        self.counts |= {"unusable_updates": 0, "pf_reinit": 0, "pmf_reinit": 0, "beams_used": 0}
        self.counts |= {"pmf_unusable_updates": 0}
        self.beams: tuple[list, list] | None = None

    # -- one tick ------------------------------------------------------------------------------

    def _start(self, est: Estimate, t_s: float) -> None:
        x, P2 = est.x[:2].copy(), est.P[:2, :2].copy()
        self.pf = ParticleTrn(self.options, x, P2, self.rng)
        self.pmf = PointMassTrn(self.options, x, P2, self.rng)
        self.aided = DvlAidedTrn(self.aided_options, t_s, x, P2, (self.pf, self.pmf))
        self.base.nav.reset_dr(est.x)
        self.started = True

    def _ping(
        self, tick: RigTick, depth_m: float, current_m_s: Array | None
    ) -> tuple[int, Array | None, int]:
        """Predict with the DVL and update the filters at this tick (class docstring).

        Returns:
            The DVL's mode, the prediction covariance since the previous update if an update
            was due at this tick (else ``None``), the beams the particle filter used.
        """
        ping = next((m for m in tick.arrived if m.device == "dvl"), None)
        t = tick.t_s
        mode = 0
        if ping is not None:
            p = ping.payload
            mode = int(p.mode)
            if self.beams is None:
                self.beams = (
                    np.asarray(p.beam_directions_body, float).tolist(),
                    np.asarray(p.lever_arm_body_m, float).tolist(),
                )
            ins = tick.held["ins"]
            omega = np.array([ins[2], -ins[3], -ins[4]])  # INS rates back to body FLU
            self.velocity = velocity_world_from_dvl(
                np.asarray(p.velocity_body_m_s, float),
                np.asarray(ping.attitude_rad, float),
                omega,
                np.asarray(p.lever_arm_body_m, float),
            )
            if mode == 2 and current_m_s is not None:  # through the water: add the current
                self.velocity[:2] += current_m_s
        self.counts["pings"] += 1
        self.counts[MODES.get(mode, "none")] += 1
        if ping is None:
            self.counts["held"] += 1
        q = self.aided.advance(t, self.velocity, mode == 1)
        if q is None:
            return mode, None, 0
        beams = 0
        if ping is not None and mode == 1:
            p = ping.payload
            snd = soundings(
                p.beam_ranges_m,
                p.beam_echo,
                p.beam_directions_body,
                ping.attitude_rad,
                p.lever_arm_body_m,
                depth_m,
            )
            u, v = self.aided.update(self.map, snd)
            beams = int(u.used_beams)
            self.counts["beams_used"] += beams
            self.counts["unusable_updates"] += int(beams == 0)
            self.counts["pmf_unusable_updates"] += int(v.used_beams == 0)
            self.counts["pf_reinit"] += int(u.reinitialised)
            self.counts["pmf_reinit"] += int(v.reinitialised)
        else:
            self.counts["unusable_updates"] += 1
            self.counts["pmf_unusable_updates"] += 1
        self.counts["updates"] += 1
        return mode, q, beams

    def step(self, tick: RigTick, initial: bool = False) -> NavOutput:
        t = tick.t_s
        ref = self.reference.step(tick, initial)
        if t >= self.t_dive - 1e-9:
            tick = dataclasses.replace(
                tick, arrived=tuple(m for m in tick.arrived if m.device != "usbl")
            )
        out = self.base.step(tick, initial)
        mode, updated, beams = 0, False, 0
        q = np.zeros((2, 2))
        if not self.started and t >= self.t_dive - 1e-9:
            self._start(out.estimate, t)
            out = dataclasses.replace(out, dr_position_m=self.base.nav.dr_position)
        elif self.started:
            mode, q_update, beams = self._ping(tick, out.depth_m, out.current_m_s)
            if q_update is not None:
                updated, q = True, q_update
        z = out.estimate.x[2]
        if self.started:
            pf_x, pf_P = self.pf.estimate()
            pmf_x, pmf_P = self.pmf.estimate()
            dvl_x = self.aided.dr.position
            dr_log = out.dr_position_m
        else:
            pf_x = pmf_x = dvl_x = out.estimate.x[:2]
            pf_P = pmf_P = out.estimate.P[:2, :2]
            dr_log = out.estimate.x
        est = {
            "dr_log": np.asarray(dr_log, float).copy(),
            "dr_dvl": np.array([*dvl_x, z]),
            "trn_pf": np.array([*pf_x, z]),
            "trn_pmf": np.array([*pmf_x, z]),
            "ekf_log": out.estimate.x.copy(),
            "usbl_ekf": ref.estimate.x.copy(),
        }
        for k, v in est.items():
            if not np.all(np.isfinite(v)):
                raise NavError(f"{k} estimate not finite at t = {t:.2f} s")
        covs = {
            "trn_pf": pf_P,
            "trn_pmf": pmf_P,
            "dr_dvl": self.aided.dr.covariance if self.started else out.estimate.P[:2, :2],
            "usbl_ekf": ref.estimate.P[:2, :2],
        }
        steer = self.scn.navigation.steer
        P3 = out.estimate.P.copy()
        if steer in covs:
            P3[:2, :2] = covs[steer]
            P3[:2, 2] = P3[2, :2] = 0.0
        report = TrnReport(
            **est,
            trn_pf_P=np.asarray(pf_P, float).copy(),
            dvl_mode=float(mode),
            trn_update=float(updated),
            trn_beams=float(beams),
            trn_q=q,
            trn_pmf_P=np.asarray(pmf_P, float).copy(),
            dr_dvl_P=np.asarray(covs["dr_dvl"], float).copy(),
            ekf_log_P=out.estimate.P[:2, :2].copy(),
            usbl_ekf_P=np.asarray(covs["usbl_ekf"], float).copy(),
        )
        return dataclasses.replace(out, estimate=Estimate(t, est[steer], P3), report=report)

    def outcome(self) -> dict[str, Any]:
        """The counts of :meth:`_ping` and the DVL's nominal beams and lever arm (for the bound
        along the true track, :func:`tasks.missions.trn.terrain.pcrb_track`)."""
        out: dict[str, Any] = dict(self.counts)
        if self.beams is not None:
            out["beam_directions_body"], out["dvl_lever_arm_body_m"] = self.beams
        return out


EN = ("east", "north")

EXTRA_COLUMNS: dict[str, tuple[str, str, str, tuple[str, ...], bool]] = {
    **{
        m: (m, "m", f"{m} position estimate (world)", ("east", "north", "up"), False)
        for m in METHODS
    },
    **{
        f"{m}_P": (f"{m}_P", "m^2", f"{what} horizontal position covariance, world", EN, False)
        for m, what in (
            ("trn_pf", "particle TRN's"),
            ("trn_pmf", "point-mass TRN's"),
            ("dr_dvl", "DVL dead reckoning's"),
            ("ekf_log", "log EKF's"),
            ("usbl_ekf", "reference USBL EKF's"),
        )
    },
    "dvl_mode": ("dvl_mode", "1", "DVL mode: 0 none, 1 bottom lock, 2 water track", (), False),
    "trn_update": ("trn_update", "1", "a TRN update at this tick (1) or not (0)", (), False),
    "trn_beams": ("trn_beams", "1", "beams the particle TRN update used", (), False),
    "trn_q": ("trn_q", "m^2", "TRN prediction covariance since the last update", EN, False),
}
"""Per-tick columns the mission adds (:class:`TrnReport`): every method's position, and the
horizontal covariance of each but ``dr_log`` (before the dive the EKF's)."""

ESTIMATES = (
    EstimateTrack("ekf_pos", "EKF", "ekf_P"),
    *(
        EstimateTrack(m, LABELS[m], f"{m}_P" if f"{m}_P" in EXTRA_COLUMNS else None)
        for m in METHODS
    ),
)
"""The estimates the recording draws: the vehicle's EKF (USBL until the dive, the log EKF after
it) with its covariance, and every method with its horizontal covariance (the log DR has none)."""


@dataclass(frozen=True)
class TrnMission:
    """The design: one BAUV with the standard rig plus the DVL, flying the survey on
    ``navigation.steer``."""

    def vehicle_names(self, scenario: TrnScenario) -> tuple[str, ...]:
        return ("bauv",)

    def scene(self, scenario: TrnScenario) -> SceneConfig:
        return single_vehicle_scene(scenario, ())

    def build(self, scn: TrnScenario, seed: int, run: int, physics) -> P.MissionParts:
        table = load_speed_table()
        pos = place_vehicle(physics, scn.start, seed, run, "bauv")
        s = scn.sensors
        devices = {"compass": s.compass, "ins": s.ins}
        if s.use_log:
            devices["log"] = s.log
        devices |= {"odometry": s.odometry, "pressure": s.pressure, "dvl": s.dvl}
        if s.use_usbl:
            devices["usbl"] = s.usbl
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
        arms, tr = rig.lever_arms_body_m, physics.transceiver_world()
        base = EkfNavigation(n, pos + e0, tr, arms, use_gps=False)
        reference = EkfNavigation(n, pos + e0, tr, arms, use_gps=False)
        nav = TrnNavigation(base, reference, scn, navigator_map(scn, seed), seed, run)
        guidance = P.WaypointSteering(waypoint_guidance(scn, rig), "ekf")
        v = P.VehicleParts("bauv", rig, nav, guidance, scn.autopilot, table)
        v.extra_columns = EXTRA_COLUMNS
        v.estimates = ESTIMATES
        return P.MissionParts([v], scenario_sea(scn, seed, run))
