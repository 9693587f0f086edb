"""Seed 000's EKF over many passages at once, written for throughput.

The filter is the one of :mod:`nav.ekf` (seed 000 eq. 17-23, Joseph form, inactive components
left out, optional chi-square gate) for its particular structure: a 3-D position state whose
state Jacobian is the identity (eq. 17-18: ``x- = x + inc``, ``P- = P + Q``) and a measurement
of three components with a diagonal noise ``R`` (the USBL's range, azimuth and elevation, eq.
15 and 20). With that structure every matrix product of the update is a few products of
length-n vectors, so the tracks are kept as a *structure of arrays*: the time axis first, then
the component, then the passages,

- states ``xs``, shape (T + 1, 3, n): ``xs[k, i]`` is component i of every passage at tick k;
- covariances ``Ps``, shape (T + 1, 6, n), the upper triangle in the order of :data:`SYM`
  (00, 01, 02, 11, 12, 22).

Each tick's prediction is then one contiguous addition for the states and one for the
covariances, and an update is about 200 vector operations whatever n, where the stacked-matrix
form of :func:`nav.ekf.update` spends most of its time in numpy's per-matrix dispatch of
3 x 3 products. The numbers equal :func:`nav.ekf.update` and filterpy's ``ExtendedKalmanFilter``
to rounding (tested to 1e-9 against filterpy stepped tick by tick).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from nav.ekf import adjugate_sym3
from nav.errors import FilterDivergedError, NavInputError

Array = NDArray[np.float64]

SYM = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
"""The (row, column) of each stored component of a symmetric 3 x 3 covariance."""
_IDX = ((0, 1, 2), (1, 3, 4), (2, 4, 5))  # _IDX[i][j]: where P[i][j] is stored


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
    gate_limits: Array | None = None,
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
        gate_limits: chi-square limits of the NIS by number of active components, shape (4,)
            (index 0 unused), or None for no gate.

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
                xs[k + 1], Ps[k + 1], model, z[:, j], present[:, j], r_diag, gate_limits
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
    gate_limits: Array | None,
) -> tuple[Array, NDArray[np.bool_]]:
    """One update of all passages in place (eq. 19-23, Joseph form).

    Args:
        x: states, shape (3, n), updated in place.
        Pp: packed covariances, shape (6, n), updated in place.
        model: the measurement model.
        z: measurements, shape (n, 3).
        present: shape (n,).
        r: the diagonal of R, shape (3,).
        gate_limits: see :func:`ekf_tracks`.

    Returns:
        ``(nis (n,), rejected (n,))``; NIS NaN where nothing was measured.
    """
    xt = x.T
    if hasattr(model, "linearise"):  # h, H and active from one evaluation of the geometry
        hx, Hm, act = model.linearise(xt)
    else:
        hx, Hm, act = model.h(xt), model.H(xt), model.active(xt)
    act = act & present[:, None]
    y_all = model.residual(np.where(present[:, None], z, hx), hx)
    # inactive components leave the update exactly: their H rows and innovations are zero (R is
    # diagonal, so no cross term remains), as nav.ekf.update does
    H = [[np.where(act[:, a], Hm[:, a, c], 0.0) for c in range(3)] for a in range(3)]
    y = [np.where(act[:, a], y_all[:, a], 0.0) for a in range(3)]
    P = [[Pp[_IDX[i][j]] for j in range(3)] for i in range(3)]
    PHt = [
        [P[i][0] * H[a][0] + P[i][1] * H[a][1] + P[i][2] * H[a][2] for a in range(3)]
        for i in range(3)
    ]  # (state i, measurement a)
    S = {}
    for a, b in SYM:  # eq. 20, upper triangle
        S[a, b] = H[a][0] * PHt[0][b] + H[a][1] * PHt[1][b] + H[a][2] * PHt[2][b]
        if a == b:
            S[a, b] = S[a, b] + r[a]
    (c00, c01, c02, c11, c12, c22), det = adjugate_sym3(*(S[ab] for ab in SYM))
    if np.any(det <= 0):
        raise NavInputError("innovation covariance is not positive definite")
    inv_det = 1.0 / det
    Si = [[c00, c01, c02], [c01, c11, c12], [c02, c12, c22]]
    Si = [[v * inv_det for v in row] for row in Si]
    Siy = [Si[a][0] * y[0] + Si[a][1] * y[1] + Si[a][2] * y[2] for a in range(3)]
    nis = y[0] * Siy[0] + y[1] * Siy[1] + y[2] * Siy[2]
    dof = act.sum(axis=1)
    measured = dof > 0
    rejected = np.zeros(len(dof), dtype=bool)
    if gate_limits is not None:
        rejected = measured & (nis > np.asarray(gate_limits)[dof])
    applied = measured & ~rejected
    K = [
        [PHt[i][0] * Si[0][a] + PHt[i][1] * Si[1][a] + PHt[i][2] * Si[2][a] for a in range(3)]
        for i in range(3)
    ]  # eq. 21
    A = [
        [
            (1.0 if i == c else 0.0) - (K[i][0] * H[0][c] + K[i][1] * H[1][c] + K[i][2] * H[2][c])
            for c in range(3)
        ]
        for i in range(3)
    ]  # I - K H
    AP = [
        [A[i][0] * P[0][c] + A[i][1] * P[1][c] + A[i][2] * P[2][c] for c in range(3)]
        for i in range(3)
    ]
    new = []
    for i, j in SYM:  # eq. 23, Joseph form: (I - KH) P (I - KH)^T + K R K^T
        v = AP[i][0] * A[j][0] + AP[i][1] * A[j][1] + AP[i][2] * A[j][2]
        v = v + K[i][0] * r[0] * K[j][0] + K[i][1] * r[1] * K[j][1] + K[i][2] * r[2] * K[j][2]
        new.append(v)
    for i in range(3):  # eq. 22
        np.copyto(x[i], x[i] + K[i][0] * y[0] + K[i][1] * y[1] + K[i][2] * y[2], where=applied)
    for c in range(6):
        np.copyto(Pp[c], new[c], where=applied)
    return np.where(measured, nis, np.nan), rejected
