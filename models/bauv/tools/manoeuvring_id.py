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
   fins, fitted to :data:`~bauv_sim.manoeuvring.model.FIN_TERMS`.
4. **Tail (free runs)**: straight swims at several frequencies (steady speed, motor power, the
   beat's heading and roll oscillation fitted as a sinusoid at the beat frequency), accelerations
   from rest at two frequencies (thrust = inertia x acceleration - hull drag, beat by beat) and
   steady turns at several biases and two frequencies (the tail's mean force is what balances the
   rest of the model in the turn); fitted to :data:`~bauv_sim.manoeuvring.model.TAIL_TERMS`.

Validation (other manoeuvres than those identified on): the timestep table's quantities (cruise
speed and power, turn rate and radius at +-10 and +-20 deg of bias, the autopilot's 5 m depth
step, the +0.2 rad fin step) and 0.3 m/s current steps along and across the track, full model
against the manoeuvring model, with the timestep table's thresholds.

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
from timestep import THRESHOLDS, depth_step, depth_step_metrics

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


def fit_tail(coef: mm.ManoeuvringCoefficients, swims, accels, turns) -> dict:
    """The tail's tables and coefficients: the force that balances the rest of the model in the
    straight swims (tables), the thrust's slope in surge from the accelerations, the bias's share
    from the turns."""
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
    x, y = [], []
    for f, u, du in accels:
        nu = np.array([u, 0, 0, 0, 0, 0.0])
        thrust = mx * du - rest(f, 0.0, nu, (0.0, 0.0), 0.0)[0]
        x.append(-f * (u - np.interp(f, fz, u_ss)))
        y.append(thrust - np.interp(f, fz, straight[:, 0]))
    slope = float(np.dot(x, y) / np.dot(x, x))
    print("accel samples (f, u, du/dt, thrust - table):")
    print(np.c_[accels, y].round(3)[::4])
    rows, tau = [], []
    for tr in turns:
        base = np.array([np.interp(tr.frequency_hz, fz, straight[:, j]) for j in range(6)])
        base[0] -= slope * tr.frequency_hz * (tr.nu[0] - np.interp(tr.frequency_hz, fz, u_ss))
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
    return {"tail": tail, "tail_straight": straight, "thrust_speed_slope": slope}


def identify(seed: int = 27) -> tuple[mm.ManoeuvringCoefficients, dict]:
    """Run the whole identification; the coefficients and a report of fit errors."""
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    ph = scene(speed_m_s=0.0)
    rigid = rigid_part(ph)
    hull, hull_err = fit_hull(ph, rng)
    fin_p, fin_p_err = fit_fin(ph, rng, "bauv/fin_port_pitch")
    fin_s, fin_s_err = fit_fin(ph, rng, "bauv/fin_starboard_pitch")
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
    )  # fmt: skip
    tail = fit_tail(coef, swims, accels, turns)
    coef = mm.ManoeuvringCoefficients(**{**coef.__dict__, **tail})
    report = {
        "hull_fit_relative_rms": hull_err.tolist(),
        "fin_port_fit_relative_rms": fin_p_err.tolist(),
        "fin_starboard_fit_relative_rms": fin_s_err.tolist(),
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
                    "terms": {"hull": mm.HULL_TERMS, "fin": mm.FIN_TERMS, "tail": mm.TAIL_TERMS},
                    "fit": report, **coef.to_json()}  # fmt: skip
            mm.DATA_PATH.write_text(json.dumps(data, indent=1) + "\n")
        print(json.dumps({k: v for k, v in report.items() if k != "swims"}, indent=1))
    t0 = time.perf_counter()
    man = model_results(coef, f)
    print(f"manoeuvring model trials: {time.perf_counter() - t0:.1f} s")
    full = full_results(f)
    table = render(full, man)
    print(table)
    if not args.no_write:
        write_readme(table)


if __name__ == "__main__":
    main()
