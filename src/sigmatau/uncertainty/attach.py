"""Noise type, equivalent degrees of freedom and interval for each row of a result.

The statistic functions call :func:`attach` on the raw result. At each τ:

1. the noise type α is identified (numerics.md §5.5, :func:`sigmatau.noiseid.identify`)
   unless the caller forces one with ``alpha=``;
2. the EDF ν follows from α, m and N (:func:`sigmatau.confidence.edf_array`);
3. the deviation interval is the exact χ² interval at ``confidence``
   (:func:`sigmatau.confidence.deviation_interval`), single-sided (upper bound only)
   where ν < :data:`SINGLE_SIDED_EDF`; or, with ``ci="simple"``, the design
   tip's estimate dev ± dev/√n.

A row that cannot get an interval keeps NaN bounds and says why in ``ci_reason``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Literal, Optional

import numpy as np

from .confidence import EDF_STATISTICS, deviation_interval, edf_array
from ..errors import DataError, ParameterError
from ..core.result import StabilityResult

__all__ = ["CI_METHODS", "DECISIVE_AVERAGES", "SINGLE_SIDED_EDF", "attach", "check_options", "edf_alpha"]

CiMethod = Literal["chi2", "simple"]
CI_METHODS = ("chi2", "simple", None)

#: Below this EDF a two-sided interval is meaningless; only an upper bound is given.
SINGLE_SIDED_EDF = 1.0

#: Statistics for which no χ² interval is defined (extreme-value or plain RMS statistics).
_NO_INTERVAL = {
    "mtie": "no confidence interval is defined for MTIE (an extreme-value statistic)",
    "tierms": "no confidence interval is defined for TIE rms",
}

_ALPHA_RANGE = (-4, 2)

#: Averages ⌊N/m⌋ from which one τ's identification alone sets the EDF. Below it the lag-1
#: method calls white FM its whiter neighbour in over 1 % of records, and B1 (from 30
#: averages down) in 15–28 %; a whiter type has a several times larger EDF, so such a row's
#: interval would cover 57 % instead of 68 % (tests/test_confidence_mc.py, long-τ rows).
DECISIVE_AVERAGES = 136

#: Statistics whose noise type does not come from the per-τ identification (TheoBR's κ
#: averages over the whole record) or which identify at another τ (the Theo family).
_OWN_IDENTIFICATION = frozenset({"theo1", "theobr", "theoh"})


def check_options(alpha: object, confidence: object, ci: object) -> tuple[Optional[int], float, Optional[str]]:
    """Validate the ``alpha``, ``confidence`` and ``ci`` keywords of a statistic."""
    if ci not in CI_METHODS:
        raise ParameterError(f"ci={ci!r} must be 'chi2', 'simple' or None")
    try:
        conf = float(confidence)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"confidence={confidence!r} must be a number in (0, 1)") from None
    if isinstance(confidence, (bool, str)) or not (0.0 < conf < 1.0):
        raise ParameterError(f"confidence={confidence!r} must be a number in (0, 1)")
    if alpha is None:
        return None, conf, ci  # type: ignore[return-value]
    if isinstance(alpha, (bool, np.bool_)) or not isinstance(alpha, (int, np.integer)):
        if not (isinstance(alpha, float) and alpha.is_integer()):
            raise ParameterError(f"alpha={alpha!r} must be an integer noise exponent from -4 to 2")
    a = int(alpha)  # type: ignore[arg-type]
    if not (_ALPHA_RANGE[0] <= a <= _ALPHA_RANGE[1]):
        raise ParameterError(f"alpha={alpha!r} must be an integer noise exponent from -4 to 2")
    return a, conf, ci  # type: ignore[return-value]


def _identify(result: StabilityResult, data: np.ndarray, data_type: str, id_factors: np.ndarray):
    from .noiseid import identify

    try:
        # Stable32 compares B1 with its expectation for the statistic's own number of terms
        same_factors = np.array_equal(id_factors, result.m)
        ident = identify(data, id_factors, data_type=data_type, family=result.statistic,
                         n_terms=result.n if same_factors else None)
    except DataError as exc:
        reason = f"noise type not identified ({exc}); give alpha= for an interval"
        n = len(result)
        return np.full(n, np.nan), np.full(n, np.nan), (reason,) * n
    return ident.alpha.astype(float), ident.alpha_estimate, ("",) * len(result)


def attach(
    result: StabilityResult,
    data: np.ndarray,
    data_type: str,
    *,
    alpha: Optional[int],
    confidence: float,
    ci: Optional[str],
    id_factors: Optional[np.ndarray] = None,
    identified: Optional[tuple[np.ndarray, np.ndarray]] = None,
) -> StabilityResult:
    """Return ``result`` with ``alpha``, ``alpha_estimate``, ``edf``, ``ci_low``,
    ``ci_high``, ``confidence`` and ``ci_reason`` filled.

    Parameters
    ----------
    result : StabilityResult
        Raw result of a statistic.
    data, data_type
        The user's samples as given (noise identification works on them).
    alpha : int or None
        Forced noise type for every τ; None identifies it per τ.
    confidence : float
        Two-sided coverage of the interval.
    ci : {"chi2", "simple", None}
        Interval method; None leaves every uncertainty field empty.
    id_factors : array of int, optional
        Averaging factors at which to identify the noise (default ``result.m``;
        the Theo family passes the factor of the equivalent Allan τ).
    identified : (alpha, alpha_estimate), optional
        Noise type already determined by the statistic itself (TheoBR from κ).
    """
    if ci is None or len(result) == 0:
        return result
    n_rows = len(result)
    if result.statistic in _NO_INTERVAL:
        reason = _NO_INTERVAL[result.statistic]
        nan = np.full(n_rows, np.nan)
        return dataclasses.replace(result, edf=nan, ci_low=nan, ci_high=nan, confidence=confidence,
                                   ci_reason=(reason,) * n_rows)
    has_edf = result.statistic in EDF_STATISTICS
    if alpha is not None:
        if has_edf:
            edf_array(result.statistic, alpha, result.m[:1], max(result.n_points, 1), unsupported="raise")
        a = np.full(n_rows, float(alpha))
        est = np.full(n_rows, np.nan)
        reasons = ("",) * n_rows
    elif identified is not None:
        a, est = (np.asarray(v, dtype=float) for v in identified)
        reasons = tuple("" if math.isfinite(v) else "noise type not identified" for v in a)
    else:
        factors = result.m if id_factors is None else id_factors
        a, est, reasons = _identify(result, data, data_type, factors)

    known = np.isfinite(a)
    nu = np.full(n_rows, np.nan)
    edf_reasons = list(reasons)
    a_lo = a if alpha is not None or result.statistic in _OWN_IDENTIFICATION else edf_alpha(result, a)
    if not has_edf:
        edf_reasons = [f"no published EDF for {result.statistic}"] * n_rows
    elif known.any():
        for rows, n_points in _rows_by_points(result, known):
            vals, why = _least_edf(result, a, a_lo, rows, n_points)
            nu[rows] = vals
            for i, w in zip(rows, why):
                edf_reasons[i] = w
    low = np.full(n_rows, np.nan)
    high = np.full(n_rows, np.nan)
    if ci == "simple":
        err = result.dev / np.sqrt(np.maximum(result.n, 1))
        ok = result.n >= 1
        low[ok] = np.maximum(result.dev[ok] - err[ok], 0.0)
        high[ok] = result.dev[ok] + err[ok]
        # The simple estimate needs only n, so EDF reasons do not apply here.
        edf_reasons = ["" if ok[i] else "no terms" for i in range(n_rows)]
    else:
        two = np.isfinite(nu) & (nu >= SINGLE_SIDED_EDF)
        one = np.isfinite(nu) & (nu > 0) & (nu < SINGLE_SIDED_EDF)
        if two.any():
            lo, hi = deviation_interval(result.dev[two], nu[two], confidence)
            low[two], high[two] = lo, hi
        if one.any():
            lo, hi = deviation_interval(result.dev[one], nu[one], confidence, sided="upper")
            low[one], high[one] = lo, hi
            for i in np.flatnonzero(one):
                edf_reasons[i] = f"edf {_below(nu[i], SINGLE_SIDED_EDF)} < {SINGLE_SIDED_EDF:g}: single-sided upper bound"
    return dataclasses.replace(
        result,
        alpha=a,
        alpha_estimate=est,
        edf=nu,
        ci_low=low,
        ci_high=high,
        confidence=confidence,
        ci_reason=tuple(edf_reasons),
    )


def edf_alpha(result: StabilityResult, alpha: np.ndarray) -> np.ndarray:
    """Noise type the EDF of each row is computed for: the identified α, or, on a row with
    fewer than :data:`DECISIVE_AVERAGES` averages, the reddest α identified at that τ or a
    shorter one.

    ``α_edf(m) = min(α(m), min{α(m') : m' < m})`` where ``⌊N/m⌋ < 136`` or ``α(m) = 2``,
    else ``α(m)`` (white PM after flicker PM is the lag-1 method's bias, not chance).

    The dominant type of a sum of power-law noises can only redden as τ grows (each term's
    AVAR goes as τ^(−α−1)), so a whiter type at a longer τ is either a real change of the
    process (a servo loop, a disciplined oscillator) or a misidentification. With few
    averages the second is common, and it is the costly one: a whiter type has a larger EDF
    (OADEV at m = 4096 of 32768 points: ν = 110 for flicker PM against 9.8 for white FM), so
    the interval is far too narrow. Taking the redder type gives the narrower-EDF, wider
    interval, which covers in both cases. The reported α (the Stable32 Alpha column) is
    unchanged; only the EDF and interval use ``α_edf``, and ``ci_reason`` says so.

    Parameters
    ----------
    result : StabilityResult
        Its ``m`` and record length (``n_points``, or per row ``n_effective`` with gaps).
    alpha : numpy.ndarray
        Identified α per row (NaN where none).

    Returns
    -------
    numpy.ndarray
        α for the EDF, NaN where ``alpha`` is NaN.
    """
    points = np.asarray(result.n_points if result.n_effective is None else result.n_effective, dtype=float)
    # White PM is never decisive after flicker PM: decimated flicker PM reads white to the
    # lag-1 method whatever the number of averages (43 % of records at 2048 averages,
    # 71 % at 256; test_confidence_mc.py), so only a redder type at a shorter τ counts.
    weak = (np.floor(points / np.maximum(result.m, 1)) < DECISIVE_AVERAGES) | (np.asarray(alpha) == 2)
    out = np.array(alpha, dtype=float, copy=True)
    known = np.isfinite(out)
    for i in np.flatnonzero(known & weak):
        shorter = known & (result.m < result.m[i])
        if shorter.any():
            out[i] = min(out[i], float(np.min(np.asarray(alpha, dtype=float)[shorter])))
    return out


def _least_edf(result: StabilityResult, alpha: np.ndarray, alpha_lo: np.ndarray, rows: np.ndarray,
               n_points: int) -> tuple[np.ndarray, list[str]]:
    """EDF of each row (and its reason): that of α, or where ``alpha_lo < alpha`` the smallest
    EDF over the types from ``alpha_lo`` to α — the widest interval the data cannot rule out
    (the EDF is not monotone in α for every statistic: HDEV's at few averages is not)."""
    nu, why = edf_array(result.statistic, alpha[rows].astype(np.int64), result.m[rows], n_points,
                        return_reason=True, unsupported="nan")
    nu = np.array(nu, dtype=float)
    why = list(why)
    for k, i in enumerate(rows):
        if not (alpha_lo[i] < alpha[i] and math.isfinite(nu[k])):
            continue  # no type to weigh, or none defined for the identified one (TOTDEV WPM)
        for cand in range(int(alpha_lo[i]), int(alpha[i])):
            v, w = edf_array(result.statistic, np.array([cand]), result.m[i:i + 1], n_points,
                             return_reason=True, unsupported="nan")
            if math.isfinite(v[0]) and not w[0] and not v[0] >= nu[k]:
                nu[k] = float(v[0])
                why[k] = (f"EDF for alpha={cand}, a redder noise type than the one identified here"
                          f" (alpha={int(alpha[i])}) and seen at this or a shorter tau: too few averages"
                          " here to rule it out")
    return nu, why


def _rows_by_points(result: StabilityResult, rows: np.ndarray) -> list[tuple[np.ndarray, int]]:
    """The selected rows grouped by the record length their EDF is computed for: ``n_points``,
    or with gaps each row's equivalent contiguous length (``result.n_effective``)."""
    idx = np.flatnonzero(rows)
    if result.n_effective is None:
        return [(idx, result.n_points)]
    points = np.asarray(result.n_effective)[idx]
    return [(idx[points == p], int(p)) for p in np.unique(points)]


def _below(value: float, limit: float) -> str:
    """``value`` with enough digits to show it is below ``limit`` (0.998 printed as "1" read
    "edf 1 < 1")."""
    for digits in range(3, 8):
        text = f"{value:.{digits}g}"
        if float(text) < limit:
            return text
    return repr(float(value))
