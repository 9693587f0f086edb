"""The scenario of ``acoustics/sound-speed``: the sea's profile, a USBL passage, modem links.

Reading of the experiment where the issue is silent (documented in the fields):

* the truth is kinematic and fixed: the vehicle's transponder passes the transceiver on a
  straight line at one depth (``usbl``), and two vehicles hold still at the link geometries of
  ``modem`` (the sender at one depth, the receiver at each depth and horizontal range); the
  runs differ only by the devices' error draws;
* the devices' ``sound_speed_m_s`` (1500 m/s by default) is the nominal speed they and the
  "nominal" navigator assume; the sea's profile (``sound``, default Munk's 1974 thermocline) is
  the truth the sound travels in, and what the "profile" navigator knows exactly;
* the USBL fixes are converted to positions by each navigator; the modem's ranges are compared
  with the true slant range between the transducers (the depths being known to both ends).
"""

from __future__ import annotations

import math

from pydantic import Field, field_validator, model_validator

from bauv_sim.acoustics import SoundSpeedConfig, thermocline_preset
from bauv_sim.config import Config
from bauv_sim.sensors.modem import ModemConfig
from bauv_sim.sensors.usbl import UsblConfig

MAX_FIXES = 10_000
"""The most USBL fixes along the passage."""
MAX_LINKS = 400
"""The most modem link geometries (receiver depths x horizontal ranges)."""


class UsblPassageConfig(Config):
    """A straight passage of the transponder past the transceiver, at one depth."""

    transceiver_depth_m: float = Field(
        5.0, ge=0, le=1000, description="depth of the transceiver's array, m"
    )
    depth_m: float = Field(40.0, ge=0, le=1000, description="depth of the transponder, m")
    closest_approach_m: float = Field(
        50.0, ge=0, le=5000, description="horizontal distance at the closest approach, m"
    )
    half_length_m: float = Field(
        450.0, gt=0, le=5000, description="the passage runs +-this along east, m"
    )
    fixes: int = Field(91, ge=2, le=MAX_FIXES, description="fixes evenly along the passage")
    device: UsblConfig = Field(
        default_factory=lambda: UsblConfig(max_range_m=1000.0),
        description="the USBL (seed 000's MicronNav errors; range limit 1000 m here)",
    )


class ModemLinksConfig(Config):
    """Modem links: a sender at one depth, receivers at several depths and ranges."""

    sender_depth_m: float = Field(10.0, ge=0, le=1000, description="sender's depth, m")
    receiver_depths_m: list[float] = Field(
        [10.0, 40.0, 80.0],
        min_length=1,
        max_length=20,
        description="receiver depths, m",
    )
    horizontal_ranges_m: list[float] = Field(
        [100.0, 250.0, 500.0, 750.0, 1000.0],
        min_length=1,
        max_length=20,
        description="horizontal ranges between sender and receiver, m",
    )
    device: ModemConfig = Field(
        default_factory=lambda: ModemConfig(max_range_m=1500.0),
        description="the modem (seed 003's range errors; range limit 1500 m here)",
    )

    @field_validator("receiver_depths_m")
    @classmethod
    def _depths(cls, v: list[float]) -> list[float]:
        bad = [x for x in v if not (math.isfinite(x) and 0 <= x <= 1000)]
        if bad:
            raise ValueError(f"every depth must be in [0, 1000] m (not {bad[0]})")
        return v

    @field_validator("horizontal_ranges_m")
    @classmethod
    def _ranges(cls, v: list[float]) -> list[float]:
        bad = [x for x in v if not (math.isfinite(x) and 0 < x <= 10_000)]
        if bad:
            raise ValueError(f"every range must be in (0, 10000] m (not {bad[0]})")
        return v


class RunnerConfig(Config):
    """Batching (fixed by the scenario, never by the worker count)."""

    block_size: int = Field(25, ge=1, le=10_000, description="runs per block")


class SoundSpeedScenario(Config):
    """Scenario of ``acoustics/sound-speed`` (module docstring)."""

    sound: SoundSpeedConfig = Field(
        default_factory=thermocline_preset,
        description="the sea's true sound-speed profile (default: Munk 1974)",
    )
    usbl: UsblPassageConfig = Field(default_factory=UsblPassageConfig)
    modem: ModemLinksConfig = Field(default_factory=ModemLinksConfig)
    runner: RunnerConfig = Field(default_factory=RunnerConfig)

    @model_validator(mode="after")
    def _sizes(self) -> SoundSpeedScenario:
        links = len(self.modem.receiver_depths_m) * len(self.modem.horizontal_ranges_m)
        if links > MAX_LINKS:
            raise ValueError(
                f"modem: {links} link geometries (receiver_depths_m x horizontal_ranges_m); at "
                f"most {MAX_LINKS}"
            )
        return self
