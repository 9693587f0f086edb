"""Seed 004's closed loop on the kinematic world: EKF, UPMF and CMNF steering eq. 7 on their own
estimate, batched over paths, reduced to per-step sums (no path is kept but a few).

Each filter flies its own copy of every path (the control depends on the estimate) with the same
draws. Per filter and step the block keeps: the number of paths that are still finite, the sums of
``||X°_k - X_k||^2`` (eq. 4), of the error ``X_k - X^_k`` and of its square per axis, of the CMNF's
and the Kalman filters' stated error variance, of the Fisher information of the bearings at the
true positions (for the PCRB, :mod:`nav.bearings.pcrb`), the count of absent bearing pairs, and the
sample paths of the first runs. A filter whose estimate or covariance stops being finite on a path
is *diverged* there: the path leaves the sums from that step on and is counted.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bauv_sim.kinematic.seed004 import (
    NominalPathConfig,
    PathNoise,
    Seed004Noise,
    Seed004World,
    TrainingNoise,
)
from nav.bearings import SystemPrediction, bank
from nav.bearings.cmnf import DEFAULT_CLIP_SIGMAS, CmnfGains, train
from nav.bearings.local_control import ControlLimits, limited_control, optimal_control
from nav.bearings.pcrb import bearing_information

if TYPE_CHECKING:
    from bauv_sim.geo import GeoOriginConfig
    from bauv_sim.seabed import SeabedConfig
    from bauv_sim.sensors.multibeam import MultibeamConfig

Array = NDArray[np.float64]

FILTERS = ("CMNF", "UPMF", "EKF")
"""The filters of :mod:`nav.bearings.bank` in the order of the columns of the paper's Table 1."""
SHIFT_BIN_M = 0.05
SHIFT_BINS = 2000


@dataclass(frozen=True)
class LoopSetting:
    """What one closed loop needs (taken from a scenario by the experiments).

    Attributes:
        path: the nominal path.
        noise: truth's disturbances and bearing noise.
        beacons: ``(B, 3)`` m.
        filter_noise: what the filters assume (default: the truth's).
        filter_s0: the filters' initial covariance ``(3, 3)`` m^2 (default: the truth's S_0).
        limits: box limits of the control (None: unbounded, as in the paper).
        correction: the CMNF's basic correction (``"residual"`` or ``"pseudo"``).
        upmf_form: ``"unbiased"`` or ``"printed"`` (:func:`nav.bearings.upmf_update`).
        floor: the CMNF's singular-value floor.
        clip_sigmas: the CMNF's winsorisation of its basic correction, robust sigmas (None:
            unclipped, the paper's filter; :func:`nav.bearings.cmnf.clip_bounds`).
        train_paths: CMNF training paths.
        prediction: ``"system"`` (eq. 1, row 1 of Table 1), ``"seabed-one_attitude"`` /
            ``"seabed-turning"`` (eq. 15, row 2, over the seed's harmonic seabeds;
            :mod:`tasks.paper004.seabed`) or ``"heightfield"`` (eq. 15 over the heightfield
            ``heightfield`` with the multibeam ``multibeam``:
            :class:`tasks.paper004.seabed.HeightfieldPrediction`).
        heightfield: the scene's seabed (for ``"heightfield"``).
        heightfield_geo: the scene's origin on the Earth, for a seabed from a bathymetry file
            (``heightfield.file``).
        multibeam: the multibeam of a seabed prediction (default: seed 004's).
        slope_basis: Appendix A's basis (for ``"heightfield"``).
    """

    path: NominalPathConfig
    noise: Seed004Noise
    beacons: tuple[tuple[float, float, float], ...]
    filter_noise: Seed004Noise | None = None
    filter_s0: tuple[float, float, float] | None = None
    limits: ControlLimits | None = None
    correction: str = "residual"
    upmf_form: str = "unbiased"
    floor: float = 1e-9
    clip_sigmas: float | None = DEFAULT_CLIP_SIGMAS
    train_paths: int = 100_000
    prediction: str = "system"
    heightfield: SeabedConfig | None = None
    heightfield_geo: GeoOriginConfig | None = None
    multibeam: MultibeamConfig | None = None
    slope_basis: str = "quadratic"

    @property
    def b(self) -> Array:
        """Beacons as a ``(B, 3)`` array, m."""
        return np.asarray(self.beacons, dtype=float)

    @property
    def fnoise(self) -> Seed004Noise:
        """The noise the filters assume."""
        return self.filter_noise or self.noise

    @property
    def s0_filter(self) -> Array:
        """The filters' initial covariance, ``(3, 3)`` m^2."""
        if self.filter_s0 is None:
            return self.noise.s_0
        return np.diag(np.square(self.filter_s0))

    def key(self) -> str:
        """A stable text key of the setting (for the gains cache)."""
        d = {
            "path": self.path.model_dump(mode="json"),
            "noise": self.noise.model_dump(mode="json"),
            "fnoise": self.fnoise.model_dump(mode="json"),
            "beacons": self.beacons,
            "s0": self.filter_s0,
            "limits": None if self.limits is None else self.limits.__dict__,
            "correction": self.correction,
            "upmf_form": self.upmf_form,
            "floor": self.floor,
            "clip_sigmas": self.clip_sigmas,
            "train": self.train_paths,
            "prediction": self.prediction,
        }
        if self.prediction == "heightfield":
            d["heightfield"] = None if self.heightfield is None else self.heightfield.model_dump()
            d["slope_basis"] = self.slope_basis
            if self.heightfield_geo is not None:
                d["heightfield_geo"] = self.heightfield_geo.model_dump()
        if self.prediction != "system" and self.multibeam is not None:
            d["multibeam"] = self.multibeam.model_dump()
        return json.dumps(d, sort_keys=True)


class Controller:
    """The control law of a setting: eq. 7 (unbounded) or its box-limited form.

    Called as ``(k, x_hat (n, 3) m) -> u (n, 3)``; it remembers the previous command for the
    rate limits (starting from the nominal control at t_0).
    """

    def __init__(self, s: LoopSetting, n: int):
        self.xn = s.path.path()
        self.vn = s.path.velocities()
        self.dt = s.path.dt_s
        self.limits = s.limits
        self.prev = np.broadcast_to(s.path.controls()[0], (n, 3)).copy()

    def __call__(self, k: int, x_hat: Array) -> Array:
        if self.limits is None:
            u = optimal_control(x_hat, self.xn[k], self.vn[k], self.dt)
        else:
            u = limited_control(x_hat, self.xn[k], self.vn[k], self.dt, self.prev, self.limits)
        self.prev = u
        return u


class _SensedWorld:
    """A world whose every move is imaged by a sensing prediction (before and after)."""

    def __init__(self, world: Seed004World, pred):
        self.world, self.pred = world, pred

    def start(self) -> Array:
        return self.world.start()

    def advance(self, k: int, x: Array, u: Array) -> Array:
        self.pred.before(k, x, u)
        x1 = self.world.advance(k, x, u)
        self.pred.after(k, x1, u)
        return x1

    def observe(self, k: int, x: Array):
        return self.world.observe(k, x)


def prediction_of(s: LoopSetting, seed: int, runs: tuple[int, ...], world, stream: str):
    """The setting's prediction for a batch of paths, and the world it needs (sensed or not)."""
    if s.prediction == "system":
        return SystemPrediction(s.path.dt_s, s.fnoise.s_w), world
    if s.prediction == "heightfield":
        from tasks.paper004.seabed import HeightfieldPrediction, heightfield

        if s.heightfield is None or s.multibeam is None:
            raise ValueError("prediction 'heightfield' needs the heightfield and the multibeam")
        pred = HeightfieldPrediction(
            heightfield(s.heightfield, s.heightfield_geo),
            s.multibeam,
            s.slope_basis,
            seed,
            runs,
            s.path.dt_s,
            s.fnoise.s_w,
            stream,
        )
        return pred, _SensedWorld(world, pred)
    from tasks.paper004.seabed import SeabedPrediction

    reading = s.prediction.removeprefix("seabed-")
    pred = SeabedPrediction(
        reading, seed, runs, s.path.dt_s, s.path.controls(), stream, cfg=s.multibeam
    )
    return pred, _SensedWorld(world, pred)


def train_gains(s: LoopSetting, seed: int) -> tuple[CmnfGains, object]:
    """Fit the CMNF gains of a setting on ``s.train_paths`` training paths (CMNF in the loop)."""
    from tasks.paper004.seabed import TRAIN_RUN_OFFSET

    draws = TrainingNoise(s.noise, len(s.beacons), seed, s.train_paths)
    world = Seed004World(s.path, s.noise, s.b, draws)
    runs = tuple(range(TRAIN_RUN_OFFSET, TRAIN_RUN_OFFSET + s.train_paths))
    pred, world = prediction_of(s, seed, runs, world, "train")
    return train(
        world,
        np.asarray(s.path.start_m),
        s.path.n_steps,
        Controller(s, s.train_paths),
        pred,
        s.b,
        correction=s.correction,
        floor=s.floor,
        clip_sigmas=s.clip_sigmas,
        nominal=s.path.path(),
        info={"seed": seed, "prediction": s.prediction},
    )


@functools.lru_cache(maxsize=4)
def _cached_gains(key: str, seed: int, s: LoopSetting) -> CmnfGains:
    return train_gains(s, seed)[0]


def gains_for(s: LoopSetting, seed: int) -> CmnfGains:
    """The setting's gains, trained once per process (deterministic in ``(setting, seed)``)."""
    return _cached_gains(s.key(), seed, s)


@dataclass
class LoopSums:
    """Per-step sums of one block (shapes: F filters, N + 1 steps).

    Attributes:
        count: finite paths, ``(F, N + 1)``.
        j: sum of ``||X°_k - X_k||^2``, ``(F, N + 1)`` m^2.
        err: sum of ``X_k - X^_k``, ``(F, N + 1, 3)`` m.
        err2: sum of its square, ``(F, N + 1, 3)`` m^2.
        pred_err2: sum of the prediction's squared error ``||X_k - X~_k||^2``, ``(F, N + 1)``
            m^2 (0 at k = 0): on these test paths, which the CMNF's gains never saw, a correction
            that is worth its gains leaves ``err2`` below it.
        stated: sum of the filter's stated error variance per axis, ``(F, N + 1, 3)`` m^2 (the
            CMNF's is the same for every path).
        info: sum of the bearing information at the true positions, ``(F, N + 1, 3, 3)`` 1/m^2.
        absent: absent bearing pairs, ``(F, N + 1)``.
        diverged: paths that became non-finite, ``(F,)``.
        shift_n: predicted shifts compared with the true move (sensed predictions), ``(F,)``.
        shift_err: sum of ``dX^ - (X_{k+1} - X_k)``, ``(F, 3)`` m.
        shift_hist: histogram of its norm, bins of :data:`SHIFT_BIN_M` from 0 (the last bin
            holds everything beyond), ``(F, SHIFT_BINS)``.
        shift_none: sensed shifts not produced (too few echoes; the command stood in), ``(F,)``.
        shift_beams: sum of the beams the sensed shifts used (produced or not), ``(F,)``.
        samples: run -> filter -> ``(N + 1, 6)`` true and estimated positions (float32).
    """

    count: Array
    j: Array
    err: Array
    err2: Array
    stated: Array
    info: Array
    absent: Array
    diverged: Array
    shift_n: Array
    shift_err: Array
    shift_hist: Array
    shift_none: Array = field(default_factory=lambda: np.zeros(0))
    shift_beams: Array = field(default_factory=lambda: np.zeros(0))
    pred_err2: Array = field(default_factory=lambda: np.zeros(0))
    samples: dict = field(default_factory=dict)


@dataclass
class _Recorder:
    """Adds one step of one filter to the block's sums."""

    out: LoopSums
    fi: int
    beacons: Array
    s_eps: Array
    xn: Array
    keep: list
    track: Array

    def __call__(self, k, a, x, x_hat, var, present, x_tilde=None) -> None:
        o, fi = self.out, self.fi
        e = x - x_hat
        o.count[fi, k] = a.sum()
        if x_tilde is not None:
            o.pred_err2[fi, k] = np.sum(((x - x_tilde) ** 2).sum(1)[a])
        o.j[fi, k] = np.sum(((x - self.xn[k]) ** 2).sum(1)[a])
        o.err[fi, k] = e[a].sum(0)
        o.err2[fi, k] = (e[a] ** 2).sum(0)
        o.stated[fi, k] = var[a].sum(0)
        o.info[fi, k] = bearing_information(x[a], self.beacons, self.s_eps, present[a]).sum(0)
        o.absent[fi, k] = (~present[a]).sum()
        if self.keep:
            self.track[:, k, :3], self.track[:, k, 3:] = x[self.keep], x_hat[self.keep]


def fly(
    s: LoopSetting,
    seed: int,
    runs: tuple[int, ...],
    gains: CmnfGains | None,
    filters: tuple[str, ...] = FILTERS,
    sample_runs: int = 3,
) -> LoopSums:
    """Fly the test paths of ``runs`` with each filter in the loop and reduce them (module doc)."""
    n, N = len(runs), s.path.n_steps
    draws = PathNoise(s.noise, N, len(s.beacons), seed, runs)
    b = s.b
    fn = s.fnoise
    xn = s.path.path()
    F = len(filters)
    out = LoopSums(
        count=np.zeros((F, N + 1)),
        j=np.zeros((F, N + 1)),
        err=np.zeros((F, N + 1, 3)),
        err2=np.zeros((F, N + 1, 3)),
        stated=np.zeros((F, N + 1, 3)),
        info=np.zeros((F, N + 1, 3, 3)),
        absent=np.zeros((F, N + 1)),
        diverged=np.zeros(F),
        shift_n=np.zeros(F),
        shift_err=np.zeros((F, 3)),
        shift_hist=np.zeros((F, SHIFT_BINS)),
        shift_none=np.zeros(F),
        shift_beams=np.zeros(F),
        pred_err2=np.zeros((F, N + 1)),
    )
    keep = [i for i, r in enumerate(runs) if r < sample_runs]
    options = bank.BankOptions(fn.s_eps, s.upmf_form, gains, s.correction)
    for fi, name in enumerate(filters):
        world = Seed004World(s.path, s.noise, b, draws)
        pred, world = prediction_of(s, seed, runs, world, "test")
        ctl = Controller(s, n)
        x = world.start()
        x_hat = np.broadcast_to(xn[0], (n, 3)).copy()
        P = np.broadcast_to(s.s0_filter, (n, 3, 3)).copy()
        alive = np.ones(n, dtype=bool)
        track = np.zeros((len(keep), N + 1, 6))

        rec = _Recorder(out, fi, b, s.noise.s_eps, xn, keep, track)
        rec(0, alive, x, x_hat, np.diagonal(P, axis1=1, axis2=2), np.ones((n, len(b)), bool))
        for k in range(N):
            u = ctl(k, x_hat)
            x_prev = x
            x = world.advance(k, x, u)
            shift = pred(k, x_hat, u)  # after the move (a sensed shift reads t_{k+1}'s data)
            if s.prediction != "system" and getattr(pred, "last", None) is not None:
                ok = pred.last.ok[alive]
                out.shift_none[fi] += (~ok).sum()
                out.shift_beams[fi] += pred.last.beams[alive].sum()
                e = (shift.displacement_m - (x - x_prev))[alive][ok]
                out.shift_n[fi] += len(e)
                out.shift_err[fi] += e.sum(0)
                idx = np.minimum(np.linalg.norm(e, axis=1) / SHIFT_BIN_M, SHIFT_BINS - 1)
                out.shift_hist[fi] += np.bincount(idx.astype(int), minlength=SHIFT_BINS)
            y, present = world.observe(k + 1, x)
            res = bank.step(name, k + 1, x_hat, P, shift, y, present, b, options)
            x_t, x_hat, P = res.x_tilde, res.x_hat, res.p_hat
            var = np.diagonal(P, axis1=1, axis2=2)
            bad = alive & ~(np.isfinite(x_hat).all(1) & np.isfinite(var).all(1))
            if name != "CMNF":
                bad |= alive & ~np.isfinite(P).all((1, 2))
            if bad.any():
                out.diverged[fi] += bad.sum()
                alive &= ~bad
                # keep the arithmetic finite on paths that left the statistics
                x_hat = np.where(alive[:, None], x_hat, xn[k + 1])
                if name != "CMNF":
                    P = np.where(alive[:, None, None], P, np.eye(3))
                var = np.where(alive[:, None], var, 0.0)
            x = np.where(alive[:, None], x, xn[k + 1])
            rec(k + 1, alive, x, x_hat, var, present, x_t)
        for j, i in enumerate(keep):
            out.samples.setdefault(runs[i], {})[name] = track[j].astype(np.float32)
    return out
