"""Seed 004, Table 1 row 2: the filters' prediction from seabed-sensing dead reckoning.

``X~_{k+1} = X^_k + dX^_{k+1}`` with the shift ``dX^_{k+1}`` of eq. 15 from two acoustic images
(:func:`nav.seabed.shift_estimate`, Appendix A slopes) and its stated covariance; for the CMNF
``alpha_{k+1} = X^_k + dX^_{k+1}`` (eq. 24, second set). The multibeam (8 x 8 beams, 0.1 m range
noise, :class:`bauv_sim.sensors.multibeam.Multibeam`) samples seed 004's harmonic seabed (eq. 24,
one per path) at the true positions; the filters see only the ranges.

A closed loop drives it in three calls per step: :meth:`SeabedPrediction.before` (image k at
``X_k``, aimed from the control ``u_k`` just chosen), :meth:`SeabedPrediction.after` (image k+1 at
``X_{k+1}``), then the prediction itself. The beam attitude of image k+1 is one of the readings of
the seed's notes (:data:`READINGS`):

* ``"one_attitude"``: image k+1 aimed from ``u_k`` too (both images of a shift at one attitude);
* ``"turning"``: image k+1 aimed from the next command as the vehicle can know it before its
  estimate of ``X_{k+1}`` exists: the locally optimal control computed on its prediction by
  virtue of the system, which with eq. 7 is the nominal control of step k+1; eq. 10 accounts for
  the turn. (The text's own order, ``u_{k+1}`` from an estimate that needs ``L_{k+1}``, is
  circular.)

Training paths draw their seabeds and range noise from run indices offset by
:data:`TRAIN_RUN_OFFSET` (and the stream name ``"train"``), so they never share a seabed with the
test runs.

:class:`HeightfieldPrediction` is the same prediction over a physics scene's heightfield instead of
the seed's harmonic seabed, with one image per step as on the physical vehicle: the kinematic
surrogate of ``mission/seed004`` with ``navigation.prediction = "seabed"``.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

from bauv_sim import seabed as seabed_mod
from bauv_sim.geo import GeoOriginConfig
from bauv_sim.seabed import Seabed, SeabedConfig
from bauv_sim.sensors.multibeam import (
    HarmonicSeabed,
    Multibeam,
    MultibeamConfig,
    MultibeamImages,
    beam_directions,
)
from nav.bearings import PredictedShift, velocity
from nav.seabed import BeamGeometry, SlopeBasis, shift_estimate

Array = NDArray[np.float64]

READINGS = ("one_attitude", "turning")
TRAIN_RUN_OFFSET = 2**31
"""Run index offset of the CMNF training paths' seabeds and sonar streams."""


class SeabedPrediction:
    """The seabed-sensing prediction of a batch of paths (a :class:`nav.bearings.Prediction`).

    Args:
        reading: ``"one_attitude"`` or ``"turning"`` (module docstring).
        seed: batch seed.
        runs: run indices (one seabed each).
        dt: step, s.
        nominal_controls: ``(N, 3)`` nominal (gamma, theta, V), for the turning reading.
        stream: name of the sonar's error stream.
        cfg: the multibeam (default: seed 004's).
    """

    def __init__(
        self,
        reading: str,
        seed: int,
        runs: tuple[int, ...],
        dt: float,
        nominal_controls: Array,
        stream: str = "test",
        cfg: MultibeamConfig | None = None,
    ):
        if reading not in READINGS:
            raise ValueError(f"reading = {reading!r}: one of {READINGS}")
        self.reading, self.dt = reading, dt
        self.cfg = cfg or MultibeamConfig()
        self.geometry = BeamGeometry(self.cfg.elevations_rad(), self.cfg.azimuths_rad())
        self.seabed = HarmonicSeabed.draw(seed, runs)
        self.sonar = Multibeam(self.cfg, seed, runs, f"multibeam/seed004/{stream}")
        self.un = nominal_controls
        self.n = len(runs)
        self._img0 = self._img1 = None
        self._att0 = self._att1 = None

    def _image(self, k: int, x: Array, att: Array):
        return self.sonar.sample_harmonic(
            self.seabed, x[:, None], att[:, None], np.array([k * self.dt])
        )

    def before(self, k: int, x_true: Array, u: Array) -> None:
        """Image k at the true ``X_k`` ``(n, 3)`` m, aimed from ``u_k`` ``(n, 3)``."""
        self._att0 = np.asarray(u, float)[:, :2].copy()
        self._img0 = self._image(k, x_true, self._att0)

    def after(self, k: int, x_true: Array, u: Array) -> None:
        """Image k+1 at the true ``X_{k+1}`` ``(n, 3)`` m (attitude by the reading)."""
        if self.reading == "one_attitude" or k + 1 >= len(self.un):
            self._att1 = self._att0
        else:
            self._att1 = np.broadcast_to(self.un[k + 1, :2], (self.n, 2)).copy()
        self._img1 = self._image(k + 1, x_true, self._att1)

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift:
        """The shift of eq. 15 between images k and k+1, with its stated covariance."""
        est = shift_estimate(
            self._img0.ranges_m[:, 0],
            self._img1.ranges_m[:, 0],
            self.geometry,
            self._att0,
            self._att1,
            echo=self._img0.echo[:, 0],
            next_echo=self._img1.echo[:, 0],
            reading=self.reading,  # type: ignore[arg-type]
            position_m=x_hat,
            sigma_range_m=self.cfg.range.sigma_m,
            commanded_shift_m=velocity(u) * self.dt,
        )
        self.last = est
        return PredictedShift(est.shift_m, est.covariance_m2)


@functools.lru_cache(maxsize=2)
def _heightfield(cfg_json: str, geo_json: str | None) -> Seabed:
    geo = None if geo_json is None else GeoOriginConfig.model_validate_json(geo_json)
    return seabed_mod.generate(
        SeabedConfig.model_validate_json(cfg_json), None if geo is None else geo.frame()
    )


def heightfield(cfg: SeabedConfig, geo: GeoOriginConfig | None = None) -> Seabed:
    """The seabed of a configuration (generated, or from its bathymetry file around ``geo``;
    cached per process: a 1001 x 1001 grid takes about a second)."""
    return _heightfield(cfg.model_dump_json(), None if geo is None else geo.model_dump_json())


class HeightfieldPrediction:
    """The seabed-sensing prediction over a physics scene's heightfield, for the kinematic
    surrogate of ``mission/seed004`` (a :class:`nav.bearings.Prediction`).

    The surrogate's vehicle carries the mission's multibeam (beams relative to its direction of
    motion, range errors of ``cfg.range``) over the scene's triangulated heightfield, ranges by
    :meth:`bauv_sim.seabed.Seabed.ray_ranges` (the surface MuJoCo's rays meet). As on the physical
    vehicle, there is one image per step, taken at the step's end: image k+1 at ``X_{k+1}``
    aimed from the attitude the vehicle moved with, ``(gamma, theta)`` of ``u_k``; the shift of
    step k comes from images k and k+1 with the turn between their attitudes (reading
    ``"turning"``, the exact change of the beams, :func:`nav.seabed.shift_estimate`). The first
    step has no image before it: its prediction is the commanded displacement with
    ``first_covariance_m2`` (by virtue of the system), as on the vehicle.

    Args:
        bed: the scene's seabed.
        cfg: the multibeam.
        basis: Appendix A's basis (``"quadratic"``, ``"plane"`` or ``"harmonic"``).
        seed: batch seed.
        runs: run indices (the sonar's error streams).
        dt: step, s.
        first_covariance_m2: the first step's covariance ``(3, 3)``, m^2.
        stream: name of the sonar's error stream.
    """

    def __init__(
        self,
        bed: Seabed,
        cfg: MultibeamConfig,
        basis: str,
        seed: int,
        runs: tuple[int, ...],
        dt: float,
        first_covariance_m2: Array,
        stream: str = "test",
    ):
        self.bed, self.cfg, self.dt = bed, cfg, dt
        self.basis = SlopeBasis(basis)  # type: ignore[arg-type]
        self.geometry = BeamGeometry(cfg.elevations_rad(), cfg.azimuths_rad())
        self.sonar = Multibeam(cfg, seed, runs, f"multibeam/seed004-mission/{stream}")
        self.first_cov = np.asarray(first_covariance_m2, float)
        self.n = len(runs)
        self._img: MultibeamImages | None = None
        self._next: MultibeamImages | None = None

    def image(self, k: int, x: Array, attitude: Array) -> MultibeamImages:
        """Image k at the positions ``(n, 3)`` m aimed from ``(gamma, theta)`` ``(n, 2)`` rad."""
        e = beam_directions(self.cfg, attitude)  # (n, Mi, Mj, 3)
        L, hit = self.bed.ray_ranges(x[:, None, None, :], e, self.cfg.max_range_m)
        return self.sonar.measure(
            L[:, None], hit[:, None], np.array([k * self.dt]), attitude[:, None]
        )

    def before(self, k: int, x_true: Array, u: Array) -> None:
        """Nothing to do: image k is the previous step's second image."""
        self._img = self._next if k else None

    def after(self, k: int, x_true: Array, u: Array) -> None:
        """Image k+1 at the true ``X_{k+1}`` ``(n, 3)`` m, aimed from ``u_k`` ``(n, 3)``."""
        self._next = self.image(k + 1, x_true, np.asarray(u, float)[:, :2].copy())

    def __call__(self, k: int, x_hat: Array, u: Array) -> PredictedShift:
        """The shift of eq. 15 between images k and k+1 (the commanded displacement at k = 0)."""
        cmd = velocity(u) * self.dt
        if self._img is None:
            self.last = None
            return PredictedShift(cmd, self.first_cov)
        a, b = self._img, self._next
        est = shift_estimate(
            a.ranges_m[:, 0],
            b.ranges_m[:, 0],
            self.geometry,
            a.attitude_rad[:, 0],
            b.attitude_rad[:, 0],
            echo=a.echo[:, 0],
            next_echo=b.echo[:, 0],
            reading="turning",
            delta_e="exact",
            basis=self.basis,
            position_m=x_hat,
            sigma_range_m=self.cfg.range.sigma_m,
            commanded_shift_m=cmd,
        )
        self.last = est
        return PredictedShift(est.shift_m, est.covariance_m2)
