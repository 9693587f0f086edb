"""Seed 000 sections 2-3: analytic accuracy of USBL fixes and dead reckoning (Figures 3-6).

Registers ``paper-000/accuracy``: no simulation, only the propagation of the devices' mean errors
(:mod:`nav.usbl.accuracy`):

* Figure 3: map of the USBL mean error M_xy around the transceiver (eq. 5), 26.2 m at 500 m;
* Figure 4: USBL mean error ellipse semi-axes against distance (eq. 6-7);
* Figure 5: DR mean error against distance travelled, in the paper's single-step form (eq. 10-11
  with dt = t: 25.54 m per 100 m) beside the random walk of independent 1 s steps (sqrt growth);
* Figure 6: DR mean error ellipses after 200 m and 500 m (eq. 12-14).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field

from bauv_sim.config import Config
from bauv_sim.frames import unit_vector_scalar
from nav.usbl import accuracy as acc
from tasks.core import style
from tasks.core.registry import Experiment, ReportContext, ReportSummary, register
from tasks.core.report import Table, write_metrics, write_tables


class AccuracyScenario(Config):
    """Device errors and geometry of seed 000's analytic figures."""

    sigma_range_m: float = Field(0.2, gt=0, description="USBL range sigma, m (MicronNav)")
    sigma_azimuth_deg: float = Field(3.0, gt=0, description="USBL azimuth sigma, deg")
    usbl_max_range_m: float = Field(500.0, gt=0, description="USBL working range, m")
    map_step_m: float = Field(5.0, gt=0, description="grid step of the accuracy map, m")
    sigma_course_deg: float = Field(3.0, gt=0, description="INS COG sigma, deg (section 3)")
    sigma_speed_m_s: float = Field(
        0.25, gt=0, description="log SOG sigma, m/s (0.5 kn rounded as in Figure 5)"
    )
    speed_m_s: float = Field(1.0, gt=0, description="SOG of Figure 5, m/s")
    course_deg: float = Field(90.0, ge=0, lt=360, description="COG of Figure 5, deg")
    distance_max_m: float = Field(500.0, gt=0, description="end of Figure 5, m")
    ellipse_distances_m: tuple[float, ...] = Field((200.0, 500.0), description="Figure 6, m")


class EllipseOut(BaseModel):
    """An error ellipse: semi-axes (m) and major-axis direction (deg from the x/east axis)."""

    distance_m: float
    a_m: float
    b_m: float
    tau_deg: float


class AccuracyMetrics(BaseModel):
    """``metrics.json`` of ``paper-000/accuracy``."""

    schema_version: Literal[1] = 1
    experiment: str
    usbl_mean_error_at_max_range_m: float = Field(description="eq. 5 at the working range")
    usbl_mean_error_by_distance_m: dict[str, float]
    dr_single_step_per_100m_m: float = Field(description="Figure 5 slope (eq. 10-11, dt = t)")
    dr_single_step_by_distance_m: dict[str, float]
    dr_random_walk_by_distance_m: dict[str, float]
    dr_ellipses_single_step: list[EllipseOut]
    dr_ellipses_random_walk: list[EllipseOut]


def _ellipse_out(distance: float, P: np.ndarray) -> EllipseOut:
    e = acc.ellipse_parameters(P)
    return EllipseOut(
        distance_m=distance, a_m=float(e.a), b_m=float(e.b), tau_deg=float(np.degrees(e.tau))
    )


@dataclass(frozen=True)
class AccuracyExperiment(Experiment):
    """The analytic figures of seed 000 (one run, no randomness)."""

    scenario_type = AccuracyScenario
    metrics_type = AccuracyMetrics

    def run_block(self, scenario: AccuracyScenario, seed: int, runs: tuple[int, ...]) -> None:
        return None

    def report(self, ctx: ReportContext) -> ReportSummary:
        for _ in ctx.blocks:  # nothing was simulated
            pass
        s: AccuracyScenario = ctx.scenario  # type: ignore[assignment]
        out = ctx.out_dir
        sa, sr = math.radians(s.sigma_azimuth_deg), s.sigma_range_m
        sc, ss = math.radians(s.sigma_course_deg), s.sigma_speed_m_s
        c, v = math.radians(s.course_deg), s.speed_m_s
        dists = np.arange(100.0, s.usbl_max_range_m + 1, 100.0)
        m_usbl = acc.usbl_mean_error(dists, sr, sa)
        a_usbl, b_usbl = acc.usbl_ellipse(dists, sr, sa)
        d_dr = np.arange(100.0, s.distance_max_m + 1, 100.0)
        P_one = acc.dr_covariance_single_step(d_dr / v, c, v, sc, ss)
        P_rw = acc.dr_covariance_random_walk(d_dr / v, c, v, sc, ss)
        m_one, m_rw = acc.mean_error(P_one), acc.mean_error(P_rw)
        ell_one = [
            _ellipse_out(d, acc.dr_covariance_single_step(d / v, c, v, sc, ss))
            for d in s.ellipse_distances_m
        ]
        ell_rw = [
            _ellipse_out(d, acc.dr_covariance_random_walk(d / v, c, v, sc, ss))
            for d in s.ellipse_distances_m
        ]
        per100 = float(acc.mean_error(acc.dr_covariance_single_step(100.0 / v, c, v, sc, ss)))
        metrics = AccuracyMetrics(
            experiment=self.name,
            usbl_mean_error_at_max_range_m=float(acc.usbl_mean_error(s.usbl_max_range_m, sr, sa)),
            usbl_mean_error_by_distance_m={
                f"{d:g}": float(m) for d, m in zip(dists, m_usbl, strict=True)
            },
            dr_single_step_per_100m_m=per100,
            dr_single_step_by_distance_m={
                f"{d:g}": float(m) for d, m in zip(d_dr, m_one, strict=True)
            },
            dr_random_walk_by_distance_m={
                f"{d:g}": float(m) for d, m in zip(d_dr, m_rw, strict=True)
            },
            dr_ellipses_single_step=ell_one,
            dr_ellipses_random_walk=ell_rw,
        )
        files = [write_metrics(out, metrics)]
        tables = [
            Table(
                "USBL mean error and ellipse against distance (eq. 5-7; paper: 26.2 m at 500 m)",
                ["Distance (m)", "M_xy (m)", "a (m)", "b (m)"],
                [[d, m, a, b] for d, m, a, b in zip(dists, m_usbl, a_usbl, b_usbl, strict=True)],
                digits=2,
                slug="usbl-accuracy",
            ),
            Table(
                "DR mean error against distance (eq. 10-11; paper: 25.54 m per 100 m)",
                ["Distance (m)", "Single step, dt = t (m)", "Random walk of 1 s steps (m)"],
                [[d, a, b] for d, a, b in zip(d_dr, m_one, m_rw, strict=True)],
                digits=2,
                slug="dr-accuracy",
                note="Single step: the paper's Figure 5 reading (linear growth). Random walk: "
                "independent per-second errors (growth with sqrt(t)).",
            ),
            Table(
                "DR mean error ellipses (eq. 12-14)",
                ["Form", "Distance (m)", "a (m)", "b (m)", "tau (deg from east)"],
                [["single step", e.distance_m, e.a_m, e.b_m, e.tau_deg] for e in ell_one]
                + [["random walk", e.distance_m, e.a_m, e.b_m, e.tau_deg] for e in ell_rw],
                digits=2,
                slug="dr-ellipses",
            ),
        ]
        files += write_tables(out, tables, heading=f"{self.name}: {self.summary}")
        files += _figures(out, s)
        text = "".join(t.to_text() + "\n" for t in tables)
        return ReportSummary(text + f"wrote {len(files)} files to {out}\n", tuple(files))


@style.styled
def _figures(out, s: AccuracyScenario) -> list[str]:
    """Seed 000 Figures 3-6 (PNG and PDF, project style)."""
    from matplotlib.patches import Ellipse as EllipsePatch

    sa, sr = math.radians(s.sigma_azimuth_deg), s.sigma_range_m
    sc, ss = math.radians(s.sigma_course_deg), s.sigma_speed_m_s
    c, v = math.radians(s.course_deg), s.speed_m_s
    R = s.usbl_max_range_m
    usbl_sig = f"$\\sigma_r$ = {sr:g} m, $\\sigma_\\alpha$ = {s.sigma_azimuth_deg:g}°"
    dr_sig = f"$\\sigma_{{COG}}$ = {s.sigma_course_deg:g}°, $\\sigma_{{SOG}}$ = {ss:g} m/s"
    files: list[str] = []

    # Figure 3: accuracy map
    g = np.arange(-R, R + s.map_step_m / 2, s.map_step_m)
    X, Y = np.meshgrid(g, g)
    r = np.hypot(X, Y)
    M = np.where(r <= R, acc.usbl_mean_error(r, sr, sa), np.nan)
    fig, ax = style.subplots("column", 3.0)
    im = ax.pcolormesh(X, Y, M, shading="auto", cmap="viridis", rasterized=True)
    cs = ax.contour(X, Y, M, levels=np.arange(5, 30, 5), colors="white", linewidths=0.6)
    ax.clabel(cs, fmt="%g m", fontsize=6)
    ax.plot(0, 0, "^", color="white", mec="k", ms=6, label="transceiver")
    fig.colorbar(im, ax=ax, label=style.label("mean error $M_{xy}$", "m"), shrink=0.9)
    ax.set_aspect("equal")
    ax.grid(False)
    ax.set_xlabel(style.label("east", "m"))
    ax.set_ylabel(style.label("north", "m"))
    style.title(ax, f"USBL accuracy ({usbl_sig})")
    ax.legend(loc="upper right")
    files += style.save(fig, out / "fig3-usbl-accuracy-map.png")

    # Figure 4: ellipse parameters against distance (log axis: b is 100 times smaller than a),
    # and the ellipses drawn to scale around the transceiver along eight bearings
    d = np.arange(100.0, R + 1, 100.0)
    a, b = acc.usbl_ellipse(d, sr, sa)
    fig, (ax1, ax2) = style.subplots("page", 3.3, 1, 2, width_ratios=[1.0, 1.0])
    ax1.plot(d, a, "o-", color=style.PALETTE["blue"], label="a (across the line of sight)")
    ax1.plot(d, b, "s-", color=style.PALETTE["vermillion"], label="b (along the line of sight)")
    ax1.set_yscale("log")
    style.log_ticks(ax1)
    ax1.set_xlabel(style.label("distance to the transceiver", "m"))
    ax1.set_ylabel(style.label("semi-axis", "m"))
    ax1.legend(loc="center right")
    style.title(ax1, f"USBL mean error ellipse ({usbl_sig})")
    for az in np.radians(np.arange(0.0, 360.0, 45.0)):
        ux, uy = unit_vector_scalar(float(az))
        for di, ai, bi in zip(d, a, b, strict=True):
            ax2.add_patch(
                EllipsePatch(
                    (di * ux, di * uy),
                    2 * bi,
                    2 * ai,
                    angle=90.0 - math.degrees(float(az)),
                    fill=False,
                    color=style.PALETTE["blue"],
                    lw=0.8,
                )
            )
    ring = np.linspace(0, 2 * np.pi, 200)
    for di in d:
        ax2.plot(di * np.cos(ring), di * np.sin(ring), color="0.85", lw=0.4, zorder=0)
    ax2.plot(0, 0, "k^", ms=6)
    ax2.set_xlim(-R * 1.08, R * 1.08)
    ax2.set_ylim(-R * 1.08, R * 1.08)
    ax2.set_aspect("equal")
    ax2.set_xlabel(style.label("east", "m"))
    ax2.set_ylabel(style.label("north", "m"))
    style.title(ax2, "the ellipses to scale, every 100 m, 8 bearings")
    style.panel_letters((ax1, ax2))
    files += style.save(fig, out / "fig4-usbl-ellipses.png")

    # Figure 5: DR mean error against distance
    dist = np.linspace(0, s.distance_max_m, 201)
    t = dist / v
    m1 = acc.mean_error(acc.dr_covariance_single_step(t, c, v, sc, ss))
    m2 = acc.mean_error(acc.dr_covariance_random_walk(t, c, v, sc, ss))
    fig, ax = style.subplots("column", 2.4)
    ax.plot(dist, m1, color=style.PALETTE["vermillion"], label="single step dt = t (paper)")
    ax.plot(dist, m2, color=style.PALETTE["blue"], ls="--", label="random walk of 1 s steps")
    ax.set_xlabel(style.label("distance travelled", "m"))
    ax.set_ylabel(style.label("mean error $M_{xy}$", "m"))
    ax.legend(loc="upper left")
    style.title(ax, f"DR accuracy ({dr_sig})")
    files += style.save(fig, out / "fig5-dr-accuracy.png")

    # Figure 6: DR ellipses after the chosen distances, one panel per form, each as tall as its
    # data (equal scales), with the values written beside each ellipse
    forms = [
        ("single step", acc.dr_covariance_single_step, 1.0),
        ("random walk", acc.dr_covariance_random_walk, 10.0),
    ]
    u = np.array(unit_vector_scalar(c))
    panels = []
    for form, fn, scale in forms:
        ells = [
            (dd, acc.ellipse_parameters(fn(dd / v, c, v, sc, ss))) for dd in s.ellipse_distances_m
        ]
        ends = np.array([[0.0, 0.0], max(s.ellipse_distances_m) * u])
        lo, hi = ends.min(axis=0), ends.max(axis=0)
        for dd, e in ells:
            A, B, tau = scale * float(e.a), scale * float(e.b), float(e.tau)
            half = np.array(
                [
                    math.hypot(A * math.cos(tau), B * math.sin(tau)),
                    math.hypot(A * math.sin(tau), B * math.cos(tau)),
                ]
            )
            lo = np.minimum(lo, dd * u - half)
            hi = np.maximum(hi, dd * u + half)
        span = hi - lo
        lo, hi = lo - 0.04 * span.max(), hi + np.array([0.04, 0.1]) * span.max()
        panels.append((form, scale, ells, ends, lo, hi))
    ratios = [float((hi[1] - lo[1]) / (hi[0] - lo[0])) for *_, lo, hi in panels]
    width = style.PAGE_IN
    height = min(9.0, 0.9 * width * sum(ratios) + 0.75 * len(panels))
    fig, axes = style.subplots("page", height, len(panels), 1, height_ratios=ratios)
    for ax, (form, scale, ells, ends, lo, hi) in zip(np.ravel(axes), panels, strict=True):
        for dd, e in ells:
            cx, cy = dd * u
            ax.add_patch(
                EllipsePatch(
                    (cx, cy),
                    2 * scale * float(e.a),
                    2 * scale * float(e.b),
                    angle=float(np.degrees(e.tau)),
                    fill=False,
                    color=style.color("DR"),
                    lw=1.0,
                )
            )
            ax.plot(cx, cy, "k.", ms=3)
            ax.annotate(
                f"after {dd:g} m:\na = {float(e.a):.1f} m, b = {float(e.b):.1f} m",
                (
                    cx,
                    cy
                    + math.hypot(
                        scale * float(e.a) * math.sin(float(e.tau)),
                        scale * float(e.b) * math.cos(float(e.tau)),
                    ),
                ),
                textcoords="offset points",
                xytext=(0, 2),
                ha="center",
                va="bottom",
                fontsize=6.5,
            )
        ax.plot(ends[:, 0], ends[:, 1], "k--", lw=0.6)
        ax.plot(0, 0, "ko", ms=3)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(style.label("east", "m"))
        ax.set_ylabel(style.label("north", "m"))
        drawn = "" if scale == 1.0 else f", ellipses drawn {scale:g}x"
        style.title(ax, f"DR mean error ellipses: {form}{drawn} ({dr_sig})")
    style.panel_letters(axes)
    files += style.save(fig, out / "fig6-dr-ellipses.png")
    return files


register(
    AccuracyExperiment(
        name="paper-000/accuracy",
        summary="seed 000 sections 2-3: analytic USBL and DR accuracy (Figures 3-6)",
        default_runs=1,
        max_runs=1,
    )
)
