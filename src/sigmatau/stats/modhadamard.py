"""Modified Hadamard family: MHDEV, LDEV and MHTOTDEV.

The modified Hadamard variance averages m successive third differences of the
phase before squaring, as MVAR does with second differences: it separates white
from flicker phase noise (slopes −3/2 and −1 on MHDEV), ignores a linear
frequency drift, and converges for noise down to random-run FM (α > −5).

* MHVAR and LDEV cost O(N) per τ: the inner sums are window sums of the third
  differences (phase data) or double window sums of the frequency samples
  (:class:`~sigmatau.core.numeric.WindowSums`, frequency data).
* MHTOT detrends and reflects every 4m-point subsequence separately, as MTOT
  does with 3m points. The direct kernel :func:`mhtot_sums` (vectorised over
  blocks of subsequences, O(N·m) per τ) is the oracle and serves m below
  ``FAST_MIN_M``; from there on :func:`~sigmatau.stats.modhadamard_sums.mhtot_sums_fast`
  expands the sum of squares into running sums, O(N) per τ, as
  :func:`~sigmatau.stats.total_sums.tot_sums_fast` does for MTOT.

Records with missing samples are computed over their gap-free runs and pooled
(:func:`sigmatau.core.gaps.pooled_over_runs`): exactly the terms, or MHTOT
subsequences, that read no missing point. The plain loop definitions are in
``tests/test_modhadamard.py``, which holds these kernels to them.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..core.driver import Statistic
from ..core.kernels import window_sums_by_factor
from ..core.numeric import sumsq, sumsq_combination
from ..core.result import StabilityResult
from ..core.taus import STOP_RATIOS
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod
from ..uncertainty.confidence import ONE_SIGMA
from .allan import _doc
from .engine import run
from .modhadamard_sums import FAST_MIN_M, mhtot_sums_fast, remove_quadratic
from .total_sums import BLOCK_ELEMENTS

__all__ = ["mhdev", "ldev", "mhtotdev"]

#: LDEV² = τ²·MHVAR/(10/3): for white PM of variance σ_x², E[MHVAR] = 10σ_x²/(3mτ²)
#: (each inner sum is m independent third differences, 1 + 9 + 9 + 1 = 20), so
#: E[LDEV²] = σ_x²/m, the same as E[TDEV²].
_LDEV_SCALE = 10.0 / 3.0


# --- MHVAR kernels: (phase x or frequency y, factors, τ0) -> (variance, terms) --------


def _mhvar_sums(x: np.ndarray, m: int) -> np.ndarray:
    """Inner sums ``Σ_{i=j}^{j+m-1} Δ³_m x_i`` for j = 0 … N-4m, in O(N).

    The running sum is taken over the third differences themselves, not over
    x, so it stays of the size of the result (no cancellation for red noise).
    """
    d3 = x[3 * m :] - 3.0 * x[2 * m : -m] + 3.0 * x[m : -2 * m] - x[: -3 * m]
    c = np.empty(d3.size + 1)
    c[0] = 0.0
    np.cumsum(d3, out=c[1:])
    return c[m:] - c[:-m]


def _mhvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        s = _mhvar_sums(x, int(m))
        var[i] = sumsq(s) / (6.0 * float(m) ** 2 * (m * tau0) ** 2 * s.size)
        n[i] = s.size
    return var, n


def _mhvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # With A_m, B_m the single and double window sums of y, Δ³_m x_i = τ0·(A[i+2m] - 2A[i+m] + A[i])
    # and Σ_{i=j}^{j+m-1} of it = τ0·(B[j+2m] - 2B[j+m] + B[j]), j = 0 … M-4m+1.
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in window_sums_by_factor(y, ms, double=True, b_only=True):
        b = ws.b
        k = y.size - 4 * m + 2
        var[i] = sumsq_combination([(1.0, b[2 * m :]), (-2.0, b[m:-m]), (1.0, b[: -2 * m])], k) / (
            6.0 * float(m) ** 4 * k
        )
        n[i] = k
    return var, n


def _ldev_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mhvar_kernel(x, ms, tau0)
    return var * (ms * tau0) ** 2 / _LDEV_SCALE, n


def _ldev_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mhvar_freq(y, ms, tau0)
    return var * (ms * tau0) ** 2 / _LDEV_SCALE, n


# --- MHTOT kernel ----------------------------------------------------------------------


def mhtot_sums(x: np.ndarray, m: int, block: Optional[int] = None) -> tuple[float, int]:
    """``Σ_n Σ_j w_j(n)²`` over the ``N - 4m + 1`` subsequences of the MHTOT construction.

    For every start n the 4m points ``s_k = x_{n+k}`` lose their least-squares
    quadratic (a frequency offset and a linear frequency drift), are extended to
    ``e = [rev s', s', rev s']`` (12m points) and
    ``w_j = a_j - 3a_{j+m} + 3a_{j+2m} - a_{j+3m}``, j = 0 … 8m-1, where ``a_j``
    is the mean of ``e_j … e_{j+m-1}``. Returns the double sum and the number
    of subsequences. Subsequences go in blocks of about ``block`` values per
    temporary array, so memory is O(N) + O(block) whatever m. The quadratic is
    removed in extended precision (:func:`~sigmatau.stats.modhadamard_sums.remove_quadratic`).
    """
    m = int(m)
    length = 4 * m
    windows = x.size - length + 1
    rows = max(1, min(windows, (block or BLOCK_ELEMENTS) // (3 * length + 1)))
    view = sliding_window_view(x, length)
    ext = np.empty((rows, 3 * length + 1))
    total = 0.0
    for start in range(0, windows, rows):
        blk = view[start : start + rows]
        r = blk.shape[0]
        s = remove_quadratic(blk)
        e = ext[:r]
        e[:, 0] = 0.0
        e[:, 1 : length + 1] = s[:, ::-1]
        e[:, length + 1 : 2 * length + 1] = s
        e[:, 2 * length + 1 :] = s[:, ::-1]
        np.cumsum(e[:, 1:], axis=1, out=e[:, 1:])
        sums = e[:, m:] - e[:, :-m]  # m-sums of the extension, j = 0 … 11m
        w = sums[:, : 2 * length] - 3.0 * sums[:, m : 2 * length + m] + 3.0 * sums[:, 2 * m : 2 * length + 2 * m] \
            - sums[:, 3 * m : 2 * length + 3 * m]
        total += sumsq(w.reshape(-1))
    return total / float(m) ** 2, windows


def mhtot_total(x: np.ndarray, m: int) -> tuple[float, int]:
    """``Σ_n Σ_j w_j(n)²`` and the subsequence count, by the faster kernel for this m.

    The O(N) expansion (:func:`~sigmatau.stats.modhadamard_sums.mhtot_sums_fast`)
    from ``FAST_MIN_M`` on; below it the direct kernel :func:`mhtot_sums` is faster.
    """
    if m < FAST_MIN_M:
        return mhtot_sums(x, m)
    return mhtot_sums_fast(x, m)


def _mhtot_formula_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    """MHTOT by its defining construction at every factor, m = 1 included."""
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        total, windows = mhtot_total(x, int(m))
        var[i] = total / (8.0 * m * 6.0 * (m * tau0) ** 2 * windows)
        n[i] = windows
    return var, n


def _mhtot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    # At m = 1 a 4-point subsequence keeps one degree of freedom after the quadratic is
    # removed (its cubic part, Δ³x_n), so the construction is a fixed multiple (0.495)
    # of OHVAR(τ0): MHVAR(τ0) = OHVAR(τ0) is reported there, as HTOT reports OHVAR.
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    one = ms == 1
    var[one], n[one] = _mhvar_kernel(x, ms[one], tau0)
    var[~one], n[~one] = _mhtot_formula_kernel(x, ms[~one], tau0)
    return var, n


MHVAR = Statistic("mhdev", _mhvar_kernel, max_m=lambda n: n // 4, stop_ratio=STOP_RATIOS["mhdev"], min_points=4,
                  compute_freq=_mhvar_freq)
LVAR = Statistic("ldev", _ldev_kernel, max_m=lambda n: n // 4, stop_ratio=STOP_RATIOS["ldev"], min_points=4,
                 compute_freq=_ldev_freq)
MHTOT = Statistic("mhtotdev", _mhtot_kernel, max_m=lambda n: n // 4, stop_ratio=STOP_RATIOS["mhtotdev"],
                  min_points=4)


# --- public functions ------------------------------------------------------------------


@_doc
def mhdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Modified Hadamard deviation (MHVAR).

    {common}
    Notes
    -----
    .. math:: \\mathrm{Mod}\\,σ_H^2(τ) = \\frac{1}{6m^2τ^2(N-4m+1)} \\sum_{j=0}^{N-4m}
              \\Big[\\sum_{i=j}^{j+m-1} (x_{i+3m} - 3x_{i+2m} + 3x_{i+m} - x_i)\\Big]^2 ,

    ``n = N - 4m + 1`` terms, O(N) per τ; at m = 1 it is OHVAR. It ignores a
    linear frequency drift and converges for α > −5 (RRFM included). Log–log
    slopes of MHDEV: WPM −3/2, FPM −1, WFM −1/2, FFM 0, RWFM 1/2, FWFM 1,
    RRFM 3/2. EDF: Greenhall–Riley with d = 3, F = 1, S = m. Keyword grids stop
    at m ≤ N/5 (one term in five of the record at the last τ; sigmatau's choice,
    as MDEV's N/4 leaves N/4 terms).

    References
    ----------
    W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065
    (2008), §5.2.10 (modified Hadamard variance); C. A. Greenhall and W. J.
    Riley, "Uncertainty of stability variances based on finite differences",
    Proc. 35th PTTI (2003) (EDF).

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.ohdev(y, m=[1]).dev]
    [70.80607]
    >>> from sigmatau.stats.modhadamard import mhdev
    >>> [round(float(d), 5) for d in mhdev(y, m=[1]).dev]
    [70.80607]
    """
    return run(MHVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def ldev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Hadamard time deviation LDEV = τ·MHDEV/√(10/3), in the unit of the phase data.

    {common}
    Notes
    -----
    .. math:: σ_L^2(τ) = \\frac{3τ^2}{10}\\,\\mathrm{Mod}\\,σ_H^2(τ) .

    The Hadamard counterpart of TDEV (= τ·MDEV/√3): with 10/3, the
    expectation of LDEV² for white PM is σ_x²/m, as that of TDEV². Same terms
    and EDF as MHDEV (a deterministic rescaling). Log–log slopes: those of
    MHDEV plus one.

    References
    ----------
    The Stable32 manual (LDEV) and StabLab.jl (``ldev``) define it this way;
    NIST SP 1065 (2008) §5.2.10 for MHVAR itself.

    Examples
    --------
    >>> from sigmatau.stats.modhadamard import ldev, mhdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> bool(abs(ldev(y, m=[2]).dev[0] - 2 * mhdev(y, m=[2]).dev[0] / (10 / 3) ** 0.5) < 1e-12)
    True
    """
    return run(LVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def mhtotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Modified Hadamard total deviation (MHTOT), raw (no bias correction).

    {common}
    Notes
    -----
    For each of the ``N - 4m + 1`` subsequences ``s_k = x_{n+k}`` (k < 4m, the
    span of one MHVAR term) the least-squares quadratic is removed (frequency
    offset and linear frequency drift: the polynomials the third difference
    annihilates, so the reflection adds no kink from them); the 12m-point
    extension ``e = [rev s', s', rev s']`` (uninverted even reflection, as
    MTOT) gives m-averages ``a_j`` and
    ``w_j(n) = a_j - 3a_{j+m} + 3a_{j+2m} - a_{j+3m}``, j = 0 … 8m-1, and

    .. math:: \\mathrm{Mod\\,Htot}\\,σ^2(τ) = \\frac{1}{6τ^2(N-4m+1)}
              \\sum_{n=0}^{N-4m} \\frac{1}{8m} \\sum_{j=0}^{8m-1} w_j(n)^2 .

    This is MTOT's construction (SP1065 §5.2.12) with MHVAR's third
    difference; no published definition text or value table was available to
    check it against Stable32 or StabLab.jl (which detrends 3m + 1 points
    linearly), so values may differ from theirs. Removing only a line, as
    MTOT does, is not enough with third differences: on random-walk and
    random-run FM the reflection kinks then dominate (Monte Carlo ratio to
    MHVAR 2 for RWFM, 70 … 1000 for RRFM, against 0.8 with the quadratic).
    Cost O(N) per τ (:mod:`sigmatau.stats.modhadamard_sums`; an octave grid
    takes about 0.3 s at N = 16384, 1 s at N = 10⁵ and 10–15 s at N = 10⁶ on
    the 2-core reference machine, against 6 s, 4 min and about 7.5 h, by
    extrapolation, for the O(N·m) direct kernel). Keyword grids stop at m ≤ N/4 (one subsequence at the last τ, as
    MTOT's N/3). The EDF is a Monte-Carlo fit
    (:mod:`sigmatau.uncertainty.empirical_edf`): none is published.

    At m = 1 the 4-point subsequence keeps a single degree of freedom (its
    cubic part), the construction is exactly 0.495·OHVAR(τ0) whatever the noise, and
    MHVAR(τ0) (= OHVAR(τ0)) is reported instead, as for HTOT. For m ≥ 2 the
    raw estimator is about 0.80 of MHVAR for WFM, RWFM and RRFM and 0.90 for
    WPM (Monte Carlo, N = 1025); no bias correction is applied.

    References
    ----------
    W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065
    (2008), §5.2.10, §5.2.12, §5.2.14; D. A. Howe and F. Vernotte,
    "Generalization of the total variance approach to the modified Allan
    variance", Proc. 31st PTTI (1999).

    Examples
    --------
    >>> from sigmatau.stats.modhadamard import mhtotdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> r = mhtotdev(y, m=[1, 2], ci=None)
    >>> r.n.tolist()
    [7, 3]
    """
    return run(MHTOT, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
