"""Underwater acoustics experiments (issue 24): ``acoustics/sound-speed``, what a sound-speed
mismatch costs the USBL and the modem. Importing registers it."""

from tasks.acoustics import sound_speed

__all__ = ["sound_speed"]
