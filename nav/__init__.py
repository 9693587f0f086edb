"""nav: the navigation stack (estimators, models, accuracy, guidance, metrics).

Knows nothing of MuJoCo or of :mod:`bauv_sim`: it sees measurements, never truth. Arrays carry a
leading axis of Monte Carlo runs: state ``(n, dim)``, covariance ``(n, dim, dim)``.
"""

import lazy_loader

from nav.errors import NavError as NavError

# the public names: those of __init__.pyi, each imported from its module on first use
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
