"""Decentralised cooperative navigation: each vehicle fuses ranges with its peers' broadcast
estimates, by covariance intersection so that nothing is counted twice.

A :class:`CoopNavigator` holds one vehicle's block ``[east_m, north_m, clock_offset_s(,
clock_drift)]`` over n runs. A peer's broadcast (:class:`PeerEstimate`: its position and clock
offset at its transmission, with their 3 x 3 covariance) arrives with each range. The estimates of
two vehicles that have ranged to each other before are correlated by an unknown amount: fusing the
peer's estimate as if it were independent ("naive") counts the shared information again and
again, and the filter becomes over-confident.

**Covariance intersection** (Julier & Uhlmann 1997, "A non-divergent estimation algorithm in the
presence of unknown correlations", Proc. American Control Conference, eq. 5-6): for any
cross-covariance ``P_ij`` and any ``w`` in (0, 1),
``blockdiag(P_i / w, P_j / (1 - w)) >= [[P_i, P_ij], [P_ji, P_j]]``. The joint state
``[x_i, x_j]`` with that prior is updated with the range (independent of both estimates) through
:func:`nav.ekf.update_with`, and the receiver keeps its block: a posterior that bounds the true
error whatever the correlation (the "split"-free CI update of a measurement that involves both,
e.g. Carrillo-Arce, Nerurkar, Gordillo & Roumeliotis 2013, "Decentralized multi-robot cooperative
localization using covariance intersection", IROS, eq. 8-12). ``w`` minimises the determinant of
the receiver's posterior position covariance: a grid over (0, 1), then golden-section search in
the best grid cell, per run (vectorised). ``"naive"`` uses ``w = 1`` and the peer's covariance
unscaled (for the comparison).

**Relayed ranges.** A one-way range observes ``distance + c (b_receiver - b_sender)``: from one
direction alone a receiver separates its clock from the distance only as the geometry changes.
A vehicle's broadcast may carry the ranges it received since its last transmission, each with its
estimate at the reception (:func:`nav.cooperative.team_tracks` does so with
``CoopOptions.relay``); the original sender fuses it with ``fuse_range(..., sent_by_me=True)``,
``h = distance + c (b_peer - b_me)``, and the two directions of the pair give the clocks'
difference (the information the centralised filter has from both receptions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav import ekf
from nav.cooperative.clock import ClockOptions, block_size, vehicle_prior, vehicle_transition
from nav.cooperative.ranging import OwttRangeMeasurement, PositionFix, TwttRangeMeasurement
from nav.cooperative.team import CoopOptions, Fusion
from nav.ekf import UpdateInfo
from nav.errors import NavInputError

Array = NDArray[np.float64]

_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
_W_EDGE = 1e-6


@dataclass(frozen=True)
class PeerEstimate:
    """A vehicle's broadcast: its estimate at its transmission, over n runs.

    Attributes:
        position_m: (east, north), shape (n, 2), m.
        clock_offset_s: clock offset (local minus team time), shape (n,), s.
        cov_m2: covariance of ``[east, north, offset]``, shape (n, 3, 3) (m^2, m s, s^2).
    """

    position_m: Array
    clock_offset_s: Array
    cov_m2: Array

    def __post_init__(self) -> None:
        p = np.asarray(self.position_m, dtype=float)
        b = np.asarray(self.clock_offset_s, dtype=float)
        c = np.asarray(self.cov_m2, dtype=float)
        n = p.shape[0] if p.ndim == 2 else -1
        if n < 0 or p.shape != (n, 2) or b.shape != (n,) or c.shape != (n, 3, 3):
            raise NavInputError(
                f"PeerEstimate: position_m (n, 2), clock_offset_s (n,) and cov_m2 (n, 3, 3), not "
                f"shapes {p.shape}, {b.shape}, {c.shape}"
            )
        object.__setattr__(self, "position_m", p)
        object.__setattr__(self, "clock_offset_s", b)
        object.__setattr__(self, "cov_m2", c)

    @classmethod
    def from_parts(
        cls,
        position_m: ArrayLike,
        position_cov_m2: ArrayLike,
        clock_offset_s: ArrayLike,
        clock_var_s2: ArrayLike,
    ) -> PeerEstimate:
        """A broadcast from its position covariance (n, 2, 2) and its clock's variance (n,),
        taken uncorrelated."""
        pc = np.asarray(position_cov_m2, dtype=float)
        cov = np.zeros((pc.shape[0], 3, 3))
        cov[:, :2, :2] = pc
        cov[:, 2, 2] = clock_var_s2
        return cls(np.asarray(position_m, dtype=float), np.asarray(clock_offset_s, float), cov)

    def state(self) -> Array:
        """``[east, north, offset]``, shape (n, 3)."""
        return np.concatenate([self.position_m, self.clock_offset_s[:, None]], axis=1)


def _posterior_position_det(P_own: Array, g: Array, a: Array, b: Array, r, w: Array):
    """Determinant of the receiver's posterior position covariance for CI weights ``w``
    (n, G): prior ``P_own / w``, innovation variance ``S = a / w + b / (1 - w) + r`` with
    ``a = h_i P_i h_i^T``, ``b = h_j P_j h_j^T``, and ``g = P_i h_i^T``: the posterior position
    block is ``P_pp / w - g_p g_p^T / (w^2 S)`` (the scalar update's covariance, written out
    only to choose ``w``; the update itself is :func:`nav.ekf.update_with`'s)."""
    S = a[:, None] / w + b[:, None] / (1.0 - w) + r
    w2S = w * w * S
    m00 = P_own[:, 0, 0, None] / w - g[:, 0, None] ** 2 / w2S
    m11 = P_own[:, 1, 1, None] / w - g[:, 1, None] ** 2 / w2S
    m01 = P_own[:, 0, 1, None] / w - (g[:, 0] * g[:, 1])[:, None] / w2S
    return m00 * m11 - m01 * m01


def _posterior_state_log_det(P_own: Array, g: Array, a: Array, b: Array, r, w: Array):
    """``log det`` of the receiver's whole posterior block (up to a constant) for CI weights
    ``w`` (n, G): by the matrix determinant lemma ``det(P / w - g g^T / (w^2 S)) = det(P) w^-s
    (1 - a / (w S))``, and ``1 - a / (w S) = w c / (a + w c)`` with ``c = b / (1 - w) + r``."""
    s = P_own.shape[-1]
    c = b[:, None] / (1.0 - w) + r
    return -s * np.log(w) + np.log(w * c) - np.log(a[:, None] + w * c)


def ci_weight(
    P_own: ArrayLike,
    P_peer: ArrayLike,
    h_own: ArrayLike,
    h_peer: ArrayLike,
    r_m2: float,
    grid: int = 16,
    iterations: int = 20,
    criterion: str = "position",
) -> Array:
    """The covariance-intersection weight of a scalar measurement, per run: ``w`` in (0, 1)
    minimising the determinant of the receiver's posterior position covariance (Julier & Uhlmann
    1997 choose ``w`` minimising a measure of the fused covariance; here the measure is taken
    after the update, where it matters). A grid of ``grid`` points, then golden-section search in
    the best point's neighbourhood (``iterations`` steps, bracket shrinking by 0.618 each).

    Args:
        P_own: the receiver's covariance, shape (n, s, s) (position first).
        P_peer: the peer's covariance, shape (n, 3, 3).
        h_own: the measurement's Jacobian on the receiver's block, shape (n, s).
        h_peer: on the peer's block, shape (n, 3).
        r_m2: the measurement's noise variance, m^2, scalar or (n,).
        grid: grid points.
        iterations: golden-section steps.
        criterion: ``"position"`` (the determinant of the posterior position block) or
            ``"state"`` (of the whole block: ``det(P) w^-s (1 - a / (w S))`` by the matrix
            determinant lemma).

    Returns:
        ``w``, shape (n,), in ``[1e-6, 1 - 1e-6]``.
    """
    Po = np.asarray(P_own, dtype=float)
    Pp = np.asarray(P_peer, dtype=float)
    ho = np.asarray(h_own, dtype=float)
    hp = np.asarray(h_peer, dtype=float)
    r_m2 = np.broadcast_to(np.asarray(r_m2, dtype=float), (Po.shape[0],))[:, None]
    g = np.einsum("nij,nj->ni", Po, ho)
    a = np.einsum("ni,ni->n", ho, g)
    b = np.einsum("ni,nij,nj->n", hp, Pp, hp)
    n = Po.shape[0]
    objective = _posterior_state_log_det if criterion == "state" else _posterior_position_det
    ws = (np.arange(grid) + 1.0) / (grid + 1.0)
    f = objective(Po, g, a, b, r_m2, np.broadcast_to(ws, (n, grid)))
    best = np.argmin(f, axis=1)
    lo = np.where(best > 0, ws[np.maximum(best - 1, 0)], _W_EDGE)
    hi = np.where(best < grid - 1, ws[np.minimum(best + 1, grid - 1)], 1.0 - _W_EDGE)
    c = hi - _GOLDEN * (hi - lo)
    d = lo + _GOLDEN * (hi - lo)
    fc = objective(Po, g, a, b, r_m2, c[:, None])[:, 0]
    fd = objective(Po, g, a, b, r_m2, d[:, None])[:, 0]
    for _ in range(iterations):
        left = fc < fd  # the minimum lies in [lo, d]
        hi = np.where(left, d, hi)
        lo = np.where(left, lo, c)
        c_new = hi - _GOLDEN * (hi - lo)
        d_new = lo + _GOLDEN * (hi - lo)
        probe = np.where(left, c_new, d_new)
        fp = objective(Po, g, a, b, r_m2, probe[:, None])[:, 0]
        # left: the old c becomes d, the probe is the new c; right: the old d becomes c
        c, d, fc, fd = (
            np.where(left, c_new, d),
            np.where(left, c, d_new),
            np.where(left, fp, fd),
            np.where(left, fc, fp),
        )
    return np.clip(0.5 * (lo + hi), _W_EDGE, 1.0 - _W_EDGE)


class CoopNavigator:
    """One vehicle's decentralised filter over n runs: its dead reckoning, its fixes, and ranges
    fused with its peers' broadcasts by covariance intersection (or naively, for comparison).

    Args:
        start_m: initial position, shape (n, 2), m.
        start_cov_m2: its covariance, shape (n, 2, 2), m^2.
        clock: this vehicle's clock model (the leader's: GPS-disciplined, a small prior).
        fusion: ``"ci"`` or ``"naive"``.
        min_range_m: ranges below this are left out, m.
        gate_probability: chi-square gate of the range updates, or ``None``.
        ci_grid, ci_iterations, ci_criterion: the CI weight's search (:func:`ci_weight`).

    Attributes:
        x: state, shape (n, s): ``[east, north, offset(, drift)]``.
        P: covariance, shape (n, s, s).
        clock: the clock model.
        fusion: the fusion.
    """

    def __init__(
        self,
        start_m: ArrayLike,
        start_cov_m2: ArrayLike,
        clock: ClockOptions,
        *,
        fusion: Fusion = "ci",
        min_range_m: float = 0.5,
        gate_probability: float | None = None,
        ci_grid: int = 16,
        ci_iterations: int = 20,
        ci_criterion: str = "position",
    ):
        start = np.asarray(start_m, dtype=float)
        cov = np.asarray(start_cov_m2, dtype=float)
        if start.ndim != 2 or start.shape[1] != 2 or cov.shape != (*start.shape, 2):
            raise NavInputError(
                f"start_m (n, 2) and start_cov_m2 (n, 2, 2) must match, not shapes {start.shape} "
                f"and {cov.shape}"
            )
        if fusion not in ("ci", "naive"):
            raise NavInputError(f"fusion must be 'ci' or 'naive', not {fusion!r}")
        self.clock = clock
        self.fusion = fusion
        self.min_range_m = min_range_m
        self.gate_probability = gate_probability
        self.ci_grid, self.ci_iterations = ci_grid, ci_iterations
        if ci_criterion not in ("state", "position"):
            raise NavInputError(f"ci_criterion must be 'state' or 'position', not {ci_criterion!r}")
        self.ci_criterion = ci_criterion
        s = block_size(clock.estimate_drift)
        self.x = np.zeros((start.shape[0], s))
        self.x[:, :2] = start
        self.P = vehicle_prior(cov, clock)

    @classmethod
    def for_vehicle(
        cls, vehicle: int, start_m: ArrayLike, start_cov_m2: ArrayLike, options: CoopOptions
    ) -> CoopNavigator:
        """The navigator of team member ``vehicle`` (0: the leader's clock) with the team's
        options."""
        return cls(
            start_m,
            start_cov_m2,
            options.clock_of(vehicle),
            fusion=options.fusion,
            min_range_m=options.min_range_m,
            gate_probability=options.gate_probability,
            ci_grid=options.ci_grid,
            ci_iterations=options.ci_iterations,
            ci_criterion=options.ci_criterion,
        )

    def predict(self, step_m: ArrayLike, step_cov_m2: ArrayLike, dt_s: float) -> None:
        """Advance by the dead-reckoned step (:func:`nav.ekf.predict`): ``p += step``,
        ``b += d dt``.

        Args:
            step_m: displacement over ground, shape (n, 2), m.
            step_cov_m2: its covariance, shape (n, 2, 2), m^2.
            dt_s: duration, s (> 0).
        """
        if not dt_s > 0:
            raise NavInputError(f"dt_s must be > 0, not {dt_s!r}")
        F, Qc = vehicle_transition(self.clock, dt_s)
        Q = np.broadcast_to(Qc, self.P.shape).copy()
        Q[:, :2, :2] = step_cov_m2
        fx = self.x.copy()
        fx[:, :2] += step_m
        if self.clock.estimate_drift:
            fx[:, 2] += self.x[:, 3] * dt_s
        self.x, self.P = ekf.predict(self.x, self.P, fx, F, Q)

    def fuse_position(
        self, z_m: ArrayLike, cov_m2: ArrayLike, present: ArrayLike | None = None
    ) -> UpdateInfo:
        """Correct with a position fix (USBL, GPS), shape (n, 2) m, covariance (2, 2) or
        (n, 2, 2) m^2, through :func:`nav.ekf.update_with`."""
        model = PositionFix(0, cov_m2)
        self.x, self.P, info = ekf.update_with(self.x, self.P, model, np.asarray(z_m), present)
        return info

    def fuse_range(
        self,
        range_m: ArrayLike,
        peer: PeerEstimate,
        *,
        sigma_m: float,
        depth_m: ArrayLike,
        peer_depth_m: ArrayLike,
        kind: str = "owtt",
        sound_speed_m_s: float = 1500.0,
        lag_s: ArrayLike = 0.0,
        velocity_m_s: ArrayLike | None = None,
        present: ArrayLike | None = None,
        sent_by_me: bool = False,
        extra_var_m2: ArrayLike | None = None,
    ) -> tuple[UpdateInfo, Array]:
        """Fuse one range with the peer's broadcast (the module's CI update).

        Args:
            range_m: the ranges, shape (n,), m (OWTT: ``c_nom (L - T)``).
            peer: the sender's broadcast at its transmission (TWTT: the responder's estimate;
                ``sent_by_me``: the peer's estimate at its reception).
            sigma_m: the range's standard deviation, m.
            depth_m: this vehicle's depth at its end of the range, (n,) or scalar, m.
            peer_depth_m: the peer's depth at its end, m.
            kind: ``"owtt"`` or ``"twtt"``.
            sound_speed_m_s: the nominal sound speed of the ranges, m/s.
            lag_s: this filter's time minus this vehicle's instant of the range (its reception;
                ``sent_by_me``: its transmission; TWTT: the mid-time), s.
            velocity_m_s: this vehicle's velocity over ground, (n, 2), m/s (its displacement
                since that instant divided by ``lag_s``).
            present: runs with the range, shape (n,).
            sent_by_me: the range was transmitted by this vehicle and received by the peer, which
                relays it in its broadcast (OWTT: ``h = r + c_nom (b_peer - b_me)``; with the
                direct range of the pair it separates the clocks from the distance).
            extra_var_m2: variance added to the range's (the DR noise over the lags), (n,), m^2.

        Returns:
            ``(info, w)``: the update's diagnostics and the CI weight of each run (1 for
            naive fusion).
        """
        z = np.asarray(range_m, dtype=float).reshape(-1, 1)
        n, s = self.x.shape
        pres = np.ones(n, dtype=bool) if present is None else np.asarray(present, dtype=bool)
        pres = pres & np.isfinite(z[:, 0]) & (np.nan_to_num(z[:, 0]) >= self.min_range_m)
        dz = np.asarray(depth_m, dtype=float) - np.asarray(peer_depth_m, dtype=float)
        me, other = ("sender", "receiver") if sent_by_me else ("receiver", "sender")
        geometry = {
            f"{me}_at": 0,
            f"{other}_at": s,
            "sigma_m": sigma_m,
            "extra_var_m2": extra_var_m2,
            "dz_m": -dz if sent_by_me else dz,
            f"{me}_lag_s": lag_s,
            f"{me}_velocity_m_s": velocity_m_s,
        }
        if kind == "owtt":
            model = OwttRangeMeasurement(
                **geometry,
                sound_speed_m_s=sound_speed_m_s,
                **{f"{me}_drift": self.clock.estimate_drift},
            )
        elif kind == "twtt":
            model = TwttRangeMeasurement(**geometry)
        else:
            raise NavInputError(f"kind must be 'owtt' or 'twtt', not {kind!r}")
        xj = np.concatenate([self.x, peer.state()], axis=1)
        if self.fusion == "naive":
            w = np.ones(n)
            own_scale, peer_scale = np.ones(n), np.ones(n)
        else:
            H = model.H(xj)[:, 0]
            w = ci_weight(
                self.P,
                peer.cov_m2,
                H[:, :s],
                H[:, s:],
                model.R()[..., 0, 0],
                self.ci_grid,
                self.ci_iterations,
                self.ci_criterion,
            )
            own_scale, peer_scale = 1.0 / w, 1.0 / (1.0 - w)
        Pj = np.zeros((n, s + 3, s + 3))
        Pj[:, :s, :s] = self.P * own_scale[:, None, None]
        Pj[:, s:, s:] = peer.cov_m2 * peer_scale[:, None, None]
        xj, Pj, info = ekf.update_with(xj, Pj, model, z, pres, self.gate_probability)
        used = info.applied
        self.x = np.where(used[:, None], xj[:, :s], self.x)
        self.P = np.where(used[:, None, None], Pj[:, :s, :s], self.P)
        return info, w

    def broadcast(
        self, ahead_s: ArrayLike = 0.0, velocity_m_s: ArrayLike | None = None
    ) -> PeerEstimate:
        """This vehicle's broadcast, its estimate moved ``ahead_s`` (the transmission's time
        minus the filter's, s, scalar or (n,)) with its velocity (n, 2) m/s: the position by
        ``v ahead``, the offset by ``d ahead`` (with its covariance mapped by the same linear
        step; the velocity's own error over a fraction of a second is left out).

        Returns:
            The broadcast.
        """
        n, s = self.x.shape
        ahead = np.broadcast_to(np.asarray(ahead_s, dtype=float), (n,))
        T = np.zeros((n, 3, s))
        T[:, 0, 0] = T[:, 1, 1] = T[:, 2, 2] = 1.0
        if self.clock.estimate_drift:
            T[:, 2, 3] = ahead
        state = np.einsum("nij,nj->ni", T, self.x)
        if velocity_m_s is not None:
            state[:, :2] += np.asarray(velocity_m_s, dtype=float) * ahead[:, None]
        cov = T @ self.P @ np.swapaxes(T, 1, 2)
        return PeerEstimate(state[:, :2], state[:, 2], 0.5 * (cov + np.swapaxes(cov, 1, 2)))

    @property
    def position(self) -> Array:
        """Position estimate, shape (n, 2), m."""
        return self.x[:, :2]

    @property
    def covariance(self) -> Array:
        """Its covariance, shape (n, 2, 2), m^2."""
        return self.P[:, :2, :2]

    @property
    def clock_offset(self) -> Array:
        """Clock offset estimate, shape (n,), s."""
        return self.x[:, 2]

    @property
    def clock_variance(self) -> Array:
        """Its variance, shape (n,), s^2."""
        return self.P[:, 2, 2]
