"""``mission/seed004``: the experiment (checks, memory, the flights of a block) and its
registration (package docstring)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bauv_sim import seabed
from bauv_sim.errors import ConfigError, GeometryError
from tasks.closed_loop.experiment import BYTES_PER_TICK as MISSION_BYTES_PER_TICK
from tasks.closed_loop.experiment import MissionExperiment
from tasks.closed_loop.world import fly
from tasks.core.registry import MemoryTerm, ReportContext, ReportSummary, register
from tasks.missions.seed004.metrics import Seed004Metrics, Seed004RunResult, flight_metrics
from tasks.missions.seed004.parts import Seed004Mission
from tasks.missions.seed004.report import report_seed004
from tasks.missions.seed004.scenario import (
    SEABED_PRESET,
    Seed004Scenario,
    beacon_specs,
    flown_filters,
    gains_for,
    path_config,
)

if TYPE_CHECKING:
    pass

Array = NDArray[np.float64]

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


BYTES_PER_TICK = 650.0
"""A flight's memory per control tick, bytes: its per-tick columns, the mission's own included
(the control, the filter step, the shift), measured 507 B per tick, and its bearings (the ``doa``
fix table: 4 beacons every second), 65 B per tick at the 0.2 s tick (numpy's bytes of a 20 s
flight's columns); a run's result with its metrics pickles to 626 B per tick and flight."""


@dataclass(frozen=True)
class Seed004Experiment(MissionExperiment):
    """Seed 004's filters steering the physical BAUV (one flight per filter and run)."""

    scenario_type = Seed004Scenario
    metrics_type = Seed004Metrics

    def filters(self, scn: Seed004Scenario) -> tuple[str, ...]:
        return flown_filters(scn)

    def flight(self, scenario: Seed004Scenario, seed: int, run: int):
        """The flight of the first filter of ``navigation.filter`` (:meth:`run_block` flies
        each)."""
        f = self.filters(scenario)[0]
        return Seed004Mission(f, gains_for(scenario, seed) if f == "cmnf" else None), scenario

    def _flight_terms(self, terms: list[MemoryTerm], scn: Seed004Scenario) -> list[MemoryTerm]:
        """The per-tick terms of :meth:`MissionExperiment.memory` (its first two: a run in the
        worker, every run in the report) for every filter a run flies, at
        :data:`BYTES_PER_TICK` instead of the mission's."""
        k = len(self.filters(scn)) * BYTES_PER_TICK / MISSION_BYTES_PER_TICK
        what = f" x {len(self.filters(scn))} filters (navigation.filter), bearings included"
        scaled = [
            dataclasses.replace(t, bytes=k * t.bytes, fields=t.fields + what) for t in terms[:2]
        ]
        return scaled + terms[2:]

    def memory(self, scenario: Seed004Scenario, n_runs: int) -> list[MemoryTerm]:
        """The mission's terms (:meth:`MissionExperiment.memory`; its per-tick terms for each
        filter flown, :meth:`_flight_terms`, since a run keeps every flight), and with the seabed
        prediction and the CMNF the surrogate's (:func:`surrogate`): its heightfield, kept in the
        process while the scene's own grid is generated (:data:`HEIGHTFIELD_KEPT_BYTES_PER_POINT`),
        and the multibeam images of ``seed004.train_paths`` training paths at once
        (:data:`IMAGE_BYTES_PER_PATH_BEAM`), in the worker; in the report too, which trains the
        gains again where the worker's are not at hand and flies
        ``seed004.surrogate_test_paths`` paths."""
        terms = self._flight_terms(super().memory(scenario, n_runs), scenario)
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
        bed = seabed.generate(scenario.seabed, scenario.frame())
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
                res.flights[f] = flight
            out.append(res)
        return out

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_seed004(self, ctx)


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
