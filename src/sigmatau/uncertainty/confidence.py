"""Equivalent degrees of freedom (EDF) and χ² confidence intervals.

A variance estimate ``s²`` with ν equivalent degrees of freedom is modelled as
``ν s²/σ² ~ χ²_ν``; the interval on the true variance follows from two χ²
quantiles, and deviation bounds are their square roots (numerics.md §2.1).
This module holds the EDF rules and the interval arithmetic; it depends on
numpy and scipy only and knows nothing about the estimators themselves.

EDF rules by statistic (numerics.md §2):

* ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev``, ``ohdev`` (and the
  modified Hadamard ``mhdev`` and ``ldev``): the Greenhall–Riley combined algorithm,
  :func:`greenhall_edf`.
* ``totdev``, ``mtotdev``, ``ttotdev``, ``htotdev``, ``theo1``, ``theobr``,
  ``theoh``: the empirical formulas of SP1065 and Howe et al.; ``mhtotdev``:
  the same form with coefficients measured by Monte Carlo (none is published).
* ``stdev``: ``K − 1`` independent averages (white FM only).

All EDFs take ``N``, the number of **phase** points (frequency samples + 1).

The rules live in sibling modules: :mod:`.greenhall` (Greenhall–Riley) and
:mod:`.empirical_edf` (SP1065, Howe et al., Theo1), and the exact EDF of a white PM + white FM
mixture in :mod:`.mixture_edf`; this module dispatches
between them (:func:`edf`, :func:`edf_array`) and holds the intervals. Every
name stays importable from here.
"""

from __future__ import annotations

import functools
import math
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import chdtri

from ..errors import ParameterError
from .edfchecks import Version, _check_alpha, _check_int, _check_version
from .empirical_edf import _EMPIRICAL_ALPHAS, _empirical_edf, edf_oadev_simple
# _sw and _sx are imported from here by tests/test_confidence.py.
from .greenhall import _sw, _sx  # noqa: F401
from .greenhall import _GREENHALL_STATS, _greenhall_inverse, greenhall_edf
from .mixture_edf import white_mixture_edf
from .pdev_edf import PDEV_ALPHAS, pdev_edf_scalar

__all__ = [
    "ONE_SIGMA",
    "ConfidenceInterval",
    "EDF_STATISTICS",
    "greenhall_edf",
    "edf",
    "edf_array",
    "edf_reason",
    "edf_oadev_simple",
    "white_mixture_edf",
    "simple_error",
    "chi2_interval",
    "deviation_interval",
]

#: Two-sided coverage of ±1 standard deviation of a normal law, erf(1/√2).
ONE_SIGMA: float = math.erf(1.0 / math.sqrt(2.0))

Sided = Literal["two", "upper", "lower"]


class ConfidenceInterval(NamedTuple):
    """Lower and upper confidence bounds (scalars or arrays).

    A named tuple, as in :mod:`scipy.stats`: it unpacks as ``low, high`` and is
    immutable.
    """

    low: float | np.ndarray
    high: float | np.ndarray


#: Statistics with an EDF rule.
EDF_STATISTICS: tuple[str, ...] = tuple(_GREENHALL_STATS) + tuple(_EMPIRICAL_ALPHAS) + ("pdev",)

_NAMES = {-4: "RRFM", -3: "FWFM", -2: "RWFM", -1: "FFM", 0: "WFM", 1: "FPM", 2: "WPM"}


def _check_statistic(statistic: object) -> str:
    """The lower-cased statistic name, if it has an EDF rule."""
    if not isinstance(statistic, str) or statistic.lower() not in EDF_STATISTICS:
        raise ParameterError(
            f"statistic={statistic!r} has no EDF rule; choose one of {', '.join(EDF_STATISTICS)}"
        )
    return statistic.lower()


def _check_pair(statistic: str, alpha: int) -> None:
    """Raise ParameterError when (statistic, alpha) has no EDF rule."""
    if statistic == "pdev":
        if alpha not in PDEV_ALPHAS:
            raise ParameterError(f"pdev with alpha={alpha} ({_NAMES[alpha]}): the variance diverges"
                                 " (needs alpha > -3)")
        return
    if statistic in _GREENHALL_STATS:
        d = _GREENHALL_STATS[statistic][0]
        if alpha + 2 * d <= 1:
            raise ParameterError(
                f"{statistic} with alpha={alpha} ({_NAMES[alpha]}): the variance diverges"
                f" (needs alpha > {1 - 2 * d})"
            )
        return
    allowed = _EMPIRICAL_ALPHAS[statistic]
    if alpha == 2 and statistic in ("totdev", "htotdev"):
        raise ParameterError(
            f"{statistic} has no EDF for alpha=2 (WPM): the OAVAR closed form overstates it"
            " up to 3x (Monte Carlo); total variances are meant for FM noise, use oadev"
        )
    if alpha not in allowed:
        raise ParameterError(
            f"{statistic} has no EDF formula for alpha={alpha} ({_NAMES[alpha]});"
            f" tabulated: alpha in {list(allowed)}"
        )


def _row_statistic(statistic: str, m: int) -> str:
    """The estimator whose EDF applies at factor ``m``.

    HTOT at m = 1 *is* OHVAR(τ0) (SP1065 and Stable32 report OHDEV there, and
    so does :func:`sigmatau.htotdev`), so that row takes OHVAR's EDF; the HTOT
    formula and the SP1065 Table 5 forms describe other estimators (Table 5's
    FFM form at m = 1 gives ν ≈ 0.87 for any N, an interval from zero).
    MHTOT at m = 1 is likewise MHVAR(τ0) (:func:`sigmatau.stats.modhadamard.mhtotdev`).
    """
    if m == 1 and statistic in _AT_ONE:
        return _AT_ONE[statistic]
    return statistic


#: Statistics that report another estimator at m = 1 (see :func:`_row_statistic`).
_AT_ONE = {"htotdev": "ohdev", "mhtotdev": "mhdev"}


# ν depends only on its five arguments; the Greenhall sums cost milliseconds while a
# statistic itself costs microseconds, and the same (statistic, α, m, N) recurs on
# every call with the same record length.
@functools.lru_cache(maxsize=4096)
def _edf_scalar(statistic: str, alpha: int, m: int, N: int, version: str) -> tuple[float, str]:
    """``(ν, "")``, or ``(nan, reason)`` when the record is too short (checked arguments)."""
    if statistic == "pdev":
        return pdev_edf_scalar(alpha, m, N)
    if statistic in _GREENHALL_STATS:
        d, modified, overlapped = _GREENHALL_STATS[statistic]
        inv, why = _greenhall_inverse(alpha, d, m, modified, overlapped, N, version)
        return (math.nan, why) if why else (1.0 / inv, "")
    return _empirical_edf(statistic, alpha, m, N)


def edf(statistic: str, alpha: int, m: int, N: int, *, version: Version = "full") -> float:
    r"""Equivalent degrees of freedom of ``statistic`` at one averaging factor.

    Parameters
    ----------
    statistic : str
        One of :data:`EDF_STATISTICS` (case-insensitive).
    alpha : int
        Dominant power-law noise exponent (2 WPM, 1 FPM, 0 WFM, −1 FFM,
        −2 RWFM, −3 FWFM, −4 RRFM).
    m : int
        Averaging factor (for the Theo family τ = 0.75·m·τ0).
    N : int
        Number of phase points (frequency samples + 1).
    version : {"full", "simplified"}
        Greenhall algorithm variant; ignored by the empirical rules.

    Returns
    -------
    float
        ν, or NaN when the record is too short or the empirical formula gives
        ν ≤ 0; :func:`edf_reason` says why.

    Raises
    ------
    ParameterError
        Unknown statistic, invalid m or N, or an α without a rule (below).

    Notes
    -----
    Rules and supported α (any other α raises :class:`ParameterError`):

    ============================  ========================  ====================
    statistic                     rule                      α
    ============================  ========================  ====================
    adev, oadev, mdev, tdev       Greenhall, d = 2          2 … −2
    hdev, ohdev, mhdev, ldev      Greenhall, d = 3          2 … −4
    totdev                        ν = b·N/m − c             0, −1, −2
    totdev                        SP1065 Table 5 (FPM)      1
    mtotdev, ttotdev              ν = b·N/m − c             2 … −2
    htotdev, m ≥ 16               ν = (M/m)/(b0 + b1·m/M)   0 … −4
    htotdev, m ≥ 16               SP1065 Table 5 (FPM)      1
    htotdev, 1 < m < 16           SP1065 Table 5            1 … −2
    htotdev, 1 < m < 16           ν = (M/m)/(b0 + b1·m/M)   −3, −4
    htotdev, m = 1                as ohdev (HTOT is OHVAR)  2 … −4
    mhtotdev, m ≥ 2               ν = (N/m)/(b0 + b1·m/N)   2 … −4 (Monte Carlo)
    mhtotdev, m = 1               as mhdev (it is MHVAR)    2 … −4
    theo1, theobr, theoh          Theo1 formulas            2 … −2
    stdev                         ν = ⌊(N−1)/m⌋ − 1         0
    ============================  ========================  ====================

    Greenhall (F, S): adev (m, 1), oadev (m, m), mdev/tdev (1, m), hdev (m, 1),
    ohdev (m, m), mhdev (1, m); see :func:`greenhall_edf`. "SP1065 Table 5" is
    the closed-form OAVAR EDF of :func:`edf_oadev_simple`.

    The empirical formulas (TOTVAR, MTOT/TTOT, HTOT, Theo1), their
    coefficients, and how they compare with Stable32 and Monte Carlo are
    given in :mod:`sigmatau.uncertainty.empirical_edf`. TheoBR and the TheoBR
    part of TheoH use the Theo1 EDF (the AVAR part of TheoH takes
    ``edf("oadev", ...)``); the Theo1 RWFM formula turns negative for
    ``t ≳ 0.63 N``, ``t = 0.75 m``, and NaN is returned there.

    References
    ----------
    W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065
    (2008), §5.3 and Tables 7–8. C. A. Greenhall and W. J. Riley, Proc. 35th
    PTTI (2003). D. A. Howe, R. L. Beard, C. A. Greenhall, W. J. Riley, "A total
    estimator of the Hadamard function used for GPS operations", Proc. 32nd
    PTTI (2000). D. A. Howe and T. N. Tasset, "Theo1: characterization of very
    long-term frequency stability", Proc. 18th EFTF (2004).

    Examples
    --------
    >>> round(edf("oadev", 0, 10, 1001), 3)
    135.071
    >>> round(edf("totdev", 0, 10, 1001), 2)
    150.15
    """
    return _edf_scalar(*_checked_row(statistic, alpha, m, N, version))[0]


def edf_reason(statistic: str, alpha: int, m: int, N: int, *, version: Version = "full") -> str:
    """Why :func:`edf` returns NaN for these arguments; ``""`` when it does not.

    Examples
    --------
    >>> edf_reason("oadev", 0, 501, 1001)
    'N=1001 phase points is fewer than the filter length L=1003'
    >>> edf_reason("oadev", 0, 10, 1001)
    ''
    """
    return _edf_scalar(*_checked_row(statistic, alpha, m, N, version))[1]


def _checked_row(statistic: object, alpha: object, m: object, N: object,
                 version: object) -> tuple[str, int, int, int, str]:
    """Checked arguments of :func:`edf` and :func:`edf_reason`, as :func:`_edf_scalar` takes them.

    The statistic is the one whose rule applies at ``m`` (:func:`_row_statistic`),
    and the (statistic, α) pair has a rule (else ParameterError).
    """
    statistic = _check_statistic(statistic)
    alpha = _check_alpha(alpha)
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    version = _check_version(version)
    statistic = _row_statistic(statistic, m)
    _check_pair(statistic, alpha)
    return statistic, alpha, m, N, version


def edf_array(statistic: str, alpha: ArrayLike, ms: ArrayLike, N: int, *,
              version: Version = "full", return_reason: bool = False,
              unsupported: Literal["raise", "nan"] = "raise",
              ) -> np.ndarray | tuple[np.ndarray, tuple[str, ...]]:
    """:func:`edf` over many averaging factors.

    Parameters
    ----------
    statistic : str
        As in :func:`edf`.
    alpha : int or array_like of int
        One noise exponent, or one per averaging factor (broadcast with ``ms``).
    ms : array_like of int
        Averaging factors.
    N : int
        Number of phase points.
    version : {"full", "simplified"}
        Greenhall algorithm variant.
    return_reason : bool
        Also return a tuple of strings, ``""`` where ν is defined and the
        reason for NaN elsewhere.
    unsupported : {"raise", "nan"}
        What to do with an α that has no rule for ``statistic``: raise
        :class:`ParameterError` (default), or give NaN with the error message
        as the reason — convenient when α comes from noise identification
        at each τ.

    Returns
    -------
    nu : numpy.ndarray
        ν for each factor, NaN where undefined.
    reasons : tuple of str
        Only when ``return_reason`` is true.

    Raises
    ------
    ParameterError
        As :func:`edf`; with ``unsupported="raise"`` every (statistic, α) pair
        is checked before computing.

    Examples
    --------
    >>> edf_array("mtotdev", 0, [10, 100], 1001).round(2)
    array([108.91,   9.81])
    """
    statistic = _check_statistic(statistic)
    N = _check_int(N, "N", 1)
    version = _check_version(version)
    if unsupported not in ("raise", "nan"):
        raise ParameterError(f"unsupported={unsupported!r} must be 'raise' or 'nan'")
    try:
        a_arr, m_arr = np.broadcast_arrays(np.asarray(alpha), np.asarray(ms))
    except ValueError:
        raise ParameterError(
            f"alpha (shape {np.shape(alpha)}) and ms (shape {np.shape(ms)}) do not broadcast"
        ) from None
    if m_arr.ndim > 1:
        raise ParameterError(f"ms must be a scalar or 1-D, got shape {m_arr.shape}")
    alphas = [_check_alpha(a) for a in a_arr.ravel()]
    factors = [_check_int(v, "m", 1) for v in m_arr.ravel()]
    rows = [(_row_statistic(statistic, v), a, v) for a, v in zip(alphas, factors)]
    refused: dict[tuple[str, int], str] = {}
    for key in sorted({(st, a) for st, a, _ in rows}):
        try:
            _check_pair(*key)
        except ParameterError as exc:
            if unsupported == "raise":
                raise
            refused[key] = str(exc)
    pairs = [(math.nan, refused[st, a]) if (st, a) in refused else _edf_scalar(st, a, v, N, version)
             for st, a, v in rows]
    nu = np.array([p[0] for p in pairs], dtype=float).reshape(m_arr.shape)
    if return_reason:
        return nu, tuple(p[1] for p in pairs)
    return nu


# Lesage–Audoin style factors of Stable32 for non-overlapped ADEV, by alpha.
_K_ALPHA = {2: 0.99, 1: 0.99, 0: 0.87, -1: 0.77, -2: 0.75}


def simple_error(dev: ArrayLike, n: ArrayLike, *, alpha: int | None = None) -> np.ndarray:
    """The simple 1-σ error estimate ``dev/√n`` (optionally ``K_α·dev/√n``).

    Parameters
    ----------
    dev : array_like
        Deviations.
    n : array_like
        Number of terms summed by the estimator at each τ.
    alpha : {2, 1, 0, -1, -2}, optional
        When given, multiply by Stable32's noise factor ``K_α`` = 0.99, 0.99,
        0.87, 0.77, 0.75 (WPM … RWFM), meant for the non-overlapped ADEV.

    Returns
    -------
    numpy.ndarray
        The error; NaN where ``n < 1``.

    Notes
    -----
    Exact only for uncorrelated terms (non-overlapped AVAR of white FM); the
    terms of overlapped estimators are correlated and this understates the
    error. Prefer :func:`deviation_interval` with :func:`edf`.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3; Stable32 User Manual ("Kn"
    factors, after Lesage & Audoin).

    Examples
    --------
    >>> float(simple_error(0.1, 100))
    0.01
    """
    d = np.asarray(dev, dtype=float)
    nn = np.asarray(n, dtype=float)
    factor = 1.0
    if alpha is not None:
        a = _check_alpha(alpha)
        if a not in _K_ALPHA:
            raise ParameterError(f"alpha={alpha} has no K_alpha factor (needs -2 <= alpha <= 2)")
        factor = _K_ALPHA[a]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = factor * d / np.sqrt(np.where(nn >= 1.0, nn, np.nan))
    return out


# --- intervals ---------------------------------------------------------------------------


def _check_confidence(confidence: object) -> float:
    """A coverage probability in (0, 1)."""
    try:
        value = float(confidence)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"confidence={confidence!r} must be a number in (0, 1)") from None
    if not 0.0 < value < 1.0:
        raise ParameterError(f"confidence={confidence!r} must be in (0, 1), e.g. 0.683 or 0.95")
    return value


def chi2_interval(var: ArrayLike, edf: ArrayLike, confidence: float = ONE_SIGMA, *,
                  sided: Sided = "two") -> ConfidenceInterval:
    r"""χ² confidence interval on a variance from its equivalent degrees of freedom.

    Parameters
    ----------
    var : array_like
        Variance estimates ``s²`` (≥ 0; NaN propagates).
    edf : array_like
        Equivalent degrees of freedom ν (broadcast with ``var``; non-integer
        allowed). Where ν is NaN or ≤ 0 both bounds are NaN.
    confidence : float
        Coverage probability p in (0, 1); default ``erf(1/√2) ≈ 0.682689``
        (±1σ).
    sided : {"two", "upper", "lower"}
        ``"two"``: equal tails. ``"upper"``: single-sided upper bound, the
        interval ``[0, hi]`` (``low = 0``, the true lower end of a one-sided
        interval on a variance, as for the last low-EDF points of a run).
        ``"lower"``: ``[lo, ∞)`` (``high = inf``).

    Returns
    -------
    ConfidenceInterval
        ``(low, high)`` on the variance; floats for scalar inputs, arrays
        otherwise.

    Raises
    ------
    ParameterError
        Confidence outside (0, 1), an unknown ``sided`` or a negative variance.

    Notes
    -----
    Since ``ν s²/σ² ~ χ²_ν``, with ``χ²_ν(q)`` the q-quantile,

    .. math::

        σ^2_{lo} = \frac{ν s^2}{χ^2_ν\bigl(1 - (1-p)/2\bigr)},\qquad
        σ^2_{hi} = \frac{ν s^2}{χ^2_ν\bigl((1-p)/2\bigr)},

    and the single-sided bounds use ``χ²_ν(p)`` (lower) and ``χ²_ν(1 − p)``
    (upper). Exact quantiles (``scipy.special.chdtri``, the inverse χ² survival
    function) are used; Stable32's
    approximate inverse differs in the 4th digit.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3 (eqs. for the χ² interval).

    Examples
    --------
    >>> lo, hi = chi2_interval(1.0, 100.0)
    >>> round(lo, 4), round(hi, 4)
    (0.8765, 1.1641)
    """
    p = _check_confidence(confidence)
    if sided not in ("two", "upper", "lower"):
        raise ParameterError(f"sided={sided!r} must be 'two', 'upper' or 'lower'")
    v = np.asarray(var, dtype=float)
    if np.any(v < 0.0):
        raise ParameterError("var must be >= 0 (got a negative variance)")
    nu = np.asarray(edf, dtype=float)
    v, nu = np.broadcast_arrays(v, nu)
    good = np.isfinite(nu) & (nu > 0.0)
    nu_ok = np.where(good, nu, 1.0)
    scaled = np.where(good, nu_ok * v, np.nan)
    if sided == "two":
        low = scaled / chdtri(nu_ok, (1.0 - p) / 2.0)
        high = scaled / chdtri(nu_ok, (1.0 + p) / 2.0)
    elif sided == "upper":
        low = np.where(good, 0.0, np.nan) * np.where(np.isnan(v), np.nan, 1.0)
        high = scaled / chdtri(nu_ok, p)
    else:
        low = scaled / chdtri(nu_ok, 1.0 - p)
        high = np.where(good, np.inf, np.nan) * np.where(np.isnan(v), np.nan, 1.0)
    if low.ndim == 0:
        return ConfidenceInterval(float(low), float(high))
    return ConfidenceInterval(low, high)


def deviation_interval(dev: ArrayLike, edf: ArrayLike, confidence: float = ONE_SIGMA, *,
                       sided: Sided = "two") -> ConfidenceInterval:
    """χ² confidence interval on a deviation: square roots of :func:`chi2_interval`.

    Parameters
    ----------
    dev : array_like
        Deviations ``s`` (≥ 0).
    edf : array_like
        Equivalent degrees of freedom.
    confidence : float
        Coverage in (0, 1), default ±1σ (0.682689…).
    sided : {"two", "upper", "lower"}
        See :func:`chi2_interval`.

    Returns
    -------
    ConfidenceInterval
        ``(low, high)`` on the deviation.

    Examples
    --------
    >>> lo, hi = deviation_interval(9.159953e-02, edf("oadev", 0, 10, 1001))
    >>> f"{lo:.6e} {hi:.6e}"
    '8.649995e-02 9.772219e-02'
    """
    d = np.asarray(dev, dtype=float)
    if np.any(d < 0.0):
        raise ParameterError("dev must be >= 0 (got a negative deviation)")
    low, high = chi2_interval(d * d, edf, confidence, sided=sided)
    if np.ndim(low) == 0:
        return ConfidenceInterval(math.sqrt(low), math.sqrt(high))
    return ConfidenceInterval(np.sqrt(low), np.sqrt(high))
