"""Sound-speed profiles and eigenrays against closed forms worked out here, and a ray ODE.

Truth used: Mackenzie's (1981) published check value; the straight line of isovelocity; the
circular ray of a constant-gradient layer (its centre on the depth where c would vanish, the
travel time ``(1/|g|) |ln tan(psi_B/2) - ln tan(psi_A/2)|`` from ``dt = R dpsi / (|g| R sin
psi)``); the ray equations of Jensen et al. (2011, eq. 3.23) integrated by scipy's RK45 from
the returned launch angle for a multi-layer profile (shooting: the integrated ray must reach the
receiver at the returned time).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nav.acoustics import (
    Eigenray,
    Isovelocity,
    LayeredMedium,
    SoundSpeedProfile,
    mackenzie_speed,
)
from nav.acoustics.inversion import range_from_travel_time, source_from_arrival
from nav.angles import range_azimuth_elevation
from nav.errors import NavInputError


def test_mackenzie_check_value() -> None:
    # Mackenzie (1981), the paper's check value: 1550.744 m/s at 25 C, 35 psu, 1000 m.
    assert mackenzie_speed(25.0, 35.0, 1000.0) == pytest.approx(1550.744, abs=5e-4)
    profile = SoundSpeedProfile.from_temperature_salinity([0.0, 1000.0], [25.0, 25.0], 35.0)
    assert profile.speed(1000.0) == pytest.approx(1550.744, abs=5e-4)


def test_profile_is_piecewise_linear_and_constant_outside() -> None:
    profile = SoundSpeedProfile(np.array([0.0, 50.0, 150.0]), np.array([1520.0, 1525.0, 1495.0]))
    assert profile.speed(25.0) == pytest.approx(1522.5, rel=1e-15)
    assert profile.speed(100.0) == pytest.approx(1510.0, rel=1e-15)
    assert profile.speed(-3.0) == 1520.0 and profile.speed(900.0) == 1495.0
    assert profile.gradient(25.0) == pytest.approx(0.1)
    assert profile.gradient(120.0) == pytest.approx(-0.3)
    assert profile.gradient(500.0) == 0.0
    # Harmonic mean of a linear layer: dz / ((1/g) ln(c2/c1)).
    expected = 50.0 / (np.log(1525.0 / 1520.0) / 0.1)
    assert profile.harmonic_mean_speed(0.0, 50.0) == pytest.approx(expected, rel=1e-12)
    assert profile.harmonic_mean_speed(50.0, 0.0) == pytest.approx(expected, rel=1e-12)
    assert profile.harmonic_mean_speed(30.0, 30.0) == pytest.approx(1523.0, rel=1e-15)
    two_layers = 150.0 / (np.log(1525.0 / 1520.0) / 0.1 + np.log(1495.0 / 1525.0) / -0.3)
    assert profile.harmonic_mean_speed(0.0, 150.0) == pytest.approx(two_layers, rel=1e-12)


@pytest.mark.parametrize(
    ("depth", "speed", "field"),
    [
        ([0.0, 0.0], [1500.0, 1501.0], "depth_m"),
        ([0.0, 10.0], [1500.0], "speed_m_s"),
        ([0.0, 10.0], [1500.0, -1.0], "speed_m_s"),
        ([0.0, np.nan], [1500.0, 1500.0], "depth_m"),
    ],
)
def test_profile_rejects_bad_input(depth: list, speed: list, field: str) -> None:
    with pytest.raises(NavInputError, match=field):
        SoundSpeedProfile(np.array(depth), np.array(speed))


def _points(rng: np.random.Generator, n: int, max_depth: float, span: float) -> tuple:
    a = np.column_stack([rng.uniform(-span, span, (n, 2)), -rng.uniform(0.0, max_depth, n)])
    b = np.column_stack([rng.uniform(-span, span, (n, 2)), -rng.uniform(0.0, max_depth, n)])
    return a, b


def test_isovelocity_is_the_straight_line() -> None:
    rng = np.random.default_rng(1)
    a, b = _points(rng, 500, 300.0, 800.0)
    # Same depth, vertical, coincident and above-the-surface cases.
    b[:20, 2] = a[:20, 2]
    b[20:30, :2] = a[20:30, :2]
    b[30] = a[30]
    a[31:35, 2] = 1.5
    medium = LayeredMedium(SoundSpeedProfile.isovelocity(1493.0))
    ray = medium.eigenray(a, b)
    d = b - a
    distance = np.sqrt(np.sum(d**2, axis=-1))
    elevation = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    np.testing.assert_allclose(ray.travel_time_s, distance / 1493.0, rtol=1e-9, atol=0.0)
    np.testing.assert_allclose(ray.launch_elevation_rad, elevation, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(ray.arrival_elevation_rad, -elevation, rtol=0.0, atol=1e-9)
    ref = Isovelocity(1493.0).eigenray(a, b)
    np.testing.assert_allclose(ray.travel_time_s, ref.travel_time_s, rtol=1e-9)


def _circle_truth(c0: float, g: float, a: np.ndarray, b: np.ndarray) -> Eigenray:
    """The constant-gradient ray by geometry: the circle through A and B centred on the level
    where c = c0 + g depth vanishes; u = up = -depth, x along the horizontal from A to B."""
    x_b = np.hypot(*(b[:, :2] - a[:, :2]).T)
    u_a, u_b = a[:, 2], b[:, 2]
    u_c = c0 / g  # depth -c0/g, i.e. up = c0/g
    x_c = (x_b**2 + (u_b - u_c) ** 2 - (u_a - u_c) ** 2) / (2.0 * x_b)
    psi_a = np.arctan2(u_a - u_c, -x_c)
    psi_b = np.arctan2(u_b - u_c, x_b - x_c)
    travel = np.abs(np.log(np.tan(np.abs(psi_b) / 2)) - np.log(np.tan(np.abs(psi_a) / 2))) / abs(g)
    if g > 0:  # centre above, points on the lower half, x grows with psi
        launch = np.arctan2(np.cos(psi_a), -np.sin(psi_a))
        arrival = np.arctan2(-np.cos(psi_b), -np.sin(psi_b))  # back along the arc, elevation
    else:  # centre below, points on the upper half, x grows as psi falls
        launch = np.arctan2(-np.cos(psi_a), np.sin(psi_a))
        arrival = np.arctan2(np.cos(psi_b), np.sin(psi_b))
    radius = np.hypot(x_c, u_a - u_c)
    return Eigenray(travel, launch, arrival), u_c, radius


@pytest.mark.parametrize(("c0", "g"), [(1480.0, 0.05), (1540.0, -0.05), (1500.0, 0.017)])
def test_constant_gradient_is_the_circle(c0: float, g: float) -> None:
    rng = np.random.default_rng(2)
    a, b = _points(rng, 600, 400.0, 600.0)
    b[:40, 2] = a[:40, 2]  # same depth: the ray turns between them
    truth, u_c, radius = _circle_truth(c0, g, a, b)
    # Keep arcs inside the water and inside the gradient (no surface, no bottom of the layer).
    inside = (u_c - radius > -4000.0) if g > 0 else (u_c + radius < 0.0)
    assert inside.sum() > 150
    medium = LayeredMedium(SoundSpeedProfile.constant_gradient(c0, g, 4000.0))
    ray = medium.eigenray(a[inside], b[inside])
    np.testing.assert_allclose(ray.travel_time_s, truth.travel_time_s[inside], rtol=1e-9, atol=0)
    np.testing.assert_allclose(
        ray.launch_elevation_rad, truth.launch_elevation_rad[inside], rtol=1e-6, atol=1e-9
    )
    np.testing.assert_allclose(
        ray.arrival_elevation_rad, truth.arrival_elevation_rad[inside], rtol=1e-6, atol=1e-9
    )


THERMOCLINE = SoundSpeedProfile(
    np.array([0.0, 40.0, 60.0, 200.0, 600.0, 1200.0]),
    np.array([1520.0, 1520.6, 1514.0, 1495.0, 1487.0, 1490.0]),
)


def test_reciprocity() -> None:
    rng = np.random.default_rng(3)
    a, b = _points(rng, 400, 500.0, 1500.0)
    b[:30, 2] = a[:30, 2]
    medium = LayeredMedium(THERMOCLINE)
    forward, backward = medium.eigenray(a, b), medium.eigenray(b, a)
    both = np.isfinite(forward.travel_time_s)
    assert both.sum() > 300
    np.testing.assert_array_equal(both, np.isfinite(backward.travel_time_s))
    np.testing.assert_allclose(
        backward.travel_time_s[both], forward.travel_time_s[both], rtol=1e-12
    )
    np.testing.assert_allclose(
        backward.launch_elevation_rad[both], forward.arrival_elevation_rad[both], atol=1e-9
    )
    np.testing.assert_allclose(
        backward.arrival_elevation_rad[both], forward.launch_elevation_rad[both], atol=1e-9
    )


def _shoot(profile: SoundSpeedProfile, source: np.ndarray, launch: float, horizontal: float):
    """Integrate the ray equations (Jensen et al. 2011, eq. 3.23) in arclength s:
    dx/ds = c xi, dz/ds = c zeta, dxi/ds = 0, dzeta/ds = -c_z / c^2, dt/ds = 1/c (z depth),
    from the launch elevation until the horizontal distance is reached; the integration stops
    and restarts at every knot (the gradient jumps there), so the steps never straddle one."""
    depth0 = -source[2]
    c0 = float(profile.speed(depth0))
    y = np.array([0.0, depth0, np.cos(launch) / c0, -np.sin(launch) / c0, 0.0])

    def reach(_s: float, y: np.ndarray) -> float:
        return y[0] - horizontal

    reach.terminal = True
    for _ in range(50):
        # The layer the ray is in (by its depth and where it heads).
        probe = y[1] + (1e-9 if y[3] > 0 else -1e-9)
        c_here = float(profile.speed(probe))
        dc = float(profile.gradient(probe))

        def rhs(_s: float, yy: np.ndarray, c1=c_here, z1=probe, g=dc) -> np.ndarray:
            c = c1 + g * (yy[1] - z1)
            return np.array([c * yy[2], c * yy[3], 0.0, -g / c**2, 1.0 / c])

        events = [reach]
        for knot in profile.depth_m:
            if abs(knot - y[1]) > 1e-9:

                def cross(_s: float, yy: np.ndarray, k=knot) -> float:
                    return yy[1] - k

                cross.terminal = True
                events.append(cross)
        sol = solve_ivp(rhs, (0.0, 1e5), y, events=events, rtol=1e-12, atol=1e-12, max_step=50.0)
        if sol.t_events[0].size:
            end = sol.y_events[0][0]
            return end[1], end[4]
        hit = next(i for i in range(1, len(events)) if sol.t_events[i].size)
        y = sol.y_events[hit][0]
    raise AssertionError("the integrated ray never reached the receiver's range")


def test_multilayer_rays_agree_with_integrated_ray_equations() -> None:
    medium = LayeredMedium(THERMOCLINE)
    cases = [
        # (source xyz, receiver xyz): crossing the thermocline, in the surface duct (turning
        # above the layer base), turning below in the deep positive gradient, steep.
        (np.array([0.0, 0.0, -10.0]), np.array([700.0, 300.0, -150.0])),
        (np.array([0.0, 0.0, -20.0]), np.array([1800.0, 0.0, -25.0])),
        (np.array([0.0, 0.0, -700.0]), np.array([0.0, 4000.0, -750.0])),
        (np.array([0.0, 0.0, -5.0]), np.array([50.0, 20.0, -400.0])),
        (np.array([10.0, 0.0, -300.0]), np.array([900.0, -200.0, -80.0])),
    ]
    for source, receiver in cases:
        ray = medium.eigenray(source, receiver)
        assert np.isfinite(ray.travel_time_s)
        horizontal = float(np.hypot(*(receiver[:2] - source[:2])))
        depth, time = _shoot(THERMOCLINE, source, float(ray.launch_elevation_rad), horizontal)
        assert depth == pytest.approx(-receiver[2], abs=1e-6)
        assert time == pytest.approx(float(ray.travel_time_s), rel=1e-9)


def test_shadow_has_no_ray_and_turning_rays_are_found() -> None:
    # A negative gradient from the surface: rays bend down; two points at 5 m depth 3 km apart
    # would need a ray turning above the surface (sagitta R/8 x^2 > 5 m): no direct ray.
    medium = LayeredMedium(SoundSpeedProfile.constant_gradient(1540.0, -0.05, 1000.0))
    ray = medium.eigenray(np.array([0.0, 0.0, -5.0]), np.array([3000.0, 0.0, -5.0]))
    assert np.isnan(ray.travel_time_s) and np.isnan(ray.arrival_elevation_rad)
    near = medium.eigenray(np.array([0.0, 0.0, -5.0]), np.array([500.0, 0.0, -5.0]))
    assert np.isfinite(near.travel_time_s) and near.launch_elevation_rad > 0.0


def test_shapes_broadcast_and_bad_input() -> None:
    medium = LayeredMedium(THERMOCLINE)
    src = np.zeros((4, 1, 3)) + np.array([0.0, 0.0, -10.0])
    rcv = np.zeros((1, 5, 3)) + np.array([300.0, 0.0, -80.0])
    ray = medium.eigenray(src, rcv)
    assert ray.travel_time_s.shape == (4, 5)
    with pytest.raises(NavInputError, match="last axis"):
        medium.eigenray(np.zeros(2), np.zeros(2))
    with pytest.raises(NavInputError, match="profile"):
        LayeredMedium("not a profile")  # type: ignore[arg-type]


def test_inversion_isovelocity_closed_forms() -> None:
    rng = np.random.default_rng(6)
    n = 300
    c = 1487.0
    za, zb = rng.uniform(0.0, 300.0, n), rng.uniform(0.0, 300.0, n)
    travel = np.hypot(rng.uniform(1.0, 900.0, n), zb - za) / c
    for medium in (Isovelocity(c), LayeredMedium(SoundSpeedProfile.isovelocity(c))):
        x = range_from_travel_time(medium, za, zb, travel)
        np.testing.assert_allclose(x, np.sqrt((c * travel) ** 2 - (zb - za) ** 2), rtol=1e-9)
    receiver = np.column_stack([rng.uniform(-50, 50, (n, 2)), -rng.uniform(0, 30, n)])
    azimuth = rng.uniform(0.0, 2 * np.pi, n)
    elevation = rng.uniform(-1.5, 1.5, n)
    source = source_from_arrival(Isovelocity(c), receiver, azimuth, elevation, travel)
    r = c * travel
    expected = receiver + np.column_stack(
        [
            r * np.cos(elevation) * np.sin(azimuth),
            r * np.cos(elevation) * np.cos(azimuth),
            r * np.sin(elevation),
        ]
    )
    np.testing.assert_allclose(source, expected, rtol=0, atol=1e-6)
    # A time shorter than the vertical ray's (noise) gives range 0, not NaN.
    assert range_from_travel_time(Isovelocity(c), 0.0, 150.0, 100.0 / c) == 0.0


def test_inversion_round_trip_through_a_thermocline() -> None:
    rng = np.random.default_rng(5)
    n = 600
    a = np.column_stack([rng.uniform(-1500, 1500, (n, 2)), -rng.uniform(0, 500, n)])
    b = np.column_stack([rng.uniform(-1500, 1500, (n, 2)), -rng.uniform(0, 500, n)])
    b[:40, 2] = a[:40, 2]
    medium = LayeredMedium(THERMOCLINE)
    ray = medium.eigenray(a, b)
    ok = np.isfinite(ray.travel_time_s)
    assert ok.sum() > 500
    a, b, travel = a[ok], b[ok], ray.travel_time_s[ok]
    horizontal = np.hypot(*(b[:, :2] - a[:, :2]).T)
    x = range_from_travel_time(medium, -a[:, 2], -b[:, 2], travel)
    np.testing.assert_allclose(x, horizontal, rtol=1e-9, atol=1e-9)
    azimuth = range_azimuth_elevation(a - b)[:, 1]
    source = source_from_arrival(medium, b, azimuth, ray.arrival_elevation_rad[ok], travel)
    np.testing.assert_allclose(source, a, rtol=0, atol=1e-5)
    with pytest.raises(NavInputError, match="medium"):
        range_from_travel_time(THERMOCLINE, 0.0, 1.0, 1.0)  # type: ignore[arg-type]
