"""Underwater acoustics the navigation needs: how sound travels between two points.

:mod:`nav.acoustics.propagation` defines what a medium answers (:class:`Propagation`: the
eigenray between a source and a receiver, with its travel time and its angles) and the
isovelocity medium (straight rays at one speed). Both the devices of :mod:`bauv_sim` (which
sample travel times from the true medium) and the filters (which turn a measured travel time
back into a range with the medium they assume) use it: it lives in ``nav`` because ``nav``
cannot import ``bauv_sim``.
"""

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
]
