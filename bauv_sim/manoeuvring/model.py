"""A manoeuvring model of the BAUV: Fossen's 6-DOF rigid-body and added-mass equations with
forces identified from the full MuJoCo vehicle, vectorised over Monte Carlo runs (issue 27).

The equations of motion, in the body frame FLU about the hull origin (the facade's reference
point), with nu_r = (u, v, w, p, q, r) the velocity relative to the water (Fossen 2021, eq. 6.5
and 10.46 for an irrotational current that is uniform around the vehicle)::

    (M_RB + M_A) d(nu_r)/dt = -C_RB(nu_r) nu_r + F_hull(nu_r) + F_fins(delta, nu_r)
                              + F_tail(f, b, u, w) + g(eta)

* ``M_RB``, ``M_A``: the full model's free-joint mass matrix with the tail straight (the plugin
  puts ``M_A`` there), split with the plugin's own ``M_A``;
* ``C_RB``: the rigid-body Coriolis and centripetal matrix of ``M_RB`` (Fossen 2021, eq. 3.57);
* ``F_hull``: the quasi-steady fluid force on the whole vehicle (MuJoCo's ellipsoid drag, the
  plugin's crossflow, lift, Munk couple, plates, the added mass's velocity terms) as a polynomial
  in ``nu_r`` fitted to captive tests of the full model (tail straight, fins level);
* ``F_fins``: each lateral fin's change of that force with its angle, in the local flow at the
  fin's centre (the plugin's thin-plate terms as regressors), fitted to captive tests;
* ``F_tail``: the flapping tail's force averaged over a beat: a straight-swim table in f, the
  thrust's change ``-k f (u - u_ss(f))`` fitted to accelerations of the full model from rest, the
  beat's share in heave fitted to its steady glides after fin steps, and the bias's force and
  moments fitted to its steady turns;
* ``g(eta)``: weight at the CG and buoyancy at the CB (neutral: the vehicle's BG of 48 mm).

The vehicle moves with the water: a neutrally buoyant body in a uniform current feels no force
from its acceleration (Froude-Krylov and added mass cancel it), so the relative velocity obeys
the equations above whatever the current does, and the velocity over ground is
``R nu_r + current``.

The tail beat's oscillation of heading and roll, which the beat-averaged equations do not carry,
is added to the attitude the sensors read as a periodic term at the beat's phase, with the
amplitudes measured on the full model (:meth:`ManoeuvringWorld.roll_pitch_heading`).

Actuators follow their commands with the full model's first-order filters (tail bias 0.2 s,
lateral fins 0.05 s, battery 1 s), integrated exactly over each substep.

References:
    Fossen, T. I. (2021). Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed.
    Wiley: ch. 3 (rigid-body kinetics), 6 (added mass), 10 (currents).
"""

from __future__ import annotations

import json
import math
from dataclasses import MISSING, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from bauv_sim.hull import MODEL_DIR
from bauv_sim.manoeuvring.regressors import (
    FIN_FLOW_TERMS as FIN_FLOW_TERMS,
)
from bauv_sim.manoeuvring.regressors import (
    FIN_TERMS as FIN_TERMS,
)
from bauv_sim.manoeuvring.regressors import (  # the model's public names, as before
    HULL_LINE_TERMS as HULL_LINE_TERMS,
)
from bauv_sim.manoeuvring.regressors import (
    HULL_TERMS as HULL_TERMS,
)
from bauv_sim.manoeuvring.regressors import (
    TAIL_HEAVE_TERMS as TAIL_HEAVE_TERMS,
)
from bauv_sim.manoeuvring.regressors import (
    TAIL_TERMS as TAIL_TERMS,
)
from bauv_sim.manoeuvring.regressors import _cross, _fin_plate_change
from bauv_sim.manoeuvring.regressors import (
    fin_flow_regressors as fin_flow_regressors,
)
from bauv_sim.manoeuvring.regressors import (
    fin_regressors as fin_regressors,
)
from bauv_sim.manoeuvring.regressors import (
    hull_regressors as hull_regressors,
)
from bauv_sim.manoeuvring.regressors import (
    skew as skew,
)
from bauv_sim.manoeuvring.regressors import (
    tail_heave_regressors as tail_heave_regressors,
)
from bauv_sim.manoeuvring.regressors import (
    tail_regressors as tail_regressors,
)

DATA_PATH = MODEL_DIR / "manoeuvring.json"
"""The identified tables, written by ``models/bauv/tools/manoeuvring_id.py``."""

GRAVITY_M_S2 = 9.81
"""Gravity, m/s^2 (the scene's ``option gravity``)."""


@dataclass(frozen=True)
class ManoeuvringCoefficients:
    """The identified manoeuvring model (``models/bauv/manoeuvring.json``).

    Attributes:
        mass_matrix: M_RB + M_A about the hull origin, body FLU, shape (6, 6), kg, kg m, kg m^2.
        rigid_mass_kg: m, kg.
        cg_body_m: centre of gravity, body FLU from the hull origin, shape (3,), m.
        inertia_origin_kg_m2: rigid inertia about the hull origin, body FLU, shape (3, 3).
        weight_n: weight, N.
        buoyancy_n: buoyancy, N.
        cb_body_m: centre of buoyancy, body FLU, shape (3,), m.
        battery_kg: mass of the movable battery, kg (its slide moves the CG along x).
        hull: coefficients of :data:`HULL_TERMS` for (X, Y, Z, K, M, N), shape (59, 6), N, N m.
        fin_port: coefficients of :data:`FIN_TERMS` for the port fin, shape (3, 6).
        fin_starboard: the same for the starboard fin, shape (3, 6).
        tail: coefficients of :data:`TAIL_TERMS`, shape (6, 6).
        power_frequency_hz: frequencies of the tables below, Hz, shape (k,), increasing, from 0.
        tail_straight: the tail's mean force and moment in a steady straight swim at those
            frequencies (what balances the rest of the model there), shape (k, 6), N, N m.
        straight_speed_m_s: the steady speed through water there, m/s, shape (k,).
        thrust_speed_slope: k of the thrust's change with surge off the steady swim,
            -k f (u - u_ss(f)), N / (Hz m/s).
        tail_bias_grid_rad: tail biases of the bias table, rad, shape (k_b,), increasing.
        tail_bias_per_uu: the bias's share of the tail's mean force and moment over u abs(u)
            at those biases (measured at the cruise frequency), shape (k_b, 6), N / (m/s)^2;
            interpolated linearly in the bias and added to the :data:`TAIL_TERMS` regression.
        hull_box_low, hull_box_high: the box of relative velocities the hull's force was fitted
            in, shape (6,) each; outside it the regressors are evaluated at the nearest point of
            the box (the polynomial is not extrapolated).
        power_w: cruise motor power at those frequencies, W, shape (k,).
        yaw_amplitude_rad: half the peak-to-peak heading oscillation per beat, rad, shape (k,).
        roll_amplitude_rad: half the peak-to-peak roll oscillation per beat, rad, shape (k,).
        roll_phase_rad: phase of the roll oscillation after the heading's, rad.
        bias_time_constant_s, fin_time_constant_s, battery_time_constant_s: the actuators'
            first-order filters, s.
        fin_flow_port, fin_flow_starboard: coefficients of :data:`FIN_FLOW_TERMS` for each fin,
            shape (8, 6); when present they replace ``fin_port`` and ``fin_starboard`` (which
            see the fins at zero heave only). None in data identified before them.
        fin_position_body_m: the fins' centres (port, starboard), body FLU from the hull origin,
            shape (2, 3), m; with ``fin_flow_*``.
        tail_heave: coefficients of :data:`TAIL_HEAVE_TERMS`, shape (3, 6); None (no term) in
            data identified before it.
    """

    mass_matrix: NDArray[np.float64]
    rigid_mass_kg: float
    cg_body_m: NDArray[np.float64]
    inertia_origin_kg_m2: NDArray[np.float64]
    weight_n: float
    buoyancy_n: float
    cb_body_m: NDArray[np.float64]
    battery_kg: float
    hull: NDArray[np.float64]
    fin_port: NDArray[np.float64]
    fin_starboard: NDArray[np.float64]
    tail: NDArray[np.float64]
    power_frequency_hz: NDArray[np.float64]
    tail_straight: NDArray[np.float64]
    straight_speed_m_s: NDArray[np.float64]
    thrust_speed_slope: float
    hull_box_low: NDArray[np.float64]
    hull_box_high: NDArray[np.float64]
    tail_bias_grid_rad: NDArray[np.float64]
    tail_bias_per_uu: NDArray[np.float64]
    power_w: NDArray[np.float64]
    yaw_amplitude_rad: NDArray[np.float64]
    roll_amplitude_rad: NDArray[np.float64]
    roll_phase_rad: float
    bias_time_constant_s: float = 0.2
    fin_time_constant_s: float = 0.05
    battery_time_constant_s: float = 1.0
    fin_flow_port: NDArray[np.float64] | None = None
    fin_flow_starboard: NDArray[np.float64] | None = None
    fin_position_body_m: NDArray[np.float64] | None = None
    tail_heave: NDArray[np.float64] | None = None

    def to_json(self) -> dict:
        """Plain JSON-able dict (arrays as nested lists)."""
        out = {}
        for k, v in self.__dict__.items():
            out[k] = np.asarray(v).tolist() if isinstance(v, np.ndarray) else v
        return out

    @classmethod
    def from_json(cls, data: dict) -> ManoeuvringCoefficients:
        """Inverse of :meth:`to_json` (extra keys, such as the provenance, are ignored)."""
        kw: dict[str, Any] = {}
        for k, f in cls.__dataclass_fields__.items():
            if k not in data:
                if f.default is not MISSING:
                    continue
                raise ConfigError(f"manoeuvring data: field {k!r} missing")
            v = data[k]
            if v is None and f.default is None:
                continue
            kw[k] = np.asarray(v, dtype=float) if isinstance(v, list) else float(v)
        return cls(**kw)


def load_coefficients(path: str | Path | None = None) -> ManoeuvringCoefficients:
    """Read the identified model.

    Args:
        path: the JSON file; default :data:`DATA_PATH`.

    Returns:
        The :class:`ManoeuvringCoefficients`.

    Raises:
        ConfigError: the file is missing (run ``python models/bauv/tools/manoeuvring_id.py``).
    """
    p = Path(path) if path is not None else DATA_PATH
    if not p.is_file():
        raise ConfigError(
            f"manoeuvring data {p}: not found "
            "(python models/bauv/tools/manoeuvring_id.py writes it)"
        )
    return ManoeuvringCoefficients.from_json(json.loads(p.read_text()))


class ManoeuvringWorld:
    """Many independent BAUVs under the manoeuvring model, stepped together at a control tick.

    Every array has a leading axis of runs ``n``. The state is the hull origin's position
    (world ENU), the attitude as Euler angles (roll about body x, a rotation about body y, yaw
    about world z: ``R_world_from_body = Rz(yaw) Ry(theta) Rx(roll)``; navigation pitch is
    ``-theta``, heading is ``pi/2 - yaw``), the velocity relative to the water (body FLU),
    the actuators' filtered positions and the tail beat's phase. Integration: classical
    Runge-Kutta 4 over ``substeps`` equal substeps per tick, the actuators' filters exactly.

    Args:
        n_runs: number of runs (>= 1).
        coefficients: the identified model (default: :func:`load_coefficients`).
        tick_s: control tick, s (> 0).
        substeps: Runge-Kutta substeps per tick (>= 1).
    """

    def __init__(
        self,
        n_runs: int,
        coefficients: ManoeuvringCoefficients | None = None,
        tick_s: float = 0.2,
        substeps: int = 2,
    ) -> None:
        if n_runs < 1:
            raise ConfigError(f"n_runs = {n_runs}: must be >= 1")
        if not tick_s > 0:
            raise ConfigError(f"tick_s = {tick_s}: must be > 0")
        if substeps < 1:
            raise ConfigError(f"substeps = {substeps}: must be >= 1")
        c = coefficients if coefficients is not None else load_coefficients()
        self.c = c
        self.n = n_runs
        self.tick_s = float(tick_s)
        self.substeps = int(substeps)
        self._Minv = np.linalg.inv(c.mass_matrix)
        n = n_runs
        self.time_s = 0.0
        self.position_world_m = np.zeros((n, 3))
        self.euler_rad = np.zeros((n, 3))
        self.nu_r = np.zeros((n, 6))
        self.current_world_m_s = np.zeros((n, 3))
        self.frequency_hz = np.zeros(n)
        self.bias_cmd_rad = np.zeros(n)
        self.fins_cmd_rad = np.zeros((n, 2))
        self.battery_cmd_m = np.zeros(n)
        self.bias_rad = np.zeros(n)
        self.fins_rad = np.zeros((n, 2))
        self.battery_m = np.zeros(n)
        self.beat_phase_rad = np.zeros(n)
        self._kernel: tuple | None = None

    # -------------------------------------------------------------------------------------
    # set-up and commands

    def set_pose(
        self,
        position_world_m: NDArray[np.float64],
        roll_pitch_heading_rad: NDArray[np.float64],
        velocity_through_water_body_m_s: NDArray[np.float64] | None = None,
    ) -> None:
        """Place the vehicles.

        Args:
            position_world_m: hull origin, world ENU, m, shape (n, 3) or (3,).
            roll_pitch_heading_rad: navigation attitude (roll starboard down +, pitch nose up +,
                heading clockwise from north), rad, shape (n, 3) or (3,).
            velocity_through_water_body_m_s: (u, v, w), body FLU, m/s, shape (n, 3) or (3,);
                default at rest relative to the water. Angular velocity is set to zero.
        """
        self.position_world_m[:] = position_world_m
        a = np.broadcast_to(np.asarray(roll_pitch_heading_rad, float), (self.n, 3))
        self.euler_rad[:, 0] = a[:, 0]
        self.euler_rad[:, 1] = -a[:, 1]
        self.euler_rad[:, 2] = math.pi / 2 - a[:, 2]
        self.nu_r[:] = 0.0
        if velocity_through_water_body_m_s is not None:
            self.nu_r[:, :3] = velocity_through_water_body_m_s

    def command(
        self,
        tail_beat_frequency_hz: NDArray[np.float64] | float | None = None,
        tail_bias_rad: NDArray[np.float64] | float | None = None,
        fin_port_rad: NDArray[np.float64] | float | None = None,
        fin_starboard_rad: NDArray[np.float64] | float | None = None,
        battery_m: NDArray[np.float64] | float | None = None,
    ) -> None:
        """Set commands (None keeps the previous); each a scalar or shape (n,). Units: Hz, rad
        (tail to port +; fins leading edge up +), m (battery forward +)."""
        if tail_beat_frequency_hz is not None:
            self.frequency_hz[:] = tail_beat_frequency_hz
        if tail_bias_rad is not None:
            self.bias_cmd_rad[:] = tail_bias_rad
        if fin_port_rad is not None:
            self.fins_cmd_rad[:, 0] = fin_port_rad
        if fin_starboard_rad is not None:
            self.fins_cmd_rad[:, 1] = fin_starboard_rad
        if battery_m is not None:
            self.battery_cmd_m[:] = battery_m

    def set_current_world(self, current_world_m_s: NDArray[np.float64]) -> None:
        """The water velocity at each vehicle for the next ticks, world ENU, m/s, shape (n, 3) or
        (3,)."""
        self.current_world_m_s[:] = current_world_m_s

    # -------------------------------------------------------------------------------------
    # dynamics

    def _rotation(self, eul: NDArray[np.float64]) -> NDArray[np.float64]:
        cf, sf = np.cos(eul[:, 0]), np.sin(eul[:, 0])
        ct, st = np.cos(eul[:, 1]), np.sin(eul[:, 1])
        cp, sp = np.cos(eul[:, 2]), np.sin(eul[:, 2])
        R = np.empty((eul.shape[0], 3, 3))
        R[:, 0, 0] = cp * ct
        R[:, 0, 1] = cp * st * sf - sp * cf
        R[:, 0, 2] = cp * st * cf + sp * sf
        R[:, 1, 0] = sp * ct
        R[:, 1, 1] = sp * st * sf + cp * cf
        R[:, 1, 2] = sp * st * cf - cp * sf
        R[:, 2, 0] = -st
        R[:, 2, 1] = ct * sf
        R[:, 2, 2] = ct * cf
        return R

    def generalised_force(
        self,
        eul: NDArray[np.float64],
        nu: NDArray[np.float64],
        fins: NDArray[np.float64],
        bias: NDArray[np.float64],
        battery: NDArray[np.float64],
        tail_table: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
        bias_table: NDArray[np.float64] | None = None,
    ) -> NDArray[np.float64]:
        """All forces but inertia: -C_RB nu + F_hull + F_fins + F_tail + g, body FLU about the
        hull origin, shape (n, 6) (N, N m). Arguments as the state's arrays; ``tail_table``:
        :meth:`tail_table` of the current frequencies, ``bias_table``: :meth:`bias_table` of
        ``bias`` (each computed if None)."""
        c = self.c
        v, w = nu[:, :3], nu[:, 3:]
        m = c.rigid_mass_kg
        rg = np.empty((nu.shape[0], 3))
        rg[:] = c.cg_body_m
        rg[:, 0] = c.cg_body_m[0] + (c.battery_kg / m) * battery  # the battery slides along x
        # rigid body Coriolis, Fossen (2021) eq. 3.57 with r_g: force m (w x v + w x (w x r_g)),
        # moment m r_g x (w x v) + w x (I_o w)
        wxv = _cross(w, v)
        f_c = m * (wxv + _cross(w, _cross(w, rg)))
        m_c = m * _cross(rg, wxv) + _cross(w, w @ c.inertia_origin_kg_m2.T)
        out = -np.concatenate([f_c, m_c], axis=1)
        out += hull_regressors(np.clip(nu, c.hull_box_low, c.hull_box_high)) @ c.hull
        u = nu[:, 0]
        rf = c.fin_position_body_m
        if c.fin_flow_port is not None and c.fin_flow_starboard is not None and rf is not None:
            # both fins at once, (2, n): fin_flow_regressors of each
            u_l = nu[None, :, 0] + nu[None, :, 4] * rf[:, 2:3] - nu[None, :, 5] * rf[:, 1:2]
            w_l = nu[None, :, 2] + nu[None, :, 3] * rf[:, 1:2] - nu[None, :, 4] * rf[:, 0:1]
            a = _fin_plate_change(u_l, w_l, fins.T)
            out += a[0] @ c.fin_flow_port
            out += a[1] @ c.fin_flow_starboard
        else:
            out += fin_regressors(u, fins[:, 0]) @ c.fin_port
            out += fin_regressors(u, fins[:, 1]) @ c.fin_starboard
        out += tail_regressors(self.frequency_hz, bias, u) @ c.tail
        if c.tail_heave is not None:
            out += tail_heave_regressors(self.frequency_hz, nu[:, 2]) @ c.tail_heave
        tb = bias_table if bias_table is not None else self.bias_table(bias)
        out += (u * np.abs(u))[:, None] * tb
        tab, u_ss = tail_table if tail_table is not None else self.tail_table(self.frequency_hz)
        out += tab
        out[:, 0] -= c.thrust_speed_slope * self.frequency_hz * (u - u_ss)
        # restoring: weight at the CG, buoyancy at the CB; world down in the body frame
        cf, sf = np.cos(eul[:, 0]), np.sin(eul[:, 0])
        ct, st = np.cos(eul[:, 1]), np.sin(eul[:, 1])
        down = np.empty((nu.shape[0], 3))  # R^T (0, 0, -1)
        down[:, 0] = st
        down[:, 1] = -ct * sf
        down[:, 2] = -ct * cf
        fw = c.weight_n * down
        fb = -c.buoyancy_n * down
        out[:, :3] += fw + fb
        out[:, 3:] += _cross(rg, fw) + _cross(np.broadcast_to(c.cb_body_m, fb.shape), fb)
        return out

    def bias_table(self, bias: NDArray[np.float64]) -> NDArray[np.float64]:
        """The bias table's share over u abs(u) at tail biases ``bias`` (rad, shape (n,)),
        interpolated linearly: shape (n, 6), N / (m/s)^2."""
        c = self.c
        gb = c.tail_bias_grid_rad
        xb = np.interp(bias, gb, np.arange(gb.size, dtype=float))
        ib = np.minimum(xb.astype(int), gb.size - 2)
        ab = (xb - ib)[:, None]
        return (1 - ab) * c.tail_bias_per_uu[ib] + ab * c.tail_bias_per_uu[ib + 1]

    def tail_table(self, f: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The straight-swim table at frequencies f (Hz, shape (n,)): the unbiased tail's mean
        force and moment, shape (n, 6) (N, N m), and the steady speed u_ss(f), shape (n,) (m/s);
        the thrust is changed by -k f (u - u_ss(f)) off the steady swim."""
        c = self.c
        fz = c.power_frequency_hz
        x = np.interp(f, fz, np.arange(fz.size, dtype=float))
        i = np.minimum(x.astype(int), fz.size - 2)
        a = (x - i)[:, None]
        tab = (1 - a) * c.tail_straight[i] + a * c.tail_straight[i + 1]
        us = (1 - a[:, 0]) * c.straight_speed_m_s[i] + a[:, 0] * c.straight_speed_m_s[i + 1]
        return tab, us

    def _derivative(self, eul, nu, fins, bias, battery, tab, tb):
        tau = self.generalised_force(eul, nu, fins, bias, battery, tab, tb)
        nu_dot = tau @ self._Minv.T
        R = self._rotation(eul)
        pos_dot = np.einsum("nij,nj->ni", R, nu[:, :3])
        cf, sf = np.cos(eul[:, 0]), np.sin(eul[:, 0])
        ct, tt = np.cos(eul[:, 1]), np.tan(eul[:, 1])
        p, q, r = nu[:, 3], nu[:, 4], nu[:, 5]
        eul_dot = np.empty((nu.shape[0], 3))
        eul_dot[:, 0] = p + sf * tt * q + cf * tt * r
        eul_dot[:, 1] = cf * q - sf * r
        eul_dot[:, 2] = (sf * q + cf * r) / ct
        return pos_dot, eul_dot, nu_dot

    def _kernel_args(self) -> tuple:
        """The coefficients as :func:`bauv_sim.manoeuvring.kernel.step` takes them."""
        c = self.c
        flow = c.fin_flow_port is not None and c.fin_flow_starboard is not None
        flow = flow and c.fin_position_body_m is not None
        f64 = np.ascontiguousarray

        def arr(a: NDArray[np.float64] | None, shape: tuple[int, ...]) -> NDArray[np.float64]:
            return f64(a, dtype=float) if a is not None else np.zeros(shape)

        P = (
            f64(c.hull, dtype=float),
            f64(c.hull_box_low, dtype=float),
            f64(c.hull_box_high, dtype=float),
            arr(c.fin_flow_port if flow else c.fin_port, (8, 6)),
            arr(c.fin_flow_starboard if flow else c.fin_starboard, (8, 6)),
            arr(c.fin_position_body_m if flow else None, (2, 3)),
            f64(c.tail, dtype=float),
            arr(c.tail_heave, (3, 6)),
            f64(c.inertia_origin_kg_m2, dtype=float),
            f64(c.cg_body_m, dtype=float),
            f64(c.cb_body_m, dtype=float),
            np.array(
                [c.rigid_mass_kg, c.battery_kg, c.weight_n, c.buoyancy_n, c.thrust_speed_slope]
            ),
        )
        F = (int(flow), int(c.tail_heave is not None))
        return P, F, f64(self._Minv), f64(c.tail_bias_grid_rad, dtype=float)

    def step(self) -> None:
        """Advance every run by one control tick (compiled: :mod:`bauv_sim.manoeuvring.kernel`;
        the same equations as :meth:`generalised_force`, to rounding)."""
        from bauv_sim.manoeuvring import kernel

        if self._kernel is None:
            self._kernel = self._kernel_args()
        P, F, minv, grid = self._kernel
        h = self.tick_s / self.substeps
        c = self.c
        tab, u_ss = self.tail_table(self.frequency_hz)  # the frequency is held over the tick
        # new arrays each tick, as the numpy step: a reference kept by a caller keeps its values
        pos, eul, nu = self.position_world_m.copy(), self.euler_rad.copy(), self.nu_r.copy()
        bias, fins, bat = self.bias_rad.copy(), self.fins_rad.copy(), self.battery_m.copy()
        phase = self.beat_phase_rad.copy()
        f64 = np.ascontiguousarray
        kernel.step(
            pos, eul, nu, bias, fins, bat, phase, f64(self.frequency_hz, dtype=float),
            f64(self.bias_cmd_rad, dtype=float), f64(self.fins_cmd_rad, dtype=float),
            f64(self.battery_cmd_m, dtype=float), f64(self.current_world_m_s, dtype=float),
            f64(tab), f64(u_ss), grid, f64(c.tail_bias_per_uu, dtype=float), h, self.substeps,
            math.exp(-h / c.bias_time_constant_s), math.exp(-h / c.fin_time_constant_s),
            math.exp(-h / c.battery_time_constant_s), P, F, minv,
        )  # fmt: skip
        self.position_world_m, self.euler_rad, self.nu_r = pos, eul, nu
        self.bias_rad, self.fins_rad, self.battery_m = bias, fins, bat
        self.beat_phase_rad = phase
        self.time_s += self.tick_s

    def _step_numpy(self) -> None:
        """:meth:`step` in numpy (the reference the compiled step is tested against)."""
        h = self.tick_s / self.substeps
        c = self.c
        kb = math.exp(-h / c.bias_time_constant_s)
        kf = math.exp(-h / c.fin_time_constant_s)
        kbat = math.exp(-h / c.battery_time_constant_s)
        tab = self.tail_table(self.frequency_hz)  # the frequency is held over the tick
        for _ in range(self.substeps):
            # actuators: exact first-order filters over the substep, held at their mid value
            b0, f0, t0 = self.bias_rad, self.fins_rad, self.battery_m
            b1 = self.bias_cmd_rad + (b0 - self.bias_cmd_rad) * kb
            f1 = self.fins_cmd_rad + (f0 - self.fins_cmd_rad) * kf
            t1 = self.battery_cmd_m + (t0 - self.battery_cmd_m) * kbat
            bm, fm, tm = 0.5 * (b0 + b1), 0.5 * (f0 + f1), 0.5 * (t0 + t1)
            x, e, nu = self.position_world_m, self.euler_rad, self.nu_r
            a = (fm, bm, tm, tab, self.bias_table(bm))  # held over the substep
            d1 = self._derivative(e, nu, *a)
            d2 = self._derivative(e + 0.5 * h * d1[1], nu + 0.5 * h * d1[2], *a)
            d3 = self._derivative(e + 0.5 * h * d2[1], nu + 0.5 * h * d2[2], *a)
            d4 = self._derivative(e + h * d3[1], nu + h * d3[2], *a)
            self.position_world_m = x + (h / 6) * (
                d1[0] + 2 * d2[0] + 2 * d3[0] + d4[0] + 6 * self.current_world_m_s
            )
            self.euler_rad = e + (h / 6) * (d1[1] + 2 * d2[1] + 2 * d3[1] + d4[1])
            self.nu_r = nu + (h / 6) * (d1[2] + 2 * d2[2] + 2 * d3[2] + d4[2])
            self.bias_rad, self.fins_rad, self.battery_m = b1, f1, t1
            self.beat_phase_rad = np.mod(
                self.beat_phase_rad + 2 * math.pi * h * self.frequency_hz, 2 * math.pi
            )
        self.time_s += self.tick_s

    def advance(self, duration_s: float) -> None:
        """Advance by whole ticks covering ``duration_s`` (rounded), s."""
        for _ in range(round(duration_s / self.tick_s)):
            self.step()

    # -------------------------------------------------------------------------------------
    # truth

    def _oscillation(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        c = self.c
        f = self.frequency_hz
        ay = np.interp(f, c.power_frequency_hz, c.yaw_amplitude_rad, left=0.0)
        ar = np.interp(f, c.power_frequency_hz, c.roll_amplitude_rad, left=0.0)
        return ay, ar

    def roll_pitch_heading(self, beat: bool = True) -> NDArray[np.float64]:
        """(roll, pitch, heading), rad, shape (n, 3) (conventions of the facade's
        ``roll_pitch_heading``), with the tail beat's periodic heading and roll oscillation
        (``beat=False``: the beat-averaged attitude)."""
        e = self.euler_rad
        roll = e[:, 0].copy()
        head = math.pi / 2 - e[:, 2]
        if beat:
            ay, ar = self._oscillation()
            ph = self.beat_phase_rad
            head = head + ay * np.sin(ph)
            roll = roll + ar * np.sin(ph + self.c.roll_phase_rad)
        return np.stack([roll, -e[:, 1], np.mod(head, 2 * math.pi)], axis=1)

    def angular_velocity_body(self, beat: bool = True) -> NDArray[np.float64]:
        """Angular velocity, body FLU, rad/s, shape (n, 3), with the beat's oscillation rates
        (its roll and yaw rates added about body x and z)."""
        w = self.nu_r[:, 3:].copy()
        if beat:
            ay, ar = self._oscillation()
            om = 2 * math.pi * self.frequency_hz
            ph = self.beat_phase_rad
            w[:, 0] += ar * om * np.cos(ph + self.c.roll_phase_rad)
            w[:, 2] -= ay * om * np.cos(ph)  # heading is clockwise: yaw rate is its negative
        return w

    def depth_m(self) -> NDArray[np.float64]:
        """Depth of the hull origin, m (positive down), shape (n,)."""
        return -self.position_world_m[:, 2]

    def R_world_from_body(self) -> NDArray[np.float64]:
        """Beat-averaged rotation body FLU -> world ENU, shape (n, 3, 3)."""
        return self._rotation(self.euler_rad)

    def velocity_through_water_world(self) -> NDArray[np.float64]:
        """Velocity relative to the water, world ENU, m/s, shape (n, 3)."""
        return np.einsum("nij,nj->ni", self._rotation(self.euler_rad), self.nu_r[:, :3])

    def velocity_world(self) -> NDArray[np.float64]:
        """Velocity over ground, world ENU, m/s, shape (n, 3)."""
        return self.velocity_through_water_world() + self.current_world_m_s

    def motor_power_w(self) -> NDArray[np.float64]:
        """Mean mechanical motor power at the commanded frequency (the full model's straight-swim
        table), W, shape (n,)."""
        return np.interp(self.frequency_hz, self.c.power_frequency_hz, self.c.power_w, left=0.0)
