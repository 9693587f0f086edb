"""Autopilot: heading, depth and speed loops onto the BAUV's tail, lateral fins and battery.

Inputs are what the vehicle measures (heading from the compass, depth from the pressure sensor,
pitch and rates from the INS, speed through water from the log or the odometry); outputs are the
actuator settings of :mod:`bauv_sim.physics`:

* **speed** -> tail-beat frequency: feed-forward from the self-propelled speed table (the frequency
  that gives the desired speed in still water) plus a PI correction on the measured speed;
* **heading** -> tail bias: PID on the wrapped heading error, the derivative taken on the measured
  yaw rate (no derivative kick on a course step);
* **depth** -> lateral fins, as a cascade: depth error -> desired pitch (PI, limited), pitch error
  -> symmetric fin angle (PD on the measured pitch rate); a roll PD adds a differential fin angle;
* **trim** -> battery position: a slow integrator that moves the battery so that the fins' mean
  deflection goes to zero in steady flight (static trim left to the battery, fins free to control).

**Tail-beat averaging.** A fish-like body yaws, sways and surges with every tail stroke (on
``models/bauv`` at 1.2 Hz: about +-7 deg of head yaw and +-40 deg/s of yaw rate). Fed straight
into a derivative term, that recoil slams the tail bias from stop to stop at the beat frequency.
The measurements are therefore averaged over the last tail-beat period (a moving average over
``round(1 / (f dt))`` control ticks at the commanded frequency f: a notch at the beat frequency and
its harmonics); the heading is averaged as a unit vector. The averaging delays the loops by half a
beat, which the gains below allow for.

Every integrator has anti-windup: it stops integrating while the loop's output is saturated in
the direction the integral would push it (conditional integration), and is clamped. Gains and
limits are in :class:`AutopilotConfig` with their reasoning; they were tuned on the model of
``models/bauv`` (step responses in ``models/bauv/tools/checks.py``, recorded in the model README).
"""

from __future__ import annotations

import collections
import itertools
import math
from dataclasses import dataclass, field

from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.frames import course_of_scalar, unit_vector_scalar, wrap_pi_scalar


@dataclass
class PID:
    """A PID loop with conditional-integration anti-windup.

    ``u = kp e + ki integral(e) - kd rate``, with ``rate`` the measured rate of the controlled
    quantity (derivative on measurement), the integral clamped to +-``i_limit``, frozen while
    ``u`` is saturated in the direction of ``e``, and only accumulated while ``|e| <= i_zone`` (so
    that a large set-point change, a turn or a dive, does not wind it up).

    Attributes:
        kp: proportional gain.
        ki: integral gain, per s.
        kd: derivative gain on the measured rate, s.
        u_min: lower output limit.
        u_max: upper output limit.
        i_limit: limit of the integral term's contribution (in output units).
    """

    kp: float
    ki: float = 0.0
    kd: float = 0.0
    u_min: float = -math.inf
    u_max: float = math.inf
    i_limit: float = math.inf
    i_zone: float = math.inf
    integral: float = field(default=0.0)

    def step(self, error: float, rate: float, dt_s: float, feedforward: float = 0.0) -> float:
        """One update.

        Args:
            error: setpoint minus measurement.
            rate: measured rate of the controlled quantity (for the D term).
            dt_s: time since the previous update, s.
            feedforward: added to the output before saturation.

        Returns:
            The saturated output.
        """
        u_unsat = feedforward + self.kp * error + self.integral - self.kd * rate
        saturated_high = u_unsat >= self.u_max and error > 0
        saturated_low = u_unsat <= self.u_min and error < 0
        if self.ki and abs(error) <= self.i_zone and not (saturated_high or saturated_low):
            i = self.integral + self.ki * error * dt_s
            self.integral = min(max(i, -self.i_limit), self.i_limit)
        u = feedforward + self.kp * error + self.integral - self.kd * rate
        return min(max(u, self.u_min), self.u_max)

    def reset(self) -> None:
        """Clear the integral."""
        self.integral = 0.0


class AutopilotConfig(Config):
    """Gains and limits of the autopilot (tuned on ``models/bauv``; see the module docstring)."""

    heading_kp: float = Field(0.8, ge=0, description="tail bias per heading error, rad/rad")
    heading_ki: float = Field(0.05, ge=0, description="per s")
    heading_kd: float = Field(0.5, ge=0, description="tail bias per yaw rate, rad/(rad/s)")
    tail_bias_max_deg: float = Field(25.0, gt=0, le=60, description="tail bias limit, deg")
    heading_i_zone_deg: float = Field(10.0, gt=0, description="integrate only within, deg")

    depth_kp: float = Field(0.3, ge=0, description="desired pitch per depth error, rad/m")
    depth_ki: float = Field(0.02, ge=0, description="per s")
    depth_kd: float = Field(0.6, ge=0, description="desired pitch per depth rate, rad/(m/s)")
    depth_i_zone_m: float = Field(0.5, gt=0, description="integrate only within, m")
    pitch_max_deg: float = Field(20.0, gt=0, le=45, description="desired pitch limit, deg")
    pitch_kp: float = Field(2.0, ge=0, description="fin angle per pitch error, rad/rad")
    pitch_kd: float = Field(1.0, ge=0, description="fin angle per pitch rate, rad/(rad/s)")
    roll_kp: float = Field(0.5, ge=0, description="differential fin per roll, rad/rad")
    roll_kd: float = Field(0.3, ge=0, description="differential fin per roll rate")
    fin_max_deg: float = Field(25.0, gt=0, le=45, description="lateral fin limit, deg")

    speed_kp: float = Field(
        0.35,
        ge=0,
        description="tail-beat frequency per speed error, Hz/(m/s) (the speed table's slope at "
        "cruise is 1.2 m/s per Hz: a loop gain of 0.4)",
    )
    speed_ki: float = Field(0.035, ge=0, description="per s")
    frequency_max_hz: float = Field(3.0, gt=0, description="tail-beat frequency limit, Hz")

    trim_gain_m_per_rad_s: float = Field(
        0.002, ge=0, description="battery speed per mean fin deflection, (m/s)/rad"
    )
    beat_averaging: bool = Field(True, description="average measurements over a tail beat")
    battery_min_m: float = Field(-0.05, description="battery slide lower limit, m")
    battery_max_m: float = Field(0.05, description="battery slide upper limit, m")


@dataclass(frozen=True)
class Measured:
    """What the autopilot reads, all from the vehicle's own sensors.

    Attributes:
        heading_rad: compass heading, rad clockwise from north.
        yaw_rate_rad_s: rate of the heading (clockwise +), rad/s.
        depth_m: pressure depth, m.
        pitch_rad: pitch, nose up +, rad.
        pitch_rate_rad_s: rate of the pitch, rad/s.
        roll_rad: roll, starboard down +, rad.
        roll_rate_rad_s: rate of the roll, rad/s.
        speed_m_s: speed through water (log, or odometry when the log is blind), m/s.
    """

    heading_rad: float
    yaw_rate_rad_s: float
    depth_m: float
    pitch_rad: float
    pitch_rate_rad_s: float
    roll_rad: float
    roll_rate_rad_s: float
    speed_m_s: float


@dataclass(frozen=True)
class ActuatorCommand:
    """Settings for the vehicle's actuators.

    Attributes:
        tail_beat_hz: motor speed as tail-beat frequency, Hz.
        tail_bias_rad: tail bias, rad (positive turns the vehicle to starboard, i.e. increases
            the heading).
        fin_port_rad: port lateral fin pitch, rad (positive: leading edge up, pitches nose up).
        fin_starboard_rad: starboard lateral fin pitch, rad.
        battery_m: battery position on its slide, m (positive forward).
    """

    tail_beat_hz: float
    tail_bias_rad: float
    fin_port_rad: float
    fin_starboard_rad: float
    battery_m: float


class BeatAverage:
    """Moving averages of the measurements: over the last tail-beat period for the attitude and
    depth, over ``speed_window_s`` for the speed (the surge recoil at twice the beat frequency is
    close to the tick's Nyquist frequency, and speed changes slowly), and the depth rate as the
    slope of the beat-averaged depth over the last ``depth_rate_window_s``.

    Plain Python arithmetic on a short history: it runs at every control tick.

    Args:
        speed_window_s: averaging window of the speed, s.
        depth_rate_window_s: baseline of the depth rate, s.
        max_samples: longest window, in control ticks.
    """

    def __init__(
        self,
        speed_window_s: float = 4.0,
        depth_rate_window_s: float = 1.0,
        max_samples: int = 100,
    ):
        self.speed_window_s = speed_window_s
        self.depth_rate_window_s = depth_rate_window_s
        self._rows: collections.deque[tuple[float, ...]] = collections.deque(maxlen=max_samples)
        self._speeds: collections.deque[float] = collections.deque(maxlen=max_samples)
        self._depths: collections.deque[float] = collections.deque(maxlen=max_samples)

    def __call__(self, m: Measured, frequency_hz: float, dt_s: float) -> tuple[Measured, float]:
        """Filtered measurements, and the depth rate (m/s, positive going deeper)."""
        self._rows.append(
            (
                *unit_vector_scalar(m.heading_rad),
                m.yaw_rate_rad_s,
                m.depth_m,
                m.pitch_rad,
                m.pitch_rate_rad_s,
                m.roll_rad,
                m.roll_rate_rad_s,
            )
        )
        self._speeds.append(m.speed_m_s)
        n = 1 if frequency_hz <= 0 else round(1.0 / (frequency_hz * dt_s))
        n = max(1, min(n, len(self._rows)))
        rows = list(itertools.islice(reversed(self._rows), n))
        a = [sum(col) / n for col in zip(*rows, strict=True)]
        ns = max(1, min(round(self.speed_window_s / dt_s), len(self._speeds)))
        speed = sum(itertools.islice(reversed(self._speeds), ns)) / ns
        self._depths.append(a[3])
        nd = min(round(self.depth_rate_window_s / dt_s), len(self._depths) - 1)
        rate = (a[3] - self._depths[-1 - nd]) / (nd * dt_s) if nd >= 1 else 0.0
        heading = course_of_scalar(a[0], a[1])
        return Measured(heading, a[2], a[3], a[4], a[5], a[6], a[7], speed), rate


class Autopilot:
    """The three loops and the trim integrator (see the module docstring).

    Args:
        cfg: gains and limits.
        frequency_for_speed: feed-forward map desired speed (m/s) -> tail-beat frequency (Hz),
            from the vehicle's speed table.
        tail_bias_sign: +1 if a positive tail bias turns the vehicle to starboard on this model,
            -1 otherwise (a property of the model, measured by ``models/bauv/tools/checks.py``).
        fin_sign: +1 if a positive symmetric fin angle pitches the nose up, else -1.
        battery0_m: initial battery position, m.
    """

    def __init__(
        self,
        cfg: AutopilotConfig,
        frequency_for_speed,
        tail_bias_sign: float = 1.0,
        fin_sign: float = 1.0,
        battery0_m: float = 0.0,
    ):
        self.cfg = cfg
        self.frequency_for_speed = frequency_for_speed
        self.tail_bias_sign = float(tail_bias_sign)
        self.fin_sign = float(fin_sign)
        bias = math.radians(cfg.tail_bias_max_deg)
        fin = math.radians(cfg.fin_max_deg)
        pitch = math.radians(cfg.pitch_max_deg)
        self.heading = PID(
            cfg.heading_kp,
            cfg.heading_ki,
            cfg.heading_kd,
            -bias,
            bias,
            0.5 * bias,
            math.radians(cfg.heading_i_zone_deg),
        )
        self.depth = PID(
            cfg.depth_kp,
            cfg.depth_ki,
            cfg.depth_kd,
            -pitch,
            pitch,
            0.5 * pitch,
            cfg.depth_i_zone_m,
        )
        self.pitch = PID(cfg.pitch_kp, 0.0, cfg.pitch_kd, -fin, fin)
        self.roll = PID(cfg.roll_kp, 0.0, cfg.roll_kd, -0.5 * fin, 0.5 * fin)
        self.speed = PID(cfg.speed_kp, cfg.speed_ki, 0.0, 0.0, cfg.frequency_max_hz, 1.0)
        self.battery_m = float(battery0_m)
        self.desired_pitch_rad = 0.0
        self.smooth = BeatAverage() if cfg.beat_averaging else None
        self.frequency_hz = 0.0

    def step(
        self, dt_s: float, course_rad: float, depth_m: float, speed_m_s: float, m: Measured
    ) -> ActuatorCommand:
        """One control tick.

        Args:
            dt_s: control period, s.
            course_rad: desired heading, rad clockwise from north.
            depth_m: desired depth, m.
            speed_m_s: desired speed through water, m/s.
            m: measurements.

        Returns:
            The actuator command.
        """
        c = self.cfg
        depth_rate = 0.0
        if self.smooth is not None:
            m, depth_rate = self.smooth(m, self.frequency_hz, dt_s)
        # heading: error > 0 means turn clockwise (to starboard)
        e_h = wrap_pi_scalar(course_rad - m.heading_rad)
        bias = self.tail_bias_sign * self.heading.step(e_h, m.yaw_rate_rad_s, dt_s)
        # depth cascade: deeper than wanted (e_d < 0) -> pitch up
        e_d = depth_m - m.depth_m
        self.desired_pitch_rad = -self.depth.step(e_d, depth_rate, dt_s)
        e_p = self.desired_pitch_rad - m.pitch_rad
        sym = self.fin_sign * self.pitch.step(e_p, m.pitch_rate_rad_s, dt_s)
        diff = self.roll.step(-m.roll_rad, m.roll_rate_rad_s, dt_s)
        fin_max = math.radians(c.fin_max_deg)
        port = min(max(sym + diff, -fin_max), fin_max)
        stbd = min(max(sym - diff, -fin_max), fin_max)
        # speed: feed-forward from the speed table plus PI
        if speed_m_s <= 0.0:
            self.speed.reset()
            freq = 0.0
        else:
            ff = float(self.frequency_for_speed(speed_m_s))
            freq = self.speed.step(speed_m_s - m.speed_m_s, 0.0, dt_s, feedforward=ff)
        # trim: move the battery to null the mean fin deflection (only when swimming)
        if freq > 0.0:
            mean_fin = self.fin_sign * 0.5 * (port + stbd)
            b = self.battery_m - c.trim_gain_m_per_rad_s * mean_fin * dt_s
            self.battery_m = min(max(b, c.battery_min_m), c.battery_max_m)
        self.frequency_hz = freq
        return ActuatorCommand(freq, bias, port, stbd, self.battery_m)
