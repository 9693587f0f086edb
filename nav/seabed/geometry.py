"""Seed 004's multibeam geometry and Appendix A's slope basis (:mod:`nav.seabed`): the beams'
aiming angles and unit vectors (eq. 8) with their change between two images (eq. 10), the basis
of the seabed's fit and the check that a fit is possible.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from nav.errors import NavInputError

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


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
