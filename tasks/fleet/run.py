"""One block of ``fleet/survey``: n way-point missions flown together on the manoeuvring model,
every run with its own sensors, EKF, guidance and autopilot, all vectorised over the block.

At every control tick, for all runs at once (the order of a mission's tick,
:meth:`tasks.closed_loop.world.MissionWorld._tick`):

1. the truth of :class:`bauv_sim.manoeuvring.ManoeuvringWorld` (attitude with the tail beat's
   oscillation, rates, depth, velocity through water) and the sea's current at each vehicle;
2. the devices due this tick (:mod:`bauv_sim.sensors`: compass every tick, log and pressure
   every ``period_s``, a USBL fix every ``period_s`` that reaches the vehicle after its travel
   time and latency), each with its error model and each run's own streams (the streams of
   ``mission/survey``'s rig: ``("sensor", "compass", "heading")``, ...); the EM log's speed where
   it sees the water, else the speed table's speed at the commanded frequency (the odometry);
3. the navigator (:class:`nav.navigator.batch.BatchNavigator`): predict with heading and speed
   (not on the initial tick), the pressure depth when sampled, the fixes that arrived, each at
   its time of validity, gated;
4. guidance (:class:`nav.guidance_batch.BatchWaypointGuidance`) on each run's estimate and its
   worst horizontal sigma, and the autopilot (:class:`bauv_sim.autopilot_batch.BatchAutopilot`)
   on what the vehicle measures;
5. the commands into the model, which then steps one tick.

A run ends when its guidance is done (its numbers are frozen there; the block steps on until
every run is done or ``timing.max_duration_s``). Each run draws from its own streams: a run's
numbers do not depend on the block it is in or on the worker that flew it (tested: a batch of n
equals n batches of one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from bauv_sim import rng as rng_mod
from bauv_sim.autopilot_batch import BatchAutopilot, BatchMeasured
from bauv_sim.currents import make_current
from bauv_sim.frames import R_from_roll_pitch_heading, wrap_2pi
from bauv_sim.manoeuvring import model as mm
from bauv_sim.sensors.batch import BatchUsbl, PrefetchedErrors
from bauv_sim.sensors.compass import Compass
from bauv_sim.sensors.log import Log
from bauv_sim.sensors.pressure import Pressure
from bauv_sim.sensors.usbl import Usbl
from nav.ekf import adjugate_sym3
from nav.guidance import Waypoint
from nav.guidance_batch import BatchWaypointGuidance, horizontal_sigma_batch_m
from nav.models import CourseSpeedDepthMotion, DepthMeasurement, UsblMeasurement
from nav.navigator.batch import BatchNavigator
from tasks.closed_loop.navigation import initial_covariance
from tasks.core import store
from tasks.fleet.scenario import FleetScenario

Array = NDArray[np.float64]

OUTCOMES: dict[str, tuple[str, str]] = {
    "duration_s": ("s", "time the mission ended (guidance done, or timing.max_duration_s)"),
    "completed": ("bool", "guidance finished every leg before timing.max_duration_s"),
    "waypoints_reached": ("1", "legs ended reached by the estimate"),
    "waypoints_reached_by_truth": ("1", "way-points whose circle the truth entered"),
    "max_closest_distance_m": ("m", "largest closest true approach to a way-point"),
    "mean_closest_distance_m": ("m", "mean closest true approach to the way-points"),
    "ekf_mean_error_m": ("m", "EKF horizontal error, mean over the ticks"),
    "ekf_max_error_m": ("m", "EKF horizontal error, largest"),
    "ekf_final_error_m": ("m", "EKF horizontal error at the end"),
    "dr_mean_error_m": ("m", "dead reckoning's horizontal error, mean over the ticks"),
    "dr_max_error_m": ("m", "dead reckoning's horizontal error, largest"),
    "dr_final_error_m": ("m", "dead reckoning's horizontal error at the end"),
    "nees_mean": ("1", "EKF position NEES (3 dof), mean over the ticks"),
    "nees_in_95": ("1", "fraction of ticks whose NEES is inside the 95 % chi-square interval"),
    "usbl_fixes": ("1", "USBL fixes that reached the vehicle"),
    "usbl_rejected": ("1", "of which the gate rejected"),
    "energy_j": ("J", "motor energy (mean mechanical power x time)"),
    "mean_power_w": ("W", "mean motor power"),
}
"""Per-run outcomes: name -> (unit, description)."""

TRACK_COLUMNS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "truth_pos": ("m", "true position (east, north, up), world", ("x", "y", "z")),
    "ekf_pos": ("m", "EKF position estimate, world", ("x", "y", "z")),
    "ekf_sigma_h": ("m", "EKF standard deviation, worst horizontal direction", ()),
    "dr_pos": ("m", "dead-reckoned position, world", ("x", "y", "z")),
    "heading": ("rad", "true heading (with the beat), clockwise from north", ()),
    "waypoint": ("1", "way-point being approached (= number of way-points when done)", ()),
}
"""Decimated per-run columns: name -> (unit, description, components)."""

NEES_95 = (0.2158, 9.3484)
"""The 2.5 % and 97.5 % quantiles of chi-square with 3 degrees of freedom."""


@store.plain_data("fleet.FleetBlock")
@dataclass(frozen=True)
class FleetBlock:
    """A block's result (plain data, kept by the runner).

    Attributes:
        runs: run indices, shape (b,).
        outcomes: :data:`OUTCOMES` by name, each shape (b,).
        reached: whether each leg ended reached by the estimate, shape (b, k).
        closest_m: closest true horizontal approach to each way-point, shape (b, k), m.
        leg_end_s: when each leg ended, shape (b, k), s (NaN: it never ended).
        t_s: times of the decimated tracks, shape (T,), s.
        tracks: :data:`TRACK_COLUMNS` by name, each shape (T, b, ...) (empty without tracks).
        failed: one line per failed run (``"run 3: ..."``).
    """

    runs: NDArray[np.int64]
    outcomes: dict
    reached: NDArray[np.bool_]
    closest_m: Array
    leg_end_s: Array
    t_s: Array
    tracks: dict = field(default_factory=dict)
    failed: tuple = ()


def frequency_for_speed(coef: mm.ManoeuvringCoefficients):
    """The speed table's feed-forward: speed through water (m/s, shape (n,)) -> tail-beat
    frequency (Hz), the inverse of the model's steady straight swim."""
    s, f = coef.straight_speed_m_s, coef.power_frequency_hz
    return lambda v: np.interp(v, s, f)


def fly_block(scn: FleetScenario, seed: int, runs: tuple[int, ...]) -> FleetBlock:
    """Fly the runs ``runs`` of a batch together (module docstring).

    Args:
        scn: the scenario.
        seed: the batch seed.
        runs: run indices of the block.

    Returns:
        The block's result.
    """
    n = len(runs)
    coef = mm.load_coefficients()
    tim = scn.timing
    tick = tim.control_tick_s
    world = mm.ManoeuvringWorld(n, coef, tick_s=tick, substeps=tim.substeps)
    st = scn.start
    e0, n0 = scn.start_east_north_m()
    d = rng_mod.RunStreams(seed, runs, "fleet", "start").draw("standard_normal", 3)
    pos0 = np.stack(
        [
            e0 + st.position_sigma_m * d[:, 0],
            n0 + st.position_sigma_m * d[:, 1],
            np.full(n, -st.depth_m),
        ],
        axis=1,
    )
    head0 = math.radians(st.heading_deg) + math.radians(st.heading_sigma_deg) * d[:, 2]
    world.set_pose(pos0, np.stack([0 * head0, 0 * head0, head0], 1), np.array([st.speed_m_s, 0, 0]))
    current = make_current(scn.current)
    # sensors: the survey rig's device streams
    s = scn.sensors
    compass = PrefetchedErrors(Compass(s.compass, seed, runs)._err, s.compass.period_s)
    log = PrefetchedErrors(Log(s.log, seed, runs)._err, s.log.period_s)
    pressure = PrefetchedErrors(Pressure(s.pressure, seed, runs)._err, s.pressure.period_s)
    transceiver = np.array([0.0, 0.0, -scn.transceiver_depth_m])
    usbl = BatchUsbl(Usbl(s.usbl, transceiver, seed, runs))
    arm = np.asarray(s.usbl.transponder_body_m, dtype=float)
    every = {k: round(getattr(s, k).period_s / tick) for k in ("log", "pressure", "usbl")}
    needs_course = s.compass.heading.to_model().needs_reference()
    # navigation
    nc = scn.navigation
    P0 = initial_covariance(nc)
    e_init = rng_mod.RunStreams(seed, runs, "initial").draw("standard_normal", 3) @ np.sqrt(P0)
    motion = CourseSpeedDepthMotion(
        math.radians(nc.sigma_heading_deg), nc.sigma_speed_m_s, nc.sigma_vertical_m_per_tick
    )
    nav = BatchNavigator(
        n,
        0.0,
        pos0 + e_init,
        P0,
        motion,
        tick,
        nc.history_s,
        nc.gate_probability if nc.gate_enabled else None,
        nc.current_sigma0_m_s if nc.estimate_current else None,
        nc.current_walk_m_s_per_sqrt_s,
        nc.max_consecutive_rejections or None,
    )
    depth_model = DepthMeasurement(nc.sigma_depth_m)
    usbl_sig = (
        nc.sigma_range_m, math.radians(nc.sigma_azimuth_deg), math.radians(nc.sigma_elevation_deg)
    )  # fmt: skip
    # guidance and autopilot
    g = scn.guidance
    pts = scn.waypoints()
    wps = [Waypoint(e, nn, scn.plan.depth_m, scn.plan.acceptance_radius_m) for e, nn in pts]
    guide = BatchWaypointGuidance(
        wps, n, g.speed_m_s, g.max_leg_time_s, g.reach_probability, g.min_reach_m
    )
    ff = frequency_for_speed(coef)
    pilot = BatchAutopilot(scn.autopilot, n, ff)
    wp_en = np.array(pts)  # (k, 2)
    # accumulators
    active = np.ones(n, dtype=bool)
    ticks = np.zeros(n)
    acc = {k: np.zeros(n) for k in ("ekf", "dr", "nees", "nees_in", "energy", "fixes", "rej")}
    mx = {k: np.zeros(n) for k in ("ekf", "dr")}
    final = {k: np.zeros(n) for k in ("ekf", "dr")}
    duration = np.full(n, tim.max_duration_s)
    closest = np.full((n, len(pts)), np.inf)
    rec_every = round(tim.record_every_s / tick)
    rec_t: list[float] = []
    rec: dict[str, list[Array]] = {k: [] for k in TRACK_COLUMNS}
    # held sensor values
    speed_log = np.zeros(n)
    log_ok = np.zeros(n, dtype=bool)
    speed_odo = np.zeros(n)
    depth_meas = np.zeros(n)
    pending_z = np.zeros((n, 3))
    pending_valid = np.zeros(n)
    pending_arrival = np.full(n, np.inf)
    pending_R = np.zeros((n, 3, 3))
    freq_cmd = np.zeros(n)
    k_max = round(tim.max_duration_s / tick)
    for k in range(k_max + 1):
        t = k * tick
        initial = k == 0
        # 1. truth
        pos = world.position_world_m
        world.set_current_world(current.velocity_world(t, pos))
        rph = world.roll_pitch_heading()
        w_body = world.angular_velocity_body()
        v_water = world.velocity_through_water_world()
        roll, pitch, heading = rph[:, 0], rph[:, 1], rph[:, 2]
        cp = np.cos(pitch)
        u_fwd = (
            cp * np.sin(heading) * v_water[:, 0]
            + cp * np.cos(heading) * v_water[:, 1]
            + np.sin(pitch) * v_water[:, 2]
        )
        depth_true = -pos[:, 2]
        # 2. devices
        course = None
        if needs_course:
            v = world.velocity_world()
            course = np.arctan2(v[:, 0], v[:, 1]) % (2 * math.pi)
        heading_meas = wrap_2pi(compass.measure(heading, t, course)[0])
        if k % every["log"] == 0:
            speed_log, log_ok = log.measure(u_fwd, t)
            log_ok = log_ok & (np.abs(u_fwd) >= s.log.min_speed_m_s)
            speed_odo = np.interp(freq_cmd, coef.power_frequency_hz, coef.straight_speed_m_s)
        sampled_depth = k % every["pressure"] == 0
        if sampled_depth:
            depth_meas = pressure.measure(depth_true, t)[0]
        if not initial and k % every["usbl"] == 0:
            R = None
            tp = pos
            if arm.any():
                R = R_from_roll_pitch_heading(roll, pitch, heading)
                tp = pos + R @ arm
            z, prod, t_arr = usbl.measure(t, tp)
            new = prod & active
            pending_z = np.where(new[:, None], z, pending_z)
            pending_valid = np.where(new, t, pending_valid)
            pending_arrival = np.where(new, t_arr, pending_arrival)
            if R is not None:
                pending_R = np.where(new[:, None, None], R, pending_R)
        arrived = pending_arrival <= t + 1e-9
        speed = np.where(log_ok, speed_log, speed_odo)
        # 3. navigation
        if not initial:
            nav.predict(t, heading_meas, speed, 0.0)
        if sampled_depth:
            nav.fuse(depth_model, depth_meas[:, None], np.ones(n, dtype=bool))
        if arrived.any():
            trans = np.broadcast_to(transceiver, (n, 3))
            if arm.any():
                trans = transceiver - np.einsum("nij,j->ni", pending_R, arm)
            model = UsblMeasurement(np.ascontiguousarray(trans), *usbl_sig)
            _, _applied, rejected = nav.fuse(model, pending_z, arrived, pending_valid, "usbl")
            acc["fixes"] += arrived & active
            acc["rej"] += rejected & active
            pending_arrival = np.where(arrived, np.inf, pending_arrival)
        # 4. guidance and autopilot
        x = nav.x
        P = nav.P
        sigma_h = horizontal_sigma_batch_m(P)
        course_cmd, depth_cmd, speed_cmd = guide.step(t, x[:, :3], sigma_h)
        # the run's metrics up to the tick its mission ends (the scalar world's last tick)
        e_ekf = np.hypot(x[:, 0] - pos[:, 0], x[:, 1] - pos[:, 1])
        dr = nav.dr_position
        e_dr = np.hypot(dr[:, 0] - pos[:, 0], dr[:, 1] - pos[:, 1])
        err = x[:, :3] - pos
        (c00, c01, c02, c11, c12, c22), det = adjugate_sym3(
            P[:, 0, 0], P[:, 0, 1], P[:, 0, 2], P[:, 1, 1], P[:, 1, 2], P[:, 2, 2]
        )
        ex, ey, ez = err[:, 0], err[:, 1], err[:, 2]
        nees = (
            c00 * ex * ex + c11 * ey * ey + c22 * ez * ez
            + 2 * (c01 * ex * ey + c02 * ex * ez + c12 * ey * ez)
        ) / det  # fmt: skip
        a = active.astype(float)
        ticks += a
        acc["ekf"] += a * e_ekf
        acc["dr"] += a * e_dr
        acc["nees"] += a * nees
        acc["nees_in"] += a * ((nees >= NEES_95[0]) & (nees <= NEES_95[1]))
        mx["ekf"] = np.where(active, np.maximum(mx["ekf"], e_ekf), mx["ekf"])
        mx["dr"] = np.where(active, np.maximum(mx["dr"], e_dr), mx["dr"])
        final["ekf"] = np.where(active, e_ekf, final["ekf"])
        final["dr"] = np.where(active, e_dr, final["dr"])
        dwp = np.hypot(pos[:, None, 0] - wp_en[None, :, 0], pos[:, None, 1] - wp_en[None, :, 1])
        closest = np.where(active[:, None], np.minimum(closest, dwp), closest)
        if k % rec_every == 0 and scn.report.tracks:
            rec_t.append(t)
            rec["truth_pos"].append(pos.copy())
            rec["ekf_pos"].append(x[:, :3].copy())
            rec["ekf_sigma_h"].append(sigma_h)
            rec["dr_pos"].append(dr.copy())
            rec["heading"].append(heading.copy())
            rec["waypoint"].append(guide.index.astype(np.int32))
        ended = active & guide.done
        duration = np.where(ended, t, duration)
        active = active & ~guide.done
        if not active.any() or k == k_max:
            break
        m = BatchMeasured(
            heading_meas, -w_body[:, 2], depth_meas, pitch, -w_body[:, 1], roll, w_body[:, 0], speed
        )
        cmd = pilot.step(tick, course_cmd, depth_cmd, speed_cmd, m)
        freq_cmd = cmd.tail_beat_hz
        world.command(
            freq_cmd, cmd.tail_bias_rad, cmd.fin_port_rad, cmd.fin_starboard_rad, cmd.battery_m
        )
        acc["energy"] += a * world.motor_power_w() * tick
        world.step()
    nt = np.maximum(ticks, 1.0)
    reached = guide.reached
    out = {
        "duration_s": duration,
        "completed": (~active).astype(float),
        "waypoints_reached": reached.sum(axis=1).astype(float),
        "waypoints_reached_by_truth": (closest <= scn.plan.acceptance_radius_m)
        .sum(axis=1)
        .astype(float),
        "max_closest_distance_m": closest.max(axis=1),
        "mean_closest_distance_m": closest.mean(axis=1),
        "ekf_mean_error_m": acc["ekf"] / nt,
        "ekf_max_error_m": mx["ekf"],
        "ekf_final_error_m": final["ekf"],
        "dr_mean_error_m": acc["dr"] / nt,
        "dr_max_error_m": mx["dr"],
        "dr_final_error_m": final["dr"],
        "nees_mean": acc["nees"] / nt,
        "nees_in_95": acc["nees_in"] / nt,
        "usbl_fixes": acc["fixes"],
        "usbl_rejected": acc["rej"],
        "energy_j": acc["energy"],
        "mean_power_w": acc["energy"] / np.maximum(duration, tick),
    }
    tracks = {}
    if rec_t:
        tracks = {k: np.stack(v) for k, v in rec.items()}
    return FleetBlock(
        np.asarray(runs, dtype=np.int64),
        out,
        reached.copy(),
        closest,
        guide.leg_end_s.copy(),
        np.asarray(rec_t),
        tracks,
    )
