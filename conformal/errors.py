"""Exceptions with messages meant for the user: the CLI prints them as one line and exits 2."""


class ConformalError(Exception):
    """Base class of every error that the CLI reports as one readable line."""


class InputError(ConformalError, ValueError):
    """Bad input: a scene key, a profile file, a value out of range."""


class NoContactError(ConformalError):
    """The bodies do not touch (the message gives the smallest gap)."""


class ConvergenceError(ConformalError):
    """An iterative solver did not converge (the message gives the residual)."""
