"""The validation manoeuvres of the full model (:mod:`bauv_sim.manoeuvres`, the timestep table's
autopilot depth step) flown on the manoeuvring model, with the same definitions, so that
``models/bauv/tools/manoeuvring_id.py`` compares like with like.

Every trial starts as :func:`bauv_sim.manoeuvres.open_water_scene` does: 20 m deep, heading
north, 1 m/s through still water, and holds depth with the same fixed law as
:class:`bauv_sim.manoeuvres.DepthHold` where the full trial does.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bauv_sim.autopilot import Autopilot, AutopilotConfig, Measured
from bauv_sim.frames import navigation_rates_from_body
from bauv_sim.manoeuvring.model import ManoeuvringCoefficients, ManoeuvringWorld

OPEN_WATER_TICK_S = 0.1
"""Control tick of the open-loop trials, s (the facade's default, as the full trials)."""

BIAS_LIMIT_RAD = math.asin(0.016 / 0.045)
"""The tail-bias carriage's limit (+-16 mm on a 45 mm lever), rad."""

FIN_LIMIT_RAD = 0.5
"""The lateral fins' range, rad."""

BATTERY_LIMIT_M = 0.08
"""The battery slide's range, m."""

FREQUENCY_LIMIT_HZ = 3.0
"""The motor's range as tail-beat frequency, Hz."""


def start(
    coef: ManoeuvringCoefficients,
    n: int = 1,
    tick_s: float = OPEN_WATER_TICK_S,
    depth_m: float = 20.0,
    speed_m_s: float = 1.0,
) -> ManoeuvringWorld:
    """``n`` vehicles heading north at ``depth_m`` (m), ``speed_m_s`` (m/s) through the water."""
    w = ManoeuvringWorld(n, coef, tick_s=tick_s)
    w.set_pose(np.array([0.0, 0.0, -depth_m]), np.zeros(3), np.array([speed_m_s, 0.0, 0.0]))
    return w


def depth_hold(w: ManoeuvringWorld, target_depth_m: float) -> NDArray[np.float64]:
    """The fin angle of :class:`bauv_sim.manoeuvres.DepthHold` (default gains), rad, shape (n,)."""
    e = w.depth_m() - target_depth_m
    pitch = w.roll_pitch_heading()[:, 1]
    w_up = w.velocity_world()[:, 2]
    return np.clip(0.25 * e - 1.0 * pitch - 1.0 * w_up, -0.35, 0.35)


def _fly(w: ManoeuvringWorld, seconds: float, target_depth_m: float | None, log=None) -> None:
    for _ in range(round(seconds / w.tick_s)):
        if target_depth_m is not None:
            a = depth_hold(w, target_depth_m)
            w.command(fin_port_rad=a, fin_starboard_rad=a)
        w.step()
        if log is not None:
            log.append(
                (w.time_s, w.position_world_m.copy(), w.roll_pitch_heading()[:, 2].copy(),
                 w.depth_m().copy(), w.velocity_world().copy())
            )  # fmt: skip


def straight_swim(
    coef: ManoeuvringCoefficients, frequency_hz: float, settle_s: float = 30.0,
    measure_s: float = 20.0,
) -> tuple[float, float]:  # fmt: skip
    """Speed through water (m/s) and motor power (W) of a steady straight swim, depth held."""
    w = start(coef)
    w.command(tail_beat_frequency_hz=frequency_hz)
    _fly(w, settle_s, 20.0)
    p0, t0 = w.position_world_m.copy(), w.time_s
    _fly(w, measure_s, 20.0)
    v = (w.position_world_m - p0) / (w.time_s - t0) - w.current_world_m_s
    return float(np.linalg.norm(v[0])), float(w.motor_power_w()[0])


def _fit_circle_radius(xy: NDArray[np.float64]) -> float:
    A = np.c_[2.0 * xy, np.ones(len(xy))]
    b = (xy**2).sum(axis=1)
    c, *_ = np.linalg.lstsq(A, b, rcond=None)
    return float(np.sqrt(c[2] + c[0] ** 2 + c[1] ** 2))


def heading_change(
    coef: ManoeuvringCoefficients, frequency_hz: float, bias_rad: float,
    approach_s: float = 30.0, turn_s: float = 60.0,
) -> tuple[float, float]:  # fmt: skip
    """Turn rate (rad/s, clockwise +) and radius (m) as
    :func:`bauv_sim.manoeuvres.heading_change`: the second half of the turn."""
    w = start(coef)
    w.command(tail_beat_frequency_hz=frequency_hz)
    _fly(w, approach_s, 20.0)
    h0 = float(w.roll_pitch_heading()[0, 2])
    w.command(tail_bias_rad=bias_rad)
    log: list = []
    _fly(w, turn_s, 20.0, log)
    t = np.array([r[0] for r in log])
    pos = np.array([r[1][0] for r in log])
    head = np.unwrap(np.r_[h0, [r[2][0] for r in log]])[1:]
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    rate = float(np.polyfit(t[half], head[half], 1)[0])
    return rate, _fit_circle_radius(pos[half, :2])


def fin_step(
    coef: ManoeuvringCoefficients, frequency_hz: float, fin_rad: float,
    approach_s: float = 30.0, step_s: float = 20.0,
) -> float:  # fmt: skip
    """Depth rate (m/s, diving +) over the second half of an open-loop fin step, as
    :func:`bauv_sim.manoeuvres.depth_change`."""
    w = start(coef)
    w.command(tail_beat_frequency_hz=frequency_hz, fin_port_rad=0.0, fin_starboard_rad=0.0)
    _fly(w, approach_s, None)
    w.command(fin_port_rad=fin_rad, fin_starboard_rad=fin_rad)
    log: list = []
    _fly(w, step_s, None, log)
    t = np.array([r[0] for r in log])
    z = np.array([r[3][0] for r in log])
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    return float(np.polyfit(t[half], z[half], 1)[0])


def autopilot_depth_step(
    coef: ManoeuvringCoefficients,
    config: AutopilotConfig,
    tick_s: float,
    depth_m: float,
    step_m: float,
    speed_m_s: float,
    duration_s: float = 80.0,
    t_step_s: float = 10.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The autopilot's depth step (``tasks.vehicle.autopilot.fly_trial``'s, course north, speed
    held) from noise-free truth: times (s) and depths (m) sampled before each tick's step."""
    from bauv_sim.design.speed_table import load_speed_table

    w = start(coef, tick_s=tick_s, depth_m=depth_m)
    table = load_speed_table()
    ap = Autopilot(config, lambda v: float(table.frequency_for(v)))
    ts, ds = [], []
    for _ in range(round(duration_s / tick_s)):
        t = w.time_s
        r, pt, h = w.roll_pitch_heading()[0]
        roll_rate, pitch_rate, heading_rate = navigation_rates_from_body(
            w.angular_velocity_body()[0]
        )
        v = w.velocity_through_water_world()[0]
        x_axis = np.array([math.cos(pt) * math.sin(h), math.cos(pt) * math.cos(h), math.sin(pt)])
        u = float(v @ x_axis)
        d = float(w.depth_m()[0])
        target = depth_m if t < t_step_s else depth_m + step_m
        c = ap.step(
            tick_s, 0.0, target, speed_m_s,
            Measured(h, heading_rate, d, pt, pitch_rate, r, roll_rate, u),
        )  # fmt: skip
        w.command(
            tail_beat_frequency_hz=float(np.clip(c.tail_beat_hz, 0.0, FREQUENCY_LIMIT_HZ)),
            tail_bias_rad=float(np.clip(c.tail_bias_rad, -BIAS_LIMIT_RAD, BIAS_LIMIT_RAD)),
            fin_port_rad=float(np.clip(c.fin_port_rad, -FIN_LIMIT_RAD, FIN_LIMIT_RAD)),
            fin_starboard_rad=float(np.clip(c.fin_starboard_rad, -FIN_LIMIT_RAD, FIN_LIMIT_RAD)),
            battery_m=float(np.clip(c.battery_m, -BATTERY_LIMIT_M, BATTERY_LIMIT_M)),
        )
        ts.append(t)
        ds.append(d)
        w.step()
    return np.array(ts), np.array(ds)


def current_step(
    coef: ManoeuvringCoefficients, frequency_hz: float, along: bool
) -> tuple[float, float]:
    """Cruise north with depth held; after 30 s a 0.3 m/s current along (north) or across (east);
    what the current changed in the mean ground velocity along (north) and across (east) the
    track over 40-60 s (against the same swim in still water, run beside it), m/s."""
    w = start(coef, n=2)
    w.command(tail_beat_frequency_hz=frequency_hz)
    _fly(w, 30.0, 20.0)
    c = np.array([0.0, 0.3, 0.0]) if along else np.array([0.3, 0.0, 0.0])
    w.set_current_world(np.stack([np.zeros(3), c]))
    _fly(w, 10.0, 20.0)
    p0, t0 = w.position_world_m.copy(), w.time_s
    _fly(w, 20.0, 20.0)
    v = (w.position_world_m - p0) / (w.time_s - t0)
    d = v[1] - v[0]
    return float(d[1]), float(d[0])
