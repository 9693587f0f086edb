"""Alias of :mod:`nav.bearings.cmnf`: the module moved into seed 004's package; this name
stays importable and is the same module object."""

import sys

from nav.bearings import cmnf as _module

sys.modules[__name__] = _module
