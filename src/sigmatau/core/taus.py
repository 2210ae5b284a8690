"""Averaging-factor grids and the usable range of each statistic.

A τ grid is given either as a keyword (``"octave"``, ``"decade"``, ``"all"``,
``"log"``), as an array of τ in seconds, or as explicit averaging factors ``m``
(τ = m·τ0, or 0.75·m·τ0 for the Theo family).

Keyword grids stop at the statistic's *default* largest factor
``m ≤ ⌊N/stop⌋`` where ``N`` is the number of phase points and ``stop`` the
Stable32 stop ratio of the statistic (numerics.md §1; W. J. Riley, "The
evolution of frequency stability analysis software", Table III). Past that the
estimate has few degrees of freedom; the design tip recommends even less (about
10 % of the record for OAVAR/OHVAR, 30-50 % for the total variances, 75 % for
Theo1). Explicit ``m`` or ``taus`` may go beyond the default up to the
mathematical limit of the estimator, with a :class:`~sigmatau.errors.RangeWarning`.
``m`` replaces the default ``taus="octave"``; giving ``m`` together with any other
``taus`` is a :class:`~sigmatau.errors.ParameterError`.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import warnings
from collections.abc import Iterator
from typing import Literal, Union

import numpy as np

from ..errors import ParameterError, RangeWarning, caller_stacklevel

__all__ = ["TauGrid", "TAU_GRIDS", "STOP_RATIOS", "m_grid", "select_m", "long_factors_expected"]

TauGrid = Literal["octave", "decade", "all", "log"]
TAU_GRIDS: tuple[str, ...] = ("octave", "decade", "all", "log")
TausArg = Union[str, "np.typing.ArrayLike"]

#: Stable32 stop ratios of the Allan, Hadamard and total families: keyword grids end
#: at m ≤ ⌊N/stop⌋ (W. J. Riley, "The evolution of frequency stability analysis
#: software", Table III). Noise identification reads them too: Stable32 applies B1
#: down to 2·stop averages (:func:`sigmatau.noiseid.b1_min_averages`). The Theo
#: family (1) and the TIE statistics keep theirs with their definitions.
STOP_RATIOS: dict[str, float] = {
    "stdev": 5, "adev": 5, "hdev": 5,
    "ostdev": 4, "oadev": 4, "mdev": 4, "tdev": 4, "ohdev": 4,
    "totdev": 2, "mtotdev": 3, "ttotdev": 3, "htotdev": 3,
    # Not in Riley's table (Stable32 predates them): MHVAR's N−4m+1 terms keep N/5 at N/5,
    # as MDEV's stop 4 keeps N/4; MHTOT ends with one subsequence, as MTOT does at N/3.
    "mhdev": 5, "ldev": 5, "mhtotdev": 4,
    # PVAR's N−2m terms: the stop of OADEV and MDEV (B1 then reaches down to 8 averages)
    "pdev": 4,
}

# A context variable, not warnings.catch_warnings: the warning filters are
# process-wide, so a catch_warnings block in one worker thread (compute_channels)
# restores them under another thread's feet and its long-τ warning escapes.
_LONG_FACTORS_EXPECTED = contextvars.ContextVar("sigmatau_long_factors_expected", default=False)


@contextlib.contextmanager
def long_factors_expected() -> Iterator[None]:
    """Silence the few-degrees-of-freedom :class:`~sigmatau.errors.RangeWarning` in this context.

    For internal callers that ask for long averaging factors on purpose (the
    R(n) noise test, the allantools-compatible grids). Thread- and task-safe:
    the flag lives in a :class:`contextvars.ContextVar`, so other threads keep
    their warnings.
    """
    token = _LONG_FACTORS_EXPECTED.set(True)
    try:
        yield
    finally:
        _LONG_FACTORS_EXPECTED.reset(token)


def m_grid(
    kind: str,
    m_max: int,
    *,
    m_min: int = 1,
    even: bool = False,
    points_per_decade: int = 10,
) -> np.ndarray:
    """Averaging factors of a keyword grid, between ``m_min`` and ``m_max`` inclusive.

    Parameters
    ----------
    kind : {"octave", "decade", "all", "log"}
        ``octave``: 1, 2, 4, 8 …; ``decade``: 1, 2, 4, 10, 20, 40, 100 …;
        ``all``: every factor; ``log``: ``points_per_decade`` factors per decade,
        logarithmically spaced and rounded to distinct integers.
    m_max, m_min : int
        Inclusive bounds.
    even : bool
        Keep only even factors (Theo1 family); ``octave`` then starts at 2.
    points_per_decade : int
        Density of the ``log`` grid.
    """
    if kind not in TAU_GRIDS:
        raise ParameterError(f"taus={kind!r} must be one of {TAU_GRIDS} or an array of τ in seconds")
    if m_max < m_min:
        return np.empty(0, dtype=np.int64)
    if kind == "octave":
        k_max = int(math.floor(math.log2(m_max))) + 1
        ms = 2 ** np.arange(k_max, dtype=np.int64)
    elif kind == "decade":
        k_max = int(math.floor(math.log10(m_max))) + 1
        ms = (np.array([1, 2, 4], dtype=np.int64)[None, :] * 10 ** np.arange(k_max, dtype=np.int64)[:, None]).ravel()
    elif kind == "all":
        ms = np.arange(m_min, m_max + 1, dtype=np.int64)
    else:
        if not (isinstance(points_per_decade, (int, np.integer)) and points_per_decade > 0):
            raise ParameterError(f"points_per_decade={points_per_decade!r} must be a positive integer")
        count = int(math.ceil(math.log10(m_max) * points_per_decade)) + 1
        ms = np.unique(np.round(np.logspace(0.0, math.log10(m_max), max(count, 1))).astype(np.int64))
    if even:
        ms = np.unique(np.where(ms % 2 == 1, ms + 1, ms)) if kind != "octave" else ms[ms >= 2]
    ms = ms[(ms >= m_min) & (ms <= m_max)]
    return np.unique(ms)


def _as_int_factors(m: object) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(m))
    if arr.ndim != 1 or arr.size == 0:
        raise ParameterError(f"m={m!r} must be a positive integer or a 1-D sequence of them")
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ParameterError(f"m={m!r} must hold integers")
    if np.issubdtype(arr.dtype, np.floating):
        if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
            raise ParameterError(f"m={m!r} must hold whole numbers")
    return np.unique(arr.astype(np.int64))


def select_m(
    name: str,
    *,
    n_points: int,
    rate: float,
    taus: object,
    m: object,
    points_per_decade: int,
    m_min: int,
    m_max: int,
    stop_ratio: float,
    even: bool = False,
    tau_factor: float = 1.0,
) -> np.ndarray:
    """Averaging factors for one statistic from the user's ``taus``/``m`` arguments.

    ``m_max`` is the mathematical limit for ``n_points`` phase points and
    ``stop_ratio`` sets the default limit ``⌊n_points/stop_ratio⌋`` of keyword
    grids. Requests outside ``[m_min, m_max]`` raise :class:`ParameterError`;
    explicit requests past the default limit are kept with a :class:`RangeWarning`.
    """
    default_max = min(m_max, max(m_min, int(n_points // stop_ratio)))
    explicit = m is not None or not isinstance(taus, str)
    if m is not None:
        # "octave" is the default of taus: explicit m overrides it.
        if not (isinstance(taus, str) and taus == "octave"):
            raise ParameterError(f"give either taus={taus!r} or m, not both")
        ms = _as_int_factors(m)
    elif isinstance(taus, str):
        return m_grid(taus, default_max, m_min=m_min, even=even, points_per_decade=points_per_decade)
    else:
        t = np.atleast_1d(np.asarray(taus, dtype=float)) if is_numeric(taus) else None
        if t is None or t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise ParameterError(
                f"taus={taus!r} must be one of {TAU_GRIDS} or a 1-D array of positive τ in seconds"
            )
        exact = t * rate / tau_factor
        step = 2 if even else 1
        ms = (np.round(exact / step) * step).astype(np.int64)
        off = np.abs(ms - exact) > 1e-6 * np.maximum(exact, 1.0)
        if np.any(off):
            warnings.warn(
                f"{name}: {int(off.sum())} requested τ are not multiples of {step * tau_factor:g}·τ0;"
                " they were rounded to the nearest usable averaging factor",
                RangeWarning,
                stacklevel=caller_stacklevel(),
            )
        ms = np.unique(ms)
    if even and np.any(ms % 2):
        raise ParameterError(f"{name} needs even averaging factors, got m={ms[ms % 2 == 1].tolist()}")
    bad = (ms < m_min) | (ms > m_max)
    if np.any(bad):
        raise ParameterError(
            f"{name}: m={ms[bad].tolist()} outside the range {m_min}..{m_max} allowed for"
            f" {n_points} phase points"
        )
    if explicit and np.any(ms > default_max) and not _LONG_FACTORS_EXPECTED.get():
        warnings.warn(
            f"{name}: m > {default_max} (N/{stop_ratio:g}) has few degrees of freedom;"
            f" computed as requested for m={ms[ms > default_max].tolist()}",
            RangeWarning,
            stacklevel=caller_stacklevel(),
        )
    return ms


def is_numeric(obj: object) -> bool:
    try:
        arr = np.asarray(obj)
    except Exception:
        return False
    return arr.dtype != object and (np.issubdtype(arr.dtype, np.number))
