"""The hydrodynamics checks of issue 11 and 21 on the water: a step of the current, a sea put
around the vehicles, the fins' drag, plain MuJoCo, a vehicle in water of its own, the passive
caudal spring and the model's approximations one at a time (run by :mod:`hydro`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
from hydro_body import _open_water
from numpy.typing import NDArray

from bauv_sim import build, hull, hydro, hydro_native, manoeuvres
from bauv_sim.design import fluid
from bauv_sim.physics import BauvPhysics
from bauv_sim.sea import Sea

OLD_FIN_FLUIDCOEF = {"caudal_fin_fluid": (0.08, 0.003781), "dorsal_fin_fluid": (0.08, 0.0046943)}
"""MuJoCo's blunt and slender drag coefficients of the fins before issue 21 (commit e4e897f)."""


# ------------------------------------------------------------------------------------------
# 4. a step of the current


class StepCurrent:
    """A uniform current switched on at a time: zero before ``t0``, ``velocity`` after (the sea
    spreads the step over the control tick containing it)."""

    steady_uniform = False

    def __init__(self, t0_s: float, velocity_world_m_s: tuple[float, float, float]) -> None:
        self.t0_s = float(t0_s)
        self.velocity = np.asarray(velocity_world_m_s, dtype=float)

    def velocity_world(self, t_s, pos_world_m):
        t = np.asarray(t_s, dtype=float)
        p = np.asarray(pos_world_m, dtype=float)
        v = np.where((t >= self.t0_s)[..., None], self.velocity, 0.0)
        return np.broadcast_to(v, np.broadcast_shapes(t.shape, p.shape[:-1]) + (3,)).copy()


@dataclass(frozen=True)
class StepRow:
    """A 0.3 m/s current step, along or across the heading: the idle vehicle's time to follow
    the water horizontally within 2 % of the step (s; the water ramps over one 0.1 s tick) and
    its largest vertical velocity after it (m/s: the Froude-Krylov force acts at the centre of
    buoyancy, the inertia at the CG and the hull axis, so it pitches a little); and the swimming
    vehicle's speed through water along the hull (the log's reading, m/s, sampled every 0.1 s):
    its mean and range over the 10 s before, and its least and largest within 10 s after."""

    direction: str
    idle_follow_s: float
    idle_heave_m_s: float
    log_before_m_s: float
    log_range_before_m_s: tuple[float, float]
    log_min_m_s: float
    log_max_m_s: float


def _step_run(vel: tuple[float, float, float], swim: bool, frequency_hz: float) -> NDArray:
    ph = _open_water(speed_m_s=1.0 if swim else 0.0)
    Sea(StepCurrent(20.0, vel)).immerse(ph)
    ph.set_tail_beat_frequency_hz(frequency_hz if swim else 0.0)
    hold = manoeuvres.DepthHold(ph.depth_m())
    tick = ph.control_tick_s
    rows = []
    for _ in range(round(40.0 / tick)):
        a = hold.fins_rad(ph)
        ph.set_lateral_fins_rad(a, a)
        ph.advance(tick)
        R = ph.R_world_from_body()
        through = R.T @ ph.velocity_through_water_world()
        rows.append((ph.time_s(), through[0], *ph.velocity_world()))
    return np.array(rows)


def check_current_step(frequency_hz: float | None = None) -> tuple[StepRow, ...]:
    """Along the heading (north, the vehicle heading north) and across it (east)."""
    from checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    out = []
    for name, vel in (("along", (0.0, 0.3, 0.0)), ("across", (0.3, 0.0, 0.0))):
        idle = _step_run(vel, False, f)
        err = np.linalg.norm(idle[:, 2:4] - np.asarray(vel)[:2], axis=1)
        t = idle[:, 0]
        # time after the step from which the horizontal velocity stays within 2 % of the step
        bad = np.flatnonzero((t > 20.0) & (err > 0.02 * 0.3))
        follow = float(t[bad[-1] + 1] - 20.0) if bad.size else float(t[t > 20.0][0] - 20.0)
        heave = float(np.max(np.abs(idle[t > 20.0, 4])))
        swim = _step_run(vel, True, f)
        pre = swim[(swim[:, 0] > 10.0) & (swim[:, 0] <= 20.0), 1]
        after = swim[(swim[:, 0] > 20.0) & (swim[:, 0] <= 30.0), 1]
        out.append(
            StepRow(
                name,
                follow,
                heave,
                float(pre.mean()),
                (float(pre.min()), float(pre.max())),
                float(after.min()),
                float(after.max()),
            )
        )
    return tuple(out)


@dataclass(frozen=True)
class SetSeaResult:
    """A steady uniform current put in with ``Sea.immerse`` (issue 21): the idle vehicle's
    velocity along a 0.3 m/s current, as a fraction of it, 0.2 s and 1 s after (across and along
    its heading); a vehicle placed at 1 m/s through the water and put in a cross current of 0.3
    and 2 m/s: its offset across the track from the still-water track plus the drift after 60 s
    (m); the log's least reading within 10 s after a 0.3 m/s current is set along the track of a
    vehicle swimming at 1 m/s, and its range over the 10 s before (m/s)."""

    idle: dict[str, tuple[float, float]]
    cross_lag_m: dict[float, float]
    log_min_after_m_s: float
    log_range_before_m_s: tuple[float, float]


def check_set_sea(frequency_hz: float | None = None) -> SetSeaResult:
    """The idle step, the start in a cross current and the along-track switch of issue 21."""
    from checks import cruise_frequency_hz

    from bauv_sim.currents import UniformCurrent

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    idle = {}
    for name, direction in (("across", math.pi / 2), ("along", 0.0)):
        ph = _open_water()
        ph.advance(1.0)
        c = UniformCurrent(0.3, direction)
        w = c.velocity_world(0.0, np.zeros(3))
        Sea(c).immerse(ph)
        fr = []
        for _ in range(10):
            ph.advance(0.1)
            fr.append(float(ph.velocity_world() @ w / (w @ w)))
        idle[name] = (fr[1], fr[9])

    def swim(seas: dict[int, Sea], ticks: int, log: list | None = None) -> NDArray:
        ph = _open_water(speed_m_s=1.0)
        hold = manoeuvres.DepthHold(ph.depth_m())
        ph.set_tail_beat_frequency_hz(f)
        p0 = ph.position_world()
        for k in range(ticks):
            if k in seas:
                seas[k].immerse(ph)
            a = hold.fins_rad(ph)
            ph.set_lateral_fins_rad(a, a)
            ph.advance(ph.control_tick_s)
            if log is not None:
                log.append(float(ph.R_world_from_body()[:, 0] @ ph.velocity_through_water_world()))
        return ph.position_world() - p0

    still = swim({}, 600)
    lag = {}
    for speed in (0.3, 2.0):
        moved = swim({0: Sea(UniformCurrent(speed, math.pi / 2))}, 600)
        lag[speed] = float(abs(moved[0] - (still[0] + speed * 60.0)))
    log: list[float] = []
    swim({200: Sea(UniformCurrent(0.3, 0.0))}, 300, log)
    before = log[100:200]
    return SetSeaResult(idle, lag, min(log[200:]), (min(before), max(before)))


@dataclass(frozen=True)
class FinDragResult:
    """The thin fins' drag (issue 21). ``coefficients``: per fin and incidence (deg), the drag
    coefficient on the plate's area of the plate model and of MuJoCo's projected-area formula
    with the fin's former coefficients, and that formula's projected area over the plate's true
    shadow. ``tow``: per yaw rate (rad/s), the towed drag at 1 m/s (N): MuJoCo's part and the total
    fluid force against the motion. ``cruise_speed_m_s``: the straight swim at 0.84 Hz (the
    cruise frequency before)."""

    coefficients: dict[str, dict[float, tuple[float, float, float]]]
    tow: dict[float, tuple[float, float]]
    cruise_speed_m_s: float


def projected_area_m2(semi: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[float, float]:
    """MuJoCo's projected area of an ellipsoid for a flow direction (``engine_passive.c``: a
    weighted mean of the three sections) and the true shadow ``pi abc |(u_x/a, u_y/b, u_z/c)|``,
    m^2."""
    n = np.asarray(u, dtype=float) / np.linalg.norm(u)
    r2 = np.asarray(semi, dtype=float) ** 2
    num = r2[1] ** 2 * r2[2] ** 2 * n[0] ** 2 + r2[2] ** 2 * r2[0] ** 2 * n[1] ** 2
    num += r2[0] ** 2 * r2[1] ** 2 * n[2] ** 2
    den = r2[1] * r2[2] * n[0] ** 2 + r2[2] * r2[0] * n[1] ** 2 + r2[0] * r2[1] * n[2] ** 2
    shadow = math.pi * float(np.prod(semi)) * float(np.linalg.norm(n / np.asarray(semi)))
    return math.pi * math.sqrt(num / den), shadow


def check_fins(alphas_deg: tuple[float, ...] = (1.0, 5.0, 20.0)) -> FinDragResult:
    """The caudal and dorsal fins' drag coefficients against incidence (design tables: the plate
    model the plugin applies, drag = q S (C_D0 cos^3 a + k_i C_L^2 + C_N sin^3 a) with C_L = C_La
    sin a cos a; MuJoCo's 2 (C_b A_proj + C_s (S - A_proj)) / S), the towed drag with a yaw rate,
    and the cruise speed at the former cruise frequency."""
    drag = fluid.foil_drag_coefficients()
    cla = fluid.foil_lift_slopes()
    fins = {f.geom: f for f in fluid.plate_fins()}
    coefs: dict[str, dict[float, tuple[float, float, float]]] = {}
    for geom, (cb, cs) in OLD_FIN_FLUIDCOEF.items():
        semi = np.array(fins[geom].semi_axes_m)  # chord, thickness, span
        area = math.pi * semi[0] * semi[2]
        c_d0, k_i, c_n = drag[geom]
        coefs[geom] = {}
        for a in alphas_deg:
            al = math.radians(a)
            c_l = cla[geom] * math.sin(al) * math.cos(al)
            plate = c_d0 * math.cos(al) ** 3 + k_i * c_l**2 + c_n * math.sin(al) ** 3
            a_proj, shadow = projected_area_m2(semi, np.array([math.cos(al), math.sin(al), 0.0]))
            old = 2.0 * (cb * a_proj + cs * (area - a_proj)) / area
            coefs[geom][a] = (plate, old, a_proj / shadow)
    tow_rows = {}
    for r in (0.0, 0.05, 0.1, 0.2):
        # MuJoCo's share is its qfrc_fluid: the model with MuJoCo's fluid model on (the same
        # forces; since issue 27 the model file has the plugin apply them)
        with hydro_native.formulation("mujoco-fluid"):
            ph = _open_water()
        ph.set_pose([0.0, 0.0, -20.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], None, [0.0, 0.0, r])
        total = -float(ph.fluid_force_world()[1])
        free = np.arange(6)
        mj = -float(np.asarray(ph.data.qfrc_fluid)[free][1])
        tow_rows[r] = (mj, total)
    swim = manoeuvres.straight_swim(_open_water(speed_m_s=1.0), 0.84)
    return FinDragResult(coefs, tow_rows, swim.speed_through_water_m_s)


# ------------------------------------------------------------------------------------------
# 5. plain MuJoCo, and a vehicle in water of its own


@dataclass(frozen=True)
class PlainResult:
    """``scene.xml`` compiled by plain MuJoCo (no plugin registered): the error it gives; with
    the one-line loader and stepped by plain ``mj_step`` from ``trim`` for 10 s: speed (m/s) and
    pitch (deg), and the largest difference of its state from the facade's run (the same model
    stepped by :class:`BauvPhysics`)."""

    plain_error: str
    loader_speed_m_s: float
    loader_pitch_deg: float
    difference_from_facade: float


def check_plain_mujoco() -> PlainResult:
    """Compile ``models/bauv/scene.xml`` in a fresh interpreter without the plugin; then with
    :func:`bauv_sim.hydro.load_model` step it with plain ``mujoco.mj_step`` from ``trim``."""
    import subprocess
    import sys

    code = (
        "import mujoco\n"
        "try:\n"
        f"    mujoco.MjModel.from_xml_path({str(hull.MODEL_DIR / 'scene.xml')!r})\n"
        "    print('compiled')\n"
        "except ValueError as e:\n"
        "    print(str(e).splitlines()[0])\n"
    )
    plain = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    m = hydro.load_model(hull.MODEL_DIR / "scene.xml")
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "trim"))
    mujoco.mj_step(m, d, round(10.0 / m.opt.timestep))
    qw, qx, qy, qz = d.qpos[3:7]
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, 2.0 * (qw * qy - qz * qx)))))
    ph = BauvPhysics.from_scene_xml()
    ph.reset_to_keyframe("trim")
    ph.step(round(10.0 / ph.timestep()))
    diff = float(np.max(np.abs(np.r_[ph.data.qpos - d.qpos, ph.data.qvel - d.qvel])))
    return PlainResult(plain.stdout.strip(), float(np.linalg.norm(d.qvel[:3])), abs(pitch), diff)


@dataclass(frozen=True)
class OwnWaterResult:
    """A follower swimming in water 0.4 m/s different from the leader's (the leader's water is
    MuJoCo's): its displacement relative to its own water after 60 s against the same vehicle
    alone in that water (m), and the difference."""

    displacement_m: float
    alone_m: float
    difference_m: float


class _TwoWaters:
    """Still water west of x = -15 m, a 0.4 m/s current setting north east of it."""

    steady_uniform = False

    def velocity_world(self, t_s, pos_world_m):
        p = np.asarray(pos_world_m, dtype=float)
        v = np.zeros(p.shape)
        v[..., 1] = np.where(p[..., 0] > -15.0, 0.4, 0.0)
        return v


def check_own_water(frequency_hz: float | None = None, duration_s: float = 60.0) -> OwnWaterResult:
    """The leader (first vehicle) in still water at x = -40 m, the follower at x = 0 in the 0.4
    m/s current; both swim north at the cruise frequency, from 1 m/s through their water. Alone,
    the follower would move relative to its water exactly as in still water; the difference is
    the error of the multi-vehicle coupling (held per tick before: 1.44 m after 60 s)."""
    from checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(name="leader", east_m=-40.0, depth_m=20.0, speed_m_s=1.0),
            build.VehicleSpec(name="follower", east_m=0.0, depth_m=20.0, speed_m_s=1.0),
        ),
        seabed=_flat_bed(),
        beacons=(),
    )
    two = build.build_physics(cfg)
    Sea(_TwoWaters()).immerse(two)
    for name in ("leader", "follower"):
        two.set_tail_beat_frequency_hz(f, name)
    p0 = two.position_world("follower")
    two.advance(duration_s)
    moved = two.position_world("follower") - p0 - np.array([0.0, 0.4, 0.0]) * duration_s
    alone = manoeuvres.open_water_scene(depth_m=20.0, speed_m_s=1.0)
    alone.set_tail_beat_frequency_hz(f)
    q0 = alone.position_world()
    alone.advance(duration_s)
    ref = alone.position_world() - q0
    return OwnWaterResult(
        float(np.linalg.norm(moved[:2])),
        float(np.linalg.norm(ref[:2])),
        float(np.linalg.norm(moved[:2] - ref[:2])),
    )


def _flat_bed():
    from bauv_sim.seabed import SeabedConfig

    return SeabedConfig(
        depth_at_origin_m=200.0,
        slope=0.0,
        relief_std_m=0.0,
        min_depth_m=200.0,
        half_extent_m=2000.0,
        cell_m=500.0,
    )


@dataclass(frozen=True)
class SpringRow:
    """Self-propelled speed (m/s), mean motor power (W) and tail-tip amplitude (m p-p) at one
    tail-beat frequency, with the model's fixed caudal spring and, as an experiment, with the
    spring stiffened as the frequency squared above 1.5 Hz (the fin's natural frequency then
    keeps its ratio to the beat)."""

    frequency_hz: float
    fixed_speed_m_s: float
    fixed_power_w: float
    fixed_amplitude_m: float
    scaled_speed_m_s: float
    scaled_power_w: float
    scaled_amplitude_m: float


def check_spring(frequencies_hz: tuple[float, ...] = (1.5, 2.0, 2.5, 2.75, 3.0)) -> tuple:
    """Why the speed stops rising above 2.5 Hz: the same straight swims with the model's spring
    (30 N m/rad) and with ``30 (f / 1.5)^2`` N m/rad (set in the compiled model for the run)."""
    rows = []
    for f in frequencies_hz:
        out = []
        for scaled in (False, True):
            ph = manoeuvres.open_water_scene(speed_m_s=1.5)
            if scaled:
                ph.set_joint_stiffness("caudal_fin_yaw", 30.0 * max(1.0, (f / 1.5) ** 2))
            r = manoeuvres.straight_swim(ph, f)
            out += [r.speed_through_water_m_s, r.mean_motor_power_w, r.tail_tip_amplitude_m]
        rows.append(SpringRow(f, *out))
    return tuple(rows)


@dataclass(frozen=True)
class ApproximationRow:
    """Cruise (speed m/s, head yaw p-p deg at the cruise frequency) and a 10 deg tail-bias turn
    (rate deg/s, radius m, drift deg) of the model and of a variant without one approximation."""

    variant: str
    speed_m_s: float
    yaw_pp_deg: float
    turn_rate_deg_s: float
    turn_radius_m: float
    drift_deg: float


def _variant(edit) -> BauvPhysics:
    """The open-water scene at 20 m, 1 m/s north, with its compiled model edited before the
    plugin starts (the plugin reads its tables when a data is made)."""
    import copy

    from dm_control.mujoco import wrapper

    base = _open_water(speed_m_s=1.0)
    m = copy.copy(base.model.ptr)
    edit(m)
    ph = BauvPhysics.from_model(wrapper.MjModel(m))
    ph.set_pose(base.position_world(), base.roll_pitch_heading(), base.velocity_world())
    return ph


def _set_numeric(m: mujoco.MjModel, name: str, data: NDArray[np.float64]) -> None:
    """Replace the data of the one vehicle's numeric ``<prefix>name``."""
    ids = [
        i
        for i in range(m.nnumeric)
        if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i) or "").rsplit("/", 1)[-1] == name
    ]
    (i,) = ids
    a, n = int(m.numeric_adr[i]), int(m.numeric_size[i])
    values = np.asarray(data, dtype=float).ravel()
    if values.size != n:
        raise ValueError(f"numeric {name!r} holds {n} numbers, not {values.size}")
    m.numeric_data[a : a + n] = values


def check_approximations(frequency_hz: float | None = None) -> tuple[ApproximationRow, ...]:
    """What five of the model's approximations change: the afterbody's share of the hull's Munk
    couple lost to separation (the variant keeps the whole potential couple: f = 0), the tail's
    share of the rigid-body added mass at zero tail angle (the variant leaves it out: the flapping
    parts' water then only as the hinges' armature), the fins' span efficiency e = 1 of their
    induced drag (the variant: 0.8, real fins' lower bound), their normal force C_N sin^2 a
    (the variant leaves it out) and the peduncle's crossflow strips (the variant leaves them out,
    as the model was before them)."""
    from checks import cruise_frequency_hz

    f = cruise_frequency_hz() if frequency_hz is None else frequency_hz
    sl = fluid.slender_lift_stations()
    no_tail = fluid.added_mass_matrix(
        geoms=("hull_fluid", "dorsal_fin_fluid", "fin_port_fluid", "fin_starboard_fluid")
    )
    plates = np.array(list(fluid.foil_drag_coefficients().values()))
    segments = fluid.segment_crossflow()

    def no_peduncle_strips(m: mujoco.MjModel) -> None:
        _set_numeric(m, "hydro_segment_crossflow", segments * [1, 1, 1, 1, 0, 0, 1, 1])
        _set_numeric(m, "hydro_segment_roll_damping", [0.0])

    variants = {
        "the model": lambda m: None,
        "separation off (the hull's whole Munk couple)": lambda m: _set_numeric(
            m, "hydro_slender_lift", np.r_[sl[:4], 0.0, 0.0]
        ),
        "without the tail's added mass": lambda m: _set_numeric(m, "hydro_added_mass", no_tail),
        "fins' span efficiency 0.8 (induced drag x 1.25)": lambda m: _set_numeric(
            m, "hydro_foil_drag", plates * [1.0, 1.0 / 0.8, 1.0]
        ),
        "fins without their normal (crossflow) force": lambda m: _set_numeric(
            m, "hydro_foil_drag", plates * [1.0, 1.0, 0.0]
        ),
        "without the peduncle's crossflow drag": no_peduncle_strips,
    }
    rows = []
    for label, edit in variants.items():
        swim = manoeuvres.straight_swim(_variant(edit), f)
        turn = manoeuvres.heading_change(_variant(edit), f, math.radians(10.0))
        rows.append(
            ApproximationRow(
                label,
                swim.speed_through_water_m_s,
                math.degrees(swim.yaw_amplitude_rad),
                math.degrees(turn.turn_rate_rad_s),
                turn.turning_radius_m,
                math.degrees(turn.drift_angle_rad),
            )
        )
    return tuple(rows)
