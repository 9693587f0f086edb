// Curvature-bounded ray march against seed 004's harmonic seabed (eq. 24): the hot loop of
// bauv_sim.sensors.multibeam.HarmonicSeabed.ray_ranges, one ray at a time.
//
// A plain C library without Python API, loaded with ctypes by nav.clib (bauv_sim/sensors/
// multibeam.py, _march); its entry point takes the struct bauv_march_args of the shared header
// nav/clib.h, whose layout the loader checks against its Python mirror. Python normalises the directions, checks the input and hands the rays this
// march leaves unresolved to its first-order march (HarmonicSeabed._lipschitz_ranges). The march
// checks the sizes of its buffers and the path indices itself before it reads any of them.
//
// The seabed of path p is psi(x) = 0 (water where psi > 0), with
//
//   psi(x) = a0 + z + sum_{l=1..K} (a_l sin(w_l x) + b_l cos(w_l x) + c_l sin(v_l y) + d_l cos(v_l y)),
//
//   w_l = 2 pi l / Px, v_l = 2 pi l / Py (m^-1).
//
// Along a ray x(s) = o + s e (e a unit vector, s in m), f(s) = psi(x(s)) has
//
//   f'(s) = e_z + e_x sum_l w_l (a_l cos - b_l sin) + e_y sum_l v_l (c_l cos - d_l sin),
//   |f''(s)| <= M2 = e_x^2 C_x + e_y^2 C_y,  C_x = sum_l w_l^2 hypot(a_l, b_l) (same in y)
//
// (eq. 24 is separable: no cross term). From a point where f > 0 the concave parabola
// f + f' h - M2 h^2 / 2 bounds f(s + h) from below; its first positive root
//
//   h = 2 f / (sqrt(f'^2 + 2 M2 f) - f')      (= (f' + sqrt(...)) / M2 for f' > 0)
//
// cannot pass the first crossing, and near a simple root it is Newton's step to second order.
// The upper parabola f + f' h + M2 h^2 / 2 crosses zero at
//
//   h_up = 2 f / (sqrt(f'^2 - 2 M2 f) - f'),
//
// so for f' < 0 the first crossing lies in [s + h, s + h_up]: the march takes its middle once
// that interval is at most tol wide ("close"), or takes s + h once the step is at most tol; a
// step beyond max_range means no echo. A point with f <= 0 is, at the start (s == 0), an origin at
// or below the seabed (no echo), later a rounding step onto the root (the range is s). The
// march starts where the ray enters the slab z <= top = -a0 + sum_l (hypot(a_l, b_l) +
// hypot(c_l, d_l)) that holds the seabed (a ray above it going up or level has no echo). The
// harmonics l = 2..K come from l = 1 by angle addition, sin((l+1) t) = sin(l t) cos t + cos(l t)
// sin t, cos((l+1) t) = cos(l t) cos t - sin(l t) sin t, with t reduced to [-pi, pi] first
// (t = w_1 (x - Px rint(x / Px))). A ray not resolved after `steps` steps (grazing a crest: a
// double root, slow convergence) is flagged unresolved with the distance s reached.
//
// Every operation is the one of the numpy implementation it replaced (kept in
// tests/bauv_sim/multibeam_reference.py), in the same order, so that the ranges agree to rounding
// (IEEE 754 double, no fast-math, no FMA contraction: compile with -ffp-contract=off).

#include <math.h>
#include <stdint.h>

#include "clib.h"

BAUV_DEFINE_LAYOUT(bauv_march_args, BAUV_MARCH_ARGS)

// psi and its derivative along the ray at the point (x, y, z), for one path's coefficients
// (a, b, c, d: K each, m) and frequencies (wx, wy: K each, rad/m).
static void psi_slope(double x, double y, double z, double ex, double ey, double ez, int64_t K,
                      const double* a, const double* b, const double* c, const double* d,
                      const double* wx, const double* wy, double a0, double px, double py,
                      double* f_out, double* g_out) {
  double tx = wx[0] * (x - px * nearbyint(x / px));  // round half to even, as numpy's round
  double ty = wy[0] * (y - py * nearbyint(y / py));
  double sx1 = sin(tx), cx1 = cos(tx), sy1 = sin(ty), cy1 = cos(ty);
  double sx = sx1, cx = cx1, sy = sy1, cy = cy1;
  double f = a0 + z;
  double gx = 0.0, gy = 0.0;
  for (int64_t l = 0; l < K; ++l) {
    if (l) {
      double sxn = sx * cx1 + cx * sx1, cxn = cx * cx1 - sx * sx1;
      double syn = sy * cy1 + cy * sy1, cyn = cy * cy1 - sy * sy1;
      sx = sxn, cx = cxn, sy = syn, cy = cyn;
    }
    f = f + (a[l] * sx + b[l] * cx) + (c[l] * sy + d[l] * cy);
    gx = gx + wx[l] * (a[l] * cx - b[l] * sx);
    gy = gy + wy[l] * (c[l] * cy - d[l] * sy);
  }
  *f_out = f;
  *g_out = ez + ex * gx + ey * gy;
}

// The march over n rays (the fields of bauv_march_args: n, paths = P, harmonics = K, steps, a0,
// px, py, max_range, tol, the inputs o .. cyy and the results range .. s, each buffer with its
// size).
//
// Args (shapes; P paths, K harmonics, all arrays C-contiguous):
//   n: number of rays.
//   P: number of paths (seabeds).
//   o: origins (n, 3), m, world (z up).
//   e: unit directions (n, 3), world.
//   path: each ray's seabed (n,), in [0, P).
//   K: harmonics.
//   a, b, c, d: coefficients (P, K), m.
//   wx, wy: w_l and v_l (K,), rad/m.
//   top: top of each path's slab (P,), m (z).
//   cxx, cyy: C_x and C_y (P,), m^-1.
//   a0, px, py: a0, Px, Py, m.
//   max_range: no echo beyond this distance, m.
//   tol: width at which the root is taken, m.
//   steps: steps of the march before a ray is left unresolved.
//
// Results (n each): range (m, 0 without hit), hit (0/1), unresolved (0/1), s (m: the distance
// the march reached, where the first-order march takes over for an unresolved ray; else 0).
//
// sizes: the number of elements of each buffer as allocated by the caller, in the order
//   o, e, path, a, b, c, d, wx, wy, top, cxx, cyy, range, hit, unresolved, s_out
// (n_sizes of them, 16). Nothing is read or written unless every buffer holds what n, P and K say
// (o, e: 3 n; path and the results: n; a, b, c, d: P K; wx, wy: K; top, cxx, cyy: P) and every
// path index lies in [0, P): whatever the caller passes, the march stays inside its buffers.
//
// Returns the number of unresolved rays, or -1 (a buffer shorter than n, P, K say), -2 (a path
// index outside [0, P)), -3 (n < 0, P < 1, K < 1, steps < 0, or a size product overflowing).
static int64_t march(int64_t n, int64_t P, const double* o, const double* e,
                            const int64_t* path, int64_t K,
                            const double* a, const double* b, const double* c,
                            const double* d, const double* wx, const double* wy,
                            const double* top, const double* cxx, const double* cyy, double a0,
                            double px, double py, double max_range, double tol, int64_t steps,
                            double* range, uint8_t* hit, uint8_t* unresolved, double* s_out,
                            const int64_t* sizes, int64_t n_sizes) {
  if (n_sizes != 16 || !sizes) return -1;
  if (n < 0 || P < 1 || K < 1 || steps < 0 || n > INT64_MAX / 3 || K > INT64_MAX / P) return -3;
  const int64_t need[16] = {3 * n, 3 * n, n, P * K, P * K, P * K, P * K, K, K, P, P, P,
                            n, n, n, n};
  for (int j = 0; j < 16; ++j)
    if (sizes[j] < need[j]) return -1;
  for (int64_t i = 0; i < n; ++i)
    if (path[i] < 0 || path[i] >= P) return -2;
  int64_t left = 0;
  for (int64_t i = 0; i < n; ++i) {
    const double ox = o[3 * i], oy = o[3 * i + 1], oz = o[3 * i + 2];
    const double ex = e[3 * i], ey = e[3 * i + 1], ez = e[3 * i + 2];
    const int64_t p = path[i];
    range[i] = 0.0;
    hit[i] = 0;
    unresolved[i] = 0;
    s_out[i] = 0.0;
    // enter the slab that holds the seabed (psi > 0 above its top)
    const int above = oz > top[p];
    if (above && ez >= 0) continue;
    double s = (above && ez < 0) ? (oz - top[p]) / -ez : 0.0;
    if (!(s <= max_range)) continue;
    const double m2 = ex * ex * cxx[p] + ey * ey * cyy[p];
    const double *ap = a + p * K, *bp = b + p * K, *cp = c + p * K, *dp = d + p * K;
    int live = 1;
    for (int64_t k = 0; k < steps && live; ++k) {
      double f, g;
      psi_slope(ox + s * ex, oy + s * ey, oz + s * ez, ex, ey, ez, K, ap, bp, cp, dp, wx, wy, a0,
                px, py, &f, &g);
      const int below = f <= 0;  // at the origin: no echo; later: a rounding step onto the root
      const double fp = f > 0.0 ? f : 0.0;
      const double root = sqrt(g * g + 2.0 * m2 * fp);
      double h = g > 0 ? (g + root) / m2 : 2.0 * f / (root - g);
      // the upper parabola f + f' h + M2 h^2 / 2 crosses zero at h_up: the root is in [h, h_up]
      const double h_up = 2.0 * f / (sqrt(g * g - 2.0 * m2 * fp) - g);
      if (isnan(h)) h = INFINITY;
      const int close = (g < 0) && (h_up - h <= tol);
      if (close) h = 0.5 * (h + h_up);
      const double nxt = s + h;
      if (below) {
        if (s > 0) {
          range[i] = s;
          hit[i] = 1;
        }
        live = 0;  // s == 0: an origin at or below the seabed
      } else if ((close || h <= tol) && nxt <= max_range) {
        range[i] = nxt;
        hit[i] = 1;
        live = 0;
      } else if (nxt > max_range) {
        live = 0;
      } else {
        s = nxt;
      }
    }
    if (live) {
      unresolved[i] = 1;
      s_out[i] = s;
      ++left;
    }
  }
  return left;
}

int64_t bauv_harmonic_march(const bauv_march_args* g) {
  if (!g) return -1;
  const int64_t sizes[16] = {g->o.size,   g->e.size,     g->path.size, g->a.size,
                             g->b.size,   g->c.size,     g->d.size,    g->wx.size,
                             g->wy.size,  g->top.size,   g->cxx.size,  g->cyy.size,
                             g->range.size, g->hit.size, g->unresolved.size, g->s.size};
  return march(g->n, g->paths, g->o.data, g->e.data, g->path.data, g->harmonics, g->a.data,
               g->b.data, g->c.data, g->d.data, g->wx.data, g->wy.data, g->top.data, g->cxx.data,
               g->cyy.data, g->a0, g->px, g->py, g->max_range, g->tol, g->steps, g->range.data,
               g->hit.data, g->unresolved.data, g->s.data, sizes, 16);
}
