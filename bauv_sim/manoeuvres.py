"""Open-loop manoeuvres of one BAUV, measured on the physics (the acceptance checks' experiments).

Each function takes a :class:`~bauv_sim.physics.BauvPhysics` in the state it should start from,
drives it through the facade's actuation interface and returns a frozen result record with units
in the field names. Nothing here closes a loop on heading or speed; where a manoeuvre needs level
flight to measure something else (the speed table, the turning circle) the lateral fins hold depth
with a fixed proportional-derivative law (:class:`DepthHold`), and the record says so.

:func:`open_water_scene` gives the deep, flat-bottomed scene the checks run in, so that no
manoeuvre meets the seabed.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bauv_sim import build, currents
from bauv_sim.errors import ConfigError
from bauv_sim.physics import BauvPhysics
from bauv_sim.sea import Sea
from bauv_sim.seabed import SeabedConfig


def open_water_scene(
    depth_m: float = 20.0,
    heading_deg: float = 0.0,
    speed_m_s: float = 0.0,
    bottom_depth_m: float = 200.0,
) -> BauvPhysics:
    """One vehicle over a flat seabed far below (no relief, no slope), at rest or moving.

    Args:
        depth_m: initial depth, m.
        heading_deg: initial heading, clockwise from north, deg.
        speed_m_s: initial speed along the heading, m/s.
        bottom_depth_m: depth of the flat seabed, m.

    Returns:
        The physics (control tick 0.1 s).
    """
    bed = SeabedConfig(
        depth_at_origin_m=bottom_depth_m,
        slope=0.0,
        relief_std_m=0.0,
        min_depth_m=bottom_depth_m,
        half_extent_m=2000.0,
        cell_m=500.0,
    )
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(depth_m=depth_m, heading_deg=heading_deg, speed_m_s=speed_m_s),
        ),
        seabed=bed,
        beacons=(),
    )
    return build.build_physics(cfg)


@dataclass(frozen=True)
class DepthHold:
    """Fixed proportional-derivative depth hold on the lateral fins (both fins together):

        fin = clip(k_depth (depth - target) - k_pitch pitch - k_rate w_up, +-limit)

    Positive fin angles (leading edge up) lift the vehicle; ``w_up`` is the vertical velocity
    (world z, up). Gains in rad per m, rad per rad and rad per (m/s).
    """

    target_depth_m: float
    k_depth: float = 0.25
    k_pitch: float = 1.0
    k_rate: float = 1.0
    limit_rad: float = 0.35

    def fins_rad(self, physics: BauvPhysics) -> float:
        """Fin angle for the vehicle's current state, rad."""
        e = physics.depth_m() - self.target_depth_m
        pitch = float(physics.roll_pitch_heading()[1])
        w = float(physics.velocity_world()[2])
        u = self.k_depth * e - self.k_pitch * pitch - self.k_rate * w
        return float(np.clip(u, -self.limit_rad, self.limit_rad))


# --------------------------------------------------------------------------------------------
# straight swim


@dataclass(frozen=True)
class StraightSwimResult:
    """Steady straight swimming at one tail-beat frequency.

    Attributes:
        frequency_hz: commanded tail-beat frequency, Hz.
        speed_through_water_m_s: mean speed relative to the water over the measured window, m/s.
        speed_over_ground_m_s: mean speed over ground, m/s.
        mean_motor_power_w: motor energy over the window divided by its length, W.
        peak_motor_torque_nm: largest |motor torque| sampled in the window, N m.
        tail_tip_amplitude_m: mean peak-to-peak lateral excursion per cycle of the caudal fin's
            trailing-edge tip, relative to the hull's path smoothed over one cycle, m.
        strouhal: frequency x amplitude / speed through water.
        mean_pitch_rad: mean pitch, rad.
        mean_fin_rad: mean lateral-fin angle (the depth hold's trim), rad.
        yaw_amplitude_rad: mean peak-to-peak heading oscillation per cycle, rad.
        depth_change_m: depth at the end minus depth at the start of the window, m.
        window_s: length of the measured window, s (whole tail beats).
    """

    frequency_hz: float
    speed_through_water_m_s: float
    speed_over_ground_m_s: float
    mean_motor_power_w: float
    peak_motor_torque_nm: float
    tail_tip_amplitude_m: float
    strouhal: float
    mean_pitch_rad: float
    mean_fin_rad: float
    yaw_amplitude_rad: float
    depth_change_m: float
    window_s: float


def straight_swim(
    physics: BauvPhysics,
    frequency_hz: float,
    settle_s: float = 30.0,
    measure_s: float = 20.0,
    hold_depth: bool = True,
    samples_per_beat: int = 50,
) -> StraightSwimResult:
    """Swim straight at a fixed tail-beat frequency and measure the steady state.

    Runs ``settle_s`` (rounded to control ticks) and then a window of whole tail beats of about
    ``measure_s``, sampling the caudal tip and the motor ``samples_per_beat`` times per beat.

    Args:
        physics: the physics (one vehicle; the first is used), in its starting state.
        frequency_hz: tail-beat frequency, Hz (> 0).
        settle_s: time to reach steady state before measuring, s.
        measure_s: approximate length of the measured window, s.
        hold_depth: hold the starting depth with :class:`DepthHold` (else fins stay level).
        samples_per_beat: samples of the tail per beat (>= 20).

    Returns:
        The :class:`StraightSwimResult`.
    """
    if frequency_hz <= 0:
        raise ConfigError(f"frequency = {frequency_hz} Hz: must be > 0")
    hold = DepthHold(physics.depth_m()) if hold_depth else None
    physics.set_tail_beat_frequency_hz(frequency_hz)
    physics.set_tail_bias_rad(0.0)
    physics.set_lateral_fins_rad(0.0, 0.0)
    tick = physics.control_tick_s
    for _ in range(round(settle_s / tick)):
        if hold is not None:
            a = hold.fins_rad(physics)
            physics.set_lateral_fins_rad(a, a)
        physics.advance(tick)
    # window of whole beats, sampled on whole physics steps
    dt = float(physics.timestep())
    beats = max(1, round(measure_s * frequency_hz))
    steps_per_beat = 1.0 / (frequency_hz * dt)
    sub = max(1, int(steps_per_beat // max(20, samples_per_beat)))
    n_steps = round(beats * steps_per_beat)
    n_steps -= n_steps % sub
    physics.set_energy_tracking(True)
    t0 = physics.time_s()
    p0 = physics.position_world()
    ground = np.zeros(3)
    through = np.zeros(3)
    tips, hulls, heads, pitches, torques, fins = [], [], [], [], [], []
    steps_per_tick = physics.steps_per_tick
    done = 0
    while done < n_steps:
        if hold is not None and done % steps_per_tick == 0:
            a = hold.fins_rad(physics)
            physics.set_lateral_fins_rad(a, a)
        k = min(sub, n_steps - done)
        physics.step(k)
        done += k
        tips.append(physics.site_position_world("caudal_tip"))
        hulls.append(physics.position_world())
        rph = physics.roll_pitch_heading()
        heads.append(rph[2])
        pitches.append(rph[1])
        torques.append(abs(physics.motor_torque_nm()))
        fins.append(float(np.mean(physics.lateral_fin_angles_rad())))
    window = physics.time_s() - t0
    p1 = physics.position_world()
    ground = (p1 - p0) / window
    through = ground - physics.current_at_vehicle_world()
    u_tw = float(np.linalg.norm(through))
    amp = _tip_amplitude(np.asarray(tips), np.asarray(hulls), through, beats)
    head = np.unwrap(np.asarray(heads))
    yaw = float(np.mean(np.ptp(head[: (head.size // beats) * beats].reshape(beats, -1), axis=1)))
    result = StraightSwimResult(
        frequency_hz=frequency_hz,
        speed_through_water_m_s=u_tw,
        speed_over_ground_m_s=float(np.linalg.norm(ground)),
        mean_motor_power_w=physics.mean_motor_power_w(),
        peak_motor_torque_nm=float(np.max(torques)),
        tail_tip_amplitude_m=amp,
        strouhal=frequency_hz * amp / u_tw if u_tw > 0 else math.inf,
        mean_pitch_rad=float(np.mean(pitches)),
        mean_fin_rad=float(np.mean(fins)),
        yaw_amplitude_rad=yaw,
        depth_change_m=float(-(p1[2] - p0[2])),
        window_s=window,
    )
    physics.set_energy_tracking(False)
    return result


def _tip_amplitude(
    tips: NDArray[np.float64], hulls: NDArray[np.float64], vel: NDArray[np.float64], beats: int
) -> float:
    """Mean per-beat peak-to-peak of the tip's lateral offset from the hull's path.

    The lateral direction is horizontal and normal to the mean velocity; the path is the hull's
    lateral position smoothed over one beat (a centred moving average, wrapped at the ends).
    """
    e = vel[:2] / max(float(np.linalg.norm(vel[:2])), 1e-12)
    n = np.array([-e[1], e[0]])
    per = tips.shape[0] // beats
    hull_lat = hulls[:, :2] @ n
    kernel = np.ones(per) / per
    padded = np.r_[hull_lat[-per:], hull_lat, hull_lat[:per]]
    smooth = np.convolve(padded, kernel, mode="same")[per:-per]
    # the wrap-around is wrong at the ends for a drifting path: use the interior beats only
    rel = tips[:, :2] @ n - smooth
    if beats >= 3:
        rel = rel[per : (beats - 1) * per]
        beats -= 2
    cyc = rel[: beats * per].reshape(beats, per)
    return float(np.mean(np.ptp(cyc, axis=1)))


def speed_table(
    physics: BauvPhysics,
    frequencies_hz: list[float],
    settle_s: float = 30.0,
    measure_s: float = 20.0,
) -> list[StraightSwimResult]:
    """Straight swims at increasing frequencies, one after the other in the same run (each starts
    from the previous steady state).

    Args:
        physics: the physics, starting state.
        frequencies_hz: increasing tail-beat frequencies, Hz.
        settle_s: settling time per frequency, s.
        measure_s: measured window per frequency, s.

    Returns:
        One :class:`StraightSwimResult` per frequency.
    """
    if any(b <= a for a, b in itertools.pairwise(frequencies_hz)):
        raise ConfigError(f"frequencies = {frequencies_hz}: must increase")
    return [straight_swim(physics, f, settle_s, measure_s) for f in frequencies_hz]


# --------------------------------------------------------------------------------------------
# tow test


@dataclass(frozen=True)
class TowPoint:
    """Drag of the towed vehicle at one speed.

    Attributes:
        speed_m_s: towing speed through water, m/s.
        drag_n: fluid force against the motion, N (from MuJoCo's ``qfrc_fluid``).
        side_force_n: horizontal fluid force across the motion, N.
        cd: ``drag / (rho U^2 A / 2)`` on the reference area.
    """

    speed_m_s: float
    drag_n: float
    side_force_n: float
    cd: float


def tow_test(
    physics: BauvPhysics,
    speeds_m_s: list[float],
    reference_area_m2: float,
    current_m_s: float = 0.0,
) -> list[TowPoint]:
    """Drag of the vehicle held at constant speeds with the tail straight and the fins level.

    The vehicle is placed level, heading north, moving north at each speed relative to the water
    (with ``current_m_s`` the water flows north too and the vehicle moves at speed + current over
    ground: the drag must not change), all joints at rest at zero angle; the fluid force is
    MuJoCo's ``qfrc_fluid`` on the free joint's translation (the model's fluid forces are
    quasi-steady, so a held state gives the towed drag).

    Args:
        physics: the physics (its state is overwritten).
        speeds_m_s: speeds through water, m/s.
        reference_area_m2: area of the drag coefficient, m^2.
        current_m_s: a uniform current set northwards during the test, m/s.

    Returns:
        One :class:`TowPoint` per speed.
    """
    rho = physics.water_density_kg_m3()
    out = []
    sea = Sea(currents.UniformCurrent(current_m_s, 0.0) if current_m_s else None)
    physics.reset()
    sea.immerse(physics)
    for u in speeds_m_s:
        physics.reset()
        sea.immerse(physics)
        physics.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, 0.0], [0.0, u + current_m_s, 0.0])
        f = physics.fluid_force_world()
        drag = -float(f[1])
        out.append(TowPoint(u, drag, float(f[0]), drag / (0.5 * rho * u * u * reference_area_m2)))
    Sea().immerse(physics)
    return out


# --------------------------------------------------------------------------------------------
# turning and depth change


@dataclass(frozen=True)
class TurnResult:
    """Steady turn with a fixed tail bias.

    Attributes:
        frequency_hz: tail-beat frequency, Hz.
        bias_rad: commanded tail bias, rad (positive: tail to port).
        turn_rate_rad_s: mean rate of change of heading, rad/s (positive: clockwise, to starboard).
        turning_radius_m: radius of the circle fitted to the path, m.
        speed_through_water_m_s: mean speed in the turn, m/s.
        time_to_90deg_s: time from applying the bias until the heading changed by 90 deg, s.
        mean_roll_rad: mean roll in the turn, rad.
        depth_change_m: depth change over the whole manoeuvre, m.
        drift_angle_rad: mean of course over ground minus heading over the fitted half, rad
            (positive: moving to starboard of the heading).
    """

    frequency_hz: float
    bias_rad: float
    turn_rate_rad_s: float
    turning_radius_m: float
    speed_through_water_m_s: float
    time_to_90deg_s: float
    mean_roll_rad: float
    depth_change_m: float
    drift_angle_rad: float = 0.0


def heading_change(
    physics: BauvPhysics,
    frequency_hz: float,
    bias_rad: float,
    approach_s: float = 30.0,
    turn_s: float = 60.0,
    hold_depth: bool = True,
) -> TurnResult:
    """Swim straight, then apply a fixed tail bias (open loop in heading) and measure the turn.

    Args:
        physics: the physics, starting state.
        frequency_hz: tail-beat frequency, Hz.
        bias_rad: tail bias during the turn, rad.
        approach_s: straight swim before the bias, s.
        turn_s: duration of the turn, s; the circle is fitted to its second half.
        hold_depth: hold the starting depth with the lateral fins (:class:`DepthHold`).

    Returns:
        The :class:`TurnResult`.
    """
    hold = DepthHold(physics.depth_m()) if hold_depth else None
    z0 = physics.depth_m()
    tick = physics.control_tick_s
    physics.set_tail_beat_frequency_hz(frequency_hz)
    physics.set_tail_bias_rad(0.0)

    def run(seconds: float, log: list | None) -> None:
        for _ in range(round(seconds / tick)):
            if hold is not None:
                a = hold.fins_rad(physics)
                physics.set_lateral_fins_rad(a, a)
            physics.advance(tick)
            if log is not None:
                vel = physics.velocity_world()
                log.append(
                    (
                        physics.time_s(),
                        physics.position_world(),
                        physics.heading_rad(),
                        float(physics.roll_pitch_heading()[0]),
                        math.atan2(vel[0], vel[1]),
                    )
                )

    run(approach_s, None)
    h0 = physics.heading_rad()
    t_start = physics.time_s()
    physics.set_tail_bias_rad(bias_rad)
    log: list = []
    run(turn_s, log)
    t = np.array([r[0] for r in log])
    pos = np.array([r[1] for r in log])
    head = np.unwrap(np.r_[h0, [r[2] for r in log]])[1:]
    roll = np.array([r[3] for r in log])
    turned = np.abs(head - h0)
    idx = np.flatnonzero(turned >= math.pi / 2)
    t90 = float(t[idx[0]] - t_start) if idx.size else math.inf
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    rate = float(np.polyfit(t[half], head[half], 1)[0])
    radius = _fit_circle_radius(pos[half, :2])
    dist = np.sum(np.linalg.norm(np.diff(pos[half], axis=0), axis=1))
    speed = float(dist / (t[half][-1] - t[half][0]))
    course = np.unwrap(np.r_[h0, [r[4] for r in log]])[1:]
    drift = float(np.mean(np.angle(np.exp(1j * (course[half] - head[half])))))
    return TurnResult(
        frequency_hz,
        bias_rad,
        rate,
        radius,
        speed,
        t90,
        float(np.mean(roll[half])),
        physics.depth_m() - z0,
        drift,
    )


def _fit_circle_radius(xy: NDArray[np.float64]) -> float:
    """Least-squares circle through points (algebraic fit, Kasa 1976), radius in m."""
    A = np.c_[2.0 * xy, np.ones(len(xy))]
    b = (xy**2).sum(axis=1)
    c, *_ = np.linalg.lstsq(A, b, rcond=None)
    return float(np.sqrt(c[2] + c[0] ** 2 + c[1] ** 2))


@dataclass(frozen=True)
class DepthChangeResult:
    """Response to a step of both lateral fins, open loop.

    Attributes:
        frequency_hz: tail-beat frequency, Hz.
        fin_rad: fin angle applied (positive: leading edge up), rad.
        peak_pitch_rate_rad_s: largest |pitch rate| after the step, rad/s.
        pitch_change_rad: mean pitch over the last quarter minus pitch before the step, rad.
        depth_rate_m_s: mean rate of change of depth over the second half (positive: diving), m/s.
        depth_change_m: depth change over the manoeuvre, m.
    """

    frequency_hz: float
    fin_rad: float
    peak_pitch_rate_rad_s: float
    pitch_change_rad: float
    depth_rate_m_s: float
    depth_change_m: float


def depth_change(
    physics: BauvPhysics,
    frequency_hz: float,
    fin_rad: float,
    approach_s: float = 30.0,
    step_s: float = 20.0,
) -> DepthChangeResult:
    """Swim straight with level fins, then set both lateral fins to ``fin_rad`` and hold them.

    Args:
        physics: the physics, starting state.
        frequency_hz: tail-beat frequency, Hz.
        fin_rad: fin angle after the step, rad.
        approach_s: straight swim before the step, s.
        step_s: duration after the step, s.

    Returns:
        The :class:`DepthChangeResult`.
    """
    tick = physics.control_tick_s
    physics.set_tail_beat_frequency_hz(frequency_hz)
    physics.set_tail_bias_rad(0.0)
    physics.set_lateral_fins_rad(0.0, 0.0)
    physics.advance(round(approach_s / tick) * tick)
    pitch0 = float(physics.roll_pitch_heading()[1])
    z0 = physics.depth_m()
    physics.set_lateral_fins_rad(fin_rad, fin_rad)
    t, z, pitch, q = [], [], [], []
    for _ in range(round(step_s / tick)):
        physics.advance(tick)
        t.append(physics.time_s())
        z.append(physics.depth_m())
        pitch.append(float(physics.roll_pitch_heading()[1]))
        q.append(float(physics.angular_velocity_body()[1]))
    t, z, pitch = np.array(t), np.array(z), np.array(pitch)
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    last = t >= t[0] + 0.75 * (t[-1] - t[0])
    rate = float(np.polyfit(t[half], z[half], 1)[0])
    # body y is port: a nose-up pitch rate is a negative rotation about +y
    return DepthChangeResult(
        frequency_hz,
        fin_rad,
        float(np.max(np.abs(q))),
        float(np.mean(pitch[last]) - pitch0),
        rate,
        float(z[-1] - z0),
    )


# --------------------------------------------------------------------------------------------
# hydrostatics and current


@dataclass(frozen=True)
class RollRecoveryResult:
    """Free roll decay of the idle vehicle in still water.

    Attributes:
        initial_roll_rad: roll at release, rad.
        settle_time_s: time after which |roll| stays below ``threshold_rad``, s.
        threshold_rad: the settling threshold, rad.
        period_s: mean period of the roll oscillation (zero crossings), s, or NaN if it does not
            cross zero.
        max_overshoot_rad: largest roll of the opposite sign, rad.
    """

    initial_roll_rad: float
    settle_time_s: float
    threshold_rad: float
    period_s: float
    max_overshoot_rad: float


def roll_recovery(
    physics: BauvPhysics,
    roll_rad: float = math.radians(20.0),
    duration_s: float = 10.0,
    threshold_rad: float = math.radians(2.0),
) -> RollRecoveryResult:
    """Release the idle vehicle from a roll angle at rest and time its return.

    Args:
        physics: the physics (the first vehicle is re-placed at its position, heading kept).
        roll_rad: initial roll, rad.
        duration_s: observation time, s (whole control ticks).
        threshold_rad: settling threshold, rad.

    Returns:
        The :class:`RollRecoveryResult`.
    """
    rph = physics.roll_pitch_heading()
    physics.set_pose(physics.position_world(), [roll_rad, 0.0, rph[2]])
    t0 = physics.time_s()
    ts, rolls = [0.0], [roll_rad]
    n_sub = 5
    for _ in range(round(duration_s / physics.timestep() / n_sub)):
        physics.step(n_sub)
        ts.append(physics.time_s() - t0)
        rolls.append(float(physics.roll_pitch_heading()[0]))
    t, r = np.array(ts), np.array(rolls)
    above = np.flatnonzero(np.abs(r) >= threshold_rad)
    settle = (
        float(t[above[-1] + 1])
        if above.size and above[-1] + 1 < t.size
        else (math.inf if above.size else 0.0)
    )
    sign = np.sign(r)
    cross = np.flatnonzero(sign[1:] * sign[:-1] < 0)
    period = float(2.0 * np.mean(np.diff(t[cross]))) if cross.size >= 2 else math.nan
    opposite = r * np.sign(roll_rad)
    return RollRecoveryResult(
        roll_rad, settle, threshold_rad, period, float(max(0.0, -opposite.min()))
    )


def release_in_current(physics: BauvPhysics, field: currents.CurrentField) -> None:
    """Put the (first) vehicle at rest over ground in a current that was always there: the sea is
    put around it (:meth:`~bauv_sim.sea.Sea.immerse` carries the vehicle with the water) and the
    vehicle is stopped where it is, attitude and joints kept.

    Args:
        physics: the physics.
        field: the current field.
    """
    Sea(field).immerse(physics)
    physics.set_pose(physics.position_world(), physics.roll_pitch_heading(), np.zeros(3))


@dataclass(frozen=True)
class DriftResult:
    """Idle vehicle in a current.

    Attributes:
        duration_s: time since the current was switched on, s.
        current_world_m_s: the current, shape (3,), m/s, world.
        velocity_world_m_s: velocity over ground at the end (mean over the last second), shape (3,).
        relative_error: |velocity - current| / |current| at the end.
        depth_change_m: depth change, m.
    """

    duration_s: float
    current_world_m_s: NDArray[np.float64]
    velocity_world_m_s: NDArray[np.float64]
    relative_error: float
    depth_change_m: float


def idle_drift(
    physics: BauvPhysics, field: currents.CurrentField, duration_s: float = 120.0
) -> DriftResult:
    """Release the idle vehicle (motor stopped, tail straight, fins level) at rest over ground in
    a current that was always there (the sea is set, which carries the vehicle with the water, and
    the vehicle is then stopped where it is) and let the current pick it up through drag.

    Args:
        physics: the physics, vehicle at rest.
        field: the current field.
        duration_s: drift time, s (whole control ticks).

    Returns:
        The :class:`DriftResult` (velocity averaged over the last second).
    """
    z0 = physics.depth_m()
    physics.set_tail_beat_frequency_hz(0.0)
    release_in_current(physics, field)
    tick = physics.control_tick_s
    n = round(duration_s / tick)
    last = max(1, round(1.0 / tick))
    p_mark = None
    for k in range(n):
        if k == n - last:
            p_mark, t_mark = physics.position_world(), physics.time_s()
        physics.advance(tick)
    vel = (physics.position_world() - p_mark) / (physics.time_s() - t_mark)
    cur = physics.current_at_vehicle_world()
    return DriftResult(
        duration_s,
        cur,
        vel,
        float(np.linalg.norm(vel - cur) / max(np.linalg.norm(cur), 1e-12)),
        physics.depth_m() - z0,
    )


@dataclass(frozen=True)
class CurrentSwimResult:
    """A straight swim in a current compared with the same swim in still water.

    Attributes:
        ground_velocity_m_s: mean velocity over ground in the current, shape (3,), world.
        still_velocity_m_s: mean velocity over ground of the same swim in still water, shape (3,).
        mean_current_m_s: time mean of the current at the vehicle over the window, shape (3,).
        relative_error: |ground - (still + current)| / |ground|.
    """

    ground_velocity_m_s: NDArray[np.float64]
    still_velocity_m_s: NDArray[np.float64]
    mean_current_m_s: NDArray[np.float64]
    relative_error: float


def swim_in_current(
    make_physics,
    field: currents.CurrentField,
    frequency_hz: float,
    settle_s: float = 30.0,
    measure_s: float = 30.0,
) -> CurrentSwimResult:
    """Swim with a fixed tail-beat frequency and level fins, once in still water and once in a
    current, from the same state relative to the water (putting the vehicle in the current
    carries it with the water at its start point, :meth:`~bauv_sim.sea.Sea.immerse`);
    compare velocities over the same window.

    The fluid forces see only the velocity relative to the water, so in a uniform current the
    motion relative to the water is the same and ground velocity = still-water velocity + current;
    in a spatially varying current this holds as far as the current is uniform along the path.

    Args:
        make_physics: callable returning a fresh physics in the starting state.
        field: the current.
        frequency_hz: tail-beat frequency, Hz.
        settle_s: time before the window, s.
        measure_s: window, s.

    Returns:
        The :class:`CurrentSwimResult`.
    """
    results = []
    for sea in (Sea(), Sea(field)):
        phys = make_physics()
        sea.immerse(phys)
        phys.set_tail_beat_frequency_hz(frequency_hz)
        tick = phys.control_tick_s
        phys.advance(round(settle_s / tick) * tick)
        p0, t0 = phys.position_world(), phys.time_s()
        cur = np.zeros(3)
        n = round(measure_s / tick)
        for _ in range(n):
            phys.advance(tick)
            cur += phys.current_at_vehicle_world()
        results.append(((phys.position_world() - p0) / (phys.time_s() - t0), cur / n))
    (still, _), (ground, cur) = results
    err = float(np.linalg.norm(ground - (still + cur)) / max(np.linalg.norm(ground), 1e-12))
    return CurrentSwimResult(ground, still, cur, err)
