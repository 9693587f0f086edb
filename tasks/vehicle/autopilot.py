"""``vehicle/autopilot``: step responses of the autopilot on the physical BAUV.

Four open-water trials on ``models/bauv`` in a deep scene (seabed at 40 m), each flown by
:class:`bauv_sim.autopilot.Autopilot` at its control tick from the vehicle's own measurements
(attitude, rates, depth and speed through water taken noise-free here, to characterise the loops
rather than the sensors):

* **heading**: a 90 deg course step at 1 m/s and 10 m depth;
* **depth**: a 5 m depth step (10 -> 15 m) at 1 m/s;
* **speed**: a 0.6 -> 1.0 m/s speed step;
* **current**: holding course 090 while crossing a 0.3 m/s current setting north.

Overshoot and settling time are computed on the tail-beat average of the response (a fish-like
body yaws about +-7 deg and surges at every stroke; the loops see the same average), settling
into +-2 deg, +-0.1 m and +-0.02 m/s of the new set-point.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, Field

from bauv_sim.autopilot import Autopilot, AutopilotConfig, Measured
from bauv_sim.config import Config
from bauv_sim.frames import navigation_rates_from_body, unit_vector_scalar, wrap_pi
from tasks.core.registry import Experiment, ReportContext, ReportSummary, register


class AutopilotTrialsScenario(Config):
    """Trials and gains."""

    autopilot: AutopilotConfig = Field(default_factory=AutopilotConfig)
    control_tick_s: float = Field(0.2, gt=0, description="s, a multiple of the physics timestep")
    physics_timestep_s: float = Field(
        0.002,
        gt=0,
        le=0.004,
        description="MuJoCo timestep, s (presets validated against 1 ms in models/bauv/README.md)",
    )
    depth_m: float = Field(10.0, gt=0, description="trial depth, m")
    seabed_depth_m: float = Field(40.0, gt=0, description="depth of the trial area, m")
    heading_step_deg: float = Field(90.0, gt=0, le=180)
    depth_step_m: float = Field(5.0, gt=0)
    speed_from_m_s: float = Field(0.6, gt=0)
    speed_to_m_s: float = Field(1.0, gt=0)
    current_speed_m_s: float = Field(0.3, ge=0)
    heading_band_deg: float = Field(2.0, gt=0, description="settling band, deg")
    depth_band_m: float = Field(0.1, gt=0, description="settling band, m")
    speed_band_m_s: float = Field(0.02, gt=0, description="settling band, m/s")
    hold_limit_deg: float = Field(5.0, gt=0, description="heading-hold tolerance in current")


@dataclass
class Trace:
    """One trial's time series (tail-beat averaged where noted)."""

    t_s: NDArray[np.float64]
    value: NDArray[np.float64]  # heading (deg), depth (m) or speed (m/s), beat-averaged
    command: NDArray[np.float64]
    pitch_deg: NDArray[np.float64]
    tail_bias_deg: NDArray[np.float64]
    fin_deg: NDArray[np.float64]


def fly_trial(
    s: AutopilotTrialsScenario,
    duration_s: float,
    course: Callable[[float], float],
    depth: Callable[[float], float],
    speed: Callable[[float], float],
    current_north_m_s: float = 0.0,
    heading0_rad: float = 0.0,
) -> dict[str, NDArray]:
    """Fly one trial with the autopilot from noise-free measurements, in a deep scene.

    Args:
        s: the trials' scenario (gains, control tick, physics timestep, depth, seabed).
        duration_s: length of the trial, s.
        course: set course at time t, rad (clockwise from north).
        depth: set depth at time t, m.
        speed: set speed through water at time t, m/s.
        current_north_m_s: uniform current setting north, m/s.
        heading0_rad: initial heading, rad (clockwise from north).

    Returns:
        Per control tick, each shape (n,): ``t`` (s), ``heading`` (rad), ``depth`` (m),
        ``speed`` (m/s through water along the hull), ``pitch`` (rad), ``bias`` (tail bias
        command, rad), ``fin`` (port fin command, rad); sampled before each tick's step.
    """
    from bauv_sim.build import SceneConfig, VehicleSpec, build_physics
    from bauv_sim.currents import UniformCurrent
    from bauv_sim.design.speed_table import load_speed_table
    from bauv_sim.sea import Sea
    from bauv_sim.seabed import SeabedConfig

    scene = SceneConfig(
        vehicles=(VehicleSpec(depth_m=s.depth_m, heading_deg=math.degrees(heading0_rad)),),
        seabed=SeabedConfig(
            depth_at_origin_m=s.seabed_depth_m, min_depth_m=0.75 * s.seabed_depth_m
        ),
    )
    p = build_physics(scene, control_tick_s=s.control_tick_s, timestep_s=s.physics_timestep_s)
    p.set_pose(
        [0.0, 0.0, -s.depth_m],
        [0.0, 0.0, heading0_rad],
        [*unit_vector_scalar(heading0_rad), 0.0],
    )
    # placed at 1 m/s through the water; the sea carries it with the current (Sea.immerse)
    Sea(UniformCurrent(current_north_m_s, 0.0) if current_north_m_s else None).immerse(p)
    table = load_speed_table()
    ap = Autopilot(s.autopilot, lambda v: float(table.frequency_for(v)))
    lim = p.command_limits()
    rows = []
    tick = s.control_tick_s
    for _ in range(round(duration_s / tick)):
        t = p.time_s()
        tr = p.truth()
        r, pt, h = tr.roll_pitch_heading_rad
        roll_rate, pitch_rate, heading_rate = navigation_rates_from_body(
            tr.angular_velocity_body_rad_s
        )
        east, north = unit_vector_scalar(h)
        x_axis = np.array([math.cos(pt) * east, math.cos(pt) * north, math.sin(pt)])
        u = float(tr.velocity_through_water_world_m_s @ x_axis)
        c = ap.step(
            tick,
            course(t),
            depth(t),
            speed(t),
            Measured(h, heading_rate, tr.depth_m, pt, pitch_rate, r, roll_rate, u),
        )
        p.set_tail_beat_frequency_hz(float(np.clip(c.tail_beat_hz, *lim["tail_beat_frequency_hz"])))
        p.set_tail_bias_rad(float(np.clip(c.tail_bias_rad, *lim["tail_bias_rad"])))
        p.set_lateral_fins_rad(
            float(np.clip(c.fin_port_rad, *lim["fin_port_rad"])),
            float(np.clip(c.fin_starboard_rad, *lim["fin_starboard_rad"])),
        )
        p.set_battery_position_m(float(np.clip(c.battery_m, *lim["battery_position_m"])))
        rows.append((t, h, tr.depth_m, u, pt, c.tail_bias_rad, c.fin_port_rad))
        p.advance(tick)
    a = np.array(rows)
    return {
        "t": a[:, 0],
        "heading": a[:, 1],
        "depth": a[:, 2],
        "speed": a[:, 3],
        "pitch": a[:, 4],
        "bias": a[:, 5],
        "fin": a[:, 6],
    }


def beat_average(y: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Trailing moving average over ``n`` samples (the first samples average what exists)."""
    c = np.cumsum(np.insert(y, 0, 0.0))
    k = np.arange(1, len(y) + 1)
    lo = np.maximum(k - n, 0)
    return (c[k] - c[lo]) / (k - lo)


def step_metrics(
    t: NDArray[np.float64], y: NDArray[np.float64], y0: float, y1: float, band: float
) -> tuple[float, float]:
    """Overshoot (% of the step) and settling time (s after the step into +-band of y1).

    Args:
        t: times since the step, s.
        y: response (averaged).
        y0: value before the step.
        y1: set-point after the step.
        band: settling band.

    Returns:
        ``(overshoot_percent, settling_time_s)``; the settling time is ``inf`` if the response
        is outside the band at the end.
    """
    step = y1 - y0
    overshoot = max(0.0, float(np.max((y - y1) * np.sign(step)))) / abs(step) * 100.0
    outside = np.flatnonzero(np.abs(y - y1) > band)
    if outside.size == 0:
        return overshoot, 0.0
    last = outside[-1]
    return overshoot, float(t[last + 1]) if last + 1 < len(t) else math.inf


class TrialResult(BaseModel):
    """One step response."""

    name: str
    step: str
    overshoot_percent: float
    settling_time_s: float | None = Field(description="None if it never settled")
    band: str


class AutopilotMetrics(BaseModel):
    """``metrics.json`` of ``vehicle/autopilot``."""

    schema_version: Literal[1] = 1
    experiment: str
    trials: list[TrialResult]
    current_crossing_max_heading_error_deg: float = Field(
        description="max |tail-beat-averaged heading error| after 20 s in the current"
    )
    current_crossing_mean_heading_error_deg: float
    current_crossing_max_instantaneous_error_deg: float = Field(
        description="max |heading error| of the raw heading, tail-beat recoil included"
    )
    heading_held_within_limit: bool


@dataclass(frozen=True)
class AutopilotTrials(Experiment):
    """The autopilot's step responses (one run, no randomness)."""

    scenario_type = AutopilotTrialsScenario
    metrics_type = AutopilotMetrics

    def run_block(self, scenario: AutopilotTrialsScenario, seed: int, runs: tuple[int, ...]):
        s = scenario
        t_step = 10.0
        step_h = math.radians(s.heading_step_deg)
        return {
            "heading": fly_trial(
                s,
                80.0,
                lambda t: 0.0 if t < t_step else step_h,
                lambda t: s.depth_m,
                lambda t: s.speed_to_m_s,
            ),
            "depth": fly_trial(
                s,
                100.0,
                lambda t: 0.0,
                lambda t: s.depth_m if t < t_step else s.depth_m + s.depth_step_m,
                lambda t: s.speed_to_m_s,
            ),
            "speed": fly_trial(
                s,
                60.0,
                lambda t: 0.0,
                lambda t: s.depth_m,
                lambda t: s.speed_from_m_s if t < t_step else s.speed_to_m_s,
            ),
            "current": fly_trial(
                s,
                120.0,
                lambda t: math.pi / 2,
                lambda t: s.depth_m,
                lambda t: s.speed_to_m_s,
                current_north_m_s=s.current_speed_m_s,
                heading0_rad=math.pi / 2,
            ),
        }

    def report(self, ctx: ReportContext) -> ReportSummary:
        from tasks.core.report import Table, write_metrics, write_tables

        s: AutopilotTrialsScenario = ctx.scenario  # type: ignore[assignment]
        tr = next(iter(ctx.blocks))
        t_step = 10.0
        # one tail beat at the trials' speed (the speed table's frequency)
        f_beat = float(_speed_table().frequency_for(s.speed_to_m_s))
        n = max(1, round(1.0 / (f_beat * s.control_tick_s)))
        trials = [
            # (trial, response, before, set-point, band, unit)
            (
                "heading",
                np.degrees(np.unwrap(wrap_pi(tr["heading"]["heading"]))),
                0.0,
                s.heading_step_deg,
                s.heading_band_deg,
                "deg",
            ),
            (
                "depth",
                tr["depth"]["depth"],
                s.depth_m,
                s.depth_m + s.depth_step_m,
                s.depth_band_m,
                "m",
            ),
            (
                "speed",
                tr["speed"]["speed"],
                s.speed_from_m_s,
                s.speed_to_m_s,
                s.speed_band_m_s,
                "m/s",
            ),
        ]
        results = []
        for name, y, y0, y1, band, unit in trials:
            t = tr[name]["t"]
            after = t >= t_step
            o, st = step_metrics(t[after] - t_step, beat_average(y, n)[after], y0, y1, band)
            results.append(
                TrialResult(
                    name=name,
                    step=f"{y0:g} -> {y1:g} {unit}",
                    overshoot_percent=o,
                    band=f"+-{band:g} {unit}",
                    settling_time_s=None if math.isinf(st) else st,
                )
            )
        c = tr["current"]
        raw = np.degrees(wrap_pi(c["heading"] - math.pi / 2))
        err = beat_average(raw, n)
        late = c["t"] > 20.0
        max_err = float(np.max(np.abs(err[late])))
        max_raw = float(np.max(np.abs(raw[late])))
        metrics = AutopilotMetrics(
            experiment=self.name,
            trials=results,
            current_crossing_max_heading_error_deg=max_err,
            current_crossing_mean_heading_error_deg=float(np.mean(err[late])),
            current_crossing_max_instantaneous_error_deg=max_raw,
            heading_held_within_limit=max_err <= s.hold_limit_deg,
        )
        files = [write_metrics(ctx.out_dir, metrics)]
        tables = [
            Table(
                "Autopilot step responses (tail-beat averaged)",
                ["Loop", "Step", "Overshoot (%)", "Settling time (s)", "Band"],
                [[r.name, r.step, r.overshoot_percent, r.settling_time_s, r.band] for r in results],
                slug="steps",
            ),
            Table(
                f"Heading hold across a {s.current_speed_m_s:g} m/s current (course 090, "
                "current setting 000)",
                [
                    "Max |heading error| after 20 s (deg)",
                    "Mean (deg)",
                    f"Within +-{s.hold_limit_deg:g} deg",
                    "Max instantaneous (deg)",
                ],
                [
                    [
                        max_err,
                        metrics.current_crossing_mean_heading_error_deg,
                        "yes" if metrics.heading_held_within_limit else "NO",
                        max_raw,
                    ]
                ],
                digits=2,
                slug="current-hold",
                note="The heading error is the tail-beat average; the instantaneous head yaw "
                "swings with every stroke (recoil of the fish-like propulsion).",
            ),
        ]
        files += write_tables(ctx.out_dir, tables, heading=f"{self.name}: {self.summary}")
        files += _figure(ctx.out_dir, tr, s, n)
        text = "".join(t.to_text() + "\n" for t in tables)
        return ReportSummary(text + f"wrote {len(files)} files to {ctx.out_dir}\n", tuple(files))


def _figure(out, tr, s: AutopilotTrialsScenario, n: int) -> list[str]:
    """The four trials (PNG and PDF, project style)."""
    from tasks.core import style

    with style.context():
        return _draw(out, tr, s, n, style)


def _draw(out, tr, s: AutopilotTrialsScenario, n: int, style) -> list[str]:
    fig, axs = style.subplots("page", 4.6, 2, 2)
    h = tr["heading"]
    axs[0, 0].plot(
        h["t"], np.degrees(np.unwrap(wrap_pi(h["heading"]))), color="0.7", lw=0.5, label="heading"
    )
    axs[0, 0].plot(
        h["t"],
        beat_average(np.degrees(np.unwrap(wrap_pi(h["heading"]))), n),
        "k",
        label="tail-beat average",
    )
    axs[0, 0].axhline(s.heading_step_deg, ls="--", color=style.color("command"), label="set-point")
    axs[0, 0].set_ylabel("heading (deg)")
    d = tr["depth"]
    axs[0, 1].plot(d["t"], d["depth"], color="0.7", lw=0.5)
    axs[0, 1].plot(d["t"], beat_average(d["depth"], n), "k")
    axs[0, 1].axhline(s.depth_m + s.depth_step_m, ls="--", color=style.color("command"))
    axs[0, 1].invert_yaxis()
    axs[0, 1].set_ylabel("depth (m)")
    v = tr["speed"]
    axs[1, 0].plot(v["t"], v["speed"], color="0.7", lw=0.5)
    axs[1, 0].plot(v["t"], beat_average(v["speed"], n), "k")
    axs[1, 0].axhline(s.speed_to_m_s, ls="--", color=style.color("command"))
    axs[1, 0].set_ylabel("speed through water (m/s)")
    c = tr["current"]
    e = np.degrees(wrap_pi(c["heading"] - math.pi / 2))
    axs[1, 1].plot(c["t"], e, color="0.7", lw=0.5)
    axs[1, 1].plot(c["t"], beat_average(e, n), "k")
    axs[1, 1].axhspan(
        -s.hold_limit_deg,
        s.hold_limit_deg,
        color=style.PALETTE["bluish_green"],
        alpha=0.15,
        label=f"$\\pm${s.hold_limit_deg:g}° limit",
    )
    axs[1, 1].set_ylabel(style.label("heading error", "deg"))
    titles = [
        f"heading step to {s.heading_step_deg:g}°",
        f"depth step of {s.depth_step_m:g} m",
        f"speed step to {s.speed_to_m_s:g} m/s",
        f"heading hold in a {s.current_speed_m_s:g} m/s cross current",
    ]
    for ax, text in zip(axs.ravel(), titles, strict=True):
        ax.set_xlabel(style.label("time", "s"))
        style.title(ax, text)
    axs[0, 0].legend(loc="lower right")
    axs[1, 1].legend(loc="lower right")
    style.panel_letters(axs)
    fig.suptitle("Autopilot step responses of the vehicle (grey: per tick; black: tail-beat mean)")
    return style.save(fig, out / "steps.png")


register(
    AutopilotTrials(
        name="vehicle/autopilot",
        summary="autopilot step responses (heading 90 deg, depth 5 m, speed) and current crossing",
        default_runs=1,
        max_runs=1,
    )
)


def _speed_table():
    from bauv_sim.design.speed_table import load_speed_table

    return load_speed_table()
