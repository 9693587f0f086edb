"""The acoustics of the simulated sea: clocks, the sonar equation and the acoustic network.

:mod:`bauv_sim.acoustics.clock` (each vehicle's clock: offset, drift, timestamp jitter),
:mod:`bauv_sim.acoustics.sonar` (the passive sonar equation of a modem link: spreading, Thorp
absorption, ambient noise, the probability that a packet is decoded) and
:mod:`bauv_sim.acoustics.network` (the team's acoustic network: one-way and two-way travel-time
ranging on a TDMA schedule, with clocks, motion during the travel, collisions and packet loss).
How sound travels between two points is :mod:`nav.acoustics`' (:class:`~nav.acoustics.
Propagation`).
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

__all__ = [
    "Clock",
    "ClockConfig",
    "SonarConfig",
    "noise_psd_db",
    "snr_db",
    "success_probability",
    "thorp_absorption_db_per_km",
    "transmission_loss_db",
]
