"""The native formulation's passive force as a Warp kernel (``docs/gpu.md``, "Running on MuJoCo
Warp"): :func:`bauv_sim.hydro_native.vehicle_force` written again over ``(world,)`` for one vehicle
per world, reading MuJoCo's per-world arrays (``qvel``, ``qacc``, ``xmat``, ``xpos``, ``xipos``,
``geom_xmat``, ``geom_xpos``, ``cvel``, ``cdof``, ``subtree_com``) and the vehicle's tables,
writing ``qfrc_passive`` only. Forces at points are ``J^T f`` along the body's chain from
``cdof`` (as ``mj_applyFT``), velocities of bodies and geoms from ``cvel`` (as
``mj_objectVelocity``). Single precision, as MuJoCo Warp.

Needs ``warp-lang`` (not a dependency of the project). ``tests/bauv_sim/test_hydro_warp.py`` runs
the kernel on Warp's CPU device on arrays copied from CPU MuJoCo data and compares it with
:func:`~bauv_sim.hydro_native.vehicle_force`; it is skipped where Warp is not installed.
"""

from __future__ import annotations

import inspect
from typing import Any

import mujoco
import numpy as np
import warp as wp

from bauv_sim import hydro_native

vec3 = wp.vec3
mat33 = wp.mat33
spatial = wp.spatial_vector


@wp.func
def _apply_ft(
    world: int,
    f: vec3,
    t: vec3,
    point: vec3,
    body: int,
    body_parentid: wp.array(dtype=int),
    body_dofadr: wp.array(dtype=int),
    body_dofnum: wp.array(dtype=int),
    body_rootid: wp.array(dtype=int),
    subtree_com: wp.array2d(dtype=vec3),
    cdof: wp.array2d(dtype=spatial),
    qfrc: wp.array2d(dtype=float),
):
    off = point - subtree_com[world, body_rootid[body]]
    b = body
    while b > 0:
        start = body_dofadr[b]
        for j in range(start, start + body_dofnum[b]):
            c = cdof[world, j]
            ang = wp.spatial_top(c)
            lin = wp.spatial_bottom(c)
            qfrc[world, j] = qfrc[world, j] + wp.dot(f, lin + wp.cross(ang, off)) + wp.dot(t, ang)
        b = body_parentid[b]


@wp.func
def _local_velocity(
    world: int,
    body: int,
    pos: vec3,
    rot: mat33,
    body_rootid: wp.array(dtype=int),
    subtree_com: wp.array2d(dtype=vec3),
    cvel: wp.array2d(dtype=spatial),
):
    c = cvel[world, body]
    ang = wp.spatial_top(c)
    lin = wp.spatial_bottom(c) - wp.cross(pos - subtree_com[world, body_rootid[body]], ang)
    rt = wp.transpose(rot)
    a = rt @ ang
    v = rt @ lin
    return spatial(a[0], a[1], a[2], v[0], v[1], v[2])


@wp.func
def _ellipsoid_drag(u: vec3, r: vec3, blunt: float, slender: float, rho: float, beta: float):
    speed = wp.length(u)
    lo = wp.min(r[0], wp.min(r[1], r[2]))
    hi = wp.max(r[0], wp.max(r[1], r[2]))
    mid = r[0] + r[1] + r[2] - lo - hi
    a_max = wp.pi * hi * mid
    a_proj = 0.0
    if speed > 0.0:
        x = u[0] / speed
        y = u[1] / speed
        z = u[2] / speed
        r0 = r[0] * r[0]
        r1 = r[1] * r[1]
        r2 = r[2] * r[2]
        num = r1 * r1 * r2 * r2 * x * x + r2 * r2 * r0 * r0 * y * y + r0 * r0 * r1 * r1 * z * z
        den = r1 * r2 * x * x + r2 * r0 * y * y + r0 * r1 * z * z
        if den > 0.0:
            a_proj = wp.pi * wp.sqrt(num / den)
    c = -rho * (blunt * a_proj + slender * (a_max - a_proj)) * speed
    c = c - 6.0 * wp.pi * (r[0] + r[1] + r[2]) / 3.0 * beta
    return c * u


@wp.kernel
def hydro_kernel(
    qvel: wp.array2d(dtype=float),
    qacc: wp.array2d(dtype=float),
    xmat: wp.array2d(dtype=mat33),
    xpos: wp.array2d(dtype=vec3),
    xipos: wp.array2d(dtype=vec3),
    geom_xmat: wp.array2d(dtype=mat33),
    geom_xpos: wp.array2d(dtype=vec3),
    cvel: wp.array2d(dtype=spatial),
    cdof: wp.array2d(dtype=spatial),
    subtree_com: wp.array2d(dtype=vec3),
    water: wp.array2d(dtype=float),
    time: wp.array(dtype=float),
    wind: vec3,
    rho: float,
    beta: float,
    body_parentid: wp.array(dtype=int),
    body_dofadr: wp.array(dtype=int),
    body_dofnum: wp.array(dtype=int),
    body_rootid: wp.array(dtype=int),
    geom_bodyid: wp.array(dtype=int),
    free_body: int,
    dof: int,
    MA: wp.array2d(dtype=float),
    MB: wp.array2d(dtype=float),
    dA: wp.array2d(dtype=float),
    cross_el: wp.array2d(dtype=float),
    roll_k: float,
    has_slender: int,
    slender: wp.array(dtype=float),
    seg_body: wp.array(dtype=int),
    seg_strip: wp.array2d(dtype=float),
    seg_roll: wp.array(dtype=float),
    foil_geom: wp.array(dtype=int),
    foil_normal: wp.array(dtype=int),
    foil_par: wp.array2d(dtype=float),
    panels: wp.array3d(dtype=float),
    fk_body: wp.array(dtype=int),
    fk_mass: wp.array(dtype=float),
    drag_geom: wp.array(dtype=int),
    drag_semi: wp.array(dtype=vec3),
    drag_coef: wp.array2d(dtype=float),
    qfrc: wp.array2d(dtype=float),
):
    world = wp.tid()
    dt_w = time[world] - water[world, 6]
    a_w = vec3(water[world, 3], water[world, 4], water[world, 5])
    w = vec3(water[world, 0], water[world, 1], water[world, 2]) + a_w * dt_w
    R = xmat[world, free_body]
    Rt = wp.transpose(R)
    nl = Rt @ (vec3(qvel[world, dof], qvel[world, dof + 1], qvel[world, dof + 2]) - w)
    na = vec3(qvel[world, dof + 3], qvel[world, dof + 4], qvel[world, dof + 5])
    qal = Rt @ vec3(qacc[world, dof], qacc[world, dof + 1], qacc[world, dof + 2])
    qaa = vec3(qacc[world, dof + 3], qacc[world, dof + 4], qacc[world, dof + 5])
    # Kirchhoff -C_B(nu) nu; M_A (w x nu_1 + R^T a_water); the lagged residual -dA T qacc
    pl = vec3(0.0, 0.0, 0.0)
    L = vec3(0.0, 0.0, 0.0)
    ext = wp.cross(na, nl) + Rt @ a_w
    tf = vec3(0.0, 0.0, 0.0)
    tt = vec3(0.0, 0.0, 0.0)
    for i in range(3):
        for j in range(3):
            pl[i] = pl[i] + MB[i, j] * nl[j] + MB[i, j + 3] * na[j]
            L[i] = L[i] + MB[i + 3, j] * nl[j] + MB[i + 3, j + 3] * na[j]
            tf[i] = tf[i] + MA[i, j] * ext[j] - dA[i, j] * qal[j] - dA[i, j + 3] * qaa[j]
            tt[i] = (
                tt[i] + MA[i + 3, j] * ext[j] - dA[i + 3, j] * qal[j] - dA[i + 3, j + 3] * qaa[j]
            )
    tf = tf + wp.cross(pl, na)
    tt = tt + wp.cross(pl, nl) + wp.cross(L, na)
    p = na[0]
    q = na[1]
    r = na[2]
    for k in range(cross_el.shape[0]):
        x = cross_el[k, 0]
        y = cross_el[k, 1]
        z = cross_el[k, 2]
        cy = nl[1] + r * x - p * z
        cz = nl[2] + p * y - q * x
        c = wp.sqrt(cy * cy + cz * cz)
        gy = -0.5 * rho * cross_el[k, 3] * cross_el[k, 5] * c * cy
        gz = -0.5 * rho * cross_el[k, 4] * cross_el[k, 6] * c * cz
        tf = tf + vec3(0.0, gy, gz)
        tt = tt + vec3(y * gz - z * gy, -x * gz, x * gy)
    tt = tt - vec3(roll_k * p * wp.abs(p), 0.0, 0.0)
    if has_slender != 0:
        uu = wp.max(nl[0], 0.0)
        ly = -rho * uu * slender[1] * (nl[1] + r * slender[0])
        lz = -rho * uu * slender[3] * (nl[2] - q * slender[2])
        tf = tf + vec3(0.0, ly, lz)
        yaw = slender[0] * ly + slender[4] * (MB[1, 1] - MB[0, 0]) * uu * nl[1]
        pitch = slender[2] * lz + slender[5] * (MB[2, 2] - MB[0, 0]) * uu * nl[2]
        tt = tt + vec3(0.0, -pitch, yaw)
    fw = R @ tf
    for i in range(3):
        qfrc[world, dof + i] = qfrc[world, dof + i] + fw[i]
        qfrc[world, dof + 3 + i] = qfrc[world, dof + 3 + i] + tt[i]
    zero = vec3(0.0, 0.0, 0.0)
    if wp.length(a_w) > 0.0:  # Froude-Krylov
        for k in range(fk_body.shape[0]):
            b = fk_body[k]
            _apply_ft(world, fk_mass[k] * a_w, zero, xipos[world, b], b, body_parentid,
                      body_dofadr, body_dofnum, body_rootid, subtree_com, cdof, qfrc)  # fmt: skip
    for i in range(seg_body.shape[0]):
        b = seg_body[i]
        Rb = xmat[world, b]
        vel = _local_velocity(world, b, xpos[world, b], Rb, body_rootid, subtree_com, cvel)
        om = wp.spatial_top(vel)
        ub = wp.spatial_bottom(vel) - wp.transpose(Rb) @ w
        fs = vec3(0.0, 0.0, 0.0)
        ts = vec3(0.0, 0.0, 0.0)
        for k in range(seg_strip.shape[0]):
            if int(seg_strip[k, 0]) != i:
                continue
            rr = vec3(seg_strip[k, 1], seg_strip[k, 2], seg_strip[k, 3])
            wr = wp.cross(om, rr)
            cy = ub[1] + wr[1]
            cz = ub[2] + wr[2]
            c = wp.sqrt(cy * cy + cz * cz)
            fk = vec3(
                0.0,
                -0.5 * rho * seg_strip[k, 4] * seg_strip[k, 6] * c * cy,
                -0.5 * rho * seg_strip[k, 5] * seg_strip[k, 7] * c * cz,
            )
            fs = fs + fk
            ts = ts + wp.cross(rr, fk)
        ts = ts - vec3(seg_roll[i] * om[0] * wp.abs(om[0]), 0.0, 0.0)
        _apply_ft(world, Rb @ fs, Rb @ ts, xpos[world, b], b, body_parentid, body_dofadr,
                  body_dofnum, body_rootid, subtree_com, cdof, qfrc)  # fmt: skip
    for i in range(foil_geom.shape[0]):
        g = foil_geom[i]
        b = geom_bodyid[g]
        Rg = geom_xmat[world, g]
        vel = _local_velocity(world, b, geom_xpos[world, g], Rg, body_rootid, subtree_com, cvel)
        om = wp.spatial_top(vel)
        ul = wp.spatial_bottom(vel) - wp.transpose(Rg) @ w
        n = foil_normal[i]
        span = 3 - n
        uc = ul[0]
        un = ul[n]
        sp = wp.sqrt(uc * uc + un * un)
        c_d0 = foil_par[i, 2]
        k_i = foil_par[i, 3]
        c_n = foil_par[i, 4]
        if c_d0 != 0.0 or k_i != 0.0 or c_n != 0.0:
            fp = vec3(0.0, 0.0, 0.0)
            tp = vec3(0.0, 0.0, 0.0)
            ut = wp.sqrt(uc * uc + ul[span] * ul[span])
            fp[0] = fp[0] - c_d0 * ut * uc
            fp[span] = fp[span] - c_d0 * ut * ul[span]
            if sp > 0.0:
                di = k_i * uc * uc * un * un / (sp * sp * sp)
                fp[0] = fp[0] - di * uc
                fp[n] = fp[n] - di * un
            if c_n != 0.0:
                for k in range(panels.shape[1]):
                    rr = vec3(panels[i, k, 0], panels[i, k, 1], panels[i, k, 2])
                    unp = un + wp.cross(om, rr)[n]
                    fv = vec3(0.0, 0.0, 0.0)
                    fv[n] = -c_n * panels[i, k, 3] * wp.abs(unp) * unp
                    fp = fp + fv
                    tp = tp + wp.cross(rr, fv)
            _apply_ft(world, Rg @ fp, Rg @ tp, geom_xpos[world, g], b, body_parentid,
                      body_dofadr, body_dofnum, body_rootid, subtree_com, cdof, qfrc)  # fmt: skip
        if sp > 0.0:
            kl = foil_par[i, 1] * uc * un / sp
            fl = vec3(kl * un, 0.0, 0.0)
            fl[n] = -kl * uc
            off = 0.5 * foil_par[i, 0]
            if uc <= 0.0:
                off = -off
            quarter = geom_xpos[world, g] + off * vec3(Rg[0, 0], Rg[1, 0], Rg[2, 0])
            _apply_ft(world, Rg @ fl, zero, quarter, b, body_parentid, body_dofadr,
                      body_dofnum, body_rootid, subtree_com, cdof, qfrc)  # fmt: skip
    if w[0] != wind[0] or w[1] != wind[1] or w[2] != wind[2]:
        for k in range(drag_geom.shape[0]):
            g = drag_geom[k]
            b = geom_bodyid[g]
            Rg = geom_xmat[world, g]
            vel = _local_velocity(world, b, geom_xpos[world, g], Rg, body_rootid, subtree_com, cvel)
            lin = wp.spatial_bottom(vel)
            Rgt = wp.transpose(Rg)
            fo = _ellipsoid_drag(
                lin - Rgt @ w, drag_semi[k], drag_coef[k, 0], drag_coef[k, 1], rho, beta
            )
            fr = _ellipsoid_drag(
                lin - Rgt @ wind, drag_semi[k], drag_coef[k, 0], drag_coef[k, 1], rho, beta
            )
            _apply_ft(world, Rg @ (fo - fr), zero, geom_xpos[world, g], b, body_parentid,
                      body_dofadr, body_dofnum, body_rootid, subtree_com, cdof, qfrc)  # fmt: skip


def vehicle_tables(m: mujoco.MjModel, v: hydro_native.NativeVehicle, device: str) -> dict[str, Any]:
    """The kernel's model and vehicle arguments (Warp arrays on ``device``), by parameter name."""

    def arr(x, dtype=float):
        return wp.array(np.ascontiguousarray(x), dtype=dtype, device=device)

    strips = [np.c_[np.full(len(s), i), s] for i, s in enumerate(v.seg_strips)]
    panels = np.stack([f.panels for f in v.foils]) if v.foils else np.zeros((0, 0, 4))
    par = [[f.half_chord, f.k_lift, *f.drag] for f in v.foils]
    return {
        "rho": float(m.opt.density),
        "beta": float(m.opt.viscosity),
        "body_parentid": arr(m.body_parentid, int),
        "body_dofadr": arr(m.body_dofadr, int),
        "body_dofnum": arr(m.body_dofnum, int),
        "body_rootid": arr(m.body_rootid, int),
        "geom_bodyid": arr(m.geom_bodyid, int),
        "free_body": int(v.free_body),
        "dof": int(v.dof),
        "MA": arr(v.M_A),
        "MB": arr(v.M_B),
        "dA": arr(v.dA),
        "cross_el": arr(v.cross.reshape(-1, 7)),
        "roll_k": float(v.roll_k),
        "has_slender": int(v.slender is not None),
        "slender": arr(np.zeros(6) if v.slender is None else v.slender),
        "seg_body": arr(v.seg_bodies, int),
        "seg_strip": arr(np.concatenate(strips) if strips else np.zeros((0, 8))),
        "seg_roll": arr(v.seg_roll),
        "foil_geom": arr([f.geom for f in v.foils], int),
        "foil_normal": arr([f.normal for f in v.foils], int),
        "foil_par": arr(np.array(par).reshape(-1, 5)),
        "panels": arr(panels),
        "fk_body": arr(v.fk_bodies, int),
        "fk_mass": arr(v.fk_mass),
        "drag_geom": arr(v.drag_geoms, int),
        "drag_semi": arr(v.drag_semi, vec3),
        "drag_coef": arr(v.drag_coef),
    }


def state_from_cpu(
    m: mujoco.MjModel, datas: list[mujoco.MjData], v: hydro_native.NativeVehicle, device: str
) -> dict[str, Any]:
    """The kernel's per-world arguments from CPU MuJoCo data (one world per data), by name."""

    def arr(name, dtype, shape=None):
        x = np.stack([np.asarray(getattr(d, name)) for d in datas])
        if shape is not None:
            x = x.reshape(len(datas), *shape)
        return wp.array(np.ascontiguousarray(x, dtype=np.float32), dtype=dtype, device=device)

    water = np.stack([d.userdata[v.water_adr : v.water_adr + 7] for d in datas])
    return {
        "qvel": arr("qvel", float),
        "qacc": arr("qacc", float),
        "xmat": arr("xmat", mat33, (m.nbody, 3, 3)),
        "xpos": arr("xpos", vec3),
        "xipos": arr("xipos", vec3),
        "geom_xmat": arr("geom_xmat", mat33, (m.ngeom, 3, 3)),
        "geom_xpos": arr("geom_xpos", vec3),
        "cvel": arr("cvel", spatial),
        "cdof": arr("cdof", spatial),
        "subtree_com": arr("subtree_com", vec3),
        "water": wp.array(water.astype(np.float32), dtype=float, device=device),
        "time": wp.array(np.array([d.time for d in datas], dtype=np.float32), device=device),
        "wind": vec3(*np.asarray(m.opt.wind, dtype=np.float32)),
    }


def forces(
    m: mujoco.MjModel,
    datas: list[mujoco.MjData],
    v: hydro_native.NativeVehicle,
    device: str = "cpu",
) -> np.ndarray:
    """The kernel's generalized forces for CPU data (kinematics, ``cvel`` and ``cdof`` computed),
    shape (len(datas), nv)."""
    qfrc = wp.zeros((len(datas), m.nv), dtype=float, device=device)
    args = {**state_from_cpu(m, datas, v, device), **vehicle_tables(m, v, device), "qfrc": qfrc}
    wp.launch(hydro_kernel, dim=len(datas), inputs=[args[k] for k in _PARAMS], device=device)
    return qfrc.numpy().astype(np.float64)


_PARAMS = list(inspect.signature(hydro_kernel.func).parameters)
"""The kernel's parameter names, in order."""
