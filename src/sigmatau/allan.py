"""Allan family: standard deviation of averages, ADEV, OADEV, MDEV and TDEV.

Every estimator here costs O(N) per averaging factor (O(N/m) for the
non-overlapped ones). The plain filter-chain definitions of the design tip are
in :mod:`sigmatau.filterchain` and the tests hold these fast paths to them.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ._driver import Statistic, run
from ._numeric import WindowSums, centred_sumsq, sumsq, sumsq_combination
from ._input import DataType
from ._uncertainty import CiMethod
from .confidence import ONE_SIGMA
from .result import StabilityResult

__all__ = ["stdev", "ostdev", "adev", "oadev", "mdev", "tdev"]

_DOC_COMMON = """
    Parameters
    ----------
    data : array_like
        1-D samples. With ``data_type="freq"`` (the default) they are the sensor
        output or fractional frequency, as an IMU user has them; with
        ``data_type="phase"`` they are time-error (integrated) samples. Other
        libraries default to phase: passing rate data to them with defaults gives
        results scaled by about √3 and a wrong slope.
    rate : float
        Sample rate in Hz; τ0 = 1/rate.
    data_type : {"freq", "phase"}
        Meaning of ``data`` (see above).
    taus : {"octave", "decade", "all", "log"} or array_like
        τ grid as a keyword, or τ values in seconds (rounded to multiples of τ0).
        Keyword grids stop at the statistic's default limit (see
        :mod:`sigmatau.taus`).
    m : int or array_like, optional
        Explicit averaging factors instead of ``taus``.
    points_per_decade : int
        Density of the ``"log"`` grid.
    alpha : int, optional
        Force this noise type (2 WPM, 1 FPM, 0 WFM, −1 FFM, −2 RWFM, −3 FWFM,
        −4 RRFM) at every τ for the EDF; by default it is identified at each τ
        (lag-1 autocorrelation, B1, R(n): :func:`sigmatau.noiseid.identify`).
    confidence : float
        Two-sided coverage of the interval, default ±1σ (0.6827).
    ci : {"chi2", "simple", None}
        ``"chi2"``: exact χ² interval from the EDF (Greenhall–Riley or the
        SP1065 empirical EDF); ``"simple"``: the design tip's dev ± dev/√n;
        None: no noise identification and no interval (fastest).

    Returns
    -------
    StabilityResult
        With ``alpha``, ``alpha_estimate``, ``edf``, ``ci_low``, ``ci_high``
        and ``ci_reason`` filled unless ``ci`` is None.
"""


def _doc(func):
    func.__doc__ = func.__doc__.replace("    {common}\n", _DOC_COMMON)
    return func


# --- kernels: (phase x, factors, τ0) -> (variance, number of terms) ---------------
#
# Sums of squares go through sumsq_combination, which forms the differences chunk
# by chunk: a record-sized temporary per τ costs more in page faults than the
# arithmetic itself at N = 10^6.


def _stdvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = (x.size - 1) // m
        xs = x[: k * m + 1 : m]
        _, ss = centred_sumsq(xs[1:] - xs[:-1])
        var[i] = ss / ((m * tau0) ** 2 * (k - 1))
        n[i] = k
    return var, n


def _ostdvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    buf = np.empty(x.size - 1)
    for i, m in enumerate(ms):
        k = x.size - m
        means = buf[:k]
        np.subtract(x[m:], x[:-m], out=means)
        _, ss = centred_sumsq(means)
        var[i] = ss / ((m * tau0) ** 2 * (k - 1))
        n[i] = k
    return var, n


def _avar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        xs = x[: ((x.size - 1) // m) * m + 1 : m]
        k = xs.size - 2
        var[i] = sumsq_combination([(1.0, xs[2:]), (-2.0, xs[1:-1]), (1.0, xs[:-2])], k) / (2.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


def _oavar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = x.size - 2 * m
        var[i] = sumsq_combination([(1.0, x[2 * m :]), (-2.0, x[m:-m]), (1.0, x[: -2 * m])], k) / (
            2.0 * (m * tau0) ** 2 * k
        )
        n[i] = k
    return var, n


def _mvar_sums(x: np.ndarray, m: int) -> np.ndarray:
    """Inner sums ``Σ_{i=j}^{j+m-1} Δ²_m x_i`` for j = 0 … N-3m, in O(N).

    A running sum over the second differences themselves (not over x) keeps
    the cumulative sum of the size of the result, so no digits are lost to
    cancellation even for random-run phase.
    """
    d2 = x[2 * m :] - 2.0 * x[m:-m] + x[: -2 * m]
    c = np.concatenate(([0.0], np.cumsum(d2)))
    return c[m:] - c[:-m]


def _mvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        s = _mvar_sums(x, int(m))
        var[i] = sumsq(s) / (2.0 * m**2 * (m * tau0) ** 2 * s.size)
        n[i] = s.size
    return var, n


def _tvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mvar_kernel(x, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


# --- kernels on frequency samples y (mean removed): no integration, so no phase
# round-off; each is algebraically identical to its phase kernel above. The
# window sums A_m (and the double sums B_m of MVAR) are carried from one factor
# to the next by WindowSums: one pass over the record per octave step. ----------


def _block_sums_by_factor(y: np.ndarray, ms: np.ndarray):
    """Yield ``(index, m, sums)`` over ``ms`` in increasing order; ``sums`` are the
    ⌊M/m⌋ non-overlapped block sums of m samples from 0. Each factor that is a
    power-of-two multiple of the previous one is reached by pairwise halving,
    O(M/m) per step; any other is summed from the samples."""
    prev_m, prev = 1, y
    for i in np.argsort(ms, kind="stable"):
        m = int(ms[i])
        q, r = divmod(m, prev_m)
        if r == 0 and q & (q - 1) == 0:
            sums = prev
            while q > 1:
                k = sums.size // 2
                sums = sums[0 : 2 * k : 2] + sums[1 : 2 * k : 2]
                q //= 2
        else:
            k = y.size // m
            sums = y[: k * m].reshape(k, m).sum(axis=1)
        prev_m, prev = m, sums
        yield i, m, sums


def _window_sums_by_factor(y: np.ndarray, ms: np.ndarray, *, double: bool = False):
    """Yield ``(index, m, ws)`` over ``ms`` in increasing order, ``ws`` a
    :class:`~sigmatau._numeric.WindowSums` advanced to m (its arrays are valid until the next step)."""
    ws = WindowSums(y, double=double)
    for i in np.argsort(ms, kind="stable"):
        m = int(ms[i])
        ws.advance(m)
        yield i, m, ws


def _stdvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, b in _block_sums_by_factor(y, ms):
        _, ss = centred_sumsq(b)
        var[i] = ss / (float(m) ** 2 * (b.size - 1))
        n[i] = b.size
    return var, n


def _ostdvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in _window_sums_by_factor(y, ms):
        _, ss = centred_sumsq(ws.a)
        var[i] = ss / (float(m) ** 2 * (ws.a.size - 1))
        n[i] = ws.a.size
    return var, n


def _avar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, b in _block_sums_by_factor(y, ms):
        k = b.size - 1
        var[i] = sumsq_combination([(1.0, b[1:]), (-1.0, b[:-1])], k) / (2.0 * float(m) ** 2 * k)
        n[i] = k
    return var, n


def _oavar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # Σ_{i=j}^{j+m-1} (y_{i+m} - y_i) = A_m[j+m] - A_m[j] = Δ²_m x_j / τ0, j = 0 … M-2m
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in _window_sums_by_factor(y, ms):
        a = ws.a
        k = y.size - 2 * m + 1
        var[i] = sumsq_combination([(1.0, a[m:]), (-1.0, a[:-m])], k) / (2.0 * float(m) ** 2 * k)
        n[i] = k
    return var, n


def _mvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # Σ_{k=j}^{j+m-1} (A_m[k+m] - A_m[k]) = B_m[j+m] - B_m[j], j = 0 … M-3m+1
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in _window_sums_by_factor(y, ms, double=True):
        b = ws.b
        k = y.size - 3 * m + 2
        var[i] = sumsq_combination([(1.0, b[m:]), (-1.0, b[:-m])], k) / (2.0 * float(m) ** 4 * k)
        n[i] = k
    return var, n


def _tvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mvar_freq(y, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


STDVAR = Statistic("stdev", _stdvar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=5, min_points=3, compute_freq=_stdvar_freq)
OSTDVAR = Statistic("ostdev", _ostdvar_kernel, max_m=lambda n: n - 2, stop_ratio=4, min_points=3, compute_freq=_ostdvar_freq)
AVAR = Statistic("adev", _avar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=5, min_points=3, compute_freq=_avar_freq)
OAVAR = Statistic("oadev", _oavar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=4, min_points=3, compute_freq=_oavar_freq)
MVAR = Statistic("mdev", _mvar_kernel, max_m=lambda n: n // 3, stop_ratio=4, min_points=3, compute_freq=_mvar_freq)
TVAR = Statistic("tdev", _tvar_kernel, max_m=lambda n: n // 3, stop_ratio=4, min_points=3, compute_freq=_tvar_freq)


@_doc
def stdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Standard deviation of non-overlapped m-averages (the tip's STDVAR).

    {common}
    Notes
    -----
    With ``K = ⌊M/m⌋`` averages ``ȳ_k`` of the M frequency samples,

    .. math:: s^2(τ) = \\frac{1}{K-1} \\sum_{k=0}^{K-1} (\\bar y_k - \\bar{\\bar y})^2 .

    For flicker and random-walk frequency noise it grows with the record
    length; the ratio to AVAR is Barnes' B1 function (numerics.md §1.1, §5.3).
    ``n`` is the number of averages K.

    References
    ----------
    ST DT0064 (STDVAR); W. J. Riley, NIST SP 1065 (2008) §5.2.1.

    Examples
    --------
    >>> import sigmatau
    >>> r = sigmatau.stdev([892, 809, 823, 798, 671, 644, 883, 903, 677], m=1)
    >>> round(float(r.dev[0]), 3)
    100.977
    """
    return run(STDVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def ostdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Standard deviation of overlapped (moving) m-averages (the tip's OSTDVAR).

    {common}
    Notes
    -----
    All ``M - m + 1`` moving averages ``ā_j = (1/m) Σ_{i=j}^{j+m-1} y_i`` enter the
    sample variance (ddof = 1). ``n`` is their number.

    References
    ----------
    ST DT0064 (OSTDVAR).
    """
    return run(OSTDVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def adev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Non-overlapped Allan deviation (AVAR).

    {common}
    Notes
    -----
    With ``K = ⌊(N-1)/m⌋`` non-overlapped frequency averages,

    .. math:: σ_y^2(τ) = \\frac{1}{2τ^2(K-1)} \\sum_{k=0}^{K-2}
              (x_{(k+2)m} - 2x_{(k+1)m} + x_{km})^2 .

    ``n = K - 1`` terms; O(N/m) per τ.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.2; numerics.md §1.2.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.adev(y, m=[1, 2]).dev]
    [91.22945, 115.80821]
    """
    return run(AVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def oadev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Overlapped Allan deviation (OAVAR).

    {common}
    Notes
    -----
    .. math:: σ_y^2(τ) = \\frac{1}{2τ^2(N-2m)} \\sum_{i=0}^{N-2m-1}
              (x_{i+2m} - 2x_{i+m} + x_i)^2 ,

    ``n = N - 2m`` terms; O(N) per τ.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.4; numerics.md §1.3.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.oadev(y, m=[1, 2]).dev]
    [91.22945, 85.95287]
    """
    return run(OAVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def mdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Modified Allan deviation (MVAR).

    {common}
    Notes
    -----
    .. math:: \\mathrm{Mod}\\,σ_y^2(τ) = \\frac{1}{2m^2τ^2(N-3m+1)} \\sum_{j=0}^{N-3m}
              \\Big[\\sum_{i=j}^{j+m-1} (x_{i+2m} - 2x_{i+m} + x_i)\\Big]^2 ,

    ``n = N - 3m + 1`` terms. The inner sums are a running sum of the second
    differences, so the cost is O(N) per τ, not O(N·m).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.5; numerics.md §1.4.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.mdev(y, m=[1, 2]).dev]
    [91.22945, 74.78849]
    """
    return run(MVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def tdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Time deviation (TVAR = τ²/3 · MVAR), in the unit of the phase data.

    {common}
    Notes
    -----
    .. math:: σ_x^2(τ) = \\frac{τ^2}{3}\\,\\mathrm{Mod}\\,σ_y^2(τ) .

    Best suited to white phase noise (slope −½ on TDEV).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.6; numerics.md §1.5.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.tdev(y, m=[1, 2]).dev]
    [52.67135, 86.35831]
    """
    return run(TVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
