"""Errors and warnings of the readers, all inside sigmatau's one hierarchy."""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import DataError, MissingDependencyError, SigmaTauWarning

__all__ = [
    "FormatError",
    "InputNotFoundError",
    "MissingDependencyError",
    "InputWarning",
    "TimingWarning",
    "require_optional",
    "option_hint",
    "repr_kw",
]


class FormatError(DataError):
    """The file cannot be read as its format: unrecognised, corrupt, truncated or an unsupported layout."""


class InputNotFoundError(DataError, FileNotFoundError):
    """The input path does not exist (also a :class:`FileNotFoundError`)."""


class InputWarning(SigmaTauWarning):
    """Something in the input was repaired or assumed; the message says what."""


class TimingWarning(InputWarning):
    """Timestamps were sorted or de-duplicated, or they disagree with the declared rate."""


def require_optional(module: str, *, extra: str, package: str, what: str) -> ModuleType:
    """Import an optional dependency or raise :class:`MissingDependencyError` naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependencyError(
            f"reading {what} needs the optional package {package!r}, which is not installed;"
            f" install it with: pip install 'sigmatau[{extra}]'"
        ) from None


def option_hint(cli: str, python: str) -> str:
    """How to set an option, for a message read on the command line or in Python.

    >>> option_hint("--gaps split", "gaps='split'")
    "--gaps split (gaps='split' in Python)"
    """
    return f"{cli} ({python} in Python)"


def repr_kw(name: str, value: object) -> str:
    """A keyword argument as Python code: ``repr_kw("gaps", "split")`` is ``gaps='split'``."""
    return f"{name}={value!r}"
