"""Scenario of seed 003's tests: the square, the formation, the sensors (from
:mod:`bauv_sim.kinematic.seed003`), what the follower's navigation assumes, the report's and the
runner's settings, the readings of the paper a run computes, and the tests' presets.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from bauv_sim.config import Config, load_config, to_plain
from bauv_sim.kinematic.seed003 import (
    FormationConfig,
    Seed003Sensors,
    SquarePathConfig,
    SquareTruth,
    square_truth,
)
from bauv_sim.sensors.base import check_multiple, periodic_indices
from nav.relative import GaOptions, RangeEkfOptions
from tasks.core.registry import block_by_work


class NavigationConfig(Config):
    """What the follower's navigation assumes and how GA reads the paper (seed 003, eq. 2-6)."""

    sigma_course_deg: float = Field(
        2.0, gt=0, description="sigma_C of eq. 5, deg (the VN-100 documentation's 2 deg)"
    )
    sigma_speed_m_s: float = Field(
        0.3, gt=0, description="sigma_S of eq. 5, m/s (the Alize documentation's 0.3 m/s)"
    )
    sigma_range_m: float = Field(
        0.1, gt=0, description="delta_Dh of the weight matrix P and the EKF's range sigma, m"
    )
    jacobian: Literal["printed", "true"] = Field(
        "printed",
        description="A of eq. 2: the rows as printed (geodetic column order) or the true "
        "Jacobian (nav.relative)",
    )
    restart: bool = Field(
        True, description="DR restarts from the GA position after each fix (else runs on)"
    )
    min_range_m: float = Field(
        0.5, gt=0, description="ranges below this make no fix (GA and EKF dead-reckon on), m"
    )
    min_step_m: float = Field(
        1e-3, gt=0, description="below this DR displacement the bearing row gets weight 0, m"
    )
    max_hdop: float | None = Field(
        None, gt=0, description="GA fixes with a larger HDOP are refused (none: keep all)"
    )
    leader_sigma_m: float = Field(
        0.0,
        ge=0,
        description="the EKF's sigma per axis of the leader's broadcast position, m (0: taken "
        "as exact, as in the paper; set it with sensors.modem.broadcast)",
    )
    ekf_initial_sigma_m: float = Field(
        0.0, ge=0, description="EKF's initial sigma per axis, m (0: the start is known)"
    )

    def ekf_options(self) -> RangeEkfOptions:
        """The :class:`nav.relative.RangeEkfOptions` of this configuration."""
        return RangeEkfOptions(
            sigma_range_m=self.sigma_range_m,
            min_range_m=self.min_range_m,
            initial_sigma_m=self.ekf_initial_sigma_m,
            leader_sigma_m=self.leader_sigma_m,
        )

    def ga_options(self, jacobian: str | None = None, restart: bool | None = None) -> GaOptions:
        """The :class:`nav.relative.GaOptions` of this configuration (or of another reading)."""
        return GaOptions(
            jacobian=self.jacobian if jacobian is None else jacobian,  # type: ignore[arg-type]
            restart=self.restart if restart is None else restart,
            sigma_range_m=self.sigma_range_m,
            min_range_m=self.min_range_m,
            min_step_m=self.min_step_m,
        )


class HdopMapConfig(Config):
    """Figure 2: HDOP around the leader for F moving at course 90 deg with D_r = 10 m."""

    half_width_m: float = Field(30.0, gt=0, description="the map spans +-this around L, m")
    cells: int = Field(121, ge=11, le=801, description="grid points per axis")
    course_deg: float = Field(90.0, ge=0, lt=360, description="F's course, deg")
    step_m: float = Field(10.0, gt=0, description="D_r: F's DR displacement since its start, m")


class ReportConfig(Config):
    """What the report computes, draws and writes."""

    readings: Literal["default", "all"] = Field(
        "default",
        description="default: the scenario's reading only; all: GA1/GA2 (and DR, EKF) for every "
        "combination of formation.offset, formation.bearing_of, navigation.jacobian and "
        "navigation.restart on the same draws",
    )
    single_sample: int = Field(0, ge=0, description="run of the single-test-sample columns")
    routes_max: int = Field(100, ge=0, le=1000, description="runs drawn in the 100-sample paths")
    routes_every_s: float = Field(1.0, gt=0, description="spacing of the drawn path points, s")
    figures: bool = True
    recording: bool = True
    run_data: bool = Field(True, description="write Parquet run data (single sample, per run)")
    hdop_map: HdopMapConfig = Field(default_factory=HdopMapConfig)
    warn_hdop: float = Field(
        3.0,
        gt=0,
        description="warn when the median HDOP of the accepted fixes exceeds this (abeam ~1.4; "
        "on the course line ~D_r, 5 in 5 s)",
    )
    consistency_probability: float = Field(0.95, gt=0, lt=1)


BLOCK_RUN_TICKS = 2_400_000
"""The work of a default block, run-ticks (see :class:`RunnerConfig`)."""


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int | None = Field(
        None,
        ge=1,
        le=100_000,
        description=(
            "runs per block; default: sized by work, as many runs as make "
            f"{BLOCK_RUN_TICKS:,} run-ticks (500 runs of the paper's 4,800 ticks at 10 Hz): "
            "1.5x faster than blocks of 100, about 0.5 GB per block"
        ),
    )


def block_runs(scn: Paper003Scenario) -> int:
    """Runs per block: ``runner.block_size``, or by work (:data:`BLOCK_RUN_TICKS`)."""
    return block_by_work(scn.runner.block_size, scn.path.n_ticks - 1, BLOCK_RUN_TICKS)


class Paper003Scenario(Config):
    """Scenario of seed 003's tests (defaults: Test 1)."""

    path: SquarePathConfig = Field(default_factory=SquarePathConfig)
    formation: FormationConfig = Field(default_factory=FormationConfig)
    sensors: Seed003Sensors = Field(default_factory=Seed003Sensors)
    navigation: NavigationConfig = Field(default_factory=NavigationConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)


@dataclass(frozen=True)
class Reading:
    """One combination of the readings the paper leaves open."""

    offset: str
    bearing_of: str
    jacobian: str
    restart: bool

    @property
    def label(self) -> str:
        """Short label, e.g. ``world/F-from-L/printed/restart``."""
        b = "F-from-L" if self.bearing_of == "follower_from_leader" else "L-from-F"
        r = "restart" if self.restart else "no-restart"
        return f"{self.offset}/{b}/{self.jacobian}/{r}"

    @property
    def geometry(self) -> tuple[str, str]:
        """The part of the reading that changes the truth."""
        return (self.offset, self.bearing_of)


def scenario_reading(scn: Paper003Scenario) -> Reading:
    """The reading of the scenario itself."""
    f, n = scn.formation, scn.navigation
    return Reading(f.offset, f.bearing_of, n.jacobian, n.restart)


def readings(scn: Paper003Scenario) -> tuple[Reading, ...]:
    """The readings a block computes: the scenario's first, then (``report.readings = "all"``)
    every other combination in a fixed order."""
    own = scenario_reading(scn)
    if scn.report.readings == "default":
        return (own,)
    every = [
        Reading(o, b, j, r)
        for o, b, j, r in product(
            ("world", "leg"),
            ("follower_from_leader", "leader_from_follower"),
            ("printed", "true"),
            (True, False),
        )
    ]
    return (own, *[r for r in every if r != own])


def truth_of(scn: Paper003Scenario, geometry: tuple[str, str]) -> SquareTruth:
    """The reference motion of leader and follower under a geometry ``(offset, bearing_of)``."""
    f = scn.formation.model_copy(update={"offset": geometry[0], "bearing_of": geometry[1]})
    return square_truth(scn.path, f)


def periodic_fix_ticks(scn: Paper003Scenario) -> NDArray[np.intp]:
    """Ticks of the ranges, shape (K,)."""
    every = check_multiple(scn.sensors.modem.period_s, scn.path.tick_s, "sensors.modem.period_s")
    return periodic_indices(scn.path.n_ticks, every)


def preset_of(test: str) -> dict:
    """The scenario overrides that make a test (Test 1 is the defaults)."""
    if test == "test-2":
        return {"formation": {"relative_bearing_deg": 180.0}}
    if test == "test-3":
        return {
            "sensors": {
                "ins": {"heading": {"sector_bias_deg": [0.4, 0.8, 0.0, 0.2]}},
                "log": {"speed": {"bias_m_s": 0.005}},
                "modem": {"range": {"bias_m": 0.0025}},
            }
        }
    return {}


def scenario_of(test: str, overrides: dict | None = None) -> Paper003Scenario:
    """The validated scenario of a test, with optional nested overrides (for scripts, tests)."""
    cfg = load_config(Paper003Scenario, preset_of(test))
    if overrides:
        base = to_plain(cfg)
        _deep_update(base, overrides)
        cfg = load_config(Paper003Scenario, base)
    return cfg


def _deep_update(base: dict, upd: dict) -> None:
    for k, v in upd.items():
        if isinstance(v, dict) and isinstance(base.get(k), dict):
            _deep_update(base[k], v)
        else:
            base[k] = v
