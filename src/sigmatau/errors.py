"""Exception and warning hierarchy of sigmatau.

Every error raised on purpose by the library derives from :class:`SigmaTauError`,
so a caller can catch all of them with one ``except`` clause. Errors caused by an
argument are also :class:`ValueError` so that generic code keeps working.
"""

from __future__ import annotations

import os
import sys

__all__ = [
    "SigmaTauError",
    "ParameterError",
    "DataError",
    "MissingDependencyError",
    "SigmaTauWarning",
    "RangeWarning",
]


class SigmaTauError(Exception):
    """Base class of every error raised by sigmatau."""


class ParameterError(SigmaTauError, ValueError):
    """An argument other than the data is invalid (rate, τ grid, keyword...)."""


class DataError(SigmaTauError, ValueError):
    """The data cannot be analysed (NaN, empty, too short, wrong shape...)."""


class MissingDependencyError(SigmaTauError, ImportError):
    """A feature needs an optional package that is not installed (the message names the extra)."""


class SigmaTauWarning(UserWarning):
    """Base class of the warnings issued by sigmatau."""


class RangeWarning(SigmaTauWarning):
    """An averaging factor beyond the statistic's usable range was requested."""


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep


def caller_stacklevel() -> int:
    """The ``stacklevel`` of :func:`warnings.warn` that points at the first frame outside sigmatau.

    Call it from the function that issues the warning: however many layers of
    the package lie between the user's call and that function (a public
    statistic, the engine, a streamed record, the driver), the warning names the
    user's line, not the package's internals.
    """
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level
