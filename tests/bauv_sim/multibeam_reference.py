"""The numpy curvature-bounded march of :meth:`HarmonicSeabed.ray_ranges`, as it was before its loop
moved to C (``bauv_sim/sensors/harmonic_rays.c``, numba's :mod:`bauv_sim.sensors.harmonic_march`
since issue 26): the reference the tests compare the compiled march with
(``tests/bauv_sim/test_multibeam.py``), and a variant of ``benchmarks/bench_seabed.py``.

Vectorised over the rays (the live rays compacted as they finish); the rays still unresolved after
:data:`bauv_sim.sensors.multibeam.CURVATURE_STEPS` steps go to the library's first-order march
(:meth:`HarmonicSeabed._lipschitz_ranges`), as in the library.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.sensors import multibeam
from bauv_sim.sensors.multibeam import HarmonicSeabed

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def ray_ranges(
    bed: HarmonicSeabed,
    origin_m: Array,
    directions: Array,
    max_range_m: float,
    min_step_m: float = 0.02,
    tol_m: float = 1e-9,
    max_iterations: int = 10_000,
) -> tuple[Array, BoolArray]:
    """:meth:`HarmonicSeabed.ray_ranges` with the curvature-bounded march in numpy.

    Args:
        bed: the seabeds (P paths).
        origin_m: ray origins, shape (P, ..., 3), m, world.
        directions: ray directions, shape (P, ..., 3) (broadcast with the origins; normalised
            here).
        max_range_m: no echo beyond this distance, m.
        min_step_m: smallest step of the first-order march, m.
        tol_m: width at which the root is taken, m.
        max_iterations: cap of the first-order march.

    Returns:
        ``(range_m, hit)``: shape (P, ...), m; ``range_m`` is 0 where ``hit`` is False.

    Raises:
        ConfigError: as :meth:`HarmonicSeabed.ray_ranges`.
    """
    o, e = np.broadcast_arrays(np.asarray(origin_m, float), np.asarray(directions, float))
    shape = o.shape[:-1]
    if not shape or shape[0] != bed.paths:
        raise ConfigError(f"ray_ranges: rays of shape {o.shape} for {bed.paths} seabeds")
    path = np.broadcast_to(
        np.arange(bed.paths).reshape(-1, *([1] * (len(shape) - 1))), shape
    ).ravel()
    o, e = o.reshape(-1, 3), e.reshape(-1, 3)
    norm = np.linalg.norm(e, axis=1)
    if not np.all(np.isfinite(norm) & (norm > 0)) or not np.all(np.isfinite(o)):
        raise ConfigError("ray_ranges: origins must be finite, directions finite and non-zero")
    e = e / norm[:, None]
    wx, wy = bed._w()
    m2 = (
        e[:, 0] ** 2 * (wx**2 * np.hypot(bed.a, bed.b)).sum(-1)[path]
        + e[:, 1] ** 2 * (wy**2 * np.hypot(bed.c, bed.d)).sum(-1)[path]
    )
    K = bed.a.shape[1]
    r = np.zeros(path.size)
    hit = np.zeros(path.size, bool)
    # start where the ray enters the slab that holds the seabed (psi > 0 above its top)
    top = -bed.a0_m + bed.relief_bound()[path]
    above = o[:, 2] > top
    with np.errstate(divide="ignore"):
        s0 = np.where(above & (e[:, 2] < 0), (o[:, 2] - top) / -e[:, 2], 0.0)
    gid = np.flatnonzero(~(above & (e[:, 2] >= 0)) & (s0 <= max_range_m))
    # the live rays' state, one contiguous array per quantity (compacted as rays finish)
    st = [o[gid, 0], o[gid, 1], o[gid, 2], e[gid, 0], e[gid, 1], e[gid, 2], m2[gid], s0[gid]]
    st += [getattr(bed, c)[path[gid], lv] for c in "abcd" for lv in range(K)]
    live = np.ones(gid.size, bool)
    for _ in range(multibeam.CURVATURE_STEPS):
        if gid.size == 0:
            break
        ox, oy, oz, ex, ey, ez, mi, si = st[:8]
        f, g = _psi_slope(bed, ox + si * ex, oy + si * ey, oz + si * ez, ex, ey, ez, st[8:])
        below = f <= 0  # at the origin: no echo; later: a rounding step onto the root
        fp = np.maximum(f, 0.0)
        root = np.sqrt(g * g + 2.0 * mi * fp)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = np.where(g > 0, (g + root) / mi, 2.0 * f / (root - g))
            # the upper parabola f + f' h + M2 h^2 / 2 crosses zero at h_up: the first root
            # is in [h, h_up]
            h_up = 2.0 * f / (np.sqrt(g * g - 2.0 * mi * fp) - g)
        h = np.where(np.isnan(h), np.inf, h)
        close = (g < 0) & (h_up - h <= tol_m)
        h = np.where(close, 0.5 * (h + h_up), h)
        nxt = si + h
        found = live & np.where(below, si > 0, (close | (h <= tol_m)) & (nxt <= max_range_m))
        gone = live & np.where(below, si == 0, nxt > max_range_m)
        r[gid[found]] = np.where(below, si, nxt)[found]
        hit[gid[found]] = True
        live &= ~(found | gone)
        st[7] = np.where(live, nxt, si)
        left = int(live.sum())
        if left < 0.5 * gid.size:  # compact
            gid = gid[live]
            st = [a[live] for a in st]
            live = np.ones(left, bool)
    if gid.size and live.any():  # rays grazing a crest: the first-order march from there
        gid, si = gid[live], st[7][live]
        L, h1 = bed._lipschitz_ranges(
            o[gid] + si[:, None] * e[gid],
            e[gid],
            path[gid],
            max_range_m - si,
            min_step_m,
            tol_m,
            max_iterations,
        )
        r[gid] = si + L
        hit[gid] = h1
    return np.where(hit, r, 0.0).reshape(shape), hit.reshape(shape)


def _psi_slope(
    bed: HarmonicSeabed,
    x: Array,
    y: Array,
    z: Array,
    ex: Array,
    ey: Array,
    ez: Array,
    coef: list[Array],
) -> tuple[Array, Array]:
    """``psi`` and its derivative ``grad psi . e`` along rays.

    Args:
        bed: the seabeds.
        x, y, z: points, each shape (r,), m, world.
        ex, ey, ez: the rays' unit directions, each shape (r,).
        coef: the rays' coefficients, ``a_1..a_K, b_1..b_K, c_1..c_K, d_1..d_K``, each (r,), m.

    Returns:
        ``(psi, dpsi/ds)``, each shape (r,) (m, and m per m).
    """
    K = len(coef) // 4
    wx, wy = bed._w()
    px, py = bed.period_x_m, bed.period_y_m
    tx = wx[0] * (x - px * np.round(x / px))  # reduced to [-pi, pi]: cheaper sines
    ty = wy[0] * (y - py * np.round(y / py))
    sx1, cx1, sy1, cy1 = np.sin(tx), np.cos(tx), np.sin(ty), np.cos(ty)
    sx, cx, sy, cy = sx1, cx1, sy1, cy1
    f = bed.a0_m + z
    gx = 0.0
    gy = 0.0
    for lv in range(K):
        if lv:  # sin and cos of (l + 1) theta by angle addition
            sx, cx = sx * cx1 + cx * sx1, cx * cx1 - sx * sx1
            sy, cy = sy * cy1 + cy * sy1, cy * cy1 - sy * sy1
        a, b, c, d = coef[lv], coef[K + lv], coef[2 * K + lv], coef[3 * K + lv]
        f = f + (a * sx + b * cx) + (c * sy + d * cy)
        gx = gx + wx[lv] * (a * cx - b * sx)
        gy = gy + wy[lv] * (c * cy - d * sy)
    return f, ez + ex * gx + ey * gy
