"""Fluid coefficients of the BAUV model derived from first principles (design time).

MuJoCo's ellipsoid fluid model takes five coefficients per geom (``fluidcoef``: blunt drag,
slender drag, angular drag, Kutta lift, Magnus lift); the engine plugin ``bauv.hydro`` takes the
tables of :func:`hydro_numerics`. None of them is fitted: this module derives them from the stated
hull and fins of :mod:`bauv_sim.hull` with textbook laws (ITTC-57 friction, Hoerner's form factors,
Helmbold's lift slope, Theodorsen's lift deficiency, lifting-line induced drag, strip theory of
crossflow drag), and predicts the tow-test drag the model must reproduce (:func:`drag_budget`).
``models/bauv/bauv.xml`` holds the values (``python -m bauv_sim.design.fluid`` writes them there);
``tests/bauv_sim/test_design.py`` checks that it does. Nothing here runs during a simulation.

All quantities are SI (m, m^2, N, N m s^2); the frames are the vehicle's body frame FLU.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import hankel2

from bauv_sim import hull

CROSSFLOW_DRAG_COEFFICIENT = 1.2
"""Drag coefficient of a hull section or a fin plate in flow normal to it (Hoerner 1965,
*Fluid-Dynamic Drag*, ch. 3: elliptic cylinders of fineness 1.5 about 1.2 subcritical; flat
plates normal to the flow 1.17 (disc, square) to 1.2 (aspect ratio 5)): the hull's roll damping
and the fins' normal (crossflow) force, C_N sin^2(a) of the plate's area."""

FIN_SPAN_EFFICIENCY = 1.0
"""Span efficiency e of the fins' lift-induced drag C_L^2 / (pi e A): 1 for the elliptic loading
of an elliptic planform in lifting-line theory (Prandtl 1918; Glauert 1926, *The Elements of
Aerofoil and Airscrew Theory*, ch. 11), the theory Helmbold's lift slope extends; the model's fins
are ellipses. Real fins have 0.8-0.95; ``models/bauv/README.md`` gives the effect of 0.8."""

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
    """A fin represented by a flat ellipsoid of the same area (MuJoCo's added mass) and a thin
    plate of that ellipse (the plugin's lift and drag).

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
      (2 A_f); peduncle 0 (it is the aft body, in the hull's flow; the form factor's pressure drag
      is the whole body's, on the hull's term); its crossflow drag is its strips';
    * the thin fins (caudal, dorsal, lateral): 0 for every term. MuJoCo's drag of a flat
      ellipsoid puts nearly the whole plate in the flow at a few degrees of incidence (its
      projected area is a weighted mean of the ellipsoid's three sections, 3.2 times the caudal
      fin's true shadow at 1 deg and 6.7 times at 5 deg); the plugin applies a thin plate's drag
      instead (:func:`foil_drag_coefficients`);
    * Kutta lift 0: MuJoCo's Kutta lift of a thick ellipsoid has a slope near zero angle of
      chord/thickness times the thin-plate law, and lifts along a plate's span too; the plugin
      ``bauv.hydro`` computes the lift instead (the plates' slopes: :func:`foil_lift_slopes`; the
      hull's: :func:`slender_lift_stations`);
    * angular drag: 0 on the hull and peduncle (their rotational damping is the crossflow of the
      strips the plugin applies: the hull's :func:`crossflow_elements`, the peduncle's
      :func:`segment_crossflow` in its own frame) and on the fins (their panels' normal force
      sees each panel's velocity, rotation included);
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
    out = {
        "hull_fluid": np.array(
            [
                0.5 * cf * (ff - 1.0) * (s_hull + s_ped) / af_h,
                0.5 * cf * s_hull / (amax_h - af_h),
                0.0,
                0.0,
                MAGNUS_LIFT_COEFFICIENT,
            ]
        ),
        "peduncle_fluid": np.array(
            [0.0, 0.5 * cf * s_ped / (amax_p - af_p), 0.0, 0.0, MAGNUS_LIFT_COEFFICIENT]
        ),
    }
    for fin in plate_fins():
        out[fin.geom] = np.zeros(5)
    return out


def foil_drag_coefficients(speed_m_s: float = DESIGN_SPEED_M_S) -> dict[str, NDArray[np.float64]]:
    """The thin-plate drag of every lifting plate, ``(C_D0, k_i, C_N)`` in the order of
    :data:`FOIL_GEOMS` (the model file's ``hydro_foil_drag``), which the plugin applies with the
    plate's ellipse area S and relative velocity u (chord c, span s, normal n components):

    * profile drag ``-1/2 rho S C_D0 |u_t| u_t`` of the in-plane velocity u_t = (u_c, u_s): skin
      friction on both faces times the section's form factor, C_D0 = 2 C_F(Re_c) FF_foil(t/c),
      ITTC-57 at the mean chord's Reynolds number at ``speed_m_s`` and Hoerner's foil form factor
      (the fins' term of :func:`drag_budget`); friction sees the tangential velocity (Hoerner
      1965 ch. 2, inclined plates; the independence principle);
    * lift-induced drag ``1/2 rho S k_i C_L^2 |u|^2`` against the chord-normal velocity, with
      C_L = C_La sin(a) cos(a) the plugin's lift coefficient and k_i = 1 / (pi e A) at the
      effective aspect ratio of the lift slope (lifting-line theory, :data:`FIN_SPAN_EFFICIENCY`);
    * normal (crossflow) force ``-1/2 rho C_N dA |u_n| u_n`` of every panel of the plate with its
      own normal velocity (translation and rotation): C_N sin^2(a) per unit area in uniform flow,
      the plate's drag in flow normal to it at 90 deg, C_N = :data:`CROSSFLOW_DRAG_COEFFICIENT`
      (Hoerner 1965 ch. 3).

    At small incidence this leaves the plate its friction: the caudal fin's drag coefficient on S
    is 0.019 at 1 deg (C_D0 0.0188) and 0.023 at 5 deg, where MuJoCo's projected-area drag of its
    flat ellipsoid gave 0.044 and 0.124; at 20 deg 0.112 against 0.157. The peduncle, a thick aft
    body, has zeros here: its friction is MuJoCo's slender drag, its crossflow drag its strips
    (:func:`peduncle_crossflow_strips`).

    Args:
        speed_m_s: speed at which the friction coefficients are evaluated, m/s.

    Returns:
        Mapping from fluid geom to ``(C_D0, k_i, C_N)``, shape (3,) each.
    """
    nu = hull.SEAWATER_VISCOSITY_PA_S / hull.SEAWATER_DENSITY_KG_M3
    out = {g: np.zeros(3) for g in FOIL_GEOMS}
    for fin in plate_fins():
        c = fin.mean_chord_m
        cf = float(ittc57_friction(speed_m_s * c / nu))
        out[fin.geom] = np.array(
            [
                2.0 * cf * foil_form_factor(fin.thickness_m / c),
                1.0 / (np.pi * FIN_SPAN_EFFICIENCY * fin.aspect_ratio),
                CROSSFLOW_DRAG_COEFFICIENT,
            ]
        )
    return {g: out[g] for g in FOIL_GEOMS}


BODY_GEOMS = ("hull_fluid",)
"""The non-lifting body among the fluid geoms (its potential coupling is applied, with the
separation correction of :func:`slender_lift_stations`)."""

FOIL_GEOMS = (
    "dorsal_fin_fluid",
    "fin_port_fluid",
    "fin_starboard_fluid",
    "peduncle_fluid",
    "caudal_fin_fluid",
)
"""The lifting plates of the vehicle, in the order of the model's ``hydro_foils``."""


def foil_lift_slopes() -> dict[str, float]:
    """Lift-curve slope C_La (per rad) of every lifting plate, in the thin-plate law the plugin
    applies, ``L = 1/2 rho S C_La sin(a) cos(a) |u|^2`` with S the plate's ellipse area.

    Helmbold's slope (:func:`lift_slope_per_rad`) at the effective aspect ratio (fins on the hull:
    doubled, the hull being a reflection plane); the oscillating tail (peduncle, caudal fin) is
    multiplied by Theodorsen's |C(k)| at the design cruise point (:data:`TAIL_DESIGN_FREQUENCY_HZ`,
    :data:`DESIGN_SPEED_M_S`, k = pi f c / U), since the law is quasi-steady. The peduncle, a thick
    aft body, is a plate of its side view (aspect ratio height^2 / area).

    Returns:
        Mapping from fluid geom to C_La, in the order of :data:`FOIL_GEOMS`.
    """
    ps = peduncle_fluid_semi_axes()
    _, amax_p = _ellipsoid_areas(ps)
    slopes = {
        "peduncle_fluid": lift_slope_per_rad((2.0 * ps[2]) ** 2 / amax_p)
        * _tail_lift_factor(2.0 * ps[0])
    }
    for fin in plate_fins():
        cla = lift_slope_per_rad(fin.aspect_ratio)
        if fin.geom == "caudal_fin_fluid":
            cla *= _tail_lift_factor(fin.mean_chord_m)
        slopes[fin.geom] = cla
    return {g: float(slopes[g]) for g in FOIL_GEOMS}


def _tail_lift_factor(chord_m: float) -> float:
    """Theodorsen's |C(k)| of a tail part of the given chord at the design cruise point."""
    k = np.pi * TAIL_DESIGN_FREQUENCY_HZ * chord_m / DESIGN_SPEED_M_S
    return theodorsen_magnitude(k)


CROSSFLOW_LENGTH_FACTOR = 0.75
"""Ratio of the crossflow drag of the finite hull to that of its sections in 2-D flow, eta:
0.74 at length/diameter 5 and 0.82 at 10 for cylinders in normal flow (Wieselsberger's data in
Hoerner 1965, ch. 3, fig. 16); the Allen & Perkins factor for inclined bodies of fineness 5-7 is
0.66-0.70 (NACA Report 1048). The BAUV's body (1.60 m, equivalent diameter 0.27 m) has
fineness 5.9."""

SECTION_DRAG_BY_FINENESS = ((0.5, 1.6), (1.0, 1.2), (2.0, 0.6))
"""2-D drag coefficient of elliptic cylinders against their fineness (length along the flow over
the width across it), subcritical: 1:2 ellipse broadside 1.6, circle 1.2, 2:1 ellipse 0.6
(Delany & Sorensen 1953, NACA TN 3038; Hoerner 1965, ch. 3). Interpolated in log fineness."""


def section_drag_coefficient(fineness: ArrayLike) -> NDArray[np.float64]:
    """2-D crossflow drag coefficient of an elliptic section from :data:`SECTION_DRAG_BY_FINENESS`,
    linear in log2(fineness), held at the end values outside 0.5-2.

    Args:
        fineness: section length along the flow over its width across the flow, any shape.

    Returns:
        C_d, same shape.
    """
    f, c = np.array(SECTION_DRAG_BY_FINENESS).T
    return np.interp(np.log2(np.asarray(fineness, dtype=float)), np.log2(f), c)


N_HULL_STRIPS = 16
"""Strips of the rigid hull in the crossflow model (midpoint rule; the crossflow integral of the
smooth profile is within 1 % of a 400-strip sum)."""


def hull_crossflow_strips(n: int = N_HULL_STRIPS) -> NDArray[np.float64]:
    """Crossflow elements of the rigid hull (nose to tail hinge), by strip theory.

    Each strip of length dx at station x is an elliptic section of half-height h(x) and
    half-width w(x) (:class:`bauv_sim.hull.HullProfile`); in crossflow (v, w) it takes
    ``f_y = -1/2 rho C a_y |c| c_y`` and ``f_z = -1/2 rho C a_z |c| c_z`` with the projected areas
    ``a_y = 2 h dx`` (flow along y sees the height) and ``a_z = 2 w dx``, and per direction
    ``C = eta C_2D - 2 C_blunt``: the 2-D coefficient of the elliptic section for that direction
    (:func:`section_drag_coefficient`: fineness w/h across y, h/w across z) times the finite-length
    factor :data:`CROSSFLOW_LENGTH_FACTOR`, less what MuJoCo's blunt drag of the hull ellipsoid
    already applies to flow across it (its ``rho C_blunt A |v| v`` has no 1/2).

    Args:
        n: number of strips.

    Returns:
        Rows ``(x, y, z, a_y, a_z, C_y, C_z)``, shape (n, 7): station in the hull frame (m),
        projected areas (m^2), coefficients.
    """
    h = hull.HULL
    edges = np.linspace(h.hinge_x_m, h.nose_x_m, n + 1)
    x = 0.5 * (edges[1:] + edges[:-1])
    dx = np.diff(edges)
    s = h.s_of_x(x)
    hh, ww = h.half_height(s), h.half_width(s)
    blunt = 2.0 * float(derived_fluid_coefficients()["hull_fluid"][0])
    out = np.zeros((n, 7))
    out[:, 0] = x
    out[:, 3] = 2.0 * hh * dx
    out[:, 4] = 2.0 * ww * dx
    out[:, 5] = CROSSFLOW_LENGTH_FACTOR * section_drag_coefficient(ww / hh) - blunt
    out[:, 6] = CROSSFLOW_LENGTH_FACTOR * section_drag_coefficient(hh / ww) - blunt
    return out


def crossflow_elements() -> NDArray[np.float64]:
    """All crossflow elements in the hull frame, rows ``(x, y, z, a_y, a_z, C_y, C_z)``, shape
    (k, 7) (the model file's ``hydro_crossflow``): the hull's strips
    (:func:`hull_crossflow_strips`). The peduncle's strips are in its own frame
    (:func:`segment_crossflow`); the fins' normal force is the plugin's plate model, in each fin's
    own frame (:func:`foil_drag_coefficients`)."""
    return hull_crossflow_strips()


N_PEDUNCLE_STRIPS = 10
"""Strips of the peduncle in the crossflow model (midpoint rule, 45 mm each: its side and top
areas within 0.1 % of a fine quadrature of the profile, its damping integral of |x|^3 about the
tail hinge within 0.7 %)."""

SEGMENT_BODIES = ("peduncle",)
"""The body segments that move on their own and carry crossflow strips in their own frames (the
model file's text ``hydro_segments``): the peduncle, caudal segment 1, which the crank-rocker
swings +-15.5 deg about the tail hinge."""


def peduncle_crossflow_strips(n: int = N_PEDUNCLE_STRIPS) -> NDArray[np.float64]:
    """Crossflow elements of the peduncle (tail hinge to caudal-fin hinge), by strip theory in its
    own frame.

    The peduncle is the aft part of the body profile (:class:`bauv_sim.hull.HullProfile`, from
    the tail hinge at ``hinge_x_m`` to the body's end at ``end_x_m``), and it gets the hull's strip
    treatment (:func:`hull_crossflow_strips`) in the frame of its own body, whose origin is the
    tail hinge and whose axes swing with the tail: each strip of length dx at ``x`` (aft of the
    hinge: x < 0) is an elliptic section of half-height h and half-width w of the profile there,
    with projected areas ``a_y = 2 h dx``, ``a_z = 2 w dx`` and per direction
    ``C = eta C_2D - 2 C_blunt``: the 2-D coefficient of the elliptic section by its fineness
    (:func:`section_drag_coefficient`; w/h = 0.65 at the hinge, 0.46 at the end: 1.45 to 1.6
    across y, 0.82 to 0.6 across z), times the body's finite-length factor
    :data:`CROSSFLOW_LENGTH_FACTOR` (the peduncle is the last 0.45 m of the same 1.60 m body of
    fineness 5.9), less MuJoCo's blunt drag of the peduncle's ellipsoid (0: the peduncle's
    MuJoCo drag is its friction alone). The plugin evaluates each strip with the peduncle's own
    velocity relative to the water at the strip, the tail's flapping included: sway (the beat)
    and heave (a pitched or heaving vehicle), ``c = v + omega x r`` in the peduncle's frame.
    The crossflow Reynolds number (section 0.1-0.2 m, 0.1-0.5 m/s) is 1e4-1e5, subcritical as
    the coefficients are.

    Args:
        n: number of strips.

    Returns:
        Rows ``(x, y, z, a_y, a_z, C_y, C_z)``, shape (n, 7): station in the peduncle's body
        frame (m), projected areas (m^2), coefficients.

    References:
        Allen & Perkins 1951 (NACA Report 1048): crossflow drag of a body at incidence by strips;
        Hoerner 1965, *Fluid-Dynamic Drag*, ch. 3; Delany & Sorensen 1953 (NACA TN 3038).
    """
    h = hull.HULL
    edges = np.linspace(h.end_x_m, h.hinge_x_m, n + 1)
    x = 0.5 * (edges[1:] + edges[:-1])
    dx = np.diff(edges)
    s = h.s_of_x(x)
    hh, ww = h.half_height(s), h.half_width(s)
    blunt = 2.0 * float(derived_fluid_coefficients()["peduncle_fluid"][0])
    out = np.zeros((n, 7))
    out[:, 0] = x - h.hinge_x_m
    out[:, 3] = 2.0 * hh * dx
    out[:, 4] = 2.0 * ww * dx
    out[:, 5] = CROSSFLOW_LENGTH_FACTOR * section_drag_coefficient(ww / hh) - blunt
    out[:, 6] = CROSSFLOW_LENGTH_FACTOR * section_drag_coefficient(hh / ww) - blunt
    return out


def segment_crossflow() -> NDArray[np.float64]:
    """The crossflow strips of the segments :data:`SEGMENT_BODIES`, each in its own body's frame
    (the model file's ``hydro_segment_crossflow``): rows ``(segment, x, y, z, a_y, a_z, C_y,
    C_z)``, shape (k, 8), with ``segment`` the index into :data:`SEGMENT_BODIES` and the rest as
    :func:`peduncle_crossflow_strips`."""
    strips = peduncle_crossflow_strips()
    return np.column_stack([np.zeros(len(strips)), strips])


def segment_roll_damping() -> NDArray[np.float64]:
    """Quadratic roll damping K (N m s^2) of each segment of :data:`SEGMENT_BODIES` about its own
    x axis (the model file's ``hydro_segment_roll_damping``): the peduncle's non-circular
    sections, as the hull's (:func:`hull_roll_damping`), from the tail hinge to the body's end."""
    h = hull.HULL
    blunt = 2.0 * float(derived_fluid_coefficients()["peduncle_fluid"][0])
    return np.array([_roll_damping(h.end_x_m, h.hinge_x_m, blunt)])


def slender_lift_stations() -> NDArray[np.float64]:
    """Where the hull's potential (slender-body) lift is shed, and the sectional added mass there.

    Slender-body theory (Munk 1924; Newman 1977, *Marine Hydrodynamics*, sec. 7.?): along the
    body the crossflow builds up sectional momentum ``rho A(x) U c(x)``, with A the 2-D added
    mass per unit density of the section (``pi h^2`` for an elliptic section moving along its
    width, ``pi w^2`` along its height); on a closed body it is returned at the tail (no lift,
    only the Munk moment), but the flow separates on the tapering aft body and the momentum is
    shed: the lift is ``-rho U A(x_s) c(x_s)``, at the station x_s where it is shed. For a body
    whose afterbody tapers from its largest section, the separation is taken at the largest
    section (Allen & Perkins 1951 use the base; the boat-tailed body sheds at its maximum
    section, Hopkins 1951, NACA RM A51C14): x_s is where h (sway) and w (heave) are largest.

    Aft of x_s the potential flow is gone, and with it the afterbody's share of the hull's Munk
    couple (Kirchhoff's moment of the whole body in potential flow): with sectional momentum built
    only from x_s forward, the moment is the forebody's couple plus the lift at x_s. The share is
    that of the strip-theory added mass aft of x_s, ``f = int_aft A dx / int A dx`` (the plugin
    scales the hull's (B22 - B11) u v and (B33 - B11) u w by it).

    Returns:
        ``(x_y, A_y, x_z, A_z, f_y, f_z)``: station (hull frame, m) and sectional added mass per
        density (m^2) for lift across y and across z, and the afterbody shares, shape (6,).
    """
    h = hull.HULL
    x = np.linspace(h.hinge_x_m, h.nose_x_m, 20001)
    s = h.s_of_x(x)
    hh, ww = h.half_height(s), h.half_width(s)
    iy, iz = int(np.argmax(hh)), int(np.argmax(ww))
    fy = float(np.trapezoid(hh[:iy] ** 2, x[:iy]) / np.trapezoid(hh**2, x))
    fz = float(np.trapezoid(ww[:iz] ** 2, x[:iz]) / np.trapezoid(ww**2, x))
    return np.array([x[iy], np.pi * hh[iy] ** 2, x[iz], np.pi * ww[iz] ** 2, fy, fz])


def hull_roll_damping() -> float:
    """Quadratic roll damping of the hull's non-circular sections, K (torque ``-K p |p|``).

    A section rotating about its centre moves the parts outside its inscribed circle through the
    water; strip theory with the 2-D plate coefficient on the flat-plate equivalent of the
    excess gives ``1/2 rho C (h^4 - w^4) / 4`` per unit length (the design's earlier damper term),
    integrated over the rigid hull.

    Returns:
        K, N m s^2.
    """
    h = hull.HULL
    blunt = 2.0 * float(derived_fluid_coefficients()["hull_fluid"][0])
    return _roll_damping(h.hinge_x_m, h.nose_x_m, blunt)


def _roll_damping(x0_m: float, x1_m: float, blunt: float) -> float:
    """``1/2 rho (C - blunt) (h^4 - w^4) / 4`` integrated over the body from x0 to x1 (m), with
    C = :data:`CROSSFLOW_DRAG_COEFFICIENT`, N m s^2."""
    rho = hull.SEAWATER_DENSITY_KG_M3
    h = hull.HULL
    x = np.linspace(x0_m, x1_m, 4001)
    s = h.s_of_x(x)
    hh, ww = h.half_height(s), h.half_width(s)
    c = CROSSFLOW_DRAG_COEFFICIENT - blunt
    return float(np.sum(0.5 * rho * c * 0.25 * (hh**4 - ww**4)) * (x[1] - x[0]))


def added_mass_matrix(
    path: str | None = None, geoms: Sequence[str] | None = None
) -> NDArray[np.float64]:
    """Added mass of the vehicle moving as a rigid body, about the hull origin in the hull frame.

    Every fluid ellipsoid of the vehicle has MuJoCo's added masses and moments of inertia along
    its axes (computed by the compiler from its semi-axes: Tuckerman 1925, exact for ellipsoids,
    the potential-flow values of Lamb 1932 sec. 114-115); each is moved to the hull origin as a
    rigid transformation (:func:`bauv_sim.hydro.rigid_added_mass`) with the tail straight and the
    fins level, and the matrices are summed. Interactions between the parts' flows are neglected.
    The flapping tail's own added inertia about its hinges is the joints' armature.

    Args:
        path: vehicle model file (default ``models/bauv/bauv.xml``); compiled without its plugins.
        geoms: only these fluid geoms (default: all of the vehicle's).

    Returns:
        6 x 6 symmetric matrix, order (surge, sway, heave, roll, pitch, yaw), kg, kg m, kg m^2.
    """
    import mujoco

    from bauv_sim.hydro import fluid_geoms, rigid_added_mass, subtree_bodies, water_properties

    spec = mujoco.MjSpec.from_file(str(path or hull.MODEL_DIR / "bauv.xml"))
    for p in list(spec.plugins):
        spec.delete(p)
    m = spec.compile()
    rho = water_properties(m)[0]
    vm = rho * np.array(m.geom_fluid[:, 6:12])
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    hull_b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "hull")
    bodies = set(subtree_bodies(m, hull_b).tolist())
    R0, o0 = d.xmat[hull_b].reshape(3, 3), d.xpos[hull_b]
    M = np.zeros((6, 6))
    for g in fluid_geoms(m):
        if int(m.geom_bodyid[g]) not in bodies:
            continue
        if geoms is not None and mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) not in geoms:
            continue
        Rg = R0.T @ d.geom_xmat[g].reshape(3, 3)
        rg = R0.T @ (d.geom_xpos[g] - o0)
        M += rigid_added_mass(vm[g, :3], vm[g, 3:], Rg, rg)
    return 0.5 * (M + M.T)


def hydro_numerics() -> dict[str, NDArray[np.float64]]:
    """The hydrodynamic tables the model file carries as ``<custom><numeric>`` elements, which
    the plugin ``bauv.hydro`` (:mod:`bauv_sim.hydro`) reads:

    * ``hydro_added_mass``: :func:`added_mass_matrix`, row-major (36);
    * ``hydro_body_added_mass``: the hull ellipsoid's alone (:data:`BODY_GEOMS`), whose potential
      coupling (Munk moment) the plugin applies; the plates' is replaced by their lift;
    * ``hydro_crossflow``: :func:`crossflow_elements` flattened (7 per element);
    * ``hydro_slender_lift``: :func:`slender_lift_stations`;
    * ``hydro_roll_damping``: :func:`hull_roll_damping`;
    * ``hydro_segment_crossflow``: :func:`segment_crossflow` flattened (8 per strip), the strips
      of the bodies in the text ``hydro_segments`` (:data:`SEGMENT_BODIES`), each in its own frame;
    * ``hydro_segment_roll_damping``: :func:`segment_roll_damping`, one per segment;
    * ``hydro_foil_cla``: :func:`foil_lift_slopes`, in the order of the text ``hydro_foils``;
    * ``hydro_foil_drag``: :func:`foil_drag_coefficients`, 3 per plate in the same order.

    Returns:
        Mapping from numeric name to its data, shape (n,).
    """
    return {
        "hydro_added_mass": added_mass_matrix().ravel(),
        "hydro_body_added_mass": added_mass_matrix(geoms=BODY_GEOMS).ravel(),
        "hydro_crossflow": crossflow_elements().ravel(),
        "hydro_slender_lift": slender_lift_stations(),
        "hydro_roll_damping": np.array([hull_roll_damping()]),
        "hydro_segment_crossflow": segment_crossflow().ravel(),
        "hydro_segment_roll_damping": segment_roll_damping(),
        "hydro_foil_cla": np.array(list(foil_lift_slopes().values())),
        "hydro_foil_drag": np.concatenate(list(foil_drag_coefficients().values())),
    }


def custom_xml(precision: int = 7) -> str:
    """The ``<custom>`` block of ``bauv.xml`` for :func:`hydro_numerics` (``%.{precision}g``)."""
    lines = [
        "  <custom>",
        f'    <text name="hydro_foils" data="{" ".join(FOIL_GEOMS)}"/>',
        f'    <text name="hydro_segments" data="{" ".join(SEGMENT_BODIES)}"/>',
    ]
    for name, data in hydro_numerics().items():
        vals = " ".join(f"{v:.{precision}g}" for v in data)
        lines.append(f'    <numeric name="{name}" data="{vals}"/>')
    lines.append("  </custom>")
    return "\n".join(lines)


def write_model(path: str | None = None) -> list[str]:
    """Write the derived numbers into the vehicle's model file: every fluid geom's ``fluidcoef``
    (:func:`derived_fluid_coefficients`, ``%.5g``) and the ``<custom>`` block (:func:`custom_xml`).

    Args:
        path: model file (default ``models/bauv/bauv.xml``).

    Returns:
        What was rewritten, one line each.
    """
    import re
    from pathlib import Path

    file = Path(path or hull.MODEL_DIR / "bauv.xml")
    text = file.read_text()
    done = []
    for geom, coefs in derived_fluid_coefficients().items():
        value = " ".join("0" if c == 0 else f"{c:.5g}" for c in coefs)
        pattern = rf'(<geom name="{geom}"[^>]*?fluidcoef=")([^"]*)(")'
        text, n = re.subn(
            pattern, lambda mt, v=value: mt.group(1) + v + mt.group(3), text, flags=re.S
        )
        if n != 1:
            raise RuntimeError(f"{file}: no unique fluid geom {geom!r} with fluidcoef")
        done.append(f"{geom}: fluidcoef {value}")
    text, n = re.subn(r"  <custom>.*?</custom>", lambda _: custom_xml(), text, flags=re.S)
    if n != 1:
        raise RuntimeError(f"{file}: no unique <custom> block")
    done.append(f"<custom>: {', '.join(hydro_numerics())}")
    file.write_text(text)
    return done


if __name__ == "__main__":
    for line in write_model():
        print(line)
