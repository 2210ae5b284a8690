"""Exception and warning hierarchy of sigmatau.

Every error raised on purpose by the library derives from :class:`SigmaTauError`,
so a caller can catch all of them with one ``except`` clause. Errors caused by an
argument are also :class:`ValueError` so that generic code keeps working.
"""

from __future__ import annotations

__all__ = [
    "SigmaTauError",
    "ParameterError",
    "DataError",
    "SigmaTauWarning",
    "RangeWarning",
]


class SigmaTauError(Exception):
    """Base class of every error raised by sigmatau."""


class ParameterError(SigmaTauError, ValueError):
    """An argument other than the data is invalid (rate, τ grid, keyword...)."""


class DataError(SigmaTauError, ValueError):
    """The data cannot be analysed (NaN, empty, too short, wrong shape...)."""


class SigmaTauWarning(UserWarning):
    """Base class of the warnings issued by sigmatau."""


class RangeWarning(SigmaTauWarning):
    """An averaging factor beyond the statistic's usable range was requested."""
