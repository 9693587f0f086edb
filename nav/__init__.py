"""nav: the navigation stack (estimators, models, accuracy, guidance, metrics).

Knows nothing of MuJoCo or of :mod:`bauv_sim`: it sees measurements, never truth. Arrays carry a
leading axis of Monte Carlo runs: state ``(n, dim)``, covariance ``(n, dim, dim)``.
"""

from nav.errors import NavError

__all__ = ["NavError"]
