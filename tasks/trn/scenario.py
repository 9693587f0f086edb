"""The scenario of ``trn/relief``: the kinematic track, the generated terrain, the navigator's
map and its errors, the devices, the filters and the sweep over relief and map error.

Reading of the experiment where the issue is silent (documented in the fields):

* the terrain of run ``i`` is one draw of :func:`bauv_sim.seabed.generate` (plane waves) whose
  shape is the same at every relief of the sweep, scaled to the relief's standard deviation: the
  relief comparison is paired (same tracks, same wave directions and phases, same noise);
* the mean seabed is flat (``slope = 0``), so that the relief is the only horizontal information;
* the vehicle starts where the navigator thinks it is plus ``N(0, initial_sigma_m^2 I)`` (the
  error of the last fix before the dive); dead reckoning keeps that error, TRN removes it as far
  as the terrain allows;
* the heading and the DVL's beams have white errors (no bias, no random walk by default), so the
  dead-reckoning error grows as a random walk whose increments the filters and the PCRB model
  exactly (:func:`nav.dvl.dvl_increment_covariance`, summed per update by
  :func:`tasks.trn.run.increment_covariance`). A bias, scale factor or random walk set in the
  devices' error models is simulated, but neither the filters' process noise nor the PCRB
  includes it (the bound then bounds a smaller error than the one flown).
"""

from __future__ import annotations

import math

from pydantic import Field, field_validator, model_validator

from bauv_sim.config import Config
from bauv_sim.seabed import MAX_HALF_EXTENT_M, SeabedConfig
from bauv_sim.sensors import AngleErrorConfig, CompassConfig
from bauv_sim.sensors.dvl import DvlConfig

DEFAULT_RELIEF_M = (0.25, 0.5, 1.0, 2.0, 5.0)
"""The issue's relief standard deviations, m."""

MAX_SETTINGS = 60
"""The most (relief x map error) settings of one batch."""


class TrackConfig(Config):
    """The kinematic truth: a lawn-mower at constant speed and depth (no physics, no current)."""

    speed_m_s: float = Field(1.5, gt=0, le=10, description="speed over ground, m/s")
    depth_m: float = Field(10.0, ge=0, description="vehicle depth, m (constant)")
    duration_s: float = Field(300.0, gt=0, le=36_000, description="duration of a run, s")
    leg_m: float = Field(300.0, gt=0, description="length of a survey leg, m")
    spacing_m: float = Field(50.0, gt=0, description="distance between two survey legs, m")
    start_box_m: float = Field(
        100.0, ge=0, description="the start is uniform in +-this (east, north) around the origin, m"
    )

    @property
    def lawnmower_extent_m(self) -> float:
        """The farthest the track gets from its start, m (bounded by a leg and the legs flown)."""
        path = self.speed_m_s * self.duration_s
        legs = math.ceil(path / (self.leg_m + self.spacing_m))
        return math.hypot(min(self.leg_m, path), min(legs * self.spacing_m, path))


class TerrainConfig(Config):
    """The true seabed of every run (:func:`bauv_sim.seabed.generate`, flat mean, relief from the
    sweep); its seed is drawn per run from the batch seed."""

    half_extent_m: float = Field(
        600.0, gt=0, le=MAX_HALF_EXTENT_M, description="half side of the square grid, m"
    )
    cell_m: float = Field(5.0, ge=0.5, description="grid spacing of the true seabed, m")
    depth_m: float = Field(40.0, gt=0, description="mean depth of the seabed, m")
    n_modes: int = Field(24, ge=1, le=200, description="plane waves in the relief")
    min_wavelength_m: float = Field(60.0, gt=0, description="shortest relief wavelength, m")
    max_wavelength_m: float = Field(600.0, gt=0, description="longest relief wavelength, m")

    @model_validator(mode="after")
    def _grid(self) -> TerrainConfig:
        self.seabed(1.0, 0)  # SeabedConfig's own checks (whole cells, wavelengths) now
        return self

    def seabed(self, relief_std_m: float, seed: int) -> SeabedConfig:
        """The :class:`SeabedConfig` of one run at one relief."""
        return SeabedConfig(
            half_extent_m=self.half_extent_m,
            cell_m=self.cell_m,
            depth_at_origin_m=self.depth_m,
            slope=0.0,
            relief_std_m=relief_std_m,
            n_modes=self.n_modes,
            min_wavelength_m=self.min_wavelength_m,
            max_wavelength_m=self.max_wavelength_m,
            min_depth_m=min(4.5, self.depth_m),
            seed=seed,
        )


class MapConfig(Config):
    """The navigator's map: a degraded copy of the true seabed (:func:`nav.trn.degraded`)."""

    cell_m: float = Field(
        10.0, gt=0, description="grid spacing of the map, m (no finer than the true seabed's)"
    )
    offset_m: float = Field(
        0.5, description="vertical offset of the whole map, m (depth positive down)"
    )


class SensorsConfig(Config):
    """The devices: the DVL (its beams give velocity and soundings) and the heading."""

    dvl: DvlConfig = Field(default_factory=DvlConfig, description="the DVL (5 Hz, Janus)")
    compass: CompassConfig = Field(
        default_factory=lambda: CompassConfig(
            period_s=0.2, heading=AngleErrorConfig(sigma_deg=1.0)
        ),
        description="heading (INS): white noise 1 deg per sample at the DVL's rate",
    )


class FiltersConfig(Config):
    """The TRN filters (:mod:`nav.trn`) and what they are told."""

    initial_sigma_m: float = Field(
        20.0, gt=0, le=1000, description="initial position error (truth and filters), m, 1 sigma"
    )
    update_every: int = Field(
        5, ge=1, le=1000, description="a TRN update every this many DVL pings (5: 1 Hz)"
    )
    particles: int = Field(2000, ge=10, le=1_000_000, description="particles of the PF")
    grid_points: int = Field(
        48, ge=8, le=1001, description="points per side of the point-mass filter's grid"
    )
    sigma_bias_m: float = Field(
        2.0,
        ge=0,
        description="prior sigma of a common per-ping depth bias the filters marginalise (the "
        "map's offset), m",
    )
    map_model_sigma_m: float = Field(
        0.2,
        ge=0,
        description="what the filters' measurement model misses beyond the beam's range error, "
        "the map's stated sigma and the map's own interpolation error "
        "(nav.trn.TerrainMap.interpolation_sigma_m), m, added in quadrature",
    )


class SweepConfig(Config):
    """The settings of one batch: every combination of the lists (same runs, same draws)."""

    relief_std_m: list[float] = Field(
        list(DEFAULT_RELIEF_M),
        min_length=1,
        max_length=20,
        description="standard deviations of the true relief, m",
    )
    map_sigma_m: list[float] = Field(
        [0.1, 0.5],
        min_length=1,
        max_length=20,
        description="vertical noise of the navigator's map, m, 1 sigma per map cell",
    )

    @field_validator("relief_std_m", "map_sigma_m")
    @classmethod
    def _non_negative(cls, v: list[float]) -> list[float]:
        bad = [x for x in v if not (math.isfinite(x) and 0 <= x <= 50)]
        if bad:
            raise ValueError(f"every value must be in [0, 50] m (not {bad[0]})")
        if len(set(v)) != len(v):
            raise ValueError("a value appears twice")
        return v


class ReportConfig(Config):
    """What the report draws."""

    figures: bool = True


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int = Field(2, ge=1, le=10_000, description="runs per block")


class TrnReliefScenario(Config):
    """Scenario of ``trn/relief`` (module docstring)."""

    track: TrackConfig = Field(default_factory=TrackConfig)
    terrain: TerrainConfig = Field(default_factory=TerrainConfig)
    map: MapConfig = Field(default_factory=MapConfig)
    sensors: SensorsConfig = Field(default_factory=SensorsConfig)
    filters: FiltersConfig = Field(default_factory=FiltersConfig)
    sweep: SweepConfig = Field(default_factory=SweepConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)

    @model_validator(mode="after")
    def _geometry(self) -> TrnReliefScenario:
        t, s, m = self.track, self.terrain, self.map
        if m.cell_m < s.cell_m:
            raise ValueError(
                f"map.cell_m = {m.cell_m}: finer than terrain.cell_m = {s.cell_m}; the map is a "
                "degraded copy of the true seabed and must be at least as coarse"
            )
        if m.cell_m > s.half_extent_m / 4:
            raise ValueError(
                f"map.cell_m = {m.cell_m}: must be at most terrain.half_extent_m / 4 = "
                f"{s.half_extent_m / 4:g} m"
            )
        dvl = self.sensors.dvl
        pings = math.floor(t.duration_s / dvl.period_s + 1e-9)
        if pings < self.filters.update_every:
            raise ValueError(
                f"track.duration_s = {t.duration_s}: {pings} DVL pings of "
                f"sensors.dvl.period_s = {dvl.period_s} s, fewer than one TRN update every "
                f"filters.update_every = {self.filters.update_every} pings"
            )
        relief = max(self.sweep.relief_std_m)
        # +-5 sigma of relief about the mean depth (the depth at the origin is pinned, so the
        # mean itself moves by about one sigma); a ping that loses the bottom anyway is counted
        low, high = s.depth_m - t.depth_m - 5 * relief, s.depth_m - t.depth_m + 5 * relief
        if low < dvl.min_altitude_m or high > dvl.max_altitude_m:
            raise ValueError(
                f"track.depth_m = {t.depth_m} over terrain.depth_m = {s.depth_m} with relief up "
                f"to {relief} m: the altitude can reach [{low:.1f}, {high:.1f}] m, outside the "
                f"DVL's bottom lock [{dvl.min_altitude_m}, {dvl.max_altitude_m}] m"
            )
        beam_reach = high * math.tan(math.radians(dvl.beam_angle_deg))
        margin = 5.0 * self.filters.initial_sigma_m + beam_reach + 2 * m.cell_m
        reach = t.start_box_m + t.lawnmower_extent_m + margin
        if reach > s.half_extent_m:
            raise ValueError(
                f"terrain.half_extent_m = {s.half_extent_m}: the track (start within "
                f"+-{t.start_box_m} m, lawn-mower out to {t.lawnmower_extent_m:.0f} m) with the "
                f"filters' spread and the beams' reach needs {reach:.0f} m"
            )
        return self

    def settings(self) -> list[tuple[float, float]]:
        """The batch's settings ``(relief_std_m, map_sigma_m)``, relief-major."""
        return [(r, v) for r in self.sweep.relief_std_m for v in self.sweep.map_sigma_m]
