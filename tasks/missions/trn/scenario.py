"""``mission/trn``'s scenario: the survey over relief, the DVL, the navigator's map and the
terrain-relative navigation filters (package docstring)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.currents import CurrentConfig, UniformCurrentConfig
from bauv_sim.sensors import AngleErrorConfig, CompassConfig, check_multiple
from tasks.closed_loop.scenario import MissionScenario, MissionSensors, NavigationConfig

METHODS = ("dr_log", "dr_dvl", "trn_pf", "trn_pmf", "ekf_log", "usbl_ekf")
"""The estimates computed side by side on every flight, as the metrics name them: dead reckoning
on the log (heading + speed through water), dead reckoning on the DVL (velocity over ground),
DVL + particle TRN, DVL + point-mass TRN, the log EKF with the current it learnt before the dive
(no fix after it) and the reference USBL EKF (fixes all along)."""

LABELS = {
    "dr_log": "DR-log",
    "dr_dvl": "DR-DVL",
    "trn_pf": "TRN-PF",
    "trn_pmf": "TRN-PMF",
    "ekf_log": "EKF-log",
    "usbl_ekf": "USBL-EKF",
}
"""The methods' names in tables, figures and the style table."""

TRN_METHODS = ("trn_pf", "trn_pmf")
"""The TRN filters (check 4's verdicts)."""

SEABED_PRESET = {
    "half_extent_m": 300.0,
    "cell_m": 1.0,
    "depth_at_origin_m": 14.0,
    "slope": 0.0,
    "relief_std_m": 1.5,
    "n_modes": 24,
    "min_wavelength_m": 20.0,
    "max_wavelength_m": 120.0,
    "min_depth_m": 4.5,
}
"""The mission's seabed: 14 m deep, flat on average (``slope`` 0, so a zero relief is a flat
seabed), with 1.5 m of relief in wavelengths of 20-120 m (slopes of ~0.1-0.3, what a TRN
needs: Meduna 2011's gradients), in cells of 1 m over +-300 m (the survey spans +-100 m). The
vehicle at 4 m is ~10 m above it, well inside the DVL's lock range (0.3-60 m)."""

SURVEY_WAYPOINTS = [
    {"east_m": 80.0, "north_m": -40.0, "depth_m": 4.0, "acceptance_radius_m": 6.0},
    {"east_m": 80.0, "north_m": 0.0, "depth_m": 4.0, "acceptance_radius_m": 6.0},
    {"east_m": -80.0, "north_m": 0.0, "depth_m": 4.0, "acceptance_radius_m": 6.0},
    {"east_m": -80.0, "north_m": 40.0, "depth_m": 4.0, "acceptance_radius_m": 6.0},
    {"east_m": 80.0, "north_m": 40.0, "depth_m": 4.0, "acceptance_radius_m": 6.0},
]
"""The survey: three 160 m legs 40 m apart (a lawn-mower, ~570 m, ~9.5 min at 1 m/s)."""


class TrnMissionSensors(MissionSensors):
    """The standard rig with the DVL (``sensors.dvl``; ``use_dvl`` must stay true); the compass
    has a residual 1 deg calibration bias by default (what makes dead reckoning on the DVL drift:
    ~1.7 % of the distance run, the slow error TRN bounds)."""

    use_dvl: bool = Field(True, description="the rig carries the DVL (required by this mission)")

    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2, heading=AngleErrorConfig(sigma_deg=2.0, bias_deg=1.0)
        ),
        description="VN-100 class compass/AHRS: 2 deg noise, 1 deg residual bias",
    )


class MapConfig(Config):
    """The navigator's bathymetry map: a degraded copy of the true seabed
    (:func:`nav.trn.degraded`: coarser grid, node noise, a common offset), never the truth."""

    cell_m: float = Field(2.0, gt=0, description="node spacing of the map, m")
    vertical_sigma_m: float = Field(0.1, ge=0, description="per-node vertical error, m")
    offset_m: float = Field(0.3, description="common vertical offset (datum, tide), m")
    half_extent_m: float | None = Field(
        None,
        gt=0,
        description="the map covers +-this about the origin, m (None: the seabed's grid); smaller "
        "than the survey: beams off the map are dropped",
    )
    nan_holes: int = Field(0, ge=0, le=10_000, description="holes of no data punched in the map")
    nan_hole_radius_m: float = Field(15.0, gt=0, description="radius of each hole, m")


class TrnConfig(Config):
    """The dive and the TRN filters."""

    t_dive_s: float = Field(
        60.0,
        gt=0,
        description="USBL fixes reach the vehicle's navigator until then, s (a mission that ends "
        "before has nothing to report after the dive: its verdicts say so)",
    )
    update_period_s: float = Field(
        1.0,
        gt=0,
        description="a TRN update every this, s (the DVL pings in between only predict): map "
        "errors are correlated over a map cell, so pings closer than a cell add little",
    )
    sounding_sigma_m: float = Field(
        0.1,
        gt=0,
        description="sounding depth sigma the filters assume beside the map's, m: range noise, "
        "the attitude error moving the footprint, the pressure depth",
    )
    sigma_velocity_m_s: float = Field(
        0.1,
        gt=0,
        description="velocity sigma per axis of each DVL ping's displacement the DR and TRN "
        "predictions assume, m/s: not the DVL's noise alone (0.03 made the filters overconfident, "
        "their sigma 0.1 m against errors of 0.5-0.9 m, and re-initialised them 7 times in 8 "
        "runs, measured): the DR error is a slow drift (the compass bias), which white noise "
        "covers only when larger",
    )
    sigma_water_track_m_s: float = Field(
        0.1,
        gt=0,
        description="the same for a ping without bottom lock (water track plus the current the "
        "log EKF learnt before the dive, or none: the last velocity held), m/s",
    )
    particles: int = Field(2000, ge=10, le=200_000, description="particle filter size")
    grid_points: int = Field(48, ge=8, le=512, description="point-mass grid points per axis")
    sigma_bias_m: float = Field(1.0, ge=0, description="common per-ping bias prior, m")
    reinit_sigma_m: float = Field(20.0, gt=0, description="re-initialisation spread, m")
    reinitialise: bool = Field(True, description="re-initialise a filter found diverged")
    divergence_probability: float = Field(
        1e-3, gt=0, lt=0.5, description="false-alarm probability of the divergence test"
    )
    nis_window: int = Field(20, ge=1, le=10_000, description="TRN updates in the NIS window")
    settle_s: float = Field(
        60.0, ge=0, description="after the dive, time the verdicts leave the filters to settle, s"
    )
    sample_s: float = Field(1.0, gt=0, description="errors are kept every this, s")


class TrnNavigation(NavigationConfig):
    """The standard navigation settings plus which estimate guidance steers on."""

    steer: Literal["trn_pf", "trn_pmf", "dr_dvl", "dr_log", "ekf_log", "usbl_ekf"] = Field(
        "trn_pf",
        description="estimate guidance steers on (the others are computed alongside); its reach "
        "test reads that method's horizontal covariance (the log EKF's for dr_log and ekf_log)",
    )


class TrnScenario(MissionScenario):
    """A mission scenario with the DVL in the rig, the navigator's map and the TRN settings."""

    sensors: TrnMissionSensors = Field(default_factory=TrnMissionSensors)
    current: CurrentConfig = Field(
        default_factory=lambda: UniformCurrentConfig(speed_m_s=0.3, direction_deg=30.0)
    )
    map: MapConfig = Field(default_factory=MapConfig)
    trn: TrnConfig = Field(default_factory=TrnConfig)
    navigation: TrnNavigation = Field(default_factory=TrnNavigation)

    @model_validator(mode="after")
    def _check_trn(self) -> TrnScenario:
        tick = self.timing.control_tick_s
        if not self.sensors.use_dvl:
            raise ValueError(
                "sensors.use_dvl = false: must be true (every method of mission/trn but the log's "
                "needs the DVL)"
            )
        dvl = self.sensors.dvl
        check_multiple(dvl.period_s, tick, "sensors.dvl.period_s")
        check_multiple(self.trn.update_period_s, dvl.period_s, "trn.update_period_s")
        if self.map.cell_m < self.seabed.cell_m:
            raise ValueError(
                f"map.cell_m = {self.map.cell_m:g}: must be >= seabed.cell_m = "
                f"{self.seabed.cell_m:g} (the map is a survey of the seabed, never finer)"
            )
        ext = self.map.half_extent_m
        if ext is not None and ext < 2 * self.map.cell_m:
            raise ValueError(
                f"map.half_extent_m = {ext:g}: must be >= 2 map.cell_m = {2 * self.map.cell_m:g}"
            )
        return self


PRESET = {
    "start": {
        "east_m": -80.0,
        "north_m": -40.0,
        "depth_m": 4.0,
        "heading_deg": 90.0,
        "speed_m_s": 1.0,
        "position_sigma_m": 2.0,
        "heading_sigma_deg": 3.0,
    },
    "seabed": SEABED_PRESET,
    "guidance": {"waypoints": SURVEY_WAYPOINTS, "speed_m_s": 1.0},
    "sensors": {"use_gps": False},
    "timing": {"max_duration_s": 720.0},
}
"""``mission/trn``'s preset (package docstring)."""


def seabed_text(scn: TrnScenario) -> str:
    """The seabed in a title: its bathymetry file, or the generated relief's standard
    deviation."""
    if scn.seabed.file is not None:
        return f"seabed from {scn.seabed.file}"
    return f"relief {scn.seabed.relief_std_m:g} m"
