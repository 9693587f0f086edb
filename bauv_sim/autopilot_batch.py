"""The autopilot of :mod:`bauv_sim.autopilot` over a batch of vehicles at once (issue 27).

:class:`BatchAutopilot` runs the same loops, limits, anti-windup, tail-beat averaging and trim
integrator as :class:`~bauv_sim.autopilot.Autopilot`, on arrays with a leading axis of runs
(shape (n,)), so that a Monte Carlo batch of vehicles on the manoeuvring model
(:class:`bauv_sim.manoeuvring.ManoeuvringWorld`) is steered in a few dozen array operations per
tick whatever n. Each run's numbers are those of a scalar :class:`Autopilot` fed the same
measurements, to rounding (the sums of the moving averages are taken in the scalar's order,
newest first; tested run by run to 1e-12 in ``tests/bauv_sim/test_autopilot_batch.py``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim.autopilot import AutopilotConfig

Array = NDArray[np.float64]


@dataclass
class BatchPID:
    """:class:`bauv_sim.autopilot.PID` over n runs (same gains for all; integral per run).

    Attributes:
        kp, ki, kd, u_min, u_max, i_limit, i_zone: as :class:`~bauv_sim.autopilot.PID`.
        integral: the integral term of each run, shape (n,), output units.
    """

    kp: float
    ki: float
    kd: float
    u_min: float
    u_max: float
    i_limit: float
    i_zone: float
    integral: Array

    def step(
        self, error: Array, rate: Array, dt_s: float, feedforward: Array | float = 0.0
    ) -> Array:
        """One update of every run (:meth:`bauv_sim.autopilot.PID.step`).

        Args:
            error: setpoint minus measurement, shape (n,).
            rate: measured rate of the controlled quantity, shape (n,).
            dt_s: time since the previous update, s.
            feedforward: added before saturation, shape (n,) or scalar.

        Returns:
            The saturated outputs, shape (n,).
        """
        u_unsat = feedforward + self.kp * error + self.integral - self.kd * rate
        if self.ki:
            sat_high = (u_unsat >= self.u_max) & (error > 0)
            sat_low = (u_unsat <= self.u_min) & (error < 0)
            go = (np.abs(error) <= self.i_zone) & ~(sat_high | sat_low)
            i = self.integral + self.ki * error * dt_s
            i = np.minimum(np.maximum(i, -self.i_limit), self.i_limit)
            self.integral = np.where(go, i, self.integral)
        u = feedforward + self.kp * error + self.integral - self.kd * rate
        return np.minimum(np.maximum(u, self.u_min), self.u_max)

    def reset(self, which: NDArray[np.bool_]) -> None:
        """Clear the integral of the runs where ``which`` (shape (n,)) is True."""
        self.integral = np.where(which, 0.0, self.integral)


@dataclass(frozen=True)
class BatchMeasured:
    """What the autopilots read (:class:`bauv_sim.autopilot.Measured`), each shape (n,): heading
    (rad clockwise from north), yaw rate (rad/s, clockwise +), depth (m), pitch (rad, nose up +),
    pitch rate (rad/s), roll (rad, starboard down +), roll rate (rad/s), speed through water
    (m/s)."""

    heading_rad: Array
    yaw_rate_rad_s: Array
    depth_m: Array
    pitch_rad: Array
    pitch_rate_rad_s: Array
    roll_rad: Array
    roll_rate_rad_s: Array
    speed_m_s: Array


@dataclass(frozen=True)
class BatchCommand:
    """Actuator settings of every run (:class:`bauv_sim.autopilot.ActuatorCommand`), each shape
    (n,): tail-beat frequency (Hz), tail bias (rad), port and starboard fins (rad), battery (m)."""

    tail_beat_hz: Array
    tail_bias_rad: Array
    fin_port_rad: Array
    fin_starboard_rad: Array
    battery_m: Array


class BatchBeatAverage:
    """:class:`bauv_sim.autopilot.BeatAverage` over n runs: the last ``max_samples`` rows of
    every run in a ring, each run's window from its own tail-beat frequency.

    Args:
        n: runs.
        speed_window_s: averaging window of the speed, s.
        depth_rate_window_s: baseline of the depth rate, s.
        max_samples: longest window, in control ticks.
    """

    COLUMNS = 8  # east and north of the heading, yaw rate, depth, pitch, pitch rate, roll, rate

    def __init__(
        self,
        n: int,
        speed_window_s: float = 4.0,
        depth_rate_window_s: float = 1.0,
        max_samples: int = 100,
    ):
        self.n = n
        self.speed_window_s = speed_window_s
        self.depth_rate_window_s = depth_rate_window_s
        self.max_samples = max_samples
        self._rows = np.zeros((max_samples, self.COLUMNS, n))
        self._speeds = np.zeros((max_samples, n))
        self._depths = np.zeros((max_samples, n))
        self._count = 0  # rows appended so far (all runs append together)
        self._dcount = 0

    def _window(self, ring: Array, count: int, length: NDArray[np.intp]) -> Array:
        """Sums of each run's newest ``length`` entries, newest first (the scalar's order)."""
        acc = np.zeros(ring.shape[1:])
        for age in range(int(length.max())):
            row = ring[(count - 1 - age) % self.max_samples]
            acc = acc + np.where(age < length, row, 0.0)
        return acc

    def __call__(
        self, m: BatchMeasured, frequency_hz: Array, dt_s: float
    ) -> tuple[BatchMeasured, Array]:
        """Filtered measurements, and the depth rate (m/s, positive going deeper), shape (n,)."""
        k = self._count % self.max_samples
        row = self._rows[k]
        row[0], row[1] = np.sin(m.heading_rad), np.cos(m.heading_rad)
        row[2], row[3], row[4] = m.yaw_rate_rad_s, m.depth_m, m.pitch_rad
        row[5], row[6], row[7] = m.pitch_rate_rad_s, m.roll_rad, m.roll_rate_rad_s
        self._speeds[k] = m.speed_m_s
        self._count += 1
        held = min(self._count, self.max_samples)
        safe_f = np.where(frequency_hz <= 0, 1.0, frequency_hz)
        nb = np.where(frequency_hz <= 0, 1, np.round(1.0 / (safe_f * dt_s))).astype(np.intp)
        nb = np.maximum(1, np.minimum(nb, held))
        a = self._window(self._rows, self._count, nb) / nb
        ns = max(1, min(round(self.speed_window_s / dt_s), held))
        speed = self._window(self._speeds, self._count, np.full(self.n, ns)) / ns
        self._depths[self._dcount % self.max_samples] = a[3]
        self._dcount += 1
        nd = min(round(self.depth_rate_window_s / dt_s), min(self._dcount, self.max_samples) - 1)
        if nd >= 1:
            old = self._depths[(self._dcount - 1 - nd) % self.max_samples]
            rate = (a[3] - old) / (nd * dt_s)
        else:
            rate = np.zeros(self.n)
        heading = np.arctan2(a[0], a[1]) % (2 * math.pi)
        heading = np.where(heading >= 2 * math.pi, 0.0, heading)
        out = BatchMeasured(heading, a[2], a[3], a[4], a[5], a[6], a[7], speed)
        return out, rate


class BatchAutopilot:
    """The three loops and the trim integrator of :class:`bauv_sim.autopilot.Autopilot` for n
    runs (module docstring).

    Args:
        cfg: gains and limits (the same for every run).
        n: runs.
        frequency_for_speed: feed-forward map desired speed (m/s, shape (n,)) -> tail-beat
            frequency (Hz, shape (n,)), vectorised.
        tail_bias_sign: +1 if a positive tail bias turns the vehicle to starboard, else -1.
        fin_sign: +1 if a positive symmetric fin angle pitches the nose up, else -1.
        battery0_m: initial battery position, m, scalar or shape (n,).
    """

    def __init__(
        self,
        cfg: AutopilotConfig,
        n: int,
        frequency_for_speed: Callable[[Array], Array],
        tail_bias_sign: float = 1.0,
        fin_sign: float = 1.0,
        battery0_m: Array | float = 0.0,
    ):
        self.cfg = cfg
        self.n = n
        self.frequency_for_speed = frequency_for_speed
        self.tail_bias_sign = float(tail_bias_sign)
        self.fin_sign = float(fin_sign)
        bias = math.radians(cfg.tail_bias_max_deg)
        fin = math.radians(cfg.fin_max_deg)
        pitch = math.radians(cfg.pitch_max_deg)
        z = np.zeros(n)
        inf = math.inf
        self.heading = BatchPID(
            cfg.heading_kp,
            cfg.heading_ki,
            cfg.heading_kd,
            -bias,
            bias,
            0.5 * bias,
            math.radians(cfg.heading_i_zone_deg),
            z.copy(),
        )
        self.depth = BatchPID(
            cfg.depth_kp, cfg.depth_ki, cfg.depth_kd, -pitch, pitch, 0.5 * pitch,
            cfg.depth_i_zone_m, z.copy(),
        )  # fmt: skip
        self.pitch = BatchPID(cfg.pitch_kp, 0.0, cfg.pitch_kd, -fin, fin, inf, inf, z.copy())
        self.roll = BatchPID(
            cfg.roll_kp, 0.0, cfg.roll_kd, -0.5 * fin, 0.5 * fin, inf, inf, z.copy()
        )
        self.speed = BatchPID(
            cfg.speed_kp, cfg.speed_ki, 0.0, 0.0, cfg.frequency_max_hz, 1.0, inf, z.copy()
        )
        self.battery_m = np.broadcast_to(np.asarray(battery0_m, dtype=float), (n,)).copy()
        self.desired_pitch_rad = z.copy()
        self.smooth = BatchBeatAverage(n) if cfg.beat_averaging else None
        self.frequency_hz = z.copy()

    def step(
        self, dt_s: float, course_rad: Array, depth_m: Array, speed_m_s: Array, m: BatchMeasured
    ) -> BatchCommand:
        """One control tick of every run (:meth:`bauv_sim.autopilot.Autopilot.step`).

        Args:
            dt_s: control period, s.
            course_rad: desired heading, rad clockwise from north, shape (n,).
            depth_m: desired depth, m, shape (n,).
            speed_m_s: desired speed through water, m/s, shape (n,).
            m: measurements.

        Returns:
            The actuator commands.
        """
        c = self.cfg
        depth_rate = np.zeros(self.n)
        if self.smooth is not None:
            m, depth_rate = self.smooth(m, self.frequency_hz, dt_s)
        e_h = (course_rad - m.heading_rad + math.pi) % (2 * math.pi)
        e_h = np.where(e_h >= 2 * math.pi, 0.0, e_h) - math.pi  # wrapped to [-pi, pi)
        bias = self.tail_bias_sign * self.heading.step(e_h, m.yaw_rate_rad_s, dt_s)
        e_d = depth_m - m.depth_m
        self.desired_pitch_rad = -self.depth.step(e_d, depth_rate, dt_s)
        e_p = self.desired_pitch_rad - m.pitch_rad
        sym = self.fin_sign * self.pitch.step(e_p, m.pitch_rate_rad_s, dt_s)
        diff = self.roll.step(-m.roll_rad, m.roll_rate_rad_s, dt_s)
        fin_max = math.radians(c.fin_max_deg)
        port = np.minimum(np.maximum(sym + diff, -fin_max), fin_max)
        stbd = np.minimum(np.maximum(sym - diff, -fin_max), fin_max)
        stop = speed_m_s <= 0.0
        self.speed.reset(stop)
        ff = self.frequency_for_speed(np.where(stop, 1.0, speed_m_s))
        freq = self.speed.step(speed_m_s - m.speed_m_s, np.zeros(self.n), dt_s, feedforward=ff)
        if stop.any():  # the scalar loop neither steps nor integrates a stopped vehicle
            freq = np.where(stop, 0.0, freq)
            self.speed.reset(stop)
        swim = freq > 0.0
        mean_fin = self.fin_sign * 0.5 * (port + stbd)
        b = self.battery_m - c.trim_gain_m_per_rad_s * mean_fin * dt_s
        b = np.minimum(np.maximum(b, c.battery_min_m), c.battery_max_m)
        self.battery_m = np.where(swim, b, self.battery_m)
        self.frequency_hz = freq
        return BatchCommand(freq, bias, port, stbd, self.battery_m.copy())
