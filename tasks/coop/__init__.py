"""Cooperative navigation of a team on kinematic truth (issue 24): ``coop/team`` (every method of
:func:`nav.cooperative.team_tracks` on the same draws) and ``coop/sensitivity`` (clock drift,
sound-speed mismatch, packet loss). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure (tasks.core.style), declared before its
# modules, which may read them when imported; DR, GA2 and EKF look as in paper-003 and the
# missions (one look per method everywhere)
declare(
    __name__,
    {
        "DR": MethodStyle(P["vermillion"]),
        "GA2": MethodStyle(P["sky_blue"]),
        "EKF": MethodStyle(P["blue"]),
        "decentralised": MethodStyle(P["bluish_green"], ls="--"),
        "central": MethodStyle(P["black"]),
    },
)

from tasks.coop import team  # noqa: E402

__all__ = ["team"]
