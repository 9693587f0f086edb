"""Per-path arithmetic of the seabed shift (seed 004, eq. 12-15 and Appendix A), compiled by
numba: the hot loops of :func:`nav.seabed.fit_slopes` (:func:`seabed_fit`) and
:func:`nav.seabed.shift_estimate` (:func:`seabed_shift`), one path at a time.

Both check the shapes of their arrays and the basis before they read anything. Python checks the
input, computes the beam vectors e and their change de (eq. 8, 10), and keeps the rare branches in
numpy: Appendix A's fit where its scaled Gram matrix may have a condition number above
:data:`nav.seabed.fit.FIT_C_CONDITION` (:func:`seabed_fit` flags those paths, about 5 per cent
of seed 004's) and the SVD of eq. 15 for ``rcond < 1e-8``.

**Appendix A** (:func:`seabed_fit`). Path p has m beam feet ``x_j = (x, y, z)`` with ``valid_j``
(an echo). The seabed ``psi(x) = z + sum_l p_l psi_l(x, y)`` is fitted to the valid feet in least
squares (eq. A1 with the z coefficient fixed to 1)::

    A_jl = valid_j psi_l(x_j, y_j),   b_j = -valid_j z_j,   p = argmin |A p - b|,

through the normal equations scaled to a unit diagonal, ``D = diag(A^T A)^(-1/2)``::

    G = D A^T A D = L L^T (Cholesky),   p = D G^-1 D A^T b = D L^-T L^-1 D A^T b,

taken where the bound ``lam_max / lam_min <= (largest absolute row sum of G) trace(G^-1)`` is at
most ``max_condition`` (else the path is flagged for numpy). The basis functions ``psi_l``:
"harmonic" (kind 0) 1, ``sin(l w x), cos(l w x), sin(l v y), cos(l v y)`` for ``l = 1..K``
(``w = 2 pi / Px``, ``v = 2 pi / Py``; eq. 24), the argument reduced to one period
(``t = w (x - Px rint(x / Px))``) and ``l >= 2`` by angle addition; "plane" (kind 1) 1, x, y;
"quadratic" (kind 2) 1, x, y, x^2, x y, y^2, x and y about the mean valid foot. The gradient at
every foot is ``grad psi = (sum_l p_l dpsi_l/dx, sum_l p_l dpsi_l/dy, 1)`` (zero where not fitted
or masked).

**Eq. 15** (:func:`seabed_shift`). With the gradients ``g_j`` at the used beams (echo in both
images), the ranges ``L_j`` of image k, ``dL_j = L_{k+1} - L_k``, the beam vectors ``e_j`` and
their change ``de_j`` (eq. 8, 10)::

    A_j = g_j,   B_j = -g_j . (de_j L_j + e_j dL_j)                     (eq. 12, 14)
    A^T A = V diag(s^2) V^T (Jacobi), s_c kept where s_c > max(floor sqrt(m_used), rcond s_max)
    dX = V diag(s_inv^2) V^T A^T B                                      (eq. 15, minimum norm)

with the covariance of :mod:`nav.seabed`'s module docstring: the range-noise propagation
``sum_j Ap_j var_j Ap_j^T`` (``Ap = V diag(s_inv^2) V^T A^T``,
``var_j = sigma^2 ((g.(de - e))^2 + (g.e)^2)``), the residual one ``s^2 V diag(s_inv^2) V^T``
(``s^2 = RSS / max(m_used - rank, 1)``) unless its trace is below the former's, plus ``fallback``
along the directions not kept. A path with fewer than 3 used beams or no slope fit states no
shift: ``cmd`` (or zero) with ``fallback * I``.

Every operation follows the numpy implementation these replaced (kept in
``tests/nav/seabed_reference.py``) and, in the same order, the C library that held them until
issue 26 (its numbers bit for bit): sums may run in another order than numpy's, the fit is solved
by Cholesky and eq. 15's eigen-decomposition is Jacobi's rather than LAPACK's, so results agree
with numpy to rounding times the condition numbers (about 1e-11 relative on seed 004's images).
IEEE 754 double, no fast-math, no fused multiply-add, ``error_model="numpy"``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

FIT_MAX = 64
"""Most basis functions of the compiled fit (:func:`nav.seabed.fit.fit_slopes` checks)."""

STATUS = {
    -2: "a basis the compiled fit does not take (more than FIT_MAX functions, harmonics < 1)",
    -3: "a buffer shorter than its shape (paths, beams) says",
}
"""The refusals of :func:`seabed_fit` and :func:`seabed_shift` (their negative return values)."""

_EPS = 2.220446049250313e-16  # DBL_EPSILON


@njit(cache=True, error_model="numpy", nogil=True)
def _jacobi_eigh(n, a, w, v):  # pragma: no cover
    """Eigen-decomposition of the symmetric n x n matrix ``a`` (destroyed) by cyclic Jacobi
    rotations: eigenvalues ``w`` (n,) ascending, eigenvectors in the columns of ``v`` (n, n)."""
    norm = 0.0
    for i in range(n):
        for j in range(n):
            norm += a[i, j] * a[i, j]
    tiny = 1e-30 * math.sqrt(norm)
    for i in range(n):
        for j in range(n):
            v[i, j] = 1.0 if i == j else 0.0
    for _sweep in range(60):
        rotated = False
        for p in range(n - 1):
            for q in range(p + 1, n):
                apq = a[p, q]
                app = a[p, p]
                aqq = a[q, q]
                # negligible against the diagonal (relative accuracy of the small eigenvalues) or
                # the whole matrix
                if abs(apq) <= 0.5 * _EPS * math.sqrt(abs(app * aqq)) or abs(apq) <= tiny:
                    a[p, q] = 0.0
                    a[q, p] = 0.0
                    continue
                rotated = True
                theta = (aqq - app) / (2.0 * apq)
                t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):  # columns p, q
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(n):  # rows p, q
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                a[p, q] = 0.0
                a[q, p] = 0.0
                for k in range(n):
                    vkp = v[k, p]
                    vkq = v[k, q]
                    v[k, p] = c * vkp - s * vkq
                    v[k, q] = s * vkp + c * vkq
        if not rotated:
            break
    for i in range(n):
        w[i] = a[i, i]
    for i in range(1, n):  # insertion sort, ascending, columns of v along
        j = i
        while j > 0 and w[j - 1] > w[j]:
            tw = w[j]
            w[j] = w[j - 1]
            w[j - 1] = tw
            for k in range(n):
                tv = v[k, j]
                v[k, j] = v[k, j - 1]
                v[k, j - 1] = tv
            j -= 1


@njit(cache=True, error_model="numpy", nogil=True)
def seabed_fit(
    points, valid, kind, K, px, py, max_condition, grad, fit_ok, to_numpy
):  # pragma: no cover
    """Appendix A's fit, per path (module docstring).

    Args:
        points: feet, shape (P, m, 3), m, world (z up).
        valid: echo, shape (P, m), uint8 0/1.
        kind: 0 harmonic, 1 plane, 2 quadratic.
        K: harmonics (kind 0).
        px, py: periods Px, Py, m (kind 0).
        max_condition: largest condition number of the scaled Gram matrix solved here.
        grad: out, shape (P, m, 3): grad psi at the feet (zero where not valid or the path not
            fitted, or flagged to numpy).
        fit_ok: out, shape (P,), uint8 0/1: more valid feet than basis functions.
        to_numpy: out, shape (P,), uint8 0/1: fitted but the scaled Gram matrix may have a
            condition number above ``max_condition``; the path's grad is left zero for numpy.

    Returns:
        The number of paths flagged ``to_numpy``, or -2 (a basis of more than :data:`FIT_MAX`
        functions, ``K < 1`` or an unknown kind), -3 (an array whose shape differs from P, m);
        nothing is read or written before these checks pass.
    """
    if kind < 0 or kind > 2 or (kind == 0 and (K < 1 or K > (FIT_MAX - 1) // 4)):
        return -2
    n = 1 + 4 * K if kind == 0 else (3 if kind == 1 else 6)
    P, m = valid.shape
    if points.shape[0] != P or points.shape[1] != m or points.shape[2] != 3:
        return -3
    if grad.shape[0] != P or grad.shape[1] != m or grad.shape[2] != 3:
        return -3
    if fit_ok.shape[0] < P or to_numpy.shape[0] < P:
        return -3
    phi = np.empty((n, m))
    dx = np.empty((n, m))
    dy = np.empty((n, m))
    g = np.empty((n, n))
    mi = np.empty((n, n))
    dinv = np.empty(n)
    ys = np.empty(n)
    tmp = np.empty(n)
    pc = np.empty(n)
    f3 = np.empty(6)
    fx3 = np.empty(6)
    fy3 = np.empty(6)
    w1x = 2.0 * np.pi / px
    w1y = 2.0 * np.pi / py
    flagged = 0
    for p in range(P):
        for j in range(m):
            grad[p, j, 0] = 0.0
            grad[p, j, 1] = 0.0
            grad[p, j, 2] = 0.0
        to_numpy[p] = 0
        n_valid = 0
        for j in range(m):
            n_valid += valid[p, j] != 0
        fit_ok[p] = n_valid > n
        if not fit_ok[p]:
            continue  # its gradients are zero whatever the fit
        mx = 0.0
        my = 0.0
        if kind != 0:  # centre the polynomial bases on the valid feet
            for j in range(m):
                if valid[p, j]:
                    mx += points[p, j, 0]
                    my += points[p, j, 1]
            mx /= float(n_valid)
            my /= float(n_valid)
        for j in range(m):
            x = points[p, j, 0] - mx
            y = points[p, j, 1] - my
            if kind == 1 or kind == 2:
                f3[0], f3[1], f3[2] = 1.0, x, y
                fx3[0], fx3[1], fx3[2] = 0.0, 1.0, 0.0
                fy3[0], fy3[1], fy3[2] = 0.0, 0.0, 1.0
                if kind == 2:
                    f3[3], f3[4], f3[5] = x * x, x * y, y * y
                    fx3[3], fx3[4], fx3[5] = 2 * x, y, 0.0
                    fy3[3], fy3[4], fy3[5] = 0.0, x, 2 * y
                for l in range(n):  # noqa: E741
                    phi[l, j] = f3[l]
                    dx[l, j] = fx3[l]
                    dy[l, j] = fy3[l]
            else:
                tx = w1x * (x - px * np.rint(x / px))  # half to even, as numpy's round
                ty = w1y * (y - py * np.rint(y / py))
                sx1, cx1, sy1, cy1 = math.sin(tx), math.cos(tx), math.sin(ty), math.cos(ty)
                sx, cx, sy, cy = sx1, cx1, sy1, cy1
                phi[0, j] = 1.0
                dx[0, j] = 0.0
                dy[0, j] = 0.0
                for lv in range(1, K + 1):
                    if lv > 1:
                        sxn = sx * cx1 + cx * sx1
                        cxn = cx * cx1 - sx * sx1
                        syn = sy * cy1 + cy * sy1
                        cyn = cy * cy1 - sy * sy1
                        sx, cx, sy, cy = sxn, cxn, syn, cyn
                    wx = lv * w1x
                    wy = lv * w1y
                    r = 1 + 4 * (lv - 1)
                    phi[r, j] = sx
                    phi[r + 1, j] = cx
                    phi[r + 2, j] = sy
                    phi[r + 3, j] = cy
                    dx[r, j] = wx * cx
                    dx[r + 1, j] = -wx * sx
                    dx[r + 2, j] = 0.0
                    dx[r + 3, j] = 0.0
                    dy[r, j] = 0.0
                    dy[r + 1, j] = 0.0
                    dy[r + 2, j] = wy * cy
                    dy[r + 3, j] = -wy * sy
        # G = A^T A and A^T b over the valid feet (masked feet are zero rows of A)
        for ia in range(n):
            for ib in range(ia, n):
                acc = 0.0
                for j in range(m):
                    if valid[p, j]:
                        acc += phi[ia, j] * phi[ib, j]
                g[ia, ib] = acc
                g[ib, ia] = acc
            acc = 0.0
            for j in range(m):
                if valid[p, j]:
                    acc += phi[ia, j] * -points[p, j, 2]
            ys[ia] = acc
        for ia in range(n):
            dd = math.sqrt(g[ia, ia])
            dinv[ia] = 1.0 / dd if dd > 0 else 0.0
        for ia in range(n):
            for ib in range(n):
                g[ia, ib] = g[ia, ib] * dinv[ia] * dinv[ib]
        # G = L L^T (Cholesky, L in the lower triangle of g) and M = L^-1: G^-1 = M^T M
        bound = 0.0  # Gershgorin: lam_max <= the largest absolute row sum
        for ia in range(n):
            rs = 0.0
            for ib in range(n):
                rs += abs(g[ia, ib])
            bound = rs if rs > bound else bound
        definite = True
        for j in range(n):
            dd = g[j, j]
            for k in range(j):
                dd -= g[j, k] * g[j, k]
            if not (dd > 0.0):
                definite = False
                break
            ljj = math.sqrt(dd)
            g[j, j] = ljj
            for i in range(j + 1, n):
                acc = g[i, j]
                for k in range(j):
                    acc -= g[i, k] * g[j, k]
                g[i, j] = acc / ljj
        trace_inv = 0.0  # trace(G^-1) = |M|_F^2 >= 1 / lam_min
        if definite:
            for j in range(n):
                mi[j, j] = 1.0 / g[j, j]
                trace_inv += mi[j, j] * mi[j, j]
                for i in range(j + 1, n):
                    acc = 0.0
                    for k in range(j, i):
                        acc += g[i, k] * mi[k, j]
                    mi[i, j] = -acc / g[i, i]
                    trace_inv += mi[i, j] * mi[i, j]
        # condition number <= bound * trace_inv: solved here only where that is <= max_condition
        if not definite or not (bound * trace_inv <= max_condition):
            to_numpy[p] = 1
            flagged += 1
            continue
        for ia in range(n):
            ys[ia] = dinv[ia] * ys[ia]
        for i in range(n):  # M ys
            acc = 0.0
            for k in range(i + 1):
                acc += mi[i, k] * ys[k]
            tmp[i] = acc
        for ia in range(n):  # p = D M^T (M ys)
            acc = 0.0
            for i in range(ia, n):
                acc += mi[i, ia] * tmp[i]
            pc[ia] = dinv[ia] * acc
        for j in range(m):
            if not valid[p, j]:
                continue
            gx = 0.0
            gy = 0.0
            for l in range(n):  # noqa: E741
                gx += pc[l] * dx[l, j]
                gy += pc[l] * dy[l, j]
            grad[p, j, 0] = gx
            grad[p, j, 1] = gy
            grad[p, j, 2] = 1.0
    return flagged


@njit(cache=True, error_model="numpy", nogil=True)
def seabed_shift(
    grad,
    e,
    de,
    L0,
    L1,
    use,
    fit_ok,
    residual,
    sigma,
    fallback,
    rcond,
    singular_floor,
    cmd,
    shift,
    cov,
    beams,
    rank,
    ok,
    rms,
):  # pragma: no cover  (compiled)
    """Eq. 12-15 with the stated covariance, per path (module docstring).

    Args:
        grad: grad psi at the feet of image k, shape (P, m, 3) (rows of unused beams ignored).
        e: beam vectors of image k, shape (P, m, 3), world.
        de: their change to image k+1, shape (P, m, 3), or shape (0, 0, 3) for none (reading
            "one_attitude").
        L0, L1: ranges of images k and k+1, shape (P, m), m.
        use: echo in both images, shape (P, m), uint8 0/1.
        fit_ok: shape (P,), uint8 0/1.
        residual: True for the "residual" covariance, False for "range_noise".
        sigma: range noise standard deviation, m.
        fallback: variance of unobserved directions, m^2.
        rcond: relative singular-value cut-off.
        singular_floor: the absolute one per sqrt(beam).
        cmd: shift stated where none is produced, shape (P, 3), m, or shape (0, 3) for zero.
        shift, cov: out, shapes (P, 3) m and (P, 3, 3) m^2.
        beams, rank: out, shape (P,) int64: used beams, kept singular values.
        ok: out, shape (P,) uint8 0/1; rms: out, shape (P,), m.

    Returns:
        0, or -3 (an array whose shape differs from P, m); nothing is read or written before
        that check passes.
    """
    P, m = use.shape
    if grad.shape != (P, m, 3) or e.shape != (P, m, 3):
        return -3
    has_de = de.shape[0] != 0
    if has_de and (de.shape[0] != P or de.shape[1] != m or de.shape[2] != 3):
        return -3
    has_cmd = cmd.shape[0] != 0
    if has_cmd and (cmd.shape[0] != P or cmd.shape[1] != 3):
        return -3
    if L0.shape[0] != P or L0.shape[1] != m or L1.shape[0] != P or L1.shape[1] != m:
        return -3
    if fit_ok.shape[0] < P or shift.shape[0] < P or shift.shape[1] != 3:
        return -3
    if cov.shape[0] < P or cov.shape[1] != 3 or cov.shape[2] != 3:
        return -3
    if beams.shape[0] < P or rank.shape[0] < P or ok.shape[0] < P or rms.shape[0] < P:
        return -3
    ata = np.empty((3, 3))
    atb = np.empty(3)
    lam = np.empty(3)
    v = np.empty((3, 3))
    sv = np.empty(3)
    vt = np.empty((3, 3))
    sinv2 = np.empty(3)
    unobs = np.empty(3)
    mm = np.empty((3, 3))
    x = np.empty(3)
    tmp = np.empty(3)
    cn = np.empty((3, 3))
    cr = np.empty((3, 3))
    ap = np.empty(3)
    for p in range(P):
        ata[:] = 0.0
        atb[:] = 0.0
        nb = 0
        for j in range(m):
            if not use[p, j]:
                continue
            nb += 1
            l0 = L0[p, j]
            dl = L1[p, j] - L0[p, j]
            b = 0.0
            for c in range(3):
                dec = de[p, j, c] if has_de else 0.0
                b += grad[p, j, c] * (dec * l0 + e[p, j, c] * dl)  # eq. 12
            b = -b
            for c in range(3):
                atb[c] += grad[p, j, c] * b
                for d in range(3):
                    ata[c, d] += grad[p, j, c] * grad[p, j, d]
        beams[p] = nb
        ok[p] = fit_ok[p] != 0 and nb >= 3
        # eq. 15 by the singular values of A from the eigen-decomposition of A^T A
        _jacobi_eigh(3, ata, lam, v)
        for c in range(3):  # descending, rows of vt the right singular vectors (as an SVD's)
            sv[c] = math.sqrt(lam[2 - c] if lam[2 - c] > 0.0 else 0.0)
            for d in range(3):
                vt[c, d] = v[d, 2 - c]
        f1 = singular_floor * math.sqrt(float(nb if nb > 1 else 1))
        f2 = rcond * sv[0]
        floor = f1 if f1 > f2 else f2
        rk = 0
        for c in range(3):
            keep = sv[c] > floor
            rk += keep
            si = 1.0 / sv[c] if keep else 0.0
            sinv2[c] = si * si
            unobs[c] = 0.0 if keep else fallback
        for d in range(3):  # V diag(s_inv^2) V^T
            for f in range(3):
                acc = 0.0
                for c in range(3):
                    acc += vt[c, d] * sinv2[c] * vt[c, f]
                mm[d, f] = acc
        for c in range(3):
            acc = 0.0
            for d in range(3):
                acc += vt[c, d] * atb[d]
            tmp[c] = acc * sinv2[c]
        for d in range(3):
            acc = 0.0
            for c in range(3):
                acc += vt[c, d] * tmp[c]
            x[d] = acc
        # residual and the range-noise propagation through Ap = V diag(s_inv^2) V^T A^T
        rss = 0.0
        cn[:] = 0.0
        for j in range(m):
            if not use[p, j]:
                continue
            l0 = L0[p, j]
            dl = L1[p, j] - L0[p, j]
            b = 0.0
            r = 0.0
            gb0 = 0.0
            gb1 = 0.0
            for c in range(3):
                dec = de[p, j, c] if has_de else 0.0
                gc = grad[p, j, c]
                b += gc * (dec * l0 + e[p, j, c] * dl)
                r += gc * x[c]
                gb0 += gc * (dec - e[p, j, c])
                gb1 += gc * e[p, j, c]
            r = r + b  # A dX - B with B = -b
            rss += r * r
            var = sigma * sigma * (gb0 * gb0 + gb1 * gb1)
            for d in range(3):
                ap[d] = (
                    mm[d, 0] * grad[p, j, 0] + mm[d, 1] * grad[p, j, 1] + mm[d, 2] * grad[p, j, 2]
                )
            for d in range(3):
                for f in range(3):
                    cn[d, f] += ap[d] * var * ap[f]
        if residual:
            dof = nb - rk if nb - rk > 1 else 1
            s2 = rss / float(dof)
            for d in range(3):
                for f in range(3):
                    acc = 0.0
                    for c in range(3):
                        acc += vt[c, d] * (s2 * sinv2[c]) * vt[c, f]
                    cr[d, f] = acc
            use_res = (
                cr[0, 0] + cr[1, 1] + cr[2, 2] >= cn[0, 0] + cn[1, 1] + cn[2, 2]
            )  # never below noise
            for d in range(3):
                for f in range(3):
                    cov[p, d, f] = cr[d, f] if use_res else cn[d, f]
        else:
            for d in range(3):
                for f in range(3):
                    cov[p, d, f] = cn[d, f]
        for d in range(3):
            for f in range(3):
                acc = 0.0
                for c in range(3):
                    acc += vt[c, d] * unobs[c] * vt[c, f]
                cov[p, d, f] += acc
        if ok[p]:
            for d in range(3):
                shift[p, d] = x[d]
            rank[p] = rk
            rms[p] = math.sqrt(rss / float(nb if nb > 1 else 1))
        else:
            for d in range(3):
                shift[p, d] = cmd[p, d] if has_cmd else 0.0
            for d in range(3):
                for f in range(3):
                    cov[p, d, f] = fallback if d == f else 0.0
            rank[p] = 0
            rms[p] = 0.0
    return 0
