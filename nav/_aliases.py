"""Public names of :mod:`nav` that differ from their names in the module defining them (the
package's ``__init__.pyi`` imports them from here): ``ekf_update``, ``degraded``, ``step`` and
``train`` would be ambiguous at the top of the package."""

from nav.bearings.bank import step as filter_bank_step
from nav.bearings.cmnf import train as train_cmnf
from nav.bearings.filters import ekf_update as bearing_ekf_update
from nav.trn import degraded as degraded_map

__all__ = ["bearing_ekf_update", "degraded_map", "filter_bank_step", "train_cmnf"]
