"""Options and per-ping diagnostics shared by the TRN filters (particle and point-mass)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]


def _integer(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


@dataclass(frozen=True)
class TrnOptions:
    """Options of :class:`nav.trn.ParticleTrn` and :class:`nav.trn.PointMassTrn`.

    Attributes:
        particles: particle count of the particle filter, >= 10.
        grid_points: points per axis of the point-mass filter's grid (``grid_points^2`` in all),
            >= 8.
        grid_sigmas: half-width of the point-mass grid in standard deviations of the current
            estimate along each axis, >= 3 (Bergman 1999 sizes the grid to the support).
        min_cell_m: smallest spacing of the point-mass grid, m, > 0.
        sigma_bias_m: prior standard deviation of a common vertical bias of one ping's soundings
            (the map's offset, a tide or pressure-sensor error), m, >= 0; the likelihood
            marginalises it analytically (:mod:`nav.trn.likelihood`); 0 = no bias.
        resample_threshold: resample when the effective sample size falls below this fraction of
            the particle count, in (0, 1] (mbtrnav uses 0.75: ``MIN_EFF_SAMP_SIZE``).
        roughening: the constant K of Gordon, Salmond & Smith (1993) roughening after a
            resampling: jitter ``N(0, (K E_a N^(-1/2))^2)`` along each axis a, E_a the span of the
            particles along a; >= 0 (0 = no roughening).
        nis_window: number of pings whose normalised innovations squared are summed for the
            divergence test, >= 1 (mbtrnav's ``NIS_WINDOW_LENGTH`` is 20).
        divergence_probability: false-alarm probability of the divergence test for a consistent
            filter: diverged when the window's NIS sum exceeds the chi-square quantile
            ``1 - divergence_probability`` of its degrees of freedom; in (0, 0.5).
        reinitialise: whether a divergence re-initialises the filter.
        reinit_sigma_m: standard deviation of the Gaussian spread a re-initialisation puts
            around the current estimate (added to its covariance), m, > 0.
    """

    particles: int = 10_000
    grid_points: int = 64
    grid_sigmas: float = 5.0
    min_cell_m: float = 0.02
    sigma_bias_m: float = 10.0
    resample_threshold: float = 0.5
    roughening: float = 0.2
    nis_window: int = 20
    divergence_probability: float = 1e-3
    reinitialise: bool = True
    reinit_sigma_m: float = 50.0

    def __post_init__(self) -> None:
        rules = {
            "particles": (lambda v: _integer(v) and v >= 10, "an integer >= 10"),
            "grid_points": (lambda v: _integer(v) and v >= 8, "an integer >= 8"),
            "grid_sigmas": (lambda v: v >= 3.0, "a finite number >= 3"),
            "min_cell_m": (lambda v: v > 0.0, "a finite number > 0"),
            "sigma_bias_m": (lambda v: v >= 0.0, "a finite number >= 0"),
            "resample_threshold": (lambda v: 0.0 < v <= 1.0, "in (0, 1]"),
            "roughening": (lambda v: v >= 0.0, "a finite number >= 0"),
            "nis_window": (lambda v: _integer(v) and v >= 1, "an integer >= 1"),
            "divergence_probability": (lambda v: 0.0 < v < 0.5, "in (0, 0.5)"),
            "reinitialise": (lambda v: isinstance(v, bool), "True or False"),
            "reinit_sigma_m": (lambda v: v > 0.0, "a finite number > 0"),
        }
        for f in fields(self):
            value = getattr(self, f.name)
            check, allowed = rules[f.name]
            numeric = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
                value, (bool, np.bool_)
            )
            if f.name == "reinitialise":
                numeric = True
            ok = numeric and (isinstance(value, bool) or math.isfinite(value)) and check(value)
            if not ok:
                raise NavInputError(f"TrnOptions.{f.name} = {value!r}: must be {allowed}")


@dataclass(frozen=True)
class TrnUpdate:
    """Diagnostics of one measurement update.

    Attributes:
        nis: normalised innovation squared of the ping, ``nu^T S^-1 nu`` with ``nu`` the measured
            minus the filter's weighted mean predicted depths and ``S`` the spread of the
            predictions plus the measurement covariance (0 when not evaluated).
        ess: effective sample size ``1 / sum w^2`` after the update (particles or grid points).
        diverged: the window's NIS sum exceeded its chi-square quantile at this ping.
        reinitialised: the filter was re-initialised at this ping.
        used_beams: beams that fell on the map for at least one hypothesis (0 = no update).
        nis_dof: degrees of freedom of ``nis`` (beams in it; 0 when not evaluated).
    """

    nis: float
    ess: float
    diverged: bool
    reinitialised: bool
    used_beams: int
    nis_dof: int = 0


def check_gaussian(name_x: str, x: ArrayLike, name_p: str, p: ArrayLike) -> tuple[Array, Array]:
    """A finite 2-vector and a symmetric positive-semidefinite 2x2 covariance, or an error.

    Raises:
        NavInputError: naming the argument, its value and what is allowed.
    """
    xa = np.asarray(x, dtype=float)
    pa = np.asarray(p, dtype=float)
    if xa.shape != (2,) or not np.all(np.isfinite(xa)):
        raise NavInputError(f"{name_x} = {xa.tolist()}: must be 2 finite numbers (east, north), m")
    if pa.shape != (2, 2) or not np.all(np.isfinite(pa)):
        raise NavInputError(f"{name_p} = {pa.tolist()}: must be a finite 2x2 covariance, m^2")
    if (
        abs(pa[0, 1] - pa[1, 0]) > 1e-9 * (1.0 + abs(pa).max())
        or np.linalg.eigvalsh(pa)[0] < -1e-12
    ):
        raise NavInputError(f"{name_p} = {pa.tolist()}: must be symmetric positive semi-definite")
    return xa, 0.5 * (pa + pa.T)


def beam_sigmas(sigma_m: float | ArrayLike, m: int, map_sigma_m: float) -> Array:
    """Per-beam standard deviation ``sqrt(sigma^2 + map_sigma^2)``, shape ``(m,)``, m.

    Raises:
        NavInputError: a sigma that is not finite and > 0, or of the wrong shape.
    """
    s = (
        np.broadcast_to(np.asarray(sigma_m, dtype=float), (m,))
        if np.ndim(sigma_m) == 0
        else (np.asarray(sigma_m, dtype=float))
    )
    if s.shape != (m,) or not np.all(np.isfinite(s)) or np.any(s <= 0.0):
        raise NavInputError(
            f"sigma_m = {np.asarray(sigma_m).tolist()}: must be finite and > 0, a float or ({m},)"
        )
    return np.sqrt(s * s + map_sigma_m * map_sigma_m)
