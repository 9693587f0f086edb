"""INS attitude and body rates (VectorNav VN-100/VN-200 class), as the autopilot reads them.

The attitude and rate errors of a 0.1-deg-class INS are negligible for the vehicle's control loops
and for the lever-arm corrections of the position fixes (a 0.1 deg roll error moves a 0.3 m lever
arm by 0.5 mm), so this device reports the true roll, pitch and rates without error. The heading
comes from the compass (:mod:`bauv_sim.sensors.compass`), whose errors matter.
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from bauv_sim.config import Config
from bauv_sim.frames import navigation_rates_from_body
from bauv_sim.sensors.online import DeviceBuild, Measurement, TickContext, register_device


class InsConfig(Config):
    """The INS (exact attitude and rates; see the module docstring)."""

    period_s: float = Field(0.2, gt=0, description="sample period, s (every control tick)")


@register_device(InsConfig)
class InsDevice:
    """The INS in a vehicle's rig (held).

    Value: ``(roll, pitch, roll rate, pitch rate, heading rate)``, shape (5,): rad and rad/s;
    roll starboard-down positive, pitch nose-up positive, heading rate clockwise from above
    positive (the navigation convention; :func:`bauv_sim.frames.navigation_rates_from_body`).
    """

    kind = "held"

    def __init__(self, cfg: InsConfig, build: DeviceBuild):
        self.name = build.name
        self.every = build.every(cfg.period_s)

    def step(self, ctx: TickContext) -> Measurement:
        """The true attitude and rates."""
        vt = ctx.truth
        rph = vt.roll_pitch_heading_rad
        w = vt.angular_velocity_body_rad_s
        value = np.array([rph[0], rph[1], *navigation_rates_from_body(w)])
        return Measurement(self.name, ctx.t_s, ctx.t_s, value)
