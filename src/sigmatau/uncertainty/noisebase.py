"""Shared pieces of noise identification: noise names, the too-few-points error, argument checks.

Split out of :mod:`sigmatau.uncertainty.noiseid` so that the lag-1, B1/R(n),
decision and fit modules can share them without importing each other.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..core.present import NOISE_NAMES
from ..errors import DataError, ParameterError

Family = Literal["allan", "modified", "hadamard", "total", "theo"]


class InsufficientDataError(DataError):
    """Too few points remain at this averaging factor for the requested method.

    Raised by :func:`lag1_acf_noise_id` (fewer than 30 points) and
    :func:`b1_noise_id` (fewer than 3 averages); :func:`identify` catches it and
    falls back to the next method.
    """


# --------------------------------------------------------------------------- checks


def _check_m(m: object, name: str = "m") -> int:
    """An averaging factor: a positive integer (an integral float is accepted)."""
    if isinstance(m, (bool, np.bool_)) or not isinstance(m, (int, np.integer)):
        if isinstance(m, (float, np.floating)) and float(m).is_integer():
            m = int(m)
        else:
            raise ParameterError(f"{name}={m!r} must be a positive integer averaging factor")
    if m < 1:
        raise ParameterError(f"{name}={m!r} must be a positive integer averaging factor")
    return int(m)


def _check_count(value: object, name: str) -> int:
    """A number of terms: an integer ≥ 1 (0 and 1 leave the default N in place)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ParameterError(f"{name}={value!r} must be a non-negative integer number of terms")
    return int(value)


def _check_d(dmin: object, dmax: object) -> tuple[int, int]:
    """The fewest and most differences of the lag-1 method: ``0 ≤ dmin ≤ dmax``."""
    for name, value in (("dmin", dmin), ("dmax", dmax)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ParameterError(f"{name}={value!r} must be a non-negative integer")
    if dmin > dmax:  # type: ignore[operator]
        raise ParameterError(f"dmin={dmin!r} must not exceed dmax={dmax!r}")
    return int(dmin), int(dmax)  # type: ignore[arg-type]


def _frequency(data: np.ndarray, data_type: str) -> np.ndarray:
    """Frequency samples up to a constant factor (τ0 cancels in every ratio here)."""
    return np.diff(data) if data_type == "phase" else data

