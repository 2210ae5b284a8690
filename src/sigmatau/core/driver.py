"""One statistic's kernel over a τ grid, packaged as a result (no noise type or interval).

Every estimator is described by a :class:`Statistic`; :func:`compute` validates
the inputs, converts frequency data to phase when the kernel wants phase,
chooses the averaging factors and builds the raw
:class:`~sigmatau.core.result.StabilityResult`. The statistics layer adds the
noise type and interval (:func:`sigmatau.stats.engine.run`). Records that are
computed piecewise reach the statistics through the :class:`StreamedSeries`
protocol defined here and implemented by the scale-out layer.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator, Optional, Protocol

import numpy as np

from .validate import (
    as_series, check_data_type, check_rate, remove_linear_phase, scale_to_unit, to_phase, unscale_variance,
)
from ..errors import DataError, ParameterError, RangeWarning, caller_stacklevel
from .accel import fused_for
from .gaps import GapKernel, detrended_phase, missing_mask, pooled_over_runs, present_runs
from .result import StabilityResult
from .shared import derived, memoized
from .taus import select_m

__all__ = [
    "Statistic", "ScaledPhase", "StreamedSeries", "GappedPhase", "compute", "gap_free_runs", "gapped_phase",
    "drop_empty_factors", "is_streamed", "prepare", "prepare_scaled", "register_streamed", "streamed",
    "validated_samples",
]

#: ``compute(x, ms, tau0) -> (var, n)``: variance and number of terms for each
#: averaging factor in ``ms``, from the phase series ``x``.
Kernel = Callable[[np.ndarray, np.ndarray, float], "tuple[np.ndarray, np.ndarray]"]


@dataclass(frozen=True)
class Statistic:
    """Description of one estimator.

    Attributes
    ----------
    name : str
        Public name, e.g. ``"oadev"``.
    compute : Kernel
        Vectorised over the averaging factors; receives the phase series.
    max_m : callable
        Mathematical largest factor for N phase points.
    stop_ratio : float
        Keyword grids stop at ``⌊N/stop_ratio⌋`` (Stable32 convention).
    min_points : int
        Fewest phase points the estimator needs at its smallest factor.
    min_m : int
        Smallest factor (2 for the Theo family).
    even : bool
        Only even factors are valid (Theo family).
    tau_factor : float
        τ = tau_factor·m·τ0 (0.75 for the Theo family).
    trend_invariant : bool
        The estimator ignores a linear phase trend (a constant frequency offset),
        so the driver removes it before ``compute`` to protect precision.
    compute_freq : Kernel, optional
        Same contract as ``compute`` but receives the frequency samples (mean
        removed when ``trend_invariant``) instead of the phase. Used for
        frequency input: differencing the samples themselves avoids the
        round-off of an integrated phase that is much larger than its
        differences (random-walk and random-run FM, drifting sensors).
    """

    name: str
    compute: Kernel
    max_m: Callable[[int], int]
    stop_ratio: float
    min_points: int
    min_m: int = 1
    even: bool = False
    tau_factor: float = 1.0
    trend_invariant: bool = True
    compute_freq: Optional[Kernel] = None
    phase_gaps: Optional[GapKernel] = None
    freq_gaps: Optional[GapKernel] = None
    pooling: str = "mean"
    terms_per_point: Optional[Callable[[np.ndarray], np.ndarray]] = None
    min_run_points: Optional[int] = None


class StreamedSeries(Protocol):
    """A record computed piecewise, never loaded whole (:class:`sigmatau.chunked.ChunkedSeries`).

    The statistics reach such a record only through these two methods, the way
    numpy reaches ``__array_function__``: the core defines the protocol, the
    scale-out layer implements it. Foreign types (dask arrays) are turned into
    one by the adapters that layer registers with :func:`register_streamed`.
    """

    def __sigmatau_statistic__(self, stat: Statistic, **options: Any) -> StabilityResult:
        """Compute ``stat`` with the options of :func:`sigmatau.stats.engine.run`."""

    def __sigmatau_finish__(self, result: StabilityResult, data_type: str, **options: Any) -> StabilityResult:
        """Attach noise type, EDF and interval to ``result`` (:func:`sigmatau.stats.engine.finish`)."""


#: ``(claims, adapt)`` pairs: ``claims(data)`` says, from the type alone, that ``data`` is a record
#: of that kind; ``adapt(data)`` turns it into a :class:`StreamedSeries` (and may refuse it).
_ADAPTERS: list[tuple[Callable[[object], bool], Callable[[object], StreamedSeries]]] = []


def register_streamed(claims: Callable[[object], bool], adapt: Callable[[object], StreamedSeries]) -> None:
    """Register a foreign record type: ``claims(data) -> bool`` (cheap, by type) and ``adapt(data)``."""
    if (claims, adapt) not in _ADAPTERS:
        _ADAPTERS.append((claims, adapt))


def _claimed(data: object) -> Optional[Callable[[object], StreamedSeries]]:
    if isinstance(data, np.ndarray):  # the common case: no adapter asked
        return None
    return next((adapt for claims, adapt in _ADAPTERS if claims(data)), None)


def is_streamed(data: object) -> bool:
    """Whether ``data`` is computed piecewise (a :class:`StreamedSeries` or a registered foreign type)."""
    return hasattr(type(data), "__sigmatau_statistic__") or _claimed(data) is not None


def streamed(data: object) -> Optional[StreamedSeries]:
    """``data`` as a :class:`StreamedSeries`, or None for in-memory data."""
    if hasattr(type(data), "__sigmatau_statistic__"):
        return data  # type: ignore[return-value]
    adapt = _claimed(data)
    return None if adapt is None else adapt(data)


def _refuse_streamed(stat: Statistic, data: object) -> None:
    # By type only: the record is refused before any adapter looks at its contents.
    if is_streamed(data):
        raise ParameterError(f"{stat.name} does not accept chunked data; see sigmatau.chunked.STATISTICS")


def _offset_free(stat: Statistic, data_type: str) -> bool:
    """The statistic ignores a constant added to the data: every one does to phase (they use
    phase differences only); to frequency only those that ignore a frequency offset."""
    return data_type == "phase" or stat.trend_invariant


def _validated(stat: Statistic, data: object, rate: object, data_type: object) -> tuple[np.ndarray, float, str, int, int]:
    """Validated ``(samples, rate, data_type, n_points, k)``; N = number of phase points.

    The samples are scaled by the exact power of two 2**-k that brings their largest
    magnitude into [0.5, 1) (:func:`~sigmatau.core.validate.scale_to_unit`); integer data
    beyond ±2**53 are first taken exactly relative to their first value when the
    statistic ignores that offset.
    """
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    series, k = validated_samples(data, remove_offset=_offset_free(stat, dtype))
    n_points = series.size if dtype == "phase" else series.size + 1
    if n_points < stat.min_points:
        kind = "phase" if dtype == "phase" else "frequency"
        need = stat.min_points if dtype == "phase" else stat.min_points - 1
        raise DataError(f"{stat.name} needs at least {need} {kind} samples, got {series.size}")
    return series, rate_f, dtype, n_points, k


def validated_samples(data: object, *, remove_offset: bool) -> tuple[np.ndarray, int]:
    """``scale_to_unit(as_series(data, remove_offset=...))``: the samples every kernel sees, and k.

    Computed once per :func:`~sigmatau.core.shared.shared_record` scope for the
    scope's record (the main job's channel); ``remove_offset`` changes the samples
    only for integer data, so float data share one copy whatever it is. Missing
    samples (NaN, masked values) are kept as NaN (:mod:`sigmatau.core.gaps`).
    """
    float_array = isinstance(data, np.ndarray) and not np.issubdtype(data.dtype, np.integer)
    return derived(data, ("validated", remove_offset and not float_array),
                   lambda: scale_to_unit(as_series(data, remove_offset=remove_offset, gaps=True)))


def _phase_of(stat: Statistic, series: np.ndarray, rate: float, dtype: str) -> np.ndarray:
    # Shared by the statistics of a record (TOTDEV and TheoH both integrate the same samples).
    return derived(series, ("phase", stat.trend_invariant, rate, dtype),
                   lambda: _phase_from(stat.trend_invariant, series, rate, dtype))


def _phase_from(trend_invariant: bool, series: np.ndarray, rate: float, dtype: str) -> np.ndarray:
    if not trend_invariant:
        return to_phase(series, rate, dtype)
    if dtype == "freq":
        fast = fused_for(series.size)
        if fast is not None:  # the same values, without the record-sized centred copy
            return fast.phase_of_freq(series, _mean(series), rate)
        return to_phase(series - series.mean(), rate, dtype)
    return remove_linear_phase(series)


#: Largest |binary exponent| of the phase :func:`prepare` hands out: its squares and their
#: sums over any record (< 2**60 terms) stay inside float64's normal range.
_PREPARE_EXPONENT = 450


def prepare(stat: Statistic, data: object, rate: object, data_type: object) -> tuple[np.ndarray, float, str]:
    """Validate the data and return ``(phase, rate, data_type)``.

    The phase has its linear trend removed when the statistic is invariant to it,
    and is in the user's unit (not scaled). Its magnitude is checked so that the
    caller's kernel cannot overflow or underflow: a phase beyond 2**±450
    (≈ 1e±135) is a DataError. :func:`~sigmatau.stats.engine.finish` checks the variance again.
    """
    _refuse_streamed(stat, data)
    series, rate_f, dtype, _, k = _validated(stat, data, rate, data_type)
    x_unit = _phase_of(stat, series, rate_f, dtype)
    with np.errstate(over="ignore", under="ignore"):  # an inf or 0 peak is refused below
        x = np.ldexp(x_unit, k)
    peak = float(np.max(np.abs(x)))
    if peak != 0.0 and not 2.0 ** -_PREPARE_EXPONENT <= peak <= 2.0 ** _PREPARE_EXPONENT:
        raise DataError(
            f"{stat.name}: the phase of these data reaches {peak:.3g}, outside the range this statistic"
            f" computes safely ({2.0 ** -_PREPARE_EXPONENT:.1e} … {2.0 ** _PREPARE_EXPONENT:.1e});"
            " rescale the data (another unit) or change the rate"
        )
    return x, rate_f, dtype


@dataclass(frozen=True)
class ScaledPhase:
    """Phase of validated data scaled by an exact power of two (:func:`prepare_scaled`).

    Attributes
    ----------
    phase : numpy.ndarray
        The phase (linear trend removed when the statistic ignores it) × 2**-exponent.
    rate : float
        Validated sample rate in Hz.
    data_type : {"freq", "phase"}
        Kind of the user's data.
    exponent : int
        k: a variance computed from ``phase`` is the user's × 4**-k; undo it with
        :func:`sigmatau.core.validate.unscale_variance` ``(var, k, name)``.
    """

    phase: np.ndarray
    rate: float
    data_type: str
    exponent: int


def prepare_scaled(stat: Statistic, data: object, rate: object, data_type: object) -> ScaledPhase:
    """Validate the data and return its phase scaled near 1 (see :class:`ScaledPhase`).

    For a statistic whose kernel is called outside :func:`~sigmatau.stats.engine.run` (TheoBR, TheoH): the
    same scaling as :func:`~sigmatau.stats.engine.run`, so data at any scale whose variance float64 can hold
    give the scale-1 answer, while :func:`prepare` refuses a phase beyond 2**±450.
    Every estimator is homogeneous of degree two, var(c·x) = c²·var(x), and a power
    of two changes no digit of the data.
    """
    _refuse_streamed(stat, data)
    series, rate_f, dtype, _, k = _validated(stat, data, rate, data_type)
    return ScaledPhase(_phase_of(stat, series, rate_f, dtype), rate_f, dtype, k)


@dataclass(frozen=True)
class GappedPhase:
    """A validated record with missing samples, as gap-free phase runs (:func:`gapped_phase`).

    Attributes
    ----------
    runs : list of numpy.ndarray
        The phase of each gap-free run (frequency runs integrated; linear trend
        removed per run when the statistic ignores it), scaled by 2**-exponent.
    rate, data_type, exponent
        As in :class:`ScaledPhase`.
    n_points : int
        Phase points of the whole record, gaps included.
    n_missing : int
        Missing samples.
    """

    runs: list
    rate: float
    data_type: str
    exponent: int
    n_points: int
    n_missing: int


def gapped_phase(stat: Statistic, data: object, rate: object, data_type: object) -> Optional[GappedPhase]:
    """The record as gap-free phase runs, or None when no sample is missing.

    For statistics that call their kernels themselves (TheoBR, TheoH): with gaps they
    pool their kernels over the runs (:func:`sigmatau.core.gaps.pooled_over_runs`).
    """
    _refuse_streamed(stat, data)
    series, rate_f, dtype, n_points, k = _validated(stat, data, rate, data_type)
    missing = missing_mask(series)
    if missing is None:
        return None
    plain = replace(stat, compute_freq=None)  # runs as phase, whatever the data type
    runs = list(gap_free_runs(plain, series, missing, rate_f, dtype))
    return GappedPhase(runs, rate_f, dtype, k, int(n_points), int(np.count_nonzero(missing)))


def compute(
    stat: Statistic,
    data: object,
    *,
    rate: object,
    data_type: object,
    taus: object,
    m: object,
    points_per_decade: int = 10,
) -> tuple[StabilityResult, np.ndarray]:
    """Compute ``stat`` on in-memory ``data``: the raw variance, no noise type or interval.

    Returns the result and the validated samples as the kernel saw them (scaled;
    noise identification is scale-invariant and works on them).

    The kernel runs on the data scaled by an exact power of two, 2**-k, into
    [0.5, 1) and the variance is multiplied back by 4**k: every statistic is
    homogeneous of degree two (var(c·x) = c²·var(x)), so the result is the same
    while no intermediate square can overflow or underflow. A variance that
    float64 cannot hold is a DataError, never inf or 0.
    """
    series, rate_f, dtype, n_points, k = _validated(stat, data, rate, data_type)
    given = series
    missing = missing_mask(series)
    use_freq = dtype == "freq" and stat.compute_freq is not None
    kernel = stat.compute_freq if use_freq else stat.compute
    if missing is None:  # with gaps, _with_gaps prepares the samples itself
        if use_freq:
            kernel, series = _freq_kernel(stat, series)
        else:
            series = _phase_of(stat, series, rate_f, dtype)
    ms = select_m(
        stat.name,
        n_points=n_points,
        rate=rate_f,
        taus=taus,
        m=m,
        points_per_decade=points_per_decade,
        m_min=stat.min_m,
        m_max=stat.max_m(n_points),
        stop_ratio=stat.stop_ratio,
        even=stat.even,
        tau_factor=stat.tau_factor,
    )
    tau0 = 1.0 / rate_f
    n_eff = None
    if missing is not None:
        var, n, n_eff = _with_gaps(stat, series, missing, rate_f, dtype, ms)
        explicit = m is not None or not isinstance(taus, str)
        ms, var, n, n_eff = drop_empty_factors(stat.name, ms, var, n, n_eff, explicit=explicit)
    elif ms.size:
        var, n = kernel(series, ms, tau0)
    else:
        var, n = np.empty(0), np.empty(0, dtype=np.int64)
    var = np.asarray(var, dtype=float)
    # Round-off can leave a tiny negative variance for constant data.
    var = unscale_variance(np.where(var < 0.0, 0.0, var), k, stat.name)
    result = StabilityResult(
        statistic=stat.name,
        taus=stat.tau_factor * ms * tau0,
        m=ms,
        var=var,
        dev=np.sqrt(var),
        n=np.asarray(n, dtype=np.int64),
        rate=rate_f,
        data_type=dtype,
        n_points=int(n_points),
    )
    if missing is not None:
        result = replace(result, n_missing=int(np.count_nonzero(missing)), n_effective=n_eff)
    return result, given


def _freq_kernel(stat: Statistic, series: np.ndarray) -> tuple[Kernel, np.ndarray]:
    """``stat.compute_freq`` and the samples it takes (mean removed when the statistic ignores it).

    A kernel with a compiled twin (:func:`sigmatau.core.accel.twin`) chosen for this record
    removes the mean in its loop: the samples go unchanged, and no centred copy of the record
    is made.
    """
    kernel = stat.compute_freq
    assert kernel is not None
    name = getattr(kernel, "fused_name", None)
    fast = fused_for(series.size) if name is not None else None
    if fast is not None:
        mean = _mean(series) if stat.trend_invariant else 0.0
        compiled = getattr(fast, name)
        return (lambda y, ms, tau0: compiled(y, ms, tau0, mean=mean)), series
    return kernel, (series - series.mean() if stat.trend_invariant else series)


def _mean(series: np.ndarray) -> float:
    """``series.mean()``, once per record in a shared scope (each frequency statistic removes it)."""
    return memoized(series, ("mean",), lambda: float(series.mean()))


def _with_gaps(stat: Statistic, series: np.ndarray, missing: np.ndarray, rate: float, dtype: str,
               ms: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(var, n, n_equivalent)`` of ``stat`` on scaled samples with NaN gaps (:mod:`sigmatau.core.gaps`)."""
    tau0 = 1.0 / rate
    if ms.size == 0:
        empty = np.empty(0, dtype=np.int64)
        return np.empty(0), empty, empty
    own = stat.freq_gaps if dtype == "freq" else stat.phase_gaps
    if own is not None:
        if dtype == "freq":
            samples = series - np.nanmean(series) if stat.trend_invariant else series
        else:
            samples = detrended_phase(series) if stat.trend_invariant else series
        return own(samples, ms, tau0)
    runs = gap_free_runs(stat, series, missing, rate, dtype)
    use_freq = dtype == "freq" and stat.compute_freq is not None
    kernel = stat.compute_freq if use_freq else stat.compute
    extra = 1 if use_freq else 0  # a kernel on y of L samples sees L + 1 phase points
    return pooled_over_runs(kernel, runs, lambda size: size + extra, stat.max_m, _run_minimum(stat), ms, tau0,
                            pooling=stat.pooling, terms_per_point=stat.terms_per_point)


def _run_minimum(stat: Statistic) -> int:
    return stat.min_points if stat.min_run_points is None else stat.min_run_points


def gap_free_runs(stat: Statistic, series: np.ndarray, missing: np.ndarray, rate: float,
                  dtype: str) -> Iterator[np.ndarray]:
    """The gap-free runs of validated samples, each in the form ``stat``'s ordinary kernel takes.

    Frequency samples go to ``compute_freq`` (mean removed when the statistic ignores it) or are
    integrated to phase; phase runs lose their linear trend when the statistic ignores it.
    Runs are yielded one at a time, so only one is converted at once.
    """
    starts, stops = present_runs(missing)
    extra = 1 if dtype == "freq" else 0
    for a, b in zip(starts.tolist(), stops.tolist()):
        if b - a + extra < _run_minimum(stat) or stat.max_m(b - a + extra) < stat.min_m:
            continue
        run = series[a:b]
        if dtype == "freq" and stat.compute_freq is not None:
            yield run - run.mean() if stat.trend_invariant else run
        else:
            yield _phase_from(stat.trend_invariant, run, rate, dtype)


def drop_empty_factors(name: str, ms: np.ndarray, var: np.ndarray, n: np.ndarray, n_eff: np.ndarray, *,
                       explicit: bool, allow_empty: bool = False
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Drop the factors at which every term reads a gap; say so when the user asked for them.

    Raises DataError when none is left (unless ``allow_empty``: one part of a hybrid statistic).
    """
    keep = np.asarray(n) > 0
    if not keep.any() and not (allow_empty or ms.size == 0):
        raise DataError(f"{name}: every term reads a missing sample (gap) at every averaging factor;"
                        " the record has no gap-free stretch long enough")
    if not keep.all() and explicit:
        warnings.warn(
            f"{name}: no gap-free term at m={ms[~keep].tolist()}; those factors are left out",
            RangeWarning, stacklevel=caller_stacklevel(),
        )
    return ms[keep], np.asarray(var)[keep], np.asarray(n)[keep], np.asarray(n_eff)[keep]
