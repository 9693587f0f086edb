// The argument structs of the project's ctypes-loaded C libraries, declared once.
//
// Each entry point takes one pointer to its argument struct instead of a positional list:
//   bauv_harmonic_march (bauv_sim/sensors/harmonic_rays.c): bauv_march_args
//   bauv_seabed_fit     (nav/seabed/seabed_shift.c):        bauv_seabed_fit_args
//   bauv_seabed_shift   (nav/seabed/seabed_shift.c):        bauv_seabed_shift_args
// Every buffer travels with its element count as allocated by the caller (a bauv_in_* or
// bauv_out_* view), so an entry point checks what it reads and writes against the shapes it is
// given before it touches any buffer; a NULL buffer has data NULL and size 0.
//
// The Python mirror is nav/clib.py (ctypes.Structure classes with the same fields in the same
// order). The fields of each struct are listed once, in an X-macro, from which both the struct
// and its layout description are made: a library defines, with BAUV_DEFINE_LAYOUT, for each
// struct T it takes, T_layout (sizeof(T) and the offset of every field) and T_fields (the
// fields' C types and names, "type:name" separated by spaces). The loader (nav.clib) compares
// both with the mirror when it loads the library and refuses a mismatch, so the two sides cannot
// drift apart silently.
#ifndef BAUV_CLIB_H
#define BAUV_CLIB_H

#include <stddef.h>
#include <stdint.h>

// Buffer views: a C-contiguous array and its number of elements.
typedef struct {
  const double* data;
  int64_t size;
} bauv_in_f64;
typedef struct {
  const int64_t* data;
  int64_t size;
} bauv_in_i64;
typedef struct {
  const uint8_t* data;
  int64_t size;
} bauv_in_u8;
typedef struct {
  double* data;
  int64_t size;
} bauv_out_f64;
typedef struct {
  int64_t* data;
  int64_t size;
} bauv_out_i64;
typedef struct {
  uint8_t* data;
  int64_t size;
} bauv_out_u8;

// The ray march against seed 004's harmonic seabed (harmonic_rays.c: meaning of every field).
#define BAUV_MARCH_ARGS(X, T)                                                                 \
  X(T, int64_t, n) X(T, int64_t, paths) X(T, int64_t, harmonics) X(T, int64_t, steps)          \
  X(T, double, a0) X(T, double, px) X(T, double, py) X(T, double, max_range) X(T, double, tol) \
  X(T, bauv_in_f64, o) X(T, bauv_in_f64, e) X(T, bauv_in_i64, path) X(T, bauv_in_f64, a)      \
  X(T, bauv_in_f64, b) X(T, bauv_in_f64, c) X(T, bauv_in_f64, d) X(T, bauv_in_f64, wx)        \
  X(T, bauv_in_f64, wy) X(T, bauv_in_f64, top) X(T, bauv_in_f64, cxx) X(T, bauv_in_f64, cyy)  \
  X(T, bauv_out_f64, range) X(T, bauv_out_u8, hit) X(T, bauv_out_u8, unresolved)             \
  X(T, bauv_out_f64, s)

// Appendix A's slope fit of the seabed shift (seabed_shift.c: meaning of every field).
#define BAUV_SEABED_FIT_ARGS(X, T)                                                         \
  X(T, int64_t, paths) X(T, int64_t, feet) X(T, int64_t, kind) X(T, int64_t, harmonics)     \
  X(T, double, px) X(T, double, py) X(T, double, max_condition) X(T, bauv_in_f64, points)   \
  X(T, bauv_in_u8, valid) X(T, bauv_out_f64, grad) X(T, bauv_out_u8, fit_ok)                \
  X(T, bauv_out_u8, to_numpy)

// Eq. 12-15 of the seabed shift with its covariance (seabed_shift.c: meaning of every field).
#define BAUV_SEABED_SHIFT_ARGS(X, T)                                                          \
  X(T, int64_t, paths) X(T, int64_t, beams) X(T, int64_t, residual) X(T, double, sigma)      \
  X(T, double, fallback) X(T, double, rcond) X(T, double, singular_floor)                    \
  X(T, bauv_in_f64, grad) X(T, bauv_in_f64, e) X(T, bauv_in_f64, de) X(T, bauv_in_f64, l0)   \
  X(T, bauv_in_f64, l1) X(T, bauv_in_u8, use) X(T, bauv_in_u8, fit_ok) X(T, bauv_in_f64, cmd) \
  X(T, bauv_out_f64, shift) X(T, bauv_out_f64, cov) X(T, bauv_out_i64, used)                 \
  X(T, bauv_out_i64, rank) X(T, bauv_out_u8, ok) X(T, bauv_out_f64, rms)

#define BAUV_FIELD(T, type, name) type name;
#define BAUV_OFFSET(T, type, name) (int64_t) offsetof(T, name),
#define BAUV_NAME(T, type, name) #type ":" #name " "

typedef struct {
  BAUV_MARCH_ARGS(BAUV_FIELD, _)
} bauv_march_args;
typedef struct {
  BAUV_SEABED_FIT_ARGS(BAUV_FIELD, _)
} bauv_seabed_fit_args;
typedef struct {
  BAUV_SEABED_SHIFT_ARGS(BAUV_FIELD, _)
} bauv_seabed_shift_args;

// Defines T_fields() and T_layout(out, cap) for the struct T whose fields FIELDS lists:
// T_layout writes sizeof(T) and then each field's offset into out (at most cap values) and
// returns how many values the layout has (1 + the number of fields).
#define BAUV_DEFINE_LAYOUT(T, FIELDS)                                       \
  const char* T##_fields(void) { return FIELDS(BAUV_NAME, T); }             \
  int64_t T##_layout(int64_t* out, int64_t cap) {                           \
    const int64_t v[] = {(int64_t)sizeof(T), FIELDS(BAUV_OFFSET, T)};       \
    const int64_t k = (int64_t)(sizeof v / sizeof v[0]);                    \
    for (int64_t i = 0; i < k && i < cap; ++i) out[i] = v[i];               \
    return k;                                                               \
  }

#endif  // BAUV_CLIB_H
