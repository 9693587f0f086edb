"""A second, plain implementation of the equations of the plugin ``bauv.hydro``, for the tests.

Written from the model's tables and the equations of ``bauv_sim/plugin/hydro.c``'s header (not
from its code): numpy, one term at a time, MuJoCo's own ``mj_objectVelocity`` and ``mj_applyFT`` for
the kinematics. ``tests/bauv_sim/test_hydro.py`` compares the plugin's forces and mass matrix with
it at random states.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from bauv_sim import hydro


def _numeric(m: mujoco.MjModel, name: str) -> NDArray[np.float64] | None:
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, name)
    if i < 0:
        return None
    a, n = int(m.numeric_adr[i]), int(m.numeric_size[i])
    return np.array(m.numeric_data[a : a + n])


def _text(m: mujoco.MjModel, name: str) -> str | None:
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXT, name)
    if i < 0:
        return None
    a, n = int(m.text_adr[i]), int(m.text_size[i])
    return bytes(m.text_data[a : a + n]).decode().rstrip("\x00")


N_SPAN, N_CHORD = 8, 4
"""The plate's normal-force panels: span strips and chordwise panels per strip."""


def _panels(a: float, b: float, span: int) -> list[tuple[NDArray[np.float64], float]]:
    """Panels of an ellipse of semi-axes a (chord, geom x) and b (span, geom axis ``span``): span
    stations at the nodes of Gauss-Chebyshev quadrature of the second kind (weight
    sqrt(1 - eta^2), the chord's distribution), strip areas pi a b times the normalised weights,
    each strip's chord cut into N_CHORD equal panels. Position (geom frame, m) and area (m^2) of
    each."""
    theta = np.arange(1, N_SPAN + 1) * np.pi / (N_SPAN + 1)
    weight = np.sin(theta) ** 2 / np.sum(np.sin(theta) ** 2)
    xi = -1.0 + (2.0 * np.arange(N_CHORD) + 1.0) / N_CHORD
    out = []
    for th, wt in zip(theta, weight, strict=True):
        for x in xi:
            r = np.zeros(3)
            r[0], r[span] = x * np.sin(th) * a, np.cos(th) * b
            out.append((r, np.pi * a * b * wt / N_CHORD))
    return out


def free_body(m: mujoco.MjModel, prefix: str) -> int:
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, prefix + "hull")
    while m.body_jntnum[b] == 0 and m.body_parentid[b] != 0:
        b = int(m.body_parentid[b])
    return b


def reference(
    m: mujoco.MjModel, d: mujoco.MjData, prefix: str = ""
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The plugin's generalized force and the added mass it puts in the mass matrix.

    Args:
        m: model with kinematics and velocities computed in ``d``.
        d: data (``plugin_state`` holds the water).
        prefix: the vehicle's prefix.

    Returns:
        Generalized force (nv,) and the free joint's added 6 x 6 block (qvel coordinates).
    """
    inst = hydro.plugin_instances(m)[prefix]
    w, a_w = hydro.water(m, d, inst)
    rho, mu = hydro.water_properties(m)
    fb = free_body(m, prefix)
    dof = int(m.jnt_dofadr[m.body_jntadr[fb]])
    R = d.xmat[fb].reshape(3, 3)
    M_A = _numeric(m, prefix + "hydro_added_mass").reshape(6, 6)
    body = _numeric(m, prefix + "hydro_body_added_mass")
    M_B = M_A if body is None else body.reshape(6, 6)
    nu = np.r_[R.T @ (d.qvel[dof : dof + 3] - w), d.qvel[dof + 3 : dof + 6]]
    T = np.zeros((6, 6))
    T[:3, :3] = R.T
    T[3:, 3:] = np.eye(3)
    M_add = T.T @ M_A @ T
    # Kirchhoff: the hull's -C_B(nu) nu, plus M_A (w x nu_1 + R^T a_water)
    tau = hydro.coriolis_added_mass(M_B, nu)
    tau += M_A[:, :3] @ (np.cross(nu[3:], nu[:3]) + R.T @ a_w)
    # crossflow strips
    cross = _numeric(m, prefix + "hydro_crossflow")
    if cross is not None:
        for x, y, z, ay, az, cy_, cz_ in cross.reshape(-1, 7):
            ve = nu[:3] + np.cross(nu[3:], [x, y, z])
            c = np.hypot(ve[1], ve[2])
            f = -0.5 * rho * c * np.array([0.0, ay * cy_ * ve[1], az * cz_ * ve[2]])
            tau[:3] += f
            tau[3:] += np.cross([x, y, z], f)
    k_roll = _numeric(m, prefix + "hydro_roll_damping")
    if k_roll is not None:
        tau[3] -= k_roll[0] * nu[3] * abs(nu[3])
    sl = _numeric(m, prefix + "hydro_slender_lift")
    if sl is not None:
        xy, a_y, xz, a_z, f_y, f_z = sl
        u = max(nu[0], 0.0)
        for station, area, axis in ((xy, a_y, 1), (xz, a_z, 2)):
            pos = np.array([station, 0.0, 0.0])
            c = (nu[:3] + np.cross(nu[3:], pos))[axis]
            f = np.zeros(3)
            f[axis] = -rho * u * area * c
            tau[:3] += f
            tau[3:] += np.cross(pos, f)
        # the afterbody's share of the hull's Munk couple p x v (translation, p = diag(B) v) is
        # lost to separation, moving forward
        vt = np.array([u, nu[1], nu[2]])
        munk = np.cross(np.diag(M_B)[:3] * vt, vt)
        tau[5] -= f_y * munk[2]
        tau[4] -= f_z * munk[1]
    qfrc = np.zeros(m.nv)
    qfrc[dof : dof + 3] += R @ tau[:3]
    qfrc[dof + 3 : dof + 6] += tau[3:]
    # the segments' strips, each in its body's frame: the strip's velocity from the point
    # Jacobian at its world position, its force applied there
    segments = (_text(m, prefix + "hydro_segments") or "").split()
    strips = _numeric(m, prefix + "hydro_segment_crossflow")
    rolls = _numeric(m, prefix + "hydro_segment_roll_damping")
    for k, name in enumerate(segments):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, prefix + name)
        Rb = d.xmat[b].reshape(3, 3)
        for row in strips.reshape(-1, 8):
            if int(row[0]) != k:
                continue
            r, (ay, az, cy_, cz_) = row[1:4], row[4:]
            point = d.xpos[b] + Rb @ r
            jacp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jacp, None, point, b)
            ve = Rb.T @ (jacp @ d.qvel - w)
            c = np.hypot(ve[1], ve[2])
            f = -0.5 * rho * c * np.array([0.0, ay * cy_ * ve[1], az * cz_ * ve[2]])
            mujoco.mj_applyFT(m, d, Rb @ f, np.zeros(3), point, b, qfrc)
        if rolls is not None:
            jacr = np.zeros((3, m.nv))
            mujoco.mj_jacBody(m, d, None, jacr, b)
            p_seg = (Rb.T @ (jacr @ d.qvel))[0]
            torque = Rb @ np.array([-rolls[k] * p_seg * abs(p_seg), 0.0, 0.0])
            mujoco.mj_applyFT(m, d, np.zeros(3), torque, d.xpos[b], b, qfrc)
    # Froude-Krylov on every displacing body of the vehicle
    bodies = hydro.subtree_bodies(m, fb)
    if np.any(a_w != 0):
        for b in bodies:
            if m.body_gravcomp[b] > 0:
                f = m.body_gravcomp[b] * m.body_mass[b] * a_w
                mujoco.mj_applyFT(m, d, f, np.zeros(3), d.xipos[b], int(b), qfrc)
    # thin plates
    names = (_text(m, prefix + "hydro_foils") or "").split()
    cla = _numeric(m, prefix + "hydro_foil_cla")
    drag = _numeric(m, prefix + "hydro_foil_drag")
    drag = np.zeros((len(names), 3)) if drag is None else drag.reshape(-1, 3)
    for name, c_la, (c_d0, k_i, c_n) in zip(names, [] if cla is None else cla, drag, strict=True):
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, prefix + name)
        size = m.geom_size[g]
        n = 1 if size[1] <= size[2] else 2
        span = 3 - n
        area = np.pi * size[0] * size[span]
        vel = np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 1)
        Rg = d.geom_xmat[g].reshape(3, 3)
        u = vel[3:] - Rg.T @ w
        uc, un = u[0], u[n]
        speed = np.hypot(uc, un)
        # drag: profile drag of the in-plane velocity, lift-induced drag against the chord-normal
        # velocity (C_L = C_La sin a cos a), normal force of the plate's area by panels
        f = np.zeros(3)
        tangential = np.array([uc, 0.0, 0.0])
        tangential[span] = u[span]
        f -= 0.5 * rho * area * c_d0 * np.linalg.norm(tangential) * tangential
        if speed > 0:
            c_l = c_la * (uc / speed) * (un / speed)
            chord_normal = np.zeros(3)
            chord_normal[0], chord_normal[n] = uc, un
            f -= 0.5 * rho * area * k_i * c_l**2 * speed * chord_normal
        torque = np.zeros(3)
        if c_n:
            for r, d_area in _panels(size[0], size[span], span):
                u_n = (u + np.cross(vel[:3], r))[n]
                fn = np.zeros(3)
                fn[n] = -0.5 * rho * c_n * d_area * abs(u_n) * u_n
                f += fn
                torque += np.cross(r, fn)
        if c_d0 or k_i or c_n:
            mujoco.mj_applyFT(
                m, d, Rg @ f, Rg @ torque, d.geom_xpos[g], int(m.geom_bodyid[g]), qfrc
            )
        if speed == 0:
            continue
        # lift perpendicular to (uc, un) in the chord-normal plane, magnitude
        # 1/2 rho S C_La sin a cos a |u|^2 = 1/2 rho S C_La uc un
        mag = 0.5 * rho * area * c_la * uc * un
        direction = np.zeros(3)
        direction[0], direction[n] = un / speed, -uc / speed
        f = Rg @ (mag * direction)
        quarter = d.geom_xpos[g] + np.sign(uc) * 0.5 * size[0] * Rg[:, 0]  # quarter chord
        mujoco.mj_applyFT(m, d, f, np.zeros(3), quarter, int(m.geom_bodyid[g]), qfrc)
    # the model file's hydro_water: the plugin applies MuJoCo's ellipsoid model (without virtual
    # masses) in this vehicle's water; else MuJoCo's drag in this vehicle's water instead of
    # option wind
    if hydro.plugin_fluid_model(m):
        for g in hydro.fluid_geoms(m):
            if int(m.geom_bodyid[g]) in set(bodies.tolist()):
                _ellipsoid_model(m, d, int(g), w, rho, mu, qfrc)
        return qfrc, M_add
    wind = np.array(m.opt.wind)
    if not np.array_equal(w, wind):
        for g in hydro.fluid_geoms(m):
            if int(m.geom_bodyid[g]) not in set(bodies.tolist()):
                continue
            cb, cs = m.geom_fluid[g, 1], m.geom_fluid[g, 2]
            size = m.geom_size[g]
            if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:  # MuJoCo's semi-axes (r, r, r)
                size = np.array([size[0]] * 3)
            vel = np.zeros(6)
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 1)
            Rg = d.geom_xmat[g].reshape(3, 3)
            semi = np.array(size)[None]
            args = (semi, np.array([cb]), np.array([cs]), rho, mu)
            f_own = hydro.ellipsoid_drag((vel[3:] - Rg.T @ w)[None], *args)[0]
            f_ref = hydro.ellipsoid_drag((vel[3:] - Rg.T @ wind)[None], *args)[0]
            mujoco.mj_applyFT(
                m, d, Rg @ (f_own - f_ref), np.zeros(3), d.geom_xpos[g], int(m.geom_bodyid[g]), qfrc
            )
    return qfrc, M_add


def _ellipsoid_model(
    m: mujoco.MjModel,
    d: mujoco.MjData,
    g: int,
    w: NDArray[np.float64],
    rho: float,
    mu: float,
    qfrc: NDArray[np.float64],
) -> None:
    """MuJoCo's ellipsoid model of one geom without virtual mass (MuJoCo documentation, "Fluid
    forces"), one term per line, applied at the geom's centre."""
    fl = m.geom_fluid[g]
    blunt, slender, angular, kutta, magnus = fl[1:6]
    r = np.array(m.geom_size[g], dtype=float)
    if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:
        r = np.full(3, r[0])
    vel = np.zeros(6)
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_GEOM, g, vel, 1)
    Rg = d.geom_xmat[g].reshape(3, 3)
    om, u = vel[:3], vel[3:] - Rg.T @ w
    # translation: blunt and slender quadratic drag and Stokes (hydro.ellipsoid_drag)
    f = hydro.ellipsoid_drag(u[None], r[None], np.array([blunt]), np.array([slender]), rho, mu)[0]
    # rotation: Stokes -pi D^3 mu om and -rho |M| om, M_i = om_i (C_ang I_i + C_sl (I_max - I_i))
    d_eq = 2.0 / 3.0 * r.sum()
    srt = np.sort(r)
    i_max = 8.0 / 15.0 * np.pi * srt[1] * srt[2] ** 4
    ii = np.array([8.0 / 15.0 * np.pi * r[i] * max(r[(i + 1) % 3], r[(i + 2) % 3]) ** 4
                   for i in range(3)])  # fmt: skip
    mom = om * (angular * ii + slender * (i_max - ii))
    t = -(mu * np.pi * d_eq**3 + rho * np.linalg.norm(mom)) * om
    # lifts: Kutta (rho C_K cos a A_proj (n x u) x u) and Magnus (rho C_M V om x u)
    speed = np.linalg.norm(u)
    sq = np.array([(r[1] * r[2]) ** 2, (r[2] * r[0]) ** 2, (r[0] * r[1]) ** 2])
    if kutta != 0 and speed > 0:
        den, num = float(np.sum(sq**2 * u**2)), float(np.sum(sq * u**2))
        a_proj = np.pi * np.sqrt(den / num)
        f = f + kutta * rho * num / (speed * den) * a_proj * np.cross(np.cross(sq * u, u), u)
    f = f + magnus * rho * 4.0 / 3.0 * np.pi * np.prod(r) * np.cross(om, u)
    mujoco.mj_applyFT(m, d, fl[0] * (Rg @ f), fl[0] * (Rg @ t), d.geom_xpos[g],
                      int(m.geom_bodyid[g]), qfrc)  # fmt: skip
