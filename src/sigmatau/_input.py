"""Validation of user data and conversion between phase and frequency.

Conventions (numerics.md §0): phase (time-error) samples ``x_0 … x_{N-1}``,
fractional-frequency samples ``y_i = (x_{i+1} - x_i)/τ0``; frequency to phase
is the cumulative sum with ``x_0 = 0``.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from .errors import DataError, ParameterError

__all__ = [
    "DataType",
    "as_series",
    "check_rate",
    "check_data_type",
    "frequency_to_phase",
    "phase_to_frequency",
    "to_phase",
    "remove_linear_phase",
]

DataType = Literal["freq", "phase"]
_DATA_TYPES = ("freq", "phase")


def as_series(data: object, name: str = "data") -> np.ndarray:
    """Return ``data`` as a finite, 1-D float64 array (a copy is made when needed).

    Raises
    ------
    DataError
        When the data is not numeric, not 1-D, empty or holds NaN/inf.
    """
    try:
        arr = np.asarray(data)
    except Exception:  # ragged lists and the like
        raise DataError(f"{name} cannot be read as a numeric array (ragged or mixed sequence?)") from None
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.number) or np.issubdtype(arr.dtype, np.bool_)
    ):
        raise DataError(f"{name} must be numeric, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.complexfloating):
        raise DataError(f"{name} must be real, got dtype {arr.dtype}")
    if arr.ndim != 1:
        if arr.ndim == 2 and 1 in arr.shape:
            arr = arr.reshape(-1)
        else:
            raise DataError(f"{name} must be 1-D, got shape {arr.shape}")
    if arr.size == 0:
        raise DataError(f"{name} is empty")
    arr = np.asarray(arr, dtype=np.float64)
    finite = np.isfinite(arr)
    if not finite.all():
        bad = int(np.flatnonzero(~finite)[0])
        count = int((~finite).sum())
        raise DataError(
            f"{name} holds {count} non-finite value(s) (first at index {bad}: {float(arr[bad])});"
            " remove or fill them first"
        )
    return arr


def check_rate(rate: object) -> float:
    """Return the sample rate as a positive finite float, or raise ParameterError."""
    # float() would also parse "2", b"2" and True: none of them is a sample rate.
    if isinstance(rate, (str, bytes, bool, np.bool_)):
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)")
    try:
        value = float(rate)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError(f"rate={rate!r} must be a positive finite number (Hz)")
    return value


def check_data_type(data_type: object) -> DataType:
    """Return ``data_type`` if it is "freq" or "phase", else raise ParameterError."""
    if data_type not in _DATA_TYPES:
        raise ParameterError(f"data_type={data_type!r} must be one of {_DATA_TYPES}")
    return data_type  # type: ignore[return-value]


def frequency_to_phase(y: object, *, rate: float = 1.0) -> np.ndarray:
    """Integrate frequency samples into phase: ``x_0 = 0``, ``x_{i+1} = x_i + y_i/rate``.

    Parameters
    ----------
    y : array_like
        Fractional-frequency (or sensor-output) samples, M points.
    rate : float
        Sample rate in Hz (τ0 = 1/rate).

    Returns
    -------
    numpy.ndarray
        M + 1 phase points.
    """
    y = as_series(y, "y")
    tau0 = 1.0 / check_rate(rate)
    x = np.empty(y.size + 1)
    x[0] = 0.0
    np.cumsum(y, out=x[1:])
    x[1:] *= tau0
    return x


def phase_to_frequency(x: object, *, rate: float = 1.0) -> np.ndarray:
    """Differentiate phase into frequency: ``y_i = (x_{i+1} - x_i)·rate`` (N - 1 points)."""
    x = as_series(x, "x")
    return np.diff(x) * check_rate(rate)


def to_phase(data: np.ndarray, rate: float, data_type: DataType) -> np.ndarray:
    """Phase series of already validated data: frequency is integrated, phase passed through."""
    if data_type == "phase":
        return data
    return frequency_to_phase(data, rate=rate)


def remove_linear_phase(x: np.ndarray) -> np.ndarray:
    """Subtract the line through the first and last phase points.

    This removes the mean frequency exactly, which leaves every statistic built
    on second or higher differences unchanged while keeping the phase values,
    and hence round-off, small.
    """
    if x.size < 2:
        return x - x[0]
    ramp = np.linspace(0.0, x[-1] - x[0], x.size)
    return (x - x[0]) - ramp
