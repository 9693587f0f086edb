"""Terrain-relative navigation experiments (issue 23): ``trn/relief``, the kinematic Monte Carlo
of TRN error against the terrain's relief and the map's error. Importing registers it."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure (tasks.core.style), declared before its
# modules, which may read them when imported; the same names and looks as mission/trn's (and
# paper-004's PCRB): a method has one look everywhere
declare(
    __name__,
    {
        "DR-DVL": MethodStyle(P["orange"]),
        "TRN-PF": MethodStyle(P["blue"]),
        "TRN-PMF": MethodStyle(P["sky_blue"], ls="-."),
        "PCRB": MethodStyle(P["black"], ls=":"),
    },
)

from tasks.trn import relief  # noqa: E402

__all__ = ["relief"]
