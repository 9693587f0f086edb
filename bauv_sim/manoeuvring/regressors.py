"""The manoeuvring model's regressors (:mod:`bauv_sim.manoeuvring.model`): the terms the hull's,
the fins' and the tail's identified forces are linear in, as functions of the relative velocity,
the actuators and the tail-beat frequency, with :func:`skew` and the row-wise cross product."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

HULL_LINE_TERMS: tuple[str, ...] = ("u", "u|u|", "u^3")
"""Regressors of the hull's force in straight flight (functions of the surge u, m/s, alone)."""

HULL_TERMS: tuple[str, ...] = (
    *HULL_LINE_TERMS,
    *("v", "w", "p", "q", "r"),
    *("v|v|", "w|w|", "p|p|", "q|q|", "r|r|"),
    *("uv", "uw", "up", "uq", "ur", "vw", "vp", "vq", "vr", "wp", "wq", "wr", "pq", "pr", "qr"),
    *("|v|r", "|r|v", "|w|q", "|q|w"),
    *("v^2", "w^2", "p^2", "q^2", "r^2"),
    *("u|v|", "u|w|", "u|p|", "u|q|", "u|r|"),
    *("uv^2", "uw^2", "ur^2", "uq^2", "v^2r", "w^2q", "vr^2"),
    *("wq^2", "|u|v", "|u|w", "|u|r", "|u|q", "|v|w", "|w|v", "|v|p", "|r|p"),
)
"""Regressors of the hull's quasi-steady force, in this order: :data:`HULL_LINE_TERMS`, then
products that vanish in straight flight, of the relative body velocity's components u, v, w
(m/s) and p, q, r (rad/s). The force is fitted in two stages (straight tows for the first,
random states for the rest), so that straight flight, where the missions spend their time, is
not traded against the large coupling terms of a turn."""


def _hull_index() -> tuple[NDArray[np.intp], ...]:
    """Where each of :data:`HULL_TERMS` comes from: (columns, sources) for the components x_i,
    the products x_i x_j, abs(x_i) x_j and the cubes (x_i x_j) x_k, in the order the terms are
    written (each product computed as the same single multiplications, so the regressors are
    those of writing every term out)."""
    P = [(0, 1), (0, 2), (0, 3), (0, 4), (0, 5), (1, 2), (1, 3), (1, 4), (1, 5), (2, 3), (2, 4)]
    P += [(2, 5), (3, 4), (3, 5), (4, 5)]
    spec: list[tuple[str, tuple[int, ...]]] = [("x", (0,)), ("a", (0, 0)), ("c", (0, 0, 0))]
    spec += [("x", (i,)) for i in range(1, 6)]
    spec += [("a", (i, i)) for i in range(1, 6)]
    spec += [("p", ij) for ij in P]
    spec += [("a", ij) for ij in ((1, 5), (5, 1), (2, 4), (4, 2))]
    spec += [("p", (i, i)) for i in range(1, 6)]
    spec += [("a", (i, 0)) for i in range(1, 6)]  # u abs(x) = abs(x) u (exactly)
    cubes = ((0, 1, 1), (0, 2, 2), (0, 5, 5), (0, 4, 4), (1, 1, 5), (2, 2, 4), (1, 5, 5), (2, 4, 4))
    spec += [("c", ijk) for ijk in cubes]
    spec += [("a", ij) for ij in ((0, 1), (0, 2), (0, 5), (0, 4), (1, 2), (2, 1), (1, 3), (5, 3))]
    out: list[NDArray[np.intp]] = []
    for kind in "xpac":
        cols = [j for j, (k, _) in enumerate(spec) if k == kind]
        src = [ix for k, ix in spec if k == kind]
        out.append(np.array(cols, dtype=np.intp))
        if kind == "x":
            out.append(np.array([ix[0] for ix in src], dtype=np.intp))
        elif kind == "c":
            out.append(np.array([6 * ix[0] + ix[1] for ix in src], dtype=np.intp))
            out.append(np.array([ix[2] for ix in src], dtype=np.intp))
        else:
            out.append(np.array([6 * ix[0] + ix[1] for ix in src], dtype=np.intp))
    return tuple(out)


_HULL_INDEX = _hull_index()
_GATHER_MAX_RUNS = 16
"""Up to this many runs the regressors are gathered from outer products in a few calls (per-call
overhead dominates); above it they are built column by column (no large temporaries). The
two give the same numbers bit for bit."""


def hull_regressors(nu: NDArray[np.float64]) -> NDArray[np.float64]:
    """The regressors :data:`HULL_TERMS` of relative body velocities.

    Args:
        nu: (u, v, w, p, q, r) relative to the water, body FLU, m/s and rad/s, shape (n, 6).

    Returns:
        Shape (n, len(HULL_TERMS)).
    """
    n = nu.shape[0]
    if n > _GATHER_MAX_RUNS:
        return _hull_regressors_columns(nu)
    cx, sx, cp, sp, ca, sa, cc, sc, kc = _HULL_INDEX
    x = nu.T  # (6, n): whole rows gathered below
    P = (x[:, None, :] * x[None, :, :]).reshape(36, n)  # x_i x_j
    A = (np.abs(x)[:, None, :] * x[None, :, :]).reshape(36, n)  # abs(x_i) x_j
    out = np.empty((len(HULL_TERMS), n))
    out[cx] = x[sx]
    out[cp] = P[sp]
    out[ca] = A[sa]
    out[cc] = P[sc] * x[kc]
    return np.ascontiguousarray(out.T)


def _hull_regressors_columns(nu: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`hull_regressors` column by column (many runs: no large temporaries)."""
    u, v, w, p, q, r = nu.T
    a = np.abs(nu)
    au, av, aw, ap, aq, ar = a.T
    return np.stack(
        [
            u, au * u, u * u * u,
            v, w, p, q, r,
            av * v, aw * w, ap * p, aq * q, ar * r,
            u * v, u * w, u * p, u * q, u * r, v * w, v * p, v * q, v * r,
            w * p, w * q, w * r, p * q, p * r, q * r,
            av * r, ar * v, aw * q, aq * w,
            v * v, w * w, p * p, q * q, r * r,
            u * av, u * aw, u * ap, u * aq, u * ar,
            u * v * v, u * w * w, u * r * r, u * q * q, v * v * r, w * w * q, v * r * r, w * q * q,
            au * v, au * w, au * r, au * q, av * w, aw * v, av * p, ar * p,
        ],
        axis=1,
    )  # fmt: skip


FIN_TERMS: tuple[str, ...] = ("u|u| sin(d) cos(d)", "u|u| sin(d)^2", "u|u| sin(d)|sin(d)|")
"""Regressors of one lateral fin's force at angle d (rad) and surge u (m/s)."""


def fin_regressors(u: NDArray[np.float64], d: NDArray[np.float64]) -> NDArray[np.float64]:
    """The regressors :data:`FIN_TERMS`.

    Args:
        u: surge relative to the water, m/s, shape (n,).
        d: fin angle, rad (leading edge up +), shape (n,).

    Returns:
        Shape (n, 3).
    """
    q = u * np.abs(u)
    s = np.sin(d)
    return np.stack([q * s * np.cos(d), q * s * s, q * s * np.abs(s)], axis=1)


FIN_FLOW_TERMS: tuple[str, ...] = (
    *("lift x", "lift z", "induced x", "induced z"),
    *("normal x", "normal z", "profile x", "profile z"),
)
"""Regressors of one lateral fin's force in the local flow at its centre: the plate's terms of
the ``bauv.hydro`` plugin in the chord-normal plane (lift ``uc un / |u| (un, -uc)``, induced drag
``uc^2 un^2 / |u|^3 (uc, un)``, normal force ``(0, |un| un)``, profile drag ``(|uc| uc, 0)``, with
``uc``, ``un`` the chord and normal components of the local velocity), each rotated into the
body's x and z by the fin angle; the change from the level fin (:func:`fin_flow_regressors`)."""


def _fin_plate_features(
    u_l: NDArray[np.float64], w_l: NDArray[np.float64], d: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The plate's terms of :data:`FIN_FLOW_TERMS` at fin angle d, shape (n, 8)."""
    c, s = np.cos(d), np.sin(d)
    uc = c * u_l + s * w_l  # chord component (the fin frame is Ry(-d) of the body's)
    un = -s * u_l + c * w_l  # chord-normal component
    sp = np.sqrt(uc * uc + un * un)
    inv = np.divide(1.0, sp, out=np.zeros_like(sp), where=sp > 0)
    k = uc * un * inv
    ki = (uc * un * inv) ** 2 * inv
    fin = (
        (k * un, -k * uc),  # lift
        (ki * uc, ki * un),  # induced drag
        (0.0 * un, np.abs(un) * un),  # normal force
        (np.abs(uc) * uc, 0.0 * uc),  # profile drag (chordwise)
    )
    cols = []
    for a_c, a_n in fin:
        cols.append(c * a_c - s * a_n)  # body x
        cols.append(s * a_c + c * a_n)  # body z
    return np.stack(cols, axis=1)


def _fin_plate_change(
    u_l: NDArray[np.float64], w_l: NDArray[np.float64], d: NDArray[np.float64]
) -> NDArray[np.float64]:
    """:func:`_fin_plate_features` at d minus at 0 (the level fin), any shape (...) of the
    arguments, result (..., 8): the same numbers in fewer calls (the level fin's chord and
    normal components are u_l and w_l themselves)."""
    c, s = np.cos(d), np.sin(d)
    uc = c * u_l + s * w_l
    un = -s * u_l + c * w_l
    sp = np.sqrt(uc * uc + un * un)
    inv = np.divide(1.0, sp, out=np.zeros_like(sp), where=sp > 0)
    k = uc * un * inv
    ki = k**2 * inv
    sp0 = np.sqrt(u_l * u_l + w_l * w_l)
    inv0 = np.divide(1.0, sp0, out=np.zeros_like(sp0), where=sp0 > 0)
    k0 = u_l * w_l * inv0
    ki0 = k0**2 * inv0
    out = np.empty((*u_l.shape, 8))
    a_c, a_n = k * un, -k * uc  # lift
    out[..., 0] = (c * a_c - s * a_n) - k0 * w_l
    out[..., 1] = (s * a_c + c * a_n) - -k0 * u_l
    a_c, a_n = ki * uc, ki * un  # induced drag
    out[..., 2] = (c * a_c - s * a_n) - ki0 * u_l
    out[..., 3] = (s * a_c + c * a_n) - ki0 * w_l
    a_n = np.abs(un) * un  # normal force
    out[..., 4] = -(s * a_n)
    out[..., 5] = c * a_n - np.abs(w_l) * w_l
    a_c = np.abs(uc) * uc  # profile drag
    out[..., 6] = c * a_c - np.abs(u_l) * u_l
    out[..., 7] = s * a_c
    return out


def fin_flow_regressors(
    nu: NDArray[np.float64], d: NDArray[np.float64], position_body_m: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The regressors :data:`FIN_FLOW_TERMS` of one fin: its plate's terms at angle d minus at
    the level fin, in the local flow at the fin's centre (the rigid velocity v + omega x r there,
    its x and z components: heave, pitch and roll rates change the fin's angle of attack).

    Args:
        nu: (u, v, w, p, q, r) relative to the water, body FLU, m/s and rad/s, shape (n, 6).
        d: fin angle, rad (leading edge up +), shape (n,).
        position_body_m: the fin's centre, body FLU from the hull origin, shape (3,), m.

    Returns:
        Shape (n, 8).
    """
    x, y, z = position_body_m
    u_l = nu[:, 0] + nu[:, 4] * z - nu[:, 5] * y
    w_l = nu[:, 2] + nu[:, 3] * y - nu[:, 4] * x
    return _fin_plate_change(u_l, w_l, d)


TAIL_TERMS: tuple[str, ...] = (
    *("u|u| sin(b)", "u|u| sin(b)^2", "u|u| sin(b)^3"),
    *("f^2 sin(b)", "f^2 sin(b)^2", "f^2 sin(b)^3"),
)
"""Regressors of the tail bias's share of the tail's beat-averaged force at frequency f (Hz),
bias b (rad, tail to port +) and surge u (m/s); the straight swim's share is a table in f
(:attr:`ManoeuvringCoefficients.tail_straight`)."""


def tail_regressors(
    f: NDArray[np.float64], b: NDArray[np.float64], u: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The regressors :data:`TAIL_TERMS`.

    Args:
        f: tail-beat frequency, Hz, shape (n,).
        b: tail bias, rad (tail to port +), shape (n,).
        u: surge relative to the water, m/s, shape (n,).

    Returns:
        Shape (n, 6).
    """
    s = np.sin(b)
    uu = u * np.abs(u)
    ff = f * f
    s2 = s * s
    out = np.empty((s.shape[0], 6))
    out[:, 0] = uu * s
    out[:, 1] = uu * s2
    out[:, 2] = uu * s2 * s
    out[:, 3] = ff * s
    out[:, 4] = ff * s2
    out[:, 5] = ff * s2 * s
    return out


TAIL_HEAVE_TERMS: tuple[str, ...] = ("f w", "f w|w|", "f w^2")
"""Regressors of the beat's share of the force in heave at frequency f (Hz) and heave w (m/s,
body z relative to the water): what the beating tail and the hull's oscillation add to the
straight vehicle's heave force and pitch moment (X on the even term, Z and M on the odd ones),
identified from the full model's steady glides after open-loop fin steps."""


def tail_heave_regressors(f: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
    """The regressors :data:`TAIL_HEAVE_TERMS`.

    Args:
        f: tail-beat frequency, Hz, shape (n,).
        w: heave relative to the water, body FLU z, m/s, shape (n,).

    Returns:
        Shape (n, 3).
    """
    fw = f * w
    out = np.empty((fw.shape[0], 3))
    out[:, 0] = fw
    out[:, 1] = fw * np.abs(w)
    out[:, 2] = fw * w
    return out


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise a x b of shape (n, 3) arrays (np.cross's result, at a fraction of its overhead
    for small n)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def skew(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cross-product matrix S(a) with S(a) b = a x b, shape (..., 3, 3)."""
    z = np.zeros_like(a[..., 0])
    return np.stack(
        [
            np.stack([z, -a[..., 2], a[..., 1]], -1),
            np.stack([a[..., 2], z, -a[..., 0]], -1),
            np.stack([-a[..., 1], a[..., 0], z], -1),
        ],
        -2,
    )
