"""The seabed shift's C library (``nav/seabed/seabed_shift.c``), bound through :mod:`nav.clib`:
``bauv_seabed_fit`` (Appendix A's slope fit) and ``bauv_seabed_shift`` (eq. 12-15 with the
stated covariance), each taking its struct of ``nav/clib.h`` (:class:`nav.clib.SeabedFitArgs`,
:class:`nav.clib.SeabedShiftArgs`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from nav import clib

LIBRARY = "_seabed_shift"
"""The C library of :func:`nav.seabed.fit_slopes` and :func:`nav.seabed.shift_estimate`
(``seabed_shift.c``, built beside this module by ``pip install``, see ``setup.py``)."""

STATUS = {
    -1: "out of memory",
    -2: "a basis the C fit does not take (more than FIT_MAX functions, harmonics < 1)",
    -3: "a buffer shorter than its shape (paths, beams) says",
}
"""The refusals of ``seabed_shift.c`` (its entry points' negative return values)."""


@dataclass(frozen=True)
class ShiftLibrary:
    """The two entry points of ``seabed_shift.c``.

    Attributes:
        fit: ``bauv_seabed_fit``, called with a :class:`nav.clib.SeabedFitArgs`.
        shift: ``bauv_seabed_shift``, called with a :class:`nav.clib.SeabedShiftArgs`.
    """

    fit: Callable[[clib.SeabedFitArgs], int]
    shift: Callable[[clib.SeabedShiftArgs], int]


@functools.cache
def library() -> ShiftLibrary:
    """The entry points, their structs' layouts checked (loaded once per process, on first use).

    Raises:
        NavError: if the library is not built or its structs differ from :mod:`nav.clib`'s.
    """
    lib = clib.load_library(Path(__file__).parent, LIBRARY)
    return ShiftLibrary(
        clib.entry_point(lib, "bauv_seabed_fit", clib.SeabedFitArgs),
        clib.entry_point(lib, "bauv_seabed_shift", clib.SeabedShiftArgs),
    )
