"""``mission/seed004``'s metrics: one flight's against the nominal path and the truth, and their
summaries over the runs (package docstring)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from nav.bearings import velocity
from nav.bearings.cmnf import CmnfGains
from tasks.closed_loop.result import MissionRun
from tasks.core import store
from tasks.missions.seed004.parts import control_of
from tasks.missions.seed004.scenario import SURROGATE_RUN_OFFSET, Seed004Scenario, surrogate

if TYPE_CHECKING:
    pass

Array = NDArray[np.float64]

# ---------------------------------------------------------------------------------------------
# Metrics of one flight


def distance_to_polyline(points: Array, line: Array) -> Array:
    """Distance of each point to a polyline.

    Args:
        points: shape (n, 3), m.
        line: vertices, shape (m, 3), m (m >= 2).

    Returns:
        Shape (n,), m: the distance to the nearest point of any segment.
    """
    a, b = line[:-1], line[1:]
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    ap = points[:, None, :] - a[None]
    t = np.clip(np.einsum("nij,ij->ni", ap, ab) / L2, 0.0, 1.0)
    near = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None, :] - near, axis=2).min(axis=1)


def flight_metrics(
    run: MissionRun, nominal: Array, dt: float, seabed_shift: bool = False
) -> dict[str, Any]:
    """Path following and estimation of one flight (NaN never: missing data gives ``None``).

    Args:
        run: the flight.
        nominal: the nominal path, shape (N + 1, 3), m.
        dt: filter step, s.
        seabed_shift: the flight predicted with the seabed shift (adds its errors).

    Returns:
        ``path_mean_m`` / ``path_max_m`` (distance of the truth to the nominal path, every
        control tick), ``j_k`` (``||X°_k - X_k||^2`` at the filter steps, list, m^2),
        ``est_rmse_m`` / ``est_max_m`` (``||X_k - X^_k||`` at the filter steps), ``residual_std_m``
        (per axis, of ``X_{k+1} - X_k - V(u_k) dt``), ``steps`` reached, and with
        ``seabed_shift``: ``shift_err_m`` (the seabed shift less the true move of the reference
        point at each filter step with a shift, ``(n, 3)`` float32, m), ``shift_beams_mean`` and
        ``shift_none`` (steps after the first without a shift).
    """
    v = run.lead
    seen = {k: int(v.outcome.get(k, 0)) for k in ("absent_pairs", "missing_sets")}
    c = v.ticks
    x = np.asarray(c["truth_pos"].values, float)
    xh = np.asarray(c["ekf_pos"].values, float)
    k = np.asarray(c["filter_step"].values, float)
    u = control_of(c)
    sel = np.flatnonzero(k >= 0)
    ks = k[sel].astype(int)
    if len(x) < 2 or len(sel) < 2:
        return {"steps": int(ks.max()) if len(ks) else 0, **seen}
    d = distance_to_polyline(x, nominal)
    xk = x[sel]
    e = np.linalg.norm(xk - xh[sel], axis=1)
    jk = np.sum((xk - nominal[ks]) ** 2, axis=1)
    # the control applied over step j is the one logged at step j
    res = xk[1:] - xk[:-1] - velocity(u[sel][:-1]) * dt
    return {
        "steps": int(ks.max()),
        "path_mean_m": float(d.mean()),
        "path_max_m": float(d.max()),
        "j_k": [float(a) for a in jk],
        "est_rmse_m": float(np.sqrt(np.mean(e[1:] ** 2))),
        "est_max_m": float(e[1:].max()),
        "est_rmse_axis_m": [float(a) for a in np.sqrt(np.mean((xk - xh[sel])[1:] ** 2, axis=0))],
        "residual_std_m": [float(a) for a in res.std(axis=0)],
        "residual_mean_m": [float(a) for a in res.mean(axis=0)],
        "track": xk.astype(np.float32),
        **seen,
        **(_shift_errors(c, sel, xk) if seabed_shift else {}),
    }


def _shift_errors(c, sel: NDArray[np.int_], xk: Array) -> dict[str, Any]:
    """The seabed shift's own error at the filter steps that had one (:func:`flight_metrics`)."""
    if "shift_beams" not in c:
        return {}
    beams = np.asarray(c["shift_beams"].values, float)[sel][1:]
    shift = np.asarray(c["shift"].values, float)[sel][1:]
    used = beams > 0
    err = (shift - (xk[1:] - xk[:-1]))[used]
    return {
        "shift_err_m": err.astype(np.float32),
        "shift_beams_mean": float(beams[used].mean()) if used.any() else 0.0,
        "shift_none": int((~used[1:]).sum()),
    }


@store.plain_data("missions.seed004.Seed004RunResult")
@dataclass
class Seed004RunResult:
    """One run: per filter, the flight and its metrics (plain data).

    Attributes:
        run: run index.
        failed: per filter, the failure or ``None``.
        metrics: per filter, :func:`flight_metrics`.
        flights: per filter, the flight (its ticks: the truth, that filter's estimate and
            covariance as ``ekf_pos`` / ``ekf_P``, DR, the commands, the control; its ``doa``
            fix table: the bearings), exported as the run data with the filter as the variant.
    """

    run: int
    failed: dict[str, str | None]
    metrics: dict[str, dict[str, Any]] = field(default_factory=dict)
    flights: dict[str, MissionRun] = field(default_factory=dict)


class FilterSummary(BaseModel):
    """One filter over the batch."""

    runs_ok: int
    path_mean_m: float | None = Field(description="mean over runs of the mean distance, m")
    path_max_m: float | None = Field(description="max over runs of the max distance, m")
    path_max_mean_m: float | None = Field(description="mean over runs of the max distance, m")
    est_rmse_m: float | None = Field(description="RMS estimation error at the filter steps, m")
    est_max_m: float | None = Field(description="max estimation error over runs and steps, m")
    est_rmse_axis_m: list[float] | None = Field(description="RMS error per axis (x, y, z), m")
    j_bar_m2: float | None = Field(description="max_k mean over runs ||X°_k - X_k||^2, m^2")
    j_mean_m2: float | None = Field(description="mean_k mean over runs ||X°_k - X_k||^2, m^2")
    residual_std_m: list[float] | None = Field(description="physics step residual std, m")
    residual_mean_m: list[float] | None = Field(description="physics step residual mean, m")
    diverged_runs: int = Field(0, description="runs whose flight stopped on a named failure")
    shift_steps: int = Field(0, description="filter steps with a seabed shift (all runs)")
    shift_err_median_m: float | None = Field(None, description="median |shift error|, m")
    shift_err_p90_m: float | None = Field(None, description="90th percentile |shift error|, m")
    shift_err_bias_m: list[float] | None = Field(None, description="mean shift error, m")
    shift_beams_mean: float | None = Field(None, description="beams used per shift, mean")
    shift_none_steps: int = Field(0, description="filter steps without a shift (no echoes)")


class Seed004Metrics(BaseModel):
    """``metrics.json`` of ``mission/seed004``."""

    schema_version: Literal[1] = 1
    experiment: str
    seed: int
    n_runs: int
    prediction: Literal["system", "seabed"] = "system"
    filters: dict[str, FilterSummary]
    cmnf_j_bar_surrogate_m2: float | None = Field(description="CMNF J-bar on the surrogate")
    cmnf_j_bar_physics_m2: float | None
    cmnf_gap_m2: float | None = Field(description="physics minus surrogate J-bar, m^2")
    cmnf_j_mean_surrogate_m2: float | None = Field(description="CMNF time-mean J, surrogate")
    cmnf_j_mean_physics_m2: float | None
    cmnf_j_mean_gap_m2: float | None = Field(description="physics minus surrogate mean J, m^2")
    surrogate_shift: dict[str, Any] = Field(
        default_factory=dict,
        description="the seabed shift's error on the CMNF's surrogate paths (median, p90, bias)",
    )
    cmnf_train_paths: int
    failures: list[str]
    warnings: list[str]


def _mean(vals: list[float]) -> float | None:
    return float(np.mean(vals)) if vals else None


def _shift_summary(results: list[Seed004RunResult], name: str) -> dict[str, Any]:
    """The seabed shift's own error pooled over the filter steps of every run (failed ones too:
    the shift does not depend on the filter's success)."""
    all_m = [r.metrics[name] for r in results if name in r.metrics]
    errs = [np.asarray(m["shift_err_m"], float) for m in all_m if "shift_err_m" in m]
    out: dict[str, Any] = {
        "diverged_runs": sum(1 for r in results if r.failed.get(name) is not None),
        "shift_none_steps": sum(int(m.get("shift_none", 0)) for m in all_m),
    }
    err = np.concatenate(errs) if errs else np.zeros((0, 3))
    if len(err):
        norm = np.linalg.norm(err, axis=1)
        beams = [m["shift_beams_mean"] * len(m["shift_err_m"]) for m in all_m if "shift_err_m" in m]
        out |= {
            "shift_steps": len(err),
            "shift_err_median_m": float(np.median(norm)),
            "shift_err_p90_m": float(np.quantile(norm, 0.9)),
            "shift_err_bias_m": [float(a) for a in err.mean(axis=0)],
            "shift_beams_mean": float(sum(beams) / len(err)),
        }
    return out


def summarise_filter(results: list[Seed004RunResult], name: str) -> FilterSummary:
    """A filter's summary over the runs that completed (the seabed shift's error and the
    diverged runs over all)."""
    ms = [r.metrics[name] for r in results if r.failed.get(name) is None and name in r.metrics]
    ms = [m for m in ms if "path_mean_m" in m]
    shift = _shift_summary(results, name)
    if not ms:
        return FilterSummary(
            **shift,
            runs_ok=0,
            path_mean_m=None,
            path_max_m=None,
            path_max_mean_m=None,
            est_rmse_m=None,
            est_max_m=None,
            j_bar_m2=None,
            j_mean_m2=None,
            residual_std_m=None,
            residual_mean_m=None,
            est_rmse_axis_m=None,
        )
    n = min(len(m["j_k"]) for m in ms)
    jk = np.mean([m["j_k"][:n] for m in ms], axis=0)
    jbar, jmean = float(np.max(jk)), float(np.mean(jk))
    return FilterSummary(
        **shift,
        runs_ok=len(ms),
        path_mean_m=_mean([m["path_mean_m"] for m in ms]),
        path_max_m=float(max(m["path_max_m"] for m in ms)),
        path_max_mean_m=_mean([m["path_max_m"] for m in ms]),
        est_rmse_m=float(np.sqrt(np.mean([m["est_rmse_m"] ** 2 for m in ms]))),
        est_max_m=float(max(m["est_max_m"] for m in ms)),
        est_rmse_axis_m=[
            float(a) for a in np.sqrt(np.mean([np.square(m["est_rmse_axis_m"]) for m in ms], 0))
        ],
        j_bar_m2=jbar,
        j_mean_m2=jmean,
        residual_std_m=[float(a) for a in np.mean([m["residual_std_m"] for m in ms], axis=0)],
        residual_mean_m=[float(a) for a in np.mean([m["residual_mean_m"] for m in ms], axis=0)],
    )


def surrogate_j(
    scn: Seed004Scenario, seed: int, gains: CmnfGains
) -> tuple[float | None, float | None, dict[str, Any]]:
    """The CMNF's J-bar (``max_k``) and time-mean J (``mean_k`` of ``E||X°_k - X_k||^2``) on
    fresh surrogate paths, m^2 (the definitions used on physics; ``None`` if a path diverged),
    and with the seabed prediction the surrogate's own shift error (``shift_err_median_m``,
    ``shift_err_p90_m`` to the histogram's 0.05 m bins, ``shift_err_bias_m``)."""

    from tasks.paper004.sim import SHIFT_BIN_M
    from tasks.paper004.sim import fly as fly_surrogate

    s = surrogate(scn)
    n = scn.seed004.surrogate_test_paths
    runs = tuple(range(SURROGATE_RUN_OFFSET, SURROGATE_RUN_OFFSET + n))
    sums = fly_surrogate(s, seed, runs, gains, filters=("CMNF",), sample_runs=0)
    shift: dict[str, Any] = {}
    if sums.shift_n[0] > 0:
        c = np.cumsum(sums.shift_hist[0]) / sums.shift_hist[0].sum()
        shift = {
            "shift_err_median_m": float((np.searchsorted(c, 0.5) + 0.5) * SHIFT_BIN_M),
            "shift_err_p90_m": float((np.searchsorted(c, 0.9) + 0.5) * SHIFT_BIN_M),
            "shift_err_bias_m": [float(v) for v in sums.shift_err[0] / sums.shift_n[0]],
        }
    ok = sums.count[0] > 0
    if not ok.all():
        return None, None, shift
    j = sums.j[0] / sums.count[0]
    return float(np.max(j)), float(np.mean(j)), shift
