"""The scene's geographic frame (bauv_sim.geo) against Vincenty's inverse formula, derived here."""

import math

import numpy as np
import pytest

from bauv_sim.errors import ConfigError
from bauv_sim.geo import GeoOriginConfig, LocalFrame

A_M = 6378137.0  # WGS 84 semi-major axis
F = 1 / 298.257223563  # WGS 84 flattening
B_M = A_M * (1 - F)


def vincenty_inverse(lat1, lon1, lat2, lon2):
    """Geodesic distance (m) and initial azimuth (rad, clockwise from north) on WGS 84:
    Vincenty (1975), Survey Review 23(176), 88-93, the inverse problem by iteration on lambda."""
    phi1, phi2 = math.radians(lat1), math.radians(lat2)
    L = math.radians(lon2 - lon1)
    U1 = math.atan((1 - F) * math.tan(phi1))
    U2 = math.atan((1 - F) * math.tan(phi2))
    sU1, cU1, sU2, cU2 = math.sin(U1), math.cos(U1), math.sin(U2), math.cos(U2)
    lam = L
    for _ in range(200):
        sl, cl = math.sin(lam), math.cos(lam)
        s_sigma = math.hypot(cU2 * sl, cU1 * sU2 - sU1 * cU2 * cl)
        c_sigma = sU1 * sU2 + cU1 * cU2 * cl
        sigma = math.atan2(s_sigma, c_sigma)
        if s_sigma == 0.0:
            return 0.0, 0.0  # coincident points
        s_alpha = cU1 * cU2 * sl / s_sigma
        c2_alpha = 1 - s_alpha**2
        c2sm = c_sigma - 2 * sU1 * sU2 / c2_alpha if c2_alpha else 0.0
        C = F / 16 * c2_alpha * (4 + F * (4 - 3 * c2_alpha))
        prev = lam
        lam = L + (1 - C) * F * s_alpha * (
            sigma + C * s_sigma * (c2sm + C * c_sigma * (-1 + 2 * c2sm**2))
        )
        if abs(lam - prev) < 1e-14:
            break
    u2 = c2_alpha * (A_M**2 - B_M**2) / B_M**2
    A = 1 + u2 / 16384 * (4096 + u2 * (-768 + u2 * (320 - 175 * u2)))
    B = u2 / 1024 * (256 + u2 * (-128 + u2 * (74 - 47 * u2)))
    d_sigma = (
        B
        * s_sigma
        * (
            c2sm
            + B
            / 4
            * (
                c_sigma * (-1 + 2 * c2sm**2)
                - B / 6 * c2sm * (-3 + 4 * s_sigma**2) * (-3 + 4 * c2sm**2)
            )
        )
    )
    s = B_M * A * (sigma - d_sigma)
    sl, cl = math.sin(lam), math.cos(lam)
    alpha1 = math.atan2(cU2 * sl, cU1 * sU2 - sU1 * cU2 * cl)
    return s, alpha1


ORIGINS = [(0.0, 0.0), (43.1, 5.9), (70.5, -20.0), (-35.2, 150.4), (10.0, 179.95)]


def _points(lat0, lon0, n=60, seed=3):
    """Points up to 10 km from the origin in every direction (lat/lon offsets)."""
    rng = np.random.default_rng(seed)
    dist = rng.uniform(50.0, 10_000.0, n)
    az = rng.uniform(0.0, 2 * math.pi, n)
    dlat = dist * np.cos(az) / 111_000.0
    dlon = dist * np.sin(az) / (111_000.0 * math.cos(math.radians(lat0)))
    return lat0 + dlat, lon0 + dlon


@pytest.mark.parametrize(("lat0", "lon0"), ORIGINS)
def test_east_north_equal_vincenty_within_1_cm_over_10_km(lat0, lon0):
    frame = LocalFrame(lat0, lon0)
    lat, lon = _points(lat0, lon0)
    east, north = frame.to_local(lat, lon)
    for i in range(len(lat)):
        s, alpha = vincenty_inverse(lat0, lon0, float(lat[i]), float(lon[i]))
        assert s < 10_500.0
        assert abs(east[i] - s * math.sin(alpha)) < 0.01
        assert abs(north[i] - s * math.cos(alpha)) < 0.01


@pytest.mark.parametrize(("lat0", "lon0"), ORIGINS)
def test_round_trip_within_1_mm_over_10_km(lat0, lon0):
    frame = LocalFrame(lat0, lon0)
    rng = np.random.default_rng(11)
    east = rng.uniform(-10_000.0, 10_000.0, 200)
    north = rng.uniform(-10_000.0, 10_000.0, 200)
    lat, lon = frame.to_geographic(east, north)
    e2, n2 = frame.to_local(lat, lon)
    assert np.max(np.hypot(e2 - east, n2 - north)) < 1e-3
    # and the other way: geographic -> local -> geographic, compared as a distance on the ground
    lat_p, lon_p = _points(lat0, lon0, seed=12)
    lat_b, lon_b = frame.to_geographic(*frame.to_local(lat_p, lon_p))
    for i in range(len(lat_p)):
        s, _ = vincenty_inverse(float(lat_p[i]), float(lon_p[i]), float(lat_b[i]), float(lon_b[i]))
        assert s < 1e-3


def test_the_origin_and_a_meridian_arc():
    """The origin maps to (0, 0); a point due north lies on the east = 0 line at the meridian
    arc's length, which a series for the meridian arc gives independently (Helmert's)."""
    lat0 = 40.0
    frame = LocalFrame(lat0, 10.0)
    e0, n0 = frame.to_local(lat0, 10.0)
    assert abs(e0) < 1e-9 and abs(n0) < 1e-9
    n_ = F / (2 - F)

    def arc(phi):
        # Helmert's series for the meridian arc from the equator
        A = A_M / (1 + n_) * (1 + n_**2 / 4 + n_**4 / 64)
        return A * (
            phi
            - (3 * n_ / 2 - 9 * n_**3 / 16) * math.sin(2 * phi)
            + (15 * n_**2 / 16 - 15 * n_**4 / 32) * math.sin(4 * phi)
            - 35 * n_**3 / 48 * math.sin(6 * phi)
        )

    lat1 = lat0 + 0.08
    e, n = frame.to_local(lat1, 10.0)
    assert abs(e) < 1e-6
    assert abs(n - (arc(math.radians(lat1)) - arc(math.radians(lat0)))) < 1e-3


def test_bad_input_names_the_field():
    with pytest.raises(ConfigError, match=r"origin.latitude_deg = 90.0"):
        LocalFrame(90.0, 0.0)
    with pytest.raises(ConfigError, match=r"origin.longitude_deg = nan"):
        LocalFrame(0.0, float("nan"))
    frame = LocalFrame(10.0, 10.0)
    with pytest.raises(ConfigError, match=r"latitude_deg = 95.0"):
        frame.to_local([95.0], [10.0])
    with pytest.raises(ConfigError, match=r"east_m, north_m"):
        frame.to_geographic([float("inf")], [0.0])
    with pytest.raises(ConfigError, match=r"latitude_deg"):
        from bauv_sim.config import load_config

        load_config(GeoOriginConfig, {"latitude_deg": 91})
