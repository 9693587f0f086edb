"""Underwater acoustics experiments (issue 24): ``acoustics/sound-speed``, what a sound-speed
mismatch costs the USBL and the modem. Importing registers it."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's navigators in every figure (tasks.core.style), declared before its
# modules, which may read them when imported
declare(
    __name__,
    {
        "nominal": MethodStyle(P["vermillion"]),
        "harmonic": MethodStyle(P["orange"], ls="--"),
        "profile": MethodStyle(P["blue"]),
    },
)

from tasks.acoustics import sound_speed  # noqa: E402

__all__ = ["sound_speed"]
