"""Seed 001 replica's scenario: the kinematic world, the grid of cells and the report options
(`paper-001/replica`; :mod:`tasks.paper001.replica`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from bauv_sim.kinematic import seed001 as kin

Array = NDArray[np.float64]
PROCEDURES = ("cp1", "cp2")
DR_KINDS = ("nocp", "cp", "baseline")
NAME = "paper-001/replica"


# --------------------------------------------------------------------------------------------
# Scenario


class Paper001ReportConfig(Config):
    """What the report draws."""

    figures: bool = Field(True, description="write the PNG figures")
    figure_missions: int = Field(1, ge=0, description="missions whose tracks are kept for figures")
    figure_cell: tuple[float, float, float] = Field(
        (0.3, 0.5, 20.0), description="(|Vg| m/s, |Vc| m/s, beta deg) of the example figures"
    )


class Paper001Scenario(Config):
    """Seed 001's experiment (defaults: the paper's parameters, section "Conditions of
    experiments"; Tables 1-3 show the positive ``|Vg|`` and ``beta`` of the grid)."""

    world: kin.Seed001WorldConfig = Field(default_factory=kin.Seed001WorldConfig)
    systematic_speeds_m_s: tuple[float, ...] = Field(
        (0.1, 0.3), min_length=1, description="|Vg| = signed |Vs| grid, m/s"
    )
    betas_deg: tuple[float, ...] = Field(
        (5.0, 20.0), min_length=1, description="beta grid: deviation of Vs from the course, deg"
    )
    current_speeds_m_s: tuple[float, ...] = Field(
        (0.1, 0.5), min_length=1, description="|Vc| grid, m/s"
    )
    cp1_beta_max_deg: float = Field(
        20.0, gt=0, lt=90, description="beta_CP^max: CP1's starting beta in [-max, max], deg"
    )
    cp1_beta_step_deg: float = Field(1.0, gt=0, description="spacing of CP1's starting beta, deg")
    cp1_min_course_separation_deg: float = Field(
        5.0,
        ge=0,
        lt=90,
        description="CP1's courses must be at least this far from the same and from opposite, deg",
    )
    cp2_courses_deg: tuple[float, float] = Field(
        (45.0, 225.0), description="CP2's first two courses, deg"
    )
    missions_per_block: int = Field(5, ge=1, description="missions per runner block")
    report: Paper001ReportConfig = Field(default_factory=Paper001ReportConfig)

    @model_validator(mode="after")
    def _check(self) -> Paper001Scenario:
        for b in self.betas_deg:
            if not -90.0 < b < 90.0:
                raise ValueError(f"betas_deg contains {b}: the paper assumes beta in (-90, 90) deg")
        for v in self.current_speeds_m_s:
            if not 0.0 <= v <= 5.0:
                raise ValueError(f"current_speeds_m_s contains {v}: must be in [0, 5] m/s")
        a, b = self.cp2_courses_deg
        if abs(abs(((b - a) + 180.0) % 360.0 - 180.0) - 180.0) > 1e-9:
            raise ValueError(f"cp2_courses_deg = {self.cp2_courses_deg}: must be opposite")
        return self

    def cells(self) -> list[tuple[float, float, float]]:
        """The grid cells ``(|Vg|, |Vc|, beta_deg)`` in table order."""
        return [
            (vg, vc, b)
            for vg in self.systematic_speeds_m_s
            for vc in self.current_speeds_m_s
            for b in self.betas_deg
        ]


def cell_key(cell: tuple[float, float, float]) -> str:
    vg, vc, b = cell
    return f"vg={vg:g},vc={vc:g},beta={b:g}"
