"""The scenario of ``mission/correction``: the experiment's options and the legs of a run."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config, load_config, to_plain
from bauv_sim.frames import (
    unit_vector_scalar,
    wrap_2pi_scalar,
)
from tasks.closed_loop.scenario import MissionScenario

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
