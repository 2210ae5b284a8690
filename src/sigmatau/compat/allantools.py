"""allantools-compatible statistics computed by sigmatau.

Scripts written for allantools keep working, faster, after one changed line::

    import sigmatau.compat.allantools as allantools

The module provides ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev``, ``ohdev``,
``pdev``, ``totdev``, ``mtotdev``, ``ttotdev``, ``htotdev``, ``theo1``, ``mtie`` and
``tierms`` with allantools' signature ``f(data, rate=1.0, data_type="phase",
taus=None)`` and its return value ``(taus, devs, errs, ns)``, four float64
arrays, and ``gcodev(data_1, data_2, rate, data_type, taus)`` (allantools'
unsigned Groslambert codeviation ``sqrt|cov|``; :func:`sigmatau.gcodev` keeps the
sign). The values come from sigmatau's estimators (``ci=None``, no bias
correction); allantools itself is not needed. Everything else allantools offers
(``gradev``, ``Dataset``, ``noise``, ``tau_generator``, conversions, plotting,
confidence intervals) is not provided: import it from allantools.

Conventions kept from allantools (the tests hold this module to allantools 2024.6)
----------------------------------------------------------------------------------
* **Data.** ``data_type="phase"`` by default. Frequency data lose leading and
  trailing NaN, then their mean, and are integrated from ``x_0 = 0``
  (``x_{i+1} = x_i + y_i/rate``). Only MTIE and TIE rms depend on the removed
  mean; every other statistic here ignores a frequency offset.
* **τ grid.** ``taus=None`` or ``[]`` means ``"octave"``. Keywords build τ on
  the length L of the series the statistic works on (phase points; frequency
  samples for ``htotdev``): ``"all"`` m = 1 … L, ``"octave"`` m = 2^k ≤ L,
  ``"decade"`` m = 1, 2, 4 × 10^k with 10^k ≤ L, ``"log10"`` ``int(10·log10 L)``
  log-spaced values. τ in seconds (any array-like or scalar) become
  ``m = round(τ·rate)`` (NumPy rounding, half to even). Only 0 < m < L is kept
  (also m ≤ L/3 for ``mtotdev``, ``ttotdev`` and ``htotdev``; only even m for
  ``theo1``), duplicates are merged and m sorted; τ that do not fit are dropped
  without a word. Rows whose estimator has one term or none (``ns ≤ 1``) are
  dropped too.
* **Returned τ** are ``m/rate`` — also for ``theo1``, whose τ is m·τ0 here and in
  allantools although :func:`sigmatau.theo1` reports Theo1 at 0.75·m·τ0 (the
  Stable32 convention). The deviations are the same.
* **ns** is the number of terms of each estimator, as a float array: adev
  ⌊(N−1)/m⌋−1, oadev N−2m, mdev/tdev N−3m+1, hdev ⌊(N−1)/m⌋−2, ohdev N−3m,
  pdev N−2m, totdev N−2, mtotdev/ttotdev N−3m+1, htotdev N−3m (N−3 at m = 1), theo1
  (N−m)·m/2, mtie/tierms N−m, for N phase points.
* **errs** is ``devs/sqrt(ns)``, except theo1 (``devs/sqrt(N−m)``) and tierms
  (zeros), as in allantools. These are not confidence intervals; use
  :mod:`sigmatau` itself (``ci="chi2"``) for those.
* **Estimators.** mtotdev, ttotdev and htotdev are raw (no bias correction);
  ttotdev = τ²/3·mtotdev; htotdev at m = 1 is the overlapped Hadamard deviation;
  mtie is the largest peak-to-peak phase excursion over windows of m + 1 points;
  tierms is the rms of ``x_{i+m} − x_i``; theo1 includes the 1/0.75 factor.

Intentional differences from allantools
---------------------------------------
1. **Errors are exceptions of sigmatau's hierarchy.** An unknown ``data_type``,
   ``rate ≤ 0`` or non-numeric, an unknown ``taus`` keyword or non-numeric
   ``taus`` raise :class:`~sigmatau.errors.ParameterError` (a ``ValueError``);
   allantools raises a bare ``Exception``, a ``RuntimeError`` (rate 0), a NumPy
   ``TypeError`` or returns nonsense (negative rate).
2. **No usable τ** raises :class:`~sigmatau.errors.DataError` (a
   ``ValueError``); allantools prints a message and raises ``UserWarning``.
3. **NaN and infinity** raise :class:`~sigmatau.errors.DataError`, apart from
   the leading and trailing NaN of frequency data that both libraries drop.
   allantools lets them through into NaN deviations; its ``htotdev`` on
   frequency data does not drop the end NaN either (and builds its τ grid on
   the untrimmed length), this module does.
4. **Nothing is printed.**
5. **Round-off.** sigmatau removes the mean frequency or the linear phase trend
   before differencing and works on frequency samples directly when given
   frequency data, so the sums are evaluated in another order and the results
   differ from allantools' by round-off: up to a few 1e-11 relative in the
   tests (the tests require 1e-10), where the phase values are 10^4–10^5 times
   the differences the estimators take (a frequency offset, random-run FM) and
   float64 resolves those differences to about that. The worse the data are
   conditioned (larger offsets or drifts, longer records), the larger the
   difference.
6. **Cost.** Every statistic is O(N) per τ except mtotdev, ttotdev and
   htotdev (whatever :mod:`sigmatau.stats.total` costs) and theo1 (O(N log² m) per
   τ, or the plain O(N·m) sum where that is cheaper or needed for accuracy);
   allantools' theo1, mtotdev, ttotdev and htotdev loop in Python over O(N·m)
   terms per τ and its mtie reduces an O(N·m) window view. bench/ measures both.
7. **Input.** Data go through sigmatau's validation: they must be a real 1-D
   numeric array-like (a single column is accepted); the result arrays are new,
   writable float64 arrays.

Examples
--------
>>> import sigmatau.compat.allantools as allantools
>>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
>>> taus, devs, errs, ns = allantools.oadev(y, data_type="freq", taus=[1, 2])
>>> taus.tolist(), [round(float(d), 5) for d in devs], ns.tolist()
([1.0, 2.0], [91.22945, 85.95287], [8.0, 6.0])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal, Union

import numpy as np
import numpy.typing as npt

from ..compare import covariance
from ..stats import allan, hadamard, parabolic, theo, tie, total
from ..core.validate import as_series, check_data_type, check_rate
from ..errors import DataError, ParameterError
from ..core.taus import long_factors_expected

__all__ = [
    "adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "pdev", "totdev",
    "mtotdev", "ttotdev", "htotdev", "theo1", "mtie", "tierms", "gcodev",
]

#: The four arrays every function returns: taus, devs, errs, ns.
AllantoolsResult = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
DataType = Literal["phase", "freq"]
#: A keyword, τ in seconds (scalar or sequence), or None for "octave".
TausArg = Union[str, float, "npt.ArrayLike", None]

_KEYWORDS = ("all", "octave", "decade", "log10")


@dataclass(frozen=True)
class _Spec:
    """How one allantools statistic maps onto sigmatau.

    ``count(m, N)`` is allantools' number of terms for N phase points; ``error``
    turns ``(devs, ns, m, N)`` into allantools' ``errs``.
    """

    func: Callable[..., object]
    count: Callable[[np.ndarray, int], np.ndarray]
    error: Callable[[np.ndarray, np.ndarray, np.ndarray, int], np.ndarray]
    third: bool = False  # τ grid limited to m ≤ L/3
    on_freq: bool = False  # τ grid built on the frequency samples
    even: bool = False  # only even m (Theo1)
    offset_sensitive: bool = False  # needs allantools' mean-removed integration


def _dev_over_sqrt_n(devs, ns, m, n_phase):
    return devs / np.sqrt(ns)


def _theo1_error(devs, ns, m, n_phase):
    return devs / np.sqrt(n_phase - m)


def _zero_error(devs, ns, m, n_phase):
    return np.zeros_like(devs)


def _blocks_minus(k: int) -> Callable[[np.ndarray, int], np.ndarray]:
    return lambda m, n: (n - 1) // m - k


def _overlap(k: int, plus: int = 0) -> Callable[[np.ndarray, int], np.ndarray]:
    return lambda m, n: n - k * m + plus


_SPECS: dict[str, _Spec] = {
    "adev": _Spec(allan.adev, _blocks_minus(1), _dev_over_sqrt_n),
    "oadev": _Spec(allan.oadev, _overlap(2), _dev_over_sqrt_n),
    "mdev": _Spec(allan.mdev, _overlap(3, 1), _dev_over_sqrt_n),
    "tdev": _Spec(allan.tdev, _overlap(3, 1), _dev_over_sqrt_n),
    "hdev": _Spec(hadamard.hdev, _blocks_minus(2), _dev_over_sqrt_n),
    "ohdev": _Spec(hadamard.ohdev, _overlap(3), _dev_over_sqrt_n),
    "pdev": _Spec(parabolic.pdev, _overlap(2), _dev_over_sqrt_n),
    "totdev": _Spec(total.totdev, lambda m, n: np.full(m.shape, n - 2), _dev_over_sqrt_n),
    "mtotdev": _Spec(total.mtotdev, _overlap(3, 1), _dev_over_sqrt_n, third=True),
    "ttotdev": _Spec(total.ttotdev, _overlap(3, 1), _dev_over_sqrt_n, third=True),
    # M = N - 1 frequency samples give M - 3m + 1 = N - 3m subsequences; m = 1 is OHDEV.
    "htotdev": _Spec(total.htotdev, _overlap(3), _dev_over_sqrt_n, third=True, on_freq=True),
    "theo1": _Spec(theo.theo1, lambda m, n: (n - m) * m // 2, _theo1_error, even=True),
    "mtie": _Spec(tie.mtie, _overlap(1), _dev_over_sqrt_n, offset_sensitive=True),
    "tierms": _Spec(tie.tierms, _overlap(1), _zero_error, offset_sensitive=True),
}


def _series(data: object, data_type: str) -> np.ndarray:
    """The samples as float64; frequency data lose their leading and trailing NaN."""
    if data_type == "freq":
        try:
            arr = np.asarray(data)
        except Exception:  # ragged input: as_series explains
            arr = None
        if arr is not None and arr.ndim == 1 and np.issubdtype(arr.dtype, np.floating):
            keep = np.flatnonzero(~np.isnan(arr))
            data = arr[keep[0] : keep[-1] + 1] if keep.size else arr[:0]
    return as_series(data)


def _keyword_grid(keyword: str, length: int) -> np.ndarray:
    """Averaging factors (as floats) of an allantools keyword grid for a series of ``length``."""
    if keyword == "all":
        return np.arange(1.0, length + 1.0)
    if keyword == "octave":
        return 2.0 ** np.arange(int(np.floor(np.log2(length))) + 1)
    if keyword == "decade":
        powers = 10.0 ** np.arange(int(np.floor(np.log10(length))) + 1)
        return (powers[:, None] * np.array([1.0, 2.0, 4.0])[None, :]).ravel()
    top = float(np.log10(length))
    return np.logspace(0.0, top, int(10 * top))


def _factors(taus: object, length: int, rate: float, *, third: bool, even: bool) -> np.ndarray:
    """allantools' averaging factors for ``taus`` on a series of ``length`` points."""
    if taus is None or (isinstance(taus, list) and len(taus) == 0):
        taus = "octave"
    if length < 2:
        return np.empty(0, dtype=np.int64)
    if isinstance(taus, str):
        if taus not in _KEYWORDS:
            raise ParameterError(
                f"taus={taus!r} must be one of {_KEYWORDS}, None or an array of τ in seconds"
            )
        seconds = (1.0 / rate) * _keyword_grid(taus, length)
    else:
        try:
            seconds = np.atleast_1d(np.asarray(taus, dtype=float))
        except (TypeError, ValueError):
            raise ParameterError(
                f"taus={taus!r} must be one of {_KEYWORDS}, None or an array of τ in seconds"
            ) from None
        if seconds.ndim != 1:
            raise ParameterError(f"taus must be 1-D, got shape {seconds.shape}")
    m = np.round(seconds * rate)
    with np.errstate(invalid="ignore"):
        ok = (m > 0) & (m < length)
        if third:
            ok &= m <= length / 3.0
    m = np.unique(m[ok]).astype(np.int64)
    return m[m % 2 == 0] if even else m


def _describe(taus: object) -> str:
    if isinstance(taus, str) or taus is None:
        return f"taus={taus!r}"
    arr = np.atleast_1d(np.asarray(taus, dtype=float))
    if arr.size == 0:
        return "an empty taus"
    return f"{arr.size} τ from {np.nanmin(arr):g} s to {np.nanmax(arr):g} s"


def _compute(name: str, data: object, rate: object, data_type: object, taus: object) -> AllantoolsResult:
    spec = _SPECS[name]
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    series = _series(data, dtype)
    n_phase = series.size + 1 if dtype == "freq" else series.size
    length = n_phase - 1 if spec.on_freq else n_phase
    ms = _factors(taus, length, rate_f, third=spec.third, even=spec.even)
    ms = ms[spec.count(ms, n_phase) > 1]
    if ms.size == 0:
        raise DataError(
            f"{name}: no averaging time of {_describe(taus)} leaves more than one term"
            f" with {n_phase} phase points at rate={rate_f:g} Hz"
        )
    if spec.offset_sensitive and dtype == "freq":
        series = series - series.mean()
    # allantools' grids run to the estimator's limit, past sigmatau's default stop.
    with long_factors_expected():
        res = spec.func(series, rate=rate_f, data_type=dtype, m=ms, ci=None)
    devs = np.array(res.dev, dtype=np.float64)
    ns = np.array(res.n, dtype=np.float64)
    errs = spec.error(devs, ns, ms, n_phase)
    return ms / rate_f, devs, np.asarray(errs, dtype=np.float64), ns


_DOC = """

    Parameters
    ----------
    data : array_like
        Phase (time error, seconds) or fractional-frequency samples.
    rate : float
        Sample rate in Hz; τ0 = 1/rate.
    data_type : {"phase", "freq"}
        Meaning of ``data``; phase by default, as in allantools.
    taus : {"octave", "decade", "all", "log10"}, array_like or None
        τ grid: a keyword, or τ in seconds rounded to the nearest multiple of
        τ0; None or ``[]`` means ``"octave"``. τ that do not fit are dropped
        (see the module notes).

    Returns
    -------
    taus, devs, errs, ns : numpy.ndarray
        τ = m/rate actually used, the deviations, allantools' error estimate
        and the number of terms (float) at each τ.

    Raises
    ------
    ParameterError
        Invalid ``rate``, ``data_type`` or ``taus``.
    DataError
        Invalid data, or no usable τ.
"""


def _doc(sigmatau_name: str) -> Callable[[Callable[..., AllantoolsResult]], Callable[..., AllantoolsResult]]:
    def decorate(func: Callable[..., AllantoolsResult]) -> Callable[..., AllantoolsResult]:
        func.__doc__ = (func.__doc__ or "") + _DOC + f"""
    See Also
    --------
    sigmatau.{sigmatau_name} : the same estimator with sigmatau's conventions.
"""
        return func
    return decorate


@_doc("adev")
def adev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Non-overlapped Allan deviation, allantools-style."""
    return _compute("adev", data, rate, data_type, taus)


@_doc("oadev")
def oadev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Overlapped Allan deviation, allantools-style."""
    return _compute("oadev", data, rate, data_type, taus)


@_doc("mdev")
def mdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Modified Allan deviation, allantools-style."""
    return _compute("mdev", data, rate, data_type, taus)


@_doc("tdev")
def tdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Time deviation (τ/√3 · MDEV, in the phase unit), allantools-style."""
    return _compute("tdev", data, rate, data_type, taus)


@_doc("hdev")
def hdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Non-overlapped Hadamard deviation, allantools-style."""
    return _compute("hdev", data, rate, data_type, taus)


@_doc("ohdev")
def ohdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Overlapped Hadamard deviation, allantools-style."""
    return _compute("ohdev", data, rate, data_type, taus)


@_doc("pdev")
def pdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Parabolic deviation, allantools-style (= OADEV at m = 1)."""
    return _compute("pdev", data, rate, data_type, taus)


@_doc("totdev")
def totdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Total deviation (doubly reflected phase), allantools-style."""
    return _compute("totdev", data, rate, data_type, taus)


@_doc("mtotdev")
def mtotdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Modified total deviation (raw, no bias correction), allantools-style."""
    return _compute("mtotdev", data, rate, data_type, taus)


@_doc("ttotdev")
def ttotdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Time total deviation (τ/√3 · raw MTOT), allantools-style."""
    return _compute("ttotdev", data, rate, data_type, taus)


@_doc("htotdev")
def htotdev(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Hadamard total deviation (raw; OHDEV at m = 1), allantools-style."""
    return _compute("htotdev", data, rate, data_type, taus)


@_doc("theo1")
def theo1(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Theo1 deviation at even m, reported at τ = m·τ0 (allantools' convention)."""
    return _compute("theo1", data, rate, data_type, taus)


@_doc("mtie")
def mtie(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """Maximum time interval error over windows of m + 1 points, allantools-style."""
    return _compute("mtie", data, rate, data_type, taus)


@_doc("tierms")
def tierms(
    data: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase", taus: TausArg = None,
) -> AllantoolsResult:
    """RMS time interval error (errs are zeros, as in allantools)."""
    return _compute("tierms", data, rate, data_type, taus)


def gcodev(
    data_1: npt.ArrayLike, data_2: npt.ArrayLike, rate: float = 1.0, data_type: DataType = "phase",
    taus: TausArg = None,
) -> AllantoolsResult:
    """Groslambert codeviation of two simultaneous series, allantools-style: ``sqrt|cov|``, unsigned.

    The overlapped Allan covariance ``Σ Δ²x1·Δ²x2 / (2τ²(N−2m))`` of the two phase
    series, with allantools' conventions (``taus``, ``ns = N − 2m``,
    ``errs = devs/sqrt(ns)``). allantools drops the sign; :func:`sigmatau.gcodev`
    keeps it (a negative covariance is information: the two series share a device
    with opposite signs).

    See Also
    --------
    sigmatau.gcodev : the signed covariance with sigmatau's conventions.
    sigmatau.cornered_hat : each device's deviation, with intervals.
    """
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    a, b = _series(data_1, dtype), _series(data_2, dtype)
    if a.size != b.size:
        raise DataError(f"gcodev: the two series have {a.size} and {b.size} samples; they must be simultaneous")
    n_phase = a.size + 1 if dtype == "freq" else a.size
    ms = _factors(taus, n_phase, rate_f, third=False, even=False)
    ms = ms[n_phase - 2 * ms > 1]
    if ms.size == 0:
        raise DataError(f"gcodev: no averaging time of {_describe(taus)} leaves more than one term"
                        f" with {n_phase} phase points at rate={rate_f:g} Hz")
    with long_factors_expected():
        res = covariance.gcodev(a, b, rate=rate_f, data_type=dtype, m=ms)
    devs = np.abs(np.asarray(res.dev, dtype=np.float64))
    ns = np.asarray(res.n, dtype=np.float64)
    return ms / rate_f, devs, devs / np.sqrt(ns), ns
