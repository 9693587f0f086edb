"""The sea's acoustics for the simulated devices: the sound-speed profile the sound travels in.

:mod:`bauv_sim.acoustics.sound`: the scenario's ``sound`` section (:class:`SoundSpeedConfig`,
the true medium handed to every acoustic device through ``SensorRig(..., propagation=...)``).
The ray tracing itself is navigation-side knowledge and lives in :mod:`nav.acoustics`.
"""

from bauv_sim.acoustics.sound import SoundSpeedConfig, munk_speed, thermocline_preset

__all__ = ["SoundSpeedConfig", "munk_speed", "thermocline_preset"]
