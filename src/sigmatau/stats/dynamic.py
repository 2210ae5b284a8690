"""Dynamic stability: a statistic over sliding windows of the record, and a stationarity test.

:func:`dynamic` evaluates one public statistic (OADEV by default) on windows of
``window`` samples taken every ``step`` samples — Stable32's *Dynamic
Stability*, the dynamic Allan variance of Galleani and Tavella — and returns a
(time × τ) :class:`DynamicResult` with the EDF and interval of every cell. Each
window is the statistic of those samples alone: the per-window path calls the
public function (:data:`sigmatau.stats.FUNCTIONS`) on each slice; for OADEV on
frequency data the cumulative path computes every window from one pass per τ
over the whole record and attaches the uncertainty with
:func:`sigmatau.stats.engine.finish`, with the same result to round-off (the
tests hold the two paths together).

The result carries a :class:`StationarityCheck`: at each τ a Bartlett χ²
homogeneity test of the variances of non-overlapping windows, weighted by their
EDF (from the noise type identified once on the whole record), with Holm's
correction across τ, the cells that disagree, and the time of a change of level.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, fields
from typing import Any, Callable, Literal, Optional

import numpy as np
from scipy.special import chdtrc, fdtr, fdtrc

from .engine import finish
from ..core.kernels import window_sums_by_factor
from ..core.result import StabilityResult
from ..core.taus import long_factors_expected
from ..core.validate import as_series, check_data_type, check_rate, scale_to_unit, unscale_variance
from ..errors import DataError, ParameterError, RangeWarning
from ..uncertainty.attach import CiMethod
from ..uncertainty.confidence import EDF_STATISTICS, ONE_SIGMA, edf_array
from ..uncertainty.noiseid import identify

__all__ = ["dynamic", "DynamicResult", "StationarityCheck", "DYNAMIC_METHODS", "MIN_TEST_EDF"]

#: ``method`` of :func:`dynamic`: ``"auto"`` takes ``"cumulative"`` where it applies (OADEV on
#: finite frequency data), ``"windows"`` elsewhere.
DYNAMIC_METHODS: tuple[str, ...] = ("auto", "windows", "cumulative")

#: Fewest equivalent degrees of freedom a window needs to enter the stationarity test: below it
#: the χ² model of a variance estimate, and Bartlett's approximation built on it, are too coarse.
MIN_TEST_EDF = 3.0

_WindowUnit = Literal["samples", "seconds"]
_Method = Literal["auto", "windows", "cumulative"]


# ----------------------------------------------------------------------------- results


def _frozen(value: Any, dtype: Any = float) -> np.ndarray:
    arr = np.array(value, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


def _json(value: Any) -> Any:
    """``value`` as plain Python for JSON: arrays as (nested) lists, NaN and ±inf as None."""
    if isinstance(value, np.ndarray):
        return _json(value.tolist())
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


@dataclass(frozen=True, repr=False, eq=False)
class StationarityCheck:
    """Whether the windows of a :class:`DynamicResult` agree within their uncertainty.

    Attributes
    ----------
    tested : bool
        False when no τ could be tested (fewer than two non-overlapping windows, no EDF:
        ``ci=None`` or a statistic without one); ``finding`` says why.
    flagged : bool
        The windows disagree beyond their intervals at one τ at least (Holm-adjusted
        p-value ≤ ``significance``).
    finding : str
        One readable sentence or two: what was tested, and where and how the windows differ.
    significance : float
        Family-wise error rate of the test across τ.
    test_windows : numpy.ndarray
        Indices of the non-overlapping windows the test uses.
    alpha, edf : numpy.ndarray
        Per τ: the noise type the test assumes for every window (identified once on the
        whole record, or the caller's ``alpha``) and the EDF of one window that follows
        from it (NaN where unknown).
    statistic, dof, p_value, p_adjusted : numpy.ndarray
        Per τ: Bartlett's statistic, its χ² degrees of freedom (windows tested − 1), the
        p-value and the Holm-adjusted p-value (NaN, 0 where not tested).
    rejected : numpy.ndarray of bool
        Per τ: homogeneity rejected.
    disagree : numpy.ndarray of bool
        (window × τ): at a rejected τ, the window's variance differs from the pooled variance
        of the test windows that do not overlap it (two-sided F test, Bonferroni over the
        test windows).
    change_time : float or None
        Time in seconds from the first sample of the single change of level that explains
        the rejected τ best (a boundary between two windows: to one step when ``step``
        divides ``window``, else to one window), None when not flagged.
    """

    tested: bool
    flagged: bool
    finding: str
    significance: float
    test_windows: np.ndarray
    alpha: np.ndarray
    edf: np.ndarray
    statistic: np.ndarray
    dof: np.ndarray
    p_value: np.ndarray
    p_adjusted: np.ndarray
    rejected: np.ndarray
    disagree: np.ndarray
    change_time: Optional[float] = None

    def __post_init__(self) -> None:
        for name, dtype in (("test_windows", np.int64), ("alpha", float), ("edf", float), ("statistic", float), ("dof", np.int64),
                            ("p_value", float), ("p_adjusted", float), ("rejected", bool), ("disagree", bool)):
            object.__setattr__(self, name, _frozen(getattr(self, name), dtype))

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (lists; None for NaN), JSON-ready."""
        return {f.name: _json(getattr(self, f.name)) for f in fields(self)}

    def __repr__(self) -> str:
        state = "not tested" if not self.tested else ("FLAGGED" if self.flagged else "no disagreement")
        return f"StationarityCheck({state}: {self.finding})"


@dataclass(frozen=True, repr=False, eq=False)
class DynamicResult:
    """One statistic over sliding windows: a (window × τ) grid of estimates.

    Attributes
    ----------
    statistic : str
        Name of the statistic (``"oadev"`` …).
    rate : float
        Sample rate in Hz.
    data_type : {"freq", "phase"}
        Kind of the input data.
    window, step : int
        Samples per window and between window starts.
    start, centre : numpy.ndarray
        Per window: time of its first sample and of its middle, in seconds from the first
        sample of the record (sample i is at i/rate; a window of W frequency samples spans
        W/rate, one of W phase points (W−1)/rate).
    taus, m : numpy.ndarray
        The τ grid (seconds) and averaging factors, the same for every window.
    dev : numpy.ndarray
        (window × τ) deviations.
    n : numpy.ndarray
        (window × τ) number of terms.
    edf, ci_low, ci_high : numpy.ndarray
        (window × τ) equivalent degrees of freedom and interval at ``confidence``; NaN
        where not computed (``ci=None``, noise type not identified, no EDF rule).
    alpha : numpy.ndarray
        (window × τ) noise type used for the EDF (2 WPM … −4 RRFM), NaN where unknown.
    confidence : float or None
        Two-sided coverage of the intervals.
    method : {"windows", "cumulative"}
        How the windows were computed.
    stationarity : StationarityCheck
        Whether the windows agree.
    """

    statistic: str
    rate: float
    data_type: str
    window: int
    step: int
    start: np.ndarray
    centre: np.ndarray
    taus: np.ndarray
    m: np.ndarray
    dev: np.ndarray
    n: np.ndarray
    edf: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    alpha: np.ndarray
    confidence: Optional[float]
    method: str
    stationarity: StationarityCheck

    def __post_init__(self) -> None:
        for name in ("start", "centre", "taus", "dev", "edf", "ci_low", "ci_high", "alpha"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        for name in ("m", "n"):
            object.__setattr__(self, name, _frozen(getattr(self, name), np.int64))

    @property
    def n_windows(self) -> int:
        """Number of windows."""
        return int(self.start.size)

    @property
    def var(self) -> np.ndarray:
        """(window × τ) variances, ``dev**2``."""
        return self.dev**2

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (nested lists, None for NaN), JSON-ready."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            out[f.name] = value.to_dict() if isinstance(value, StationarityCheck) else _json(value)
        return out

    def __repr__(self) -> str:
        state = ("stationarity not tested" if not self.stationarity.tested
                 else "windows disagree" if self.stationarity.flagged else "windows agree")
        if self.taus.size == 0:
            return f"DynamicResult({self.statistic}, {self.n_windows} windows, no τ)"
        return (f"DynamicResult({self.statistic}, {self.n_windows} windows of {self.window / self.rate:.4g} s"
                f" every {self.step / self.rate:.4g} s, {self.taus.size} τ from {self.taus[0]:.4g} s to"
                f" {self.taus[-1]:.4g} s, {state})")


# -------------------------------------------------------------------------- validation


def _statistic_function(statistic: object) -> Callable[..., StabilityResult]:
    # Imported here: stats/__init__ may one day import this module, and FUNCTIONS lives there.
    from . import FUNCTIONS

    if not isinstance(statistic, str) or statistic not in FUNCTIONS:
        raise ParameterError(f"statistic={statistic!r} must be one of {', '.join(FUNCTIONS)}")
    return FUNCTIONS[statistic]  # type: ignore[return-value]


def _samples(value: object, name: str, unit: str, rate: float) -> int:
    """``window`` or ``step`` as a whole number of samples."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name}={value!r} must be a number of {unit}")
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ParameterError(f"{name}={value!r} must be positive")
    count = v * rate if unit == "seconds" else v
    if count < 1.0 - 1e-6:
        extra = f" (at {rate:g} Hz)" if unit == "seconds" else ""
        raise ParameterError(f"{name}={value!r} is less than one sample{extra}; {name} must be ≥ 1 sample")
    whole = round(count)
    if abs(count - whole) > 1e-6 * max(1.0, count):
        hint = f" ({name}·rate = {count:g})" if unit == "seconds" else "; for seconds give window_unit='seconds'"
        raise ParameterError(f"{name}={value!r} must be a whole number of samples{hint}")
    return int(whole)


def _dynamic_iv(data, rate, window, step, statistic, data_type, window_unit, significance, method):
    """Validated ``(samples as given (1-D), samples as float64, statistic function, rate, data_type,
    window, step)``, window and step in samples."""
    func = _statistic_function(statistic)
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    if window_unit not in ("samples", "seconds"):
        raise ParameterError(f"window_unit={window_unit!r} must be 'samples' or 'seconds'")
    if isinstance(significance, (bool, np.bool_)) or not isinstance(significance, (int, float, np.floating)) \
            or not 0.0 < float(significance) < 1.0:
        raise ParameterError(f"significance={significance!r} must be a number in (0, 1)")
    if method not in DYNAMIC_METHODS:
        raise ParameterError(f"method={method!r} must be one of {DYNAMIC_METHODS}")
    w = _samples(window, "window", window_unit, rate_f)
    s = _samples(step, "step", window_unit, rate_f)
    series = as_series(data, remove_offset=True, gaps=True)  # shape, type, inf; exact beyond 2**53; NaN: gaps
    arr = data if isinstance(data, np.ndarray) and data.ndim == 1 else np.asarray(data).reshape(-1)
    if w > series.size:
        raise ParameterError(f"window={w} samples is longer than the record ({series.size} samples)")
    if method == "cumulative" and not (statistic == "oadev" and dtype == "freq"):
        raise ParameterError(f"method='cumulative' computes oadev on frequency data only, not {statistic}"
                             f" on {dtype} data; use method='windows'")
    if method == "cumulative" and not np.isfinite(series).all():
        raise ParameterError("method='cumulative' needs every sample present (no NaN); use method='windows'")
    return arr, series, func, rate_f, dtype, w, s


# ------------------------------------------------------------------------- computation


def _first_window(func, seg, name, window, **options) -> StabilityResult:
    """The first window with the caller's grid: it fixes the τ grid of every window."""
    try:
        first = func(seg, **options)
    except DataError as exc:
        if "needs at least" not in str(exc):
            raise
        raise ParameterError(f"window={window} samples is too short for {name} ({exc})") from None
    if len(first) == 0:
        raise ParameterError(f"window={window} samples is too short for any τ of {name}")
    return first


def _sliding_sums(v: np.ndarray, length: int, count: int) -> np.ndarray:
    """``Σ v[j : j+length]`` for j = 0 … count−1, for non-negative ``v``, in O(v.size).

    The van Herk–Gil-Werman scheme: cut ``v`` into blocks of ``length``; each window is the
    tail of one block plus the head of the next, both sums of non-negative terms, so no
    window sum is the small difference of two large running sums (a quiet window after a
    loud one keeps its digits).
    """
    rows = -(-(count + length - 1) // length)
    padded = np.zeros(rows * length)
    padded[: count + length - 1] = v[: count + length - 1]
    blocks = padded.reshape(rows, length)
    head = np.cumsum(blocks, axis=1).ravel()
    tail = np.cumsum(blocks[:, ::-1], axis=1)[:, ::-1].ravel()
    starts = np.arange(count)
    out = head[starts + length - 1].copy()
    inside = starts % length != 0
    out[inside] += tail[starts[inside]]
    return out


def _window_sumsq(d: np.ndarray, step: int, length: int, count: int) -> np.ndarray:
    """``Σ d[s : s+length]²`` for the window starts s = 0, step, … (count of them).

    With ``length = q·step + r``, window j is the blocks j … j+q−1 of ``step`` terms and the
    first r terms of block j+q: one pass over ``d`` for the block sums of squares, then
    sliding sums over the blocks (:func:`_sliding_sums`), every sum one of squares.
    """
    q, r = divmod(length, step)
    full = count - 1 + q
    blocks = d[: full * step].reshape(full, step)
    out = np.zeros(count)
    if q:
        out += _sliding_sums(np.einsum("ij,ij->i", blocks, blocks), q, count)
    if r:
        heads = blocks[q:, :r]
        out[:-1] += np.einsum("ij,ij->i", heads, heads)
        last = d[full * step : full * step + r]
        out[-1] += float(np.einsum("i,i->", last, last))
    return out


def _oadev_windows(y: np.ndarray, count: int, step: int, window: int, ms: np.ndarray) -> np.ndarray:
    """OAVAR (window × τ) of frequency samples ``y``, every window from one pass per τ.

    The kernel of :mod:`sigmatau.core.kernels` on frequency data: with ``A_m`` the sums of m
    consecutive samples, each window's variance is ``Σ (A_m[j+m] − A_m[j])² / (2m²(W−2m+1))``
    over the terms inside it; the differences are formed once for the record and their
    squares summed per window.
    """
    scaled, k = scale_to_unit(y)
    centred = scaled - scaled.mean()
    var = np.empty((count, ms.size))
    for i, m, ws in window_sums_by_factor(centred, ms):
        a = ws.a
        terms = window - 2 * m + 1
        var[:, i] = _window_sumsq(a[m:] - a[:-m], step, terms, count) / (2.0 * float(m) ** 2 * terms)
    return unscale_variance(np.where(var < 0.0, 0.0, var), k, "oadev")


def _cumulative(arr, series, starts, window, step, first, rate, alpha, confidence, ci) -> list[StabilityResult]:
    var = _oadev_windows(series, starts.size, step, window, first.m)
    out = []
    for j, s in enumerate(starts):
        raw = StabilityResult(statistic="oadev", taus=first.taus, m=first.m, var=var[j], dev=np.sqrt(var[j]),
                              n=window - 2 * first.m + 1, rate=rate, data_type="freq", n_points=window + 1)
        out.append(finish(raw, arr[s : s + window], "freq", alpha=alpha, confidence=confidence, ci=ci))
    return out


def _per_window(func, arr, starts, window, first, options) -> list[StabilityResult]:
    out = [first]
    # The first window already warned about a long factor the caller asked for.
    with long_factors_expected(), warnings.catch_warnings():
        # a window whose gaps leave no term at some factor: that cell stays empty (NaN)
        warnings.simplefilter("ignore", RangeWarning)
        for s in starts[1:]:
            out.append(_aligned(func, arr[s : s + window], first, options))
    return out


def _aligned(func, seg, first: StabilityResult, options) -> StabilityResult:
    """The statistic of one window on the first window's factors; with gaps, the factors
    without a gap-free term (or a window of nothing but gaps) are empty cells: NaN, n = 0."""
    try:
        r = func(seg, m=first.m, **options)
    except DataError:
        if not np.isnan(seg).any():
            raise
        r = dataclasses.replace(first, m=first.m[:0])  # every sample or every term reads a gap
    if r.m.size == first.m.size:
        return r
    pos = np.searchsorted(first.m, r.m)
    cells = {}
    for name in ("var", "dev", "edf", "ci_low", "ci_high", "alpha"):
        full = np.full(first.m.size, np.nan)
        v = getattr(r, name)
        if v is not None and r.m.size:
            full[pos] = v
        cells[name] = full
    n = np.zeros(first.m.size, dtype=np.int64)
    if r.m.size:
        n[pos] = r.n
    return dataclasses.replace(first, n=n, alpha_estimate=None, n_effective=None, **cells)


def _cells(results: list[StabilityResult], name: str) -> np.ndarray:
    rows = [getattr(r, name) for r in results]
    if any(v is None for v in rows):
        return np.full((len(results), len(results[0])), np.nan)
    return np.array(rows, dtype=float)


# ------------------------------------------------------------------------------- public


def dynamic(
    data: object,
    *,
    rate: float = 1.0,
    window: float,
    step: float,
    statistic: str = "oadev",
    data_type: Literal["freq", "phase"] = "freq",
    taus: object = "octave",
    m: object = None,
    points_per_decade: int = 10,
    alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
    window_unit: _WindowUnit = "samples",
    significance: float = 0.01,
    method: _Method = "auto",
) -> DynamicResult:
    """A statistic over sliding windows (dynamic Allan deviation, Stable32's Dynamic Stability).

    Parameters
    ----------
    data : array_like
        1-D samples (frequency by default, as for every statistic).
    rate : float
        Sample rate in Hz.
    window, step : int or float
        Length of each window and distance between window starts, in samples (whole
        numbers), or in seconds with ``window_unit="seconds"`` (then ``value·rate`` must be
        a whole number of samples). Windows start at 0, step, 2·step …; the last one ends
        at or before the end of the record (samples after it belong to no window).
    statistic : str
        Name of a public statistic (:data:`sigmatau.stats.FUNCTIONS`), default ``"oadev"``.
    data_type, taus, m, points_per_decade, alpha, confidence, ci
        As for the statistic itself (:func:`sigmatau.oadev`). The τ grid is the one the
        statistic chooses for a record of ``window`` samples, the same for every window.
    window_unit : {"samples", "seconds"}
        Unit of ``window`` and ``step``.
    significance : float
        Family-wise error rate of the stationarity test across τ (default 1 %).
    method : {"auto", "windows", "cumulative"}
        ``"windows"`` calls the statistic on each window; ``"cumulative"`` (OADEV on
        frequency data only) forms the squared differences once for the whole record and
        sums them per window, then attaches noise type and interval per window
        (:func:`sigmatau.stats.engine.finish`); ``"auto"`` takes it where it applies and
        the data are finite. Both give the same numbers to round-off.

    Returns
    -------
    DynamicResult
        The (window × τ) grid with its :class:`StationarityCheck`.

    Raises
    ------
    ParameterError
        Unknown statistic, step < 1 sample, window longer than the record or too short for
        any τ, a length that is not a whole number of samples, bad options.
    DataError
        Data that no statistic accepts (not 1-D, empty, non-finite …).

    Notes
    -----
    Window ``j`` holds the samples ``s_j = j·step … s_j + window − 1`` and its estimate is
    the statistic of those samples alone; for OADEV (Galleani & Tavella's dynamic Allan
    variance, with their window length N_w = ``window``),

    .. math:: σ_y^2(t_j, τ) = \\frac{1}{2τ^2(W-2m+1)} \\sum_{i=s_j}^{s_j+W-2m}
              (x_{i+2m} - 2x_{i+m} + x_i)^2 ,

    each window with its own noise type, EDF and interval. The cost is that of the
    statistic on ``window`` samples times the number of windows (noise identification
    included); the cumulative path makes the variance itself O(N) per τ for the whole
    record, leaving the per-window noise identification as the main cost (``ci=None`` or a
    fixed ``alpha`` skips it; the stationarity test still identifies the noise once on the
    whole record unless ``alpha`` is given).

    Stationarity: windows whose data do not overlap are compared at each τ by Bartlett's
    test of homogeneity of variances, each estimate ``s_j²`` taken as ``σ²χ²_ν/ν``. Under
    the hypothesis tested every window has the same noise type, so ν is the EDF of one
    window for the type identified once on the whole record (the smallest of that type's
    and its two neighbours', so that a type identified one off cannot inflate ν), or for
    the caller's ``alpha``:

    .. math:: T = \\frac{ν\\ln \\bar s^2 - \\sum_j ν_j \\ln s_j^2}
              {1 + \\frac{1}{3(k-1)}\\left(\\sum_j 1/ν_j - 1/ν\\right)} \\sim χ^2_{k-1},
              \\quad ν = \\sum_j ν_j,\\ \\bar s^2 = \\sum_j ν_j s_j^2 / ν ,

    over the k windows with ν_j ≥ :data:`MIN_TEST_EDF`. Overlapping windows are left
    out of the test because their estimates share terms. The p-values across τ (which
    share the data) are corrected by Holm's procedure, valid under any dependence, so
    the flag is raised with probability at most ``significance`` for a stationary record
    whose windows are independent; correlated windows (flicker and random-walk noise)
    make the test more conservative, not less. At a rejected τ each window is compared
    with the pooled variance of the test windows that do not overlap it (two-sided F
    test), which marks the cells that disagree, and a single change of level is located
    by the split of consecutive non-overlapping windows that maximises the likelihood ratio
    of two levels against one: to one step when ``step`` divides ``window`` (every such
    chain of windows is tried), to one window otherwise.

    References
    ----------
    L. Galleani and P. Tavella, "The dynamic Allan variance", IEEE Trans. Ultrason.,
    Ferroelectr., Freq. Control 56(3), 450–464 (2009). W. J. Riley, Stable32 User Manual,
    "Dynamic Stability". M. S. Bartlett, "Properties of sufficiency and statistical tests",
    Proc. R. Soc. A 160, 268–282 (1937). S. Holm, "A simple sequentially rejective multiple
    test procedure", Scand. J. Statist. 6, 65–70 (1979).

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau.stats.dynamic import dynamic
    >>> y = np.random.default_rng(1).normal(size=4000)
    >>> y[2000:] *= 3.0                                   # the noise triples halfway
    >>> r = dynamic(y, rate=10.0, window=500, step=250)
    >>> r.dev.shape                                       # 15 windows × 7 τ
    (15, 7)
    >>> r.stationarity.flagged, r.stationarity.change_time
    (True, 200.0)
    """
    arr, series, func, rate_f, dtype, w, s = _dynamic_iv(data, rate, window, step, statistic, data_type,
                                                         window_unit, significance, method)
    starts = np.arange(0, series.size - w + 1, s, dtype=np.int64)
    options = dict(rate=rate_f, data_type=dtype, alpha=alpha, confidence=confidence, ci=ci)
    first = _first_window(func, arr[:w], statistic, w, taus=taus, m=m, points_per_decade=points_per_decade,
                          **options)  # its τ grid is every window's (with gaps, a cell may stay empty)
    fast = method == "cumulative" or (method == "auto" and statistic == "oadev" and dtype == "freq"
                                      and bool(np.isfinite(series).all()))
    if fast:
        results = _cumulative(arr, series, starts, w, s, first, rate_f, alpha, confidence, ci)
    else:
        results = _per_window(func, arr, starts, w, first, options)
    span = w if dtype == "freq" else w - 1
    start_t = starts / rate_f
    dev = _cells(results, "dev")
    test_alpha, test_edf = _test_noise(series, first, w if dtype == "phase" else w + 1, alpha)
    n = np.array([r.n for r in results], dtype=np.int64)
    check = _stationarity_check(dev, test_alpha, test_edf, starts, w, s, start_t, start_t + span / rate_f,
                                first.taus, significance=float(significance), n=n)
    return DynamicResult(
        statistic=first.statistic, rate=rate_f, data_type=dtype, window=w, step=s,
        start=start_t, centre=start_t + 0.5 * span / rate_f, taus=first.taus, m=first.m, dev=dev,
        n=n, edf=_cells(results, "edf"), ci_low=_cells(results, "ci_low"),
        ci_high=_cells(results, "ci_high"), alpha=_cells(results, "alpha"), confidence=first.confidence,
        method="cumulative" if fast else "windows", stationarity=check,
    )


# ------------------------------------------------------------------------ stationarity


def _test_noise(series, first, n_points, alpha) -> tuple[np.ndarray, np.ndarray]:
    """Per τ: the noise type every window shares under stationarity, and the EDF the test gives a window.

    The type is identified once on the whole record (:func:`sigmatau.noiseid.identify`, at
    the factor of each τ as the statistic itself does) unless the caller forces ``alpha``:
    the record has many more averages than one window. An identified type can still be one
    off near a boundary, and one type whiter claims several times the degrees of freedom at
    long τ (OADEV, m = 128 of 1000 samples: 44 for FPM against 10 for WFM), which would make
    the test reject stationary records: the EDF is the smallest of the identified type and
    its two neighbours.
    """
    n_tau = first.m.size
    nan = np.full(n_tau, np.nan)
    if first.statistic not in EDF_STATISTICS:
        return nan, nan
    if alpha is not None:
        a = np.full(n_tau, float(alpha))
        shifts: tuple[int, ...] = (0,)
    else:
        factors = np.maximum(1, np.round(first.taus * first.rate)).astype(np.int64)
        try:
            ident = identify(series, factors, data_type=first.data_type, family=first.statistic)
        except DataError:
            return nan, nan
        a = np.asarray(ident.alpha, dtype=float)
        shifts = (-1, 0, 1)
    nu = np.full(n_tau, np.inf)
    for shift in shifts:
        cand = a + shift
        ok = np.isfinite(cand) & (cand >= -4) & (cand <= 2)
        if ok.any():
            vals = np.full(n_tau, np.nan)
            vals[ok] = edf_array(first.statistic, cand[ok].astype(np.int64), first.m[ok], n_points,
                                 unsupported="nan")
            nu = np.where(np.isfinite(vals), np.minimum(nu, vals), nu)
    return a, np.where(np.isfinite(nu), nu, np.nan)


def _bartlett(v: np.ndarray, nu: np.ndarray) -> float:
    """Bartlett's homogeneity statistic of variances ``v`` with degrees of freedom ``nu``."""
    k = v.size
    total = float(nu.sum())
    pooled = float(np.dot(nu, v)) / total
    t = total * math.log(pooled) - float(np.dot(nu, np.log(v)))
    c = 1.0 + (float(np.sum(1.0 / nu)) - 1.0 / total) / (3.0 * (k - 1))
    return max(t / c, 0.0)


def _holm(p: np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values (NaN stays NaN)."""
    out = np.full(p.shape, np.nan)
    ok = np.flatnonzero(np.isfinite(p))
    if ok.size == 0:
        return out
    order = ok[np.argsort(p[ok], kind="stable")]
    scaled = (ok.size - np.arange(ok.size)) * p[order]
    out[order] = np.minimum(np.maximum.accumulate(scaled), 1.0)
    return out


def _split_ratio(v: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Likelihood-ratio statistic of a change of variance between positions b−1 and b, b = 1 … k−1."""
    total = nu.sum()
    whole = total * math.log(np.dot(nu, v) / total)
    cn, cv = np.cumsum(nu), np.cumsum(nu * v)
    na, va = cn[:-1], cv[:-1]
    nb, vb = total - na, cv[-1] - va
    return whole - na * np.log(va / na) - nb * np.log(vb / nb)


def _stationarity_check(dev: np.ndarray, test_alpha: np.ndarray, test_edf: np.ndarray, starts: np.ndarray,
                        window: int, step: int, start_t: np.ndarray, end_t: np.ndarray, taus: np.ndarray, *,
                        significance: float, n: Optional[np.ndarray] = None) -> StationarityCheck:
    """The stationarity test of :func:`dynamic` on a (window × τ) grid (see its Notes).

    ``n`` (window × τ terms): a window whose gaps leave it fewer terms than the fullest window
    at that τ gets the EDF scaled by the share of terms it kept.
    """
    n_win, n_tau = dev.shape
    edf = np.broadcast_to(test_edf, dev.shape)
    if n is not None:
        full = np.maximum(n.max(axis=0), 1)
        edf = edf * (n / full)
    stride = -(-window // step)  # windows this far apart share no sample
    test = np.arange(0, n_win, stride)
    var = dev**2
    usable = np.isfinite(var) & (var > 0) & np.isfinite(edf) & (edf >= MIN_TEST_EDF)
    stat = np.full(n_tau, np.nan)
    dof = np.zeros(n_tau, dtype=np.int64)
    p = np.full(n_tau, np.nan)
    for c in range(n_tau):
        rows = test[usable[test, c]]
        if rows.size >= 2:
            stat[c] = _bartlett(var[rows, c], edf[rows, c])
            dof[c] = rows.size - 1
            p[c] = float(chdtrc(dof[c], stat[c]))
    adjusted = _holm(p)
    rejected = np.isfinite(adjusted) & (adjusted <= significance)
    disagree = np.zeros((n_win, n_tau), dtype=bool)
    for c in np.flatnonzero(rejected):
        disagree[:, c] = _disagreeing(var[:, c], edf[:, c], usable[:, c], test, starts, window, significance)
    change = (_change_point(var, edf, usable, rejected, _tilings(n_win, window, step, test), start_t, end_t)
              if rejected.any() else None)
    finding = _finding(test, taus, p, adjusted, rejected, var, usable, change, disagree, start_t, end_t,
                       significance, n_win)
    return StationarityCheck(tested=bool(np.isfinite(p).any()), flagged=bool(rejected.any()), finding=finding,
                             significance=significance, test_windows=test, alpha=test_alpha,
                             edf=test_edf, statistic=stat, dof=dof, p_value=p,
                             p_adjusted=adjusted, rejected=rejected, disagree=disagree,
                             change_time=None if change is None else change[0])


def _disagreeing(v, nu, usable, test, starts, window, significance) -> np.ndarray:
    """Windows whose variance differs from the pooled variance of the test windows not overlapping them."""
    out = np.zeros(v.size, dtype=bool)
    rows = test[usable[test]]
    level = significance / max(rows.size, 1)
    for j in np.flatnonzero(usable):
        others = rows[np.abs(starts[rows] - starts[j]) >= window]
        if others.size == 0:
            continue
        nu_r = float(nu[others].sum())
        f = v[j] / (float(np.dot(nu[others], v[others])) / nu_r)
        two_sided = 2.0 * min(float(fdtr(nu[j], nu_r, f)), float(fdtrc(nu[j], nu_r, f)))
        out[j] = two_sided < level
    return out


def _tilings(n_win: int, window: int, step: int, test: np.ndarray) -> list[np.ndarray]:
    """Sets of windows that follow each other without overlap or gap, for locating a change.

    When ``step`` divides ``window`` every residue class of the window index modulo
    window/step is such a set, so a change is located to one step; otherwise the test
    windows alone (to one window).
    """
    if window % step:
        return [test]
    per = window // step
    return [np.arange(r, n_win, per) for r in range(min(per, n_win))]


def _change_point(var, edf, usable, rejected, tilings, start_t, end_t) -> Optional[tuple[float, float, int]]:
    """``(time, deviation ratio after/before, τ column)`` of the single change of level that fits best.

    For each tiling and each split of it into windows before and after, the likelihood ratio
    of two variance levels against one (:func:`_split_ratio`) per degree of freedom, summed
    over the rejected τ; the largest wins.
    """
    best: Optional[tuple[float, np.ndarray, int, list[int]]] = None
    for rows in tilings:
        cols = [c for c in np.flatnonzero(rejected) if rows.size >= 2 and usable[rows, c].all()]
        if not cols:
            continue
        # Per degree of freedom: tilings hold different numbers of windows, and the ratio grows
        # with the data behind it.
        lr = sum(_split_ratio(var[rows, c], edf[rows, c]) / edf[rows, c].sum() for c in cols)
        k = int(np.argmax(lr))
        if best is None or lr[k] > best[0]:
            best = (float(lr[k]), rows, k + 1, cols)
    if best is None:
        return None
    _, rows, b, cols = best
    col = max(cols, key=lambda c: _split_ratio(var[rows, c], edf[rows, c])[b - 1])
    v, nu = var[rows, col], edf[rows, col]
    before = np.dot(nu[:b], v[:b]) / nu[:b].sum()
    after = np.dot(nu[b:], v[b:]) / nu[b:].sum()
    time = 0.5 * (end_t[rows[b - 1]] + start_t[rows[b]])
    return float(time), float(math.sqrt(after / before)), int(col)


def _finding(test, taus, p, adjusted, rejected, var, usable, change, disagree, start_t, end_t,
             significance, n_win) -> str:
    if test.size < 2:
        return (f"not tested: {n_win} window(s) give {test.size} non-overlapping one(s); at least two are"
                " needed (a shorter window or a longer record)")
    if not np.isfinite(p).any():
        return (f"not tested: no τ has an EDF ≥ {MIN_TEST_EDF:g} in two non-overlapping windows"
                " (ci=None, a statistic without EDF, or windows too short)")
    tested = int(np.isfinite(p).sum())
    smallest = float(np.nanmin(adjusted))
    head = f"{test.size} non-overlapping windows compared at {tested} τ (Bartlett, Holm, level {significance:g})"
    if not rejected.any():
        return f"{head}: no disagreement beyond their intervals (smallest adjusted p = {smallest:.2g})"
    hit = np.flatnonzero(rejected)
    where = (f"τ = {taus[hit[0]]:.3g} s" if hit.size == 1
             else f"{hit.size} τ from {taus[hit[0]]:.3g} s to {taus[hit[-1]]:.3g} s")
    text = f"{head}: the windows disagree at {where} (smallest adjusted p = {smallest:.2g})"
    marked = np.flatnonzero(disagree.any(axis=1))
    if marked.size:
        text += (f"; {marked.size} of {n_win} windows differ from the rest"
                 f" ({start_t[marked[0]]:.6g} s … {end_t[marked[-1]]:.6g} s)")
    if change is not None:
        time, ratio, col = change
        text += (f"; a single change of level fits best at t ≈ {time:.6g} s"
                 f" (deviation after/before × {ratio:.3g} at τ = {taus[col]:.3g} s)")
    return text
