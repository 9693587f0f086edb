"""Alias of :mod:`nav.bearings.local_control`: the module moved into seed 004's package; this name
stays importable and is the same module object."""

import sys

from nav.bearings import local_control as _module

sys.modules[__name__] = _module
