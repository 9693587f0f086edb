"""Underwater acoustics the navigation needs: how sound travels between two points.

:mod:`nav.acoustics.propagation` defines what a medium answers (:class:`Propagation`: the
eigenray between a source and a receiver, with its travel time and its angles) and the
isovelocity medium (straight rays at one speed); :mod:`nav.acoustics.profile` the sound-speed
profile (Mackenzie 1981); :mod:`nav.acoustics.rays` the layered medium (eigenrays through a
piecewise-linear profile); :mod:`nav.acoustics.inversion` travel times back to ranges and
positions with the profile known. Both the devices of :mod:`bauv_sim` (which
sample travel times from the true medium) and the filters (which turn a measured travel time
back into a range with the medium they assume) use it: it lives in ``nav`` because ``nav``
cannot import ``bauv_sim``.
"""

from nav.acoustics.inversion import range_from_travel_time, source_from_arrival
from nav.acoustics.profile import SoundSpeedProfile, mackenzie_speed
from nav.acoustics.propagation import Eigenray, Isovelocity, Propagation
from nav.acoustics.rays import LayeredMedium

__all__ = [
    "Eigenray",
    "Isovelocity",
    "LayeredMedium",
    "Propagation",
    "SoundSpeedProfile",
    "mackenzie_speed",
    "range_from_travel_time",
    "source_from_arrival",
]
