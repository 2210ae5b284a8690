"""The design tip's digital-filter-chain definitions, written plainly: the oracle.

ST design tip DT0064 defines every statistic as a chain of three digital
filters applied to the frequency (rate-sensor) samples ``y``:

* ``M(m)`` — moving average of m samples (:func:`moving_average`),
* ``D1(m)`` — difference between a sample and the one m later (:func:`difference`),
* ``m:1`` — decimation, keep one output sample in m (:func:`decimate`),

followed by the mean of the squared output samples (×½ for the Allan kinds,
×1/6 for the Hadamard kinds). Only output samples whose filter windows lie
entirely inside the record are kept, so no start-up transient reaches the mean.

This module is written to be read, not to be fast: each filter is applied
literally, the moving average costs O(N·m). The fast estimators in
:mod:`sigmatau.stats.allan` and :mod:`sigmatau.stats.hadamard` are tested against it on
every noise type. The decimation keeps samples 0, m, 2m, …, which makes every
non-overlapped variance here identical to its NIST SP 1065 estimator (the
``⌊M/m⌋`` non-overlapped averages start at sample 0).

Every function takes frequency data. For phase (time-error) data ``x`` use
``sigmatau.phase_to_frequency(x, rate=rate)`` first. The variances are in the
units of the public functions: the square of the frequency unit, and for TVAR
the square of the phase unit (frequency unit × seconds).
"""

from __future__ import annotations

import numpy as np

from ..core.validate import as_series, check_rate
from ..errors import DataError, ParameterError

__all__ = [
    "moving_average",
    "difference",
    "decimate",
    "stdvar",
    "ostdvar",
    "avar",
    "oavar",
    "mvar",
    "tvar",
    "hvar",
    "ohvar",
]


def _check_m(m: object) -> int:
    if isinstance(m, (bool, np.bool_)) or not isinstance(m, (int, np.integer)) or m < 1:
        raise ParameterError(f"m={m!r} must be a positive integer")
    return int(m)


def _prepare(y: object, m: object, rate: object, name: str) -> tuple[np.ndarray, int, float]:
    """Validated ``(y, m, τ0)`` for statistic ``name``, or ParameterError/DataError."""
    y_arr = as_series(y, "y")
    m_int = _check_m(m)
    tau0 = 1.0 / check_rate(rate)
    fewest = _MIN_SAMPLES[name](m_int)
    if y_arr.size < fewest:
        raise DataError(
            f"{name} with m={m_int} needs at least {fewest} frequency samples, got {y_arr.size}"
        )
    return y_arr, m_int, tau0


# Fewest frequency samples M that leave at least one output sample (two for the
# sample variances); these are the SP1065 limits on m written as limits on M.
_MIN_SAMPLES = {
    "stdvar": lambda m: 2 * m,
    "ostdvar": lambda m: m + 1,
    "avar": lambda m: 2 * m,
    "oavar": lambda m: 2 * m,
    "mvar": lambda m: 3 * m - 1,
    "tvar": lambda m: 3 * m - 1,
    "hvar": lambda m: 3 * m,
    "ohvar": lambda m: 3 * m,
}


# --- the three filters -----------------------------------------------------------


def moving_average(y: object, m: int) -> np.ndarray:
    """The tip's M(m): moving average of m samples, full windows only.

    Parameters
    ----------
    y : array_like
        Input samples, L of them.
    m : int
        Window length.

    Returns
    -------
    numpy.ndarray
        ``L - m + 1`` samples (none when ``m > L``).

    Notes
    -----
    .. math:: a_j = \\frac{1}{m} \\sum_{i=j}^{j+m-1} y_i , \\qquad j = 0 … L-m .

    Output sample j averages ``y_j … y_{j+m-1}``; outputs whose window would
    reach before the first sample (the filter's transient) are not produced.
    Each window is summed afresh, so no error accumulates along the record.

    Examples
    --------
    >>> from sigmatau.filterchain import moving_average
    >>> moving_average([1.0, 2.0, 3.0, 4.0, 5.0], 2).tolist()
    [1.5, 2.5, 3.5, 4.5]
    """
    y_arr = np.asarray(y, dtype=np.float64)
    m = _check_m(m)
    if m > y_arr.size:
        return np.empty(0)
    windows = np.lib.stride_tricks.sliding_window_view(y_arr, m)
    return windows.sum(axis=1) / m


def difference(y: object, m: int) -> np.ndarray:
    """The tip's D1(m): difference between sample n + m and sample n.

    Parameters
    ----------
    y : array_like
        Input samples, L of them.
    m : int
        Lag.

    Returns
    -------
    numpy.ndarray
        ``L - m`` samples (none when ``m >= L``).

    Notes
    -----
    .. math:: d_n = y_{n+m} - y_n , \\qquad n = 0 … L-m-1 .

    The filter ``1 - z^{-m}`` has m + 1 taps; the design tip writes its last
    tap as "n+m+1" because it counts taps from 1.

    Examples
    --------
    >>> from sigmatau.filterchain import difference
    >>> difference([1.0, 2.0, 4.0, 8.0], 2).tolist()
    [3.0, 6.0]
    """
    y_arr = np.asarray(y, dtype=np.float64)
    m = _check_m(m)
    if m >= y_arr.size:
        return np.empty(0)
    return y_arr[m:] - y_arr[:-m]


def decimate(y: object, m: int) -> np.ndarray:
    """The tip's m:1 decimation: keep samples 0, m, 2m, …

    Parameters
    ----------
    y : array_like
        Input samples, L of them.
    m : int
        Decimation factor.

    Returns
    -------
    numpy.ndarray
        ``⌈L/m⌉`` samples.

    Notes
    -----
    Starting at sample 0 is the phase that reproduces the non-overlapped
    SP 1065 estimators: after ``M(m)``, output k is the average of
    ``y_{km} … y_{km+m-1}``.

    Examples
    --------
    >>> from sigmatau.filterchain import decimate
    >>> decimate([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3).tolist()
    [0.0, 3.0, 6.0]
    """
    y_arr = np.asarray(y, dtype=np.float64)
    m = _check_m(m)
    return y_arr[::m].copy()


def _half_mean_square(z: np.ndarray) -> float:
    return float(np.mean(z * z) / 2.0)


# --- the statistics ----------------------------------------------------------------


def stdvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """STDVAR: sample variance of non-overlapped m-averages, by the filter chain.

    Chain: ``y → M(m) → m:1 → sample variance``.

    Parameters
    ----------
    y : array_like
        Frequency (sensor-output) samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊M/2⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    The ``K = ⌊M/m⌋`` decimated averages ``ȳ_k`` enter

    .. math:: s^2(τ) = \\frac{1}{K-1} \\sum_{k=0}^{K-1} (\\bar y_k - \\bar{\\bar y})^2 .

    The design tip calls it the variance of the averages; the sample (K − 1)
    normalisation is SP 1065's and :func:`sigmatau.stdev`'s.

    References
    ----------
    ST DT0064 (STDVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.1; numerics.md §1.1.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import stdvar
    >>> round(stdvar(nbs9(), 1) ** 0.5, 3)
    100.977
    """
    y_arr, m, _ = _prepare(y, m, rate, "stdvar")
    a = decimate(moving_average(y_arr, m), m)
    return float(np.sum((a - a.mean()) ** 2) / (a.size - 1))


def ostdvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """OSTDVAR: sample variance of overlapped (moving) m-averages, by the filter chain.

    Chain: ``y → M(m) → sample variance``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ M - 1``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    With the ``K' = M - m + 1`` moving averages ``ā_j`` and their mean ``ā̄``,

    .. math:: s^2(τ) = \\frac{1}{K'-1} \\sum_{j=0}^{K'-1} (\\bar a_j - \\bar{\\bar a})^2 .

    References
    ----------
    ST DT0064 (OSTDVAR); numerics.md §1.1.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import ostdvar
    >>> round(ostdvar(nbs9(), 2) ** 0.5, 5)
    72.40927
    """
    y_arr, m, _ = _prepare(y, m, rate, "ostdvar")
    a = moving_average(y_arr, m)
    return float(np.sum((a - a.mean()) ** 2) / (a.size - 1))


def avar(y: object, m: int, *, rate: float = 1.0) -> float:
    """AVAR: non-overlapped Allan variance, by the filter chain.

    Chain: ``y → M(m) → D1(m) → m:1 → ½·mean square``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊M/2⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    After the decimation the chain's output is ``ȳ_{k+1} − ȳ_k`` for the
    ``K = ⌊M/m⌋`` non-overlapped averages, so

    .. math:: σ_y^2(τ) = \\frac{1}{2(K-1)} \\sum_{k=0}^{K-2} (\\bar y_{k+1} - \\bar y_k)^2 ,
              \\qquad τ = mτ_0 .

    References
    ----------
    ST DT0064 (AVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.2; numerics.md §1.2.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import avar
    >>> [round(avar(nbs9(), m) ** 0.5, 5) for m in (1, 2)]
    [91.22945, 115.80821]
    """
    y_arr, m, _ = _prepare(y, m, rate, "avar")
    return _half_mean_square(decimate(difference(moving_average(y_arr, m), m), m))


def oavar(y: object, m: int, *, rate: float = 1.0) -> float:
    """OAVAR: overlapped Allan variance, by the filter chain.

    Chain: ``y → M(m) → D1(m) → ½·mean square``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊M/2⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    With the moving averages ``ā_j`` the chain's output is ``ā_{j+m} − ā_j``
    for ``j = 0 … M−2m``:

    .. math:: σ_y^2(τ) = \\frac{1}{2(M-2m+1)} \\sum_{j=0}^{M-2m} (\\bar a_{j+m} - \\bar a_j)^2 .

    References
    ----------
    ST DT0064 (OAVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.4; numerics.md §1.3.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import oavar
    >>> [round(oavar(nbs9(), m) ** 0.5, 5) for m in (1, 2)]
    [91.22945, 85.95287]
    """
    y_arr, m, _ = _prepare(y, m, rate, "oavar")
    return _half_mean_square(difference(moving_average(y_arr, m), m))


def mvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """MVAR: modified Allan variance, by the filter chain.

    Chain: ``y → M(m) → D1(m) → M(m) → ½·mean square``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊(M+1)/3⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    The second moving average turns each Allan difference into the average of
    m consecutive ones; the ``M − 3m + 2`` output samples give

    .. math:: \\mathrm{Mod}\\,σ_y^2(τ) = \\frac{1}{2m^4(M-3m+2)} \\sum_{j=0}^{M-3m+1}
              \\Big\\{\\sum_{i=j}^{j+m-1} \\Big[\\sum_{k=i}^{i+m-1} (y_{k+m} - y_k)\\Big]\\Big\\}^2 .

    References
    ----------
    ST DT0064 (MAVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.5; numerics.md §1.4.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import mvar
    >>> [round(mvar(nbs9(), m) ** 0.5, 5) for m in (1, 2)]
    [91.22945, 74.78849]
    """
    y_arr, m, _ = _prepare(y, m, rate, "mvar")
    return _half_mean_square(moving_average(difference(moving_average(y_arr, m), m), m))


def tvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """TVAR: time variance ``τ²/3 · MVAR``, by the filter chain.

    Chain: ``y → M(m) → D1(m) → M(m) → ½·mean square``, times ``τ²/3``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊(M+1)/3⌋``.
    rate : float
        Sample rate in Hz; ``τ = m/rate``.

    Returns
    -------
    float
        The variance, in the square of (unit of ``y`` × seconds): the phase unit.

    Notes
    -----
    .. math:: σ_x^2(τ) = \\frac{τ^2}{3}\\,\\mathrm{Mod}\\,σ_y^2(τ), \\qquad τ = mτ_0 .

    References
    ----------
    ST DT0064 (TVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.6; numerics.md §1.5.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import tvar
    >>> [round(tvar(nbs9(), m) ** 0.5, 5) for m in (1, 2)]
    [52.67135, 86.35831]
    """
    y_arr, m, tau0 = _prepare(y, m, rate, "tvar")
    tau = m * tau0
    return tau**2 / 3.0 * mvar(y_arr, m)


def hvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """HVAR: non-overlapped Hadamard variance, by the filter chain.

    Chain: ``y → M(m) → D1(m) → D1(m) → m:1 → 1/6·mean square``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊M/3⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    After the decimation the output is ``ȳ_{k+2} − 2ȳ_{k+1} + ȳ_k`` for the
    ``K = ⌊M/m⌋`` non-overlapped averages:

    .. math:: Hσ_y^2(τ) = \\frac{1}{6(K-2)} \\sum_{k=0}^{K-3}
              (\\bar y_{k+2} - 2\\bar y_{k+1} + \\bar y_k)^2 .

    The 1/6 is the standard normalisation, which makes HVAR equal AVAR for
    white FM noise. The design tip's code takes ½ of the mean square, as for
    the Allan variance, so its Hadamard variance is 3 times this one (its
    deviation √3 times).

    References
    ----------
    ST DT0064 (HVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.8; numerics.md §1.6.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import hvar
    >>> [round(hvar(nbs9(), m) ** 0.5, 4) for m in (1, 2)]
    [70.8061, 116.798]
    """
    y_arr, m, _ = _prepare(y, m, rate, "hvar")
    z = decimate(difference(difference(moving_average(y_arr, m), m), m), m)
    return float(np.mean(z * z) / 6.0)


def ohvar(y: object, m: int, *, rate: float = 1.0) -> float:
    """OHVAR: overlapped Hadamard variance, by the filter chain.

    Chain: ``y → M(m) → D1(m) → D1(m) → 1/6·mean square``.

    Parameters
    ----------
    y : array_like
        Frequency samples, M of them.
    m : int
        Averaging factor, ``1 ≤ m ≤ ⌊M/3⌋``.
    rate : float
        Sample rate in Hz (τ0 = 1/rate). The result does not depend on it.

    Returns
    -------
    float
        The variance, in the square of the unit of ``y``.

    Notes
    -----
    With the moving averages ``ā_j``, the ``M − 3m + 1`` output samples give

    .. math:: Hσ_y^2(τ) = \\frac{1}{6(M-3m+1)} \\sum_{j=0}^{M-3m}
              (\\bar a_{j+2m} - 2\\bar a_{j+m} + \\bar a_j)^2 .

    Standard 1/6 normalisation; the design tip's code uses ½ (see :func:`hvar`).
    SP 1065's tables list this value under "HDEV".

    References
    ----------
    ST DT0064 (OHVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.9; numerics.md §1.7.

    Examples
    --------
    >>> from sigmatau.datasets import nbs9
    >>> from sigmatau.filterchain import ohvar
    >>> [round(ohvar(nbs9(), m) ** 0.5, 5) for m in (1, 2)]
    [70.80607, 85.61487]
    """
    y_arr, m, _ = _prepare(y, m, rate, "ohvar")
    z = difference(difference(moving_average(y_arr, m), m), m)
    return float(np.mean(z * z) / 6.0)
