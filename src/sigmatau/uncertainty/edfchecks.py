"""Argument checks shared by the EDF modules (:mod:`.greenhall`, :mod:`.empirical_edf`, :mod:`.confidence`)."""

from __future__ import annotations

from typing import Literal

from ..errors import ParameterError

Version = Literal["full", "simplified"]


def _check_alpha(alpha: object) -> int:
    """A noise exponent: an integer (or integral float) in −4 … 2."""
    try:
        value = float(alpha)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"alpha={alpha!r} must be an integer in -4 ... 2") from None
    if not value.is_integer() or not -4 <= value <= 2:
        raise ParameterError(f"alpha={alpha!r} must be an integer in -4 ... 2")
    return int(value)


def _check_int(value: object, name: str, minimum: int) -> int:
    """An integer (or integral float) argument of at least ``minimum``."""
    try:
        as_float = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}") from None
    if not as_float.is_integer() or as_float < minimum:
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}")
    return int(as_float)


def _check_version(version: object) -> str:
    """The Greenhall algorithm variant, ``"full"`` or ``"simplified"``."""
    if version not in ("full", "simplified"):
        raise ParameterError(f"version={version!r} must be 'full' or 'simplified'")
    return str(version)
