"""Motion and measurement models (f, h, their Jacobians, Q, R), apart from the algorithms.

Navigation states start with the position of the vehicle, ``x[..., :3] = (east, north, up)``, m,
world frame (ENU, z up; depth = -up); a motion model may append components (the current of
:class:`CurrentAwareMotion`) and says how long its state is (``dim``) and where a current is
(``current_components``). The measurement models read the position and work on any such state
(their Jacobians have zero columns for the appended components). Arrays carry a leading run axis:
``x`` is (n, d), covariances (n, d, d).

Motion models give their prediction twice: batched (``f``, ``F``, ``Q`` for
:class:`nav.ekf.BatchEKF`) and in closed form for a single run (``predict_one`` for
:class:`nav.ekf.SingleRunEKF`), which exploits their structure (``F = I``, or the identity plus
the current's blocks) and gives the same numbers (tested).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nav.angles import (
    course_of,
    elevation_angle,
    rel_from_range_azimuth_elevation,
    unit_vector,
    unit_vector_scalar,
    velocity_from_course_speed,
    wrap_pi,
)

Array = NDArray[np.float64]


TIME_CHUNK = 48
"""Steps computed together in :meth:`CourseSpeedDepthMotion.increment_and_packed_Q`."""


@dataclass(frozen=True)
class CourseSpeedDepthMotion:
    """Dead-reckoning motion from course, speed and depth change (seed 000 eq. 8 and 16).

    ``f(x, u) = x + (dt S sin C, dt S cos C, -dz)`` with ``u = (C, S, dz)``: course over ground
    (rad, clockwise from north), speed (m/s) and depth change over the step (m, positive down; the
    state's third component is up, hence the minus sign). ``F = df/dx = I`` and
    ``Q = G diag(sigma_C^2, sigma_S^2, sigma_dz^2) G^T`` with ``G = df/du`` (eq. 16).

    Attributes:
        sigma_course_rad: course standard deviation the filter assumes, rad.
        sigma_speed_m_s: speed standard deviation, m/s.
        sigma_depth_change_m: depth-change standard deviation per step, m.
    """

    sigma_course_rad: float
    sigma_speed_m_s: float
    sigma_depth_change_m: float

    dim: ClassVar[int] = 3
    """Length of the state: the position."""
    current_components: ClassVar[slice | None] = None
    """No current in the state."""

    def increment(self, u: Array, dt_s: float | Array) -> Array:
        """Displacement over one step, shape (n, 3), m, world (eq. 16 without the state)."""
        c, s, dz = u[..., 0], u[..., 1], u[..., 2]
        return np.concatenate([velocity_from_course_speed(c, dt_s * s), -dz[..., None]], axis=-1)

    def increment_one(self, u: Array, dt_s: float) -> Array:
        """:meth:`increment` of one run with :mod:`math`'s sine and cosine.

        Args:
            u: ``(C, S, dz)``, shape (3,).
            dt_s: step duration, s.

        Returns:
            Displacement ``(east, north, up)``, shape (3,), m, world.
        """
        c, spd, dz = np.asarray(u, dtype=float)[:3].tolist()
        return np.array(self._increment_floats(c, spd, dz, dt_s))

    @staticmethod
    def _increment_floats(
        course_rad: float, speed_m_s: float, dz_m: float, dt_s: float
    ) -> tuple[float, float, float]:
        """:meth:`increment_one` in Python floats: ``(east, north, up)``, m, world."""
        ue, un = unit_vector_scalar(course_rad)
        return dt_s * speed_m_s * ue, dt_s * speed_m_s * un, -dz_m

    def f(self, x: Array, u: Array, dt_s: float) -> Array:
        """Predicted state (eq. 17): shape (n, 3)."""
        return x + self.increment(u, dt_s)

    def F(self, x: Array, u: Array, dt_s: float) -> Array:
        """State Jacobian, the identity (section 5), shape (n, 3, 3)."""
        return np.broadcast_to(np.eye(3), (x.shape[0], 3, 3))

    def G(self, u: Array, dt_s: float | Array) -> Array:
        """Input Jacobian ``df/du``, shape (n, 3, 3)."""
        s = u[..., 1]
        unit = unit_vector(u[..., 0])
        ue, un = unit[..., 0], unit[..., 1]
        G = np.zeros((*u.shape[:-1], 3, 3))
        G[..., 0, 0] = dt_s * s * un
        G[..., 0, 1] = dt_s * ue
        G[..., 1, 0] = -dt_s * s * ue
        G[..., 1, 1] = dt_s * un
        G[..., 2, 2] = -1.0
        return G

    def Q(self, u: Array, dt_s: float | Array) -> Array:
        """Process noise (eq. 16): ``G diag(sigma^2) G^T``, shape (..., 3, 3), written out from
        the five non-zero entries of G (:meth:`G`; tested equal to the matrix product)."""
        return self.increment_and_Q(u, dt_s)[1]

    def increment_and_Q(self, u: Array, dt_s: float | Array) -> tuple[Array, Array]:
        """:meth:`increment` and :meth:`Q` of the same steps, the course's sine and cosine
        computed once.

        Args:
            u: ``(C, S, dz)`` of each step, shape (..., 3).
            dt_s: step duration, s.

        Returns:
            ``(displacement (..., 3) m, Q (..., 3, 3) m^2)``; Q is exactly symmetric.
        """
        c, s, dz = u[..., 0], u[..., 1], u[..., 2]
        ue, un = np.sin(c), np.cos(c)
        ds = dt_s * s
        inc = np.empty(u.shape)
        inc[..., 0], inc[..., 1], inc[..., 2] = ds * ue, ds * un, -dz
        g00, g01, g10, g11 = ds * un, dt_s * ue, -ds * ue, dt_s * un
        sc2, ss2 = self.sigma_course_rad**2, self.sigma_speed_m_s**2
        Q = np.zeros((*u.shape[:-1], 3, 3))
        Q[..., 0, 0] = g00 * g00 * sc2 + g01 * g01 * ss2
        Q[..., 0, 1] = Q[..., 1, 0] = g00 * g10 * sc2 + g01 * g11 * ss2
        Q[..., 1, 1] = g10 * g10 * sc2 + g11 * g11 * ss2
        Q[..., 2, 2] = self.sigma_depth_change_m**2
        return inc, Q

    def increment_and_packed_Q(self, u: Array, dt_s: float) -> tuple[Array, Array]:
        """:meth:`increment_and_Q` of n runs' T steps laid out for
        :func:`nav.usbl.tracks.ekf_tracks`.

        Args:
            u: ``(C, S, dz)`` of each step, shape (n, T, 3).
            dt_s: step duration, s.

        Returns:
            ``(displacement (T, 3, n) m, Q packed (T, 6, n) m^2)``: time-major structure of
            arrays; Q's upper triangle in the order of :data:`nav.ekf.SYM3`. The same
            numbers as :meth:`increment_and_Q` (tested), with fewer temporaries.
        """
        n, T, _ = u.shape
        inc = np.empty((T, 3, n))
        Q = np.empty((T, 6, n))
        Q[:, 2] = Q[:, 4] = 0.0
        Q[:, 5] = self.sigma_depth_change_m**2
        sc2, ss2 = self.sigma_course_rad**2, self.sigma_speed_m_s**2
        # a few dozen steps at a time, so the temporaries stay in the cache (2-3x faster for
        # blocks of 1,000 runs than whole-array operations)
        for a in range(0, T, TIME_CHUNK):
            b = min(a + TIME_CHUNK, T)
            c, s, dz = (np.ascontiguousarray(u[:, a:b, i].T) for i in range(3))  # (b - a, n)
            ue, un = np.sin(c), np.cos(c)
            ds = np.multiply(dt_s, s, out=s)
            np.multiply(ds, ue, out=inc[a:b, 0])
            np.multiply(ds, un, out=inc[a:b, 1])
            np.negative(dz, out=inc[a:b, 2])
            # G's entries (:meth:`G`): g00 = ds un, g01 = dt ue, g10 = -ds ue, g11 = dt un
            g00, g10 = inc[a:b, 1], np.negative(inc[a:b, 0], out=dz)
            g01, g11 = np.multiply(dt_s, ue, out=ue), np.multiply(dt_s, un, out=un)
            tmp = c  # scratch
            for k, p, q, r, w in (
                (0, g00, g00, g01, g01),
                (1, g00, g10, g01, g11),
                (3, g10, g10, g11, g11),
            ):
                out = Q[a:b, k]
                np.multiply(p, q, out=out)
                out *= sc2
                np.multiply(r, w, out=tmp)
                tmp *= ss2
                out += tmp
        return inc, Q

    def predict_one(self, x: Array, P: Array, u: Array, dt_s: float) -> tuple[Array, Array]:
        """One prediction of one run in closed form (eq. 17-18 with ``F = I``): ``f(x, u)`` and
        ``P + Q`` written out with :mod:`math`, the numbers of the batched EKF's prediction
        with :meth:`f`, :meth:`F` and :meth:`Q` (tested), in a fraction of its time.

        Args:
            x: state, shape (1, 3), m, world.
            P: covariance, shape (1, 3, 3), m^2.
            u: input ``(C, S, dz)``, shape (1, 3).
            dt_s: step duration, s.

        Returns:
            ``(x-, P-)``, shapes (1, 3) and (1, 3, 3).
        """
        x_new = x.copy()
        x_new[0, :3] += self.increment_one(u[0], dt_s)
        P_new = P[0].copy()
        self._add_Q_one(P_new, u[0], dt_s)
        return x_new, P_new[None]

    def _add_Q_one(self, P: Array, u: Array, dt_s: float) -> None:
        """Add :meth:`Q` of one run, written out, to the leading 3x3 block of ``P`` (d, d)."""
        c, spd = u[:2].tolist()
        ue, un = unit_vector_scalar(c)
        sc2, ss2 = self.sigma_course_rad**2, self.sigma_speed_m_s**2
        g00, g01, g10, g11 = dt_s * spd * un, dt_s * ue, -dt_s * spd * ue, dt_s * un
        q00 = g00 * g00 * sc2 + g01 * g01 * ss2
        q01 = g00 * g10 * sc2 + g01 * g11 * ss2
        q11 = g10 * g10 * sc2 + g11 * g11 * ss2
        P[0, 0] += q00
        P[0, 1] += q01
        P[1, 0] += q01
        P[1, 1] += q11
        P[2, 2] += self.sigma_depth_change_m**2


@dataclass(frozen=True)
class UsblMeasurement:
    """USBL slant range, azimuth and elevation of the vehicle from a fixed transceiver (seed 000
    eq. 15, with world z up).

    ``h(x) = (r, alpha, beta)`` with ``d = x - transceiver``, ``r = |d|``,
    ``alpha = atan2(d_e, d_n)`` and ``beta = atan2(d_u, sqrt(d_e^2 + d_n^2))``.
    ``H = dh/dx`` is the Jacobian of section 5 (rows r, alpha, beta). Where the vehicle is nearly
    vertically above or below the transceiver (horizontal distance below ``min_horizontal_m``) the
    azimuth carries no usable linear information and its Jacobian diverges as 1/l: that component
    is left out of the update (:meth:`active`) instead of producing inf or NaN.

    Attributes:
        transceiver_world_m: transceiver position, shape (3,), m, world.
        sigma_range_m: range standard deviation the filter assumes, m.
        sigma_azimuth_rad: azimuth standard deviation, rad.
        sigma_elevation_rad: elevation standard deviation, rad.
        min_horizontal_m: horizontal distance below which the azimuth is not used, m.
    """

    transceiver_world_m: Array
    sigma_range_m: float
    sigma_azimuth_rad: float
    sigma_elevation_rad: float
    min_horizontal_m: float = 1.0

    ANGLES = (1, 2)
    """Indices of the angle components (wrapped residuals)."""

    def _d(self, x: Array) -> tuple[Array, Array, Array, Array, Array]:
        d = np.asarray(x, dtype=float)[..., :3] - self.transceiver_world_m
        l2 = d[..., 0] ** 2 + d[..., 1] ** 2
        horiz = np.sqrt(l2)
        r = np.sqrt(l2 + d[..., 2] ** 2)
        return d, l2, horiz, r, l2 + d[..., 2] ** 2

    def h(self, x: Array) -> Array:
        """Predicted measurement, shape (n, 3): m, rad in [0, 2 pi), rad."""
        return self._h(self._d(x))

    def _h(self, geo: tuple[Array, ...]) -> Array:
        d, _, horiz, r, _ = geo
        return np.stack([r, course_of(d), elevation_angle(d[..., 2], horiz)], axis=-1)

    def linearise(self, x: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        """:meth:`h`, :meth:`H` and :meth:`active` at once, the geometry computed once (the
        same numbers)."""
        geo = self._d(x)
        return self._h(geo), self._H(geo, np.shape(x)[-1]), self._active(geo)

    def H(self, x: Array) -> Array:
        """Jacobian ``dh/dx``, shape (n, 3, d); rows of inactive components are zero."""
        return self._H(self._d(x), np.shape(x)[-1])

    def _H(self, geo: tuple[Array, ...], dim: int) -> Array:
        d, l2, horiz, r, l3 = geo
        dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
        safe_r = np.maximum(r, 1e-9)
        far = horiz >= self.min_horizontal_m
        safe_l2 = np.where(far, l2, 1.0)
        # unit horizontal direction, zero when exactly vertical
        safe_h = np.where(horiz > 0, horiz, 1.0)
        ux, uy = np.where(horiz > 0, dx / safe_h, 0.0), np.where(horiz > 0, dy / safe_h, 0.0)
        safe_l3 = np.maximum(l3, 1e-18)
        H = np.zeros((*d.shape[:-1], 3, dim))
        H[..., 0, 0], H[..., 0, 1], H[..., 0, 2] = dx / safe_r, dy / safe_r, dz / safe_r
        H[..., 1, 0] = np.where(far, dy / safe_l2, 0.0)
        H[..., 1, 1] = np.where(far, -dx / safe_l2, 0.0)
        H[..., 2, 0] = -dz * ux / safe_l3
        H[..., 2, 1] = -dz * uy / safe_l3
        H[..., 2, 2] = horiz / safe_l3
        return H

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Which components take part in the update, shape (n, 3)."""
        return self._active(self._d(x))

    def _active(self, geo: tuple[Array, ...]) -> NDArray[np.bool_]:
        horiz = geo[2]
        act = np.ones((*horiz.shape, 3), dtype=bool)
        act[..., 1] = horiz >= self.min_horizontal_m
        return act

    def R(self) -> Array:
        """Measurement noise (section 5), shape (3, 3)."""
        return np.diag(
            [self.sigma_range_m**2, self.sigma_azimuth_rad**2, self.sigma_elevation_rad**2]
        )

    def residual(self, z: Array, hx: Array) -> Array:
        """Innovation ``z - h(x)`` with the angles wrapped to [-pi, pi) (eq. 19), the measured
        direction folded back against the prediction.

        A USBL reports a direction past the zenith as the direction over the top (azimuth + pi,
        elevation pi - beta; :func:`nav.angles.fold_azimuth_elevation`), and past the nadir as
        (azimuth + pi, -pi - beta). Both spellings are the same direction, but eq. 19's
        innovation is linear in the angles only in the chart of the prediction: for a vehicle
        passing over the transceiver, ``(alpha + pi, pi - beta)`` against a prediction at
        ``(alpha, beta')`` is an azimuth innovation of about pi where the direction differs by
        a few degrees of elevation. The innovation is therefore taken for both spellings of the
        measured direction (with the elevation residual wrapped, over the zenith and under the
        nadir give the same) and the one with the smaller squared angle residuals in units of
        the angles' sigmas is kept; away from the poles that is always the measurement as given.

        Args:
            z: measurements ``(r, alpha, beta)``, shape (n, 3), m, rad, rad.
            hx: predicted measurements :meth:`h`, shape (n, 3).

        Returns:
            Innovations, shape (n, 3): m, rad in [-pi, pi), rad in [-pi, pi).
        """
        z = np.asarray(z, dtype=float)
        y = z - hx
        y[..., 1] = wrap_pi(y[..., 1])
        y[..., 2] = wrap_pi(y[..., 2])
        # the same direction spelled over the pole: (alpha + pi, pi - beta); the nadir's
        # spelling -pi - beta differs by 2 pi, the same wrapped residual
        ya_fold = wrap_pi(z[..., 1] + np.pi - hx[..., 1])
        yb_fold = wrap_pi(np.pi - z[..., 2] - hx[..., 2])
        sa2, sb2 = self.sigma_azimuth_rad**2, self.sigma_elevation_rad**2
        folded = ya_fold**2 / sa2 + yb_fold**2 / sb2 < y[..., 1] ** 2 / sa2 + y[..., 2] ** 2 / sb2
        y[..., 1] = np.where(folded, ya_fold, y[..., 1])
        y[..., 2] = np.where(folded, yb_fold, y[..., 2])
        return y

    def invert(self, z: ArrayLike) -> Array:
        """The USBL-only position fix from a measurement (inverse of :meth:`h`).

        Args:
            z: ``(r, alpha, beta)``, shape (..., 3).

        Returns:
            Vehicle position, shape (..., 3), m, world.
        """
        return self.transceiver_world_m + rel_from_range_azimuth_elevation(z)

    def fix_covariance(self, z: ArrayLike) -> Array:
        """Covariance of :meth:`invert` by first-order propagation of ``R``, shape (..., 3, 3)."""
        z = np.asarray(z, dtype=float)
        r, a, b = z[..., 0], z[..., 1], z[..., 2]
        J = np.zeros((*z.shape[:-1], 3, 3))
        J[..., 0, :] = np.stack(
            [np.cos(b) * np.sin(a), r * np.cos(b) * np.cos(a), -r * np.sin(b) * np.sin(a)], -1
        )
        J[..., 1, :] = np.stack(
            [np.cos(b) * np.cos(a), -r * np.cos(b) * np.sin(a), -r * np.sin(b) * np.cos(a)], -1
        )
        J[..., 2, :] = np.stack([np.sin(b), np.zeros_like(r), r * np.cos(b)], -1)
        return J @ self.R() @ np.swapaxes(J, -1, -2)


@dataclass(frozen=True)
class HorizontalPositionMeasurement:
    """A horizontal position fix (GPS at the surface): ``h(x) = (east, north)``, linear.

    Attributes:
        sigma_m: standard deviation of each coordinate, m.
    """

    sigma_m: float

    def h(self, x: Array) -> Array:
        """Predicted fix, shape (n, 2), m."""
        return np.asarray(x, dtype=float)[..., :2]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 2, d)."""
        H = np.zeros((*np.shape(x)[:-1], 2, np.shape(x)[-1]))
        H[..., 0, 0] = H[..., 1, 1] = 1.0
        return H

    def R(self) -> Array:
        """Noise, shape (2, 2), m^2."""
        return np.eye(2) * self.sigma_m**2

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Both components, shape (n, 2)."""
        return np.ones((*np.shape(x)[:-1], 2), dtype=bool)


@dataclass(frozen=True)
class DepthMeasurement:
    """A pressure depth: ``h(x) = -up`` (depth positive down), linear.

    Attributes:
        sigma_m: standard deviation, m.
    """

    sigma_m: float

    def h(self, x: Array) -> Array:
        """Predicted depth, shape (n, 1), m."""
        return -np.asarray(x, dtype=float)[..., 2:3]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d)."""
        H = np.zeros((*np.shape(x)[:-1], 1, np.shape(x)[-1]))
        H[..., 0, 2] = -1.0
        return H

    def R(self) -> Array:
        """Noise, shape (1, 1), m^2."""
        return np.array([[self.sigma_m**2]])

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Shape (n, 1)."""
        return np.ones((*np.shape(x)[:-1], 1), dtype=bool)


@dataclass(frozen=True)
class SlantRangeMeasurement:
    """The slant range from the vehicle's transducer to a known or broadcast position (a fixed
    beacon, or another vehicle's modem transducer as it states it): ``h(x) = |x + a - p|``,
    with ``a`` the transducer's lever arm in the world frame and ``p`` the other end.

    ``H = (x + a - p)^T / |x + a - p|`` on the position (zero columns for appended state
    components). A broadcast position carries its own error: with its covariance ``C_p`` the
    noise is ``R = sigma^2 + lambda_max(C_p)``, the largest variance of ``C_p`` in any direction,
    which bounds its projection ``u^T C_p u`` on the line of sight ``u`` from above (``R`` cannot
    depend on the state in :class:`nav.ekf.MeasurementModel`; the bound errs on the cautious
    side, and is exact for an isotropic ``C_p``). A horizontal covariance (2, 2) is taken with
    no vertical error. The range is inactive where the ends coincide (no direction).

    Attributes:
        position_world_m: the other end ``p``, shape (3,), m, world.
        sigma_m: the range's standard deviation, m.
        arm_world_m: the vehicle's transducer relative to its reference point, in the world frame
            (the body lever arm rotated by the vehicle's attitude), shape (3,), m.
        position_covariance_m2: covariance of ``p``, shape (3, 3) or (2, 2) (horizontal), m^2,
            or ``None`` for a known position.
    """

    position_world_m: Array
    sigma_m: float
    arm_world_m: Array = field(default_factory=lambda: np.zeros(3))
    position_covariance_m2: Array | None = None

    def _d(self, x: Array) -> tuple[Array, Array]:
        d = np.asarray(x, dtype=float)[..., :3] + self.arm_world_m - self.position_world_m
        return d, np.sqrt(np.sum(d * d, axis=-1))

    def h(self, x: Array) -> Array:
        """Predicted range, shape (n, 1), m."""
        return self._d(x)[1][..., None]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d)."""
        d, r = self._d(x)
        H = np.zeros((*np.shape(x)[:-1], 1, np.shape(x)[-1]))
        safe = np.where(r > 0, r, 1.0)
        H[..., 0, :3] = d / safe[..., None]
        return H

    def R(self) -> Array:
        """Noise, shape (1, 1), m^2 (the class docstring)."""
        var = self.sigma_m**2
        if self.position_covariance_m2 is not None:
            var += float(np.linalg.eigvalsh(np.asarray(self.position_covariance_m2))[-1])
        return np.array([[var]])

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)``."""
        return np.asarray(z, dtype=float) - hx

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Whether the range has a direction, shape (n, 1)."""
        return (self._d(x)[1] > 1e-9)[..., None]


@dataclass(frozen=True)
class BearingMeasurement:
    """The horizontal bearing from the vehicle to a beacon at a known position, clockwise from
    north (the measured relative bearing plus the vehicle's heading): ``h(x) = atan2(b_e - e,
    b_n - n)``.

    ``H = (-(b_n - n), b_e - e) / l^2`` on (east, north), with ``l`` the horizontal distance;
    the residual is wrapped to [-pi, pi). Closer than ``min_horizontal_m`` the bearing carries no
    usable linear information and its Jacobian diverges as 1/l: it is left out (:meth:`active`).

    Attributes:
        beacon_world_m: the beacon, shape (3,) or (2,), m, world.
        sigma_rad: the bearing's standard deviation, rad.
        min_horizontal_m: horizontal distance below which the bearing is not used, m.
    """

    beacon_world_m: Array
    sigma_rad: float
    min_horizontal_m: float = 1.0

    def _d(self, x: Array) -> tuple[Array, Array]:
        d = np.asarray(self.beacon_world_m, dtype=float)[:2] - np.asarray(x, dtype=float)[..., :2]
        return d, d[..., 0] ** 2 + d[..., 1] ** 2

    def h(self, x: Array) -> Array:
        """Predicted bearing, shape (n, 1), rad in [0, 2 pi)."""
        return course_of(self._d(x)[0])[..., None]

    def H(self, x: Array) -> Array:
        """Jacobian, shape (n, 1, d); zero where inactive."""
        d, l2 = self._d(x)
        far = l2 >= self.min_horizontal_m**2
        safe = np.where(far, l2, 1.0)
        H = np.zeros((*np.shape(x)[:-1], 1, np.shape(x)[-1]))
        H[..., 0, 0] = np.where(far, -d[..., 1] / safe, 0.0)
        H[..., 0, 1] = np.where(far, d[..., 0] / safe, 0.0)
        return H

    def R(self) -> Array:
        """Noise, shape (1, 1), rad^2."""
        return np.array([[self.sigma_rad**2]])

    def residual(self, z: Array, hx: Array) -> Array:
        """``z - h(x)`` wrapped to [-pi, pi)."""
        return wrap_pi(np.asarray(z, dtype=float) - hx)

    def active(self, x: Array) -> NDArray[np.bool_]:
        """Whether the beacon is far enough for a bearing, shape (n, 1)."""
        return (self._d(x)[1] >= self.min_horizontal_m**2)[..., None]


@dataclass(frozen=True)
class CurrentAwareMotion:
    """Seed 000's motion model with the water current in the state.

    State ``x = (east, north, up, c_east, c_north)``: position (m, world) and current (m/s, world).
    ``f(x, u) = (e + dt (S sin C + c_e), n + dt (S cos C + c_n), up - dz, c_e, c_n)`` with the
    inputs of :class:`CourseSpeedDepthMotion` (heading as C, speed through water as S), so that
    position fixes make the current observable and the prediction between fixes drifts with it,
    as the vehicle does. ``Q`` is seed 000's eq. 16 term for the inputs plus a random walk of the
    current, ``sigma_current_walk^2 dt`` per component.

    Attributes:
        base: the input noise model (sigmas of heading, speed, depth change).
        sigma_current_walk_m_s_per_sqrt_s: random-walk intensity of the current, (m/s)/sqrt(s).
    """

    base: CourseSpeedDepthMotion
    sigma_current_walk_m_s_per_sqrt_s: float

    dim: ClassVar[int] = 5
    """Length of the state: position and current."""
    current_components: ClassVar[slice | None] = slice(3, 5)
    """Where the current (east, north) is in the state."""

    def f(self, x: Array, u: Array, dt_s: float) -> Array:
        """Predicted state, shape (n, 5)."""
        out = np.array(x, dtype=float, copy=True)
        out[..., :3] += self.base.increment(u, dt_s)
        out[..., :2] += dt_s * x[..., 3:5]
        return out

    def F(self, x: Array, u: Array, dt_s: float) -> Array:
        """State Jacobian, shape (n, 5, 5): identity plus dt on the position-current blocks."""
        F = np.broadcast_to(np.eye(5), (x.shape[0], 5, 5)).copy()
        F[:, 0, 3] = F[:, 1, 4] = dt_s
        return F

    def Q(self, u: Array, dt_s: float) -> Array:
        """Process noise, shape (n, 5, 5)."""
        Q = np.zeros((*u.shape[:-1], 5, 5))
        Q[..., :3, :3] = self.base.Q(u, dt_s)
        q = self.sigma_current_walk_m_s_per_sqrt_s**2 * dt_s
        Q[..., 3, 3] = Q[..., 4, 4] = q
        return Q

    def predict_one(self, x: Array, P: Array, u: Array, dt_s: float) -> tuple[Array, Array]:
        """One prediction of one run in closed form (eq. 17-18): ``F`` is the identity plus
        ``dt`` on the position-current blocks, so ``F P F^T`` is two row and column updates; the
        numbers of the batched EKF's prediction with :meth:`f`, :meth:`F` and :meth:`Q` (tested).

        Args:
            x: state, shape (1, 5).
            P: covariance, shape (1, 5, 5).
            u: input ``(C, S, dz)``, shape (1, 3).
            dt_s: step duration, s.

        Returns:
            ``(x-, P-)``, shapes (1, 5) and (1, 5, 5).
        """
        # x + increment, then + dt * current, in Python floats (the same operations in the same
        # order as on the arrays)
        c, spd, dz = u[0].tolist()
        ie, in_, iu = self.base._increment_floats(c, spd, dz, dt_s)
        e, n, up, ce, cn = x[0].tolist()
        x_new = np.array([[e + ie + dt_s * ce, n + in_ + dt_s * cn, up + iu, ce, cn]])
        P_new = P[0].copy()
        P_new[:2, :] += dt_s * P_new[3:5, :]  # F P
        P_new[:, :2] += dt_s * P_new[:, 3:5]  # (F P) F^T
        q = self.sigma_current_walk_m_s_per_sqrt_s**2 * dt_s
        P_new[3, 3] += q
        P_new[4, 4] += q
        self.base._add_Q_one(P_new, u[0], dt_s)
        return x_new, P_new[None]
