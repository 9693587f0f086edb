"""Seed 003 (Naus & Piskur 2022): a follower positioned relative to the swarm leader on a square.

Registers ``paper-003/test-1``, ``test-2`` and ``test-3`` (section 3): the leader L flies one
square (120 s a side at 1 m/s, first course 45 deg) and the follower F keeps 10 m at a relative
bearing of 90 deg (Tests 1, 3) or 180 deg (Test 2). F measures course and speed at 10 Hz with the
errors of a poorly calibrated (Tests 1-2) or a calibrated (Test 3) INS and log, and receives the
range to L with L's position every 5 s. Each run is positioned four ways on the same draws, by
:mod:`nav.relative` (the experiment only drives it):

* **DR**: dead reckoning from the measured course and speed (eq. 1, :func:`nav.relative.dr_track`);
* **GA1**, **GA2**: at every range, the geodetic adjustment on the circle of the range (eq. 2-4)
  weighted by the DR covariance accumulated since the last fix (eq. 5-6), with DR going on from
  the fix in between (:func:`nav.relative.ga_track`, :func:`nav.relative.ga_fix`);
* **EKF** (beyond the paper): the range-only EKF on the same ranges, predicting with eq. 1 and
  Q = eq. 5 (:func:`nav.relative.ekf_track`, :func:`nav.relative.range_update`).

The tables are the paper's (Tables 1-3, :mod:`tasks.paper003.paper`): maximum, arithmetic mean
and standard deviation of the distance between F's reference position and each estimate, for a
single test sample (run ``report.single_sample``) and for all runs. The "100 test samples" columns
pool every 10 Hz sample of every run (the seed's reading notes: with pooling the DR rows come out
within a few percent; with the mean curve they do not). Statistics run over ticks 1..T (t = 0.1 ..
480 s; at t = 0 every estimate starts on the reference).

Readings the paper leaves open are scenario options (``formation.*`` in
:mod:`bauv_sim.kinematic.seed003`, ``navigation.jacobian`` and ``navigation.restart`` as
:class:`nav.relative.GaOptions`); ``report.readings = "all"`` computes GA1 and GA2 for every
combination of them on the same draws and reports each beside the paper (no single reading
reproduces every GA cell; nothing is tuned to the tables). The square turns right by default: the
DR rows, which do not depend on any GA reading, come out within 2 % of the paper that way and 30-45
% off turning left.

Bad geometry and data degrade to DR with a warning in the report and ``metrics.json``: a range
below ``navigation.min_range_m`` (zero range), no range (``sensors.modem.max_range_m``,
``sensors.modem.dropout_windows_s``, the vocabulary's dropout probability), or a fix whose HDOP
exceeds ``navigation.max_hdop``; GA and the EKF then dead-reckon on from their last fix.

The experiment is scenario (:mod:`tasks.paper003.scenario`), run (:mod:`tasks.paper003.run`) and
report (:mod:`tasks.paper003.report`, with :mod:`~tasks.paper003.figures` and
:mod:`~tasks.paper003.recording`); this module registers it.
"""

from __future__ import annotations

from dataclasses import dataclass

from bauv_sim.errors import ConfigError
from bauv_sim.kinematic.seed003 import measure
from tasks.core.registry import Experiment, ReportContext, ReportSummary, register
from tasks.paper003.report import Paper003Metrics, report_paper003
from tasks.paper003.run import Paper003Block, reduce_block
from tasks.paper003.scenario import (
    Paper003Scenario,
    block_runs,
    preset_of,
    readings,
    scenario_reading,
    truth_of,
)


@dataclass(frozen=True)
class SquareExperiment(Experiment):
    """Seed 003 test: N runs of the follower on the square (module docstring)."""

    scenario_type = Paper003Scenario
    metrics_type = Paper003Metrics
    test: str = "test-1"

    def block_size(self, scenario: Paper003Scenario) -> int:
        return block_runs(scenario)

    def check(self, scenario: Paper003Scenario, n_runs: int) -> None:
        if scenario.report.single_sample >= n_runs:
            raise ConfigError(
                f"report.single_sample = {scenario.report.single_sample}: must be < runs = {n_runs}"
            )
        # the truth's own checks (corner time) and the sensors' timing, before anything runs
        for rd in readings(scenario):
            truth_of(scenario, rd.geometry)
        measure(scenario.sensors, truth_of(scenario, scenario_reading(scenario).geometry), 0, (0,))

    def run_block(
        self, scenario: Paper003Scenario, seed: int, runs: tuple[int, ...]
    ) -> Paper003Block:
        return reduce_block(scenario, seed, runs)

    def report(self, ctx: ReportContext) -> ReportSummary:
        return report_paper003(self, self.test, ctx)


_SUMMARIES = {
    "test-1": "seed 003 Test 1: follower abeam (90 deg, 10 m) on the square, uncalibrated; DR, "
    "GA1, GA2, range EKF",
    "test-2": "seed 003 Test 2: follower astern (180 deg, 10 m) on the square, uncalibrated; DR, "
    "GA1, GA2, range EKF",
    "test-3": "seed 003 Test 3: follower abeam (90 deg, 10 m) on the square, calibrated; DR, GA1, "
    "GA2, range EKF",
}
for _test, _summary in _SUMMARIES.items():
    register(
        SquareExperiment(
            name=f"paper-003/{_test}",
            summary=_summary,
            preset=preset_of(_test),
            default_runs=100,
            test=_test,
        )
    )
