"""Curvature-bounded ray march against seed 004's harmonic seabed (eq. 24), compiled by numba: the
hot loop of :meth:`bauv_sim.sensors.multibeam.HarmonicSeabed.ray_ranges`, one ray at a time.

Python normalises the directions, checks the input and hands the rays this march leaves
unresolved to its first-order march (``HarmonicSeabed._lipschitz_ranges``); :func:`march` checks
the shapes of its arrays and the path indices itself before it reads any of them.

The seabed of path p is ``psi(x) = 0`` (water where ``psi > 0``), with::

    psi(x) = a0 + z + sum_{l=1..K} (a_l sin(w_l x) + b_l cos(w_l x)
                                    + c_l sin(v_l y) + d_l cos(v_l y)),
    w_l = 2 pi l / Px,  v_l = 2 pi l / Py  (m^-1).

Along a ray ``x(s) = o + s e`` (e a unit vector, s in m), ``f(s) = psi(x(s))`` has::

    f'(s) = e_z + e_x sum_l w_l (a_l cos - b_l sin) + e_y sum_l v_l (c_l cos - d_l sin),
    |f''(s)| <= M2 = e_x^2 C_x + e_y^2 C_y,  C_x = sum_l w_l^2 hypot(a_l, b_l)  (same in y)

(eq. 24 is separable: no cross term). From a point where ``f > 0`` the concave parabola
``f + f' h - M2 h^2 / 2`` bounds ``f(s + h)`` from below; its first positive root
``h = 2 f / (sqrt(f'^2 + 2 M2 f) - f')`` (``= (f' + sqrt(...)) / M2`` for ``f' > 0``) cannot pass
the first crossing, and near a simple root it is Newton's step to second order. The upper
parabola ``f + f' h + M2 h^2 / 2`` crosses zero at ``h_up = 2 f / (sqrt(f'^2 - 2 M2 f) - f')``, so
for ``f' < 0`` the first crossing lies in ``[s + h, s + h_up]``: the march takes its middle once
that interval is at most ``tol`` wide ("close"), or takes ``s + h`` once the step is at most
``tol``; a step beyond ``max_range`` means no echo. A point with ``f <= 0`` is, at the start
(``s == 0``), an origin at or below the seabed (no echo), later a rounding step onto the root
(the range is ``s``). The march starts where the ray enters the slab
``z <= top = -a0 + sum_l (hypot(a_l, b_l) + hypot(c_l, d_l))`` that holds the seabed (a ray
above it going up or level has no echo). The harmonics ``l = 2..K`` come from ``l = 1`` by angle
addition, with the argument reduced to ``[-pi, pi]`` first (``t = w_1 (x - Px rint(x / Px))``).
A ray not resolved after ``steps`` steps (grazing a crest) is flagged unresolved with the
distance ``s`` reached.

Every operation is the one of the numpy implementation this march first replaced (kept in
``tests/bauv_sim/multibeam_reference.py``) and of the C library that held it until issue 26, in
the same order: IEEE 754 double, no fast-math, no fused multiply-add (numba contracts none without
``fastmath``), ``error_model="numpy"`` (a division by zero is IEEE's, as in C).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

STATUS = {
    -1: "a buffer shorter than its shape (n, paths, harmonics) says",
    -2: "a ray's path index outside [0, paths)",
    -3: "a count out of range (rays >= 0, paths >= 1, harmonics >= 1)",
}
"""The march's refusals (:func:`march`'s negative return values)."""


@njit(cache=True, error_model="numpy", nogil=True)
def _psi_slope(x, y, z, ex, ey, ez, K, a, b, c, d, wx, wy, a0, px, py):  # pragma: no cover
    """``psi`` at ``(x, y, z)`` (m) and its derivative along the ray ``e`` for one path's
    coefficients (``a, b, c, d``, (K,) each, m) and frequencies (``wx, wy``, (K,), rad/m)."""
    tx = wx[0] * (x - px * np.rint(x / px))  # round half to even, as numpy's round
    ty = wy[0] * (y - py * np.rint(y / py))
    sx1, cx1, sy1, cy1 = math.sin(tx), math.cos(tx), math.sin(ty), math.cos(ty)
    sx, cx, sy, cy = sx1, cx1, sy1, cy1
    f = a0 + z
    gx = 0.0
    gy = 0.0
    for l in range(K):  # noqa: E741 (the harmonic's index, as in eq. 24)
        if l:
            sxn = sx * cx1 + cx * sx1
            cxn = cx * cx1 - sx * sx1
            syn = sy * cy1 + cy * sy1
            cyn = cy * cy1 - sy * sy1
            sx, cx, sy, cy = sxn, cxn, syn, cyn
        f = f + (a[l] * sx + b[l] * cx) + (c[l] * sy + d[l] * cy)
        gx = gx + wx[l] * (a[l] * cx - b[l] * sx)
        gy = gy + wy[l] * (c[l] * cy - d[l] * sy)
    return f, ez + ex * gx + ey * gy


@njit(cache=True, error_model="numpy", nogil=True)
def march(
    o,
    e,
    path,
    a,
    b,
    c,
    d,
    wx,
    wy,
    top,
    cxx,
    cyy,
    a0,
    px,
    py,
    max_range,
    tol,
    steps,
    range_m,
    hit,
    unresolved,
    s_out,
):  # pragma: no cover  (compiled)
    """The march over n rays (module docstring).

    Args:
        o: origins, shape (n, 3), m, world (z up).
        e: unit directions, shape (n, 3), world.
        path: each ray's seabed, shape (n,), int64 in ``[0, P)``.
        a, b, c, d: coefficients, shape (P, K), m.
        wx, wy: ``w_l`` and ``v_l``, shape (K,), rad/m.
        top: top of each path's slab, shape (P,), m (z).
        cxx, cyy: ``C_x`` and ``C_y``, shape (P,), m^-1.
        a0, px, py: ``a0``, ``Px``, ``Py``, m.
        max_range: no echo beyond this distance, m.
        tol: width at which the root is taken, m.
        steps: steps of the march before a ray is left unresolved.
        range_m: out, shape (n,): the range, m (0 without hit).
        hit: out, shape (n,), uint8 0/1.
        unresolved: out, shape (n,), uint8 0/1.
        s_out: out, shape (n,): for an unresolved ray the distance the march reached, m (else 0).

    Returns:
        The number of unresolved rays, or -1 (an array shorter than n, P, K say), -2 (a path index
        outside ``[0, P)``), -3 (``P < 1``, ``K < 1`` or ``steps < 0``); nothing is read or
        written before these checks pass.
    """
    n = path.shape[0]
    P, K = a.shape
    if P < 1 or K < 1 or steps < 0:
        return -3
    if o.shape[0] < n or e.shape[0] < n or o.shape[1] != 3 or e.shape[1] != 3:
        return -1
    if b.shape != (P, K) or c.shape != (P, K) or d.shape != (P, K):
        return -1
    if wx.shape[0] < K or wy.shape[0] < K:
        return -1
    if top.shape[0] < P or cxx.shape[0] < P or cyy.shape[0] < P:
        return -1
    if range_m.shape[0] < n or hit.shape[0] < n or unresolved.shape[0] < n or s_out.shape[0] < n:
        return -1
    for i in range(n):
        if path[i] < 0 or path[i] >= P:
            return -2
    left = 0
    for i in range(n):
        ox, oy, oz = o[i, 0], o[i, 1], o[i, 2]
        ex, ey, ez = e[i, 0], e[i, 1], e[i, 2]
        p = path[i]
        range_m[i] = 0.0
        hit[i] = 0
        unresolved[i] = 0
        s_out[i] = 0.0
        # enter the slab that holds the seabed (psi > 0 above its top)
        above = oz > top[p]
        if above and ez >= 0:
            continue
        s = (oz - top[p]) / -ez if (above and ez < 0) else 0.0
        if not (s <= max_range):
            continue
        m2 = ex * ex * cxx[p] + ey * ey * cyy[p]
        ap, bp, cp, dp = a[p], b[p], c[p], d[p]  # the path's rows
        live = True
        k = 0
        while k < steps and live:
            k += 1
            f, g = _psi_slope(
                ox + s * ex,
                oy + s * ey,
                oz + s * ez,
                ex,
                ey,
                ez,
                K,
                ap,
                bp,
                cp,
                dp,
                wx,
                wy,
                a0,
                px,
                py,
            )
            below = f <= 0  # at the origin: no echo; later: a rounding step onto the root
            fp = f if f > 0.0 else 0.0
            root = math.sqrt(g * g + 2.0 * m2 * fp)
            h = (g + root) / m2 if g > 0 else 2.0 * f / (root - g)
            # the upper parabola f + f' h + M2 h^2 / 2 crosses zero at h_up: the root is in
            # [h, h_up]
            h_up = 2.0 * f / (math.sqrt(g * g - 2.0 * m2 * fp) - g)
            if math.isnan(h):
                h = math.inf
            close = (g < 0) and (h_up - h <= tol)
            if close:
                h = 0.5 * (h + h_up)
            nxt = s + h
            if below:
                if s > 0:
                    range_m[i] = s
                    hit[i] = 1
                live = False  # s == 0: an origin at or below the seabed
            elif (close or h <= tol) and nxt <= max_range:
                range_m[i] = nxt
                hit[i] = 1
                live = False
            elif nxt > max_range:
                live = False
            else:
                s = nxt
        if live:
            unresolved[i] = 1
            s_out[i] = s
            left += 1
    return left
