"""The two kinds of failure softclose reports to a user.

``ConfigError`` is bad input (exit code 2); ``NumericalError`` is a numerical or
optimiser failure that was detected and explained (exit code 3). Both carry a
one-line message meant to be printed as it is.
"""


class SoftcloseError(Exception):
    """Base class: a failure with a one-line, user-facing message."""

    exit_code = 1


class ConfigError(SoftcloseError, ValueError):
    """Invalid input: names the offending key or option."""

    exit_code = 2


class NumericalError(SoftcloseError, RuntimeError):
    """A detected numerical failure, with what to change."""

    exit_code = 3
