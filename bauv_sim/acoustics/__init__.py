"""The acoustics of the simulated sea: the sound-speed profile, clocks, the sonar equation and the
acoustic network.

:mod:`bauv_sim.acoustics.sound`: the scenario's ``sound`` section (:class:`SoundSpeedConfig`,
the true medium handed to every acoustic device through ``SensorRig(..., propagation=...)``).
:mod:`bauv_sim.acoustics.clock` (each vehicle's clock: offset, drift, timestamp jitter),
:mod:`bauv_sim.acoustics.sonar` (the passive sonar equation of a modem link: spreading, Thorp
absorption, ambient noise, the probability that a packet is decoded) and
:mod:`bauv_sim.acoustics.network` (the team's acoustic network: one-way and two-way travel-time
ranging on a TDMA schedule, with clocks, motion during the travel, collisions and packet loss).
How sound travels between two points (the ray tracing) is :mod:`nav.acoustics`'
(:class:`~nav.acoustics.Propagation`).
"""

from bauv_sim.acoustics.clock import Clock, ClockConfig
from bauv_sim.acoustics.sonar import (
    SonarConfig,
    noise_psd_db,
    snr_db,
    success_probability,
    thorp_absorption_db_per_km,
    transmission_loss_db,
)
from bauv_sim.acoustics.sound import SoundSpeedConfig, munk_speed, thermocline_preset

__all__ = [
    "Clock",
    "ClockConfig",
    "SonarConfig",
    "SoundSpeedConfig",
    "munk_speed",
    "noise_psd_db",
    "snr_db",
    "success_probability",
    "thermocline_preset",
    "thorp_absorption_db_per_km",
    "transmission_loss_db",
]
