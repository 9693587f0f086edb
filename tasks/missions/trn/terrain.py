"""``mission/trn``'s terrain: the true seabed as a map, the navigator's degraded copy (cropped,
with holes of no data when asked) and the TRN posterior Cramer-Rao bound along the true track
(package docstring)."""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim import seabed
from bauv_sim.frames import R_from_roll_pitch_heading
from bauv_sim.geo import LocalFrame
from nav.trn import TerrainMap, degraded, trn_pcrb
from tasks.missions.trn.scenario import TrnScenario

Array = NDArray[np.float64]


@functools.lru_cache(maxsize=2)
def true_seabed(cfg: seabed.SeabedConfig, frame: LocalFrame | None = None) -> seabed.Seabed:
    """The scene's seabed (generated, or resampled from its bathymetry file around the
    scenario's geographic origin ``frame``, once per process, configuration and frame)."""
    return seabed.generate(cfg, frame)


def true_map(
    cfg: seabed.SeabedConfig,
    half_extent_m: float | None = None,
    frame: LocalFrame | None = None,
) -> TerrainMap:
    """The true seabed (:func:`true_seabed`) as a :class:`nav.trn.TerrainMap` (its grid points;
    ``sigma_m`` 0), cropped to ``+-half_extent_m`` about the origin when given."""
    bed = true_seabed(cfg, frame)
    n = cfg.n
    x = -cfg.half_extent_m + cfg.cell_m * np.arange(n)
    keep = np.ones(n, bool) if half_extent_m is None else np.abs(x) <= half_extent_m + 1e-9
    return TerrainMap(x[keep], x[keep], bed.depth_m[np.ix_(keep, keep)], 0.0)


def survey_box(scn: TrnScenario) -> tuple[float, float, float, float]:
    """The horizontal box of the start and the way-points, (x_min, x_max, y_min, y_max), m."""
    pts = [(w.east_m, w.north_m) for w in scn.guidance.waypoints]
    pts.append((scn.start.east_m, scn.start.north_m))
    xs, ys = zip(*pts, strict=True)
    return min(xs), max(xs), min(ys), max(ys)


@functools.lru_cache(maxsize=4)
def _navigator_map(key: str, scn: TrnScenario, seed: int) -> TerrainMap:
    c = scn.map
    truth = true_map(scn.seabed, c.half_extent_m, scn.frame())
    m = degraded(
        truth, c.cell_m, c.vertical_sigma_m, c.offset_m, rng_mod.generator(seed, 0, "trn", "map")
    )
    if c.nan_holes == 0:
        return m
    g = rng_mod.generator(seed, 0, "trn", "map_holes")
    x0, x1, y0, y1 = survey_box(scn)
    centres = np.column_stack([g.uniform(x0, x1, c.nan_holes), g.uniform(y0, y1, c.nan_holes)])
    depth = m.depth_m.copy()
    X, Y = np.meshgrid(m.x_m, m.y_m)
    for cx, cy in centres:
        depth[np.hypot(X - cx, Y - cy) <= c.nan_hole_radius_m] = np.nan
    return TerrainMap(m.x_m, m.y_m, depth, m.sigma_m)


def navigator_map(scn: TrnScenario, seed: int) -> TerrainMap:
    """The navigator's map of a batch: the true seabed (:func:`true_map`: the scene's, from
    its bathymetry file when it has one; cropped to ``map.half_extent_m``)
    degraded by :func:`nav.trn.degraded` with ``map.cell_m``, ``map.vertical_sigma_m`` and
    ``map.offset_m``, then ``map.nan_holes`` discs of ``map.nan_hole_radius_m`` without data
    centred uniformly in the survey's box; one map per batch (streams of run 0: the survey map
    is the same for every run), cached per process."""
    return _navigator_map(scn.model_dump_json(), scn, seed)


def map_nan_fraction(scn: TrnScenario, seed: int) -> float:
    """The fraction of the navigator's map nodes without data."""
    return float(np.mean(np.isnan(navigator_map(scn, seed).depth_m)))


def true_footprints(
    scn: TrnScenario,
    position_m: Array,
    rph_rad: Array,
    directions_body: Array,
    lever_arm_body_m: Array,
) -> tuple[Array, NDArray[np.bool_]]:
    """Where the DVL's beams meet the true seabed from the true poses.

    Args:
        scn: the scenario (its seabed and DVL).
        position_m: true positions, shape (k, 3), m, world.
        rph_rad: true roll, pitch, heading, shape (k, 3), rad.
        directions_body: the beams, shape (m, 3), body FLU.
        lever_arm_body_m: the transducer, shape (3,), m, body FLU.

    Returns:
        ``(points, lock)``: footprints (east, north), shape (k, m, 2), m; and whether each beam
        returns within the DVL's lock (a hit, the ping's altitude between ``sensors.dvl.
        min_altitude_m`` and ``max_altitude_m``, at least ``min_beams`` beams), shape (k, m).
    """
    bed = true_seabed(scn.seabed, scn.frame())
    R = np.array([R_from_roll_pitch_heading(*a) for a in rph_rad])
    origin = position_m + R @ lever_arm_body_m
    dirs = np.einsum("kij,mj->kmi", R, directions_body)
    d = scn.sensors.dvl
    cos_a = math.cos(math.radians(d.beam_angle_deg))
    rng_max = 1.5 * d.max_altitude_m / cos_a
    ranges, hit = bed.ray_ranges(origin[:, None, :], dirs, rng_max)
    pts = origin[:, None, :2] + ranges[..., None] * dirs[..., :2]
    n_hit = hit.sum(axis=1)
    alt = np.where(hit, ranges * cos_a, 0.0).sum(axis=1) / np.maximum(n_hit, 1)
    ok = (n_hit >= d.min_beams) & (alt >= d.min_altitude_m) & (alt <= d.max_altitude_m)
    return pts, hit & ok[:, None]


def pcrb_track(
    scn: TrnScenario,
    seed: int,
    P0_m2: Array,
    q_m2: Array,
    position_m: Array,
    rph_rad: Array,
    directions_body: Array,
    lever_arm_body_m: Array,
) -> Array:
    """The TRN posterior Cramer-Rao bound at the update times, from the true track.

    The information of a ping is the TRUE seabed's gradient at the true beam footprints
    (:func:`true_footprints`), a beam counting where it returns within the DVL's lock and the
    navigator's map has data there (a beam off the map or on a hole gives the filters nothing),
    with the per-beam sigma the filters assume (``trn.sounding_sigma_m`` and the map's stated
    sigma, in quadrature); the prediction between updates adds the covariance the filters were
    given (``q_m2``), the prior is the filters' start and the common per-ping bias is
    marginalised as the filters do (``trn.sigma_bias_m``; :func:`nav.trn.trn_pcrb`).

    Args:
        scn: the scenario.
        seed: batch seed (the navigator's map).
        P0_m2: the filters' initial covariance, shape (2, 2), m^2.
        q_m2: prediction covariance before each update, shape (k, 2, 2), m^2.
        position_m, rph_rad: the true pose at each update, shapes (k, 3), m and rad.
        directions_body, lever_arm_body_m: the DVL's beams (m, 3) and transducer (3,).

    Returns:
        The bound on the horizontal RMS error, ``sqrt(trace(J^-1))``, shape (k,), m.
    """
    k = len(position_m)
    if k == 0:
        return np.zeros(0)
    pts, lock = true_footprints(scn, position_m, rph_rad, directions_body, lever_arm_body_m)
    nav_map = navigator_map(scn, seed)
    _, on_map = nav_map.depth(pts[..., 0], pts[..., 1])
    g, g_ok = true_map(scn.seabed, frame=scn.frame()).gradient(pts[..., 0], pts[..., 1])
    active = lock & on_map & g_ok
    g = np.where(active[..., None], g, 0.0)
    sigma = np.full(active.shape, math.hypot(scn.trn.sounding_sigma_m, nav_map.sigma_m))
    J0 = np.linalg.inv(np.asarray(P0_m2, float))
    bound = trn_pcrb(J0, q_m2, g, sigma, active, scn.trn.sigma_bias_m)
    return np.sqrt(np.trace(bound, axis1=1, axis2=2))
