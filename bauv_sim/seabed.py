"""The seabed: a generated, gently varying bathymetry stored as a MuJoCo heightfield.

Depth below the surface (positive down) at horizontal position (x east, y north):

    depth(x, y) = depth_at_origin + slope * r + relief(x, y) - relief(0, 0),    r = sqrt(x^2 + y^2)

where ``relief`` is a sum of ``n_modes`` plane waves with random directions, wavelengths
log-uniform in [``min_wavelength_m``, ``max_wavelength_m``] and phases, scaled to the standard
deviation ``relief_std_m`` and drawn from the seabed's own random stream. Depths are clipped to
at least ``min_depth_m``. The defaults follow seed 000's test geometry: the USBL transceiver at the
origin lies on the seabed at 6 m depth, and the bottom falls away gently (5 m per km) with about
1 m of relief, so that a vehicle at 3 m depth clears it everywhere.

The grid is a MuJoCo heightfield in its custom binary format (int32 nrow, int32 ncol, float32
data, row 0 at the smallest y, column 0 at the smallest x), normalised to [0, 1]; the geom's z is
the deepest point and its elevation range the depth range. :func:`height_world` interpolates the
same triangles MuJoCo collides with (each cell split along the diagonal from its lower-left to its
upper-right corner).
"""

from __future__ import annotations

import argparse
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field, model_validator

from bauv_sim import PROJECT_ROOT
from bauv_sim.config import Config
from bauv_sim.errors import GeometryError
from bauv_sim.rng import generator

SEABED_DIR = PROJECT_ROOT / "assets" / "seabed"
"""Folder of the generated seabed heightfields."""

DEFAULT_SEABED_FILE = SEABED_DIR / "default.bin"
"""The heightfield of the default scene (``models/bauv/scene.xml``)."""


class SeabedConfig(Config):
    """Parameters of a generated seabed (see the module docstring)."""

    half_extent_m: float = Field(1000.0, gt=0, description="half side of the square grid, m")
    cell_m: float = Field(10.0, gt=0, description="grid spacing, m")
    depth_at_origin_m: float = Field(6.0, gt=0, description="depth at (0, 0), m")
    slope: float = Field(0.005, ge=0, le=0.5, description="radial increase of depth, m per m")
    relief_std_m: float = Field(1.0, ge=0, description="standard deviation of the relief, m")
    n_modes: int = Field(24, ge=1, le=1000, description="plane waves in the relief")
    min_wavelength_m: float = Field(60.0, gt=0, description="shortest relief wavelength, m")
    max_wavelength_m: float = Field(600.0, gt=0, description="longest relief wavelength, m")
    min_depth_m: float = Field(4.5, gt=0, description="shallowest allowed depth, m")
    base_m: float = Field(1.0, gt=0, description="thickness of the heightfield's base, m")
    seed: int = Field(1, ge=0, description="seed of the relief's random stream")

    @model_validator(mode="after")
    def _grid(self) -> SeabedConfig:
        n = self.half_extent_m / self.cell_m
        if abs(n - round(n)) > 1e-9 or round(n) < 1:
            raise ValueError(
                f"half_extent_m = {self.half_extent_m} must be a whole number of "
                f"cells of {self.cell_m} m"
            )
        if self.max_wavelength_m < self.min_wavelength_m:
            raise ValueError("max_wavelength_m must be >= min_wavelength_m")
        if self.depth_at_origin_m < self.min_depth_m:
            raise ValueError("depth_at_origin_m must be >= min_depth_m")
        return self

    @property
    def n(self) -> int:
        """Grid points per side (odd: the origin is a grid point)."""
        return 2 * round(self.half_extent_m / self.cell_m) + 1


@dataclass(frozen=True)
class Seabed:
    """A generated seabed grid.

    Attributes:
        config: its parameters.
        depth_m: depth at the grid points, shape (n, n), m; ``depth_m[i, j]`` is at
            y = -half + i cell, x = -half + j cell.
    """

    config: SeabedConfig
    depth_m: NDArray[np.float64]

    @property
    def z_min_m(self) -> float:
        """World z of the deepest point, m."""
        return -float(self.depth_m.max())

    @property
    def z_max_m(self) -> float:
        """World z of the shallowest point, m."""
        return -float(self.depth_m.min())

    def normalised(self) -> NDArray[np.float32]:
        """Heights normalised to [0, 1] as MuJoCo stores them, shape (n, n), float32."""
        z = -self.depth_m
        span = self.z_max_m - self.z_min_m
        if span <= 0:
            return np.zeros_like(z, dtype=np.float32)
        return ((z - self.z_min_m) / span).astype(np.float32)

    def to_bytes(self) -> bytes:
        """The heightfield in MuJoCo's custom binary format."""
        n = self.config.n
        return struct.pack("<ii", n, n) + self.normalised().astype("<f4").tobytes()

    def hfield_size(self) -> tuple[float, float, float, float]:
        """MuJoCo ``hfield size``: (radius x, radius y, elevation range, base), m."""
        c = self.config
        return (c.half_extent_m, c.half_extent_m, max(self.z_max_m - self.z_min_m, 1e-6), c.base_m)

    def height_world(self, x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
        """World z of the seabed surface (the triangulated heightfield), m.

        Args:
            x_m: east, any shape, m.
            y_m: north, broadcastable with ``x_m``, m.

        Returns:
            Seabed z (negative below the surface), broadcast shape, m.

        Raises:
            GeometryError: for points outside the grid.
        """
        c = self.config
        x, y = np.broadcast_arrays(np.asarray(x_m, float), np.asarray(y_m, float))
        gx = (x + c.half_extent_m) / c.cell_m
        gy = (y + c.half_extent_m) / c.cell_m
        n = c.n
        if np.any((gx < 0) | (gx > n - 1) | (gy < 0) | (gy > n - 1)):
            raise GeometryError(f"point outside the seabed grid (half extent {c.half_extent_m} m)")
        j = np.minimum(np.floor(gx).astype(int), n - 2)
        i = np.minimum(np.floor(gy).astype(int), n - 2)
        u, v = gx - j, gy - i
        # heights as MuJoCo stores them (float32 normalised), back to metres
        hn = self.normalised().astype(np.float64)
        span = self.hfield_size()[2]
        z = self.z_min_m + span * hn
        z00, z10 = z[i, j], z[i, j + 1]
        z01, z11 = z[i + 1, j], z[i + 1, j + 1]
        # triangles split along (0,0)-(1,1)
        lower = u >= v
        return np.where(
            lower, z00 + u * (z10 - z00) + v * (z11 - z10), z00 + v * (z01 - z00) + u * (z11 - z01)
        )

    def depth_at(self, x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
        """Depth of the seabed below the surface, m (positive down); see :meth:`height_world`."""
        return -self.height_world(x_m, y_m)


def generate(config: SeabedConfig | None = None) -> Seabed:
    """Generate a seabed from its parameters (deterministic for a given seed).

    Args:
        config: parameters; the defaults when None.

    Returns:
        The :class:`Seabed`.
    """
    c = config or SeabedConfig()
    rng = generator(c.seed, 0, "seabed", "relief")
    ax = np.linspace(-c.half_extent_m, c.half_extent_m, c.n)
    X, Y = np.meshgrid(ax, ax)  # [i, j] = (y_i, x_j)
    lam = np.exp(rng.uniform(np.log(c.min_wavelength_m), np.log(c.max_wavelength_m), c.n_modes))
    theta = rng.uniform(0.0, 2.0 * np.pi, c.n_modes)
    phase = rng.uniform(0.0, 2.0 * np.pi, c.n_modes)
    k = 2.0 * np.pi / lam
    relief = np.zeros_like(X)
    relief0 = 0.0
    for kk, th, ph in zip(k, theta, phase, strict=True):
        relief += np.cos(kk * (np.cos(th) * X + np.sin(th) * Y) + ph)
        relief0 += np.cos(ph)
    # sum of n unit cosines with random phases has variance n / 2
    scale = c.relief_std_m / np.sqrt(0.5 * c.n_modes)
    depth = c.depth_at_origin_m + c.slope * np.hypot(X, Y) + scale * (relief - relief0)
    depth = np.maximum(depth, c.min_depth_m)
    return Seabed(c, depth)


def write(seabed: Seabed, path: str | Path = DEFAULT_SEABED_FILE) -> Path:
    """Write a heightfield file (MuJoCo custom binary format).

    Args:
        seabed: the seabed.
        path: target file.

    Returns:
        The path written.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(seabed.to_bytes())
    return p


def main(argv: list[str] | None = None) -> None:
    """Regenerate the default seabed file and print its MuJoCo geometry."""
    parser = argparse.ArgumentParser(description="generate the default seabed heightfield")
    parser.add_argument("--out", default=str(DEFAULT_SEABED_FILE))
    args = parser.parse_args(argv)
    sb = generate()
    path = write(sb, args.out)
    print(f"wrote {path} ({path.stat().st_size} bytes)")
    print(f"hfield size = {' '.join(f'{v:.6g}' for v in sb.hfield_size())}")
    print(f"geom z = {sb.z_min_m:.6g} (deepest point); shallowest z = {sb.z_max_m:.6g}")
    print(f"depth at origin = {float(sb.depth_at(0.0, 0.0)):.6g} m")


if __name__ == "__main__":
    main()
