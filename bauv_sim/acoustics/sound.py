"""The sea's sound-speed profile as a scenario section: what the acoustic devices propagate in.

A scenario's ``sound`` section (:class:`SoundSpeedConfig`) gives the TRUE medium of the sea; the
devices keep their own ``sound_speed_m_s`` as the nominal speed they turn a travel time into a
range with. The default (``kind = "isovelocity"``, no speed) is no medium at all: every device
keeps its configured speed as the true one, today's behaviour bit for bit.

Kinds:

* ``isovelocity``: one speed (``speed_m_s``) everywhere (straight rays);
* ``table``: ``depths_m`` and ``speeds_m_s``, piecewise linear, constant outside;
* ``temperature_salinity``: ``depths_m``, ``temperatures_c``, ``salinities_psu`` through
  Mackenzie's (1981) equation, within its validity (2..30 C, 25..40 psu, 0..8000 m);
* ``munk``: Munk's canonical deep-ocean profile (the preset, below).

**The preset** (``kind = "munk"``): W. H. Munk, "Sound channel in an exponentially stratified
ocean, with application to SOFAR", J. Acoust. Soc. Am. 55(2), 220-226 (1974):
``c(z) = 1500 [1 + eps (eta - 1 + exp(-eta))]``, ``eta = 2 (z - 1300) / 1300``, ``eps =
0.00737``: the main thermocline from 1548.5 m/s at the surface down to the sound-channel axis at
1300 m (1500 m/s), then the pressure-dominated rise (the test case of Jensen, Kuperman, Porter &
Schmidt, *Computational Ocean Acoustics*, 2nd ed. 2011, sec. 3.4). It is sampled at
:data:`MUNK_KNOTS_M` and interpolated linearly: within 0.0024 m/s of the formula down to 100 m
(knots every 10 m), 0.05 m/s to 500 m, 0.10 m/s below (measured on a 1 cm grid). Near the
surface the speed is 3 % above the nominal 1500 m/s, with a gradient of -0.108 1/s.
"""

from __future__ import annotations

import itertools
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from bauv_sim.config import Config
from nav.acoustics import (
    Isovelocity,
    LayeredMedium,
    Propagation,
    SoundSpeedProfile,
    mackenzie_speed,
)

MUNK_KNOTS_M: tuple[float, ...] = (
    *(float(d) for d in range(0, 100, 10)),
    *(float(d) for d in range(100, 500, 50)),
    *(float(d) for d in range(500, 2000, 100)),
    *(float(d) for d in range(2000, 5001, 250)),
)
"""Depths at which the Munk preset is sampled, m."""


def munk_speed(depth_m: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Munk's (1974) canonical profile ``c(z) = 1500 [1 + eps (eta - 1 + exp(-eta))]``,
    ``eta = 2 (z - 1300) / 1300``, ``eps = 0.00737`` (z depth, m; c m/s)."""
    eta = 2.0 * (np.asarray(depth_m, dtype=float) - 1300.0) / 1300.0
    return 1500.0 * (1.0 + 0.00737 * (eta - 1.0 + np.exp(-eta)))


class SoundSpeedConfig(Config):
    """The sea's true sound-speed profile (default: none, each device's own speed)."""

    kind: Literal["isovelocity", "table", "temperature_salinity", "munk"] = Field(
        "isovelocity", description="how the profile is given (module docstring)"
    )
    speed_m_s: float | None = Field(
        None,
        gt=0,
        description="isovelocity: the true speed, m/s; None = every device's own "
        "sound_speed_m_s (today's behaviour)",
    )
    depths_m: tuple[float, ...] = Field(
        (), description="table / temperature_salinity: knot depths, m, strictly increasing, >= 0"
    )
    speeds_m_s: tuple[float, ...] = Field((), description="table: speed at each depth, m/s")
    temperatures_c: tuple[float, ...] = Field(
        (), description="temperature_salinity: temperature at each depth, deg C (2..30)"
    )
    salinities_psu: tuple[float, ...] = Field(
        (),
        description="temperature_salinity: salinity at each depth (or one for all), psu (25..40)",
    )

    @model_validator(mode="after")
    def _check(self) -> SoundSpeedConfig:
        used = {
            "isovelocity": {"speed_m_s"},
            "table": {"depths_m", "speeds_m_s"},
            "temperature_salinity": {"depths_m", "temperatures_c", "salinities_psu"},
            "munk": set(),
        }[self.kind]
        for name in ("speed_m_s", "depths_m", "speeds_m_s", "temperatures_c", "salinities_psu"):
            value = getattr(self, name)
            if name not in used and value not in (None, ()):
                raise ValueError(
                    f"{name} = {value}: not used with kind = {self.kind!r} (used: "
                    f"{', '.join(sorted(used)) or 'none'})"
                )
        if self.kind in ("table", "temperature_salinity"):
            d = self.depths_m
            if not d:
                raise ValueError(f"depths_m = (): kind = {self.kind!r} needs at least one depth")
            if d[0] < 0 or any(b <= a for a, b in itertools.pairwise(d)):
                raise ValueError(f"depths_m = {d}: must be >= 0 and strictly increasing")
        if self.kind == "table":
            if len(self.speeds_m_s) != len(self.depths_m):
                raise ValueError(
                    f"speeds_m_s = {self.speeds_m_s}: one speed per depth ({len(self.depths_m)})"
                )
            if any(not 1300.0 <= c <= 1800.0 for c in self.speeds_m_s):
                raise ValueError(
                    f"speeds_m_s = {self.speeds_m_s}: each must be in [1300, 1800] m/s (sea water)"
                )
        if self.kind == "temperature_salinity":
            n = len(self.depths_m)
            if len(self.temperatures_c) != n:
                raise ValueError(
                    f"temperatures_c = {self.temperatures_c}: one temperature per depth ({n})"
                )
            if len(self.salinities_psu) not in (1, n):
                raise ValueError(
                    f"salinities_psu = {self.salinities_psu}: one salinity, or one per depth ({n})"
                )
            if any(not 2.0 <= t <= 30.0 for t in self.temperatures_c):
                raise ValueError(
                    f"temperatures_c = {self.temperatures_c}: each must be in [2, 30] deg C "
                    "(Mackenzie 1981's validity)"
                )
            if any(not 25.0 <= s <= 40.0 for s in self.salinities_psu):
                raise ValueError(
                    f"salinities_psu = {self.salinities_psu}: each must be in [25, 40] psu "
                    "(Mackenzie 1981's validity)"
                )
            if self.depths_m[-1] > 8000.0:
                raise ValueError(
                    f"depths_m = {self.depths_m}: at most 8000 m (Mackenzie 1981's validity)"
                )
        return self

    @property
    def is_default(self) -> bool:
        """No medium: every device keeps its own speed (today's behaviour)."""
        return self.kind == "isovelocity" and self.speed_m_s is None

    def profile(self) -> SoundSpeedProfile | None:
        """The profile, or ``None`` for the default."""
        if self.is_default:
            return None
        if self.kind == "isovelocity":
            return SoundSpeedProfile.isovelocity(float(self.speed_m_s))  # type: ignore[arg-type]
        if self.kind == "table":
            return SoundSpeedProfile(np.array(self.depths_m), np.array(self.speeds_m_s))
        if self.kind == "temperature_salinity":
            depth = np.array(self.depths_m)
            salinity = np.broadcast_to(np.array(self.salinities_psu), depth.shape)
            return SoundSpeedProfile(
                depth, mackenzie_speed(np.array(self.temperatures_c), salinity, depth)
            )
        depth = np.array(MUNK_KNOTS_M)
        return SoundSpeedProfile(depth, munk_speed(depth))

    def propagation(self) -> Propagation | None:
        """The sea's true medium for the devices, or ``None`` for the default (each device's
        own ``sound_speed_m_s``, straight rays: today's numbers)."""
        if self.is_default:
            return None
        if self.kind == "isovelocity":
            return Isovelocity(float(self.speed_m_s))  # type: ignore[arg-type]
        profile = self.profile()
        assert profile is not None
        return LayeredMedium(profile)


def thermocline_preset() -> SoundSpeedConfig:
    """The named preset: Munk's (1974) canonical thermocline profile (``kind = "munk"``)."""
    return SoundSpeedConfig(kind="munk")
