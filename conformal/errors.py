"""Exceptions with messages meant for the user: the CLI prints them as one line and exits 2."""


class ConformalError(Exception):
    """Base class of every error that the CLI reports as one readable line."""


class InputError(ConformalError, ValueError):
    """Bad input: a scene key, a profile file, a value out of range."""


class NoContactError(ConformalError):
    """The bodies do not touch (the message gives the smallest gap)."""


class ConvergenceError(ConformalError):
    """An iterative solver did not converge (the message gives the residual)."""


#: exit status of a command whose solves did not all converge (its outputs are written and say
#: ``"converged": false``); ``--allow-unconverged`` turns it into 0
EXIT_UNCONVERGED = 3


def unconverged_exit(what: str, allow: bool, stream=None, where: str = '"converged": false in the output') -> int:
    """Report on ``stream`` (default: stderr) that ``what`` did not converge (``where`` the outputs
    say so) and return the exit status: :data:`EXIT_UNCONVERGED`, or 0 with ``allow`` (the command's ``--allow-unconverged``).

    >>> import io
    >>> s = io.StringIO()
    >>> unconverged_exit("case 2", False, s), s.getvalue().strip()
    (3, 'conformal: error: case 2 did not converge ("converged": false in the output): exit status 3; --allow-unconverged accepts it')
    >>> unconverged_exit("case 2", True, io.StringIO())
    0
    """
    import sys

    how = "accepted (--allow-unconverged)" if allow else "exit status 3; --allow-unconverged accepts it"
    print(f"conformal: {'warning' if allow else 'error'}: {what} did not converge ({where}): {how}",
          file=stream if stream is not None else sys.stderr)
    return 0 if allow else EXIT_UNCONVERGED
