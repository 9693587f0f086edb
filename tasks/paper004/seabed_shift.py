"""``paper-004/seabed-shift``: the seabed-sensing shift estimate's own error on seed 004's
setting (section 6).

Seed 004 predicts with ``X-tilde_{k+1} = X-hat_k + dX-hat_{k+1}`` (Table 1, second row), the shift
coming from two acoustic images (:func:`nav.seabed.shift_estimate`, eq. 8-15 with Appendix A).
This experiment measures that shift's error ``dX-hat_{k+1} - (X_{k+1} - X_k)`` alone, for both
readings of the beam attitude between two images (:data:`nav.seabed.BeamAttitude`), on the same
paths, seabeds and range noise:

* nominal path of eq. 3 with ``gamma_k = pi/100 cos(pi t_k / 100)``, ``theta_k = pi/3
  cos(pi t_k / 25)``, V = 2 m/s, ``X_0 = (0, 0, -10)``, dt = 1 s, N = 300 steps;
* truth of eq. 2: ``X_0 ~ N(nominal start, I)``, ``W_k ~ N(0, I)``;
* the control of eq. 6 on the vehicle's position known to ``estimate_sigma_m`` (0: full
  information; else the position plus N(0, sigma^2 I) per step, a stand-in for a filter's
  estimate: the filters are not part of this measurement);
* the harmonic seabed of eq. 24 with K = 2, a0 = 30 m, Px = Py = 20 m, coefficients standard
  uniform per path; 8 x 8 beams (42 .. 82 deg down, -10 .. 30 deg), range noise 0.1 m
  (:class:`bauv_sim.sensors.multibeam.MultibeamConfig` defaults), transducer at ``X_k``;
* "one_attitude": the images at ``X_k`` and ``X_{k+1}`` both aimed from ``u_k``; "turning": the
  second one aimed from ``u_{k+1}`` (eq. 10).

Run: ``bauv run paper-004/seabed-shift --runs 500 --seed 1`` (one run is one path and its seabed;
``--set delta_e=exact`` for the exact beam change of the turning reading, ``--set
estimate_sigma_m=...`` for a control on a noisy position, ``--set steps=...``). Every path draws
from its own streams, so a batch's numbers do not depend on its blocks or workers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim import rng as rng_mod
from bauv_sim.config import Config
from bauv_sim.sensors.multibeam import HarmonicSeabed, Multibeam, MultibeamConfig
from nav import dead_reckoning
from nav.seabed import BeamGeometry, SlopeBasis, shift_estimate
from tasks.core.registry import (
    Experiment,
    MemoryTerm,
    ReportContext,
    ReportSummary,
    block_by_work,
    register,
)
from tasks.core.report import Table, write_metrics, write_tables

Array = NDArray[np.float64]

READINGS = ("one_attitude", "turning")


def nominal_path(steps: int = 300, dt_s: float = 1.0) -> tuple[Array, Array]:
    """Seed 004's nominal path (eq. 3, section 6).

    Args:
        steps: N.
        dt_s: the step, s.

    Returns:
        ``(positions, velocities)``: shape (N + 1, 3), m, and (N + 1, 3), m/s (world, z up).
    """
    t = np.arange(steps + 1) * dt_s
    gamma = np.pi / 100 * np.cos(np.pi / 100 * t)
    theta = np.pi / 3 * np.cos(np.pi / 25 * t)
    v = 2.0 * np.column_stack(
        [np.cos(gamma) * np.cos(theta), np.cos(gamma) * np.sin(theta), np.sin(gamma)]
    )
    x = dead_reckoning.track(np.array([[0.0, 0.0, -10.0]]), (v[:-1] * dt_s)[None])[0]
    return x, v


def control_attitude(target_m: Array, position_m: Array) -> tuple[Array, Array]:
    """Eq. 6: the direction and speed that reach ``target`` in one step of 1 s.

    Args:
        target_m: the next nominal point, shape (P, 3), m.
        position_m: the position the control believes, shape (P, 3), m.

    Returns:
        ``(attitude, speed)``: ``(gamma*, theta*)`` shape (P, 2), rad (atan2 with the horizontal
        distance, reading notes), and ``V* dt``, shape (P,), m.
    """
    d = target_m - position_m
    theta = np.arctan2(d[:, 1], d[:, 0])
    gamma = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    return np.column_stack([gamma, theta]), np.linalg.norm(d, axis=1)


@dataclass(frozen=True)
class ShiftErrors:
    """Errors of the shift estimate of every step of every path, one reading.

    Attributes:
        error_m: ``dX-hat - dX``, shape (P, N, 3), m (zero where no shift was produced).
        ok: the shift was produced, shape (P, N).
        predicted_var_m2: trace of the stated covariance, shape (P, N), m^2.
        rank: observed directions of the shift (3: all), shape (P, N).
        beams: beams with an echo in both images, shape (P, N).
    """

    error_m: Array
    ok: NDArray[np.bool_]
    predicted_var_m2: Array
    rank: NDArray[np.int_]
    beams: NDArray[np.int_]

    def summary(self) -> dict[str, float | list[float] | int]:
        """Median and 90th percentile of the error norm, bias (mean error per component), RMS
        per component over the produced shifts; the stated RMS (root of the mean trace) over the
        fully observed ones (a direction not observed is stated with the fallback variance);
        the samples (all, produced, and produced with rank < 3)."""
        e = self.error_m[self.ok]
        full = self.ok & (self.rank == 3)
        if e.size == 0:
            return {"samples": 0, "produced": 0, "no_data": 1}
        norm = np.linalg.norm(e, axis=1)
        return {
            "samples": int(self.ok.size),
            "produced": int(self.ok.sum()),
            "median_m": float(np.median(norm)),
            "p90_m": float(np.percentile(norm, 90)),
            "bias_m": [float(v) for v in e.mean(axis=0)],
            "rms_m": [float(v) for v in np.sqrt((e**2).mean(axis=0))],
            "stated_rms_m": float(np.sqrt(self.predicted_var_m2[full].mean()))
            if full.any()
            else 0.0,
            "rank_deficient": int((self.ok & (self.rank < 3)).sum()),
            "mean_beams": float(self.beams.mean()),
        }


def measure_shift_error(
    paths: int | tuple[int, ...] = 500,
    seed: int = 1,
    steps: int = 300,
    estimate_sigma_m: float = 0.0,
    sonar: MultibeamConfig | None = None,
    basis: SlopeBasis | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
) -> dict[str, ShiftErrors]:
    """The shift estimate's error on seed 004's setting for both readings (module docstring).

    Args:
        paths: sample paths P (one seabed each), or the run indices of the paths (a block of a
            batch: each path draws from its own streams).
        seed: batch seed (streams ``("seabed004", ...)`` and the sonar's per run).
        steps: N.
        estimate_sigma_m: noise of the position the control uses, m (0: full information).
        sonar: the multibeam (default: seed 004's).
        basis: Appendix A's basis (default: eq. 24's harmonics).
        delta_e: the turning reading's beam change: eq. 10 (``"linear"``) or exact.

    Returns:
        Reading -> :class:`ShiftErrors`.
    """
    cfg = sonar or MultibeamConfig()
    runs = tuple(range(paths)) if isinstance(paths, int) else tuple(paths)
    paths = len(runs)
    geometry = BeamGeometry(cfg.elevations_rad(), cfg.azimuths_rad())
    seabed = HarmonicSeabed.draw(seed, runs)
    gens = rng_mod.generators(seed, runs, "seabed004", "motion")
    x0_noise = np.stack([g.standard_normal(3) for g in gens])
    w = np.stack([g.standard_normal((steps, 3)) for g in gens])  # W_k ~ N(0, I)
    est_noise = np.stack([g.standard_normal((steps + 1, 3)) for g in gens]) * estimate_sigma_m
    nominal, _ = nominal_path(steps)
    # the images at X_{k+1}: aimed from u_k (one attitude) and from u_{k+1} (the next image)
    held = Multibeam(cfg, seed, runs, "multibeam/held_attitude")
    new = Multibeam(cfg, seed, runs, "multibeam/new_attitude")
    x = nominal[0] + x0_noise
    att, step_m = control_attitude(np.broadcast_to(nominal[1], x.shape), x + est_noise[:, 0])
    img = new.sample_harmonic(seabed, x[:, None], att[:, None], np.zeros(1))
    out = {
        r: (
            np.zeros((paths, steps, 3)),
            np.zeros((paths, steps), bool),
            np.zeros((paths, steps)),
            np.zeros((paths, steps), int),
            np.zeros((paths, steps), int),
        )
        for r in READINGS
    }
    for k in range(steps):
        e = np.column_stack(
            [
                np.cos(att[:, 0]) * np.cos(att[:, 1]),
                np.cos(att[:, 0]) * np.sin(att[:, 1]),
                np.sin(att[:, 0]),
            ]
        )
        x1 = x + step_m[:, None] * e + w[:, k]  # eq. 2
        t1 = np.array([k + 1.0])
        if k + 1 < steps:
            att1, step1 = control_attitude(
                np.broadcast_to(nominal[k + 2], x1.shape), x1 + est_noise[:, k + 1]
            )
        else:
            att1, step1 = att, step_m
        img_held = held.sample_harmonic(seabed, x1[:, None], att[:, None], t1)
        img_new = new.sample_harmonic(seabed, x1[:, None], att1[:, None], t1)
        for reading, second, a1 in (
            ("one_attitude", img_held, att),
            ("turning", img_new, att1),
        ):
            est = shift_estimate(
                img.ranges_m[:, 0],
                second.ranges_m[:, 0],
                geometry,
                att,
                a1,
                echo=img.echo[:, 0],
                next_echo=second.echo[:, 0],
                reading=reading,
                basis=basis,
                position_m=x,
                sigma_range_m=cfg.range.sigma_m,
                delta_e=delta_e,
            )
            err, ok, var, rank, beams = out[reading]
            err[:, k] = np.where(est.ok[:, None], est.shift_m - (x1 - x), 0.0)
            ok[:, k] = est.ok
            var[:, k] = np.trace(est.covariance_m2, axis1=1, axis2=2)
            rank[:, k] = est.rank
            beams[:, k] = est.beams
        x, att, step_m, img = x1, att1, step1, img_new
    return {r: ShiftErrors(*out[r]) for r in READINGS}


# ---------------------------------------------------------------------------------------------
# The registered experiment


class SeabedShiftScenario(Config):
    """The setting of the shift-error measurement (defaults: seed 004, section 6)."""

    steps: int = Field(300, ge=1, le=100_000, description="steps N per path (seed 004: 300)")
    estimate_sigma_m: float = Field(
        0.0,
        ge=0,
        description="noise of the position the control uses, m (0: full information)",
    )
    delta_e: Literal["linear", "exact"] = Field(
        "linear", description="the turning reading's beam change: eq. 10 or the exact one"
    )
    multibeam: MultibeamConfig = Field(
        default_factory=MultibeamConfig, description="the sonar (seed 004's 8 x 8 beams)"
    )
    block_size: int | None = Field(
        None,
        ge=1,
        le=100_000,
        description="paths per block (default: as many as make 150,000 path-steps)",
    )


class ReadingErrors(BaseModel):
    """One reading's shift error over the batch (:meth:`ShiftErrors.summary`)."""

    samples: int = Field(description="path-steps")
    produced: int = Field(description="path-steps with a shift")
    median_m: float | None = Field(None, description="median error norm, m")
    p90_m: float | None = Field(None, description="90th percentile of the error norm, m")
    bias_m: list[float] | None = Field(None, description="mean error (x, y, z), m")
    rms_m: list[float] | None = Field(None, description="RMS error (x, y, z), m")
    stated_rms_m: float | None = Field(
        None, description="root of the mean trace of the stated covariance (rank 3 shifts), m"
    )
    rank_deficient: int | None = Field(None, description="produced shifts of rank < 3")
    mean_beams: float | None = Field(None, description="beams with an echo in both images")


class SeabedShiftMetrics(BaseModel):
    """``metrics.json`` of ``paper-004/seabed-shift``."""

    schema_version: Literal[1] = 1
    experiment: str
    n_runs: int
    seed: int
    steps: int
    estimate_sigma_m: float
    delta_e: str
    readings: dict[str, ReadingErrors]


@dataclass(frozen=True)
class SeabedShiftExperiment(Experiment):
    """The shift estimate's error alone, both readings of the beam attitude (module docstring).

    A block is a batch of paths (:func:`measure_shift_error`); its result is the per-step errors
    of every path as plain arrays, pooled by the report.
    """

    scenario_type = SeabedShiftScenario
    metrics_type = SeabedShiftMetrics

    def block_size(self, scenario: SeabedShiftScenario) -> int:
        return block_by_work(scenario.block_size, scenario.steps, 150_000)

    def memory(self, scenario: SeabedShiftScenario, n_runs: int) -> list[MemoryTerm]:
        # per reading and path-step: error (3 floats), ok, stated variance, rank, beams
        per = 2 * scenario.steps * (3 * 8 + 1 + 8 + 8 + 8)
        return [
            MemoryTerm(
                per * n_runs,
                False,
                f"runs = {n_runs} paths x steps = {scenario.steps} (the pooled errors)",
            )
        ]

    def run_block(
        self, scenario: SeabedShiftScenario, seed: int, runs: tuple[int, ...]
    ) -> dict[str, dict[str, np.ndarray]]:
        res = measure_shift_error(
            runs,
            seed,
            scenario.steps,
            scenario.estimate_sigma_m,
            sonar=scenario.multibeam,
            delta_e=scenario.delta_e,
        )
        return {r: e.__dict__.copy() for r, e in res.items()}

    def report(self, ctx: ReportContext) -> ReportSummary:
        scn: SeabedShiftScenario = ctx.scenario  # type: ignore[assignment]
        parts: dict[str, list[dict[str, np.ndarray]]] = {r: [] for r in READINGS}
        for block in ctx.blocks:
            for r in READINGS:
                parts[r].append(block[r])
        errors = {
            r: ShiftErrors(**{k: np.concatenate([b[k] for b in parts[r]]) for k in parts[r][0]})
            for r in READINGS
        }
        summaries = {r: ReadingErrors(**e.summary()) for r, e in errors.items()}
        metrics = SeabedShiftMetrics(
            experiment=self.name,
            n_runs=ctx.n_runs,
            seed=ctx.seed,
            steps=scn.steps,
            estimate_sigma_m=scn.estimate_sigma_m,
            delta_e=scn.delta_e,
            readings=summaries,
        )
        files = [write_metrics(ctx.out_dir, metrics)]
        table = shift_table(metrics)
        files += write_tables(ctx.out_dir, [table], heading=f"{self.name}: {self.summary}")
        text = table.to_text() + f"wrote {len(files)} files to {ctx.out_dir}\n"
        return ReportSummary(text, tuple(files))


def shift_table(m: SeabedShiftMetrics) -> Table:
    """The shift error per reading, as a table."""
    rows = []
    for r, s in m.readings.items():
        if not s.produced:
            rows.append([r, *[None] * 10])
            continue
        b, q = s.bias_m or [None] * 3, s.rms_m or [None] * 3
        rows.append([r, s.median_m, s.p90_m, *b, *q, s.stated_rms_m, s.rank_deficient])
    return Table(
        f"Seabed shift error, {m.n_runs} paths x {m.steps} steps, seed {m.seed}, control "
        f"position noise {m.estimate_sigma_m:g} m, turning de {m.delta_e}",
        [
            "reading",
            "median (m)",
            "p90 (m)",
            "bias x (m)",
            "bias y (m)",
            "bias z (m)",
            "rms x (m)",
            "rms y (m)",
            "rms z (m)",
            "stated rms (m)",
            "rank < 3",
        ],
        rows,
        digits=3,
        slug="seabed-shift",
    )


register(
    SeabedShiftExperiment(
        name="paper-004/seabed-shift",
        summary="seed 004 section 4: the seabed-sensing shift's own error (eq. 8-15, Appendix A) "
        "for both readings of the beam attitude, on section 6's path and seabeds",
        default_runs=500,
    )
)
