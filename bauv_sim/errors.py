"""Exceptions raised by :mod:`bauv_sim`.

Every error carries a message a user can act on: what was expected and what was received.
"""


class BauvSimError(Exception):
    """Base class of every error raised by :mod:`bauv_sim`."""


class ConfigError(BauvSimError, ValueError):
    """A scenario, model or command-line value is invalid.

    The message names the field, the value received and what is allowed.
    """


class PhysicsError(BauvSimError, RuntimeError):
    """The physics became unstable (divergence, non-finite state) or MuJoCo raised a warning.

    The message says the simulation time and what went wrong.
    """


class GeometryError(BauvSimError, ValueError):
    """A requested geometry is impossible (e.g. a vehicle below the seabed)."""
