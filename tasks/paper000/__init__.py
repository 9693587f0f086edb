"""Seed 000 (Naus & Nowak 2016): ``paper-000/test-1..3`` (straight passage: DR, EKF with USBL,
USBL alone) and ``paper-000/accuracy`` (analytic USBL and DR accuracy). Importing registers them."""

from tasks.core.style import PALETTE as P
from tasks.core.style import MethodStyle, declare

# the looks of this package's methods in every figure and recording (tasks.core.style),
# declared before its modules, which may read them when imported
declare(
    __name__,
    {
        "DR": MethodStyle(P["vermillion"]),
        "EKF": MethodStyle(P["blue"]),
        "USBL": MethodStyle(P["bluish_green"], ls="none", marker="."),
    },
)

from tasks.paper000 import accuracy, passage  # noqa: E402

__all__ = ["accuracy", "passage"]
