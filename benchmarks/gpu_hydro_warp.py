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

import argparse
import inspect
import math
import re
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
import warp as wp

if TYPE_CHECKING:  # not imported at run time: the GPU side runs without bauv_sim
    from bauv_sim.hydro_native import NativeVehicle


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


_INT_ARRAYS = (
    "body_parentid", "body_dofadr", "body_dofnum", "body_rootid", "geom_bodyid", "seg_body",
    "foil_geom", "foil_normal", "fk_body", "drag_geom",
)  # fmt: skip
_INT_SCALARS = ("free_body", "dof", "has_slender")
_FLOAT_SCALARS = ("rho", "beta", "roll_k")


def table_arrays(m: mujoco.MjModel, v: NativeVehicle) -> dict[str, np.ndarray]:
    """The kernel's model and vehicle arguments as numpy arrays (scalars 0-d), by parameter name:
    what :func:`to_warp` uploads and what ``gpu_hydro.py --export`` saves."""
    strips = [np.c_[np.full(len(s), i), s] for i, s in enumerate(v.seg_strips)]
    panels = np.stack([f.panels for f in v.foils]) if v.foils else np.zeros((0, 0, 4))
    par = [[f.half_chord, f.k_lift, *f.drag] for f in v.foils]
    return {
        "rho": np.array(m.opt.density),
        "beta": np.array(m.opt.viscosity),
        "body_parentid": np.array(m.body_parentid),
        "body_dofadr": np.array(m.body_dofadr),
        "body_dofnum": np.array(m.body_dofnum),
        "body_rootid": np.array(m.body_rootid),
        "geom_bodyid": np.array(m.geom_bodyid),
        "free_body": np.array(v.free_body),
        "dof": np.array(v.dof),
        "MA": v.M_A,
        "MB": v.M_B,
        "dA": v.dA,
        "cross_el": v.cross.reshape(-1, 7),
        "roll_k": np.array(v.roll_k),
        "has_slender": np.array(int(v.slender is not None)),
        "slender": np.zeros(6) if v.slender is None else v.slender,
        "seg_body": np.array(v.seg_bodies),
        "seg_strip": np.concatenate(strips) if strips else np.zeros((0, 8)),
        "seg_roll": v.seg_roll,
        "foil_geom": np.array([f.geom for f in v.foils]),
        "foil_normal": np.array([f.normal for f in v.foils]),
        "foil_par": np.array(par).reshape(-1, 5),
        "panels": panels,
        "fk_body": v.fk_bodies,
        "fk_mass": v.fk_mass,
        "drag_geom": v.drag_geoms,
        "drag_semi": v.drag_semi,
        "drag_coef": v.drag_coef,
    }


def to_warp(tables: dict[str, np.ndarray], device: str) -> dict[str, Any]:
    """:func:`table_arrays` as the kernel's arguments on a Warp device."""
    out: dict[str, Any] = {}
    for k, x in tables.items():
        if k in _INT_SCALARS:
            out[k] = int(x)
        elif k in _FLOAT_SCALARS:
            out[k] = float(x)
        elif k in _INT_ARRAYS:
            out[k] = wp.array(np.ascontiguousarray(x, dtype=np.int32), dtype=int, device=device)
        elif k == "drag_semi":
            out[k] = wp.array(np.ascontiguousarray(x, dtype=np.float32), dtype=vec3, device=device)
        else:
            out[k] = wp.array(np.ascontiguousarray(x, dtype=np.float32), dtype=float, device=device)
    return out


def state_from_cpu(
    m: mujoco.MjModel, datas: list[mujoco.MjData], v: NativeVehicle, device: str
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
    v: NativeVehicle,
    device: str = "cpu",
) -> np.ndarray:
    """The kernel's generalized forces for CPU data (kinematics, ``cvel`` and ``cdof`` computed),
    shape (len(datas), nv)."""
    qfrc = wp.zeros((len(datas), m.nv), dtype=float, device=device)
    args = {
        **state_from_cpu(m, datas, v, device),
        **to_warp(table_arrays(m, v), device),
        "qfrc": qfrc,
    }
    wp.launch(hydro_kernel, dim=len(datas), inputs=[args[k] for k in _PARAMS], device=device)
    return qfrc.numpy().astype(np.float64)


_PARAMS = list(inspect.signature(hydro_kernel.func).parameters)
"""The kernel's parameter names, in order."""


# ------------------------------------------------------------------------------------------------
# the GPU run: MuJoCo Warp with the kernel as its passive callback


def run(folder: Path, worlds: int, seconds: float, device: str | None = None) -> dict[str, float]:
    """Step ``worlds`` copies of the native model exported by ``gpu_hydro.py --export`` in MuJoCo
    Warp with :data:`hydro_kernel` as the passive callback.

    Args:
        folder: the export (``scene.xml`` and its assets, ``native.npz``).
        worlds: number of worlds (one vehicle each).
        seconds: simulated time, s (whole seconds of the export's track are compared).
        device: Warp device (default: Warp's default, a GPU where there is one).

    Returns:
        ``vehicles_x_real_time`` (worlds x simulated s per wall s, the first step's compilation
        excluded), ``max_error_vs_plugin_m`` and ``max_error_vs_cpu_native_m`` (world 0's hull
        position against the CPU tracks, sampled each second), ``wall_s``, ``device``.
    """
    import mujoco_warp as mjw

    z = np.load(folder / "native.npz")
    xml = (folder / "scene.xml").read_text()
    xml = re.sub(r"<extension>.*?</extension>", "", xml, flags=re.S)  # the plugin, as
    xml = re.sub(r"(<mujoco[^>]*>)", r'\1<size nuserdata="7"/>', xml, count=1)  # strip_plugin_xml
    path = folder / "native.xml"
    path.write_text(xml)
    mjm = mujoco.MjModel.from_xml_path(str(path))
    if mjm.nv != z["qvel"].size or mjm.ngeom != z["geom_fluid"].shape[0]:
        raise SystemExit(f"{path}: nv {mjm.nv}, ngeom {mjm.ngeom} differ from the export's")
    mjm.dof_armature[:] = z["dof_armature"]
    mjm.geom_fluid[:] = z["geom_fluid"]
    mjm.opt.timestep = float(z["timestep"])
    mjm.opt.wind[:] = z["wind"]
    # MuJoCo Warp has no automatic reset (the project disables it: a divergence must not restart
    # silently); the run checks that world 0's track is finite instead
    mjm.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    mjd = mujoco.MjData(mjm)
    for name in ("qpos", "qvel", "act", "ctrl", "userdata"):
        getattr(mjd, name)[:] = z[name]
    mujoco.mj_forward(mjm, mjd)
    tables = {k[2:]: z[k] for k in z.files if k.startswith("t_")}
    fb = int(tables["free_body"])
    with wp.ScopedDevice(device):
        dev = wp.get_device()
        m = mjw.put_model(mjm)
        d = mjw.put_data(mjm, mjd, nworld=worlds)
        args = to_warp(tables, str(dev))
        wind = vec3(*np.asarray(z["wind"], dtype=np.float32))

        def passive(m: Any, d: Any) -> None:
            a = {
                **args,
                "qvel": d.qvel, "qacc": d.qacc, "xmat": d.xmat, "xpos": d.xpos,
                "xipos": d.xipos, "geom_xmat": d.geom_xmat, "geom_xpos": d.geom_xpos,
                "cvel": d.cvel, "cdof": d.cdof, "subtree_com": d.subtree_com,
                "water": d.userdata, "time": d.time, "wind": wind, "qfrc": d.qfrc_passive,
            }  # fmt: skip
            wp.launch(hydro_kernel, dim=d.nworld, inputs=[a[k] for k in _PARAMS])

        m.callback.passive = passive
        per_second = round(1.0 / float(z["timestep"]))
        n_sec = max(1, int(seconds))
        track = np.zeros((n_sec, 3))
        graph = None
        if dev.is_cuda:  # one second of steps as one CUDA graph (as mujoco_warp's testspeed)
            with wp.ScopedCapture() as capture:
                for _ in range(per_second):
                    mjw.step(m, d)
            graph = capture.graph  # recorded, not run: d is still at the start
        else:
            warm = mjw.put_data(mjm, mjd, nworld=worlds)
            mjw.step(m, warm)  # compiles the kernels
        t0 = time.perf_counter()
        for k in range(n_sec):
            if graph is not None:
                wp.capture_launch(graph)
            else:
                for _ in range(per_second):
                    mjw.step(m, d)
            track[k] = d.xpos.numpy()[0, fb]
        wp.synchronize()
        wall = time.perf_counter() - t0
    if not np.all(np.isfinite(track)):
        raise SystemExit("gpu_hydro_warp: world 0's track is not finite")
    return {
        "device": str(dev),
        "worlds": worlds,
        "seconds": n_sec,
        "wall_s": wall,
        "vehicles_x_real_time": worlds * n_sec / wall,
        "max_error_vs_plugin_m": float(np.abs(track - z["plugin_track"][:n_sec]).max()),
        "max_error_vs_cpu_native_m": float(np.abs(track - z["native_track"][:n_sec]).max()),
        "distance_flown_m": float(np.linalg.norm(z["plugin_track"][n_sec - 1] - z["qpos"][:3])),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="MuJoCo Warp run of the native hydrodynamics")
    ap.add_argument("folder", type=Path, help="the export of gpu_hydro.py --export")
    ap.add_argument("--worlds", type=int, default=4096)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--device", default=None, help="Warp device (default: Warp's)")
    a = ap.parse_args(argv)
    if a.worlds < 1 or not (a.seconds >= 1 and math.isfinite(a.seconds)):
        print(f"worlds = {a.worlds}, seconds = {a.seconds}: need >= 1 each", file=sys.stderr)
        return 2
    if not (a.folder / "native.npz").exists():
        print(f"folder = {a.folder}: no native.npz (run gpu_hydro.py --export)", file=sys.stderr)
        return 2
    for k, v in run(a.folder, a.worlds, a.seconds, a.device).items():
        print(f"{k}: {v:.4g}" if isinstance(v, float) else f"{k}: {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
