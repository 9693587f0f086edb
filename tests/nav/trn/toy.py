"""A toy TRN world for the tests: an analytic 2-D terrain on a 1 m map, a Janus DVL's four beams
and pings simulated from the truth (independent of the filters' code)."""

from __future__ import annotations

import numpy as np

from nav.trn import Soundings, TerrainMap, TrnOptions

BEAM_ANGLE_RAD = np.radians(30.0)
ALTITUDE_M = 20.0
VEHICLE_DEPTH_M = 30.0


def terrain_depth(x, y):
    """Depth (m, positive down) of the toy seabed: incommensurate undulations of a few metres
    over a gentle slope, so no two places look alike over a ping's footprint for long."""
    return (
        VEHICLE_DEPTH_M
        + ALTITUDE_M
        + 3.0 * np.sin(x / 13.0) * np.cos(y / 17.0)
        + 2.0 * np.sin((x + 0.7 * y) / 9.0)
        + 1.5 * np.cos((0.3 * x - y) / 23.0)
        + 0.01 * x
    )


def toy_map(size_m: float = 400.0, cell_m: float = 1.0) -> TerrainMap:
    x = np.arange(0.0, size_m + cell_m / 2, cell_m)
    return TerrainMap(x, x.copy(), terrain_depth(x[None, :], x[:, None]))


def dvl_offsets() -> np.ndarray:
    """Horizontal offsets (east, north) of the four beams' footprints on a level seabed 20 m
    below, heading north, beams at 45 + k 90 deg, m."""
    r = ALTITUDE_M * np.tan(BEAM_ANGLE_RAD)
    phi = np.radians([45.0, 135.0, 225.0, 315.0])
    return np.column_stack([r * np.cos(phi), r * np.sin(phi)])


def ping(terrain_map, truth_xy, rng, sigma_m, bias_m=0.0) -> Soundings:
    """One ping at the true position: the map's depth at each footprint, plus a common bias and
    independent N(0, sigma^2) noise; beams off the map are not valid."""
    off = dvl_offsets()
    hit = truth_xy[None, :] + off
    z, ok = terrain_map.depth(hit[:, 0], hit[:, 1])
    z = z + bias_m + sigma_m * rng.standard_normal(z.shape)
    return Soundings(offset_m=off, depth_m=np.where(ok, z, 0.0), valid=ok)


def options(**kw) -> TrnOptions:
    return TrnOptions(**kw)
