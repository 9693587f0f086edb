"""Seed 000's EKF over many passages at once, written for throughput, and the reductions of its
tracks that are metrics (distance to a reference, NEES, the 1-sigma radius).

The filter is the one of :mod:`nav.ekf` (seed 000 eq. 17-23, Joseph form, inactive components
left out, optional chi-square gate) for its particular structure: a 3-D position state whose
state Jacobian is the identity (eq. 17-18: ``x- = x + inc``, ``P- = P + Q``) and a measurement
of three components with a diagonal noise ``R`` (the USBL's range, azimuth and elevation, eq.
15 and 20). With that structure every matrix product is a few products of length-n vectors, so
the tracks are kept as a *structure of arrays*: the time axis first, then the component, then
the passages,

- states ``xs``, shape (T + 1, 3, n): ``xs[k, i]`` is component i of every passage at tick k;
- covariances ``Ps``, shape (T + 1, 6, n), the upper triangle in the order of :data:`SYM`
  (00, 01, 02, 11, 12, 22).

Each tick's prediction is then one contiguous addition for the states and one for the
covariances, and each update is :func:`nav.ekf.update_packed3`, the one update's fast path for
this layout. The numbers equal :func:`nav.ekf.update` and filterpy's ``ExtendedKalmanFilter``
to rounding (tested to 1e-9 against filterpy stepped tick by tick).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from nav.ekf import SYM3, adjugate_sym3, update_packed3
from nav.errors import FilterDivergedError, NavInputError
from nav.models import TIME_CHUNK

Array = NDArray[np.float64]

SYM = SYM3
"""The (row, column) of each stored component of a symmetric 3 x 3 covariance
(:data:`nav.ekf.SYM3`)."""


class ThreeComponentMeasurement(Protocol):
    """What :func:`ekf_tracks` needs from a measurement model of the position (shapes: x (n, 3),
    z (n, 3)): :class:`nav.models.UsblMeasurement` is one."""

    def h(self, x: Array) -> Array: ...
    def H(self, x: Array) -> Array: ...
    def R(self) -> Array: ...
    def active(self, x: Array) -> NDArray[np.bool_]: ...
    def residual(self, z: Array, hx: Array) -> Array: ...


@dataclass(frozen=True)
class Tracks:
    """The EKF's tracks of n passages over T ticks.

    Attributes:
        xs: states, shape (T + 1, 3, n), m, world (structure of arrays, see the module).
        Ps: covariances' upper triangles, shape (T + 1, 6, n), m^2, in the order of :data:`SYM`.
        nis: normalised innovation squared at each fix, shape (n, k); NaN where no measurement
            was used (none produced, or no active component).
        rejected: fixes the gate rejected, shape (n, k).
    """

    xs: Array
    Ps: Array
    nis: Array
    rejected: NDArray[np.bool_]

    def positions(self) -> Array:
        """The states as (n, T + 1, 3), a view."""
        return self.xs.transpose(2, 0, 1)

    def covariances(self) -> Array:
        """The full covariances, shape (n, T + 1, 3, 3) (built on each call)."""
        return unpack(self.Ps)


def pack(P: Array) -> Array:
    """Covariances (..., 3, 3) as upper triangles (6, ...) in the order of :data:`SYM`."""
    return np.stack([P[..., i, j] for i, j in SYM])


def unpack(Pp: Array) -> Array:
    """Packed covariance tracks (T + 1, 6, n) as full matrices (n, T + 1, 3, 3)."""
    T1, _, n = Pp.shape
    full = np.empty((n, T1, 3, 3))
    for c, (i, j) in enumerate(SYM):
        full[:, :, i, j] = full[:, :, j, i] = Pp[:, c].T
    return full


def nees_packed(err: Array, Pp: Array) -> Array:
    """NEES ``e^T P^-1 e`` of packed covariances, written out from the adjugate.

    Args:
        err: estimate minus truth, shape (3, ...).
        Pp: packed covariances, shape (6, ...), order :data:`SYM`.

    Returns:
        Shape (...). Tested against ``numpy.linalg.solve``.
    """
    (c00, c01, c02, c11, c12, c22), det = adjugate_sym3(*Pp)
    x, y, z = err
    q = c00 * x * x + c11 * y * y + c22 * z * z + 2.0 * (c01 * x * y + c02 * x * z + c12 * y * z)
    return q / det


def ekf_tracks(
    x0: Array,
    P0: Array,
    inc: Array,
    Q: Array,
    fix_tick: NDArray[np.intp],
    z: Array,
    present: NDArray[np.bool_],
    model: ThreeComponentMeasurement,
    gate_probability: float | None = None,
) -> Tracks:
    """Run the EKF over n passages of T ticks (seed 000 eq. 17-23, F = I).

    Args:
        x0: initial states, shape (n, 3), m, world.
        P0: initial covariance, shape (3, 3) or (n, 3, 3), m^2.
        inc: each tick's displacement ``f(x, u) - x``, shape (T, 3, n), m (time-major, the
            layout of the states).
        Q: each tick's process noise packed, shape (T, 6, n), m^2 (order :data:`SYM`).
        fix_tick: tick at which each measurement is applied (after that tick's prediction),
            shape (k,), each in 1..T.
        z: measurements, shape (n, k, 3); rows where ``present`` is False may hold anything.
        present: which passages have each measurement, shape (n, k).
        model: the measurement model; its ``R`` must be diagonal.
        gate_probability: the chi-square gate on the NIS (e.g. 0.99; the quantile for each
            fix's number of active components), or None for no gate.

    Returns:
        The tracks.

    Raises:
        NavInputError: if R is not diagonal with positive variances.
        FilterDivergedError: if a final state or covariance is not finite.
    """
    T, _, n = inc.shape
    R = np.asarray(model.R(), dtype=float)
    r_diag = np.diagonal(R)
    if np.any(R != np.diag(r_diag)) or np.any(r_diag <= 0):
        raise NavInputError("ekf_tracks needs a diagonal R with positive variances")
    xs = np.empty((T + 1, 3, n))
    Ps = np.empty((T + 1, 6, n))
    xs[0] = np.asarray(x0, dtype=float).T
    Ps[0] = pack(np.broadcast_to(P0, (n, 3, 3)))
    k_fix = len(fix_tick)
    nis = np.full((n, k_fix), np.nan)
    rejected = np.zeros((n, k_fix), dtype=bool)
    fix_at = {int(t): j for j, t in enumerate(fix_tick)}
    for k in range(T):
        np.add(xs[k], inc[k], out=xs[k + 1])  # eq. 17 with F = I
        np.add(Ps[k], Q[k], out=Ps[k + 1])  # eq. 18 with F = I
        j = fix_at.get(k + 1)
        if j is not None:
            nis[:, j], rejected[:, j] = _update(
                xs[k + 1], Ps[k + 1], model, z[:, j], present[:, j], r_diag, gate_probability
            )
    if not (np.isfinite(xs[T]).all() and np.isfinite(Ps[T]).all()):
        bad = np.flatnonzero(~(np.isfinite(xs[T]).all(0) & np.isfinite(Ps[T]).all(0)))
        raise FilterDivergedError(f"EKF diverged at tick {T} in batch rows {bad[:5].tolist()}")
    return Tracks(xs, Ps, nis, rejected)


def _update(
    x: Array,
    Pp: Array,
    model: ThreeComponentMeasurement,
    z: Array,
    present: NDArray[np.bool_],
    r: Array,
    gate_probability: float | None,
) -> tuple[Array, NDArray[np.bool_]]:
    """One update of all passages in place (eq. 19-23: :func:`nav.ekf.update_packed3`).

    Args:
        x: states, shape (3, n), updated in place.
        Pp: packed covariances, shape (6, n), updated in place.
        model: the measurement model.
        z: measurements, shape (n, 3).
        present: shape (n,).
        r: the diagonal of R, shape (3,).
        gate_probability: see :func:`ekf_tracks`.

    Returns:
        ``(nis (n,), rejected (n,))``; NIS NaN where nothing was measured.
    """
    xt = x.T
    if hasattr(model, "linearise"):  # h, H and active from one evaluation of the geometry
        hx, Hm, act = model.linearise(xt)
    else:
        hx, Hm, act = model.h(xt), model.H(xt), model.active(xt)
    y = model.residual(np.where(present[:, None], z, hx), hx)
    info = update_packed3(x, Pp, y, Hm, r, act, present, gate_probability)
    return info.nis, info.rejected


# ----------------------------------------------------------------------------------------------
# Reductions of tracks that are metrics


def horizontal_distance_tm(pos: Array, ref: Array) -> Array:
    """Horizontal distance of tracks to a reference, ``sqrt(de^2 + dn^2)``, shape (n, T + 1), m.

    Args:
        pos: positions, shape (n, T + 1, 3), m, world: a view of time-major (T + 1, 3, n) tracks
            (as :meth:`Tracks.positions`), which this reads in its time-major order.
        ref: the reference, shape (T + 1, 3), m, world.

    A few dozen ticks at a time on the time-major layout, so the temporaries stay in cache (the
    numbers of :func:`nav.metrics.horizontal_distance` to rounding: a square root of the sum of
    squares rather than ``hypot``, 5x faster).
    """
    tm = pos.transpose(1, 2, 0)  # (T + 1, 3, n)
    out = np.empty(tm.shape[::2])
    for a in range(0, len(out), TIME_CHUNK):
        b = a + TIME_CHUNK
        de = tm[a:b, 0] - ref[a:b, 0, None]
        dn = tm[a:b, 1] - ref[a:b, 1, None]
        de *= de
        dn *= dn
        de += dn
        np.sqrt(de, out=out[a:b])
    return out.T


def nees_tm(xs: Array, Pp: Array, ref: Array) -> Array:
    """NEES ``e^T P^-1 e`` of time-major tracks against a reference, shape (n, T + 1).

    Args:
        xs: states, shape (T + 1, 3, n), m, world.
        Pp: packed covariances, shape (T + 1, 6, n), m^2, order :data:`SYM`.
        ref: the reference (truth), shape (T + 1, 3), m, world.
    """
    out = np.empty(xs.shape[::2])
    for a in range(0, len(out), TIME_CHUNK):  # a few dozen ticks at a time: in the cache
        b = a + TIME_CHUNK
        err = np.moveaxis(xs[a:b] - ref[a:b, :, None], 1, 0)  # (3, ticks, n)
        out[a:b] = nees_packed(err, np.moveaxis(Pp[a:b], 1, 0))
    return out.T


def sigma_h(Pp: Array) -> Array:
    """The horizontal 1-sigma radius ``sqrt(P_ee + P_nn)`` of packed covariance tracks
    (T + 1, 6, ...), shape (T + 1, ...), m (seed 000 eq. 11's mean error of the estimate)."""
    return np.sqrt(np.maximum(Pp[:, 0] + Pp[:, 3], 0.0))
