"""Editing steps: fill gaps, keep a part of the record, average (decimate) it."""

from __future__ import annotations

import math
import warnings
from typing import Literal

import numpy as np

from ..errors import DataError, ParameterError, caller_stacklevel
from ._common import data_type_of, rate_of, series
from ._result import PrepResult, PrepWarning

__all__ = ["fill", "part", "average", "gap_runs"]


def gap_runs(v: np.ndarray) -> list[list[int]]:
    """The gaps of ``v`` as half-open index ranges ``[start, stop)``.

    >>> gap_runs(np.array([1.0, np.nan, np.nan, 4.0, np.nan]))
    [[1, 3], [4, 5]]
    """
    gap = np.isnan(v).astype(np.int8)
    edges = np.diff(np.concatenate(([0], gap, [0])))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [[int(a), int(b)] for a, b in zip(starts, stops)]


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def fill(data: object, *, method: Literal["linear"] = "linear") -> PrepResult:
    """Fill the gaps (NaN) by linear interpolation between the valid samples on either side.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples; NaN marks a gap. Not modified.
    method : {"linear"}
        The interpolation (the only one offered).

    Returns
    -------
    PrepResult
        ``data``: the filled series; ``indices``: the filled positions; ``details``: the count and
        share filled, the gaps as ``[start, stop)`` ranges, and any gap at either end, which
        cannot be interpolated and is left as a gap (with a :class:`PrepWarning`).

    Raises
    ------
    ParameterError
        Unknown method.
    DataError
        All NaN.

    Notes
    -----
    A gap from i to j − 1 between valid samples ``v_{i−1}`` and ``v_j`` becomes
    ``v_k = v_{i−1} + (v_j − v_{i−1})·(k − i + 1)/(j − i + 1)``.

    Filled samples are not measurements: a straight line has no noise, so every statistic over
    a filled stretch is biased low (and its EDF overstated). The statistics of sigmatau accept
    gaps directly and use only gap-free terms; fill only for tools that need a complete series.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §10 "Analysis procedure" (gaps, jumps and outliers; gap
    handling); W. J. Riley, "Gaps, outliers, dead time, and uneven spacing in frequency
    stability data", Hamilton Technical Services; Stable32 User Manual, Fill function.

    Examples
    --------
    >>> from sigmatau.prep import fill
    >>> fill([1.0, float("nan"), float("nan"), 4.0]).data.tolist()
    [1.0, 2.0, 3.0, 4.0]
    """
    v = series(data)
    if method != "linear":
        raise ParameterError(f"method={method!r} must be 'linear'")
    gaps = np.isnan(v)
    idx_valid = np.flatnonzero(~gaps)
    first, last = int(idx_valid[0]), int(idx_valid[-1])
    interior = np.flatnonzero(gaps[first:last + 1]) + first
    out = v.copy()
    out[interior] = np.interp(interior, idx_valid, v[idx_valid])
    edges = int(gaps.sum()) - interior.size
    runs = gap_runs(v)
    if edges:
        warnings.warn(f"fill: {edges} gap sample(s) at the ends of the record cannot be interpolated and"
                      " stay gaps", PrepWarning, stacklevel=caller_stacklevel())
    details = {"filled": int(interior.size), "share": interior.size / v.size, "gaps": runs,
               "left_at_ends": edges}
    return PrepResult(step="fill", data=_frozen(out), data_type=None, parameters={"method": method},
                      indices=interior.astype(np.int64), details=details,
                      notes=(f"{interior.size} gap sample(s) ({100.0 * interior.size / v.size:.3g} %) filled by"
                             " linear interpolation: statistics over filled stretches are biased low",))


def _index(value: object, name: str, rate: float | None, unit: str) -> int | None:
    """A start/stop bound as a sample index (seconds → the first sample at or after that time)."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise ParameterError(f"{name}={value!r} must be a number of {unit}")
    if unit == "samples":
        if not isinstance(value, (int, np.integer)) and not (isinstance(value, (float, np.floating))
                                                              and float(value).is_integer()):
            raise ParameterError(f"{name}={value!r} must be a whole number of samples")
        idx = int(value)
    else:
        try:
            x = float(value) * float(rate)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ParameterError(f"{name}={value!r} must be a number of seconds") from None
        if not math.isfinite(x):
            raise ParameterError(f"{name}={value!r} must be a finite number of seconds")
        near = round(x)
        idx = int(near) if abs(x - near) <= 1e-9 * max(1.0, abs(x)) else math.ceil(x)
    if idx < 0:
        raise ParameterError(f"{name}={value!r} must not be negative")
    return idx


def part(data: object, *, start: float | None = None, stop: float | None = None, rate: float | None = None,
         unit: Literal["samples", "seconds"] = "samples") -> PrepResult:
    """Keep the samples in ``[start, stop)``, given as sample indices or times.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples; NaN marks a gap. Not modified.
    start, stop : int or float, optional
        The range, half-open; None means the start or the end of the record. In seconds
        (``unit="seconds"``) sample i sits at ``t_i = i/rate`` and is kept when
        ``start ≤ t_i < stop``. A stop beyond the end is taken as the end (and said so).
    rate : float, optional
        Sample rate in Hz; required with ``unit="seconds"``.
    unit : {"samples", "seconds"}
        How start and stop are given.

    Returns
    -------
    PrepResult
        ``data``: the part; ``details["range"]``: the ``[start, stop)`` sample indices kept.

    Raises
    ------
    ParameterError
        Negative, non-integral (samples) or non-finite bounds; an empty or inverted range;
        seconds without a rate; an unknown unit.
    DataError
        All NaN input, or a part without a valid sample.

    Notes
    -----
    In seconds the kept indices are ``⌈start·rate⌉ … ⌈stop·rate⌉ − 1`` (a product within 1e-9
    relative of a whole number counts as that number, so 0.3 s at 10 Hz is sample 3). The
    part keeps its gaps; its first sample becomes index 0 and time origin of later steps.

    References
    ----------
    Stable32 User Manual, Part function (a range of the data by point number).

    Examples
    --------
    >>> from sigmatau.prep import part
    >>> part([0.0, 1.0, 2.0, 3.0, 4.0], start=0.5, stop=1.5, rate=2.0, unit="seconds").data.tolist()
    [1.0, 2.0]
    """
    v = series(data)
    if unit not in ("samples", "seconds"):
        raise ParameterError(f"unit={unit!r} must be 'samples' or 'seconds'")
    if unit == "seconds":
        if rate is None:
            raise ParameterError("rate is required when unit='seconds'")
        rate = rate_of(rate)
    i0 = _index(start, "start", rate, unit)
    i1 = _index(stop, "stop", rate, unit)
    a = 0 if i0 is None else i0
    b = v.size if i1 is None else i1
    shown = f"[{start!r}, {stop!r}) {unit}"
    if a >= v.size:
        raise ParameterError(f"part {shown} starts at sample {a}, beyond the record's {v.size} samples")
    if b <= a:
        raise ParameterError(f"part {shown} is empty or inverted (samples {a} … {b - 1}): stop must exceed start")
    notes = []
    if b > v.size:
        notes.append(f"stop {stop!r} {unit} lies beyond the end; the part runs to the last sample")
        b = v.size
    out = v[a:b].copy()
    if np.isnan(out).all():
        raise DataError(f"part {shown} holds no valid sample (all {out.size} are gaps)")
    notes.insert(0, f"kept samples {a} … {b - 1} ({b - a} of {v.size})")
    return PrepResult(step="part", data=_frozen(out), data_type="",
                      parameters={"start": start, "stop": stop, "unit": unit, "rate": rate},
                      details={"range": [a, b], "dropped_before": a, "dropped_after": v.size - b},
                      notes=tuple(notes))


def _check_factor(factor: object) -> int:
    if isinstance(factor, (bool, np.bool_)) or not isinstance(factor, (int, np.integer)):
        raise ParameterError(f"factor={factor!r} must be a whole number ≥ 1")
    if factor < 1:
        raise ParameterError(f"factor={factor!r} must be ≥ 1")
    return int(factor)


def average(data: object, *, factor: int, data_type: Literal["freq", "phase"]) -> PrepResult:
    """Decimate by an averaging factor m: τ0 becomes m·τ0.

    Parameters
    ----------
    data : array_like
        Frequency or phase samples; NaN marks a gap. Not modified.
    factor : int
        The averaging factor m ≥ 1.
    data_type : {"freq", "phase"}
        Frequency samples are averaged in blocks; phase samples are subsampled (see Notes).

    Returns
    -------
    PrepResult
        ``data``: the decimated series; ``details``: blocks made, blocks that became gaps, and
        the samples at the end that do not fill a block (left out, and warned about).

    Raises
    ------
    ParameterError
        factor < 1 or not an integer; bad data_type.
    DataError
        All NaN, or fewer samples than one block.

    Notes
    -----
    Frequency: ``ȳ_k = (1/m)·Σ_{i=km}^{km+m−1} y_i`` for k = 0 … ⌊N/m⌋ − 1; a block holding a gap
    becomes a gap (its mean would be over a shorter, unknown interval). Phase: ``x'_k = x_{km}``
    for k = 0 … ⌊(N − 1)/m⌋; phase is a time error read at an instant, and the mean frequency
    over m·τ0 is ``(x_{(k+1)m} − x_{km})/(mτ0)``, so taking every m-th phase point *is* averaging
    the frequency — the two data types give the same frequencies, as Stable32's Average does.
    A gap among the skipped phase points loses nothing. Samples after the last whole block
    (frequency) or the last kept point (phase) are left out and reported, never silently.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.2 (averaging factor, τ = m·τ0); Stable32 User Manual,
    Average function.

    Examples
    --------
    >>> from sigmatau.prep import average
    >>> average([1.0, 3.0, 5.0, 7.0], factor=2, data_type="freq").data.tolist()
    [2.0, 6.0]
    >>> average([0.0, 1.0, 2.0, 3.0, 4.0], factor=2, data_type="phase").data.tolist()
    [0.0, 2.0, 4.0]
    """
    v = series(data)
    m = _check_factor(factor)
    data_type = data_type_of(data_type)
    n = v.size
    if data_type == "freq":
        blocks = n // m
        if blocks == 0:
            raise DataError(f"average: {n} samples do not fill one block of factor={m}")
        out = v[: blocks * m].reshape(blocks, m).mean(axis=1)  # a NaN in a block makes it NaN
        left = n - blocks * m
        gap_blocks = int(np.isnan(out).sum()) - int(np.isnan(v[: blocks * m]).reshape(blocks, m).all(axis=1).sum())
        details: dict[str, object] = {"blocks": blocks, "blocks_made_gaps": gap_blocks}
    else:
        out = v[::m].copy()
        left = (n - 1) % m
        details = {"points": int(out.size)}
    details["left_out"] = [n - left, n] if left else None
    notes = [f"averaged by factor {m} ({data_type}): {n} → {out.size} samples"]
    if left:
        what = "a partial last block" if data_type == "freq" else "after the last kept phase point"
        notes.append(f"{left} sample(s) {what} left out (indices {n - left} … {n - 1})")
        warnings.warn(f"average: {left} sample(s) at the end ({what}) are left out by factor={m}",
                      PrepWarning, stacklevel=caller_stacklevel())
    if np.isnan(out).all():
        raise DataError(f"average by factor={m} leaves no valid sample (every block holds a gap)")
    indices = np.arange(n - left, n, dtype=np.int64)
    return PrepResult(step="average", data=_frozen(np.ascontiguousarray(out)), data_type=data_type,
                      parameters={"factor": m}, indices=indices, details=details, notes=tuple(notes))
