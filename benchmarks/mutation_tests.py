"""Mutation run of the tests: each mutant is real broken science that some test must catch.

Each mutation is a named, exact source edit (file, the exact original text, its replacement),
applied to a temporary copy of the checkout, never to the working tree. The copy carries the
built C libraries (``*.so``) of the checkout, so only Python files are mutated (a mutation of a C
file is refused: it would need a rebuild). In the copy, the tests that guard the mutated module
(:data:`GUARDS`, a mutation may add its own) run in one pytest process whose imports are checked
to come from the copy. A mutant is

* **caught** when at least one test fails (a failed assertion, or an error in a test's set-up,
  e.g. a fixture that flies a mission and checks it);
* **collection error** when pytest could not even collect a test file (the mutant broke an
  import): reported apart, and counted as caught only with ``--count-collection-errors``;
* **timeout** when the tests did not finish in ``--timeout`` seconds: reported apart, never
  counted as caught;
* **survived** otherwise. A survivor documented as behaviour-preserving (``equivalent``, with
  the reason) is listed as such and left out of the rate.

Every original text must occur exactly once in its file of the checkout: otherwise the run refuses
before any test (exit status 1) and names the mutation, the file and the count, so a mutation never
silently stops applying after the code changes. ``--check`` does only that.

Before the mutants, the union of their tests runs on the unmutated copy (``--no-baseline`` skips
it): a test that fails without a mutation would "catch" every mutant, so that is an error (exit 1).

Groups: ``issue21`` (the seven mutations of issue 21 that left every relevant test green) and
``own`` (mutations of the same kinds across ``nav``, ``bauv_sim.sensors``, ``bauv_sim.currents``,
the Parquet export and the reports). Exit status 1 if any mutant of the selection survives that is
not documented as equivalent (in particular any of the seven), if an anchor does not match, or if
the baseline fails; 0 otherwise.

Usage::

    .venv/bin/python benchmarks/mutation_tests.py                    # both groups
    .venv/bin/python benchmarks/mutation_tests.py --group issue21    # the seven
    .venv/bin/python benchmarks/mutation_tests.py gate-dof-plus-one  # some, by name
    .venv/bin/python benchmarks/mutation_tests.py --whole-suite cmnf-prediction-gain-transposed
    .venv/bin/python benchmarks/mutation_tests.py --list             # names, files, tests
    .venv/bin/python benchmarks/mutation_tests.py --check            # anchors only

``--all-failures`` runs each mutant's tests to the end (default: stop at the first failure, which is
the test named in the table); ``--jobs N`` runs N mutants at a time; ``--keep`` keeps the copies.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

GUARDS: dict[str, tuple[str, ...]] = {
    # nav: the estimators and their models
    "nav/ekf.py": (
        "tests/nav/test_ekf.py",
        "tests/nav/test_track_ekf.py",
        "tests/nav/test_navigator.py",
        "tests/nav/test_relative.py",
        "tests/tasks/test_paper000.py",
    ),
    "nav/models.py": (
        "tests/nav/test_models.py",
        "tests/nav/test_ekf.py",
        "tests/nav/test_track_ekf.py",
        "tests/nav/test_navigator.py",
        "tests/tasks/test_paper000.py",
    ),
    "nav/metrics.py": ("tests/nav/test_metrics.py", "tests/tasks/test_paper000.py"),
    "nav/usbl/accuracy.py": ("tests/nav/test_accuracy.py", "tests/tasks/test_paper000.py"),
    "nav/usbl/tracks.py": ("tests/nav/test_track_ekf.py", "tests/tasks/test_paper000.py"),
    "nav/navigator/online.py": ("tests/nav/test_navigator.py", "tests/tasks/test_run_data.py"),
    "nav/navigator/follower.py": ("tests/tasks/test_swarm.py", "tests/tasks/test_run_data.py"),
    "nav/dead_reckoning.py": ("tests/nav/test_dead_reckoning.py", "tests/nav/test_navigator.py"),
    "nav/bearings/model.py": ("tests/nav/test_bearings.py", "tests/tasks/test_paper004.py"),
    "nav/bearings/filters.py": ("tests/nav/test_bearings.py", "tests/tasks/test_paper004.py"),
    "nav/bearings/bank.py": ("tests/nav/test_bearings.py", "tests/tasks/test_paper004.py"),
    "nav/bearings/cmnf.py": (
        "tests/nav/test_bearings.py",
        "tests/nav/test_cmnf.py",
        "tests/tasks/test_paper004.py",
    ),
    "nav/bearings/pcrb.py": ("tests/nav/test_bearings.py", "tests/tasks/test_paper004.py"),
    "nav/relative/motion.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/relative/adjustment.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/relative/ranging.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/relative/follower.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/relative/tracks.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/relative/metrics.py": ("tests/nav/test_relative.py", "tests/tasks/test_paper003.py"),
    "nav/surfacing/estimate.py": (
        "tests/nav/test_correction.py",
        "tests/nav/test_drns.py",
        "tests/tasks/test_paper001.py",
    ),
    "nav/surfacing/procedures.py": (
        "tests/nav/test_correction.py",
        "tests/nav/test_drns.py",
        "tests/tasks/test_paper001.py",
    ),
    "nav/surfacing/course.py": ("tests/nav/test_correction.py", "tests/tasks/test_paper001.py"),
    "nav/surfacing/drns.py": (
        "tests/nav/test_correction.py",
        "tests/nav/test_drns.py",
        "tests/tasks/test_paper001.py",
    ),
    "nav/seabed/geometry.py": ("tests/nav/test_seabed.py", "tests/nav/test_seabed_kernel.py"),
    "nav/seabed/fit.py": ("tests/nav/test_seabed.py", "tests/nav/test_seabed_kernel.py"),
    "nav/seabed/shift.py": ("tests/nav/test_seabed.py", "tests/nav/test_seabed_kernel.py"),
    "nav/seabed/kernel.py": ("tests/nav/test_seabed_kernel.py", "tests/nav/test_seabed.py"),
    "bauv_sim/sensors/harmonic_march.py": ("tests/bauv_sim/test_multibeam.py",),
    "nav/angles.py": ("tests/nav/test_angles.py", "tests/bauv_sim/test_frames.py"),
    # bauv_sim: the devices, the rig and the sea
    "bauv_sim/sensors/errors.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/compass.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/log.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/pressure.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/odometry.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/gps.py": ("tests/bauv_sim/test_sensors.py",),
    "bauv_sim/sensors/usbl.py": ("tests/bauv_sim/test_sensors.py", "tests/tasks/test_run_data.py"),
    "bauv_sim/sensors/modem.py": ("tests/bauv_sim/test_modem.py", "tests/tasks/test_swarm.py"),
    "bauv_sim/sensors/doa.py": ("tests/bauv_sim/test_doa.py",),
    "bauv_sim/sensors/multibeam.py": ("tests/bauv_sim/test_multibeam.py",),
    "bauv_sim/sensors/dvl.py": ("tests/sensors/test_dvl.py", "tests/sensors/test_dvl_device.py"),
    "nav/dvl.py": ("tests/nav/test_dvl.py", "tests/nav/test_dvl_ekf.py"),
    "bauv_sim/ocean.py": (
        "tests/bauv_sim/test_ocean.py",
        "tests/bauv_sim/test_gridded_current.py",
        "tests/tasks/test_site_current.py",
    ),
    "bauv_sim/bathymetry.py": (
        "tests/bauv_sim/test_bathymetry.py",
        "tests/bauv_sim/test_seabed_file.py",
    ),
    "tasks/core/geojson.py": ("tests/tasks/test_geojson.py",),
    "tasks/closed_loop/geo.py": ("tests/tasks/test_geo_io.py",),
    "nav/acoustics/rays.py": (
        "tests/nav/test_acoustic_rays.py",
        "tests/sensors/test_usbl_sound.py",
    ),
    "nav/acoustics/inversion.py": (
        "tests/nav/test_acoustic_rays.py",
        "tests/tasks/test_acoustics_sound.py",
    ),
    "nav/trn/likelihood.py": (
        "tests/nav/trn/test_posterior.py",
        "tests/nav/trn/test_filter_parts.py",
    ),
    "nav/trn/particle.py": (
        "tests/nav/trn/test_posterior.py",
        "tests/nav/trn/test_filter_parts.py",
    ),
    "nav/trn/point_mass.py": (
        "tests/nav/trn/test_posterior.py",
        "tests/nav/trn/test_filter_parts.py",
    ),
    "nav/trn/pcrb.py": ("tests/nav/trn/test_pcrb.py", "tests/nav/trn/test_posterior.py"),
    "bauv_sim/sensors/rig.py": (
        "tests/bauv_sim/test_sensors.py",
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_missions.py",
    ),
    "bauv_sim/currents.py": (
        "tests/bauv_sim/test_currents.py",
        "tests/bauv_sim/test_sea.py",
        "tests/bauv_sim/test_kinematic_seed001.py",
    ),
    "bauv_sim/kinematic/seed001.py": (
        "tests/bauv_sim/test_kinematic_seed001.py",
        "tests/tasks/test_paper001.py",
    ),
    "bauv_sim/kinematic/passage.py": (
        "tests/bauv_sim/test_kinematic_passage.py",
        "tests/tasks/test_paper000.py",
    ),
    # tasks: the run data (Parquet) and the reports
    "tasks/core/export.py": (
        "tests/tasks/test_export.py",
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_run_dataset.py",
    ),
    "tasks/closed_loop/result.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_export.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/closed_loop/navigation.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/closed_loop/report.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_recording.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/closed_loop/recording.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_recording.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/closed_loop/recording_vehicle.py": (
        "tests/tasks/test_recording.py",
        "tests/tasks/test_recording_contract.py",
    ),
    "tasks/closed_loop/figures.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_recording.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/closed_loop/world.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_missions.py",
    ),
    "tasks/paper000/passage.py": ("tests/tasks/test_paper000.py",),
    "tasks/paper003/scenario.py": ("tests/tasks/test_paper003.py",),
    "tasks/paper003/run.py": ("tests/tasks/test_paper003.py",),
    "tasks/paper003/report.py": ("tests/tasks/test_paper003.py",),
    "tasks/paper003/square.py": ("tests/tasks/test_paper003.py",),
    "tasks/missions/swarm/follower.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_swarm.py",
    ),
    "tasks/missions/swarm/run.py": ("tests/tasks/test_run_data.py", "tests/tasks/test_swarm.py"),
    "tasks/missions/swarm/formation.py": ("tests/tasks/test_swarm_team.py",),
    "tasks/missions/swarm/team.py": ("tests/tasks/test_swarm_team.py",),
    "tasks/missions/swarm/relay.py": ("tests/tasks/test_swarm_team.py",),
    "tasks/missions/swarm/report.py": ("tests/tasks/test_run_data.py", "tests/tasks/test_swarm.py"),
    "tasks/missions/correction/run.py": (
        "tests/tasks/test_run_data.py",
        "tests/tasks/test_missions.py",
    ),
}
"""Mutated module -> the test files that guard it, fast and focused first (with the default
fail-fast, the first to fail names the catch). A mutation may add tests of its own."""


@dataclass(frozen=True)
class Mutation:
    """One exact source edit.

    Attributes:
        name: short unique name.
        group: ``"issue21"`` or ``"own"``.
        kind: what sort of broken science (dof, correction, transpose, default, sign, unit,
            columns).
        path: the file, relative to the checkout.
        original: the exact text replaced; must occur exactly once in the file.
        replacement: what it becomes.
        what: one line on what the mutant breaks.
        tests: extra test files or node ids, run before the module's :data:`GUARDS`.
        equivalent: why the mutant cannot change behaviour, if it is documented as equivalent.
    """

    name: str
    group: str
    kind: str
    path: str
    original: str
    replacement: str
    what: str
    tests: tuple[str, ...] = ()
    equivalent: str | None = None

    def guards(self) -> tuple[str, ...]:
        """The tests run against this mutant (its own first, then the module's guards)."""
        if self.path not in GUARDS and not self.tests:
            raise SystemExit(f"mutation {self.name}: no tests guard {self.path} (add it to GUARDS)")
        out: list[str] = []
        for t in (*self.tests, *GUARDS.get(self.path, ())):
            if t not in out:
                out.append(t)
        return tuple(out)


ISSUE21: list[Mutation] = [
    Mutation(
        "gate-dof-plus-one",
        "issue21",
        "dof",
        "nav/ekf.py",
        "    return float(chi2.ppf(probability, dof))\n",
        "    return float(chi2.ppf(probability, dof + 1))\n",
        "the EKF gate's chi-square quantile taken with one degree of freedom too many",
    ),
    Mutation(
        "upmf-bias-correction-removed",
        "issue21",
        "correction",
        "nav/bearings/filters.py",
        "        yp = yp - pseudo_noise_mean(x_tilde, h0, beacons, s_eps)\n",
        "",
        "the UPMF's unbiased form no longer takes eq. 20's noise mean off the pseudo-measurement",
    ),
    Mutation(
        "cmnf-prediction-gain-transposed",
        "issue21",
        "transpose",
        "nav/bearings/cmnf.py",
        "    F = c_xa @ pinv_floor(c_aa, floor)\n",
        "    F = (c_xa @ pinv_floor(c_aa, floor)).T\n",
        "the CMNF's prediction gain F_k of eq. 22 transposed",
    ),
    Mutation(
        "compass-default-sigma-doubled",
        "issue21",
        "default",
        "bauv_sim/sensors/compass.py",
        "AngleErrorConfig(sigma_deg=3.0)",
        "AngleErrorConfig(sigma_deg=6.0)",
        "the compass's default heading sigma 6 deg instead of seed 000's 3 deg",
    ),
    Mutation(
        "randomised-current-direction-180",
        "issue21",
        "sign",
        "bauv_sim/currents.py",
        "self._vel.append(_horizontal(velocity_from_course_speed(direction, speed)))",
        "self._vel.append(_horizontal(velocity_from_course_speed(direction + math.pi, speed)))",
        "seed 001's randomised current sets towards alpha_c + 180 deg",
    ),
    Mutation(
        "parquet-heading-unit-deg",
        "issue21",
        "unit",
        "tasks/closed_loop/result.py",
        '"meas_heading": ("rad", "compass heading, clockwise from north", ())',
        '"meas_heading": ("deg", "compass heading, clockwise from north", ())',
        "the Parquet column meas_heading labelled deg while it holds radians",
    ),
    Mutation(
        "fix-t-valid-t-arrival-swapped",
        "issue21",
        "columns",
        "tasks/closed_loop/result.py",
        '            "t_valid": np.array([f.t_valid_s for f in rows]),\n'
        '            "t_arrival": np.array([f.t_arrival_s for f in rows]),\n',
        '            "t_valid": np.array([f.t_arrival_s for f in rows]),\n'
        '            "t_arrival": np.array([f.t_valid_s for f in rows]),\n',
        "the fix tables' t_valid and t_arrival columns swapped",
    ),
]
"""The seven mutations of issue 21."""

OWN: list[Mutation] = [
    # --- degrees of freedom ------------------------------------------------------------------
    Mutation(
        "ekf-single-run-gate-dof-plus-one",
        "own",
        "dof",
        "nav/ekf.py",
        "nis > gate_limit(gate_probability, int(idx.size))",
        "nis > gate_limit(gate_probability, int(idx.size) + 1)",
        "the single-run EKF gates with one degree of freedom too many",
    ),
    Mutation(
        "ekf-batched-gate-dof-plus-one",
        "own",
        "dof",
        "nav/ekf.py",
        "gate_limit(gate_probability, int(d)) for d in np.maximum(dof, 1)",
        "gate_limit(gate_probability, int(d) + 1) for d in np.maximum(dof, 1)",
        "the batched EKF gates with one degree of freedom too many",
    ),
    Mutation(
        "paper000-gate-limits-dof-plus-one",
        "own",
        "dof",
        "nav/ekf.py",
        "*(gate_limit(gate_probability, d) for d in (1, 2, 3))",
        "*(gate_limit(gate_probability, d + 1) for d in (1, 2, 3))",
        "seed 000's passage EKF (the update's fast path) gates 1, 2, 3 active components with "
        "2, 3, 4 dof",
    ),
    Mutation(
        "nees-band-dof-plus-one",
        "own",
        "dof",
        "nav/metrics.py",
        "    k = dim * n_runs\n",
        "    k = (dim + 1) * n_runs\n",
        "the averaged NEES band with one degree of freedom too many per run",
    ),
    Mutation(
        "mission-nees-band-dof-2",
        "own",
        "dof",
        "tasks/closed_loop/recording_vehicle.py",
        "    return out, d\n",
        "    return out, 2\n",
        "the mission recording's NEES band of the 3-D position taken with 2 dof",
    ),
    # --- dropped correction terms ------------------------------------------------------------
    Mutation(
        "ekf-joseph-krk-dropped",
        "own",
        "correction",
        "nav/ekf.py",
        " + K @ Rb @ np.swapaxes(K, -1, -2)  # eq. 23",
        "  # eq. 23",
        "the Joseph form's K R K^T term dropped from the batched EKF's covariance update",
    ),
    Mutation(
        "pseudo-noise-mean-elevation-term-dropped",
        "own",
        "correction",
        "nav/bearings/filters.py",
        "vl * dx * c1 - c * dz * vp * g2 / 2",
        "vl * dx * c1",
        "the UPMF's bias correction loses its elevation row's cos(phi) term",
    ),
    Mutation(
        "usbl-travel-time-dropped",
        "own",
        "correction",
        "bauv_sim/sensors/usbl.py",
        "t_arr = tr.t_s + true_rae[..., 0] / self.cfg.sound_speed_m_s"
        " + self.cfg.processing_delay_s",
        "t_arr = tr.t_s + self.cfg.processing_delay_s",
        "the USBL's latency without the acoustic travel time",
    ),
    Mutation(
        "sensor-scale-factor-dropped",
        "own",
        "correction",
        "bauv_sim/sensors/errors.py",
        "out = x * (1.0 + m.scale_factor) + m.bias",
        "out = x + m.bias",
        "the error vocabulary's scale factor never applied",
    ),
    Mutation(
        "rig-latency-ignored",
        "own",
        "correction",
        "bauv_sim/sensors/rig.py",
        "due = [m for m in self._pending if m.t_arrival_s <= t + 1e-9]",
        "due = [m for m in self._pending if m.t_valid_s <= t + 1e-9]",
        "the rig hands a measurement over at its validity, not at its arrival",
    ),
    Mutation(
        "late-fix-applied-at-arrival",
        "own",
        "correction",
        "tasks/closed_loop/navigation.py",
        "info = nav.fuse(Measurement(m.value, model, m.t_valid_s))",
        "info = nav.fuse(Measurement(m.value, model, t_s))",
        "a late USBL fix applied at its arrival instead of its time of validity",
    ),
    Mutation(
        "seed001-eq29-normalisation-dropped",
        "own",
        "correction",
        "bauv_sim/kinematic/seed001.py",
        "ratio = rho_s(gamma, cfg.rho_s_cos_coeffs) / rho_s(ac, cfg.rho_s_cos_coeffs)",
        "ratio = rho_s(gamma, cfg.rho_s_cos_coeffs)",
        "seed 001's eq. 29 without its normalising rho_s(alpha_c)",
    ),
    # --- transposed or swapped matrices and indices ------------------------------------------
    Mutation(
        "cmnf-stated-prediction-covariance-transposed",
        "own",
        "transpose",
        "nav/bearings/cmnf.py",
        "    p = c_xx - F @ c_xa.T\n",
        "    p = c_xx - F @ c_xa\n",
        "the CMNF's stated P~ uses cov(X, alpha) where section 5.2 has cov(alpha, X)",
    ),
    Mutation(
        "cmnf-step-gain-transposed",
        "own",
        "transpose",
        "nav/bearings/cmnf.py",
        "x_tilde = rows_times(alpha, gains.F[i]) + gains.f[i]",
        "x_tilde = rows_times(alpha, gains.F[i].T) + gains.f[i]",
        "the CMNF step applies the fitted prediction gain transposed",
    ),
    Mutation(
        "usbl-fix-covariance-jacobian-transposed",
        "own",
        "transpose",
        "nav/models.py",
        "return J @ self.R() @ np.swapaxes(J, -1, -2)",
        "return np.swapaxes(J, -1, -2) @ self.R() @ J",
        "the USBL-only fix's covariance J^T R J instead of J R J^T",
    ),
    Mutation(
        "usbl-R-azimuth-elevation-swapped",
        "own",
        "transpose",
        "nav/models.py",
        "[self.sigma_range_m**2, self.sigma_azimuth_rad**2, self.sigma_elevation_rad**2]",
        "[self.sigma_range_m**2, self.sigma_elevation_rad**2, self.sigma_azimuth_rad**2]",
        "the USBL's R with the azimuth and elevation variances swapped",
    ),
    Mutation(
        "export-covariance-field-names-swapped",
        "own",
        "transpose",
        "tasks/core/export.py",
        '(f"{name}_{comps[i]}_{comps[j]}", (i, j), v[:, i, j])',
        '(f"{name}_{comps[j]}_{comps[i]}", (i, j), v[:, i, j])',
        "a covariance's upper-triangle fields named <col>_<row>",
    ),
    Mutation(
        "export-angles-not-converted-to-degrees",
        "own",
        "unit",
        "tasks/core/export.py",
        'deg = np.degrees(col.values) if col.values.dtype.kind == "f" else col.values',
        "deg = col.values",
        "run data's angle columns named and labelled deg but holding radians",
    ),
    Mutation(
        "export-run-key-off-by-one",
        "own",
        "index",
        "tasks/core/export.py",
        '"run": Column(np.full(n, run, dtype=np.int32), "index", "run index of the batch"),',
        '"run": Column(np.full(n, run + 1, dtype=np.int32), "index", "run index of the batch"),',
        "the run key of a batch's rows shifted by one run",
    ),
    Mutation(
        "seed003-dr-covariance-sin-cos-swapped",
        "own",
        "transpose",
        "nav/relative/motion.py",
        "out[..., 0, 0] = dt2 * ((a * cos) ** 2 + (b * sin) ** 2)",
        "out[..., 0, 0] = dt2 * ((a * sin) ** 2 + (b * cos) ** 2)",
        "seed 003's eq. 5 sigma_x^2 with the course's sine and cosine swapped",
    ),
    Mutation(
        "seed000-dr-accuracy-sin-cos-swapped",
        "own",
        "transpose",
        "nav/usbl/accuracy.py",
        "sx2 = dt**2 * ((s * sigma_course_rad * np.cos(c)) ** 2"
        " + (sigma_speed_m_s * np.sin(c)) ** 2)",
        "sx2 = dt**2 * ((s * sigma_course_rad * np.sin(c)) ** 2"
        " + (sigma_speed_m_s * np.cos(c)) ** 2)",
        "seed 000's eq. 10 sigma_x^2 with the course's sine and cosine swapped",
    ),
    # --- doubled or halved defaults ----------------------------------------------------------
    Mutation(
        "usbl-default-sound-speed-halved",
        "own",
        "default",
        "bauv_sim/sensors/usbl.py",
        '        1500.0,\n        gt=0,\n        description="for the travel-time latency',
        '        750.0,\n        gt=0,\n        description="for the travel-time latency',
        "the USBL's default sound speed 750 m/s",
    ),
    Mutation(
        "usbl-default-azimuth-sigma-doubled",
        "own",
        "default",
        "bauv_sim/sensors/usbl.py",
        'AngleErrorConfig(sigma_deg=3.0), description="azimuth error"',
        'AngleErrorConfig(sigma_deg=6.0), description="azimuth error"',
        "the USBL's default azimuth sigma 6 deg instead of seed 000's 3 deg",
    ),
    Mutation(
        "pressure-default-sigma-doubled",
        "own",
        "default",
        "bauv_sim/sensors/pressure.py",
        "LengthErrorConfig(sigma_m=0.25)",
        "LengthErrorConfig(sigma_m=0.5)",
        "the pressure sensor's default sigma 0.5 m instead of seed 000's sigma_dz 0.25 m",
    ),
    Mutation(
        "log-default-sigma-halved",
        "own",
        "default",
        "bauv_sim/sensors/log.py",
        "SpeedErrorConfig(sigma_m_s=0.5 * KNOT_M_S)",
        "SpeedErrorConfig(sigma_m_s=0.25 * KNOT_M_S)",
        "the log's default sigma 0.25 kn instead of the ALIZE's 0.5 kn (seed 000)",
    ),
    Mutation(
        "doa-default-sigma-doubled",
        "own",
        "default",
        "bauv_sim/sensors/doa.py",
        "    return AngleErrorConfig(sigma_deg=0.5)\n",
        "    return AngleErrorConfig(sigma_deg=1.0)\n",
        "the DOA's default bearing sigma 1 deg instead of seed 004's 0.5 deg",
    ),
    Mutation(
        "randomised-current-default-sigma-direction-doubled",
        "own",
        "default",
        "bauv_sim/currents.py",
        'Field(math.sqrt(10.0), ge=0, description="sigma_alpha, deg")',
        'Field(2 * math.sqrt(10.0), ge=0, description="sigma_alpha, deg")',
        "seed 001's sigma_alpha^2 = 10 deg^2 default made 40 deg^2",
    ),
    Mutation(
        "seed001-current-direction-variance-doubled",
        "own",
        "default",
        "bauv_sim/kinematic/seed001.py",
        '10.0, ge=0, description="sigma_alpha^2: variance of the current\'s direction, deg^2"',
        '20.0, ge=0, description="sigma_alpha^2: variance of the current\'s direction, deg^2"',
        "the seed 001 replica's sigma_alpha^2 default 20 deg^2 instead of the paper's 10",
    ),
    # --- signs and 180-degree flips ----------------------------------------------------------
    Mutation(
        "uniform-current-direction-180",
        "own",
        "sign",
        "bauv_sim/currents.py",
        "velocity_from_course_speed(self.direction_rad, self.speed_m_s)",
        "velocity_from_course_speed(self.direction_rad + math.pi, self.speed_m_s)",
        "the uniform current sets towards its direction + 180 deg (from, not towards)",
    ),
    Mutation(
        "seed001-replica-current-direction-180",
        "own",
        "sign",
        "bauv_sim/kinematic/seed001.py",
        "d_l.append(rng.normal(mean_dir, sigma_dir, _SEGMENT_CHUNK))",
        "d_l.append(rng.normal(mean_dir + math.pi, sigma_dir, _SEGMENT_CHUNK))",
        "the seed 001 replica's current sets towards alpha_c + 180 deg",
    ),
    Mutation(
        "gyre-rotation-sense-flipped",
        "own",
        "sign",
        "bauv_sim/currents.py",
        "sense = -1.0 if self.clockwise else 1.0",
        "sense = 1.0 if self.clockwise else -1.0",
        "the gyre turns the other way",
    ),
    Mutation(
        "pseudo-measurement-quadrant-flipped",
        "own",
        "sign",
        "nav/bearings/filters.py",
        "phi = np.arctan(y[..., 0]) + np.where(dx < 0, np.pi, 0.0)",
        "phi = np.arctan(y[..., 0]) + np.where(dx > 0, np.pi, 0.0)",
        "eq. 19's phi put in the opposite quadrant (the beacon's bearing + 180 deg)",
    ),
    Mutation(
        "compass-deviation-sine-sign",
        "own",
        "sign",
        "bauv_sim/sensors/errors.py",
        "out = out + a + b * np.sin(ref) + c * np.cos(ref)",
        "out = out + a - b * np.sin(ref) + c * np.cos(ref)",
        "the compass deviation's B sin(psi) term with the wrong sign",
    ),
    Mutation(
        "process-noise-cross-term-sign",
        "own",
        "sign",
        "nav/models.py",
        "Q[..., 0, 1] = Q[..., 1, 0] = g00 * g10 * sc2 + g01 * g11 * ss2",
        "Q[..., 0, 1] = Q[..., 1, 0] = -(g00 * g10 * sc2 + g01 * g11 * ss2)",
        "eq. 16's process noise with the sign of its east-north covariance flipped",
    ),
    Mutation(
        "cmnf-correction-offset-sign",
        "own",
        "sign",
        "nav/bearings/cmnf.py",
        "    h = -H @ mb\n",
        "    h = H @ mb\n",
        "eq. 22's h_k = +H_k E beta instead of -H_k E beta",
    ),
    # --- unit labels -------------------------------------------------------------------------
    Mutation(
        "usbl-azimuth-unit-deg",
        "own",
        "unit",
        "tasks/closed_loop/result.py",
        '"azimuth": ("rad", "measured azimuth, clockwise from north", ())',
        '"azimuth": ("deg", "measured azimuth, clockwise from north", ())',
        "the USBL table's azimuth labelled deg",
    ),
    Mutation(
        "truth-rph-unit-deg",
        "own",
        "unit",
        "tasks/closed_loop/result.py",
        '"truth_rph": (\n        "rad",',
        '"truth_rph": (\n        "deg",',
        "the true roll, pitch, heading labelled deg",
    ),
    Mutation(
        "ekf-covariance-unit-m",
        "own",
        "unit",
        "tasks/closed_loop/result.py",
        '"ekf_P": ("m^2",',
        '"ekf_P": ("m",',
        "the EKF covariance labelled m instead of m^2",
    ),
    Mutation(
        "swarm-leader-course-unit-deg",
        "own",
        "unit",
        "tasks/missions/swarm/follower.py",
        '"leader_course": ("leader_course", "rad", "the leader\'s stated course", (), False)',
        '"leader_course": ("leader_course", "deg", "the leader\'s stated course", (), False)',
        "the swarm followers' leader_course labelled deg",
    ),
    Mutation(
        "modem-hdop-unit-m",
        "own",
        "unit",
        "tasks/closed_loop/result.py",
        '"hdop": ("1", "HDOP of the fix',
        '"hdop": ("m", "HDOP of the fix',
        "the modem table's HDOP labelled m",
    ),
    # --- swapped columns ---------------------------------------------------------------------
    Mutation(
        "gps-east-north-columns-swapped",
        "own",
        "columns",
        "tasks/closed_loop/result.py",
        '        "east": ("m", "measured antenna east", ()),\n'
        '        "north": ("m", "measured antenna north", ()),\n',
        '        "north": ("m", "measured antenna north", ()),\n'
        '        "east": ("m", "measured antenna east", ()),\n',
        "the GPS table's east and north columns swapped (filled in declaration order)",
    ),
    Mutation(
        "usbl-azimuth-elevation-columns-swapped",
        "own",
        "columns",
        "tasks/closed_loop/result.py",
        '        "azimuth": ("rad", "measured azimuth, clockwise from north", ()),\n'
        '        "elevation": ("rad", "measured elevation, positive up", ()),\n',
        '        "elevation": ("rad", "measured elevation, positive up", ()),\n'
        '        "azimuth": ("rad", "measured azimuth, clockwise from north", ()),\n',
        "the USBL table's azimuth and elevation columns swapped",
    ),
    Mutation(
        "truth-rph-components-swapped",
        "own",
        "columns",
        "tasks/closed_loop/result.py",
        '("roll", "pitch", "heading")',
        '("pitch", "roll", "heading")',
        "the true roll and pitch components named the other way round",
    ),
    Mutation(
        "modem-t-valid-t-arrival-swapped",
        "own",
        "columns",
        "tasks/missions/swarm/follower.py",
        'FixRecord("modem", m.t_valid_s, t, z,',
        'FixRecord("modem", t, m.t_valid_s, z,',
        "the modem table's t_valid and t_arrival swapped",
    ),
    Mutation(
        "summary-ekf-dr-errors-swapped",
        "own",
        "columns",
        "tasks/closed_loop/result.py",
        "    e_ekf = np.hypot(*(ekf - truth)[:, :2].T)\n"
        "    e_dr = np.hypot(*(dr - truth)[:, :2].T)\n",
        "    e_ekf = np.hypot(*(dr - truth)[:, :2].T)\n"
        "    e_dr = np.hypot(*(ekf - truth)[:, :2].T)\n",
        "the summary's (and report's) EKF and DR error columns swapped",
    ),
]
"""Mutations of the same kinds, written for this run (see the README's table)."""

OWN_ROUND2: list[Mutation] = [
    Mutation(
        "paper003-nees-band-dim-3",
        "own",
        "dof",
        "tasks/paper003/report.py",
        "lo, hi = nees_band(2, nf, scn.report.consistency_probability)",
        "lo, hi = nees_band(3, nf, scn.report.consistency_probability)",
        "seed 003's NEES band of the follower's 2-D position taken with 3 dof per fix",
    ),
    Mutation(
        "modem-travel-time-dropped",
        "own",
        "correction",
        "bauv_sim/sensors/modem.py",
        "t_arr = t[None, :] + r / c.sound_speed_m_s + c.processing_delay_s",
        "t_arr = t[None, :] + c.processing_delay_s",
        "the modem's latency without the acoustic travel time",
    ),
    Mutation(
        "pcrb-prediction-transposed",
        "own",
        "transpose",
        "nav/bearings/pcrb.py",
        "prior = q + f @ np.linalg.inv(J) @ f.T",
        "prior = q + f.T @ np.linalg.inv(J) @ f",
        "the PCRB's prediction F^T J^-1 F instead of F J^-1 F^T",
    ),
    Mutation(
        "modem-default-range-error-doubled",
        "own",
        "default",
        "bauv_sim/sensors/modem.py",
        'return LengthErrorConfig(distribution="uniform", sigma_m=0.1, uniform_k=1.0,'
        " bias_m=bias_m)",
        'return LengthErrorConfig(distribution="uniform", sigma_m=0.2, uniform_k=1.0,'
        " bias_m=bias_m)",
        "the modem's default range error uniform +-0.2 m instead of seed 003's +-0.1 m",
    ),
    Mutation(
        "log-pitch-term-sign",
        "own",
        "sign",
        "bauv_sim/sensors/log.py",
        "+ np.sin(p) * v[..., 2]",
        "- np.sin(p) * v[..., 2]",
        "the log's speed through water with the vertical term's sign flipped (nose-up pitch)",
    ),
    Mutation(
        "correction-dr-track-unit-m-s",
        "own",
        "unit",
        "tasks/missions/correction/run.py",
        '"dr_uncorrected": ("dr_uncorrected", "m",',
        '"dr_uncorrected": ("dr_uncorrected", "m/s",',
        "mission/correction's uncorrected DRNS track labelled m/s",
    ),
    Mutation(
        "truth-velocity-columns-swapped",
        "own",
        "columns",
        "tasks/closed_loop/world.py",
        '            "truth_vel": vt.velocity_world_m_s,\n'
        '            "truth_vel_water": vt.velocity_through_water_world_m_s,\n',
        '            "truth_vel": vt.velocity_through_water_world_m_s,\n'
        '            "truth_vel_water": vt.velocity_world_m_s,\n',
        "the ticks' velocity over ground and through water swapped",
    ),
    Mutation(
        "modem-centre-columns-swapped",
        "own",
        "columns",
        "tasks/missions/swarm/follower.py",
        "                centre[0],\n                centre[1],\n",
        "                centre[1],\n                centre[0],\n",
        "the modem table's centre_east and centre_north swapped",
    ),
]
"""A second round of our own mutations, written after the tests for the first round had been
added (they measure how well those tests carry over)."""

OWN_ROUND3: list[Mutation] = [
    Mutation(
        "usbl-fold-dropped",
        "own",
        "correction",
        "nav/models.py",
        "        folded = ya_fold**2 / sa2 + yb_fold**2 / sb2 < y[..., 1] ** 2 / sa2"
        " + y[..., 2] ** 2 / sb2\n",
        "        folded = np.zeros(y.shape[:-1], dtype=bool)\n",
        "the USBL innovation of a fix reported over the zenith taken as reported (azimuth + pi)",
    ),
    Mutation(
        "usbl-fold-azimuth-not-turned",
        "own",
        "sign",
        "nav/models.py",
        "ya_fold = wrap_pi(z[..., 1] + np.pi - hx[..., 1])",
        "ya_fold = wrap_pi(z[..., 1] - hx[..., 1])",
        "the folded spelling of a fix over the pole without its azimuth turned by pi",
    ),
    Mutation(
        "swarm-divergence-not-failing",
        "own",
        "correction",
        "tasks/missions/swarm/report.py",
        "return ReportSummary(text, tuple(files), tuple(failures), tuple(diverged))",
        "return ReportSummary(text, tuple(files), tuple(failures))",
        "mission/swarm names a diverged estimate but bauv run exits 0",
    ),
    Mutation(
        "swarm-divergence-dead-reckoning-counted",
        "own",
        "correction",
        "tasks/missions/swarm/run.py",
        'if "diverged_at_s" in m and (name == LEADER or method != "dr"):',
        'if "diverged_at_s" in m:',
        "dead reckoning's drift reported as a diverged estimate",
    ),
    Mutation(
        "cmnf-step-clip-dropped",
        "own",
        "correction",
        "nav/bearings/cmnf.py",
        "b = np.clip(b, gains.beta_lo[i], gains.beta_hi[i])",
        "b = b",
        "the CMNF applies gains fitted on the clipped correction to the unclipped one",
    ),
    Mutation(
        "set-sea-carry-sign",
        "own",
        "sign",
        "bauv_sim/sea.py",
        "physics.shift_velocity_world(change, name)",
        "physics.shift_velocity_world(-change, name)",
        "Sea.immerse (was set_sea) carries the vehicles against the change of the water",
        tests=("tests/bauv_sim/test_sea.py",),
    ),
]
"""A third round, of issue 21's own new code (the USBL fold, the swarm's divergence, the CMNF's
clipped correction, set_sea's carry), written after it had its tests."""

ISSUE22_SEED004 = [
    Mutation(
        "bearing-model-ignores-absent-pairs",
        "own",
        "correction",
        "nav/bearings/model.py",
        "use = observable(x, self.beacons_m) & self.present",
        "use = observable(x, self.beacons_m)",
        "the bearing EKF updates on pairs that were not measured",
    ),
    Mutation(
        "bank-cmnf-covariance-of-the-previous-step",
        "own",
        "correction",
        "nav/bearings/bank.py",
        "gains.p_hat[j - 1], (len(x_new), 3, 3)",
        "gains.p_hat[j - 2], (len(x_new), 3, 3)",
        "the bank states the CMNF's covariance of the previous step for this one",
    ),
    Mutation(
        "seabed-kernel-shape-check-dropped",
        "own",
        "correction",
        "nav/seabed/kernel.py",
        "    if fit_ok.shape[0] < P or to_numpy.shape[0] < P:\n        return -3\n",
        "",
        "the compiled fit writes past an output shorter than the paths (numba checks no bounds)",
    ),
]
"""Issue 22's seed-004 part: the bearing measurement model, the filter bank, the compiled seabed
kernel's shape checks (the C loader's layout check until issue 26)."""

ISSUE22_CORE = [
    Mutation(
        "slant-range-jacobian-sign",
        "own",
        "sign",
        "nav/models.py",
        "        H[..., 0, :3] = d / safe[..., None]\n",
        "        H[..., 0, :3] = -d / safe[..., None]\n",
        "the range to a broadcast position pulls the estimate away from the range circle",
        tests=("tests/nav/test_navigator.py",),
    ),
    Mutation(
        "dr-displacement-between-reversed",
        "own",
        "sign",
        "nav/dead_reckoning.py",
        "return self.position_m[rows, k] - self.position_m[rows, j]",
        "return self.position_m[rows, j] - self.position_m[rows, k]",
        "the dead-reckoned displacement since a fix taken backwards",
        tests=("tests/nav/test_relative.py",),
    ),
    Mutation(
        "packed3-joseph-krk-dropped",
        "own",
        "correction",
        "nav/ekf.py",
        "v = v + K[i][0] * r[0] * K[j][0] + K[i][1] * r[1] * K[j][1] + K[i][2] * r[2] * K[j][2]",
        "v = v + 0.0",
        "the fast path of the one update without the K R K^T of the Joseph form",
    ),
]
"""Issue 22's core interfaces: the slant-range measurement, the one DR's displacement between
samples, the one update's fast path."""

ISSUE23 = [
    Mutation(
        "dvl-max-altitude-ignored",
        "own",
        "default",
        "bauv_sim/sensors/dvl.py",
        "            & (altitude <= cfg.max_altitude_m)\n",
        "",
        "the DVL keeps bottom lock above its maximum altitude",
    ),
    Mutation(
        "dvl-misalignment-ignored",
        "own",
        "correction",
        "bauv_sim/sensors/dvl.py",
        "self.R_mount_true = self.R_mount @ rotation_rpy(cfg.misalignment_deg)",
        "self.R_mount_true = self.R_mount",
        "a misaligned DVL mounting measures as if it were aligned",
    ),
    Mutation(
        "dvl-lever-arm-sign",
        "own",
        "sign",
        "nav/dvl.py",
        "    return np.cross(w, r)\n",
        "    return -np.cross(w, r)\n",
        "the DVL's lever-arm rotation term added instead of removed",
    ),
    Mutation(
        "dvl-jacobian-not-transposed",
        "own",
        "transpose",
        "nav/dvl.py",
        "        H[..., :, i : i + 2] = Rt[..., :, :2]\n",
        "        H[..., :, i : i + 2] = self._R_wb[..., :, :2]\n",
        "the DVL measurement's Jacobian in the current built with R instead of R^T",
    ),
    Mutation(
        "trn-bias-not-marginalised",
        "own",
        "correction",
        "nav/trn/likelihood.py",
        "        r = e - bias[:, None]\n",
        "        r = e\n",
        "TRN likelihood without the ping's common bias removed (a map offset biases the fix)",
    ),
    Mutation(
        "trn-pcrb-without-process-noise",
        "own",
        "correction",
        "nav/trn/pcrb.py",
        "        prior_cov = np.linalg.inv(j) + q[i]\n",
        "        prior_cov = np.linalg.inv(j)\n",
        "the TRN bound forgets the motion's noise between pings",
    ),
    Mutation(
        "trn-particle-covariance-halved",
        "own",
        "unit",
        "nav/trn/particle.py",
        "        return mean, 0.5 * (cov + cov.T)\n",
        "        return mean, 0.25 * (cov + cov.T)\n",
        "the particle filter states half its covariance",
    ),
]
"""Issue 23: the DVL device's lock and mounting, the DVL measurement model, the TRN likelihood,
bound and particle covariance."""

ISSUE24_RAYS = [
    Mutation(
        "ray-layer-distance-top-speed",
        "own",
        "correction",
        "nav/acoustics/rays.py",
        "x = np.where(crossed, dz * (c1 + c2) / (q * (s1 + s2)), 0.0)",
        "x = np.where(crossed, dz * (2.0 * c1) / (q * (s1 + s2)), 0.0)",
        "a ray's horizontal distance across a layer of constant gradient from its top speed only",
    ),
    Mutation(
        "ray-turning-below-arrives-from-above",
        "own",
        "sign",
        "nav/acoustics/rays.py",
        "[np.where(down, theta_r, -theta_r), -theta_r, theta_r]",
        "[np.where(down, theta_r, -theta_r), theta_r, theta_r]",
        "a ray that turns below the receiver is said to arrive from above",
    ),
    Mutation(
        "source-from-arrival-east-north-swapped",
        "own",
        "columns",
        "nav/acoustics/inversion.py",
        "            rcv[:, 0] + horizontal * np.sin(az),\n"
        "            rcv[:, 1] + horizontal * np.cos(az),",
        "            rcv[:, 0] + horizontal * np.cos(az),\n"
        "            rcv[:, 1] + horizontal * np.sin(az),",
        "the USBL source traced back with the azimuth taken from east instead of north",
    ),
    Mutation(
        "usbl-elevation-straight-in-a-profile",
        "own",
        "correction",
        "bauv_sim/sensors/usbl.py",
        "np.where(reached, ray.arrival_elevation_rad, true_rae[..., 2])",
        "true_rae[..., 2]",
        "the USBL in a sound-speed profile measures the straight line's elevation, not the ray's",
        ("tests/sensors/test_usbl_sound.py",),
    ),
    Mutation(
        "modem-latency-straight-in-a-profile",
        "own",
        "correction",
        "bauv_sim/sensors/modem.py",
        "        t_arr = t[None, :] + travel + c.processing_delay_s",
        "        t_arr = t[None, :] + r / c.sound_speed_m_s + c.processing_delay_s",
        "the modem's latency in a sound-speed profile from the straight line at the nominal speed",
        ("tests/sensors/test_usbl_sound.py",),
    ),
]
"""Issue 24, part A: the layered medium's eigenray (distance per layer, arrival sign of a
turning ray), the USBL source traced back, the devices in a profile."""
ISSUE24_SWARM = [
    Mutation(
        "swarm-record-current-of-next-tick",
        "own",
        "index",
        "tasks/missions/swarm/team.py",
        "    c = v[current][: k - 1, :2]",
        "    c = v[current][1:k, :2]",
        "the team record's DR step from tick q dead-reckoned with the current of tick q + 1",
    ),
    Mutation(
        "swarm-relays-never-fused",
        "own",
        "default",
        "tasks/missions/swarm/relay.py",
        "                out.append(r)\n",
        "                pass\n",
        "a vehicle never fuses the ranges it sent that its peers relay back",
    ),
    Mutation(
        "swarm-generated-station-ring",
        "own",
        "index",
        "tasks/missions/swarm/formation.py",
        "distance_m=STATION_RING_M * (ring + 1)",
        "distance_m=STATION_RING_M * (ring + 2)",
        "the generated stations' rings start at 20 m (the default stations move)",
    ),
]
"""Issue 24, mission/swarm: the team record's dead reckoning, the relayed ranges of the
decentralised followers, the generated stations."""
ISSUE24 = [
    Mutation(
        "acoustic-receiver-frozen-during-travel",
        "own",
        "correction",
        "bauv_sim/acoustics/channel.py",
        "        p = receiver_at(t)\n",
        "        p = receiver_at(t_tx_s)\n",
        "the reception time solved with the receiver where it was at the transmit instant",
        tests=("tests/sensors/test_acoustic_network.py",),
    ),
    Mutation(
        "thorp-kiloyard-coefficient",
        "own",
        "unit",
        "bauv_sim/acoustics/sonar.py",
        "44.0 * f2 / (4100.0 + f2)",
        "40.0 * f2 / (4100.0 + f2)",
        "Thorp's dB/kiloyard coefficient used in the dB/km absorption",
        tests=("tests/sensors/test_acoustic_sonar.py", "tests/sensors/test_acoustic_network.py"),
    ),
    Mutation(
        "clock-offset-sign",
        "own",
        "sign",
        "bauv_sim/acoustics/clock.py",
        "return (T - _col(self.offset0_s, T)) / (1.0 + _col(self.drift, T))",
        "return (T + _col(self.offset0_s, T)) / (1.0 + _col(self.drift, T))",
        "a clock's offset added instead of removed when the sender transmits on its schedule",
        tests=("tests/sensors/test_acoustic_clock.py", "tests/sensors/test_acoustic_network.py"),
    ),
    Mutation(
        "acoustic-collisions-ignored",
        "own",
        "correction",
        "bauv_sim/acoustics/network.py",
        "        lost[collided[:, :M]] = LOST_COLLISION\n",
        "",
        "two packets arriving together at a receiver are both decoded",
        tests=("tests/sensors/test_acoustic_network.py",),
    ),
    Mutation(
        "twtt-online-own-replies-ignored",
        "own",
        "correction",
        "bauv_sim/acoustics/twtt_online.py",
        "        own += [o.t2_s for o in self._legs if o.responder == me and o.ok]\n",
        "",
        "the online interrogator hears replies while it is itself replying (half-duplex lost)",
        tests=("tests/sensors/test_acoustic_network.py",),
    ),
]
"""Issue 24 (acoustic channel): the moving receiver's reception time, Thorp's absorption, the
clock's inverse, collisions, the online TWTT's half-duplex."""
ISSUE24_COOP = [
    # part C (nav-coop): the cooperative filters' clocks and covariance intersection
    Mutation(
        "coop-owtt-clock-jacobian-sign",
        "own",
        "sign",
        "nav/cooperative/ranging.py",
        "        H[:, 0, ra + 2] = c\n",
        "        H[:, 0, ra + 2] = -c\n",
        "the one-way range's derivative in the receiver's clock offset with the wrong sign",
        tests=("tests/nav/test_coop_ranging.py", "tests/nav/test_coop_clock.py"),
    ),
    Mutation(
        "coop-clock-drift-not-propagated",
        "own",
        "correction",
        "nav/cooperative/decentralised.py",
        "            fx[:, 2] += self.x[:, 3] * dt_s\n",
        "            fx[:, 2] += 0.0\n",
        "a vehicle's clock offset does not advance by its estimated drift between ranges",
        tests=("tests/nav/test_coop_clock.py", "tests/nav/test_coop_team.py"),
    ),
    Mutation(
        "coop-ci-without-inflation",
        "own",
        "correction",
        "nav/cooperative/decentralised.py",
        "            own_scale, peer_scale = 1.0 / w, 1.0 / (1.0 - w)\n",
        "            own_scale, peer_scale = np.ones(n), np.ones(n)\n",
        "covariance intersection without its scaled priors: the peer's estimate double counted",
        tests=("tests/nav/test_coop_team.py",),
    ),
    # part D (coop-kinematic): the kinematic team's truth and the adapter's ticks
    Mutation(
        "team-second-turn-wrong-side",
        "own",
        "sign",
        "bauv_sim/kinematic/team.py",
        "    c2 = p2 - L * fwd - R * side  # centre of the second turn\n",
        "    c2 = p2 - L * fwd + R * side  # centre of the second turn\n",
        "the racetrack's second half circle turns about a centre on the wrong side",
        ("tests/bauv_sim/test_kinematic_team.py",),
    ),
    Mutation(
        "team-current-not-removed",
        "own",
        "correction",
        "bauv_sim/kinematic/team.py",
        "    vw = vg - cur\n",
        "    vw = vg\n",
        "the team's velocity through the water forgets the current (logs see ground speed)",
        ("tests/bauv_sim/test_kinematic_team.py", "tests/tasks/test_coop.py"),
    ),
    Mutation(
        "coop-range-applied-before-reception",
        "own",
        "default",
        "tasks/coop/run.py",
        "    rx = np.ceil((t_rx + guard_s) / dt - 1e-9)",
        "    rx = np.floor((t_rx + guard_s) / dt - 1e-9)",
        "the kinematic team applies a range at the sample before it was received",
        ("tests/tasks/test_coop.py",),
    ),
]
"""Issue 24: the cooperative filters (part C): the OWTT clock term, the clock prediction, the CI
bound; the kinematic team (part D): its truth's geometry and current, the adapter's ticks."""

ISSUE25: list[Mutation] = [
    Mutation(
        "gridded-current-depth-sign",
        "own",
        "sign",
        "bauv_sim/ocean.py",
        "depth = np.maximum(-flat[:, 2], self.grid.depth_m[0])",
        "depth = np.maximum(flat[:, 2], self.grid.depth_m[0])",
        "the gridded current looked up at the height above the surface instead of the depth",
    ),
    Mutation(
        "gridded-current-units-ignored",
        "own",
        "unit",
        "bauv_sim/ocean.py",
        "values = var.transpose(*order).values.astype(float) * SPEED_UNITS[units]",
        "values = var.transpose(*order).values.astype(float)",
        "an ocean model's velocities in cm/s read as m/s",
    ),
    Mutation(
        "bathymetry-elevation-sign",
        "own",
        "sign",
        "bauv_sim/bathymetry.py",
        'depth = -values if positive == "up" else values',
        'depth = values if positive == "up" else values',
        "a netCDF elevation (positive up) taken as a depth",
    ),
    Mutation(
        "geojson-lat-lon-order",
        "own",
        "columns",
        "tasks/core/geojson.py",
        "return [round(float(lon), DECIMALS), round(float(lat), DECIMALS)]",
        "return [round(float(lat), DECIMALS), round(float(lon), DECIMALS)]",
        "GeoJSON positions written latitude first (RFC 7946 wants longitude, latitude)",
    ),
    Mutation(
        "waypoint-lat-lon-east-north-swapped",
        "own",
        "columns",
        "tasks/closed_loop/geo.py",
        'return {"east_m": float(east), "north_m": float(north), **out}',
        'return {"east_m": float(north), "north_m": float(east), **out}',
        "a position given in latitude/longitude lands with east and north swapped",
    ),
]

MUTATIONS: list[Mutation] = [
    *ISSUE21,
    *OWN,
    *OWN_ROUND2,
    *OWN_ROUND3,
    *ISSUE22_SEED004,
    *ISSUE22_CORE,
    *ISSUE23,
    *ISSUE24_RAYS,
    *ISSUE24_SWARM,
    *ISSUE24,
    *ISSUE24_COOP,
    *ISSUE25,
]

_IGNORE = shutil.ignore_patterns(
    ".git", ".venv", "venv", "__pycache__", ".pytest_cache", ".ruff_cache", "runs", "*.egg-info"
)


class AnchorError(Exception):
    """An original text that does not occur exactly once."""


def check_anchor(root: Path, m: Mutation) -> None:
    """Refuse a mutation whose original text is not in its file exactly once.

    Raises:
        AnchorError: naming the mutation, the file and the count.
    """
    path = root / m.path
    if path.suffix not in (".py",):
        raise AnchorError(f"{m.name}: {m.path} is not a Python file (a C file needs a rebuild)")
    if not path.is_file():
        raise AnchorError(f"{m.name}: {m.path} does not exist")
    count = path.read_text(encoding="utf-8").count(m.original)
    if count != 1:
        raise AnchorError(
            f"{m.name}: the original text occurs {count} times in {m.path} (must be exactly once):"
            f" {m.original.strip()[:100]!r}"
        )
    if m.original == m.replacement:
        raise AnchorError(f"{m.name}: the replacement equals the original")


def copy_checkout(root: Path, dst: Path) -> Path:
    """Copy the checkout ``root`` (sources, tests, models, built ``*.so``) to ``dst``."""
    if not any((root / "bauv_sim" / "plugin").glob("_bauv_hydro*")):
        raise SystemExit("the MuJoCo plugin is not built in the checkout (pip install -e .)")
    shutil.copytree(root, dst, ignore=_IGNORE, symlinks=True)
    return dst


def apply(copy: Path, m: Mutation) -> None:
    """Apply ``m`` to the copy (its anchor checked there too)."""
    check_anchor(copy, m)
    path = copy / m.path
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace(m.original, m.replacement, 1), encoding="utf-8")


@dataclass
class Outcome:
    """What pytest said about one mutant (or the baseline)."""

    verdict: str  # caught | collection error | timeout | survived
    failed: list[str]
    errors: list[str]
    collection_errors: list[str]
    passed: int
    seconds: float
    tail: str


_SUMMARY = re.compile(r"^(FAILED|ERROR) (\S+)")


def run_tests(copy: Path, tests: Sequence[str], fail_fast: bool, timeout_s: float) -> Outcome:
    """Run ``tests`` in the copy, its own modules first on the path; classify the result."""
    env = {**os.environ, "PYTHONPATH": str(copy), "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("BAUV_MUTATION", None)
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            "import nav, bauv_sim, tasks; print(nav.__file__, bauv_sim.__file__, tasks.__file__)",
        ],
        cwd=copy,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if probe.returncode or any(not Path(p).is_relative_to(copy) for p in probe.stdout.split()):
        raise SystemExit(
            f"the copy's packages are not the ones imported: {probe.stdout}{probe.stderr}"
        )
    cmd = [sys.executable, "-m", "pytest", "-q", "-rfE", "-p", "no:cacheprovider"]
    if fail_fast:
        cmd.append("-x")
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [*cmd, *tests],
        cwd=copy,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        out, _ = proc.communicate(timeout=timeout_s)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, _ = proc.communicate()
        timed_out = True
    seconds = time.monotonic() - t0
    failed, errors, coll = [], [], []
    for line in out.splitlines():
        m = _SUMMARY.match(line)
        if not m:
            continue
        node = m.group(2)
        if m.group(1) == "FAILED":
            failed.append(node)
        elif "::" in node:
            errors.append(node)
        else:
            coll.append(node)
    passed = sum(int(n) for n in re.findall(r"(\d+) passed", out.splitlines()[-1] if out else ""))
    if timed_out:
        verdict = "timeout"
    elif coll or proc.returncode not in (0, 1):
        verdict = "collection error"  # pytest could not collect or run the tests at all
    elif failed or errors:
        verdict = "caught"
    else:
        verdict = "survived"
    return Outcome(
        verdict, failed, errors, coll, passed, seconds, "\n".join(out.splitlines()[-15:])
    )


def run_mutant(
    snapshot: Path,
    m: Mutation,
    tests: Sequence[str],
    fail_fast: bool,
    timeout_s: float,
    keep: bool,
) -> Outcome:
    """Copy the snapshot of the checkout, apply ``m`` to the copy, run ``tests`` there."""
    tmp = Path(tempfile.mkdtemp(prefix=f"mutant-{m.name}-"))
    try:
        copy = tmp / "checkout"
        shutil.copytree(snapshot, copy, symlinks=True)
        apply(copy, m)
        return run_tests(copy, tests, fail_fast, timeout_s)
    finally:
        if keep:
            print(f"  kept {tmp}", flush=True)
        else:
            shutil.rmtree(tmp, ignore_errors=True)


def _by(o: Outcome) -> str:
    nodes = o.failed + o.errors + o.collection_errors
    if not nodes:
        return ""
    first = nodes[0]
    more = f" (+{len(nodes) - 1})" if len(nodes) > 1 else ""
    return f"`{first}`{more}"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="mutations to run (default: the selected groups)")
    ap.add_argument("--group", choices=("issue21", "own", "all"), default="all")
    ap.add_argument("--whole-suite", action="store_true", help="run the whole suite per mutant")
    ap.add_argument("--all-failures", action="store_true", help="do not stop at the first failure")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per mutant")
    ap.add_argument("--jobs", type=int, default=1, help="mutants run at a time")
    ap.add_argument("--no-baseline", action="store_true", help="skip the unmutated run")
    ap.add_argument(
        "--count-collection-errors", action="store_true", help="count a collection error as caught"
    )
    ap.add_argument("--keep", action="store_true", help="keep the mutated copies")
    ap.add_argument("--list", action="store_true", help="list the mutations and exit")
    ap.add_argument("--check", action="store_true", help="check the anchors only")
    ap.add_argument(
        "--checkout",
        type=Path,
        default=ROOT,
        help="the checkout to copy and mutate (default: the one holding this script); it must "
        "have its C libraries built",
    )
    args = ap.parse_args(argv)
    root = args.checkout.resolve()

    names = [m.name for m in MUTATIONS]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise SystemExit(f"duplicate mutation names: {sorted(dup)}")
    by_name = {m.name: m for m in MUTATIONS}
    unknown = [n for n in args.names if n not in by_name]
    if unknown:
        print(f"unknown mutations: {', '.join(unknown)} (--list names them)", file=sys.stderr)
        return 2
    if args.names:
        chosen = [by_name[n] for n in args.names]
    else:
        chosen = [m for m in MUTATIONS if args.group in ("all", m.group)]

    if args.list:
        for m in chosen:
            eq = "  [equivalent]" if m.equivalent else ""
            print(f"{m.name} ({m.group}, {m.kind}) {m.path}: {m.what}{eq}")
            print(f"    tests: {' '.join(m.guards())}")
        return 0

    bad = []
    for m in chosen:
        try:
            check_anchor(root, m)
        except AnchorError as e:
            bad.append(str(e))
        for t in m.guards():
            if not (root / t.split("::")[0]).is_file():
                bad.append(f"{m.name}: its test file {t.split('::')[0]} does not exist")
    if bad:
        print("REFUSED: mutations whose anchors or tests do not match the code:", file=sys.stderr)
        for b in bad:
            print(f"  {b}", file=sys.stderr)
        return 1
    if args.check:
        print(f"all {len(chosen)} anchors match exactly once; every guarding test file exists")
        return 0

    suite = ("tests",)
    plan = {m.name: (suite if args.whole_suite else m.guards()) for m in chosen}
    status = 0
    # one snapshot of the checkout for the whole run: edits made to the working tree meanwhile
    # do not reach the mutants
    tmp = Path(tempfile.mkdtemp(prefix="mutation-tests-"))
    try:
        snapshot = copy_checkout(root, tmp / "snapshot")
        if not args.no_baseline:
            union: list[str] = []
            for tests in plan.values():
                union += [t for t in tests if t not in union]
            print(f"baseline: {len(union)} test files on the unmutated copy ...", flush=True)
            base = run_tests(snapshot, union, False, args.timeout)
            print(f"baseline: {base.passed} passed, {base.seconds:.0f} s", flush=True)
            if base.verdict != "survived":
                print("the tests fail without a mutation:\n" + base.tail, file=sys.stderr)
                return 1

        def one(m: Mutation) -> tuple[Mutation, Outcome]:
            o = run_mutant(
                snapshot, m, plan[m.name], not args.all_failures, args.timeout, args.keep
            )
            print(f"{m.name}: {o.verdict} {_by(o)} ({o.seconds:.0f} s)", flush=True)
            if args.all_failures:
                for node in o.failed + o.errors + o.collection_errors:
                    print(f"    fails: {node}", flush=True)
            return m, o

        with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            results = list(pool.map(one, chosen))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    print()
    print("| mutant | group | kind | file | verdict | by (first failing test) | tests run |")
    print("|---|---|---|---|---|---|---|")
    counted = caught = 0
    for m, o in results:
        verdict = o.verdict
        if verdict == "survived" and m.equivalent:
            verdict = "survived (equivalent)"
        files = ", ".join(Path(t.split("::")[0]).stem for t in plan[m.name])
        print(f"| {m.name} | {m.group} | {m.kind} | `{m.path}` | {verdict} | {_by(o)} | {files} |")
        if m.equivalent:
            continue
        counted += 1
        ok = o.verdict == "caught" or (
            args.count_collection_errors and o.verdict == "collection error"
        )
        caught += ok
        if not ok:
            status = 1
    print()
    for group in ("issue21", "own"):
        rs = [(m, o) for m, o in results if m.group == group and not m.equivalent]
        if rs:
            c = sum(o.verdict == "caught" for _, o in rs)
            print(f"{group}: {c} of {len(rs)} caught ({100 * c / len(rs):.0f} %)")
    eq = [m for m, _ in results if m.equivalent]
    print(
        f"rate: {caught} of {counted} caught ({100 * caught / max(counted, 1):.0f} %)"
        + (f"; {len(eq)} documented equivalent, left out" if eq else "")
    )
    for m in eq:
        print(f"  {m.name} is equivalent: {m.equivalent}")
    for m, o in results:
        if o.verdict in ("collection error", "timeout"):
            print(f"  {m.name}: {o.verdict}\n{o.tail}")
    return status


if __name__ == "__main__":
    sys.exit(main())
