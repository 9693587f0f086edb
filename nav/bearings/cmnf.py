"""Seed 004: the conditionally minimax nonlinear filter (CMNF, eq. 22-24) with Monte Carlo gains.

At every step k the CMNF predicts and corrects with linear functions of two structure functions,
the basic prediction ``alpha_k`` and the basic correction ``beta_k``::

    X~_k = F_k alpha_k + f_k,     F_k = cov(X_k, alpha_k) cov^+(alpha_k, alpha_k),
                                  f_k = E X_k - F_k E alpha_k
    X^_k = X~_k + H_k beta_k + h_k,  H_k = cov(X_k - X~_k, beta_k) cov^+(beta_k, beta_k),
                                     h_k = -H_k E beta_k

(eq. 22; its second line writes X~ on the left for X^). The covariances are Monte Carlo moments
over training paths. Because the control depends on the estimate, the paths are run with the
CMNF itself in the loop, one time step at a time (:func:`train`): the gains of step k are fitted
on the paths the gains of steps 1..k-1 produced (seed README). The pseudo-inverses treat singular
values below an absolute floor as zero: with the locally optimal control, ``alpha_k`` (prediction
by virtue of the system) is the nominal point on every path, so cov(alpha, alpha) is rounding
noise that a relative cut-off would amplify into huge gains (then ``F_k = 0`` and ``X~_k = E X_k``).

The CMNF is its own algorithm, not a Kalman update (the documented exception to the one update of
:mod:`nav.ekf`): its gains are regression coefficients of Monte Carlo moments, fitted offline, and
no measurement model or innovation covariance enters a step.

The CMNF states its own accuracy (section 5.2): ``cov(X - X~) = cov(X, X) - F cov(alpha, X)`` and
``cov(X - X^) = cov(X - X~) - H cov(beta, X - X~)``, kept per step in :class:`CmnfGains`.

Structure functions (eq. 24): ``alpha`` is the estimate plus the step's predicted displacement
(a :class:`nav.bearings.Prediction`: by virtue of the system, or the seabed-sensing shift);
``beta`` is the residual ``Y_k - Psi(X~_k)`` of the bearing tangents (``"residual"``; eq. 24's
explicit form with ``(Z_B - Z)/rho``, which is eq. 17 under this project's reading of phi,
:mod:`nav.bearings`) or, beyond the paper, the pseudo-measurement residual ``Y'_k - Psi1(Y_k)
X~_k`` of eq. 20 (``"pseudo"``). Absent pairs contribute a zero residual.

**Winsorised correction (beyond the paper).** A tangent of eq. 17 is a ratio, ``tan phi = (Y_B -
Y) / (X_B - X)``: on paths that pass close to ``X = X_B`` its distribution has Cauchy-like tails
(infinite variance), so the sample moments of ``beta`` over the training paths never settle. Near a
beacon (``paper-004/near-beacon``) one training path in 1e4 then holds 95 % of a feature's sum of
squares, the gain on that feature is set by whether the training sample happened to contain such a
path, and a test path with a residual beyond anything seen in training (144 against at most 5.4)
gets a correction of hundreds of metres from the linear gain (J-bar 25.7 against 6.0). The gains
are therefore fitted on, and applied to, ``beta`` clipped per step and feature at ``median +- c
sigma_r`` of the training paths (:func:`clip_bounds`; ``sigma_r`` the robust standard deviation
from the 5th and 95th percentiles, ``c = clip_sigmas``, default :data:`DEFAULT_CLIP_SIGMAS`). The
clipped ``beta`` is itself a structure function (a fixed function of the observations per step),
so eq. 22 and the stated covariances hold for it exactly; a near-Gaussian feature is practically
never clipped (beyond 6 sigma: 2e-9 of the paths), so where the features are well behaved (Table 1,
row 1) the filter is eq. 22-24 unchanged. ``clip_sigmas=None`` is the paper's unclipped filter.

Gains are plain data: :meth:`CmnfGains.save` writes an ``.npz`` read back with
``allow_pickle=False`` (no pickle).
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from nav.bearings.filters import pinv_floor, pseudo_measurements
from nav.bearings.model import Prediction, bearings
from nav.errors import NavInputError

Array = NDArray[np.float64]

Correction = Literal["residual", "pseudo"]
CORRECTIONS: tuple[str, ...] = ("residual", "pseudo")

DEFAULT_FLOOR = 1e-9
"""Absolute singular-value floor of the CMNF pseudo-inverses (units of the covariance: m^2 for
alpha, squared tangents for beta; the bearing noise variance tan^2(0.5 deg) is 7.6e-5)."""

DEFAULT_CLIP_SIGMAS = 6.0
"""Half-width of the winsorisation of ``beta`` in robust standard deviations (module docstring):
a Gaussian feature lies beyond it with probability 2e-9 (per step and feature, 0.002 of 1e6
training paths on average), while a tangent with Cauchy-like tails is held to the range its gain
was fitted on."""

_Z95 = 1.6448536269514722
"""The standard normal's 95th percentile: ``(q95 - q5) / (2 _Z95)`` is a Gaussian's sigma."""


def clip_bounds(b: Array, sigmas: float | None) -> tuple[Array, Array]:
    """Winsorisation bounds of the basic correction, per feature (module docstring).

    ``median +- sigmas * sigma_r`` with the robust standard deviation ``sigma_r = (q95 - q5) /
    (2 z_0.95)`` (equal to sigma for a Gaussian; unaffected by up to 5 % of the paths in either
    tail). A feature whose 5th and 95th percentiles coincide (at least 90 % of the paths equal,
    e.g. a beacon absent on most paths, whose residual is then zero) is not clipped.

    Args:
        b: the basic correction on the training paths, shape ``(n, q)``.
        sigmas: ``c``; None: no clipping.

    Returns:
        ``(lo, hi)``, each shape ``(q,)`` (``-inf`` and ``inf`` where not clipped).
    """
    q = b.shape[1]
    if sigmas is None:
        return np.full(q, -np.inf), np.full(q, np.inf)
    q05, q50, q95 = np.quantile(b, [0.05, 0.5, 0.95], axis=0)
    scale = (q95 - q05) / (2.0 * _Z95)
    half = np.where(scale > 0, sigmas * scale, np.inf)
    return q50 - half, q50 + half


def beta(kind: str, x_tilde: Array, y: Array, present: NDArray[np.bool_], beacons: Array) -> Array:
    """The basic correction function (seed 004, eq. 24; module docstring).

    Args:
        kind: ``"residual"`` (eq. 24) or ``"pseudo"`` (eq. 20's residual, beyond the paper).
        x_tilde: predictions, shape ``(n, 3)``, m.
        y: measured tangents, shape ``(n, B, 2)``.
        present: shape ``(n, B)``.
        beacons: shape ``(B, 3)``, m.

    Returns:
        Shape ``(n, 2 B)``: dimensionless for ``"residual"``, m for ``"pseudo"``.
    """
    n = len(x_tilde)
    h0, ok = bearings(x_tilde, beacons)
    use = (ok & present)[..., None]
    if kind == "residual" and use.all():
        r = y - h0
    elif kind == "residual":
        r = np.where(use, y - h0, 0.0)
    elif kind == "pseudo":
        yp, psi1, _ = pseudo_measurements(np.where(present[..., None], y, 0.0), x_tilde, beacons)
        r = np.where(use, yp - np.einsum("nbij,nj->nbi", psi1, x_tilde), 0.0)
    else:
        raise NavInputError(f"correction = {kind!r}: must be one of {', '.join(CORRECTIONS)}")
    return r.reshape(n, -1)


ROW_CHUNK = 4096
"""Rows per product in :func:`rows_times`."""


def rows_times(a: Array, m: Array) -> Array:
    """``a @ m.T`` for a tall ``a`` ``(n, p)`` and a small ``m`` ``(d, p)``, in row chunks.

    One call over 1e5 rows makes OpenBLAS split a product of a few flops per row over its
    threads; on a shared 2-core machine with the other core busy that took 70-80 ms instead of
    ~1 ms. Chunks of :data:`ROW_CHUNK` rows stay below its threading threshold. Same result.

    Returns:
        Shape ``(n, d)``.
    """
    out = np.empty((len(a), len(m)))
    mt = np.ascontiguousarray(m.T)
    for i in range(0, len(a), ROW_CHUNK):
        np.matmul(a[i : i + ROW_CHUNK], mt, out=out[i : i + ROW_CHUNK])
    return out


def _moments(a: Array, b: Array) -> tuple[Array, Array, Array, Array, Array]:
    """Sample means and (1/n) covariances of two row sets ``(n, p)``, ``(n, q)`` in one product.

    Returns:
        ``(mean_a (p,), mean_b (q,), cov(a, a) (p, p), cov(a, b) (p, q), cov(b, b) (q, q))``.
    """
    p = a.shape[1]
    z = np.concatenate([a, b], axis=1)
    m = z.sum(axis=0) / len(z)
    z -= m
    c = z.T @ z / len(z)
    return m[:p], m[p:], c[:p, :p], c[:p, p:], c[p:, p:]


def prediction_gain(x: Array, alpha: Array, floor: float) -> tuple[Array, Array, Array]:
    """F_k, f_k and the predicted error covariance from Monte Carlo samples (seed 004, eq. 22).

    Args:
        x: true states at t_k, shape ``(n, 3)``, m.
        alpha: the basic prediction at t_k, shape ``(n, p)``.
        floor: absolute singular-value floor of ``cov^+(alpha, alpha)``.

    Returns:
        ``(F (3, p), f (3,), P~ (3, 3))``; ``P~ = cov(X, X) - F cov(alpha, X)``.
    """
    mx, ma, c_xx, c_xa, c_aa = _moments(x, alpha)
    F = c_xa @ pinv_floor(c_aa, floor)
    f = mx - F @ ma
    p = c_xx - F @ c_xa.T
    return F, f, 0.5 * (p + p.T)


def correction_gain(
    x: Array, x_tilde: Array, b: Array, p_tilde: Array, floor: float
) -> tuple[Array, Array, Array]:
    """H_k, h_k and the corrected error covariance (seed 004, eq. 22 and section 5.2).

    Args:
        x: true states at t_k, shape ``(n, 3)``, m.
        x_tilde: the CMNF predictions, shape ``(n, 3)``, m.
        b: the basic correction, shape ``(n, q)``.
        p_tilde: the prediction's stated error covariance, ``(3, 3)``, m^2.
        floor: absolute singular-value floor of ``cov^+(beta, beta)``.

    Returns:
        ``(H (3, q), h (3,), P^ (3, 3))``; ``P^ = P~ - H cov(beta, X - X~)``.
    """
    _, mb, _, c_eb, c_bb = _moments(x - x_tilde, b)
    H = c_eb @ pinv_floor(c_bb, floor)
    h = -H @ mb
    p = p_tilde - H @ c_eb.T
    return H, h, 0.5 * (p + p.T)


@dataclass
class CmnfGains:
    """The fitted gains of every step and the CMNF's own error covariances (plain data).

    Step ``k`` (1..N) uses row ``k - 1``.

    Attributes:
        F: shape ``(N, 3, p)``; f: ``(N, 3)`` m; H: ``(N, 3, q)``; h: ``(N, 3)`` m.
        p_tilde: stated covariance of ``X_k - X~_k``, ``(N, 3, 3)`` m^2.
        p_hat: stated covariance of ``X_k - X^_k``, ``(N, 3, 3)`` m^2.
        info: what the gains were trained with (structure, floor, paths, seed...), JSON-able.
        beta_lo, beta_hi: the winsorisation bounds of ``beta`` per step, ``(N, q)`` each
            (:func:`clip_bounds`; ``-inf`` / ``inf`` where a feature is not clipped); None: the
            gains apply to the unclipped ``beta`` (the paper's filter).
    """

    F: Array
    f: Array
    H: Array
    h: Array
    p_tilde: Array
    p_hat: Array
    info: dict = field(default_factory=dict)
    beta_lo: Array | None = None
    beta_hi: Array | None = None

    @property
    def n_steps(self) -> int:
        """Number of steps N."""
        return len(self.F)

    def to_bytes(self) -> bytes:
        """The gains as the bytes of an ``.npz`` of plain arrays (the info as a JSON string), as
        :meth:`save` writes them (for a caller that writes files its own way)."""
        clip = {}
        if self.beta_lo is not None and self.beta_hi is not None:
            clip = {"beta_lo": self.beta_lo, "beta_hi": self.beta_hi}
        buf = io.BytesIO()
        np.savez(
            buf,
            F=self.F,
            f=self.f,
            H=self.H,
            h=self.h,
            p_tilde=self.p_tilde,
            p_hat=self.p_hat,
            info=np.array(json.dumps(self.info, sort_keys=True)),
            **clip,
        )
        return buf.getvalue()

    def save(self, path: str | Path) -> Path:
        """Write the gains as an ``.npz`` of plain arrays (the info as a JSON string)."""
        path = Path(path)
        path.write_bytes(self.to_bytes())
        return path

    @classmethod
    def load(cls, path: str | Path) -> CmnfGains:
        """Read gains written by :meth:`save` (``allow_pickle=False``).

        Raises:
            NavInputError: if the file lacks a field or the shapes disagree.
        """
        with np.load(Path(path), allow_pickle=False) as z:
            try:
                g = cls(
                    F=z["F"],
                    f=z["f"],
                    H=z["H"],
                    h=z["h"],
                    p_tilde=z["p_tilde"],
                    p_hat=z["p_hat"],
                    info=json.loads(str(z["info"])),
                    beta_lo=z["beta_lo"] if "beta_lo" in z.files else None,
                    beta_hi=z["beta_hi"] if "beta_hi" in z.files else None,
                )
            except KeyError as exc:
                raise NavInputError(f"CMNF gains file {path}: missing field {exc}") from None
        n = len(g.F)
        shapes = {
            "f": (n, 3),
            "h": (n, 3),
            "p_tilde": (n, 3, 3),
            "p_hat": (n, 3, 3),
        }
        if (g.beta_lo is None) != (g.beta_hi is None):
            raise NavInputError(f"CMNF gains file {path}: beta_lo and beta_hi come together")
        if g.beta_lo is not None:
            shapes["beta_lo"] = shapes["beta_hi"] = (n, g.H.shape[-1])
        for k, s in shapes.items():
            if getattr(g, k).shape != s:
                raise NavInputError(f"CMNF gains file {path}: {k} shape {getattr(g, k).shape}")
        return g


def cmnf_step(
    gains: CmnfGains,
    k: int,
    alpha: Array,
    correction: str,
    y: Array,
    present: NDArray[np.bool_],
    beacons: Array,
) -> tuple[Array, Array]:
    """One CMNF step with fitted gains (seed 004, eq. 22).

    Args:
        gains: the fitted gains.
        k: step index, 1..N.
        alpha: the basic prediction at t_k, shape ``(n, p)``.
        correction: the basic correction function's kind (:func:`beta`).
        y: tangents at t_k, shape ``(n, B, 2)``; present: ``(n, B)``.
        beacons: ``(B, 3)``, m.

    Returns:
        ``(x_tilde, x_hat)``, each ``(n, 3)``, m; ``beta`` is clipped to the gains' bounds
        (:attr:`CmnfGains.beta_lo`, ``beta_hi``) when they have them.
    """
    i = k - 1
    x_tilde = rows_times(alpha, gains.F[i]) + gains.f[i]
    b = beta(correction, x_tilde, y, present, beacons)
    if gains.beta_lo is not None and gains.beta_hi is not None:
        b = np.clip(b, gains.beta_lo[i], gains.beta_hi[i])
    return x_tilde, x_tilde + rows_times(b, gains.H[i]) + gains.h[i]


class TrainingWorld(Protocol):
    """The truth the gains are fitted on (a kinematic world implements it).

    ``start()`` gives the true initial positions ``(n, 3)`` m; ``advance(k, x, u)`` the true
    positions at t_{k+1} from those at t_k under the controls ``(n, 3)``; ``observe(k, x)`` the
    measured tangents ``(n, B, 2)`` and their presence ``(n, B)`` at t_k.
    """

    def start(self) -> Array: ...

    def advance(self, k: int, x: Array, u: Array) -> Array: ...

    def observe(self, k: int, x: Array) -> tuple[Array, NDArray[np.bool_]]: ...


@dataclass
class TrainingTrace:
    """Diagnostics of a training pass, per step k = 0..N (no path is kept).

    Attributes:
        j: ``mean ||X°_k - X_k||^2`` over the training paths, ``(N + 1,)`` m^2 (eq. 4).
        mse: ``mean ||X_k - X^_k||^2``, ``(N + 1,)`` m^2.
        clipped: values of ``beta`` clipped (:func:`clip_bounds`), ``(N + 1,)`` (0 at k = 0).
        top_share: the largest share one path has in the sum of squared deviations of one
            feature of the (clipped) ``beta``, ``(N + 1,)`` (0 at k = 0): near 1 when a single
            path sets that feature's moments.
    """

    j: Array
    mse: Array
    clipped: Array = field(default_factory=lambda: np.zeros(0))
    top_share: Array = field(default_factory=lambda: np.zeros(0))


def top_share(b: Array) -> float:
    """The largest share one row has in the sum of squared deviations of one column of ``b``
    ``(n, q)`` (0 for constant columns): how much a single path sets a moment."""
    d = b - b.mean(axis=0)
    d *= d
    tot = d.sum(axis=0)
    share = np.where(tot > 0, d.max(axis=0) / np.where(tot > 0, tot, 1.0), 0.0)
    return float(share.max()) if share.size else 0.0


def train(
    world: TrainingWorld,
    m0: Array,
    n_steps: int,
    control: Callable[[int, Array], Array],
    prediction: Prediction,
    beacons: Array,
    correction: str = "residual",
    floor: float = DEFAULT_FLOOR,
    nominal: Array | None = None,
    info: dict | None = None,
    clip_sigmas: float | None = DEFAULT_CLIP_SIGMAS,
) -> tuple[CmnfGains, TrainingTrace]:
    """Fit the CMNF gains on paths run with the CMNF in the loop, one step at a time.

    For k = 1..N: the control of each path comes from its CMNF estimate at k - 1, the truth
    advances, ``alpha_k`` is formed from the estimate and the prediction, ``F_k, f_k`` are fitted,
    then the observations at k give ``beta_k``, clipped to bounds taken from these paths
    (:func:`clip_bounds`), and ``H_k, h_k``, and the paths' estimates are corrected with the
    fitted gains before the next step. Memory holds the current step only.

    Args:
        world: the truth (:class:`TrainingWorld`).
        m0: the initial estimate ``X^_0``, shape ``(3,)``, m.
        n_steps: N.
        control: ``(k, x_hat (n, 3)) -> u (n, 3)``: the control law on the estimate.
        prediction: the :class:`nav.bearings.Prediction` that makes ``alpha``.
        beacons: ``(B, 3)``, m.
        correction: kind of ``beta`` (:func:`beta`).
        floor: the pseudo-inverses' absolute singular-value floor.
        nominal: the nominal path ``(N + 1, 3)`` m, for :class:`TrainingTrace.j` (optional).
        info: extra facts stored with the gains.
        clip_sigmas: half-width of the winsorisation of ``beta`` in robust standard deviations
            (:func:`clip_bounds`); None: unclipped, the paper's filter (whose gains a few paths
            with extreme tangents can set, module docstring).

    Returns:
        ``(gains, trace)``.

    Raises:
        NavInputError: for an unknown correction, a negative floor or ``clip_sigmas``, or no
            more training paths than a gain row has unknowns (``2 B + 1``: the moments of
            ``beta`` from ``n`` paths have rank at most ``n - 1``, so the gains would only
            interpolate the training paths).
    """
    if correction not in CORRECTIONS:
        raise NavInputError(f"correction = {correction!r}: must be one of {', '.join(CORRECTIONS)}")
    if not floor >= 0:
        raise NavInputError(f"floor = {floor}: must be >= 0")
    if clip_sigmas is not None and not clip_sigmas > 0:
        raise NavInputError(f"clip_sigmas = {clip_sigmas}: must be > 0 (or None: no clipping)")
    x = np.asarray(world.start(), dtype=float)
    n = len(x)
    unknowns = 2 * len(beacons) + 1  # H_k's row and h_k's entry
    if n <= max(unknowns, 3 + 1):
        raise NavInputError(
            f"{n} CMNF training paths for {len(beacons)} beacons: a gain row has {unknowns} "
            f"unknowns (2 per beacon and the offset); need more than {max(unknowns, 4)} paths"
        )
    x_hat = np.broadcast_to(np.asarray(m0, float), x.shape).copy()
    Fs, fs, Hs, hs, pts, phs, los, his = [], [], [], [], [], [], [], []
    j = np.zeros(n_steps + 1)
    mse = np.zeros(n_steps + 1)
    clipped = np.zeros(n_steps + 1, dtype=np.int64)
    shares = np.zeros(n_steps + 1)
    if nominal is not None:
        j[0] = float(np.mean(np.sum((x - nominal[0]) ** 2, axis=1)))
    mse[0] = float(np.mean(np.sum((x - x_hat) ** 2, axis=1)))
    for k in range(1, n_steps + 1):
        u = control(k - 1, x_hat)
        x = world.advance(k - 1, x, u)
        shift = prediction(k - 1, x_hat, u)  # after the move: a sensed shift may use t_k's data
        alpha = x_hat + shift.displacement_m
        F, f, p_t = prediction_gain(x, alpha, floor)
        x_tilde = rows_times(alpha, F) + f
        y, present = world.observe(k, x)
        b = beta(correction, x_tilde, y, present, beacons)
        lo, hi = clip_bounds(b, clip_sigmas)
        if clip_sigmas is not None:
            out = (b < lo) | (b > hi)
            clipped[k] = int(out.sum())
            if clipped[k]:
                b = np.clip(b, lo, hi)
        shares[k] = top_share(b)
        H, h, p_h = correction_gain(x, x_tilde, b, p_t, floor)
        x_hat = x_tilde + rows_times(b, H) + h
        los.append(lo)
        his.append(hi)
        Fs.append(F)
        fs.append(f)
        Hs.append(H)
        hs.append(h)
        pts.append(p_t)
        phs.append(p_h)
        if nominal is not None:
            j[k] = float(np.mean(np.sum((x - nominal[k]) ** 2, axis=1)))
        mse[k] = float(np.mean(np.sum((x - x_hat) ** 2, axis=1)))
    meta = {
        "correction": correction,
        "floor": floor,
        "paths": n,
        "steps": n_steps,
        "clip_sigmas": clip_sigmas,
        "clipped": int(clipped.sum()),
        "top_share": float(shares.max()),
    }
    meta.update(info or {})
    gains = CmnfGains(
        F=np.array(Fs),
        f=np.array(fs),
        H=np.array(Hs),
        h=np.array(hs),
        p_tilde=np.array(pts),
        p_hat=np.array(phs),
        info=meta,
        beta_lo=None if clip_sigmas is None else np.array(los),
        beta_hi=None if clip_sigmas is None else np.array(his),
    )
    return gains, TrainingTrace(j=j, mse=mse, clipped=clipped, top_share=shares)
