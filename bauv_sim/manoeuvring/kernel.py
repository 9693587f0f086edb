"""The manoeuvring model's control tick compiled by numba: :meth:`ManoeuvringWorld.step`'s
Runge-Kutta substeps and :meth:`ManoeuvringWorld.generalised_force`'s equations, run by run.

numpy spends most of a tick of one run in per-call overhead (some 250 calls on arrays of one
row per force evaluation, eight evaluations per tick); here each run is a loop of scalar
operations. Every equation is the numpy implementation's, in the same order where it is
elementwise; the sums of the matrix products (regressors times coefficients, the inverse mass
matrix, the rotation) run in index order, where numpy's BLAS may pair them otherwise, so a tick
agrees with :meth:`ManoeuvringWorld.generalised_force` and the numpy step to rounding (1e-12 over
minutes of flight, ``tests/bauv_sim/test_manoeuvring.py``). IEEE 754 double, no fast-math, no
fused multiply-add; ``error_model="numpy"``. Runs are independent: a batch of n runs gives each
run the numbers it has alone, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def _cross(a0, a1, a2, b0, b1, b2):  # pragma: no cover (compiled)
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, error_model="numpy", nogil=True)
def _plate(u_l, w_l, c, s, out, sign):  # pragma: no cover (compiled)
    """Add sign x the plate's terms of ``FIN_FLOW_TERMS`` at (c, s) = (cos d, sin d) to out[8]."""
    uc = c * u_l + s * w_l
    un = -s * u_l + c * w_l
    sp = math.sqrt(uc * uc + un * un)
    inv = 1.0 / sp if sp > 0 else 0.0
    k = uc * un * inv
    ki = k * k * inv
    a_c, a_n = k * un, -k * uc
    out[0] += sign * (c * a_c - s * a_n)
    out[1] += sign * (s * a_c + c * a_n)
    a_c, a_n = ki * uc, ki * un
    out[2] += sign * (c * a_c - s * a_n)
    out[3] += sign * (s * a_c + c * a_n)
    a_n = abs(un) * un
    out[4] += sign * -(s * a_n)
    out[5] += sign * (c * a_n)
    a_c = abs(uc) * uc
    out[6] += sign * (c * a_c)
    out[7] += sign * (s * a_c)


@njit(cache=True, error_model="numpy", nogil=True)
def force(
    eul, nu, fins, bias, battery, f, tab, u_ss, tb, hull, lo, hi, fin_p, fin_s, fin_flow,
    rf, tail, heave, has_heave, inertia, cg, cb, scal, out, work,
):  # pragma: no cover (compiled)  # fmt: skip
    """One run's generalised force (``ManoeuvringWorld.generalised_force``) into out[6].

    ``fin_flow``: 1 for the fins in the local flow (``fin_p``, ``fin_s`` of shape (8, 6)), 0 for
    the fins' straight-flight fit (shape (3, 6)); ``scal``: (m, battery_kg, weight_n, buoyancy_n,
    thrust_speed_slope); ``work``: scratch, shape (90,)."""
    m, bkg, wn, bn, slope = scal[0], scal[1], scal[2], scal[3], scal[4]
    rgx = cg[0] + (bkg / m) * battery
    rgy, rgz = cg[1], cg[2]
    v0, v1, v2, w0, w1, w2 = nu[0], nu[1], nu[2], nu[3], nu[4], nu[5]
    x0, x1, x2 = _cross(w0, w1, w2, v0, v1, v2)
    y0, y1, y2 = _cross(w0, w1, w2, rgx, rgy, rgz)
    y0, y1, y2 = _cross(w0, w1, w2, y0, y1, y2)
    z0, z1, z2 = _cross(rgx, rgy, rgz, x0, x1, x2)
    i0 = w0 * inertia[0, 0] + w1 * inertia[0, 1] + w2 * inertia[0, 2]
    i1 = w0 * inertia[1, 0] + w1 * inertia[1, 1] + w2 * inertia[1, 2]
    i2 = w0 * inertia[2, 0] + w1 * inertia[2, 1] + w2 * inertia[2, 2]
    j0, j1, j2 = _cross(w0, w1, w2, i0, i1, i2)
    out[0] = -(m * (x0 + y0))
    out[1] = -(m * (x1 + y1))
    out[2] = -(m * (x2 + y2))
    out[3] = -(m * z0 + j0)
    out[4] = -(m * z1 + j1)
    out[5] = -(m * z2 + j2)
    # hull: the regressors of HULL_TERMS at the velocity held in the box
    x, h, acc, g = work[0:6], work[6:64], work[64:70], work[70:78]
    for i in range(6):
        x[i] = min(max(nu[i], lo[i]), hi[i])
    u, v, w, p, q, r = x[0], x[1], x[2], x[3], x[4], x[5]
    au, av, aw, ap, aq, ar = abs(u), abs(v), abs(w), abs(p), abs(q), abs(r)
    h[0], h[1], h[2] = u, au * u, u * u * u
    h[3], h[4], h[5], h[6], h[7] = v, w, p, q, r
    h[8], h[9], h[10], h[11], h[12] = av * v, aw * w, ap * p, aq * q, ar * r
    h[13], h[14], h[15], h[16], h[17] = u * v, u * w, u * p, u * q, u * r
    h[18], h[19], h[20], h[21] = v * w, v * p, v * q, v * r
    h[22], h[23], h[24], h[25], h[26], h[27] = w * p, w * q, w * r, p * q, p * r, q * r
    h[28], h[29], h[30], h[31] = av * r, ar * v, aw * q, aq * w
    h[32], h[33], h[34], h[35], h[36] = v * v, w * w, p * p, q * q, r * r
    h[37], h[38], h[39], h[40], h[41] = u * av, u * aw, u * ap, u * aq, u * ar
    h[42], h[43], h[44], h[45] = u * v * v, u * w * w, u * r * r, u * q * q
    h[46], h[47], h[48], h[49] = v * v * r, w * w * q, v * r * r, w * q * q
    h[50], h[51], h[52], h[53] = au * v, au * w, au * r, au * q
    h[54], h[55], h[56], h[57] = av * w, aw * v, av * p, ar * p
    acc[:] = 0.0
    for k in range(h.size):
        for j in range(6):
            acc[j] += h[k] * hull[k, j]
    for j in range(6):
        out[j] += acc[j]
    # fins
    un_ = nu[0]
    if fin_flow:
        for side in range(2):
            c_f = fin_p if side == 0 else fin_s
            u_l = nu[0] + nu[4] * rf[side, 2] - nu[5] * rf[side, 1]
            w_l = nu[2] + nu[3] * rf[side, 1] - nu[4] * rf[side, 0]
            d = fins[side]
            g[:] = 0.0
            _plate(u_l, w_l, math.cos(d), math.sin(d), g, 1.0)
            _plate(u_l, w_l, 1.0, 0.0, g, -1.0)
            acc[:] = 0.0
            for k in range(8):
                for j in range(6):
                    acc[j] += g[k] * c_f[k, j]
            for j in range(6):
                out[j] += acc[j]
    else:
        qq = un_ * abs(un_)
        for side in range(2):
            c_f = fin_p if side == 0 else fin_s
            s = math.sin(fins[side])
            g3 = (qq * s * math.cos(fins[side]), qq * s * s, qq * s * abs(s))
            acc[:] = 0.0
            for k in range(3):
                for j in range(6):
                    acc[j] += g3[k] * c_f[k, j]
            for j in range(6):
                out[j] += acc[j]
    # tail: the bias's regression, the heave term, the bias table, the straight-swim table
    s = math.sin(bias)
    uu = un_ * abs(un_)
    ff = f * f
    s2 = s * s
    t6 = (uu * s, uu * s2, uu * s2 * s, ff * s, ff * s2, ff * s2 * s)
    acc[:] = 0.0
    for k in range(6):
        for j in range(6):
            acc[j] += t6[k] * tail[k, j]
    for j in range(6):
        out[j] += acc[j]
    if has_heave:
        fw = f * nu[2]
        t3 = (fw, fw * abs(nu[2]), fw * nu[2])
        acc[:] = 0.0
        for k in range(3):
            for j in range(6):
                acc[j] += t3[k] * heave[k, j]
        for j in range(6):
            out[j] += acc[j]
    for j in range(6):
        out[j] += uu * tb[j]
    for j in range(6):
        out[j] += tab[j]
    out[0] -= slope * f * (un_ - u_ss)
    # restoring: weight at the CG, buoyancy at the CB
    cf, sf = math.cos(eul[0]), math.sin(eul[0])
    ct, st = math.cos(eul[1]), math.sin(eul[1])
    d0, d1, d2 = st, -ct * sf, -ct * cf
    fw0, fw1, fw2 = wn * d0, wn * d1, wn * d2
    fb0, fb1, fb2 = -bn * d0, -bn * d1, -bn * d2
    out[0] += fw0 + fb0
    out[1] += fw1 + fb1
    out[2] += fw2 + fb2
    a0, a1, a2 = _cross(rgx, rgy, rgz, fw0, fw1, fw2)
    b0, b1, b2 = _cross(cb[0], cb[1], cb[2], fb0, fb1, fb2)
    out[3] += a0 + b0
    out[4] += a1 + b1
    out[5] += a2 + b2


@njit(cache=True, error_model="numpy", nogil=True)
def _derivative(
    eul, nu, fins, bias, battery, f, tab, u_ss, tb, P, F, minv, d_pos, d_eul, d_nu, work
):  # pragma: no cover (compiled)
    """d(position, Euler angles, nu)/dt of one run into d_pos[3], d_eul[3], d_nu[6]."""
    hull, lo, hi, fin_p, fin_s, rf, tail, heave, inertia, cg, cb, scal = P
    fin_flow, has_heave = F
    tau = work[84:90]
    force(
        eul, nu, fins, bias, battery, f, tab, u_ss, tb, hull, lo, hi, fin_p, fin_s, fin_flow,
        rf, tail, heave, has_heave, inertia, cg, cb, scal, tau, work,
    )  # fmt: skip
    for i in range(6):
        a = 0.0
        for j in range(6):
            a += tau[j] * minv[i, j]
        d_nu[i] = a
    cf, sf = math.cos(eul[0]), math.sin(eul[0])
    ct, st = math.cos(eul[1]), math.sin(eul[1])
    cp, sp = math.cos(eul[2]), math.sin(eul[2])
    r00, r01, r02 = cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf
    r10, r11, r12 = sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf
    r20, r21, r22 = -st, ct * sf, ct * cf
    d_pos[0] = r00 * nu[0] + r01 * nu[1] + r02 * nu[2]
    d_pos[1] = r10 * nu[0] + r11 * nu[1] + r12 * nu[2]
    d_pos[2] = r20 * nu[0] + r21 * nu[1] + r22 * nu[2]
    tt = math.tan(eul[1])
    p, q, r = nu[3], nu[4], nu[5]
    d_eul[0] = p + sf * tt * q + cf * tt * r
    d_eul[1] = cf * q - sf * r
    d_eul[2] = (sf * q + cf * r) / ct


@njit(cache=True, error_model="numpy", nogil=True)
def step(
    pos, eul, nu, bias_rad, fins_rad, battery_m, phase, f_hz, bias_cmd, fins_cmd, battery_cmd,
    current, tab, u_ss, bias_grid, bias_per_uu, h, substeps, kb, kf, kbat, P, F, minv,
):  # pragma: no cover (compiled)  # fmt: skip
    """One control tick of every run, in place (:meth:`ManoeuvringWorld.step`)."""
    n = pos.shape[0]
    nb = bias_grid.size
    idx = np.arange(nb).astype(np.float64)
    k1p, k1e, k1n = np.empty(3), np.empty(3), np.empty(6)
    k2p, k2e, k2n = np.empty(3), np.empty(3), np.empty(6)
    k3p, k3e, k3n = np.empty(3), np.empty(3), np.empty(6)
    k4p, k4e, k4n = np.empty(3), np.empty(3), np.empty(6)
    e2, n2 = np.empty(3), np.empty(6)
    fm = np.empty(2)
    tb = np.empty(6)
    work = np.empty(90)
    two_pi = 2 * math.pi
    for i in range(n):
        for _ in range(substeps):
            b0, t0 = bias_rad[i], battery_m[i]
            b1 = bias_cmd[i] + (b0 - bias_cmd[i]) * kb
            t1 = battery_cmd[i] + (t0 - battery_cmd[i]) * kbat
            f1a = fins_cmd[i, 0] + (fins_rad[i, 0] - fins_cmd[i, 0]) * kf
            f1b = fins_cmd[i, 1] + (fins_rad[i, 1] - fins_cmd[i, 1]) * kf
            bm, tm = 0.5 * (b0 + b1), 0.5 * (t0 + t1)
            fm[0], fm[1] = 0.5 * (fins_rad[i, 0] + f1a), 0.5 * (fins_rad[i, 1] + f1b)
            # the bias table at bm (ManoeuvringWorld.bias_table)
            xb = np.interp(bm, bias_grid, idx)
            ib = min(int(xb), nb - 2)
            ab = xb - ib
            for j in range(6):
                tb[j] = (1 - ab) * bias_per_uu[ib, j] + ab * bias_per_uu[ib + 1, j]
            e, v = eul[i], nu[i]
            fi, ti, ui = f_hz[i], tab[i], u_ss[i]
            _derivative(e, v, fm, bm, tm, fi, ti, ui, tb, P, F, minv, k1p, k1e, k1n, work)
            for j in range(3):
                e2[j] = e[j] + 0.5 * h * k1e[j]
            for j in range(6):
                n2[j] = v[j] + 0.5 * h * k1n[j]
            _derivative(e2, n2, fm, bm, tm, fi, ti, ui, tb, P, F, minv, k2p, k2e, k2n, work)
            for j in range(3):
                e2[j] = e[j] + 0.5 * h * k2e[j]
            for j in range(6):
                n2[j] = v[j] + 0.5 * h * k2n[j]
            _derivative(e2, n2, fm, bm, tm, fi, ti, ui, tb, P, F, minv, k3p, k3e, k3n, work)
            for j in range(3):
                e2[j] = e[j] + h * k3e[j]
            for j in range(6):
                n2[j] = v[j] + h * k3n[j]
            _derivative(e2, n2, fm, bm, tm, fi, ti, ui, tb, P, F, minv, k4p, k4e, k4n, work)
            for j in range(3):
                pos[i, j] = pos[i, j] + (h / 6) * (
                    k1p[j] + 2 * k2p[j] + 2 * k3p[j] + k4p[j] + 6 * current[i, j]
                )
                eul[i, j] = e[j] + (h / 6) * (k1e[j] + 2 * k2e[j] + 2 * k3e[j] + k4e[j])
            for j in range(6):
                nu[i, j] = v[j] + (h / 6) * (k1n[j] + 2 * k2n[j] + 2 * k3n[j] + k4n[j])
            bias_rad[i], battery_m[i] = b1, t1
            fins_rad[i, 0], fins_rad[i, 1] = f1a, f1b
            phase[i] = np.mod(phase[i] + two_pi * h * f_hz[i], two_pi)
