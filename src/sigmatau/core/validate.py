"""Validation of user data and conversion between phase and frequency.

Conventions (numerics.md §0): phase (time-error) samples ``x_0 … x_{N-1}``,
fractional-frequency samples ``y_i = (x_{i+1} - x_i)/τ0``; frequency to phase
is the cumulative sum with ``x_0 = 0``.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from ..errors import DataError, ParameterError
from .accel import fused_for
from .shared import memoized

__all__ = [
    "DataType",
    "RATE_RANGE",
    "as_series",
    "scale_to_unit",
    "unscale_variance",
    "check_rate",
    "check_data_type",
    "frequency_to_phase",
    "phase_to_frequency",
    "to_phase",
    "remove_linear_phase",
]

DataType = Literal["freq", "phase"]
_DATA_TYPES = ("freq", "phase")

#: Accepted sample rates in Hz (far beyond any real sensor or clock). Inside it τ0 = 1/rate,
#: every τ of a grid (at most N·τ0), τ² and 1/τ² stay far inside float64's normal range, and so
#: does the phase integrated from frequency data scaled near 1 by the driver (|x| ≤ N·τ0) for
#: records of up to 1e14 points, even inside float32 (≤ 3.4e38), which the total-deviation
#: kernels use to round a slope.
RATE_RANGE = (1e-24, 1e24)

#: Largest integer magnitude that converts to float64 exactly.
_EXACT_INT = 2**53


def as_series(data: object, name: str = "data", *, remove_offset: bool = False, gaps: bool = False) -> np.ndarray:
    """Return ``data`` as a finite, 1-D float64 array (a copy is made when needed).

    Parameters
    ----------
    data : array_like
        The samples. A numpy masked array is accepted only when nothing is masked.
    name : str
        How messages call the data.
    remove_offset : bool
        For the statistics that ignore a constant added to the data: integer data
        beyond ±2**53 (Unix-epoch nanoseconds, say) are returned as their exact
        difference from the first value, correctly rounded to float64, instead of
        being rounded value by value (which loses every digit below 2**11 and can
        leave nothing of the noise). Any other data are only cast.
    gaps : bool
        Accept missing samples: NaN, and the masked values of a numpy masked
        array (returned as NaN), the statistics' convention for gaps
        (:mod:`sigmatau.core.gaps`). Infinite values are refused all the same.

    Raises
    ------
    DataError
        When the data is not numeric, not 1-D, empty, holds inf, NaN or masked
        values (NaN and masked values are accepted with ``gaps=True``, unless
        every sample is missing).
    """
    if isinstance(data, np.ma.MaskedArray):
        data = _gaps_filled(data) if gaps else _unmasked(data, name)
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
    if remove_offset and _beyond_exact_float(arr):
        return _exact_offset_free(arr)
    arr = np.asarray(arr, dtype=np.float64)
    fast = fused_for(arr.size)
    if fast is not None and memoized(arr, ("all-finite",), lambda: fast.all_finite(arr)):
        return arr  # the common case: no mask of the record's size (and once per record in a scope)
    finite = np.isfinite(arr)
    if gaps and not finite.all():
        _check_gaps(arr, finite, name)
    elif not finite.all():
        bad = int(np.flatnonzero(~finite)[0])
        count = int((~finite).sum())
        raise DataError(
            f"{name} holds {count} non-finite value(s) (first at index {bad}: {float(arr[bad])});"
            " remove or fill them first"
        )
    return arr


def _check_gaps(arr: np.ndarray, finite: np.ndarray, name: str) -> None:
    """Refuse infinite values and a record in which every sample is missing."""
    inf = np.isinf(arr)
    if inf.any():
        bad = int(np.flatnonzero(inf)[0])
        raise DataError(
            f"{name} holds {int(inf.sum())} infinite value(s) (first at index {bad}: {float(arr[bad])});"
            " a missing sample is NaN, an infinite one is an error in the data"
        )
    if not finite.any():
        raise DataError(f"{name}: every one of its {arr.size} samples is missing (NaN)")


def _gaps_filled(data: np.ma.MaskedArray) -> np.ndarray:
    """The data of a masked array as float64 with NaN at the masked values (gaps)."""
    mask = np.ma.getmaskarray(data)
    values = np.ma.getdata(data)
    if not mask.any():
        return values
    out = np.array(values, dtype=np.float64)
    out[mask] = np.nan
    return out


def _unmasked(data: np.ma.MaskedArray, name: str) -> np.ndarray:
    """The data of a masked array in which nothing is masked; masked values are refused."""
    mask = np.ma.getmaskarray(data)
    if mask.any():
        first = int(np.flatnonzero(mask.ravel())[0])
        raise DataError(
            f"{name} is a masked array with {int(mask.sum())} masked value(s) (first at flat index {first});"
            " remove or fill them first (numpy.ma.compressed or .filled)"
        )
    return np.ma.getdata(data)


def _beyond_exact_float(arr: np.ndarray) -> bool:
    """Integer data holding a value that float64 cannot represent exactly."""
    if not np.issubdtype(arr.dtype, np.integer):
        return False
    return int(arr.max()) > _EXACT_INT or int(arr.min()) < -_EXACT_INT


def _exact_offset_free(arr: np.ndarray) -> np.ndarray:
    """``arr − arr[0]`` of 1-D integer data, each value correctly rounded to float64.

    The values are mapped order-preserving onto uint64 (signed ones by flipping the
    sign bit, i.e. adding 2**63) and split into 32-bit halves, u = h·2**32 + l, so
    ``u − u0 = (h − h0)·2**32 + (l − l0)``: both differences are exact in int64, the
    product by 2**32 is exact in float64, and the one addition rounds once. Works
    for any range, even one spanning the whole of int64 or uint64.
    """
    if np.issubdtype(arr.dtype, np.signedinteger):
        u = arr.astype(np.int64).view(np.uint64) ^ np.uint64(1 << 63)
    else:
        u = arr.astype(np.uint64)
    hi = (u >> np.uint64(32)).astype(np.int64)
    lo = (u & np.uint64(0xFFFFFFFF)).astype(np.int64)
    return np.ldexp((hi - hi[0]).astype(np.float64), 32) + (lo - lo[0]).astype(np.float64)


def scale_to_unit(v: np.ndarray) -> tuple[np.ndarray, int]:
    """``(v·2**-k, k)`` with the largest ``|v·2**-k|`` in [0.5, 1) (``k = 0`` for all zeros).

    Every statistic is homogeneous of degree two in the data, var(c·x) = c²·var(x),
    so the kernels run on the scaled series and :func:`unscale_variance` multiplies
    by 4**k afterwards. A power of two changes no digit (``numpy.ldexp`` is exact for
    normal and subnormal values alike), so the scaled series holds exactly the
    user's numbers, and no square or sum of squares of data near 1e±300 can
    overflow or underflow on the way.
    """
    fast = fused_for(v.size) if v.dtype == np.float64 and v.ndim == 1 else None
    if fast is not None:  # the same maximum, without |v| as a temporary of the record's size
        peak = fast.abs_peak(v)
    else:
        peak = float(np.nanmax(np.abs(v))) if v.size else 0.0  # NaN: a missing sample (gap)
    if peak == 0.0:
        return v, 0
    k = math.frexp(peak)[1]
    if k == 0:  # already in [0.5, 1): the samples themselves (validated data: no record-sized copy)
        return v, 0
    return np.ldexp(v, -k), k


def unscale_variance(var: np.ndarray, k: int, name: str) -> np.ndarray:
    """``var·4**k`` (exact), refusing a variance that float64 cannot hold.

    Raises
    ------
    DataError
        When a non-zero variance would overflow to inf or fall below the smallest
        normal float64 (≈ 2.2e-308, where it would lose digits or become 0).
    """
    var = np.asarray(var, dtype=np.float64)
    with np.errstate(over="ignore", under="ignore"):  # checked just below
        out = np.ldexp(var, 2 * k)
    tiny = np.finfo(np.float64).tiny
    bad = (var != 0.0) & ~(np.isfinite(out) & (np.abs(out) >= tiny))
    if bad.any():
        v = float(var[np.flatnonzero(bad)[0]])
        exponent = math.log10(abs(v)) + 2 * k * math.log10(2.0) if v != 0.0 and math.isfinite(v) else float("nan")
        raise DataError(
            f"{name}: the variance of these data (about 1e{exponent:+.0f}) is outside float64's range"
            " (1e-308 … 1e+308); rescale the data (another unit) so that the deviation lies within"
            " about 1e-154 … 1e+154"
        )
    return out


def check_rate(rate: object) -> float:
    """Return the sample rate as a positive finite float within :data:`RATE_RANGE`.

    Raises
    ------
    ParameterError
        For anything else (strings and booleans included).
    """
    # float() would also parse "2", b"2" and True: none of them is a sample rate.
    if isinstance(rate, (str, bytes, bool, np.bool_)):
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)")
    try:
        value = float(rate)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"rate={rate!r} must be a positive number (Hz)") from None
    if not math.isfinite(value) or value <= 0.0:
        raise ParameterError(f"rate={rate!r} must be a positive finite number (Hz)")
    low, high = RATE_RANGE
    if not low <= value <= high:
        # Beyond it τ² or 1/τ² over the τ grid could overflow or underflow in float64.
        raise ParameterError(f"rate={rate!r} must be a positive number within {low:g} … {high:g} Hz")
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

    Raises
    ------
    DataError
        When a phase value overflows float64 or falls below its normal range
        (where it would lose digits or become 0).
    """
    y = as_series(y, "y")
    tau0 = 1.0 / check_rate(rate)
    x = np.empty(y.size + 1)
    x[0] = 0.0
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # checked below
        np.cumsum(y, out=x[1:])
        sums = x[1:].copy()
        x[1:] *= tau0
    _check_representable(x, np.concatenate(([0.0], sums)), "frequency_to_phase", "phase")
    return x


def phase_to_frequency(x: object, *, rate: float = 1.0) -> np.ndarray:
    """Differentiate phase into frequency: ``y_i = (x_{i+1} - x_i)·rate`` (N - 1 points).

    Raises
    ------
    DataError
        When a frequency value overflows float64 or falls below its normal range.
    """
    x = as_series(x, "x")
    rate_f = check_rate(rate)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # checked below
        d = np.diff(x)
        y = d * rate_f
    _check_representable(y, d, "phase_to_frequency", "frequency")
    return y


def _check_representable(out: np.ndarray, source: np.ndarray, func: str, what: str) -> None:
    """Refuse ``out`` where it is inf/NaN, or where a ``source`` value that matters at double
    precision (≥ eps·max|source|) became subnormal or 0 (its digits lost)."""
    info = np.finfo(np.float64)
    mag = np.abs(source)
    peak = float(mag.max()) if mag.size else 0.0
    lost = (mag != 0.0) & (np.abs(out) < info.tiny) & (mag >= info.eps * peak)
    bad = ~np.isfinite(out) | lost
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise DataError(
            f"{func}: the {what} at index {i} ({float(out[i])}) is outside float64's range"
            " (about 2.2e-308 … 1.8e+308); rescale the data (another unit) first"
        )


def to_phase(data: np.ndarray, rate: float, data_type: DataType) -> np.ndarray:
    """Phase series of already validated data: frequency is integrated, phase passed through.

    Unlike :func:`frequency_to_phase` nothing is checked again: the driver hands in data
    scaled near 1 and a rate within :data:`RATE_RANGE`, so no phase value can overflow.
    """
    if data_type == "phase":
        return data
    x = np.empty(data.size + 1)
    x[0] = 0.0
    np.cumsum(data, out=x[1:])
    x[1:] *= 1.0 / rate
    return x


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
