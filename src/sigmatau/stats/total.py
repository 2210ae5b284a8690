"""Total family: TOTDEV, MTOTDEV, TTOTDEV and HTOTDEV.

The total variances extend the data beyond both ends by reflection before
differencing, so long averaging times use every sample and get more degrees of
freedom than the plain estimators at the same τ.

* TOTVAR reflects the phase record at both ends; O(N) per τ. The kernel reads
  reflected values only for the edge terms and streams the interior from the
  record in chunks, so it never holds the 3N-point extension.
* MTOT, TTOT and HTOT detrend and reflect every 3m-point subsequence
  separately. The direct kernel (:func:`~sigmatau.stats.total_sums.tot_sums`) costs O(N·m) per τ:
  inside each subsequence the m-averages of the 9m-point extension come from
  one running sum of the 3m detrended points. Subsequences are processed in
  blocks whose size keeps every temporary array near
  :data:`~sigmatau.stats.total_sums.BLOCK_ELEMENTS`
  values, so the peak memory is O(N) + O(block·m), never O(N·m). It serves
  m = 1; every larger factor goes to :func:`~sigmatau.stats.total_sums.tot_sums_fast`, which expands
  the sum of squares into running sums and costs O(N) time and memory per τ.

Each estimator ignores a linear phase trend (TOTVAR extends a line as a line,
MTOT removes a slope from every subsequence, HTOT removes a linear frequency
drift, which contains a frequency offset), so the driver may remove the mean
frequency first to protect precision. The plain definitions written with
explicit loops are in ``tests/test_total.py``, which holds these fast paths to
them.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal, Optional

import numpy as np

from ..core.accel import twin
from ..core.driver import Statistic
from ..core.gaps import equivalent_points, nan_terms_variance
from ..core.taus import STOP_RATIOS
from .engine import finish, run
from ..core.numeric import CHUNK
from ..uncertainty.attach import CiMethod, check_options
from ..uncertainty.confidence import ONE_SIGMA
from ..core.validate import DataType
from .allan import _doc
from ..errors import ParameterError
from .hadamard import _ohvar_kernel
from ..core.result import StabilityResult
from .total_sums import tot_total

__all__ = ["totdev", "mtotdev", "ttotdev", "htotdev"]

BiasMode = Literal["none", "auto", "published", "estimator"]
_BIAS_MODES = ("none", "auto", "published", "estimator")


_DOC_BIAS = """    bias : {"none", "auto", "published", "estimator"}
        ``"none"`` returns the raw estimator. ``"published"`` divides the
        variance by the bias factors of SP1065/Stable32, ``"estimator"`` by
        factors measured by Monte-Carlo for this very estimator (see Notes).
        The factor is that of ``alpha`` when given, else of the noise type
        identified at each τ. ``"auto"`` is ``"published"`` at the identified
        noise type, as Stable32 1.53 does. ``bias`` and ``bias_factor`` of the
        result say what was applied.

"""

_MTOT_BIAS_NOTE = """    alpha 2, 1, 0, −1, −2; ``"published"`` uses the SP1065/Stable32 factors
    0.94, 0.83, 0.73, 0.70, 0.69, ``"estimator"`` the Monte-Carlo factors of
    this estimator 0.995, 0.85, 0.77, 0.72, 0.68 (numerics.md §3, §8.1). The
    SP1065 tables are raw/0.73 (white FM); Stable32 1.53 all-τ runs divide by
    the factor of the alpha identified at each τ, v1.60 octave and decade
    runs print the raw value."""


def _doc_total(func):
    """Shared parameter docs of :mod:`sigmatau.stats.allan` plus ``bias`` and ``alpha``."""
    func = _doc(func)
    doc = func.__doc__.replace("\n\n    Returns\n", "\n" + _DOC_BIAS + "    Returns\n", 1)
    func.__doc__ = doc.replace("    {mtot_bias}\n", _MTOT_BIAS_NOTE + "\n")
    return func


# --- kernels: (phase x, factors, τ0) -> (variance, number of terms) ---------------


@twin("totvar_phase")
def _totvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    """TOTVAR at each factor of ``ms`` from the phase ``x``, without building the extension.

    The sum over i = 1 … N-2 of ``(x*_{i-m} - 2x*_i + x*_{i+m})²`` reads the
    reflected series x* only where i-m < 0 or i+m > N-1, at most m-1 terms at
    each end (every term once 2m > N-1). The interior terms read ``x`` itself through three shifted views;
    only the edge blocks materialise reflected values, chunk by chunk, so the
    memory beyond ``x`` is a few :data:`~sigmatau.core.numeric.CHUNK`-sized
    buffers whatever N and m (a 3N-point extension and three N-sized
    temporaries per τ cost more in page faults than the arithmetic). Each term
    is formed by the same operations, in the same order, as the numpy
    expression ``a - 2.0*b + c`` on the extension, so every term is
    bit-identical to that construction; only the order in which the squares are
    summed differs.
    """
    n_pts = x.size
    bufs = _TotvarBuffers(min(CHUNK, max(n_pts - 2, 1)))
    var = np.empty(ms.size)
    for i, m in enumerate(ms):
        var[i] = _totvar_sum(x, int(m), bufs) / (2.0 * (m * tau0) ** 2 * (n_pts - 2))
    return var, np.full(ms.size, n_pts - 2, dtype=np.int64)


def _totvar_gaps(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """TOTVAR of phase with gaps (NaN): the record extended by reflection at its two ends
    (a reflected point is missing when its source or the mirror point is), each term
    ``x*_{i-m} − 2x*_i + x*_{i+m}``, i = 1 … N-2, used when its three points are present."""
    n_pts = x.size
    inner = x[n_pts - 2 : 0 : -1]
    ext = np.concatenate((2.0 * x[0] - inner, x, 2.0 * x[-1] - inner))
    off = n_pts - 2
    var, n, neq = np.empty(ms.size), np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
    for k, m in enumerate(ms.tolist()):
        t = ext[off + 1 - m : off + n_pts - 1 - m] - 2.0 * ext[off + 1 : off + n_pts - 1] + ext[off + 1 + m : off + n_pts - 1 + m]
        var[k], n[k] = nan_terms_variance(t, 2.0 * (m * tau0) ** 2)
        neq[k] = equivalent_points(n_pts, n_pts - 2, int(n[k]))
    return var, n, neq


class _TotvarBuffers:
    """Scratch arrays of one :func:`_totvar_kernel` call, reused across factors and chunks.

    ``work`` holds the second differences of one chunk; ``left`` and ``right``
    hold the reflected operands ``x*_{i-m}`` and ``x*_{i+m}`` of an edge chunk
    (both may be needed at once when 2m > N, where one chunk spans both ends).
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self.work = np.empty(size)
        self.left = np.empty(size)
        self.right = np.empty(size)


def _totvar_sum(x: np.ndarray, m: int, bufs: _TotvarBuffers) -> float:
    """``Σ_{i=1}^{N-2} (x*_{i-m} - 2x*_i + x*_{i+m})²`` for one factor ``m`` (1 ≤ m ≤ N-1).

    The i range splits into ``[1, a)`` (i < m: the left operand is reflected),
    the interior ``[a, b)`` (m ≤ i ≤ N-1-m: all three operands are samples of
    ``x``) and ``[b, N-1)`` (the right operand is reflected, and for 2m > N-1
    possibly the left one too). With ``a = min(m, N-1)`` and
    ``b = max(N-m, a)`` the interior is empty exactly when no i satisfies both
    bounds, and the edge ranges then cover every term.
    """
    n_pts = x.size
    a = min(max(1, m), n_pts - 1)
    b = max(min(n_pts - 1, n_pts - m), a)
    total = _d2_sumsq(x[a - m : b - m], x[a:b], x[a + m : b + m], bufs) if b > a else 0.0
    total += _edge_sumsq(x, m, 1, a, bufs)
    total += _edge_sumsq(x, m, b, n_pts - 1, bufs)
    return total


def _edge_sumsq(x: np.ndarray, m: int, lo: int, hi: int, bufs: _TotvarBuffers) -> float:
    """The terms i = lo … hi-1 whose operands may fall outside ``x``, one chunk at a time."""
    total = 0.0
    for start in range(lo, hi, bufs.size):
        stop = min(start + bufs.size, hi)
        left = _xstar(x, start - m, stop - m, bufs.left)
        right = _xstar(x, start + m, stop + m, bufs.right)
        total += _d2_sumsq(left, x[start:stop], right, bufs)
    return total


def _xstar(x: np.ndarray, j0: int, j1: int, out: np.ndarray) -> np.ndarray:
    """The doubly reflected values ``x*_j``, j = j0 … j1-1 (``-(N-2) ≤ j0``, ``j1 ≤ 2N-2``).

    A view of ``x`` when the range lies inside the record (no copy), else the
    values are written to ``out``. Reflected values are computed as
    ``2.0*x[0] - x[k]`` and ``2.0*x[-1] - x[k]``, the very operations the
    extension was built with, so they carry the same bits.
    """
    n_pts = x.size
    if 0 <= j0 and j1 <= n_pts:
        return x[j0:j1]
    res = out[: j1 - j0]
    pos = 0
    if j0 < 0:  # x*_j = 2x_0 - x_{-j}, j = j0 … min(j1, 0)-1
        k = min(j1, 0) - j0
        np.subtract(2.0 * x[0], x[-j0 - k + 1 : -j0 + 1][::-1], out=res[:k])
        pos = k
    mid_lo, mid_hi = max(j0, 0), min(j1, n_pts)
    if mid_hi > mid_lo:
        res[pos : pos + mid_hi - mid_lo] = x[mid_lo:mid_hi]
        pos += mid_hi - mid_lo
    if j1 > n_pts:  # x*_j = 2x_{N-1} - x_{2N-2-j}, j = max(j0, N) … j1-1
        first = max(j0, n_pts)
        k = j1 - first
        top = 2 * n_pts - 2 - first  # index in x of the first value, counting down
        np.subtract(2.0 * x[-1], x[top - k + 1 : top + 1][::-1], out=res[pos : pos + k])
    return res


def _d2_sumsq(left: np.ndarray, mid: np.ndarray, right: np.ndarray, bufs: _TotvarBuffers) -> float:
    """``Σ (left - 2.0*mid + right)²``, chunked, each term rounded as that numpy expression.

    Three in-place passes and a sum of squares per chunk: ``w = 2.0*mid``,
    ``w = left - w``, ``w = w + right``. This is numpy's own evaluation order
    of ``left - 2.0*mid + right`` (so each term is bit-identical to the
    extension-based code), and one pass fewer than
    :func:`~sigmatau.core.numeric.sumsq_combination`, which first copies
    ``left`` and then adds ``-2.0*mid``. ``einsum`` rather than ``np.dot``:
    see :func:`~sigmatau.core.numeric.sumsq`.
    """
    n = mid.size
    size = bufs.size
    total = 0.0
    for lo in range(0, n, size):
        hi = min(lo + size, n)
        w = bufs.work[: hi - lo]
        np.multiply(mid[lo:hi], 2.0, out=w)
        np.subtract(left[lo:hi], w, out=w)
        np.add(w, right[lo:hi], out=w)
        total += float(np.einsum("i,i->", w, w))
    return total


def _mtot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        total, windows = tot_total(x, int(m))
        var[i] = total / (6.0 * m * 2.0 * (m * tau0) ** 2 * windows)
        n[i] = windows
    return var, n


def _ttot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var, n = _mtot_kernel(x, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


def _htot_formula_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    """HTOT by its defining construction at every factor, m = 1 included."""
    y = np.diff(x) / tau0
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        total, windows = tot_total(y, int(m))
        var[i] = total / (6.0 * m * 6.0 * windows)
        n[i] = windows
    return var, n


def _htot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    one = ms == 1  # Stable32 and the SP1065 tables report OHVAR at m = 1
    var[one], n[one] = _ohvar_kernel(x, ms[one], tau0)
    var[~one], n[~one] = _htot_formula_kernel(x, ms[~one], tau0)
    return var, n


TOTVAR = Statistic("totdev", _totvar_kernel, max_m=lambda n: n - 1, stop_ratio=STOP_RATIOS["totdev"], min_points=3,
                   phase_gaps=_totvar_gaps)
MTOT = Statistic("mtotdev", _mtot_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["mtotdev"], min_points=3)
TTOT = Statistic("ttotdev", _ttot_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["ttotdev"], min_points=3)
HTOT = Statistic("htotdev", _htot_kernel, max_m=lambda n: (n - 1) // 3, stop_ratio=STOP_RATIOS["htotdev"], min_points=4)


# --- bias corrections ------------------------------------------------------------

# Divisors of the raw variance, by noise exponent alpha (numerics.md §3, §8.1).
_MTOT_PUBLISHED = {2: 0.94, 1: 0.83, 0: 0.73, -1: 0.70, -2: 0.69}
_MTOT_ESTIMATOR = {2: 0.995, 1: 0.85, 0: 0.77, -1: 0.72, -2: 0.68}
_HTOT_PUBLISHED = {0: 1 - 0.005, -1: 1 - 0.149, -2: 1 - 0.229, -3: 1 - 0.283, -4: 1 - 0.321}
_HTOT_ESTIMATOR = {0: 0.994, -1: 0.850, -2: 0.771, -3: 0.717, -4: 0.679}
# TOTVAR: E[TOTVAR]/AVAR = 1 - a·τ/T (Howe); no Monte-Carlo revision.
_TOTVAR_A = {0: 0.0, -1: 1.0 / (3.0 * math.log(2.0)), -2: 0.750}

_FACTORS = {
    "mtotdev": {"published": _MTOT_PUBLISHED, "estimator": _MTOT_ESTIMATOR},
    "ttotdev": {"published": _MTOT_PUBLISHED, "estimator": _MTOT_ESTIMATOR},
    "htotdev": {"published": _HTOT_PUBLISHED, "estimator": _HTOT_ESTIMATOR},
    "totdev": {"published": _TOTVAR_A, "estimator": _TOTVAR_A},
}


def _table_name(bias: str) -> str:
    return "published" if bias == "auto" else bias


def _check_bias(name: str, bias: object, alpha: Optional[int]) -> None:
    """Validate ``bias`` (and a forced ``alpha`` against its table) before computing."""
    if bias not in _BIAS_MODES:
        raise ParameterError(f"bias={bias!r} must be one of {_BIAS_MODES}")
    if bias == "none" or alpha is None:
        return
    table = _FACTORS[name][_table_name(str(bias))]
    if alpha not in table:
        allowed = ", ".join(str(a) for a in sorted(table, reverse=True))
        raise ParameterError(f"{name}: no {_table_name(str(bias))} bias factor for alpha={alpha}; allowed: {allowed}")


def _apply_bias(res: StabilityResult, bias: str, forced: Optional[int]) -> StabilityResult:
    """Divide the variance by the bias factor of each row's noise type (``res.alpha``)."""
    if bias == "none":
        return res
    name = _table_name(bias)
    table = _FACTORS[res.statistic][name]
    alphas = res.alpha if res.alpha is not None else np.full(res.m.size, np.nan)
    coef = np.array([table.get(int(a), np.nan) if np.isfinite(a) else np.nan for a in alphas])
    missing = ~np.isfinite(coef)
    if res.statistic == "totdev":
        record = (res.n_points - 1) / res.rate
        factor = 1.0 - np.where(missing, 0.0, coef) * res.taus / record
    else:
        factor = np.where(missing, 1.0, coef)
        if res.statistic == "htotdev":
            factor[res.m == 1] = 1.0  # the OHVAR value is unbiased
    var = res.var / factor
    scaled = {}
    # A fixed divisor scales a χ² interval exactly as it scales the estimate.
    for field in ("ci_low", "ci_high"):
        if getattr(res, field) is not None:
            scaled[field] = getattr(res, field) / np.sqrt(factor)
    desc = f"{name} alpha={forced}" if forced is not None else f"{name} at the alpha identified per tau"
    if missing.any():
        desc += f" (uncorrected at {int(missing.sum())} tau whose alpha has no factor)"
    return replace(res, var=var, dev=np.sqrt(var), bias=desc, bias_factor=factor, **scaled)


def _run_total(
    stat: Statistic, data: object, rate: object, data_type: object, taus: object, m: object,
    points_per_decade: int, bias: object, alpha: object, confidence: object, ci: object,
) -> StabilityResult:
    alpha_i, _, _ = check_options(alpha, confidence, ci)
    _check_bias(stat.name, bias, alpha_i)
    res = run(stat, data, rate=rate, data_type=data_type, taus=taus, m=m,
              points_per_decade=points_per_decade, raw=True)
    # A bias correction needs each row's noise type even when no interval is wanted.
    need_alpha = bias != "none"
    res = finish(res, data, res.data_type, alpha=alpha_i, confidence=confidence,
                 ci="chi2" if (ci is None and need_alpha) else ci)
    res = _apply_bias(res, str(bias), alpha_i)
    if ci is None and need_alpha:
        res = replace(res, edf=None, ci_low=None, ci_high=None, confidence=None, ci_reason=None)
    return res


# --- public functions ------------------------------------------------------------


@_doc_total
def totdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Total deviation (TOTVAR), from the doubly reflected phase record.

    {common}
    Notes
    -----
    The N phase points are extended at both ends by odd reflection,
    ``x*_{-j} = 2x_0 - x_j`` and ``x*_{N-1+j} = 2x_{N-1} - x_{N-1-j}`` for
    j = 1 … N-2, and

    .. math:: \\mathrm{Tot}\\,σ_y^2(τ) = \\frac{1}{2τ^2(N-2)} \\sum_{i=1}^{N-2}
              (x^*_{i-m} - 2x^*_i + x^*_{i+m})^2 ,

    always ``n = N - 2`` terms, O(N) per τ. The reflection reaches indices
    ``-(N-2) … 2N-3``, so ``m ≤ N - 1``; keyword grids stop at ``m ≤ N/2``
    (Stable32), the range where the bias model holds. For frequency data the
    reflection is a half-sample mirror of the frequency samples at both ends.

    Bias: ``E[TOTVAR]/AVAR = 1 - a·τ/T`` with ``T = (N-1)τ0``, ``a = 0``
    (alpha 0), ``1/(3 ln 2)`` (alpha −1), ``0.750`` (alpha −2); the same
    factors serve both ``"published"`` and ``"estimator"``. ``bias_factor``
    holds ``1 - a·τ/T`` per τ. Stable32 applies this correction with the
    alpha its noise identification finds at each τ.

    Frequency data are differenced directly (no integration to phase), which
    keeps every digit. A program that integrates normalised frequency f/f0 ≈ 1
    to phase in float64 (Stable32 on such a file) adds that phase's rounding,
    about 1e-12 s a point after 2·10^4 points, as white phase noise: on the
    OCXO reference record its TOTDEV is 4.9e-4, 4.4e-4, 3.8e-4 too large at
    m = 1, 2, 4 (up to 1.6e-3 further on; OADEV/OHDEV up to 1.8e-3), while its
    run on y = f/f0 − 1 agrees with this function to 1e-4.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.11; D. A. Howe, "The total deviation
    approach to long-term characterization of frequency stability", IEEE TUFFC
    47(5), 2000; numerics.md §1.8, §3.

    Examples
    --------
    >>> from sigmatau import totdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in totdev(y, m=[1, 2]).dev]
    [91.22945, 93.90379]
    """
    return _run_total(TOTVAR, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def mtotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Modified total deviation (MTOT).

    {common}
    Notes
    -----
    For each of the ``N - 3m + 1`` subsequences ``s_k = x_{n+k}`` (k < 3m) the
    half-average slope ``b = [mean(s_{h2…3m-1}) - mean(s_{0…h1-1})]/h2``,
    ``h1 = ⌊3m/2⌋``, ``h2 = ⌈3m/2⌉``, is removed (``s'_k = s_k - b·k``); the
    9m-point extension ``e = [rev s', s', rev s']`` gives m-averages ``a_j`` and
    ``z_j(n) = a_j - 2a_{j+m} + a_{j+2m}``, j = 0 … 6m-1, and

    .. math:: \\mathrm{Mod\\,Tot}\\,σ_y^2(τ) = \\frac{1}{2τ^2(N-3m+1)}
              \\sum_{n=0}^{N-3m} \\frac{1}{6m} \\sum_{j=0}^{6m-1} z_j(n)^2 .

    ``n = N - 3m + 1``; ``m ≤ ⌊N/3⌋``, and keyword grids stop at ``N/3``
    (Stable32). The slope convention reproduces Stable32 at odd and even m.
    Cost O(N) per τ: the sum of squares is expanded into running sums of
    the data, formed block by block (see :mod:`sigmatau.stats.total`).

    Bias: ``bias_factor = B(alpha)``, corrected variance = raw/B, for
    {mtot_bias}

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.12; D. A. Howe & F. Vernotte,
    "Generalization of the total variance approach to the modified Allan
    variance", 31st PTTI (1999); numerics.md §1.9, §3.

    Examples
    --------
    >>> from sigmatau import mtotdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in mtotdev(y, m=[1, 2]).dev]
    [64.50896, 64.79436]
    >>> [round(float(d), 4) for d in mtotdev(y, m=[1, 2], bias="published", alpha=0).dev]
    [75.502, 75.8361]
    """
    return _run_total(MTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def ttotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Time total deviation (TTOT = τ²/3 · MTOT), in the unit of the phase data.

    {common}
    Notes
    -----
    .. math:: σ_{x,\\mathrm{tot}}^2(τ) = \\frac{τ^2}{3}\\,\\mathrm{Mod\\,Tot}\\,σ_y^2(τ)

    with MTOT as in :func:`mtotdev` (same ``n`` and range). SP1065 is reported
    to print τ³ in this equation; τ² reproduces its tables.

    Bias: the MTOT factors, for
    {mtot_bias}

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.13; numerics.md §1.10, §3.

    Examples
    --------
    >>> from sigmatau import ttotdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in ttotdev(y, m=[1, 2]).dev]
    [37.24427, 74.81809]
    """
    return _run_total(TTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def htotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Hadamard total deviation (HTOT).

    {common}
    Notes
    -----
    The MTOT construction applied to the M = N - 1 frequency samples: each
    3m-point subsequence of ``y`` loses its half-average slope (a linear
    frequency drift), is extended to 9m points by uninverted reflection, and
    the second differences ``z_j`` of its m-averages give

    .. math:: \\mathrm{Tot}\\,H σ_y^2(τ) = \\frac{1}{6(M-3m+1)}
              \\sum_{n=0}^{M-3m} \\frac{1}{6m} \\sum_{j=0}^{6m-1} z_j(n)^2 ,

    ``n = M - 3m + 1``, ``m ≤ ⌊M/3⌋``, keyword grids stop at ``N/3``; O(N)
    per τ, as for :func:`mtotdev`.

    **At m = 1 the overlapped Hadamard variance OHVAR(τ0) is reported**
    (``n = N - 3``), as Stable32 and the SP1065 tables do: the 3-point
    subsequence leaves the construction almost no freedom (for the NBS set
    it gives 0.208 against OHDEV 0.294).

    Bias: ``E[HTOT]/HVAR = 1 + a`` for alpha 0, −1, −2, −3, −4;
    ``"published"`` uses a = −0.005, −0.149, −0.229, −0.283, −0.321 (Howe
    et al. 2000; SP1065 tables are raw/0.995 for white FM), ``"estimator"``
    the Monte-Carlo factors 0.994, 0.850, 0.771, 0.717, 0.679. The OHVAR
    value at m = 1 gets factor 1.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.14; D. A. Howe, R. L. Beard,
    C. A. Greenhall, W. J. Riley, "A total estimator of the Hadamard function
    used for GPS operations", 32nd PTTI (2000); numerics.md §1.11, §3, §8.7.

    Examples
    --------
    >>> from sigmatau import htotdev
    >>> from sigmatau.datasets import nbs1000
    >>> r = htotdev(nbs1000(), m=[1, 10, 100], bias="published", alpha=0)
    >>> [f"{d:.5e}" for d in r.dev]
    ['2.94388e-01', '9.61479e-02', '3.05810e-02']
    """
    return _run_total(HTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)
