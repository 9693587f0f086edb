"""``mission/seed004``'s scenario: the seed-004 settings, the scaled path and beacons, the
kinematic surrogate the CMNF is trained on and its gains (package docstring)."""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim import seabed
from bauv_sim.build import BeaconSpec
from bauv_sim.config import Config
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.kinematic.seed004 import NominalPathConfig, Seed004Noise
from bauv_sim.sensors.doa import DoaConfig
from bauv_sim.sensors.multibeam import MultibeamConfig
from nav.bearings import bank
from nav.bearings.cmnf import CmnfGains
from nav.bearings.local_control import ControlLimits
from tasks.closed_loop.scenario import MissionScenario, NavigationConfig

if TYPE_CHECKING:
    from tasks.paper004.sim import LoopSetting

Array = NDArray[np.float64]

FILTERS = tuple(name.lower() for name in bank.FILTERS)
"""The filters of :mod:`nav.bearings.bank` as the scenario (``navigation.filter``) and the metrics
name them."""
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
    bed = seabed.generate(scn.seabed, scn.frame())
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
                "heightfield_geo": scn.geo,
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


def flown_filters(scn: Seed004Scenario) -> tuple[str, ...]:
    """The filters a run flies (``navigation.filter``; ``"all"``: each of :data:`FILTERS`)."""
    f = scn.navigation.filter
    return FILTERS if f == "all" else (f,)
