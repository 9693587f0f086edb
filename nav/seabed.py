"""Dead reckoning from multibeam seabed ranges ("acoustic images"), seed 004 section 4 and
Appendix A, batched over paths.

Frame and angles are seed 004's: world x, y horizontal, z up; the direction of motion is
``(gamma, theta)``, theta from the x axis counter-clockwise, gamma up from the horizontal
(:func:`nav.angles`-free here: the seed's angles are used as they are). Every array carries a
leading axis of paths ``P``.

**Beams (eq. 8).** Beam ``(i, j)`` points at ``(gamma_k + gamma^i, theta_k + theta^j)`` with the
unit vector

    e = (cos(g) cos(t), cos(g) sin(t), sin(g)),   g = gamma_k + gamma^i,  t = theta_k + theta^j,

and reaches the seabed at ``x^ij = X_k + L^ij e``. Seed 004's elevations "(42, 82) deg" point
*down* (z is up), so :meth:`BeamGeometry.seed004` uses ``gamma^i`` from -42 to -82 deg.

**Shift (eq. 9-15).** On a seabed ``psi(x) = 0`` the total change of ``psi`` at a beam's foot
vanishes, which linearised between two images gives one equation per beam,

    grad psi(x_k^ij) . (dX + de^ij L_k^ij + e_k^ij dL^ij) = 0,                   (eq. 11-12)

stacked into ``A dX = B`` (eq. 14: the rows of A are ``(dpsi/dx, dpsi/dy, dpsi/dz)``; the printed
matrix repeats d/dx, a typo) and solved by least squares (eq. 15). ``de`` is eq. 10 with the
printed typo corrected: the d(theta) term of ``de^Y`` is ``+cos(g) cos(t) dtheta``. The position
then dead-reckons as ``X_{k+1} = X_k + dX`` (eq. 16, :func:`seabed_track`).

**Slopes (Appendix A).** The seabed's gradient at the beam feet is not known; it is estimated
from the image itself: the feet ``x^ij = X_k + L^ij e`` (with the *estimated* position) are
fitted by ``psi(x) = z + sum_l p_l psi_l(x)`` in least squares. The coefficient of ``z`` is
fixed to 1 (Appendix A's minimisation without that constraint is solved by ``p = 0``). The
basis (:class:`SlopeBasis`) is the harmonic one of eq. 24 (a constant plus sines and cosines of
the known periods), a plane or a quadratic. Both bases are invariant under a shift of the
points, so an error in the estimated position does not change the slopes at the feet.

**Beam attitude between two images (reading notes).** The text takes ``L_{k+1}`` with the
attitude of ``u_{k+1}``, which needs the estimate that needs ``L_{k+1}``. Two readings are offered
(:data:`BeamAttitude`): ``"one_attitude"``: both images of a shift are taken at the attitude of
``u_k`` (the second one just before the vehicle turns; ``de = 0``); ``"turning"``: the second
image is taken at the next attitude and eq. 10 accounts for the turn (linearised, or exactly with
``delta_e="exact"``).

**Beams without echo** (no seabed within the sonar's range) are masked: a beam is used when it
has an echo in both images (the slope fit uses every echo of image k). A shift with fewer usable
beams than the fit needs is not produced (``ok = False``; the shift is zero, or the commanded
displacement when given, and the covariance ``fallback_var_m2 * I``, never NaN).

**Conditioning.** Eq. 15 is solved by SVD; singular values of A below ``rcond`` (relative) or
:data:`SINGULAR_FLOOR` (absolute) count as zero: the shift has no component along them and
the covariance states them unobserved, and ``rank`` says how many directions were observed.

**Error covariance.** Eq. 15 comes with no covariance. :func:`shift_estimate` offers
``"residual"``: the least-squares covariance ``s^2 (A^T A)^-1`` with ``s^2`` the residual variance
of eq. 13 (``RSS / (m - 3)``), floored by the range-noise propagation; and ``"range_noise"``: the
propagation of independent range noise ``sigma_range_m`` through B alone (a lower bound that
ignores slope and linearisation errors, which dominate on the seed's seabed). Directions the
beams do not observe (a plane seabed leaves the two directions along it unobserved) get the
variance ``fallback_var_m2``; the shift has no component along them (minimum-norm solution).

**Implementation.** The per-path arithmetic of :func:`fit_slopes` and :func:`shift_estimate`
(the basis, the fit's normal equations, eq. 12-15 and the covariance) runs in C,
``nav/seabed_shift.c``, loaded with ``ctypes`` and built by ``pip install`` (``setup.py``); numpy
keeps the input checks, the beam vectors (eq. 8, 10) and the rare branches (fits whose scaled
Gram matrix may have a condition number above :data:`FIT_C_CONDITION`, ``rcond < 1e-8``). The
numpy implementation it replaced is the tests' reference (``tests/nav/seabed_reference.py``);
the two agree to rounding times the condition numbers of the fit and of eq. 15 (about 1e-11
relative on seed 004's images), not bit for bit.

References:
    Seed 004 (Miller, Miller & Miller 2019), eq. 8-16 and Appendix A (A1).
"""

from __future__ import annotations

import ctypes
import functools
import importlib.machinery
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavError, NavInputError

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

BeamAttitude = Literal["one_attitude", "turning"]
"""The two readings of the beam attitude between two images (module docstring)."""

CovarianceKind = Literal["residual", "range_noise"]
"""How :func:`shift_estimate` states its error covariance (module docstring)."""

SINGULAR_FLOOR = 1e-9
"""Absolute singular-value floor of the shift's least squares (eq. 15): singular values of A
below ``SINGULAR_FLOOR * sqrt(m)`` (``m`` beams, each row of A of order 1: its z component is 1)
count as zero, whatever ``rcond``."""


_SHIFT_LIBRARY = "_seabed_shift"
"""The C library of :func:`fit_slopes` and :func:`shift_estimate` (``seabed_shift.c``, built
beside this module by ``pip install``, see ``setup.py``)."""


def _shift_library_path() -> Path:
    """The built C library beside this module (a Python extension's file name, no Python API).

    Raises:
        NavError: if it was not built.
    """
    here = Path(__file__).parent
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = here / (_SHIFT_LIBRARY + suffix)
        if path.is_file():
            return path
    raise NavError(
        f"the seabed shift's C library {here / _SHIFT_LIBRARY}*.so is not built: reinstall "
        "the package (pip install -e .)"
    )


@dataclass(frozen=True)
class _ShiftLibrary:
    """The two entry points of ``seabed_shift.c`` (argument lists there)."""

    fit: Callable[..., int]  # bauv_seabed_fit
    shift: Callable[..., int]  # bauv_seabed_shift


@functools.cache
def _shift_library() -> _ShiftLibrary:
    """``bauv_seabed_fit`` and ``bauv_seabed_shift`` of the C library with their argument types
    (loaded once per process, on first use)."""
    lib = ctypes.CDLL(str(_shift_library_path()))
    f64 = np.ctypeslib.ndpointer(np.float64, flags="C_CONTIGUOUS")
    u8 = np.ctypeslib.ndpointer(np.uint8, flags="C_CONTIGUOUS")
    f64_out = np.ctypeslib.ndpointer(np.float64, flags="C_CONTIGUOUS, WRITEABLE")
    i64_out = np.ctypeslib.ndpointer(np.int64, flags="C_CONTIGUOUS, WRITEABLE")
    u8_out = np.ctypeslib.ndpointer(np.uint8, flags="C_CONTIGUOUS, WRITEABLE")
    i64 = np.ctypeslib.ndpointer(np.int64, flags="C_CONTIGUOUS")
    n, x, opt = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p
    fit = lib.bauv_seabed_fit
    fit.argtypes = [n, n, f64, u8, n, n, x, x, x, f64_out, u8_out, u8_out, i64, n]
    fit.restype = n
    shift = lib.bauv_seabed_shift
    shift.argtypes = [n, n, f64, f64, opt, f64, f64, u8, u8, n, x, x, x, x, opt]
    shift.argtypes += [f64_out, f64_out, i64_out, i64_out, u8_out, f64_out, i64, n]
    shift.restype = n
    return _ShiftLibrary(fit, shift)


_C_STATUS = {
    -1: "out of memory",
    -2: "a basis the C fit does not take (more than FIT_MAX functions, harmonics < 1)",
    -3: "a buffer shorter than its shape (paths, beams) says",
}
"""The refusals of ``seabed_shift.c`` (its entry points' negative return values)."""


def _sizes(*arrays: Array | None) -> NDArray[np.int64]:
    """Element counts of the buffers handed to ``seabed_shift.c`` (0 for a NULL one)."""
    return np.array([0 if a is None else a.size for a in arrays], dtype=np.int64)


def _finite(name: str, a: Array, where: BoolArray | None = None) -> Array:
    """``a`` unchanged, or :class:`NavInputError` naming ``name`` and the first non-finite entry
    (among ``where`` when given)."""
    bad = ~np.isfinite(a)
    if where is not None:
        bad &= where
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise NavInputError(f"{name}: non-finite value {a[idx]} at index {idx}; must be finite")
    return a


@dataclass(frozen=True)
class BeamGeometry:
    """The multibeam's aiming angles relative to the direction of motion (seed 004, eq. 8).

    Attributes:
        elevation_rad: ``gamma^i``, shape (Mi,), rad, up from the direction of motion (negative:
            down).
        azimuth_rad: ``theta^j``, shape (Mj,), rad, counter-clockwise from the direction of motion.
    """

    elevation_rad: Array
    azimuth_rad: Array

    def __post_init__(self) -> None:
        for name in ("elevation_rad", "azimuth_rad"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
                raise NavInputError(f"BeamGeometry.{name}: need a finite 1-D array, got {a!r}")
            object.__setattr__(self, name, a)

    @classmethod
    def uniform(
        cls,
        elevation_deg: tuple[float, float],
        azimuth_deg: tuple[float, float],
        m_elevation: int,
        m_azimuth: int,
    ) -> BeamGeometry:
        """Beams spread uniformly (end points included) over two angle ranges.

        Args:
            elevation_deg: (first, last) ``gamma^i``, deg (negative: down).
            azimuth_deg: (first, last) ``theta^j``, deg.
            m_elevation: number of elevations, >= 1.
            m_azimuth: number of azimuths, >= 1.
        """
        if m_elevation < 1 or m_azimuth < 1:
            raise NavInputError(
                f"BeamGeometry: need >= 1 beam per axis, got {m_elevation}, {m_azimuth}"
            )
        return cls(
            np.radians(np.linspace(*elevation_deg, m_elevation)),
            np.radians(np.linspace(*azimuth_deg, m_azimuth)),
        )

    @classmethod
    def seed004(cls, m: int = 8) -> BeamGeometry:
        """Seed 004 section 6: 8 x 8 beams, ``gamma^i`` over (42, 82) deg *down* (-42 .. -82 deg,
        z up; reading notes), ``theta^j`` over (-10, 30) deg, end points included."""
        return cls.uniform((-42.0, -82.0), (-10.0, 30.0), m, m)

    @property
    def shape(self) -> tuple[int, int]:
        """``(Mi, Mj)``: beams per elevation and azimuth."""
        return (self.elevation_rad.size, self.azimuth_rad.size)

    def absolute_angles(self, attitude_rad: Array) -> tuple[Array, Array]:
        """Absolute beam angles for given directions of motion.

        Args:
            attitude_rad: ``(gamma_k, theta_k)``, shape (..., 2), rad.

        Returns:
            ``(g, t)``: ``gamma_k + gamma^i`` and ``theta_k + theta^j``, each shape
            (..., Mi, Mj), rad.
        """
        att = np.asarray(attitude_rad, dtype=float)
        g = att[..., 0, None, None] + self.elevation_rad[:, None]
        t = att[..., 1, None, None] + self.azimuth_rad[None, :]
        return np.broadcast_arrays(g, t)

    def directions(self, attitude_rad: Array) -> Array:
        """Unit beam vectors ``e`` (seed 004, eq. 8).

        Args:
            attitude_rad: ``(gamma_k, theta_k)``, shape (..., 2), rad.

        Returns:
            Shape (..., Mi, Mj, 3), world frame (z up).
        """
        g, t = self.absolute_angles(attitude_rad)
        cg = np.cos(g)
        return np.stack([cg * np.cos(t), cg * np.sin(t), np.sin(g)], axis=-1)

    def direction_change(
        self, attitude_rad: Array, next_attitude_rad: Array, exact: bool = False
    ) -> Array:
        """Change of the beam vectors between two attitudes (seed 004, eq. 10).

        Eq. 10 is the first-order change in ``dgamma = gamma_{k+1} - gamma_k`` and ``dtheta``
        (with the printed sign of the d(theta) term of ``de^Y`` corrected to
        ``+cos(g) cos(t)``); ``exact=True`` gives ``e_{k+1} - e_k`` instead.

        Args:
            attitude_rad: ``(gamma_k, theta_k)``, shape (..., 2), rad.
            next_attitude_rad: ``(gamma_{k+1}, theta_{k+1})``, shape (..., 2), rad.
            exact: the exact difference instead of eq. 10.

        Returns:
            ``de``, shape (..., Mi, Mj, 3).
        """
        a0 = np.asarray(attitude_rad, dtype=float)
        a1 = np.asarray(next_attitude_rad, dtype=float)
        if exact:
            return self.directions(a1) - self.directions(a0)
        g, t = self.absolute_angles(a0)
        dg = (a1[..., 0] - a0[..., 0])[..., None, None]
        dt = (a1[..., 1] - a0[..., 1])[..., None, None]
        sg, cg, st, ct = np.sin(g), np.cos(g), np.sin(t), np.cos(t)
        dex = -dg * sg * ct - dt * cg * st  # eq. 10
        dey = -dg * sg * st + dt * cg * ct  # eq. 10, d(theta) sign corrected
        dez = dg * cg  # eq. 10
        return np.stack([dex, dey, dez], axis=-1)


@dataclass(frozen=True)
class SlopeBasis:
    """The functions ``psi_l`` of Appendix A's seabed fit ``psi(x) = z + sum_l p_l psi_l(x)``.

    Attributes:
        kind: ``"harmonic"``: 1, sin and cos of ``2 pi l x / period_x_m`` and of
            ``2 pi l y / period_y_m``, l = 1..harmonics (the family of eq. 24: 1 + 4 K
            functions); ``"plane"``: 1, x, y; ``"quadratic"``: 1, x, y, x^2, x y, y^2 (x, y
            about the image's mean foot).
        period_x_m: the x period of the harmonic basis, m (seed 004: 20).
        period_y_m: the y period, m (seed 004: 20).
        harmonics: K of the harmonic basis (seed 004: 2).
    """

    kind: Literal["harmonic", "plane", "quadratic"] = "harmonic"
    period_x_m: float = 20.0
    period_y_m: float = 20.0
    harmonics: int = 2

    def __post_init__(self) -> None:
        if self.kind not in ("harmonic", "plane", "quadratic"):
            raise NavInputError(
                f"SlopeBasis.kind = {self.kind!r}: use harmonic, plane or quadratic"
            )
        if self.kind == "harmonic":
            if not (self.period_x_m > 0 and self.period_y_m > 0):
                raise NavInputError(
                    f"SlopeBasis periods = ({self.period_x_m}, {self.period_y_m}) m: must be > 0"
                )
            k = self.harmonics
            if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 1:
                raise NavInputError(f"SlopeBasis.harmonics = {k!r}: must be an integer >= 1")

    @classmethod
    def seed004(cls) -> SlopeBasis:
        """The harmonic basis of eq. 24: periods 20 m, K = 2."""
        return cls("harmonic", 20.0, 20.0, 2)

    @property
    def size(self) -> int:
        """Number of basis functions (besides z)."""
        return {"harmonic": 1 + 4 * self.harmonics, "plane": 3, "quadratic": 6}[self.kind]

    def values_and_gradients(self, x: Array, y: Array) -> tuple[Array, Array, Array]:
        """The basis functions and their horizontal derivatives at points.

        Args:
            x: shape (..., m), m (already centred for the polynomial bases).
            y: shape (..., m), m.

        Returns:
            ``(phi, dphi_dx, dphi_dy)``, each shape (..., m, size).
        """
        return tuple(np.swapaxes(a, -1, -2) for a in self.rows(x, y))  # type: ignore[return-value]

    def rows(self, x: Array, y: Array) -> tuple[Array, Array, Array]:
        """:meth:`values_and_gradients` with the function index before the point index.

        Returns:
            ``(phi, dphi_dx, dphi_dy)``, each shape (..., size, m).
        """
        one, zero = np.ones_like(x), np.zeros_like(x)
        if self.kind == "plane":
            return (
                np.stack([one, x, y], -2),
                np.stack([zero, one, zero], -2),
                np.stack([zero, zero, one], -2),
            )
        if self.kind == "quadratic":
            return (
                np.stack([one, x, y, x * x, x * y, y * y], -2),
                np.stack([zero, one, zero, 2 * x, y, zero], -2),
                np.stack([zero, zero, one, zero, x, 2 * y], -2),
            )
        # sin and cos of l w x from those of w x (angle addition), the argument reduced to one
        # period first (cheaper sines)
        px, py = self.period_x_m, self.period_y_m
        w1x, w1y = 2.0 * np.pi / px, 2.0 * np.pi / py
        tx, ty = w1x * (x - px * np.round(x / px)), w1y * (y - py * np.round(y / py))
        sx1, cx1, sy1, cy1 = np.sin(tx), np.cos(tx), np.sin(ty), np.cos(ty)
        sx, cx, sy, cy = sx1, cx1, sy1, cy1
        phi, dx, dy = [one], [zero], [zero]
        for lv in range(1, self.harmonics + 1):
            if lv > 1:
                sx, cx = sx * cx1 + cx * sx1, cx * cx1 - sx * sx1
                sy, cy = sy * cy1 + cy * sy1, cy * cy1 - sy * sy1
            wx, wy = lv * w1x, lv * w1y
            phi += [sx, cx, sy, cy]
            dx += [wx * cx, -wx * sx, zero, zero]
            dy += [zero, zero, wy * cy, -wy * sy]
        return np.stack(phi, -2), np.stack(dx, -2), np.stack(dy, -2)


def check_basis(basis: SlopeBasis, feet: int) -> SlopeBasis:
    """Refuse a basis with more unknowns than an image has feet (Appendix A's fit).

    The fit of a path needs more valid feet than basis functions (its ``ok``), so with ``m``
    feet per image at most ``m - 1`` functions can ever be fitted: a harmonic basis of at most
    ``(m - 2) // 4`` harmonics (``1 + 4 K`` functions), a plane from 4 feet, a quadratic from 7.

    Args:
        basis: the fit's functions.
        feet: beams per image, ``m``.

    Returns:
        ``basis``.

    Raises:
        NavInputError: if ``basis.size >= feet``.
    """
    if basis.size >= feet:
        what = (
            f"harmonics = {basis.harmonics} ({basis.size} functions; at most {(feet - 2) // 4} "
            f"harmonics for {feet} feet)"
            if basis.kind == "harmonic"
            else f"{basis.size} functions"
        )
        raise NavInputError(
            f"SlopeBasis {basis.kind!r}, {what}: Appendix A's fit has more unknowns than the "
            f"{feet} beam feet of an image give equations (it needs more feet than functions)"
        )
    return basis


def fit_slopes(points: Array, valid: BoolArray, basis: SlopeBasis) -> tuple[Array, BoolArray]:
    """Seabed gradient at the beam feet from the feet themselves (seed 004, Appendix A, eq. A1).

    Fits ``psi(x) = z + sum_l p_l psi_l(x, y)`` (z coefficient fixed to 1) to the valid points of
    each path in least squares, then returns ``grad psi = (sum p_l dpsi_l/dx, sum p_l dpsi_l/dy,
    1)`` at every point.

    The per-path arithmetic runs in C (``nav/seabed_shift.c``: the basis, the normal equations
    scaled to a unit diagonal, solved by Cholesky); paths whose scaled Gram matrix may have a
    condition number above :data:`FIT_C_CONDITION` are fitted in numpy
    (:func:`_least_squares`: LAPACK's eigen-decomposition or the SVD), as are bases of more
    than :data:`FIT_MAX_FUNCTIONS` functions.

    Args:
        points: beam feet, shape (P, m, 3), m, world (z up).
        valid: which points have an echo, shape (P, m).
        basis: the fit's functions.

    Returns:
        ``(grad, ok)``: gradients shape (P, m, 3) (zero where ``ok`` is False), and ``ok``
        shape (P,): the path had more valid points than basis functions.

    Raises:
        NavInputError: if ``points`` and ``valid`` do not match, a valid foot is not finite, or
            the basis has at least as many functions as an image has feet (no path could be
            fitted; :func:`check_basis`).
        NavError: if the C library is not built.
    """
    pts = np.ascontiguousarray(points, dtype=float)
    w = np.asarray(valid, dtype=bool)
    if w.ndim != 2 or pts.shape != (*w.shape, 3):
        raise NavInputError(
            f"fit_slopes: points of shape {pts.shape} and valid of shape {w.shape}, expected "
            "(P, m, 3) and (P, m)"
        )
    P, m = w.shape
    check_basis(basis, m)
    _finite("fit_slopes: points (at a valid foot)", pts, np.broadcast_to(w[..., None], pts.shape))
    if not np.isfinite(pts).all():  # feet without echo take no part: keep their NaN out of C
        pts = np.where(w[..., None], pts, 0.0)
    if basis.size > FIT_MAX_FUNCTIONS:
        return _fit_slopes_numpy(pts, w, basis)
    grad = np.empty((P, m, 3))
    ok = np.empty(P, np.uint8)
    to_numpy = np.empty(P, np.uint8)
    kind = {"harmonic": 0, "plane": 1, "quadratic": 2}[basis.kind]
    valid_c = np.ascontiguousarray(w, dtype=np.uint8)
    flagged = _shift_library().fit(
        P,
        m,
        pts,
        valid_c,
        kind,
        basis.harmonics,
        float(basis.period_x_m),
        float(basis.period_y_m),
        FIT_C_CONDITION,
        grad,
        ok,
        to_numpy,
        _sizes(pts, valid_c, grad, ok, to_numpy),
        5,
    )
    if flagged < 0:
        raise NavError(f"fit_slopes: the C fit refused: {_C_STATUS.get(flagged, flagged)}")
    if flagged:  # less well conditioned: numpy (LAPACK) on those paths
        bad = np.flatnonzero(to_numpy)
        grad[bad] = _fit_slopes_numpy(pts[bad], w[bad], basis)[0]
    return grad, ok.view(np.bool_)


def _fit_slopes_numpy(
    points: Array, valid: BoolArray, basis: SlopeBasis
) -> tuple[Array, BoolArray]:
    """:func:`fit_slopes` in numpy (the ill-conditioned paths and the large bases)."""
    pts = np.asarray(points, dtype=float)
    w = np.asarray(valid, dtype=bool)
    n_valid = w.sum(axis=1)
    ok = n_valid > basis.size
    x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
    if basis.kind != "harmonic":  # centre the polynomial bases on the valid feet
        cnt = np.maximum(n_valid, 1)[:, None]
        x = x - np.where(w, x, 0.0).sum(1, keepdims=True) / cnt
        y = y - np.where(w, y, 0.0).sum(1, keepdims=True) / cnt
    phi, dphi_dx, dphi_dy = basis.rows(x, y)  # (P, size, m)
    at = phi * w[:, None, :]  # A^T; masked points are zero columns
    rhs = -np.where(w, z, 0.0)[..., None]  # eq. A1 with the z coefficient fixed to 1
    p = _least_squares(at, rhs).transpose(0, 2, 1)  # (P, 1, size)
    gx = (p @ dphi_dx)[:, 0]
    gy = (p @ dphi_dy)[:, 0]
    grad = np.stack([gx, gy, np.ones_like(gx)], axis=-1)
    grad = np.where((ok[:, None] & w)[..., None], grad, 0.0)
    return grad, ok


FIT_RCOND = 1e-10
"""Relative singular-value cut-off of Appendix A's fit (:func:`fit_slopes`)."""

FIT_C_CONDITION = 1e4
"""Largest condition number of the scaled Gram matrix of Appendix A's fit solved in C
(:func:`fit_slopes`, by the bound ``max_row_sum(G) trace(G^-1)``); the C solution (Cholesky)
and numpy's (LAPACK's eigen-decomposition) differ by about the condition number times the
rounding error, so up to here they agree to ~1e-11, and the paths beyond it (about 5 per cent
of seed 004's) keep numpy's numbers."""

FIT_MAX_FUNCTIONS = 64
"""Most basis functions of Appendix A's fit in C (``FIT_MAX`` of ``nav/seabed_shift.c``); a
larger basis (a harmonic one with more than 15 harmonics) is fitted in numpy."""

GRAM_CONDITION = 1e12
"""Largest condition number of the Jacobi-scaled Gram matrix ``A^T A`` that
:func:`_least_squares` solves by its eigen-decomposition; beyond it, the SVD of ``A``."""


def _least_squares(at: Array, rhs: Array) -> Array:
    """``pinv(A, rcond=FIT_RCOND) @ rhs`` per path, through the Gram matrix where it is safe.

    The normal equations ``(A^T A) p = A^T b``, scaled to a unit diagonal and solved by the
    eigen-decomposition of the small Gram matrix, cost a fraction of a batched SVD of the tall
    ``A``. They square the condition number, so paths whose scaled Gram matrix has a condition
    number above :data:`GRAM_CONDITION` (singular values of ``A`` spread by more than 1e6; a
    rank-deficient fit among them) take the SVD pseudo-inverse instead, with its minimum-norm
    solution.

    Args:
        at: ``A^T``, shape (P, n, m).
        rhs: shape (P, m, 1).

    Returns:
        Shape (P, n, 1).
    """
    a = at.transpose(0, 2, 1)
    g = at @ a
    d = np.sqrt(np.einsum("pii->pi", g))
    dinv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    gs = g * dinv[:, :, None] * dinv[:, None, :]
    lam, v = np.linalg.eigh(gs)  # ascending
    good = lam[:, 0] > lam[:, -1] / GRAM_CONDITION
    ys = dinv[..., None] * (at @ rhs)
    lam = np.where(good[:, None], lam, 1.0)
    p = dinv[..., None] * (v @ ((v.transpose(0, 2, 1) @ ys) / lam[..., None]))
    bad = np.flatnonzero(~good)
    if bad.size:
        p[bad] = np.linalg.pinv(a[bad], rcond=FIT_RCOND) @ rhs[bad]
    return p


@dataclass(frozen=True)
class ShiftEstimate:
    """The position shift between two acoustic images (seed 004, eq. 15), per path.

    Attributes:
        shift_m: ``dX-hat_{k+1}``, shape (P, 3), m, world (where not ``ok``: zero, or the
            commanded displacement when one is given).
        covariance_m2: its error covariance, shape (P, 3, 3), m^2 (module docstring;
            ``fallback_var_m2 * I`` where not ``ok``).
        beams: beams used (echo in both images), shape (P,).
        rank: rank of eq. 14's A (3: the whole shift is observed), shape (P,).
        ok: a shift was produced (enough beams for the slope fit and the least squares),
            shape (P,).
        residual_rms: root-mean-square residual of eq. 13, shape (P,), m (0 where not ``ok``).
    """

    shift_m: Array
    covariance_m2: Array
    beams: NDArray[np.int_]
    rank: NDArray[np.int_]
    ok: BoolArray
    residual_rms: Array


def _check_images(name: str, a: Array, shape: tuple[int, ...]) -> Array:
    a = np.asarray(a)
    if a.shape != shape:
        raise NavInputError(f"{name}: shape {a.shape}, expected {shape}")
    return a


def shift_estimate(
    ranges_m: Array,
    next_ranges_m: Array,
    geometry: BeamGeometry,
    attitude_rad: Array,
    next_attitude_rad: Array | None = None,
    *,
    echo: BoolArray | None = None,
    next_echo: BoolArray | None = None,
    reading: BeamAttitude = "one_attitude",
    basis: SlopeBasis | None = None,
    position_m: Array | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
    slopes: Array | None = None,
    covariance: CovarianceKind = "residual",
    sigma_range_m: float = 0.1,
    fallback_var_m2: float = 1e6,
    rcond: float = 1e-4,
    commanded_shift_m: Array | None = None,
) -> ShiftEstimate:
    """Position shift from two consecutive acoustic images (seed 004, eq. 8-15, Appendix A).

    This is the prediction step of a filter fed by seabed sensing: ``X-tilde_{k+1} = X-hat_k +
    shift`` (seed 004 section 6, second row of Table 1).

    Args:
        ranges_m: image k, ``L_k^ij``, shape (P, Mi, Mj), m (any finite value where no echo).
        next_ranges_m: image k+1, ``L_{k+1}^ij``, shape (P, Mi, Mj), m.
        geometry: the beams' aiming angles.
        attitude_rad: ``(gamma_k, theta_k)`` of image k (from the command ``u_k``), shape
            (P, 2), rad.
        next_attitude_rad: ``(gamma_{k+1}, theta_{k+1})`` of image k+1, shape (P, 2), rad; needed
            for ``reading="turning"``, ignored for ``"one_attitude"`` (image k+1 was taken at
            ``attitude_rad``).
        echo: beams of image k with an echo, shape (P, Mi, Mj) (default: all).
        next_echo: the same for image k+1.
        reading: the beam attitude between the images (:data:`BeamAttitude`).
        basis: Appendix A's basis (default :meth:`SlopeBasis.seed004`).
        position_m: ``X-hat_k``, shape (P, 3), m, for the feet ``X-hat_k + L e`` of the slope fit
            (default zero; the bases are shift-invariant, see the module docstring).
        delta_e: eq. 10 (``"linear"``) or the exact ``e_{k+1} - e_k``.
        slopes: known ``grad psi`` at the feet of image k, shape (P, Mi, Mj, 3), instead of the
            Appendix A estimate (for tests and for a known seabed).
        covariance: ``"residual"`` or ``"range_noise"`` (module docstring).
        sigma_range_m: range noise standard deviation, m (seed 004: 0.1), for the covariance.
        fallback_var_m2: variance stated along unobserved directions and for shifts not
            produced, m^2.
        rcond: singular values of A below ``rcond`` times the largest count as zero (an
            ill-conditioned slope field, e.g. a quadratic fit of a faceted seabed, would
            otherwise give a shift of kilometres); the direction is then unobserved.
        commanded_shift_m: the commanded displacement ``V(u_k) dt``, shape (P, 3), m: the shift
            stated where none is produced (default zero), with ``fallback_var_m2 * I``.

    Returns:
        The :class:`ShiftEstimate`.

    Raises:
        NavInputError: for arrays of the wrong shape, non-finite ranges where there is an echo,
            a non-finite attitude, position, command or slope (at a used beam), a
            ``sigma_range_m``, ``fallback_var_m2`` or ``rcond`` out of range, a basis with at
            least as many functions as the image has beams (:func:`check_basis`), an unknown
            reading, or ``"turning"`` without ``next_attitude_rad``.
        NavError: if the C library (``nav/seabed_shift.c``) is not built.
    """
    L0 = np.asarray(ranges_m, dtype=float)
    if L0.ndim != 3 or L0.shape[1:] != geometry.shape:
        raise NavInputError(
            f"ranges_m: shape {L0.shape}, expected (paths, {geometry.shape[0]}, "
            f"{geometry.shape[1]})"
        )
    P = L0.shape[0]
    L1 = _check_images("next_ranges_m", np.asarray(next_ranges_m, dtype=float), L0.shape)
    w0 = np.ones(L0.shape, bool) if echo is None else _check_images("echo", echo, L0.shape)
    w1 = (
        np.ones(L0.shape, bool)
        if next_echo is None
        else _check_images("next_echo", next_echo, L0.shape)
    )
    att0 = _check_images("attitude_rad", np.asarray(attitude_rad, dtype=float), (P, 2))
    _finite("attitude_rad", att0)
    if reading not in ("one_attitude", "turning"):
        raise NavInputError(f"reading = {reading!r}: use 'one_attitude' or 'turning'")
    if reading == "turning":
        if next_attitude_rad is None:
            raise NavInputError("reading = 'turning' needs next_attitude_rad (paths, 2)")
        att1 = _check_images(
            "next_attitude_rad", np.asarray(next_attitude_rad, dtype=float), (P, 2)
        )
        _finite("next_attitude_rad", att1)
    if delta_e not in ("linear", "exact"):
        raise NavInputError(f"delta_e = {delta_e!r}: use 'linear' or 'exact'")
    if covariance not in ("residual", "range_noise"):
        raise NavInputError(f"covariance = {covariance!r}: use 'residual' or 'range_noise'")
    if not (np.isfinite(sigma_range_m) and sigma_range_m >= 0):
        raise NavInputError(f"sigma_range_m = {sigma_range_m}: must be finite and >= 0, m")
    if not (np.isfinite(fallback_var_m2) and fallback_var_m2 > 0):
        raise NavInputError(f"fallback_var_m2 = {fallback_var_m2}: must be finite and > 0, m^2")
    if not (np.isfinite(rcond) and 0 <= rcond < 1):
        raise NavInputError(f"rcond = {rcond}: must be in [0, 1)")
    w0, w1 = w0.astype(bool), w1.astype(bool)
    use = w0 & w1
    if not (np.all(np.isfinite(L0[w0])) and np.all(np.isfinite(L1[w1]))):
        raise NavInputError("ranges_m / next_ranges_m: non-finite range on a beam with an echo")
    m = geometry.shape[0] * geometry.shape[1]
    e = geometry.directions(att0).reshape(P, m, 3)  # eq. 8
    de = None
    if reading == "turning":  # step 2: eq. 10
        de = geometry.direction_change(att0, att1, exact=delta_e == "exact").reshape(P, m, 3)
    usef = use.reshape(P, m)
    if slopes is None:  # step 3: Appendix A on every foot of image k
        origin = np.zeros((P, 3)) if position_m is None else np.asarray(position_m, dtype=float)
        _finite("position_m", _check_images("position_m", origin, (P, 3)))
        w0f = w0.reshape(P, m)
        feet = origin[:, None, :] + np.where(w0f, L0.reshape(P, m), 0.0)[..., None] * e  # eq. 8
        grad, fit_ok = fit_slopes(feet, w0f, basis or SlopeBasis.seed004())
    else:
        grad = _check_images("slopes", np.asarray(slopes, dtype=float), (*L0.shape, 3))
        _finite("slopes (at a beam with an echo in both images)", grad, use[..., None])
        grad = np.where(use[..., None], grad, 0.0).reshape(P, m, 3)
        fit_ok = np.ones(P, bool)
    cmd = None
    if commanded_shift_m is not None:
        cmd = _check_images("commanded_shift_m", np.asarray(commanded_shift_m, dtype=float), (P, 3))
        _finite("commanded_shift_m", cmd)
    if rcond * 1e8 < 1.0:  # a cut-off below what eigenvalues of A^T A resolve: the SVD
        return _shift_svd(
            grad,
            e,
            de,
            L0,
            L1,
            usef,
            fit_ok,
            covariance,
            sigma_range_m,
            fallback_var_m2,
            rcond,
            cmd,
        )
    # steps 4-5 in C (nav/seabed_shift.c): eq. 12 and 14 over the used beams, eq. 15 by the
    # singular values of A from the eigen-decomposition of the 3 x 3 A^T A with an absolute floor
    # (rank-deficient A: minimum-norm shift), and the stated covariance
    shift = np.empty((P, 3))
    cov = np.empty((P, 3, 3))
    beams = np.empty(P, np.int64)
    rank = np.empty(P, np.int64)
    ok = np.empty(P, np.uint8)
    rms = np.empty(P)
    de_c = None if de is None else np.ascontiguousarray(de, dtype=float)
    cmd_c = None if cmd is None else np.ascontiguousarray(cmd, dtype=float)
    ins = [
        np.ascontiguousarray(grad, dtype=float),
        np.ascontiguousarray(e, dtype=float),
        np.ascontiguousarray(L0.reshape(P, m)),
        np.ascontiguousarray(L1.reshape(P, m)),
        np.ascontiguousarray(usef, dtype=np.uint8),
        np.ascontiguousarray(fit_ok, dtype=np.uint8),
    ]
    outs = [shift, cov, beams, rank, ok, rms]
    status = _shift_library().shift(
        P,
        m,
        *ins[:2],
        None if de_c is None else de_c.ctypes.data,
        *ins[2:],
        int(covariance == "residual"),
        float(sigma_range_m),
        float(fallback_var_m2),
        float(rcond),
        SINGULAR_FLOOR,
        None if cmd_c is None else cmd_c.ctypes.data,
        *outs,
        _sizes(*ins[:2], de_c, *ins[2:], cmd_c, *outs),
        14,
    )
    if status < 0:
        raise NavError(f"shift_estimate: the C shift refused: {_C_STATUS.get(status, status)}")
    return ShiftEstimate(shift, cov, beams, rank, ok.view(np.bool_), rms)


def _shift_svd(
    grad: Array,
    e: Array,
    de: Array | None,
    L0: Array,
    L1: Array,
    usef: BoolArray,
    fit_ok: BoolArray,
    covariance: CovarianceKind,
    sigma_range_m: float,
    fallback_var_m2: float,
    rcond: float,
    cmd: Array | None,
) -> ShiftEstimate:
    """Steps 4-5 of :func:`shift_estimate` in numpy with the SVD of A, for ``rcond`` below what
    the eigenvalues of ``A^T A`` resolve (arguments as there, flattened to (P, m, ...))."""
    P, m = usef.shape
    if de is None:
        de = np.zeros_like(e)
    L0f = np.where(usef, L0.reshape(P, m), 0.0)
    dL = np.where(usef, (L1 - L0).reshape(P, m), 0.0)  # step 1: dL = L_{k+1} - L_k
    grad = np.where(usef[..., None], grad, 0.0)
    # step 4: eq. 12 and 14 (masked beams give zero rows)
    A = grad
    B = -np.einsum("pmc,pmc->pm", grad, de * L0f[..., None] + e * dL[..., None])
    beams = usef.sum(axis=1)
    ok = fit_ok & (beams >= 3)
    # step 5: eq. 15 by the SVD of A with an absolute floor (rank-deficient A: minimum-norm shift)
    At = A.transpose(0, 2, 1)
    _, s, Vt = np.linalg.svd(A, full_matrices=False)  # (P,3), (P,3,3)
    floor = np.maximum(SINGULAR_FLOOR * np.sqrt(np.maximum(beams, 1)), rcond * s[:, 0])
    keep = s > floor[:, None]
    rank = keep.sum(axis=1)
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    atb = np.einsum("pcm,pm->pc", At, B)
    shift = np.einsum("pcd,pc->pd", Vt, np.einsum("pcd,pd->pc", Vt, atb) * s_inv**2)
    resid = np.where(usef, np.einsum("pmc,pc->pm", A, shift) - B, 0.0)
    rss = (resid**2).sum(axis=1)
    # range-noise propagation: dB/dL_k = -g.(de - e), dB/dL_{k+1} = -g.e
    gb0 = np.einsum("pmc,pmc->pm", grad, de - e)
    gb1 = np.einsum("pmc,pmc->pm", grad, e)
    var_b = sigma_range_m**2 * (gb0**2 + gb1**2) * usef
    # pseudo-inverse rows: dX = V diag(s_inv^2) V^T A^T B
    Apinv = np.einsum("pcd,pc,pce->pde", Vt, s_inv**2, Vt) @ At
    cov_noise = np.einsum("pdm,pm,pem->pde", Apinv, var_b, Apinv)
    if covariance == "residual":
        dof = np.maximum(beams - rank, 1)
        s2 = rss / dof
        cov = np.einsum("pcd,pc,pce->pde", Vt, s2[:, None] * s_inv**2, Vt)
        # never below the range-noise propagation
        trace_ok = np.trace(cov, axis1=1, axis2=2) >= np.trace(cov_noise, axis1=1, axis2=2)
        cov = np.where(trace_ok[:, None, None], cov, cov_noise)
    else:
        cov = cov_noise
    unobserved = np.where(keep, 0.0, fallback_var_m2)
    cov = cov + np.einsum("pcd,pc,pce->pde", Vt, unobserved, Vt)
    eye = np.broadcast_to(np.eye(3) * fallback_var_m2, (P, 3, 3))
    shift = np.where(ok[:, None], shift, 0.0 if cmd is None else cmd)
    cov = np.where(ok[:, None, None], cov, eye)
    rms = np.where(ok, np.sqrt(rss / np.maximum(beams, 1)), 0.0)
    return ShiftEstimate(shift, cov, beams, np.where(ok, rank, 0), ok, rms)


def seabed_track(
    start_m: Array,
    ranges_m: Array,
    next_ranges_m: Array,
    geometry: BeamGeometry,
    attitudes_rad: Array,
    *,
    echo: BoolArray | None = None,
    next_echo: BoolArray | None = None,
    reading: BeamAttitude = "one_attitude",
    basis: SlopeBasis | None = None,
    delta_e: Literal["linear", "exact"] = "linear",
    slopes: Array | None = None,
) -> tuple[Array, BoolArray]:
    """Dead reckoning on seabed shifts, ``X-hat_{k+1} = X-hat_k + dX-hat_{k+1}`` (seed 004,
    eq. 16), over N steps.

    Args:
        start_m: ``X-hat_0``, shape (P, 3), m.
        ranges_m: image at the start of each step (at ``X_k``, attitude ``u_k``), shape
            (P, N, Mi, Mj), m.
        next_ranges_m: image at the end of each step (at ``X_{k+1}``; attitude ``u_k`` for
            ``"one_attitude"``, ``u_{k+1}`` for ``"turning"``), shape (P, N, Mi, Mj), m.
        geometry: the beams.
        attitudes_rad: ``(gamma_k, theta_k)``, k = 0..N, shape (P, N + 1, 2), rad.
        echo: echoes of ``ranges_m``, shape (P, N, Mi, Mj) (default: all).
        next_echo: echoes of ``next_ranges_m``.
        reading: :data:`BeamAttitude`.
        basis: Appendix A's basis.
        delta_e: eq. 10 or the exact change.
        slopes: known ``grad psi`` at the feet of ``ranges_m``, shape (P, N, Mi, Mj, 3), instead
            of the Appendix A estimate.

    Returns:
        ``(track, ok)``: positions shape (P, N + 1, 3), m; ``ok`` shape (P, N): the step's shift
        was produced (a step without one adds zero).
    """
    x = np.asarray(start_m, dtype=float)
    L0 = np.asarray(ranges_m, dtype=float)
    P, N = L0.shape[:2]
    att = np.asarray(attitudes_rad, dtype=float)
    if att.shape != (P, N + 1, 2):
        raise NavInputError(f"attitudes_rad: shape {att.shape}, expected ({P}, {N + 1}, 2)")
    track = np.empty((P, N + 1, 3))
    oks = np.empty((P, N), bool)
    track[:, 0] = x
    for k in range(N):
        est = shift_estimate(
            L0[:, k],
            np.asarray(next_ranges_m)[:, k],
            geometry,
            att[:, k],
            att[:, k + 1],
            echo=None if echo is None else np.asarray(echo)[:, k],
            next_echo=None if next_echo is None else np.asarray(next_echo)[:, k],
            reading=reading,
            basis=basis,
            position_m=track[:, k],
            delta_e=delta_e,
            slopes=None if slopes is None else np.asarray(slopes)[:, k],
        )
        track[:, k + 1] = track[:, k] + est.shift_m  # eq. 16
        oks[:, k] = est.ok
    return track, oks
