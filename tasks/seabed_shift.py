"""The seabed-sensing shift estimate's own error on seed 004's setting (section 6).

Seed 004 predicts with ``X-tilde_{k+1} = X-hat_k + dX-hat_{k+1}`` (Table 1, second row), the shift
coming from two acoustic images (:func:`nav.seabed.shift_estimate`, eq. 8-15 with Appendix A).
This script measures that shift's error ``dX-hat_{k+1} - (X_{k+1} - X_k)`` alone, for both
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

Run: ``python -m tasks.seabed_shift --paths 500 --seed 1`` (prints the table; ``--json`` for
machine-readable output, ``--delta-e exact`` for the exact beam change of the turning reading,
``--estimate-sigma-m`` for a control on a noisy position).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.sensors.multibeam import HarmonicSeabed, Multibeam, MultibeamConfig
from nav.seabed import BeamGeometry, SlopeBasis, shift_estimate

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
    x = np.empty((steps + 1, 3))
    x[0] = (0.0, 0.0, -10.0)
    x[1:] = x[0] + np.cumsum(v[:-1] * dt_s, axis=0)
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
    paths: int = 500,
    seed: int = 1,
    steps: int = 300,
    estimate_sigma_m: float = 0.0,
    sonar: MultibeamConfig | None = None,
    basis: SlopeBasis | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
) -> dict[str, ShiftErrors]:
    """The shift estimate's error on seed 004's setting for both readings (module docstring).

    Args:
        paths: sample paths P (one seabed each).
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
    runs = tuple(range(paths))
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


def main(argv: list[str] | None = None) -> int:
    """Print the shift error table (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=500)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--estimate-sigma-m", type=float, default=0.0)
    ap.add_argument("--delta-e", choices=("linear", "exact"), default="linear")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    checks = (
        ("--paths", a.paths, a.paths >= 1, "an integer >= 1"),
        ("--steps", a.steps, a.steps >= 1, "an integer >= 1"),
        ("--seed", a.seed, a.seed >= 0, "an integer >= 0"),
        (
            "--estimate-sigma-m",
            a.estimate_sigma_m,
            bool(np.isfinite(a.estimate_sigma_m) and a.estimate_sigma_m >= 0),
            "a finite number >= 0",
        ),
    )
    for name, value, ok, allowed in checks:
        if not ok:
            print(f"{name} = {value}: must be {allowed}", file=sys.stderr)
            return 2
    res = measure_shift_error(a.paths, a.seed, a.steps, a.estimate_sigma_m, delta_e=a.delta_e)
    table = {r: e.summary() for r, e in res.items()}
    if a.json:
        print(json.dumps(table, indent=2))
        return 0
    print(
        f"seed 004 shift error, {a.paths} paths x {a.steps} steps, seed {a.seed}, "
        f"control position noise {a.estimate_sigma_m:g} m, turning de {a.delta_e}"
    )
    print(
        "reading       | median m | p90 m | bias x, y, z m        | rms x, y, z m         | "
        "stated rms m | rank < 3 | beams"
    )
    for r, s in table.items():
        if s.get("no_data"):
            print(f"{r:13s} | no shift produced")
            continue
        b, q = s["bias_m"], s["rms_m"]
        print(
            f"{r:13s} | {s['median_m']:8.3f} | {s['p90_m']:5.2f} | "
            f"{b[0]:6.3f} {b[1]:6.3f} {b[2]:6.3f}  | {q[0]:6.3f} {q[1]:6.3f} {q[2]:6.3f}  | "
            f"{s['stated_rms_m']:12.3f} | {s['rank_deficient']:8d} | {s['mean_beams']:.1f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
