"""The online navigator of one vehicle, and the navigators built from it.

* :mod:`nav.navigator.online`: :class:`OnlineNavigator` (any estimator, late measurements at
  their time of validity, gate and lock-out, DR beside it), :class:`Navigator` (seed 000's EKF in
  one call) and :class:`Measurement` (a value with its measurement model: what the navigator
  fuses);
* :mod:`nav.navigator.follower`: :class:`BroadcastRangeNavigator`, a follower navigating on ranges
  to another vehicle's broadcast position with seed 003's GA fixes or the range EKF
  (:mod:`nav.relative`), and its typed :class:`FollowerReport`;
* :mod:`nav.navigator.batch`: :class:`BatchNavigator`, the online navigator of many runs that
  tick together (late fixes per run, gate, lock-out, DR), vectorised.
"""

import lazy_loader

# the public names: those of __init__.pyi, each imported from its module on first use (a mission
# flying the online navigator does not import the batch and follower navigators)
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
