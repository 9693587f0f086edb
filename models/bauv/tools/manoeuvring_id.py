"""Identify the BAUV's manoeuvring model from the full MuJoCo vehicle and validate it (issue 27).

Writes ``models/bauv/manoeuvring.json`` (read by :mod:`bauv_sim.manoeuvring`) and the table of
the section "12. Manoeuvring model" of ``models/bauv/README.md``.

Identification, all on the full model at the missions' 4 ms step:

1. **Inertia and restoring**: the free joint's 6 x 6 block of MuJoCo's mass matrix with the
   tail straight (the plugin adds its added mass ``M_A`` there), split into ``M_RB`` and ``M_A``
   with the plugin's own ``M_A``; weight, buoyancy and their centres from the facade's
   ``hydrostatics``.
2. **Hull (captive tests)**: the vehicle held level with a prescribed velocity relative to the
   water (``hydro_body.tow``: MuJoCo's ellipsoid drag plus every term of the plugin, tail
   straight, fins level) at random states in the box of :data:`HULL_BOX`; the six components of
   the fluid force about the hull origin are fitted by least squares to
   :data:`bauv_sim.manoeuvring.model.HULL_TERMS`, and checked on other random states.
3. **Fins (captive tests)**: each fin set to an angle, the change of that force against level
   fins: at random states of the hull's box (heave, pitch and roll rate change the fin's angle of
   attack) fitted to :data:`~bauv_sim.manoeuvring.model.FIN_FLOW_TERMS` (the plugin's plate
   terms in the local flow at the fin's centre, which the model uses), and in straight flight
   to :data:`~bauv_sim.manoeuvring.model.FIN_TERMS` (kept for data identified before).
4. **Tail (free runs)**: straight swims at several frequencies (steady speed, motor power, the
   beat's heading and roll oscillation fitted as a sinusoid at the beat frequency), accelerations
   from rest at two frequencies (thrust = inertia x acceleration - hull drag, beat by beat),
   steady glides after open-loop fin steps (the beat's share in heave,
   :data:`~bauv_sim.manoeuvring.model.TAIL_HEAVE_TERMS`: what the beat-averaged rest of the model
   misses there) and steady turns at several biases and two frequencies (the tail's mean force is
   what balances the rest of the model in the turn); fitted to
   :data:`~bauv_sim.manoeuvring.model.TAIL_TERMS`.

Validation (other manoeuvres than those identified on): the timestep table's quantities (cruise
speed and power, turn rate and radius at +-10 and +-20 deg of bias, the autopilot's 5 m depth
step, the +0.2 rad fin step) and 0.3 m/s current steps along and across the track, full model
against the manoeuvring model, with the timestep table's thresholds; then further autopilot depth
steps (:data:`EXTRA_DEPTH_STEPS`: up and down, 2 and 5 m, at 0.6 and 1 m/s).

Run from the repository root (about 3 minutes)::

    python models/bauv/tools/manoeuvring_id.py             # identify, validate, write both files
    python models/bauv/tools/manoeuvring_id.py --validate  # validate the stored data only
"""

from __future__ import annotations

import argparse
import json
import math
import re
import time
from dataclasses import dataclass
from pathlib import Path

import hydro_body
import numpy as np
from timestep import DEPTH_STEP_AT_S, THRESHOLDS, depth_step, depth_step_metrics, rise_time_s

from bauv_sim import manoeuvres
from bauv_sim.manoeuvring import model as mm
from bauv_sim.manoeuvring import trials
from bauv_sim.physics import BauvPhysics

ROOT = Path(__file__).resolve().parents[3]
README = ROOT / "models" / "bauv" / "README.md"
TIMESTEP_S = 0.004
MIRROR = True
"""Fit the hull on every captive state and its mirror image."""
"""The full model's step for identification and validation, s (the missions' preset)."""

HULL_BOX = {"u": (-0.2, 1.8), "v": (-0.25, 0.25), "w": (-0.25, 0.25), "p": (-0.3, 0.3),
            "q": (-0.2, 0.2), "r": (-0.35, 0.35)}  # fmt: skip
"""Ranges of the captive tests' relative velocity, m/s and rad/s (body FLU)."""

ID_FREQUENCIES_HZ = (0.3, 0.45, 0.61, 0.8, 1.0, 1.3)
"""Straight swims for the thrust, power and the beat's oscillation, Hz."""

ID_TURNS = (
    *((0.61, b) for b in (2.5, -2.5, 5.0, -5.0, 7.5, -7.5, 12.5, -12.5, 15.0, -15.0, 17.5, -17.5)),
    *((0.61, b) for b in (20.8, -20.8)),
    *((0.9, b) for b in (10.0, -10.0, 20.0, -20.0)),
)
"""(frequency Hz, bias deg) of the identification turns; the validation turns are at the cruise
frequency with +-10 and +-20 deg."""


def scene(speed_m_s: float = 1.0, heading_deg: float = 0.0) -> BauvPhysics:
    """The open-water scene at the identification step."""
    p = manoeuvres.open_water_scene(speed_m_s=speed_m_s, heading_deg=heading_deg)
    p.set_timestep(TIMESTEP_S)
    return p


# --------------------------------------------------------------------------------------------
# 1-3: captive identification


def rigid_part(ph: BauvPhysics) -> dict:
    """Mass matrix split, CG, inertia about the origin, weight, buoyancy, CB (body FLU)."""
    import mujoco

    ph.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, math.pi / 2], [0.0, 0.0, 0.0])  # R = identity
    m, d = ph.model.ptr, ph.data.ptr
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    M = full[:6, :6]
    M = 0.5 * (M + M.T)
    MA = ph.added_mass_matrix()
    MRB = M - 0.5 * (MA + MA.T)
    mass = float(MRB[0, 0])
    S = MRB[3:, :3] / mass
    hs = ph.hydrostatics()
    origin = ph.position_world()
    bat = m.body_mass[m.body("bauv/battery").id] if _has_body(m, "bauv/battery") else 6.0
    return {
        "mass_matrix": M,
        "rigid_mass_kg": mass,
        "cg_body_m": np.array([S[2, 1], S[0, 2], S[1, 0]]),
        "inertia_origin_kg_m2": MRB[3:, 3:],
        "weight_n": hs.weight_n,
        "buoyancy_n": hs.buoyancy_n,
        "cb_body_m": hs.cb_world_m - origin,
        "battery_kg": float(bat),
    }


def _has_body(m, name: str) -> bool:
    try:
        m.body(name)
        return True
    except KeyError:
        return False


def tow_nu(ph: BauvPhysics, nu: np.ndarray) -> np.ndarray:
    """Fluid force (N) and moment about the origin (N m), body FLU, at relative velocity nu."""
    f, mo = hydro_body.tow(ph, nu[:3], tuple(nu[3:]))
    return np.r_[f, mo]


def sample_box(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random relative velocities in :data:`HULL_BOX`, shape (n, 6): a quarter anywhere in the
    box, a quarter near straight flight (all but u scaled by 0.2), a quarter in the horizontal
    plane (w = p = q = 0) and a quarter in the vertical plane (v = p = r = 0), where the
    manoeuvres live."""
    lo = np.array([b[0] for b in HULL_BOX.values()])
    hi = np.array([b[1] for b in HULL_BOX.values()])
    x = rng.uniform(lo, hi, size=(n, 6))
    k = n // 4
    x[k : 2 * k, 1:] *= 0.2
    x[2 * k : 3 * k, [2, 3, 4]] = 0.0
    x[3 * k :, [1, 3, 5]] = 0.0
    return rng.permutation(x)


def fit_hull(ph: BauvPhysics, rng: np.random.Generator, n_fit: int = 3000, n_check: int = 600):
    """Hull coefficients (len(HULL_TERMS), 6) and the held-out relative RMS error per component.

    Two stages: the straight-flight terms from tows at 61 surges in the box, then the rest from
    random states, fitted to what the first stage leaves."""
    k = len(mm.HULL_LINE_TERMS)
    u = np.linspace(HULL_BOX["u"][0], HULL_BOX["u"][1], 61)
    line = np.c_[u, np.zeros((u.size, 5))]
    F_line = np.array([tow_nu(ph, x) for x in line])
    c_line, *_ = np.linalg.lstsq(mm.hull_regressors(line)[:, :k], F_line, rcond=None)
    X = sample_box(rng, n_fit + n_check)
    F = np.array([tow_nu(ph, x) for x in X])
    if MIRROR:
        # the port-starboard mirror image of every state: v, p, r and Y, K, N change sign; the
        # fit then sees both and its errors are symmetric (the tail's even terms keep the
        # linkage's difference)
        flip = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0])
        Xm = X[:n_fit] * flip
        Fm = np.array([tow_nu(ph, x) for x in Xm])
        X = np.vstack([X[:n_fit], Xm, X[n_fit:]])
        F = np.vstack([F[:n_fit], Fm, F[n_fit:]])
        n_fit *= 2
    A = mm.hull_regressors(X)
    rest = F - A[:, :k] @ c_line
    c_rest, *_ = np.linalg.lstsq(A[:n_fit, k:], rest[:n_fit], rcond=None)
    coef = np.vstack([c_line, c_rest])
    res = A[n_fit:] @ coef - F[n_fit:]
    rel = np.sqrt(np.mean(res**2, axis=0)) / np.sqrt(np.mean(F[n_fit:] ** 2, axis=0))
    line_err = np.max(np.abs(mm.hull_regressors(line) @ coef - F_line)[:, 0])
    print(f"hull: straight-flight X error at most {line_err:.3g} N")
    return coef, rel


def fit_fin(ph: BauvPhysics, rng: np.random.Generator, joint: str, n: int = 300):
    """One fin's coefficients (3, 6) from captive tows at random speed and angle."""
    m, d = ph.model.ptr, ph.data.ptr
    adr = m.joint(joint).qposadr[0]
    u = rng.uniform(0.2, 1.8, n)
    a = rng.uniform(-0.5, 0.5, n)
    dF = []
    for ui, ai in zip(u, a, strict=True):
        nu = np.array([ui, 0, 0, 0, 0, 0.0])
        d.qpos[adr] = 0.0
        f0 = tow_nu(ph, nu)
        d.qpos[adr] = ai
        dF.append(tow_nu(ph, nu) - f0)
    d.qpos[adr] = 0.0
    A = mm.fin_regressors(u, a)
    dF = np.array(dF)
    coef, *_ = np.linalg.lstsq(A, dF, rcond=None)
    res = A @ coef - dF
    rel = np.sqrt(np.mean(res**2, axis=0)) / np.maximum(np.sqrt(np.mean(dF**2, axis=0)), 1e-12)
    return coef, rel


def fin_position(ph: BauvPhysics, geom: str) -> np.ndarray:
    """A fin's centre (its fluid plate's, the fin level), body FLU from the hull origin, m."""
    tow_nu(ph, np.zeros(6))  # level, at rest: the kinematics of the tows' pose
    g = ph.model.ptr.geom(geom).id
    return ph.R_world_from_body().T @ (ph.data.ptr.geom_xpos[g] - ph.position_world())


def fit_fin_flow(
    ph: BauvPhysics, rng: np.random.Generator, joint: str, geom: str, n: int = 1200,
    n_check: int = 300,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """One fin in the local flow: coefficients (8, 6) of
    :data:`~bauv_sim.manoeuvring.model.FIN_FLOW_TERMS`, the held-out relative RMS error per
    component and the fin's centre (body FLU, m).

    Captive tows at random relative velocities of the hull's box (:func:`sample_box`: heave,
    pitch and roll rates change the fin's angle of attack; in the depth step the fins sit at
    -25 deg while the vehicle sinks at 0.2 m/s, where the fin at -25 deg sees about -11 deg)
    and random fin angles in the fins' range; the change of the fluid force against the level
    fin at the same velocity."""
    m, d = ph.model.ptr, ph.data.ptr
    adr = m.joint(joint).qposadr[0]
    r_fin = fin_position(ph, geom)
    X = sample_box(rng, n + n_check)
    a = rng.uniform(-trials.FIN_LIMIT_RAD, trials.FIN_LIMIT_RAD, n + n_check)
    dF = []
    for nu, ai in zip(X, a, strict=True):
        d.qpos[adr] = 0.0
        f0 = tow_nu(ph, nu)
        d.qpos[adr] = ai
        dF.append(tow_nu(ph, nu) - f0)
    d.qpos[adr] = 0.0
    dF = np.array(dF)
    A = mm.fin_flow_regressors(X, a, r_fin)
    coef, *_ = np.linalg.lstsq(A[:n], dF[:n], rcond=None)
    res = A[n:] @ coef - dF[n:]
    rms = np.sqrt(np.mean(dF[n:] ** 2, axis=0))
    rel = np.sqrt(np.mean(res**2, axis=0)) / np.maximum(rms, 1e-12)
    rel[rms < 1e-6] = 0.0  # a component the fin does not produce (Y: zero to rounding)
    return coef, rel, r_fin


# --------------------------------------------------------------------------------------------
# 4: the tail, from free runs


def _sinusoid(t: np.ndarray, y: np.ndarray, omega: float) -> tuple[float, float]:
    """Amplitude and phase of y = A sin(omega t + phase) + a + b t (least squares)."""
    A = np.c_[np.sin(omega * t), np.cos(omega * t), np.ones_like(t), t]
    c, *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(math.hypot(c[0], c[1])), float(math.atan2(c[1], c[0]))


@dataclass(frozen=True)
class Swim:
    """A steady straight swim of the full model."""

    frequency_hz: float
    speed_m_s: float
    power_w: float
    yaw_amplitude_rad: float
    roll_amplitude_rad: float
    roll_phase_rad: float
    fin_rad: float
    pitch_rad: float
    nu: np.ndarray  # (6,) mean relative body velocity over five beats


def full_swim(f: float) -> Swim:
    """Straight swim (depth held) and the beat's heading and roll oscillation."""
    ph = scene()
    s = manoeuvres.straight_swim(ph, f)
    hold = manoeuvres.DepthHold(20.0)
    t, head, roll, nus = [], [], [], []
    sub = 5
    n = round(5.0 / f / (sub * TIMESTEP_S))  # five beats
    for k in range(n):
        if k % (ph.steps_per_tick // sub) == 0:
            a = hold.fins_rad(ph)
            ph.set_lateral_fins_rad(a, a)
        ph.step(sub)
        rph = ph.roll_pitch_heading()
        t.append(ph.time_s())
        head.append(rph[2])
        roll.append(rph[0])
        v = ph.R_world_from_body().T @ ph.velocity_through_water_world()
        nus.append(np.r_[v, ph.angular_velocity_body()])
    t = np.array(t)
    ah, phh = _sinusoid(t, np.unwrap(head), 2 * math.pi * f)
    ar, phr = _sinusoid(t, np.array(roll), 2 * math.pi * f)
    return Swim(
        f, s.speed_through_water_m_s, s.mean_motor_power_w, ah, ar, phr - phh,
        s.mean_fin_rad, s.mean_pitch_rad, np.mean(nus, axis=0),
    )  # fmt: skip


def full_accel(f: float, seconds: float = 40.0) -> np.ndarray:
    """Acceleration from rest at frequency f: rows (f, u, du/dt) per beat (beat means)."""
    ph = scene(speed_m_s=0.0)
    ph.set_tail_beat_frequency_hz(f)
    hold = manoeuvres.DepthHold(20.0)
    T = 1.0 / f
    steps = round(T / TIMESTEP_S)
    t, p = [ph.time_s()], [ph.position_world()]
    done = 0
    while ph.time_s() < seconds:
        a = hold.fins_rad(ph)
        ph.set_lateral_fins_rad(a, a)
        k = min(ph.steps_per_tick, steps - done)
        ph.step(k)
        done += k
        if done >= steps:
            done = 0
            t.append(ph.time_s())
            p.append(ph.position_world())
    t, p = np.array(t), np.array(p)
    u = np.diff(p[:, 1]) / np.diff(t)  # along the heading (north): the beat's sway drops out
    tm = 0.5 * (t[1:] + t[:-1])
    du = np.gradient(u, tm)
    keep = slice(1, -1)  # the first beat starts the tail; the ends' gradients are one-sided
    return np.c_[np.full(u[keep].size, f), u[keep], du[keep]]


@dataclass(frozen=True)
class Turn:
    """Beat-averaged steady turn of the full model (second half of 60 s)."""

    frequency_hz: float
    bias_rad: float
    nu: np.ndarray  # (6,)
    roll_pitch_heading: np.ndarray  # (3,)
    fin_rad: float


def full_turn(f: float, bias_deg: float) -> Turn:
    """The turn of :func:`bauv_sim.manoeuvres.heading_change`, with body velocities logged."""
    ph = scene()
    hold = manoeuvres.DepthHold(ph.depth_m())
    ph.set_tail_beat_frequency_hz(f)
    tick = ph.control_tick_s
    rows = []
    for k in range(round(90.0 / tick)):
        if k == round(30.0 / tick):
            ph.set_tail_bias_rad(math.radians(bias_deg))
        a = hold.fins_rad(ph)
        ph.set_lateral_fins_rad(a, a)
        ph.advance(tick)
        if k >= round(60.0 / tick):
            v = ph.R_world_from_body().T @ ph.velocity_through_water_world()
            rph = ph.roll_pitch_heading()
            rows.append(np.r_[v, ph.angular_velocity_body(), rph[:2], a, ph.time_s(), rph[2]])
    rows = np.array(rows)
    r = np.mean(rows, axis=0)
    # the yaw rate the beat-averaged kinematics must carry is the heading's mean rate (what a
    # compass and the turn-rate measurement see), not the mean body rate: the beat's roll and
    # pitch-rate oscillations rectify (mean of sin(roll) q), about 4 % of the rate at 10 deg
    heading_rate = float(np.polyfit(rows[:, 9], np.unwrap(rows[:, 10]), 1)[0])
    roll, pitch = r[6], r[7]
    psi_dot = -heading_rate  # yaw about world z (up) is minus the clockwise heading's rate
    r[5] = (psi_dot * math.cos(pitch) - math.sin(roll) * r[4]) / math.cos(roll)
    return Turn(f, math.radians(bias_deg), r[:6], np.r_[r[6:8], 0.0], float(r[8]))


ID_GLIDES = tuple((f, a) for f in (0.61, 0.75) for a in (-0.35, -0.25, -0.1, 0.1, 0.3))
"""(frequency Hz, fin angle rad) of the identification's open-loop fin steps; the validation's
is +0.2 rad at the cruise frequency (and the autopilot's depth step)."""


@dataclass(frozen=True)
class Glide:
    """The steady climb or dive of the full model after an open-loop fin step (beat means)."""

    frequency_hz: float
    fin_rad: float
    nu: np.ndarray  # (6,) mean relative body velocity
    nu_dot: np.ndarray  # (6,) its mean rate (the swim is close to, not at, a steady state)
    roll_pitch_heading: np.ndarray  # (3,)


def full_glide(f: float, fin_rad: float, approach_s: float = 30.0, step_s: float = 40.0) -> Glide:
    """As :func:`bauv_sim.manoeuvres.depth_change` (level fins, then both fins at ``fin_rad``,
    open loop), longer: the means over the last 20 s of ``step_s``."""
    ph = scene()
    ph.set_tail_beat_frequency_hz(f)
    tick = ph.control_tick_s
    ph.advance(round(approach_s / tick) * tick)
    ph.set_lateral_fins_rad(fin_rad, fin_rad)
    rows = []
    for k in range(round(step_s / tick)):
        ph.advance(tick)
        if k >= round((step_s - 20.0) / tick):
            v = ph.R_world_from_body().T @ ph.velocity_through_water_world()
            rows.append(np.r_[ph.time_s(), v, ph.angular_velocity_body(), ph.roll_pitch_heading()])
    a = np.array(rows)
    slope = np.array([np.polyfit(a[:, 0], a[:, 1 + j], 1)[0] for j in range(6)])
    r = a[:, 1:].mean(axis=0)
    return Glide(f, fin_rad, r[:6], slope, np.r_[r[6:8], 0.0])


def fit_tail(coef: mm.ManoeuvringCoefficients, swims, accels, turns, glides=()) -> dict:
    """The tail's tables and coefficients: the force that balances the rest of the model in the
    straight swims (tables), the thrust's slope in surge from the accelerations, the beat's share
    in heave from the glides (what the rest of the model, beat-averaged, misses there: X even in
    the heave, Z and M odd), the bias's share from the turns (with the heave term in the
    rest)."""
    k0 = len(mm.TAIL_TERMS)
    fz = coef.power_frequency_hz
    zero = mm.ManoeuvringCoefficients(
        **{**coef.__dict__, "tail": np.zeros((k0, 6)), "tail_straight": np.zeros((fz.size, 6)),
           "thrust_speed_slope": 0.0, "tail_bias_per_uu": np.zeros((2, 6)),
           "tail_bias_grid_rad": np.array([-1.0, 1.0])}
    )  # fmt: skip
    world = mm.ManoeuvringWorld(1, zero)

    def rest(f, b, nu, rph, fin):
        world.frequency_hz[:] = f
        eul = np.array([[rph[0], -rph[1], 0.0]])
        return world.generalised_force(
            eul, nu[None, :], np.array([[fin, fin]]), np.array([b]), np.zeros(1)
        )[0]

    straight = np.zeros((fz.size, 6))
    for i, s in enumerate(swims, start=1):
        nu = s.nu
        straight[i] = -rest(s.frequency_hz, 0.0, nu, (0.0, s.pitch_rad), s.fin_rad)
    u_ss = coef.straight_speed_m_s
    mx = coef.mass_matrix[0, 0]

    def thrust_slope():
        x, y = [], []
        for f, u, du in accels:
            nu = np.array([u, 0, 0, 0, 0, 0.0])
            thrust = mx * du - rest(f, 0.0, nu, (0.0, 0.0), 0.0)[0]
            x.append(-f * (u - np.interp(f, fz, u_ss)))
            y.append(thrust - np.interp(f, fz, straight[:, 0]))
        return float(np.dot(x, y) / np.dot(x, x)), y

    def base_of(f, u):
        b = np.array([np.interp(f, fz, straight[:, j]) for j in range(6)])
        b[0] -= slope * f * (u - np.interp(f, fz, u_ss))
        return b

    slope, y = thrust_slope()
    heave = None
    if len(glides):
        # the heave term is the change off the straight swim at the same frequency (the swims
        # above 0.61 Hz hold depth with the nose up and heave -0.1 to -0.34 m/s: the table
        # balances the term there): glide residual = A(glide) c - A(swim at its f) c, with the
        # table's linear interpolation in f
        A_sw = np.zeros((fz.size, len(mm.TAIL_HEAVE_TERMS)))
        for i, s in enumerate(swims, start=1):
            A_sw[i] = mm.tail_heave_regressors(np.array([s.frequency_hz]), s.nu[2:3])[0]
        gw = np.array([(g.frequency_hz, g.nu[2]) for g in glides])
        Ag = mm.tail_heave_regressors(gw[:, 0], gw[:, 1]) - np.array(
            [[np.interp(f, fz, A_sw[:, k]) for k in range(A_sw.shape[1])] for f in gw[:, 0]]
        )
        tau_g = np.array(
            [coef.mass_matrix @ g.nu_dot - base_of(g.frequency_hz, g.nu[0])
             - rest(g.frequency_hz, 0.0, g.nu, g.roll_pitch_heading, g.fin_rad) for g in glides]
        )  # fmt: skip
        heave = np.zeros((Ag.shape[1], 6))
        for j, cols in ((0, [2]), (2, [0, 1]), (4, [0, 1])):  # X even in w; Z, M odd
            heave[cols, j], *_ = np.linalg.lstsq(Ag[:, cols], tau_g[:, j], rcond=None)
        print("glides (f, w; residual X Z M before, after the heave term):")
        print(np.c_[gw, tau_g[:, [0, 2, 4]], (tau_g - Ag @ heave)[:, [0, 2, 4]]].round(3))
        straight -= A_sw @ heave  # the table balances the term at the swims
        slope, y = thrust_slope()  # with the table's new X (the accelerations: heave ~ 0)
    print("accel samples (f, u, du/dt, thrust - table):")
    print(np.c_[accels, y].round(3)[::4])

    rows, tau = [], []
    for tr in turns:
        base = base_of(tr.frequency_hz, tr.nu[0])
        if heave is not None:
            base += (mm.tail_heave_regressors(np.array([tr.frequency_hz]), tr.nu[2:3]) @ heave)[0]
        rows.append((tr.frequency_hz, tr.bias_rad, tr.nu[0]))
        tau.append(
            -rest(tr.frequency_hz, tr.bias_rad, tr.nu, tr.roll_pitch_heading, tr.fin_rad) - base
        )
    rows, tau = np.array(rows), np.array(tau)
    A = mm.tail_regressors(rows[:, 0], rows[:, 1], rows[:, 2])
    # symmetry of the bias: the longitudinal components (X, Z, M) even in b, the lateral ones
    # (Y, K, N) odd, with one even term for the linkage's port-starboard difference (without
    # it the +20 deg turn was 4.5 % slow, the -20 deg one 3.0 % fast: the rest of the model is
    # not mirror-symmetric either)
    even = [1, 4]  # u|u| sin(b)^2, f^2 sin(b)^2
    lateral = [0, 1, 2, 3, 5]
    tail = np.zeros((A.shape[1], 6))
    for j in range(6):
        cols = even if j in (0, 2, 4) else lateral
        tail[cols, j], *_ = np.linalg.lstsq(A[:, cols], tau[:, j], rcond=None)
    print(
        f"tail: thrust slope {slope:.4g} N/(Hz m/s); turn fit residual rms "
        f"{np.sqrt(np.mean((A @ tail - tau) ** 2, axis=0)).round(3)}"
    )
    return {"tail": tail, "tail_straight": straight, "thrust_speed_slope": slope,
            "tail_heave": heave}  # fmt: skip


def identify(seed: int = 27) -> tuple[mm.ManoeuvringCoefficients, dict]:
    """Run the whole identification; the coefficients and a report of fit errors."""
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    ph = scene(speed_m_s=0.0)
    rigid = rigid_part(ph)
    hull, hull_err = fit_hull(ph, rng)
    fin_p, fin_p_err = fit_fin(ph, rng, "bauv/fin_port_pitch")
    fin_s, fin_s_err = fit_fin(ph, rng, "bauv/fin_starboard_pitch")
    flow_p, flow_p_err, r_p = fit_fin_flow(ph, rng, "bauv/fin_port_pitch", "bauv/fin_port_fluid")
    flow_s, flow_s_err, r_s = fit_fin_flow(
        ph, rng, "bauv/fin_starboard_pitch", "bauv/fin_starboard_fluid"
    )
    print(f"fins in the local flow: held-out rel. RMS {flow_p_err.round(4)}, {flow_s_err.round(4)}")
    print(f"captive tests: {time.perf_counter() - t0:.0f} s; hull fit rel. RMS {hull_err.round(3)}")
    swims = [full_swim(f) for f in ID_FREQUENCIES_HZ]
    for s in swims:
        print(
            f"swim {s.frequency_hz} Hz: speed {s.speed_m_s:.4f}, pitch "
            f"{math.degrees(s.pitch_rad):.2f} deg, fin {math.degrees(s.fin_rad):.2f} deg, "
            f"nu {s.nu.round(4)}"
        )
    accels = np.vstack([full_accel(f) for f in (0.61, 1.0)])
    turns = [full_turn(f, b) for f, b in ID_TURNS]
    glides = [full_glide(f, a) for f, a in ID_GLIDES]
    print(f"free runs: {time.perf_counter() - t0:.0f} s")
    fz = np.r_[0.0, [s.frequency_hz for s in swims]]
    coef = mm.ManoeuvringCoefficients(
        **rigid,
        hull=hull,
        fin_port=fin_p,
        fin_starboard=fin_s,
        tail=np.zeros((len(mm.TAIL_TERMS), 6)),
        power_frequency_hz=fz,
        tail_straight=np.zeros((fz.size, 6)),
        straight_speed_m_s=np.r_[0.0, [s.speed_m_s for s in swims]],
        thrust_speed_slope=0.0,
        # the bias table (interpolated in the bias at the cruise frequency) is left empty: with
        # it the +-10 deg turns were 3.3-3.9 % off, with the regression 0.6-3.5 %
        tail_bias_grid_rad=np.array([-1.0, 1.0]),
        tail_bias_per_uu=np.zeros((2, 6)),
        hull_box_low=np.array([b[0] for b in HULL_BOX.values()]),
        hull_box_high=np.array([b[1] for b in HULL_BOX.values()]),
        power_w=np.r_[0.0, [s.power_w for s in swims]],
        yaw_amplitude_rad=np.r_[0.0, [s.yaw_amplitude_rad for s in swims]],
        roll_amplitude_rad=np.r_[0.0, [s.roll_amplitude_rad for s in swims]],
        roll_phase_rad=float(np.angle(np.mean(np.exp(1j * np.array([s.roll_phase_rad for s in swims]))))),  # noqa: E501
        fin_flow_port=flow_p,
        fin_flow_starboard=flow_s,
        fin_position_body_m=np.stack([r_p, r_s]),
    )  # fmt: skip
    tail = fit_tail(coef, swims, accels, turns, glides)
    coef = mm.ManoeuvringCoefficients(**{**coef.__dict__, **tail})
    report = {
        "hull_fit_relative_rms": hull_err.tolist(),
        "fin_port_fit_relative_rms": fin_p_err.tolist(),
        "fin_starboard_fit_relative_rms": fin_s_err.tolist(),
        "fin_flow_port_fit_relative_rms": flow_p_err.tolist(),
        "fin_flow_starboard_fit_relative_rms": flow_s_err.tolist(),
        "swims": [{k: np.asarray(v).tolist() for k, v in s.__dict__.items()} for s in swims],
        "identification_s": time.perf_counter() - t0,
    }
    return coef, report


# --------------------------------------------------------------------------------------------
# validation


def full_current_step(f: float, along: bool | None) -> tuple[float, float]:
    """Cruise north (depth held), then a 0.3 m/s current along (north) or across (east) the
    track (None: no current), ramped over one tick as the sea does; the mean ground velocity
    along and across the track over the last 20 s of 30 s after the step, m/s."""
    ph = scene()
    hold = manoeuvres.DepthHold(ph.depth_m())
    ph.set_tail_beat_frequency_hz(f)
    tick = ph.control_tick_s
    c = np.zeros(3) if along is None else np.array([0.0, 0.3, 0.0] if along else [0.3, 0.0, 0.0])
    p0 = t0 = None
    for k in range(round(60.0 / tick)):
        if k == round(30.0 / tick):
            ph.set_water_world(np.zeros(3), c / tick)
        elif k == round(30.0 / tick) + 1:
            ph.set_water_world(c)
        if k == round(40.0 / tick):
            p0, t0 = ph.position_world(), ph.time_s()
        a = hold.fins_rad(ph)
        ph.set_lateral_fins_rad(a, a)
        ph.advance(tick)
    v = (ph.position_world() - p0) / (ph.time_s() - t0)
    return float(v[1]), float(v[0])


def full_results(f: float) -> dict[str, float]:
    """The validation quantities on the full model."""
    out: dict[str, float] = {}
    s = manoeuvres.straight_swim(scene(), f)
    out["cruise_speed_m_s"] = s.speed_through_water_m_s
    out["cruise_power_w"] = s.mean_motor_power_w
    for b in (10.0, -10.0, 20.0, -20.0):
        tr = manoeuvres.heading_change(scene(), f, math.radians(b))
        out[f"turn_rate_{b:+.0f}_deg_s"] = math.degrees(tr.turn_rate_rad_s)
        out[f"turn_radius_{b:+.0f}_m"] = tr.turning_radius_m
    fin = manoeuvres.depth_change(scene(), f, 0.2)
    out["fin_step_depth_rate_m_s"] = fin.depth_rate_m_s
    rise, overshoot = depth_step(TIMESTEP_S, f)
    out["depth_rise_time_s"], out["depth_overshoot_percent"] = rise, overshoot
    a0, c0 = full_current_step(f, None)
    for along in (True, False):
        a, c = full_current_step(f, along)
        a, c = a - a0, c - c0  # what the current changed
        key = "along" if along else "across"
        out[f"current_{key}_ground_along_m_s"] = a
        out[f"current_{key}_ground_across_m_s"] = c
    return out


def model_results(coef: mm.ManoeuvringCoefficients, f: float) -> dict[str, float]:
    """The same quantities on the manoeuvring model (its own trials, one run each)."""
    from tasks.vehicle.autopilot import AutopilotTrialsScenario

    out: dict[str, float] = {}
    sp, pw = trials.straight_swim(coef, f)
    out["cruise_speed_m_s"], out["cruise_power_w"] = sp, pw
    for b in (10.0, -10.0, 20.0, -20.0):
        rate, radius = trials.heading_change(coef, f, math.radians(b))
        out[f"turn_rate_{b:+.0f}_deg_s"] = math.degrees(rate)
        out[f"turn_radius_{b:+.0f}_m"] = radius
    out["fin_step_depth_rate_m_s"] = trials.fin_step(coef, f, 0.2)
    sc = AutopilotTrialsScenario()
    t, depth = trials.autopilot_depth_step(coef, sc.autopilot, sc.control_tick_s,
                                           sc.depth_m, sc.depth_step_m, sc.speed_to_m_s)  # fmt: skip  # noqa: E501
    rise, overshoot = depth_step_metrics(t, depth, sc, f)
    out["depth_rise_time_s"], out["depth_overshoot_percent"] = rise, overshoot
    for along in (True, False):
        a, c = trials.current_step(coef, f, along)
        key = "along" if along else "across"
        out[f"current_{key}_ground_along_m_s"] = a
        out[f"current_{key}_ground_across_m_s"] = c
    return out


def bound(key: str, ref: dict[str, float]) -> tuple[str, float]:
    """The threshold of a quantity: the timestep table's; for the current steps the cruise
    speed's 1 % on the component along the current, and 1 % of the cruise speed (m/s) on the
    other."""
    if key.startswith("turn_rate"):
        return THRESHOLDS["turn_rate_deg_s"]
    if key.startswith("turn_radius"):
        return THRESHOLDS["turn_radius_m"]
    if key in ("current_along_ground_along_m_s", "current_across_ground_across_m_s"):
        return THRESHOLDS["cruise_speed_m_s"]
    if key.startswith("current_"):
        return ("absolute", 0.01 * ref["cruise_speed_m_s"])
    return THRESHOLDS[key]


def render(full: dict[str, float], man: dict[str, float]) -> str:
    """Markdown table full model against manoeuvring model."""
    lines = [
        "| quantity | threshold | full model (4 ms) | manoeuvring model | difference | holds |",
        "|---|---|---|---|---|---|",
    ]
    for k, x in full.items():
        kind, b = bound(k, full)
        y = man[k]
        if kind == "relative":
            diff = (y - x) / abs(x)
            ok = abs(diff) <= b
            lines.append(
                f"| {k} | {b * 100:g} % | {x:.4g} | {y:.4g} | {diff * 100:+.2f} % "
                f"| {'yes' if ok else 'NO'} |"
            )
        else:
            diff = y - x
            ok = abs(diff) <= b
            lines.append(
                f"| {k} | {b:.3g} | {x:.4g} | {y:.4g} | {diff:+.3g} | {'yes' if ok else 'NO'} |"
            )
    return "\n".join(lines)  # fmt: skip


def write_readme(table: str, tag: str = "manoeuvring") -> None:
    """Replace the block between the BEGIN/END markers of ``tag`` in the model README."""
    text = README.read_text()
    pat = re.compile(rf"(<!-- BEGIN results:{tag} -->\n).*?(\n<!-- END results:{tag} -->)", re.S)
    if not pat.search(text):
        raise SystemExit(f"{README}: no results:{tag} markers")
    README.write_text(pat.sub(lambda m: m.group(1) + table + m.group(2), text))


EXTRA_DEPTH_STEPS = ((-5.0, 1.0), (2.0, 1.0), (5.0, 0.6), (-2.0, 0.6))
"""(step m, positive deeper; speed m/s) of the autopilot's further depth steps from 10 m, beside
the table's +5 m at 1 m/s: up as well as down, smaller, slower (none identified on)."""


def _step_metrics(t_s, depth_m, sc, step_m: float, frequency_hz: float) -> tuple[float, float]:
    """10-90 % rise (s) and overshoot past the new depth (% of the step) of the beat-averaged
    depth of a step of either sign (:func:`timestep.depth_step_metrics` for any step)."""
    from tasks.vehicle.autopilot import beat_average

    n = max(1, round(1.0 / (frequency_hz * sc.control_tick_s)))
    depth = beat_average(np.asarray(depth_m, dtype=float), n)
    t = np.asarray(t_s, dtype=float)
    after = t >= DEPTH_STEP_AT_S
    y0, y1 = sc.depth_m, sc.depth_m + step_m
    rise = rise_time_s(t[after] - DEPTH_STEP_AT_S, depth[after], y0, y1)
    past = np.max((depth[after] - y1) * math.copysign(1.0, step_m))
    return rise, max(0.0, float(past)) / abs(step_m) * 100.0


def extra_depth_steps(coef: mm.ManoeuvringCoefficients) -> str:
    """The autopilot's depth steps of :data:`EXTRA_DEPTH_STEPS`, full model (``fly_trial`` at 4
    ms) against the manoeuvring model: a markdown table with the timestep table's thresholds."""
    from bauv_sim.design.speed_table import load_speed_table
    from tasks.vehicle.autopilot import AutopilotTrialsScenario, fly_trial

    sc = AutopilotTrialsScenario().model_copy(update={"physics_timestep_s": TIMESTEP_S})
    lines = [
        "| depth step | speed (m/s) | rise, full model (s) | rise, manoeuvring (s) | difference "
        "| overshoot, full / manoeuvring (%) | holds |",
        "|---|---|---|---|---|---|---|",
    ]
    for step, speed in EXTRA_DEPTH_STEPS:
        f = float(load_speed_table().frequency_for(speed))
        tr = fly_trial(
            sc, 80.0, lambda t: 0.0,
            lambda t, s=step: sc.depth_m + (s if t >= DEPTH_STEP_AT_S else 0.0),
            lambda t, v=speed: v,
        )  # fmt: skip
        rf, of = _step_metrics(tr["t"], tr["depth"], sc, step, f)
        t, d = trials.autopilot_depth_step(
            coef, sc.autopilot, sc.control_tick_s, sc.depth_m, step, speed
        )
        rm, om = _step_metrics(t, d, sc, step, f)
        diff = (rm - rf) / rf
        ok = (
            abs(diff) <= THRESHOLDS["depth_rise_time_s"][1]
            and abs(om - of) <= THRESHOLDS["depth_overshoot_percent"][1]
        )
        lines.append(
            f"| {step:+g} m | {speed:g} | {rf:.2f} | {rm:.2f} | {diff * 100:+.2f} % "
            f"| {of:.2f} / {om:.2f} | {'yes' if ok else 'NO'} |"
        )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--validate", action="store_true", help="validate the stored data only")
    ap.add_argument("--no-write", action="store_true", help="print, write nothing")
    args = ap.parse_args()
    from checks import cruise_frequency_hz

    f = cruise_frequency_hz()
    if args.validate:
        coef = mm.load_coefficients()
    else:
        coef, report = identify()
        if not args.no_write:
            data = {"about": "identified by manoeuvring_id.py from the full model at 4 ms",
                    "terms": {"hull": mm.HULL_TERMS, "fin": mm.FIN_TERMS, "tail": mm.TAIL_TERMS,
                              "fin_flow": mm.FIN_FLOW_TERMS,
                              "tail_heave": mm.TAIL_HEAVE_TERMS},
                    "fit": report, **coef.to_json()}  # fmt: skip
            mm.DATA_PATH.write_text(json.dumps(data, indent=1) + "\n")
        print(json.dumps({k: v for k, v in report.items() if k != "swims"}, indent=1))
    t0 = time.perf_counter()
    man = model_results(coef, f)
    print(f"manoeuvring model trials: {time.perf_counter() - t0:.1f} s")
    full = full_results(f)
    table = render(full, man)
    print(table)
    extra = extra_depth_steps(coef)
    print(extra)
    if not args.no_write:
        write_readme(table)
        write_readme(extra, "manoeuvring-depth-steps")


if __name__ == "__main__":
    main()
