"""Exceptions raised by :mod:`nav`."""


class NavError(Exception):
    """Base class of every error raised by :mod:`nav`."""


class NavInputError(NavError, ValueError):
    """An estimator received input it cannot use (the message says which and why)."""


class FilterDivergedError(NavError, RuntimeError):
    """A filter's covariance lost positive definiteness or its state became non-finite."""
