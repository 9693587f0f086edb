"""Geographic coordinates: WGS 84 latitude and longitude against the scene's east/north frame.

The scene is flat (MuJoCo's world, the kinematic worlds, the navigators' east/north); a dive site
is on the ellipsoid. :class:`LocalFrame` maps one onto the other with the **azimuthal equidistant
projection** centred at the scene's geographic origin, on the WGS 84 ellipsoid: a point at
geodesic distance ``s`` and azimuth ``alpha`` (clockwise from true north) from the origin has

    east = s sin(alpha),   north = s cos(alpha),

so every distance and bearing *from the origin* is the true geodesic one, and the distortion of
distances between two other points grows as (r / R)^2 (about 1e-6 at 6 km, 2.5e-6 at 10 km from
the origin; r the distance from the origin, R the Earth's radius). Heights are not projected:
the scene's z is the height above the origin's ellipsoid height (depth = -z).

The projection is PROJ's ``aeqd`` on the WGS 84 ellipsoid through pyproj, which computes the
ellipsoidal geodesics of Karney (2013), *Algorithms for geodesics*, J. Geodesy 87, 43-55, to
nanometres: pyproj is the library geodesy in Python is done with (the PROJ the GIS tools use),
so the frame agrees with what a chart of the same site shows. A test derives east/north from
Vincenty's (1975) inverse formula independently.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.errors import ConfigError

Array = NDArray[np.float64]

MAX_LATITUDE_DEG = 89.0
"""The origin's latitude is kept off the poles, where east and north have no meaning, deg."""


def _check_origin(latitude_deg: float, longitude_deg: float, where: str) -> None:
    if not (np.isfinite(latitude_deg) and abs(latitude_deg) <= MAX_LATITUDE_DEG):
        raise ConfigError(
            f"{where}.latitude_deg = {latitude_deg!r}: must be a finite number in "
            f"[-{MAX_LATITUDE_DEG:g}, {MAX_LATITUDE_DEG:g}] (WGS 84, deg)"
        )
    if not (np.isfinite(longitude_deg) and -180.0 <= longitude_deg <= 180.0):
        raise ConfigError(
            f"{where}.longitude_deg = {longitude_deg!r}: must be a finite number in "
            "[-180, 180] (WGS 84, deg)"
        )


@dataclass(frozen=True)
class LocalFrame:
    """The scene's east/north frame at a geographic origin (see the module docstring).

    Attributes:
        latitude_deg: the origin's WGS 84 latitude, deg, in [-89, 89].
        longitude_deg: the origin's WGS 84 longitude, deg, in [-180, 180].

    Raises:
        ConfigError: for an origin out of range (naming the field and the value).
    """

    latitude_deg: float
    longitude_deg: float
    _forward: object = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        _check_origin(self.latitude_deg, self.longitude_deg, "origin")
        from pyproj import CRS, Transformer

        local = CRS.from_proj4(
            f"+proj=aeqd +lat_0={self.latitude_deg!r} +lon_0={self.longitude_deg!r} "
            "+x_0=0 +y_0=0 +ellps=WGS84 +units=m +no_defs"
        )
        transformer = Transformer.from_crs(CRS.from_epsg(4326), local, always_xy=True)
        object.__setattr__(self, "_forward", transformer)

    def to_local(self, latitude_deg: ArrayLike, longitude_deg: ArrayLike) -> tuple[Array, Array]:
        """East and north of geographic points.

        Args:
            latitude_deg: WGS 84 latitudes, any shape, deg.
            longitude_deg: WGS 84 longitudes, the same shape, deg.

        Returns:
            ``(east_m, north_m)``, each of the input's shape, m, in the scene's frame.

        Raises:
            ConfigError: for a non-finite or out-of-range latitude or longitude.
        """
        lat = np.asarray(latitude_deg, dtype=float)
        lon = np.asarray(longitude_deg, dtype=float)
        if lat.shape != lon.shape:
            raise ConfigError(
                f"latitude_deg and longitude_deg: shapes {lat.shape} and {lon.shape} differ"
            )
        bad = ~np.isfinite(lat) | (np.abs(lat) > 90.0)
        if bad.any():
            raise ConfigError(
                f"latitude_deg = {float(lat[bad].flat[0])!r}: must be a finite number in [-90, 90]"
            )
        bad = ~np.isfinite(lon) | (np.abs(lon) > 360.0)
        if bad.any():
            raise ConfigError(
                f"longitude_deg = {float(lon[bad].flat[0])!r}: must be a finite number in "
                "[-360, 360]"
            )
        east, north = self._forward.transform(lon, lat)  # type: ignore[attr-defined]
        return np.asarray(east, dtype=float), np.asarray(north, dtype=float)

    def to_geographic(self, east_m: ArrayLike, north_m: ArrayLike) -> tuple[Array, Array]:
        """Latitude and longitude of points of the scene.

        Args:
            east_m: east coordinates, any shape, m.
            north_m: north coordinates, the same shape, m.

        Returns:
            ``(latitude_deg, longitude_deg)``, each of the input's shape, WGS 84, deg
            (longitude in [-180, 180]).

        Raises:
            ConfigError: for non-finite coordinates.
        """
        e = np.asarray(east_m, dtype=float)
        n = np.asarray(north_m, dtype=float)
        if e.shape != n.shape:
            raise ConfigError(f"east_m and north_m: shapes {e.shape} and {n.shape} differ")
        if not (np.isfinite(e).all() and np.isfinite(n).all()):
            raise ConfigError("east_m, north_m: must be finite numbers (m)")
        lon, lat = self._forward.transform(e, n, direction="INVERSE")  # type: ignore[attr-defined]
        lon = (np.asarray(lon, dtype=float) + 180.0) % 360.0 - 180.0
        return np.asarray(lat, dtype=float), lon


class GeoOriginConfig(Config):
    """Where the scene's origin is on the Earth (WGS 84)."""

    latitude_deg: float = Field(
        0.0, ge=-MAX_LATITUDE_DEG, le=MAX_LATITUDE_DEG, description="latitude of the origin, deg"
    )
    longitude_deg: float = Field(
        0.0, ge=-180.0, le=180.0, description="longitude of the origin, deg"
    )

    def frame(self) -> LocalFrame:
        """The scene's frame at this origin (one per origin and process: building PROJ's
        transformer takes milliseconds)."""
        return _frame_at(self.latitude_deg, self.longitude_deg)


@functools.lru_cache(maxsize=16)
def _frame_at(latitude_deg: float, longitude_deg: float) -> LocalFrame:
    return LocalFrame(latitude_deg, longitude_deg)
