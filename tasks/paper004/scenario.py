"""The scenario of seed 004's kinematic experiments (``paper-004/table-1``, ``table-1-seabed``,
``near-beacon``): the configuration, the cases of a batch's sweep, each case's closed-loop
setting and CMNF gains, and the presets of the registered experiments."""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import product
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, field_validator

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.seed004 import (
    SECTION6_BEACONS,
    NominalPathConfig,
    Seed004Noise,
    check_beacons,
)
from bauv_sim.sensors.multibeam import MultibeamConfig
from nav.bearings.cmnf import DEFAULT_CLIP_SIGMAS, CmnfGains
from nav.bearings.local_control import ControlLimits
from tasks.paper004.sim import LoopSetting, gains_for

# ----------------------------------------------------------------------------------------------
# Scenario


class FilterConfig(Config):
    """What the filters assume and how the CMNF is trained (seed 004, section 6)."""

    bearing_sigma_deg: float | None = Field(
        None, gt=0, lt=45, description="bearing precision the filters assume, deg (none: truth's)"
    )
    correction: Literal["residual", "pseudo"] = Field(
        "residual",
        description="CMNF basic correction: residual (eq. 24) or pseudo (eq. 20's residual)",
    )
    upmf_form: Literal["unbiased", "printed"] = Field(
        "unbiased",
        description="UPMF gain at the predicted bearings with the noise mean removed (unbiased) "
        "or at the measured ones as eq. 21 prints (biased ~0.02 m in x)",
    )
    floor: float = Field(
        1e-9, ge=0, le=1e-3, description="CMNF pseudo-inverses' absolute singular-value floor"
    )
    clip_sigmas: float = Field(
        DEFAULT_CLIP_SIGMAS,
        ge=0,
        le=1e6,
        description="CMNF: clip its basic correction at median +- this many robust sigmas of "
        "the training paths, per step and feature (nav.bearings.cmnf.clip_bounds); 0: "
        "unclipped, the paper's filter, whose gains near a beacon a few paths with extreme "
        "tangents set",
    )
    train_paths: int = Field(
        100_000, ge=10, le=1_000_000, description="CMNF training paths (the paper: 1e5)"
    )
    gains_dir: str | None = Field(
        None,
        description="folder of gains-<case>.npz written by an earlier run (its gains/): load "
        "instead of training; refused if trained for another setting",
    )


class GuidanceConfig(Config):
    """The control law: eq. 7 unbounded (as in the paper) or with box limits."""

    limits: bool = Field(False, description="apply the box limits below")
    max_turn_rate_deg_s: float = Field(30.0, ge=0, le=360, description="theta rate limit, deg/s")
    max_pitch_rate_deg_s: float = Field(10.0, ge=0, le=360, description="gamma rate limit, deg/s")
    max_gamma_deg: float = Field(30.0, ge=0, lt=90, description="|gamma| limit, deg")
    v_min_m_s: float = Field(0.0, ge=0, le=50, description="speed lower limit, m/s")
    v_max_m_s: float = Field(6.0, gt=0, le=50, description="speed upper limit, m/s")

    def control_limits(self) -> ControlLimits | None:
        """The :class:`nav.bearings.local_control.ControlLimits`, or None when unbounded."""
        if not self.limits:
            return None
        if self.v_min_m_s > self.v_max_m_s:
            raise ConfigError(
                f"guidance.v_min_m_s = {self.v_min_m_s}: must be <= guidance.v_max_m_s = "
                f"{self.v_max_m_s}"
            )
        return ControlLimits(
            max_turn_rate=math.radians(self.max_turn_rate_deg_s),
            max_pitch_rate=math.radians(self.max_pitch_rate_deg_s),
            max_gamma=math.radians(self.max_gamma_deg),
            v_min=self.v_min_m_s,
            v_max=self.v_max_m_s,
        )


class SweepConfig(Config):
    """The cases of one batch: every combination of the lists (same draws for each)."""

    bearing_sigma_deg: list[float] = Field(
        [0.5, 1.0], min_length=1, max_length=8, description="truth's bearing precision, deg"
    )
    initial_variance_m2: list[float] = Field(
        [1.0], min_length=1, max_length=12, description="S_0 = this I (truth and filters), m^2"
    )

    prediction: list[Literal["system", "seabed-one_attitude", "seabed-turning"]] = Field(
        ["system"],
        min_length=1,
        max_length=3,
        description="the filters' prediction: by virtue of the system (row 1) or the seabed "
        "shift with one reading of the beam attitude (row 2; tasks.paper004.seabed)",
    )

    @field_validator("bearing_sigma_deg")
    @classmethod
    def _bearing(cls, v: list[float]) -> list[float]:
        if any(not 0 < x < 45 for x in v):
            raise ValueError(f"{v}: every bearing sigma must be in (0, 45) deg")
        return v

    @field_validator("initial_variance_m2")
    @classmethod
    def _var(cls, v: list[float]) -> list[float]:
        if any(not 0 < x <= 1e6 for x in v):
            raise ValueError(f"{v}: every initial variance must be in (0, 1e6] m^2")
        return v


class ReportConfig(Config):
    """What the report computes and draws."""

    figures: bool = True
    sample_runs: int = Field(3, ge=0, le=20, description="runs drawn as sample paths")
    documented_variance_m2: float = Field(
        10.0, gt=0, description="near-beacon: the initial variance of the documented breakdown"
    )
    steep_elevation_deg: float = Field(
        80.0, gt=0, le=90, description="warn when a beacon is this steep above the nominal path"
    )
    loses_ratio: float = Field(
        1.1, gt=1, description="the EKF 'starts to lose' where its J-bar exceeds this x the best"
    )


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int = Field(1000, ge=1, le=100_000, description="runs per block")


class Paper004Scenario(Config):
    """Scenario of seed 004's kinematic experiments (defaults: Table 1, row 1)."""

    path: NominalPathConfig = Field(default_factory=NominalPathConfig)
    noise: Seed004Noise = Field(default_factory=Seed004Noise)
    beacons: list[tuple[float, float, float]] = Field(
        [list(b) for b in SECTION6_BEACONS],
        min_length=1,
        max_length=16,
        description="beacon positions [x, y, z up], m (section 6: four on the surface)",
    )
    filters: FilterConfig = Field(default_factory=FilterConfig)
    guidance: GuidanceConfig = Field(default_factory=GuidanceConfig)
    sweep: SweepConfig = Field(default_factory=SweepConfig)
    report: ReportConfig = Field(default_factory=ReportConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)
    multibeam: MultibeamConfig = Field(
        default_factory=MultibeamConfig,
        description="the multibeam of the seabed-sensing prediction (row 2; seed 004's 8 x 8 "
        "beams, 0.1 m range noise)",
    )


@dataclass(frozen=True)
class Case:
    """One setting of a batch."""

    bearing_sigma_deg: float
    initial_variance_m2: float
    prediction: str = "system"

    @property
    def label(self) -> str:
        """Short label, e.g. ``bearing1deg-s0x1`` (``-seabed-one_attitude`` for row 2)."""
        base = f"bearing{self.bearing_sigma_deg:g}deg-s0x{self.initial_variance_m2:g}"
        return base if self.prediction == "system" else f"{base}-{self.prediction}"


def cases(scn: Paper004Scenario) -> tuple[Case, ...]:
    """The batch's cases, in sweep order."""
    return tuple(
        Case(b, v, p)
        for p, b, v in product(
            scn.sweep.prediction, scn.sweep.bearing_sigma_deg, scn.sweep.initial_variance_m2
        )
    )


def setting(scn: Paper004Scenario, case: Case) -> LoopSetting:
    """The :class:`tasks.paper004.sim.LoopSetting` of a case."""
    s0 = (math.sqrt(case.initial_variance_m2),) * 3
    noise = scn.noise.model_copy(
        update={"bearing_sigma_deg": case.bearing_sigma_deg, "sigma_x0_m": s0}
    )
    fnoise = None
    if scn.filters.bearing_sigma_deg is not None:
        fnoise = noise.model_copy(update={"bearing_sigma_deg": scn.filters.bearing_sigma_deg})
    return LoopSetting(
        path=scn.path,
        noise=noise,
        beacons=tuple(tuple(float(c) for c in b) for b in scn.beacons),
        filter_noise=fnoise,
        limits=scn.guidance.control_limits(),
        correction=scn.filters.correction,
        upmf_form=scn.filters.upmf_form,
        floor=scn.filters.floor,
        clip_sigmas=scn.filters.clip_sigmas or None,
        train_paths=scn.filters.train_paths,
        prediction=case.prediction,
        multibeam=None if case.prediction == "system" else scn.multibeam,
    )


def case_gains(scn: Paper004Scenario, case: Case, seed: int) -> CmnfGains:
    """The CMNF gains of a case: loaded from ``filters.gains_dir`` or trained (cached)."""
    s = setting(scn, case)
    if scn.filters.gains_dir is None:
        return gains_for(s, seed)
    path = Path(scn.filters.gains_dir) / f"gains-{case.label}.npz"
    if not path.is_file():
        raise ConfigError(f"filters.gains_dir = {scn.filters.gains_dir!r}: no {path.name} there")
    g = CmnfGains.load(path)
    if g.info.get("setting") != s.key() or g.info.get("seed") != seed:
        raise ConfigError(
            f"filters.gains_dir = {scn.filters.gains_dir!r}: {path.name} was trained for another "
            "setting or seed"
        )
    return g


def steep_beacons(scn: Paper004Scenario) -> list[tuple[int, float]]:
    """Beacons whose elevation seen from the nominal path exceeds ``report.steep_elevation_deg``:
    ``(index, largest elevation deg)``."""
    xn = scn.path.path()
    out = []
    for i, b in enumerate(check_beacons(scn.beacons)):
        d = b[None] - xn
        el = np.degrees(np.arctan2(np.abs(d[:, 2]), np.hypot(d[:, 0], d[:, 1])))
        if el.max() > scn.report.steep_elevation_deg:
            out.append((i + 1, float(el.max())))
    return out


NEAR_BEACON_PRESET = {
    "beacons": [[500.0, 100.0, 0.0], [500.0, -100.0, 0.0], [-100.0, 100.0, 0.0], [-5.0, -5.0, 0.0]],
    "path": {"duration_s": 10.0},
    "sweep": {"bearing_sigma_deg": [0.5], "initial_variance_m2": [1.0, 2.0, 3.0, 5.0, 10.0, 20.0]},
    "filters": {"upmf_form": "printed"},
}
"""The near-beacon case. The UPMF is eq. 21 as printed here: its gain at the measured angles stays
stable when the prediction is far off near the beacon, while the unbiased form's gain at the
predicted bearings does not (J-bar 496 against 34 m^2 at S_0 = 10 I, 1e4 paths)."""

SEABED_PRESET = {
    "sweep": {
        "bearing_sigma_deg": [1.0],
        "prediction": ["seabed-one_attitude", "seabed-turning"],
    },
    "filters": {"train_paths": 300},
    "runner": {"block_size": 250},
}
"""Row 2: both readings of the beam attitude, at the bearing noise that reproduces row 1. Every
step ray-casts two 8 x 8 images per path (~0.3 ms per path-step here, ray casting about 60 % of
it), so the defaults are 300 training paths and 200 test paths (the paper: 1e5); the figures at
scale are in CHANGELOG.md. Blocks of 250 paths keep numpy's per-call overhead small."""
