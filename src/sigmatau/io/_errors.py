"""Errors and warnings of the readers, all inside sigmatau's one hierarchy."""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import DataError, SigmaTauError, SigmaTauWarning

__all__ = [
    "FormatError",
    "InputNotFoundError",
    "MissingDependencyError",
    "InputWarning",
    "TimingWarning",
    "need",
]


class FormatError(DataError):
    """The file cannot be read as its format: unrecognised, corrupt, truncated or an unsupported layout."""


class InputNotFoundError(DataError, FileNotFoundError):
    """The input path does not exist (also a :class:`FileNotFoundError`)."""


class MissingDependencyError(SigmaTauError, ImportError):
    """Reading this format needs an optional package that is not installed."""


class InputWarning(SigmaTauWarning):
    """Something in the input was repaired or assumed; the message says what."""


class TimingWarning(InputWarning):
    """Timestamps were sorted or de-duplicated, or they disagree with the declared rate."""


def need(module: str, *, extra: str, package: str, what: str) -> ModuleType:
    """Import an optional dependency or raise :class:`MissingDependencyError` naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependencyError(
            f"reading {what} needs the optional package {package!r}, which is not installed;"
            f" install it with: pip install 'sigmatau[{extra}]'"
        ) from None
