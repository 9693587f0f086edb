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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bauv_sim.sensors.multibeam import HarmonicSeabed, Multibeam, MultibeamConfig
from nav.bearings import PredictedShift, velocity
from nav.seabed import BeamGeometry, shift_estimate

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
    """

    def __init__(
        self,
        reading: str,
        seed: int,
        runs: tuple[int, ...],
        dt: float,
        nominal_controls: Array,
        stream: str = "test",
    ):
        if reading not in READINGS:
            raise ValueError(f"reading = {reading!r}: one of {READINGS}")
        self.reading, self.dt = reading, dt
        self.cfg = MultibeamConfig()
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
            commanded_shift_m=velocity(u) * self.dt,
        )
        self.last = est
        return PredictedShift(est.shift_m, est.covariance_m2)
