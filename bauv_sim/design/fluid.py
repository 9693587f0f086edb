"""Fluid coefficients of the BAUV model derived from first principles (design time).

MuJoCo's ellipsoid fluid model takes five coefficients per geom (``fluidcoef``: blunt drag,
slender drag, angular drag, Kutta lift, Magnus lift) and the model adds a pure angular-drag
ellipsoid (the crossflow damper). None of them is fitted: this module derives them from the stated
hull and fins of :mod:`bauv_sim.hull` with textbook laws (ITTC-57 friction, Hoerner's form factors,
Helmbold's lift slope, Theodorsen's lift deficiency, strip theory of crossflow drag), and predicts
the tow-test drag the model must reproduce (:func:`drag_budget`). ``models/bauv/bauv.xml`` holds
the values; ``tests/bauv_sim/test_design.py`` checks that it does. Nothing here runs during a
simulation.

All quantities are SI (m, m^2, N, N m s^2); the frames are the vehicle's body frame FLU.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import hankel2

from bauv_sim import hull
from bauv_sim.errors import ConfigError

CROSSFLOW_DRAG_COEFFICIENT = 1.2
"""Drag coefficient of a hull section or a fin plate in flow normal to it (Hoerner 1965,
*Fluid-Dynamic Drag*, ch. 3: elliptic cylinders of fineness 1.5 about 1.2 subcritical; plates of
aspect ratio 1-5 about 1.2), used for the rotational (crossflow) damping."""

FIN_OPERATING_DRAG_COEFFICIENT = 0.16
"""Drag coefficient of a low-aspect-ratio fin at its operating angles of attack (10-20 deg),
profile plus induced drag: about 0.1-0.2 (Hoerner 1965 ch. 7; Whicker & Fehlner 1958, DTMB 933,
aspect ratio 1-3 at 15 deg). MuJoCo's blunt-drag coefficient is half of it (its drag has no 1/2)."""

TAIL_DESIGN_FREQUENCY_HZ = 1.2
"""Tail-beat frequency of the design cruise point (1 m/s), Hz: sets the reduced frequency at
which the oscillating tail's lift deficiency is evaluated (:func:`theodorsen_magnitude`)."""

DESIGN_SPEED_M_S = 1.0
"""Cruise speed of seed 000's BAUV, m/s ("optimum cruise speed is around 1 m/s")."""

MAGNUS_LIFT_COEFFICIENT = 0.0
"""No part of the vehicle spins about its own axis; MuJoCo's Magnus term on a yawing hull has no
physical counterpart here, so it is off everywhere."""


def ittc57_friction(reynolds: ArrayLike) -> NDArray[np.float64]:
    """ITTC 1957 model-ship correlation line, C_F = 0.075 / (log10 Re - 2)^2.

    Args:
        reynolds: Reynolds number(s) U L / nu, any shape.

    Returns:
        Skin-friction coefficient on the wetted area, same shape.
    """
    re = np.asarray(reynolds, dtype=float)
    return 0.075 / (np.log10(re) - 2.0) ** 2


def body_form_factor(d_over_l: float) -> float:
    """Form factor of a streamlined body of revolution, 1 + 1.5 (d/l)^1.5 + 7 (d/l)^3
    (Hoerner 1965, ch. 6, eq. 29); multiplies the skin friction to give the total drag."""
    return 1.0 + 1.5 * d_over_l**1.5 + 7.0 * d_over_l**3


def foil_form_factor(t_over_c: float) -> float:
    """Form factor of a foil section, 1 + 2 (t/c) + 60 (t/c)^4 (Hoerner 1965, ch. 6, eq. 24)."""
    return 1.0 + 2.0 * t_over_c + 60.0 * t_over_c**4


def theodorsen_magnitude(reduced_frequency: float) -> float:
    """Magnitude of Theodorsen's function, |C(k)| = |H1(k) / (H1(k) + i H0(k))| with Hankel
    functions of the second kind: the lift of an oscillating foil relative to its quasi-steady
    value (Theodorsen 1935, NACA Report 496). 1 at k = 0, about 0.62 at k = 0.48, 0.5 as k grows.

    Args:
        reduced_frequency: k = pi f c / U (omega times half-chord over speed).

    Returns:
        |C(k)|.
    """
    k = float(reduced_frequency)
    if k <= 0:
        return 1.0
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return float(abs(h1 / (h1 + 1j * h0)))


def lift_slope_per_rad(aspect_ratio: float) -> float:
    """Lift-curve slope of a thin wing, 2 pi A / (2 + sqrt(A^2 + 4)), per rad (Helmbold 1942;
    the USAF DATCOM form at zero sweep); tends to 2 pi for large A and pi A / 2 for small A."""
    a = float(aspect_ratio)
    return 2.0 * np.pi * a / (2.0 + np.sqrt(a * a + 4.0))


@dataclass(frozen=True)
class PlateFin:
    """A fin represented in MuJoCo by a flat ellipsoid of the same area.

    Attributes:
        geom: name of its fluid geom.
        area_m2: planform area, m^2.
        span_m: span, m.
        thickness_m: plate thickness, m.
        aspect_ratio: effective aspect ratio (doubled for a fin whose root is on the hull, which
            acts as a reflection plane).
        semi_axes_m: fluid ellipsoid semi-axes (chord, thickness, span) in the geom frame, m.
    """

    geom: str
    area_m2: float
    span_m: float
    thickness_m: float
    aspect_ratio: float
    semi_axes_m: tuple[float, float, float]

    @property
    def mean_chord_m(self) -> float:
        """Area over span, m."""
        return self.area_m2 / self.span_m


def plate_fins() -> list[PlateFin]:
    """The vehicle's fins as :class:`PlateFin` records, from :mod:`bauv_sim.hull`."""
    out = []
    caudal_area = hull.caudal_fin_area_centroid(hull.TAIL)[0]
    specs = [
        ("caudal_fin_fluid", caudal_area, hull.TAIL.fin_span_m, hull.TAIL.fin_thickness_m, False),
        (
            "fin_port_fluid",
            hull.LATERAL_FIN.area_m2(),
            hull.LATERAL_FIN.span_m,
            hull.LATERAL_FIN.thickness_m,
            True,
        ),
        (
            "fin_starboard_fluid",
            hull.LATERAL_FIN.area_m2(),
            hull.LATERAL_FIN.span_m,
            hull.LATERAL_FIN.thickness_m,
            True,
        ),
        (
            "dorsal_fin_fluid",
            hull.DORSAL_FIN.area_m2(),
            hull.DORSAL_FIN.span_m,
            hull.DORSAL_FIN.thickness_m,
            True,
        ),
    ]
    for name, area, span, thick, on_hull in specs:
        ar = (2.0 if on_hull else 1.0) * span**2 / area
        semi = (area / (np.pi * 0.5 * span), 0.5 * thick, 0.5 * span)
        out.append(PlateFin(name, area, span, thick, ar, semi))
    return out


def hull_fluid_semi_axes() -> tuple[float, float, float]:
    """Semi-axes (x, y, z) of the hull's fluid ellipsoid: half the rigid hull's length, half its
    largest width and height, m."""
    h = hull.HULL
    return (0.5 * (h.nose_x_m - h.hinge_x_m), 0.5 * h.max_width_m, 0.5 * h.max_height_m)


def peduncle_fluid_semi_axes() -> tuple[float, float, float]:
    """Semi-axes (x, y, z) of the peduncle's fluid ellipsoid: half its length, the half-width and
    half-height of its mid section, m."""
    h = hull.HULL
    s_mid = 0.5 * (h.s_hinge + 1.0)
    return (
        0.5 * (h.hinge_x_m - h.end_x_m),
        float(h.half_width(s_mid)),
        float(h.half_height(s_mid)),
    )


def _ellipsoid_areas(semi: Sequence[float]) -> tuple[float, float]:
    """(frontal area along x, largest cross-section) of an ellipsoid, m^2 (MuJoCo's A_proj for
    flow along x and A_max)."""
    _, b, c = semi
    d = sorted(semi)
    return float(np.pi * b * c), float(np.pi * d[2] * d[1])


@dataclass(frozen=True)
class DragBudget:
    """Drag of the towed vehicle (tail straight, fins level) predicted from first principles.

    Attributes:
        speed_m_s: towing speed, m/s.
        frontal_area_m2: reference area (largest body cross-section), m^2.
        body_n: hull and peduncle, friction times Hoerner's form factor, N.
        fins_n: fins, friction times the foil form factor, N.
        cd: total drag coefficient on the frontal area.
    """

    speed_m_s: float
    frontal_area_m2: float
    body_n: float
    fins_n: float

    @property
    def total_n(self) -> float:
        """Total drag, N."""
        return self.body_n + self.fins_n

    @property
    def cd(self) -> float:
        """Drag coefficient D / (rho U^2 A / 2) on the frontal area."""
        rho = hull.SEAWATER_DENSITY_KG_M3
        return self.total_n / (0.5 * rho * self.speed_m_s**2 * self.frontal_area_m2)


def _wetted_areas() -> tuple[float, float]:
    h = hull.HULL
    sh = h.s_hinge
    cap = float(h.section_area(sh))
    end = float(h.section_area(1.0))
    return (float(hull.hull_mesh(h).area) - cap, float(hull.peduncle_mesh(h).area) - cap - end)


def drag_budget(speed_m_s: float = 1.0) -> DragBudget:
    """Tow-test drag predicted without MuJoCo (the calibration target of the tow test).

    Body: D = 1/2 rho U^2 C_F(Re_L) FF S_wet with L the body length, FF Hoerner's form factor of a
    body of revolution of the same fineness (equivalent diameter sqrt(H W)). Fins:
    D = 1/2 rho U^2 C_F(Re_c) FF_foil 2 A with c the mean chord.

    Args:
        speed_m_s: towing speed, m/s.

    Returns:
        The :class:`DragBudget`.
    """
    h = hull.HULL
    rho = hull.SEAWATER_DENSITY_KG_M3
    nu = hull.SEAWATER_VISCOSITY_PA_S / rho
    s_hull, s_ped = _wetted_areas()
    d_eq = np.sqrt(h.max_height_m * h.max_width_m)
    q = 0.5 * rho * speed_m_s**2
    cf_body = float(ittc57_friction(speed_m_s * h.body_length_m / nu))
    body = q * cf_body * body_form_factor(d_eq / h.body_length_m) * (s_hull + s_ped)
    fins = 0.0
    for fin in plate_fins():
        c = fin.mean_chord_m
        cf = float(ittc57_friction(speed_m_s * c / nu))
        fins += q * cf * foil_form_factor(fin.thickness_m / c) * 2.0 * fin.area_m2
    return DragBudget(speed_m_s, h.frontal_area_m2(), body, fins)


def derived_fluid_coefficients(speed_m_s: float = 1.0) -> dict[str, NDArray[np.float64]]:
    """``fluidcoef`` of every fluid geom, derived from the geometry (the values in ``bauv.xml``).

    MuJoCo's ellipsoid model (``engine_passive.c``): drag = rho |v| v (C_blunt A_proj +
    C_slender (A_max - A_proj)), Kutta lift = C_K rho A U^2 sin(a) cos(a) for a thin plate, angular
    drag per axis rho C_ang I_i w^2. Matching term by term at the cruise speed:

    * slender drag = skin friction: C_slender (A_max - A_f) = C_F FF S_wet / 2 on each part;
    * blunt drag: hull = the pressure part of Hoerner's body form factor, C_F (FF - 1) S_wet /
      (2 A_f); peduncle 0 (it is the aft body, in the hull's flow); fins = half the operating drag
      coefficient :data:`FIN_OPERATING_DRAG_COEFFICIENT` (the slender term then makes up the
      friction the edge-on blunt term leaves);
    * Kutta lift = half the lift slope, C_K = C_La / 2, with Helmbold's slope at the effective
      aspect ratio (hull: the mean of its side and top views; fins on the hull: doubled); the
      oscillating tail (peduncle, caudal fin) is multiplied by Theodorsen's |C(k)| at the design
      cruise point (:data:`TAIL_DESIGN_FREQUENCY_HZ`, :data:`DESIGN_SPEED_M_S`, k = pi f c / U),
      since MuJoCo's model is quasi-steady;
    * angular drag: 0 on the hull and peduncle (their rotational damping is the separate crossflow
      damper, :func:`crossflow_damping_constants`); on the fins C_dc / (2 pi), the value that
      reproduces strip-theory crossflow damping for an ellipse;
    * Magnus lift 0 (:data:`MAGNUS_LIFT_COEFFICIENT`).

    Args:
        speed_m_s: speed at which friction coefficients are evaluated, m/s.

    Returns:
        Mapping from fluid-geom name to its five coefficients.
    """
    h = hull.HULL
    nu = hull.SEAWATER_VISCOSITY_PA_S / hull.SEAWATER_DENSITY_KG_M3
    s_hull, s_ped = _wetted_areas()
    cf = float(ittc57_friction(speed_m_s * h.body_length_m / nu))
    ff = body_form_factor(np.sqrt(h.max_height_m * h.max_width_m) / h.body_length_m)
    hs = hull_fluid_semi_axes()
    af_h, amax_h = _ellipsoid_areas(hs)
    ps = peduncle_fluid_semi_axes()
    af_p, amax_p = _ellipsoid_areas(ps)
    ar_side = h.max_height_m**2 / amax_h
    ar_top = h.max_width_m**2 / (np.pi * hs[0] * hs[1])
    ar_ped = (2.0 * ps[2]) ** 2 / amax_p
    c_ang_fin = CROSSFLOW_DRAG_COEFFICIENT / (2.0 * np.pi)
    out = {
        "hull_fluid": np.array(
            [
                0.5 * cf * (ff - 1.0) * (s_hull + s_ped) / af_h,
                0.5 * cf * s_hull / (amax_h - af_h),
                0.0,
                0.5 * lift_slope_per_rad(0.5 * (ar_side + ar_top)),
                MAGNUS_LIFT_COEFFICIENT,
            ]
        ),
        "peduncle_fluid": np.array(
            [
                0.0,
                0.5 * cf * s_ped / (amax_p - af_p),
                0.0,
                0.5 * lift_slope_per_rad(ar_ped) * _tail_lift_factor(2.0 * ps[0]),
                MAGNUS_LIFT_COEFFICIENT,
            ]
        ),
    }
    cb_fin = 0.5 * FIN_OPERATING_DRAG_COEFFICIENT
    for fin in plate_fins():
        c = fin.mean_chord_m
        cf_fin = float(ittc57_friction(speed_m_s * c / nu))
        friction = cf_fin * foil_form_factor(fin.thickness_m / c) * fin.area_m2
        a_edge = np.pi * fin.semi_axes_m[1] * fin.semi_axes_m[2]
        a_plate = np.pi * fin.semi_axes_m[0] * fin.semi_axes_m[2]
        lift = 0.5 * lift_slope_per_rad(fin.aspect_ratio)
        if fin.geom == "caudal_fin_fluid":
            lift *= _tail_lift_factor(c)
        out[fin.geom] = np.array(
            [
                cb_fin,
                max(0.0, (friction - cb_fin * a_edge) / (a_plate - a_edge)),
                c_ang_fin,
                lift,
                MAGNUS_LIFT_COEFFICIENT,
            ]
        )
    return out


def _tail_lift_factor(chord_m: float) -> float:
    """Theodorsen's |C(k)| of a tail part of the given chord at the design cruise point."""
    k = np.pi * TAIL_DESIGN_FREQUENCY_HZ * chord_m / DESIGN_SPEED_M_S
    return theodorsen_magnitude(k)


def crossflow_damping_constants(cg_hull_m: ArrayLike) -> NDArray[np.float64]:
    """Quadratic rotational damping of the hull and its fixed fins from strip theory.

    MuJoCo's blunt-drag coefficient must be small for the hull (axial drag) and for the fins
    (flapping at moderate angles of attack), so MuJoCo under-predicts the drag of flow *normal* to
    hull sides and fin plates, which is what damps rotations. Strip theory with
    :data:`CROSSFLOW_DRAG_COEFFICIENT` C_dc gives, about axes through the CG,
    K = sum over strips of 1/2 rho dC_dc h |r|^3 dr, with dC_dc = C_dc - 2 C_blunt(MuJoCo) (only
    the part MuJoCo misses):

    * yaw: hull strips of height 2 h(x) at lever x - x_cg, and the dorsal fin (lumped);
    * pitch: hull strips of width 2 w(x), and the lateral fins (lumped);
    * roll: the parts of each hull section beyond its inscribed circle (1/4 (h^4 - w^4) per
      unit length), the dorsal fin, and the lateral fins.

    The tail (peduncle, caudal fin) is left out: while it flaps, its crossflow is what the fluid
    model's lift and drag of those geoms describe.

    Args:
        cg_hull_m: centre of gravity in the hull frame, shape (3,), m.

    Returns:
        ``(K_roll, K_pitch, K_yaw)``, shape (3,), N m s^2 (torque = -K w |w| about each axis).
    """
    rho = hull.SEAWATER_DENSITY_KG_M3
    cg = np.asarray(cg_hull_m, dtype=float)
    coefs = derived_fluid_coefficients()
    h = hull.HULL
    x = np.linspace(h.hinge_x_m, h.nose_x_m, 4001)
    dx = x[1] - x[0]
    s = h.s_of_x(x)
    hh, ww = h.half_height(s), h.half_width(s)
    dc_hull = CROSSFLOW_DRAG_COEFFICIENT - 2.0 * coefs["hull_fluid"][0]
    r = np.abs(x - cg[0])
    k_yaw = float(np.sum(0.5 * rho * dc_hull * 2.0 * hh * r**3) * dx)
    k_pitch = float(np.sum(0.5 * rho * dc_hull * 2.0 * ww * r**3) * dx)
    k_roll = float(np.sum(0.5 * rho * dc_hull * 0.25 * (hh**4 - ww**4)) * dx)
    # fins: strips along the span with the local chord
    dc_fin = CROSSFLOW_DRAG_COEFFICIENT - FIN_OPERATING_DRAG_COEFFICIENT
    rr, le, te = hull.DORSAL_FIN.edges(401)
    chord = le - te
    dr = rr[1] - rr[0]
    z = hull.DORSAL_FIN_ROOT_M[2] + rr - cg[2]
    k_roll += float(np.sum(0.5 * rho * dc_fin * chord * np.abs(z) ** 3) * dr)
    # dorsal fin in yaw, lumped at its area centroid (it is compact compared with its lever)
    xd = hull.DORSAL_FIN_ROOT_M[0] + float(hull.DORSAL_FIN.centroid_m()[0]) - cg[0]
    k_yaw += 0.5 * rho * dc_fin * hull.DORSAL_FIN.area_m2() * abs(xd) ** 3
    rr, le, te = hull.LATERAL_FIN.edges(401)
    chord = le - te
    dr = rr[1] - rr[0]
    y = hull.LATERAL_FIN_PIVOT_M[1] + rr
    k_roll += 2.0 * float(np.sum(0.5 * rho * dc_fin * chord * np.abs(y) ** 3) * dr)
    area = hull.LATERAL_FIN.area_m2()
    xl = (
        hull.LATERAL_FIN_PIVOT_M[0]
        + float(hull.LATERAL_FIN.centroid_m()[0])
        + (hull.LATERAL_FIN_AXIS_FRAC * hull.LATERAL_FIN.root_chord_m)
        - cg[0]
    )
    k_pitch += 2.0 * 0.5 * rho * dc_fin * area * abs(xl) ** 3
    return np.array([k_roll, k_pitch, k_yaw])


def damper_semi_axes(k_rpy: ArrayLike, rho: float = 1025.0) -> NDArray[np.float64]:
    """Semi-axes of a pure angular-drag ellipsoid (``fluidcoef="0 0 1 0 0"``) that reproduces given
    damping constants about its x, y, z axes.

    MuJoCo's angular drag about axis i is rho C_ang I_i w_i |w| with
    I_i = 8/15 pi d_i max(d_j, d_k)^4. For K_yaw > K_pitch > K_roll and d_x largest:
    d_y / d_z = K_pitch / K_yaw, d_x / d_z = (K_yaw / K_roll)^(1/3), and K_roll fixes the scale.

    Args:
        k_rpy: ``(K_roll, K_pitch, K_yaw)``, N m s^2, with K_yaw >= K_pitch and K_yaw > K_roll.
        rho: water density, kg/m^3.

    Returns:
        ``(d_x, d_y, d_z)``, m.
    """
    kr, kp, ky = (float(v) for v in k_rpy)
    if not (ky >= kp > 0 and ky > kr > 0):
        raise ConfigError(
            f"damping constants {k_rpy}: need K_yaw >= K_pitch > 0 and K_yaw > K_roll > 0"
        )
    c = 8.0 / 15.0 * np.pi
    ratio_x = (ky / kr) ** (1.0 / 3.0)
    dz = (kr / (rho * c * ratio_x)) ** 0.2
    dx, dy = ratio_x * dz, dz * kp / ky
    if not dx >= dz >= dy:
        raise ConfigError(f"damping constants {k_rpy}: no ellipsoid with d_x >= d_z >= d_y fits")
    return np.array([dx, dy, dz])
