"""Checks of a stream's options and of each chunk, before anything is changed.

Every refusal is one :class:`~sigmatau.errors.ParameterError` (an option) or
:class:`~sigmatau.errors.DataError` (a chunk) whose message names what is wrong
and what is allowed; a refused chunk leaves the stream as it was.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import DataError, ParameterError
from .results import STATISTICS

__all__ = ["STREAMABLE", "NOT_STREAMABLE", "check_statistics", "check_taus", "check_max_m", "check_channels",
           "as_chunk"]

#: Statistics a stream computes, in the design tip's order.
STREAMABLE: tuple[str, ...] = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev")

#: Why the other statistics cannot be streamed in memory bounded by the longest τ.
NOT_STREAMABLE: dict[str, str] = {
    "stdev": "not implemented as a stream (the block means would stream with running moments)",
    "ostdev": "not implemented as a stream",
    "mhdev": "not implemented as a stream (its terms would stream like MDEV's)",
    "ldev": "not implemented as a stream (its terms would stream like MDEV's)",
    "pdev": "not implemented as a stream",
    "mtotdev": "each 3m-point subsequence is detrended and reflected on its own; not implemented as a stream",
    "ttotdev": "each 3m-point subsequence is detrended and reflected on its own; not implemented as a stream",
    "htotdev": "each 3m-point subsequence is detrended and reflected on its own; not implemented as a stream",
    "mhtotdev": "each subsequence is detrended and reflected on its own; not implemented as a stream",
    "theo1": "its τ reach 75 % of the record, so its spans grow with N: O(N) memory",
    "theobr": "Theo1's τ reach 75 % of the record, so its spans grow with N: O(N) memory",
    "theoh": "Theo1's τ reach 75 % of the record, so its spans grow with N: O(N) memory",
    "mtie": "it needs the extremes of every window at every τ over the record; not implemented as a stream",
    "tierms": "it is not invariant to the frequency offset a stream removes; not implemented as a stream",
}

_EXACT_INT = 2**53


def check_statistics(statistics: object) -> tuple[str, ...]:
    """The requested statistics as a tuple of distinct streamable names, in the order given."""
    names = (statistics,) if isinstance(statistics, str) else statistics
    try:
        names = tuple(names)  # type: ignore[arg-type]
    except TypeError:
        raise ParameterError(f"statistics={statistics!r} must be a name or a sequence of names") from None
    if not names:
        raise ParameterError(f"statistics is empty; choose among {', '.join(STREAMABLE)}")
    out: list[str] = []
    for name in names:
        check_name(name)
        if name not in out:
            out.append(name)
    return tuple(out)


def check_name(name: object) -> str:
    """A streamable statistic's name, or the ParameterError that lists them (and says why not)."""
    if isinstance(name, str) and name in STATISTICS:
        return name
    why = f" ({NOT_STREAMABLE[name]})" if isinstance(name, str) and name in NOT_STREAMABLE else ""
    raise ParameterError(f"{name!r} cannot be streamed{why}; the streamable statistics are {', '.join(STREAMABLE)}")


def check_taus(taus: object) -> str:
    """Only the octave grid: its factors for N points are a prefix of those for more points."""
    if taus != "octave":
        raise ParameterError(
            f"taus={taus!r}: a stream computes the octave grid only (m = 1, 2, 4 … up to max_m); the"
            " 'log' grid moves with N, and other grids would need window sums at every factor")
    return "octave"


def check_max_m(max_m: object) -> int:
    """The largest averaging factor: an integer ≥ 2."""
    if isinstance(max_m, (bool, np.bool_)) or not isinstance(max_m, (int, np.integer)) or max_m < 2:
        raise ParameterError(f"max_m={max_m!r} must be an integer ≥ 2 (the largest averaging factor)")
    if max_m > 2**40:
        raise ParameterError(f"max_m={max_m!r} is beyond 2**40: the state (about 100 bytes per unit) would not fit")
    return int(max_m)


def check_channels(channels: object) -> Optional[int]:
    """None (taken from the first chunk) or a positive number of channels."""
    if channels is None:
        return None
    if isinstance(channels, (bool, np.bool_)) or not isinstance(channels, (int, np.integer)) or channels < 1:
        raise ParameterError(f"channels={channels!r} must be a positive integer or None")
    return int(channels)


def as_chunk(chunk: object, channels: Optional[int]) -> np.ndarray:
    """The chunk as a finite float64 array of shape ``(samples, channels)`` (0 samples allowed).

    Raises
    ------
    DataError
        Non-numeric, complex, masked, not 1-D/2-D, another number of channels, integers beyond
        ±2**53 (which float64 would round), NaN or infinite values.
    """
    if isinstance(chunk, np.ma.MaskedArray):
        if np.ma.getmaskarray(chunk).any():
            raise DataError("the chunk is a masked array with masked values; a stream takes no gaps")
        chunk = np.ma.getdata(chunk)
    try:
        arr = np.asarray(chunk)
    except Exception:  # ragged lists and the like
        raise DataError("the chunk cannot be read as a numeric array (ragged or mixed sequence?)") from None
    if arr.dtype == object or not (np.issubdtype(arr.dtype, np.number) or np.issubdtype(arr.dtype, np.bool_)):
        raise DataError(f"the chunk must be numeric, got dtype {arr.dtype}")
    if np.issubdtype(arr.dtype, np.complexfloating):
        raise DataError(f"the chunk must be real, got dtype {arr.dtype}")
    arr = _two_dimensional(arr, channels)
    if np.issubdtype(arr.dtype, np.integer) and arr.size and (int(arr.max()) > _EXACT_INT or int(arr.min()) < -_EXACT_INT):
        raise DataError("the chunk holds integers beyond ±2**53, which float64 would round; subtract an offset first")
    arr = np.asarray(arr, dtype=np.float64)
    finite = np.isfinite(arr)
    if not finite.all():
        row, col = (int(v) for v in np.argwhere(~finite)[0])
        raise DataError(
            f"the chunk holds {int((~finite).sum())} non-finite value(s) (first at sample {row}, channel {col}:"
            f" {float(arr[row, col])}); a stream takes no gaps (NaN) or infinite values: fill or remove them, or"
            " analyse the record in memory, where NaN marks a gap")
    return arr


def _two_dimensional(arr: np.ndarray, channels: Optional[int]) -> np.ndarray:
    """``(samples, channels)``: a 1-D chunk is one channel's samples."""
    if arr.ndim == 1:
        arr = arr[:, None]
    elif arr.ndim != 2:
        raise DataError(f"the chunk must be 1-D (samples) or 2-D (samples, channels), got shape {arr.shape}")
    if channels is not None and arr.shape[1] != channels:
        raise DataError(f"the chunk has {arr.shape[1]} channel(s), shape {arr.shape}; this stream has {channels}")
    if arr.shape[1] == 0:
        raise DataError(f"the chunk has no channel, shape {arr.shape}")
    return arr
