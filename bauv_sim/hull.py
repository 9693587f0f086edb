"""The BAUV's outer shape: a stated profile, the meshes generated from it, and its hydrostatics.

The body is a laterally compressed, fish-like solid of elliptical cross-sections. Its side-view
half-height and top-view half-width follow one power law along the body axis (a rounded nose,
the thickest section at 35.7 % of the body length, a nearly straight taper aft), blended into a
finite section at the caudal peduncle where the caudal fin is hinged. The body is cut at the tail
hinge plane into the rigid **hull** (modules 1-4 and the drive of module 5) and the **peduncle**
(segment 1 of the two-segment caudal fin); the **caudal fin** (segment 2), the **lateral fins**
and a fixed **dorsal fin** are thin plates.

Everything here is geometry in the **body frame** (FLU: x forward, y port, z up; metres), with
the body axis on y = 0, z = 0. :func:`write_assets` writes the meshes used by
``models/bauv/bauv.xml`` and :func:`main` prints the numbers the model file quotes (volumes,
centres of buoyancy, areas); ``tests/bauv_sim/test_hull.py`` checks that they agree.
"""

from __future__ import annotations

import argparse
import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bauv_sim import PROJECT_ROOT
from bauv_sim.errors import GeometryError

if TYPE_CHECKING:
    import trimesh

# trimesh and scipy.integrate are imported by the functions that build meshes or integrate: a
# mission imports this module for MODEL_DIR only, and the two took 1.7 s of its start-up.

MODEL_DIR: Path = PROJECT_ROOT / "models" / "bauv"
"""Folder of the vehicle model (``bauv.xml``, ``scene.xml``, ``assets/``)."""

SEAWATER_DENSITY_KG_M3 = 1025.0
"""Density of sea water, kg/m^3 (the customary engineering value for about 10-15 degC and
35 psu; the UNESCO 1981 equation of state gives 1025.9-1026.9 kg/m^3 there)."""

SEAWATER_VISCOSITY_PA_S = 1.08e-3
"""Dynamic viscosity of sea water at 20 degC, 35 psu, Pa s (ITTC 2011, *Fresh water and seawater
properties*, procedure 7.5-02-01-03)."""

GRAVITY_M_S2 = 9.81
"""Standard gravity used by the model (MuJoCo ``option gravity``), m/s^2."""


@dataclass(frozen=True)
class HullProfile:
    """The stated body profile.

    With ``s`` the fraction of the body length from the nose, the normalised thickness law is

        g(s) = (s / s_m)^alpha * ((1 - s) / (1 - s_m))^beta,   s_m = alpha / (alpha + beta)

    (1 at s = s_m, a round nose for alpha = 1/2, a nearly conical taper for beta close to 1),
    blended into a finite peduncle section by ``sqrt(g^2 + (e s^8)^2)`` with ``e`` the end
    section's size over the largest. Half-height and half-width are ``max/2`` times this law with
    their own ``e``; cross-sections are ellipses.

    Attributes:
        nose_x_m: body-frame x of the nose tip, m.
        body_length_m: nose tip to the caudal-fin hinge (end of the peduncle), m.
        hinge_x_m: body-frame x of the tail hinge, where the rigid hull ends and the peduncle
            (caudal segment 1) begins, m.
        max_height_m: largest height (side view), m.
        max_width_m: largest width (top view), m; smaller than the height: laterally compressed.
        end_half_height_m: half-height of the peduncle's end section, m.
        end_half_width_m: half-width of the peduncle's end section, m.
        alpha: nose exponent.
        beta: tail exponent.
    """

    nose_x_m: float = 0.80
    body_length_m: float = 1.60
    hinge_x_m: float = -0.35
    max_height_m: float = 0.34
    max_width_m: float = 0.22
    end_half_height_m: float = 0.035
    end_half_width_m: float = 0.016
    alpha: float = 0.5
    beta: float = 0.9

    @property
    def end_x_m(self) -> float:
        """Body-frame x of the end of the peduncle (the caudal-fin hinge at zero tail angle), m."""
        return self.nose_x_m - self.body_length_m

    @property
    def s_max(self) -> float:
        """Fraction of the length from the nose of the thickest section."""
        return self.alpha / (self.alpha + self.beta)

    @property
    def s_hinge(self) -> float:
        """Fraction of the length from the nose of the tail hinge."""
        return float(self.s_of_x(self.hinge_x_m))

    def s_of_x(self, x_m: ArrayLike) -> NDArray[np.float64]:
        """Fraction of the body length from the nose at body-frame ``x_m`` (m); same shape."""
        return (self.nose_x_m - np.asarray(x_m, dtype=float)) / self.body_length_m

    def x_of_s(self, s: ArrayLike) -> NDArray[np.float64]:
        """Body-frame x (m) at the fraction ``s`` of the length from the nose; same shape."""
        return self.nose_x_m - np.asarray(s, dtype=float) * self.body_length_m

    def thickness_law(self, s: ArrayLike, end_frac: float) -> NDArray[np.float64]:
        """The normalised law g blended into an end section of relative size ``end_frac``."""
        ss = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
        sm = self.s_max
        g = (ss / sm) ** self.alpha * ((1.0 - ss) / (1.0 - sm)) ** self.beta
        return np.sqrt(g**2 + (end_frac * ss**8) ** 2)

    def half_height(self, s: ArrayLike) -> NDArray[np.float64]:
        """Half-height of the cross-section at fraction ``s`` from the nose, m; same shape."""
        e = 2.0 * self.end_half_height_m / self.max_height_m
        return 0.5 * self.max_height_m * self.thickness_law(s, e)

    def half_width(self, s: ArrayLike) -> NDArray[np.float64]:
        """Half-width of the cross-section at fraction ``s`` from the nose, m; same shape."""
        e = 2.0 * self.end_half_width_m / self.max_width_m
        return 0.5 * self.max_width_m * self.thickness_law(s, e)

    def section_area(self, s: ArrayLike) -> NDArray[np.float64]:
        """Area of the elliptical cross-section at fraction ``s`` from the nose, m^2."""
        return np.pi * self.half_height(s) * self.half_width(s)

    def frontal_area_m2(self) -> float:
        """Largest cross-section (the reference area of the drag coefficient), m^2."""
        s = np.linspace(0.0, 1.0, 20001)
        return float(np.max(self.section_area(s)))

    def volume_m3(self, s0: float = 0.0, s1: float | None = None) -> float:
        """Volume between two stations by quadrature of the section areas (no mesh), m^3.

        Args:
            s0: first station (fraction of the length from the nose).
            s1: last station; the tail hinge by default, so that the result is the rigid hull's.
        """
        from scipy import integrate

        s1 = self.s_hinge if s1 is None else s1
        v, _ = integrate.quad(lambda s: float(self.section_area(s)), s0, s1, limit=200)
        return v * self.body_length_m

    def centroid_x_m(self, s0: float = 0.0, s1: float | None = None) -> float:
        """Body-frame x of the volume centroid between two stations (default: the rigid hull), m.

        The sections are symmetric about y = 0 and z = 0, so the centroid lies on the body axis.
        """
        from scipy import integrate

        s1 = self.s_hinge if s1 is None else s1
        m1, _ = integrate.quad(
            lambda s: float(self.section_area(s) * self.x_of_s(s)), s0, s1, limit=200
        )
        return m1 * self.body_length_m / self.volume_m3(s0, s1)


# --------------------------------------------------------------------------------------------
# Appendages


@dataclass(frozen=True)
class TailGeometry:
    """The caudal fin (segment 2 of the caudal-fin module; segment 1, the peduncle, is the aft part
    of the body profile).

    Attributes:
        fin_root_chord_m: chord of the caudal fin at its root (on the fin hinge), m.
        fin_span_m: tip-to-tip height of the caudal fin, m.
        fin_sweep_m: how far aft of the root trailing edge the tips reach (lunate shape), m.
        fin_thickness_m: thickness of the fin plate, m.
    """

    fin_root_chord_m: float = 0.12
    fin_span_m: float = 0.40
    fin_sweep_m: float = 0.22
    fin_thickness_m: float = 0.012


def _outward(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Check that a mesh built with consistent winding is closed; make its normals point out."""
    if not (mesh.is_watertight and mesh.is_winding_consistent):
        raise GeometryError("generated mesh is not a closed, consistently wound surface")
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _ellipse_ring(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    ang = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.cos(ang), np.sin(ang)


def _loft(
    xs: NDArray[np.float64],
    hy: NDArray[np.float64],
    hz: NDArray[np.float64],
    n_around: int,
    apex_front: bool,
) -> trimesh.Trimesh:
    """Closed mesh through elliptical rings (x, half-width hy, half-height hz).

    The first ring is replaced by an apex vertex when ``apex_front``; otherwise it is capped with a
    flat face, as the last ring always is.
    """
    c, s = _ellipse_ring(n_around)
    verts: list[NDArray[np.float64]] = []
    faces: list[list[int]] = []
    rings: list[int] = []
    start = 0
    if apex_front:
        verts.append(np.array([[xs[0], 0.0, 0.0]]))
        start = 1
    for k in range(start, xs.size):
        ring = np.column_stack([np.full(n_around, xs[k]), hy[k] * c, hz[k] * s])
        rings.append(sum(v.shape[0] for v in verts))
        verts.append(ring)
    V = np.vstack(verts)
    if apex_front:
        r0 = rings[0]
        for j in range(n_around):
            faces.append([0, r0 + (j + 1) % n_around, r0 + j])
    else:
        centre = V.shape[0]
        V = np.vstack([V, [[xs[0], 0.0, 0.0]]])
        r0 = rings[0]
        for j in range(n_around):
            faces.append([centre, r0 + (j + 1) % n_around, r0 + j])
    for a, b in itertools.pairwise(rings):
        for j in range(n_around):
            j1 = (j + 1) % n_around
            faces.append([a + j, a + j1, b + j1])
            faces.append([a + j, b + j1, b + j])
    centre = V.shape[0]
    V = np.vstack([V, [[xs[-1], 0.0, 0.0]]])
    rl = rings[-1]
    for j in range(n_around):
        faces.append([centre, rl + j, rl + (j + 1) % n_around])
    import trimesh

    return _outward(trimesh.Trimesh(vertices=V, faces=np.asarray(faces), process=True))


def _stations(s0: float, s1: float, n: int, nose: bool) -> NDArray[np.float64]:
    u = np.linspace(0.0, 1.0, n)
    if nose:  # cluster stations at the round nose: half cosine, half uniform spacing
        u = 0.5 * (1.0 - np.cos(0.5 * np.pi * u)) + 0.5 * u
    return s0 + (s1 - s0) * u


def hull_mesh(profile: HullProfile, n_stations: int = 56, n_around: int = 36) -> trimesh.Trimesh:
    """Watertight surface of the rigid hull: the body from the nose to the tail-hinge plane.

    Args:
        profile: the body profile.
        n_stations: number of cross-sections including the nose apex.
        n_around: vertices per cross-section.

    Returns:
        The mesh in the body frame, m.
    """
    s = _stations(0.0, profile.s_hinge, n_stations, nose=True)
    return _loft(
        profile.x_of_s(s), profile.half_width(s), profile.half_height(s), n_around, apex_front=True
    )


def peduncle_mesh(
    profile: HullProfile, n_stations: int = 16, n_around: int = 36
) -> trimesh.Trimesh:
    """The peduncle (caudal segment 1): the body from the tail-hinge plane to its end.

    Returns:
        The mesh in the peduncle frame: the body frame shifted so that the tail hinge is the
        origin (x forward at zero tail angle), m.
    """
    s = _stations(profile.s_hinge, 1.0, n_stations, nose=False)
    xs = profile.x_of_s(s) - profile.hinge_x_m
    return _loft(xs, profile.half_width(s), profile.half_height(s), n_around, apex_front=False)


def _strip_plate(
    r: NDArray[np.float64], x_le: NDArray[np.float64], x_te: NDArray[np.float64], thickness_m: float
) -> trimesh.Trimesh:
    """Closed slab between a leading and a trailing edge given at span stations.

    The plate lies in the (x, r) plane with its thickness along the third axis t; the result has
    columns (x, r, t).
    """
    n = r.size
    h = 0.5 * thickness_m
    V = np.empty((4 * n, 3))
    V[0::4] = np.column_stack([x_le, r, np.full(n, h)])  # leading edge, +t side
    V[1::4] = np.column_stack([x_te, r, np.full(n, h)])  # trailing edge, +t side
    V[2::4] = np.column_stack([x_le, r, np.full(n, -h)])  # leading edge, -t side
    V[3::4] = np.column_stack([x_te, r, np.full(n, -h)])  # trailing edge, -t side
    F = []
    for i in range(n - 1):
        a, b = 4 * i, 4 * (i + 1)
        F += [[a, a + 1, b + 1], [a, b + 1, b]]  # +t face
        F += [[a + 2, b + 3, a + 3], [a + 2, b + 2, b + 3]]  # -t face
        F += [[a, b, b + 2], [a, b + 2, a + 2]]  # leading-edge wall
        F += [[a + 1, a + 3, b + 3], [a + 1, b + 3, b + 1]]  # trailing-edge wall
    a = 4 * (n - 1)
    F += [[0, 2, 3], [0, 3, 1], [a, a + 3, a + 2], [a, a + 1, a + 3]]  # end caps
    import trimesh

    return _outward(trimesh.Trimesh(vertices=V, faces=np.asarray(F), process=True))


def _tip_taper(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Chord factor that rounds a fin tip: 1 inside, falling to 2 % at |u| = 1."""
    return np.maximum(np.sqrt(np.clip(1.0 - np.abs(u) ** 6, 0.0, 1.0)), 0.02)


def caudal_fin_edges(tail: TailGeometry, n: int = 41) -> tuple[NDArray[np.float64], ...]:
    """Lunate caudal-fin edges in the fin frame (x forward, origin on the fin hinge, z up).

    The leading edge sweeps back from the root towards the tips; the trailing edge is a crescent
    whose centre lies ``fin_root_chord_m`` aft of the hinge and whose tips reach ``fin_sweep_m``
    further aft; the tips are rounded by a chord taper.

    Args:
        tail: the tail geometry.
        n: number of span stations.

    Returns:
        ``(z, x_le, x_te)``, each shape (n,), m.
    """
    half = 0.5 * tail.fin_span_m
    z = np.linspace(-half, half, n)
    u = z / half
    x_le = -0.55 * tail.fin_sweep_m * np.abs(u) ** 1.5
    x_te = -tail.fin_root_chord_m - tail.fin_sweep_m * u**2
    mid, taper = 0.5 * (x_le + x_te), _tip_taper(u)
    return z, mid + (x_le - mid) * taper, mid + (x_te - mid) * taper


def _edges_area_centroid(
    r: NDArray[np.float64], x_le: NDArray[np.float64], x_te: NDArray[np.float64]
) -> tuple[float, NDArray[np.float64]]:
    from scipy import integrate

    chord = x_le - x_te
    area = float(integrate.trapezoid(chord, r))
    cx = float(integrate.trapezoid(chord * 0.5 * (x_le + x_te), r)) / area
    cr = float(integrate.trapezoid(chord * r, r)) / area
    return area, np.array([cx, cr])


def _to_vertical(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Map plate columns (x, r, t) to (x, t, r): a vertical plate spanning z, thickness along y."""
    rot = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float)
    mesh.apply_transform(rot)  # a reflection: turns the faces inside out
    return _outward(mesh)


@dataclass(frozen=True)
class FinPlanform:
    """A fin planform with straight edges and a rounded tip (lateral or dorsal fin).

    Attributes:
        root_chord_m: chord at the root, m.
        tip_chord_m: chord where the tip rounding starts, m.
        span_m: root to tip, m.
        sweep_m: aft displacement of the leading edge at the tip, m.
        thickness_m: plate thickness, m.
    """

    root_chord_m: float
    tip_chord_m: float
    span_m: float
    sweep_m: float
    thickness_m: float

    def edges(self, n: int = 25) -> tuple[NDArray[np.float64], ...]:
        """``(r, x_le, x_te)`` at n span stations, m; root leading edge at (0, 0)."""
        r = np.linspace(0.0, self.span_m, n)
        u = r / self.span_m
        x_le = -self.sweep_m * u
        chord = self.root_chord_m + (self.tip_chord_m - self.root_chord_m) * u
        x_te = x_le - chord
        mid, taper = 0.5 * (x_le + x_te), _tip_taper(u)
        return r, mid + (x_le - mid) * taper, mid + (x_te - mid) * taper

    def area_m2(self) -> float:
        """Planform area, m^2."""
        return _edges_area_centroid(*self.edges(801))[0]

    def centroid_m(self) -> NDArray[np.float64]:
        """Area centroid (x, r) in the planform frame, m."""
        return _edges_area_centroid(*self.edges(801))[1]


LATERAL_FIN = FinPlanform(
    root_chord_m=0.15, tip_chord_m=0.08, span_m=0.20, sweep_m=0.05, thickness_m=0.012
)
"""Lateral fin planform (both fins): span chosen with the dorsal fin for passive roll damping
(README.md, "Roll")."""

DORSAL_FIN = FinPlanform(
    root_chord_m=0.30, tip_chord_m=0.08, span_m=0.18, sweep_m=0.20, thickness_m=0.010
)
"""Dorsal fin planform (fixed to the hull)."""

LATERAL_FIN_PIVOT_M = (0.20, 0.105, -0.04)
"""Body-frame position of the port lateral fin's pitch axis at its root (starboard: y mirrored),
m: module 3 (x 0.32..0.10), just below the axis, root 2 mm inside the hull surface."""

DORSAL_FIN_ROOT_M = (0.05, 0.0, 0.15)
"""Body-frame position of the dorsal fin's root leading edge, m (embedded 1-14 mm in the hull
top, which falls from 0.164 to 0.131 m along the root chord)."""

LATERAL_FIN_AXIS_FRAC = 0.3
"""The lateral fins' pitch axis runs through 30 % of the root chord from the leading edge (near
the quarter chord, so that the hydrodynamic hinge moment is small)."""


def lateral_fin_mesh(fin: FinPlanform = LATERAL_FIN, side: int = 1) -> trimesh.Trimesh:
    """Lateral fin plate in its own frame: origin at the root on the pitch axis, span along +y
    (port, ``side = 1``) or -y (starboard, ``side = -1``), thickness along z.

    Returns:
        The mesh, m.
    """
    r, x_le, x_te = fin.edges()
    shift = LATERAL_FIN_AXIS_FRAC * fin.root_chord_m
    mesh = _strip_plate(r, x_le + shift, x_te + shift, fin.thickness_m)
    if side < 0:
        mesh.apply_transform(np.diag([1.0, -1.0, 1.0, 1.0]))  # a reflection
        mesh = _outward(mesh)
    return mesh


def dorsal_fin_mesh(fin: FinPlanform = DORSAL_FIN) -> trimesh.Trimesh:
    """Dorsal fin plate: origin at the root leading edge, span along +z, thickness along y.

    Returns:
        The mesh, m.
    """
    return _to_vertical(_strip_plate(*fin.edges(), fin.thickness_m))


def caudal_fin_mesh(tail: TailGeometry) -> trimesh.Trimesh:
    """Caudal fin (tail segment 2) in its own frame: origin on the fin hinge, x forward.

    Returns:
        The mesh, m.
    """
    return _to_vertical(_strip_plate(*caudal_fin_edges(tail), tail.fin_thickness_m))


def caudal_fin_area_centroid(tail: TailGeometry) -> tuple[float, NDArray[np.float64]]:
    """Planform area (m^2) and area centroid (x, z) in the fin frame (m) of the caudal fin."""
    return _edges_area_centroid(*caudal_fin_edges(tail, 801))


# --------------------------------------------------------------------------------------------
# Assets


HULL = HullProfile()
"""The hull of the model (``models/bauv/bauv.xml``)."""

TAIL = TailGeometry()
"""The tail of the model."""


def write_assets(out_dir: str | Path = MODEL_DIR / "assets") -> dict[str, Path]:
    """Write the model's meshes as Wavefront OBJ files (0.1 mm precision).

    Args:
        out_dir: target folder (created if missing).

    Returns:
        Mapping from mesh name to the written path.
    """
    import trimesh

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    meshes = {
        "hull": hull_mesh(HULL),
        "peduncle": peduncle_mesh(HULL),
        "caudal_fin": caudal_fin_mesh(TAIL),
        "lateral_fin_port": lateral_fin_mesh(LATERAL_FIN, side=1),
        "lateral_fin_starboard": lateral_fin_mesh(LATERAL_FIN, side=-1),
        "dorsal_fin": dorsal_fin_mesh(DORSAL_FIN),
    }
    paths = {}
    for name, mesh in meshes.items():
        p = out / f"{name}.obj"
        text = trimesh.exchange.obj.export_obj(
            mesh,
            include_normals=False,
            include_color=False,
            include_texture=False,
            digits=4,
            header=None,
        )
        head = f"# {name}: generated by bauv_sim.hull (python -m bauv_sim.hull); do not edit\n"
        p.write_text(head + text)
        paths[name] = p
    return paths


def derived_numbers() -> dict[str, float]:
    """The numbers ``bauv.xml`` quotes that follow from the geometry.

    Returns:
        A flat mapping with units in the keys: volumes by quadrature and from the meshes, centres
        of buoyancy, reference areas, appendage areas.
    """
    mesh = hull_mesh(HULL)
    ped = peduncle_mesh(HULL)
    fin_area, fin_c = caudal_fin_area_centroid(TAIL)
    s_h = HULL.s_hinge
    return {
        "hull_volume_quad_m3": HULL.volume_m3(),
        "hull_volume_mesh_m3": float(mesh.volume),
        "hull_cb_x_m": HULL.centroid_x_m(),
        "hull_cb_x_mesh_m": float(mesh.center_mass[0]),
        "body_frontal_area_m2": HULL.frontal_area_m2(),
        "hull_wetted_area_m2": float(mesh.area),
        "hinge_half_height_m": float(HULL.half_height(s_h)),
        "hinge_half_width_m": float(HULL.half_width(s_h)),
        "hull_displaced_mass_kg": SEAWATER_DENSITY_KG_M3 * HULL.volume_m3(),
        "peduncle_volume_quad_m3": HULL.volume_m3(s_h, 1.0),
        "peduncle_volume_mesh_m3": float(ped.volume),
        "peduncle_cb_x_from_hinge_m": HULL.centroid_x_m(s_h, 1.0) - HULL.hinge_x_m,
        "peduncle_length_m": HULL.hinge_x_m - HULL.end_x_m,
        "caudal_fin_area_m2": fin_area,
        "caudal_fin_centroid_x_m": float(fin_c[0]),
        "caudal_fin_volume_m3": float(caudal_fin_mesh(TAIL).volume),
        "lateral_fin_area_m2": LATERAL_FIN.area_m2(),
        "lateral_fin_centroid_xr_m": float(LATERAL_FIN.centroid_m()[0]),
        "lateral_fin_centroid_r_m": float(LATERAL_FIN.centroid_m()[1]),
        "lateral_fin_volume_m3": float(lateral_fin_mesh(LATERAL_FIN).volume),
        "dorsal_fin_area_m2": DORSAL_FIN.area_m2(),
        "dorsal_fin_centroid_x_m": float(DORSAL_FIN.centroid_m()[0]),
        "dorsal_fin_centroid_r_m": float(DORSAL_FIN.centroid_m()[1]),
        "dorsal_fin_volume_m3": float(dorsal_fin_mesh(DORSAL_FIN).volume),
    }


def main(argv: list[str] | None = None) -> None:
    """Regenerate the mesh assets and print the derived numbers."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(MODEL_DIR / "assets"), help="asset folder")
    args = parser.parse_args(argv)
    for name, path in write_assets(args.out).items():
        print(f"wrote {name}: {path}")
    for k, v in derived_numbers().items():
        print(f"{k} = {v:.6g}")


if __name__ == "__main__":
    main()
