// Per-path arithmetic of the seabed shift (seed 004, eq. 12-15 and Appendix A): the hot loops of
// nav.seabed.fit_slopes and nav.seabed.shift_estimate, one path at a time.
//
// A plain C library without Python API, loaded with ctypes by nav.clib (nav/seabed/kernel.py).
// Both entry points take their struct of the shared header nav/clib.h (bauv_seabed_fit_args,
// bauv_seabed_shift_args: every buffer with its size), whose layout the loader checks against
// its Python mirror, and check the sizes of their buffers and the basis before they read
// anything, whatever the caller passes. Python checks the input, computes the beam vectors e and their change de (eq. 8, 10), and keeps
// the rare branches in numpy: Appendix A's fit where its scaled Gram matrix may have a condition
// number above nav.seabed.FIT_C_CONDITION = 1e4 (bauv_seabed_fit flags those paths, about 5 per
// cent of seed 004's) and the SVD of eq. 15 for rcond < 1e-8.
//
// Appendix A (bauv_seabed_fit). Path p has m beam feet x_j = (x, y, z) with valid_j (an echo). The
// seabed psi(x) = z + sum_l p_l psi_l(x, y) is fitted to the valid feet in least squares (eq. A1
// with the z coefficient fixed to 1):
//
//   A_jl = valid_j psi_l(x_j, y_j),   b_j = -valid_j z_j,   p = argmin |A p - b|,
//
// through the normal equations scaled to a unit diagonal, D = diag(A^T A)^(-1/2):
//
//   G = D A^T A D = L L^T (Cholesky),   p = D G^-1 D A^T b = D L^-T L^-1 D A^T b,
//
// taken where the bound lam_max / lam_min <= (largest absolute row sum of G) trace(G^-1) is at
// most max_condition (else the path is flagged for numpy, nav.seabed._fit_slopes_numpy, whose
// eigen-decomposition or pinv keep the numbers of the numpy implementation there). The basis
// functions psi_l: "harmonic" (kind 0) 1, sin(l w x), cos(l w x), sin(l v y), cos(l v y) for
// l = 1..K (w = 2 pi / Px, v = 2 pi / Py; eq. 24), with the argument reduced to one period,
// t = w (x - Px rint(x / Px)), and l >= 2 by angle addition; "plane" (kind 1) 1, x, y; "quadratic"
// (kind 2) 1, x, y, x^2, x y, y^2, x and y about the mean valid foot. The gradient at every foot is
//
//   grad psi = (sum_l p_l dpsi_l/dx, sum_l p_l dpsi_l/dy, 1)   (zero where not fitted or masked).
//
// Eq. 15 (bauv_seabed_shift). With the gradients g_j at the used beams (echo in both images; zero
// rows elsewhere), the ranges L_j of image k, dL_j = L_{k+1} - L_k, the beam vectors e_j and their
// change de_j (eq. 8, 10):
//
//   A_j = g_j,   B_j = -g_j . (de_j L_j + e_j dL_j)                     (eq. 12, 14)
//   A^T A = V diag(s^2) V^T (Jacobi), s_c kept where s_c > max(floor sqrt(m_used), rcond s_max)
//   dX = V diag(s_inv^2) V^T A^T B                                      (eq. 15, minimum norm)
//
// with the covariance of nav.seabed's module docstring: the range-noise propagation
// sum_j Ap_j var_j Ap_j^T (Ap = V diag(s_inv^2) V^T A^T, var_j = sigma^2 ((g.(de - e))^2 +
// (g.e)^2)), the residual one s^2 V diag(s_inv^2) V^T (s^2 = RSS / max(m_used - rank, 1)) unless
// its trace is below the former's, plus fallback along the directions not kept. A path with
// fewer than 3 used beams or no slope fit states no shift: cmd (or zero) with fallback * I.
//
// Every operation follows the numpy implementation it replaced (kept in
// tests/nav/seabed_reference.py); sums may run in another order, the fit is solved by Cholesky
// and eq. 15's eigen-decomposition is Jacobi's rather than LAPACK's, so results agree to rounding
// times the condition numbers (about 1e-11 relative on seed 004's images), not bit for bit.
// IEEE 754 double, no fast-math, no FMA contraction (compile with -ffp-contract=off).

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "clib.h"

BAUV_DEFINE_LAYOUT(bauv_seabed_fit_args, BAUV_SEABED_FIT_ARGS)
BAUV_DEFINE_LAYOUT(bauv_seabed_shift_args, BAUV_SEABED_SHIFT_ARGS)

#define FIT_MAX 64  // most basis functions of the fit (nav/seabed/fit.py checks)

static const double PI = 3.14159265358979323846;  // numpy.pi

// Eigen-decomposition of the symmetric n x n matrix a (row-major, destroyed) by cyclic Jacobi
// rotations: eigenvalues w (n) ascending, eigenvectors in the columns of v (n x n, row-major).
static void jacobi_eigh(int n, double* a, double* w, double* v) {
  double norm = 0.0;
  for (int i = 0; i < n * n; ++i) norm += a[i] * a[i];
  const double tiny = 1e-30 * sqrt(norm);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) v[i * n + j] = (i == j) ? 1.0 : 0.0;
  for (int sweep = 0; sweep < 60; ++sweep) {
    int rotated = 0;
    for (int p = 0; p < n - 1; ++p) {
      for (int q = p + 1; q < n; ++q) {
        const double apq = a[p * n + q];
        const double app = a[p * n + p], aqq = a[q * n + q];
        // negligible against the diagonal (relative accuracy of the small eigenvalues) or the
        // whole matrix
        if (fabs(apq) <= 0.5 * DBL_EPSILON * sqrt(fabs(app * aqq)) || fabs(apq) <= tiny) {
          a[p * n + q] = a[q * n + p] = 0.0;
          continue;
        }
        rotated = 1;
        const double theta = (aqq - app) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) {  // columns p, q
          const double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) {  // rows p, q
          const double apk = a[p * n + k], aqk = a[q * n + k];
          a[p * n + k] = c * apk - s * aqk;
          a[q * n + k] = s * apk + c * aqk;
        }
        a[p * n + q] = a[q * n + p] = 0.0;
        for (int k = 0; k < n; ++k) {
          const double vkp = v[k * n + p], vkq = v[k * n + q];
          v[k * n + p] = c * vkp - s * vkq;
          v[k * n + q] = s * vkp + c * vkq;
        }
      }
    }
    if (!rotated) break;
  }
  for (int i = 0; i < n; ++i) w[i] = a[i * n + i];
  for (int i = 1; i < n; ++i) {  // insertion sort, ascending, columns of v along
    for (int j = i; j > 0 && w[j - 1] > w[j]; --j) {
      const double tw = w[j];
      w[j] = w[j - 1];
      w[j - 1] = tw;
      for (int k = 0; k < n; ++k) {
        const double tv = v[k * n + j];
        v[k * n + j] = v[k * n + j - 1];
        v[k * n + j - 1] = tv;
      }
    }
  }
}

// Appendix A's fit, per path (bauv_seabed_fit_args: paths = P, feet = m, kind, harmonics = K, px,
// py, max_condition, points, valid, grad, fit_ok, to_numpy; each buffer with its size).
//
// Args (P paths, m feet, all arrays C-contiguous):
//   P, m: paths and feet per path.
//   points: feet (P, m, 3), m, world (z up).
//   valid: echo (P, m), 0/1.
//   kind: 0 harmonic, 1 plane, 2 quadratic.
//   K: harmonics (kind 0).
//   px, py: periods Px, Py, m (kind 0).
//   max_condition: largest condition number of the scaled Gram matrix solved here (Python's
//     FIT_C_CONDITION: LAPACK's eigen-decomposition and this one give solutions that differ by
//     about the condition number times the rounding error).
//
// Results:
//   grad: (P, m, 3), grad psi at the feet (zero where not valid or the path not fitted).
//   fit_ok: (P,), 0/1: more valid feet than basis functions.
//   to_numpy: (P,), 0/1: fit_ok but the scaled Gram matrix has a condition number above
//     max_condition; grad of the path is left zero for numpy.
//
// sizes: the number of elements of each buffer as allocated by the caller, in the order
//   points, valid, grad, fit_ok, to_numpy
// (n_sizes of them, 5); nothing is read or written unless each holds what P and m say (3 P m,
// P m, 3 P m, P, P).
//
// Returns the number of paths flagged to_numpy, or -1 (out of memory), -2 (a basis of more than
// FIT_MAX functions, K < 1 or an unknown kind), -3 (a buffer shorter than P and m say, P < 0,
// m < 0, or a size product overflowing).
static int64_t seabed_fit(int64_t P, int64_t m, const double* points, const uint8_t* valid,
                        int64_t kind, int64_t K, double px, double py, double max_condition,
                        double* grad, uint8_t* fit_ok, uint8_t* to_numpy, const int64_t* sizes,
                        int64_t n_sizes) {
  if (kind < 0 || kind > 2 || (kind == 0 && (K < 1 || K > (FIT_MAX - 1) / 4))) return -2;
  const int n = kind == 0 ? (int)(1 + 4 * K) : (kind == 1 ? 3 : 6);  // K bounded: no overflow
  if (n_sizes != 5 || !sizes || P < 0 || m < 0) return -3;
  if (m > 0 && P > INT64_MAX / 3 / m) return -3;
  const int64_t need[5] = {3 * P * m, P * m, 3 * P * m, P, P};
  for (int j = 0; j < 5; ++j)
    if (sizes[j] < need[j]) return -3;
  double* phi = malloc(sizeof(double) * 3 * (size_t)n * (size_t)(m > 0 ? m : 1));
  if (!phi) return -1;
  double* dx = phi + n * m;  // (n, m) each
  double* dy = dx + n * m;
  double g[FIT_MAX * FIT_MAX], mi[FIT_MAX * FIT_MAX], dinv[FIT_MAX], ys[FIT_MAX];
  double tmp[FIT_MAX], pc[FIT_MAX];
  const double w1x = 2.0 * PI / px, w1y = 2.0 * PI / py;
  int64_t flagged = 0;
  for (int64_t p = 0; p < P; ++p) {
    const double* pts = points + p * m * 3;
    const uint8_t* w = valid + p * m;
    double* gr = grad + p * m * 3;
    memset(gr, 0, sizeof(double) * 3 * (size_t)m);
    to_numpy[p] = 0;
    int64_t n_valid = 0;
    for (int64_t j = 0; j < m; ++j) n_valid += w[j] != 0;
    fit_ok[p] = n_valid > n;
    if (!fit_ok[p]) continue;  // its gradients are zero whatever the fit
    double mx = 0.0, my = 0.0;
    if (kind != 0) {  // centre the polynomial bases on the valid feet
      for (int64_t j = 0; j < m; ++j)
        if (w[j]) mx += pts[3 * j], my += pts[3 * j + 1];
      mx /= (double)n_valid;
      my /= (double)n_valid;
    }
    for (int64_t j = 0; j < m; ++j) {
      const double x = pts[3 * j] - mx, y = pts[3 * j + 1] - my;
      if (kind == 1) {
        const double f[3] = {1.0, x, y}, fx[3] = {0.0, 1.0, 0.0}, fy[3] = {0.0, 0.0, 1.0};
        for (int l = 0; l < 3; ++l) phi[l * m + j] = f[l], dx[l * m + j] = fx[l], dy[l * m + j] = fy[l];
      } else if (kind == 2) {
        const double f[6] = {1.0, x, y, x * x, x * y, y * y};
        const double fx[6] = {0.0, 1.0, 0.0, 2 * x, y, 0.0};
        const double fy[6] = {0.0, 0.0, 1.0, 0.0, x, 2 * y};
        for (int l = 0; l < 6; ++l) phi[l * m + j] = f[l], dx[l * m + j] = fx[l], dy[l * m + j] = fy[l];
      } else {
        const double tx = w1x * (x - px * nearbyint(x / px));  // half to even, as numpy's round
        const double ty = w1y * (y - py * nearbyint(y / py));
        const double sx1 = sin(tx), cx1 = cos(tx), sy1 = sin(ty), cy1 = cos(ty);
        double sx = sx1, cx = cx1, sy = sy1, cy = cy1;
        phi[j] = 1.0, dx[j] = 0.0, dy[j] = 0.0;
        for (int64_t lv = 1; lv <= K; ++lv) {
          if (lv > 1) {
            const double sxn = sx * cx1 + cx * sx1, cxn = cx * cx1 - sx * sx1;
            const double syn = sy * cy1 + cy * sy1, cyn = cy * cy1 - sy * sy1;
            sx = sxn, cx = cxn, sy = syn, cy = cyn;
          }
          const double wx = lv * w1x, wy = lv * w1y;
          const int64_t r = 1 + 4 * (lv - 1);
          phi[r * m + j] = sx, phi[(r + 1) * m + j] = cx;
          phi[(r + 2) * m + j] = sy, phi[(r + 3) * m + j] = cy;
          dx[r * m + j] = wx * cx, dx[(r + 1) * m + j] = -wx * sx;
          dx[(r + 2) * m + j] = 0.0, dx[(r + 3) * m + j] = 0.0;
          dy[r * m + j] = 0.0, dy[(r + 1) * m + j] = 0.0;
          dy[(r + 2) * m + j] = wy * cy, dy[(r + 3) * m + j] = -wy * sy;
        }
      }
    }
    // G = A^T A and A^T b over the valid feet (masked feet are zero rows of A)
    for (int a = 0; a < n; ++a) {
      for (int b = a; b < n; ++b) {
        double acc = 0.0;
        for (int64_t j = 0; j < m; ++j)
          if (w[j]) acc += phi[a * m + j] * phi[b * m + j];
        g[a * n + b] = g[b * n + a] = acc;
      }
      double acc = 0.0;
      for (int64_t j = 0; j < m; ++j)
        if (w[j]) acc += phi[a * m + j] * -pts[3 * j + 2];
      ys[a] = acc;
    }
    for (int a = 0; a < n; ++a) {
      const double d = sqrt(g[a * n + a]);
      dinv[a] = d > 0 ? 1.0 / d : 0.0;
    }
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) g[a * n + b] = g[a * n + b] * dinv[a] * dinv[b];
    // G = L L^T (Cholesky, L in the lower triangle of g) and M = L^-1: G^-1 = M^T M
    double bound = 0.0;  // Gershgorin: lam_max <= the largest absolute row sum
    for (int a = 0; a < n; ++a) {
      double r = 0.0;
      for (int b = 0; b < n; ++b) r += fabs(g[a * n + b]);
      bound = r > bound ? r : bound;
    }
    int definite = 1;
    for (int j = 0; j < n && definite; ++j) {
      double d = g[j * n + j];
      for (int k = 0; k < j; ++k) d -= g[j * n + k] * g[j * n + k];
      if (!(d > 0.0)) {
        definite = 0;
        break;
      }
      const double ljj = sqrt(d);
      g[j * n + j] = ljj;
      for (int i = j + 1; i < n; ++i) {
        double acc = g[i * n + j];
        for (int k = 0; k < j; ++k) acc -= g[i * n + k] * g[j * n + k];
        g[i * n + j] = acc / ljj;
      }
    }
    double trace_inv = 0.0;  // trace(G^-1) = |M|_F^2 >= 1 / lam_min
    if (definite) {
      for (int j = 0; j < n; ++j) {
        mi[j * n + j] = 1.0 / g[j * n + j];
        trace_inv += mi[j * n + j] * mi[j * n + j];
        for (int i = j + 1; i < n; ++i) {
          double acc = 0.0;
          for (int k = j; k < i; ++k) acc += g[i * n + k] * mi[k * n + j];
          mi[i * n + j] = -acc / g[i * n + i];
          trace_inv += mi[i * n + j] * mi[i * n + j];
        }
      }
    }
    // condition number <= bound * trace_inv: solved here only where that is <= max_condition
    if (!definite || !(bound * trace_inv <= max_condition)) {
      to_numpy[p] = 1;
      ++flagged;
      continue;
    }
    for (int a = 0; a < n; ++a) ys[a] = dinv[a] * ys[a];
    for (int i = 0; i < n; ++i) {  // M ys
      double acc = 0.0;
      for (int k = 0; k <= i; ++k) acc += mi[i * n + k] * ys[k];
      tmp[i] = acc;
    }
    for (int a = 0; a < n; ++a) {  // p = D M^T (M ys)
      double acc = 0.0;
      for (int i = a; i < n; ++i) acc += mi[i * n + a] * tmp[i];
      pc[a] = dinv[a] * acc;
    }
    for (int64_t j = 0; j < m; ++j) {
      if (!w[j]) continue;
      double gx = 0.0, gy = 0.0;
      for (int l = 0; l < n; ++l) gx += pc[l] * dx[l * m + j], gy += pc[l] * dy[l * m + j];
      gr[3 * j] = gx, gr[3 * j + 1] = gy, gr[3 * j + 2] = 1.0;
    }
  }
  free(phi);
  return flagged;
}

// Eq. 12-15 with the stated covariance, per path (bauv_seabed_shift_args: paths = P, beams = m,
// residual, sigma, fallback, rcond, singular_floor, grad, e, de, l0 = L0, l1 = L1, use, fit_ok,
// cmd, shift, cov, used = beams, rank, ok, rms; each buffer with its size, de and cmd may be
// NULL with size 0).
//
// Args (P paths, m beams, all arrays C-contiguous):
//   grad: grad psi at the feet of image k (P, m, 3) (rows of masked beams are ignored).
//   e: beam vectors of image k (P, m, 3), world; de: their change to image k+1 (P, m, 3), or
//     NULL for none (reading "one_attitude").
//   L0, L1: ranges of images k and k+1 (P, m), m.
//   use: echo in both images (P, m), 0/1; fit_ok: (P,), 0/1.
//   residual: 1 for the "residual" covariance, 0 for "range_noise".
//   sigma: range noise standard deviation, m; fallback: variance of unobserved directions, m^2;
//   rcond: relative singular-value cut-off; singular_floor: the absolute one per sqrt(beam).
//   cmd: shift stated where none is produced (P, 3), m, or NULL for zero.
//
// Results: shift (P, 3) m, cov (P, 3, 3) m^2, beams (P,), rank (P,), ok (P,) 0/1, rms (P,) m.
//
// sizes: the number of elements of each buffer as allocated by the caller, in the order
//   grad, e, de, L0, L1, use, fit_ok, cmd, shift, cov, beams, rank, ok, rms
// (n_sizes of them, 14; 0 for a NULL de or cmd); nothing is read or written unless each holds what
// P and m say (3 P m for grad, e, de; P m for L0, L1, use; P for fit_ok and the results beams,
// rank, ok, rms; 3 P for cmd and shift; 9 P for cov).
//
// Returns 0, or -3 (a buffer shorter than P and m say, P < 0, m < 0, or a size product
// overflowing).
static int64_t seabed_shift(int64_t P, int64_t m, const double* grad, const double* e,
                          const double* de, const double* L0, const double* L1,
                          const uint8_t* use, const uint8_t* fit_ok, int64_t residual,
                          double sigma, double fallback, double rcond, double singular_floor,
                          const double* cmd, double* shift, double* cov, int64_t* beams,
                          int64_t* rank, uint8_t* ok, double* rms, const int64_t* sizes,
                          int64_t n_sizes) {
  if (n_sizes != 14 || !sizes || P < 0 || m < 0 || P > INT64_MAX / 9) return -3;
  if (m > 0 && P > INT64_MAX / 3 / m) return -3;
  const int64_t need[14] = {3 * P * m, 3 * P * m, de ? 3 * P * m : 0, P * m, P * m, P * m, P,
                            cmd ? 3 * P : 0, 3 * P, 9 * P, P, P, P, P};
  for (int j = 0; j < 14; ++j)
    if (sizes[j] < need[j]) return -3;
  for (int64_t p = 0; p < P; ++p) {
    const double* gp = grad + p * m * 3;
    const double* ep = e + p * m * 3;
    const double* dep = de ? de + p * m * 3 : NULL;
    const uint8_t* u = use + p * m;
    double ata[9] = {0}, atb[3] = {0}, lam[3], v[9];
    int64_t nb = 0;
    for (int64_t j = 0; j < m; ++j) {
      if (!u[j]) continue;
      ++nb;
      const double* g = gp + 3 * j;
      const double l0 = L0[p * m + j], dl = L1[p * m + j] - L0[p * m + j];
      double b = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double dec = dep ? dep[3 * j + c] : 0.0;
        b += g[c] * (dec * l0 + ep[3 * j + c] * dl);  // eq. 12
      }
      b = -b;
      for (int c = 0; c < 3; ++c) {
        atb[c] += g[c] * b;
        for (int d = 0; d < 3; ++d) ata[c * 3 + d] += g[c] * g[d];
      }
    }
    beams[p] = nb;
    ok[p] = fit_ok[p] && nb >= 3;
    // eq. 15 by the singular values of A from the eigen-decomposition of A^T A
    jacobi_eigh(3, ata, lam, v);
    double s[3], vt[9];  // descending, rows of vt the right singular vectors (as an SVD's)
    for (int c = 0; c < 3; ++c) {
      s[c] = sqrt(lam[2 - c] > 0.0 ? lam[2 - c] : 0.0);
      for (int d = 0; d < 3; ++d) vt[c * 3 + d] = v[d * 3 + (2 - c)];
    }
    const double f1 = singular_floor * sqrt((double)(nb > 1 ? nb : 1)), f2 = rcond * s[0];
    const double floor = f1 > f2 ? f1 : f2;
    double sinv2[3], unobs[3];
    int64_t rk = 0;
    for (int c = 0; c < 3; ++c) {
      const int keep = s[c] > floor;
      rk += keep;
      const double si = keep ? 1.0 / s[c] : 0.0;
      sinv2[c] = si * si;
      unobs[c] = keep ? 0.0 : fallback;
    }
    double mm[9];  // V diag(s_inv^2) V^T
    for (int d = 0; d < 3; ++d)
      for (int f = 0; f < 3; ++f) {
        double acc = 0.0;
        for (int c = 0; c < 3; ++c) acc += vt[c * 3 + d] * sinv2[c] * vt[c * 3 + f];
        mm[d * 3 + f] = acc;
      }
    double x[3], tmp[3];
    for (int c = 0; c < 3; ++c) {
      double acc = 0.0;
      for (int d = 0; d < 3; ++d) acc += vt[c * 3 + d] * atb[d];
      tmp[c] = acc * sinv2[c];
    }
    for (int d = 0; d < 3; ++d) {
      double acc = 0.0;
      for (int c = 0; c < 3; ++c) acc += vt[c * 3 + d] * tmp[c];
      x[d] = acc;
    }
    // residual and the range-noise propagation through Ap = V diag(s_inv^2) V^T A^T
    double rss = 0.0, cn[9] = {0};
    for (int64_t j = 0; j < m; ++j) {
      if (!u[j]) continue;
      const double* g = gp + 3 * j;
      const double l0 = L0[p * m + j], dl = L1[p * m + j] - L0[p * m + j];
      double b = 0.0, r = 0.0, gb0 = 0.0, gb1 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double dec = dep ? dep[3 * j + c] : 0.0;
        b += g[c] * (dec * l0 + ep[3 * j + c] * dl);
        r += g[c] * x[c];
        gb0 += g[c] * (dec - ep[3 * j + c]);
        gb1 += g[c] * ep[3 * j + c];
      }
      r = r + b;  // A dX - B with B = -b
      rss += r * r;
      const double var = sigma * sigma * (gb0 * gb0 + gb1 * gb1);
      double ap[3];
      for (int d = 0; d < 3; ++d) ap[d] = mm[d * 3] * g[0] + mm[d * 3 + 1] * g[1] + mm[d * 3 + 2] * g[2];
      for (int d = 0; d < 3; ++d)
        for (int f = 0; f < 3; ++f) cn[d * 3 + f] += ap[d] * var * ap[f];
    }
    double* cp = cov + p * 9;
    if (residual) {
      const int64_t dof = nb - rk > 1 ? nb - rk : 1;
      const double s2 = rss / (double)dof;
      double cr[9];
      for (int d = 0; d < 3; ++d)
        for (int f = 0; f < 3; ++f) {
          double acc = 0.0;
          for (int c = 0; c < 3; ++c) acc += vt[c * 3 + d] * (s2 * sinv2[c]) * vt[c * 3 + f];
          cr[d * 3 + f] = acc;
        }
      const int use_res = cr[0] + cr[4] + cr[8] >= cn[0] + cn[4] + cn[8];  // never below noise
      for (int k = 0; k < 9; ++k) cp[k] = use_res ? cr[k] : cn[k];
    } else {
      for (int k = 0; k < 9; ++k) cp[k] = cn[k];
    }
    for (int d = 0; d < 3; ++d)
      for (int f = 0; f < 3; ++f) {
        double acc = 0.0;
        for (int c = 0; c < 3; ++c) acc += vt[c * 3 + d] * unobs[c] * vt[c * 3 + f];
        cp[d * 3 + f] += acc;
      }
    if (ok[p]) {
      for (int d = 0; d < 3; ++d) shift[p * 3 + d] = x[d];
      rank[p] = rk;
      rms[p] = sqrt(rss / (double)(nb > 1 ? nb : 1));
    } else {
      for (int d = 0; d < 3; ++d) shift[p * 3 + d] = cmd ? cmd[p * 3 + d] : 0.0;
      for (int k = 0; k < 9; ++k) cp[k] = (k % 4 == 0) ? fallback : 0.0;
      rank[p] = 0;
      rms[p] = 0.0;
    }
  }
  return 0;
}

int64_t bauv_seabed_fit(const bauv_seabed_fit_args* g) {
  if (!g) return -3;
  const int64_t sizes[5] = {g->points.size, g->valid.size, g->grad.size, g->fit_ok.size,
                            g->to_numpy.size};
  return seabed_fit(g->paths, g->feet, g->points.data, g->valid.data, g->kind, g->harmonics, g->px,
                    g->py, g->max_condition, g->grad.data, g->fit_ok.data, g->to_numpy.data,
                    sizes, 5);
}

int64_t bauv_seabed_shift(const bauv_seabed_shift_args* g) {
  if (!g) return -3;
  const int64_t sizes[14] = {g->grad.size, g->e.size,    g->de.size,   g->l0.size,   g->l1.size,
                             g->use.size,  g->fit_ok.size, g->cmd.size, g->shift.size,
                             g->cov.size,  g->used.size, g->rank.size, g->ok.size,   g->rms.size};
  return seabed_shift(g->paths, g->beams, g->grad.data, g->e.data, g->de.data, g->l0.data,
                      g->l1.data, g->use.data, g->fit_ok.data, g->residual, g->sigma, g->fallback,
                      g->rcond, g->singular_floor, g->cmd.data, g->shift.data, g->cov.data,
                      g->used.data, g->rank.data, g->ok.data, g->rms.data, sizes, 14);
}
