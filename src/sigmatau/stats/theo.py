"""Theo1 family: Theo1, the bias-removed TheoBR and the hybrid TheoH.

Theo1 reaches averaging times up to 75 % of the record. Its defining double
sum costs O(N·m) per τ. Here it is evaluated from lag sums (FFT correlations
plus exact end corrections) in O(N log² m) per τ, or, when many factors are
wanted (TheoBR's κ, the "all" grid), in one incremental pass over m costing
O(N + m) per step. The plain sum stays beside them
(:func:`~sigmatau.stats.theo_sums.theo1_sum_direct`): it is used where it is
cheaper and wherever a rounding-error estimate says the fast forms could lose
digits. TheoBR's bias factor κ needs Theo1 at about N/30 factors (O(N²)); by
default it is computed on a block-averaged copy of long records (Fast TheoBR,
:func:`theobr_kappa`).

Size: about 620 lines, a little over the house limit, because the three public
statistics and the κ they share (its methods, checks and noise mapping) belong
together; the numerical sums are in :mod:`.theo_sums` and Theo1's AVAR bias in
:mod:`.theo_bias`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import Literal, Optional

import numpy as np

from ..core import driver as _driver
from ..core.driver import Statistic
from .engine import finish, run
from ..core.validate import unscale_variance
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod, check_options
from ..core.driver import GappedPhase, drop_empty_factors
from ..core.gaps import pooled_over_runs
from ..core.kernels import OAVAR, oavar_kernel
from .allan import _doc
from ..uncertainty.confidence import ONE_SIGMA
from ..uncertainty.noiseid import theo_noise_id
from ..errors import DataError, ParameterError, RangeWarning, caller_stacklevel
from ..core.result import StabilityResult
from .theo_sums import theo1_sums
from ..core.taus import TAU_GRIDS, is_numeric, m_grid, select_m
from .theo_bias import _apply_theo1_bias, _check_theo1_bias

__all__ = ["theo1", "theobr", "theoh", "theobr_kappa", "theoh_split", "TheoBRKappa", "KAPPA_FAST_POINTS",
           "THEOH_FAST_POINTS"]


def _theo1_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    N = x.size
    ms = np.asarray(ms, dtype=np.int64)
    var = theo1_sums(x, ms) / (0.75 * (N - ms) * (ms * tau0) ** 2)
    return var, (N - ms) * ms // 2


def _theo1_terms_per_point(ms: np.ndarray) -> np.ndarray:
    return np.asarray(ms, dtype=float) / 2.0  # n = (N - m)·m/2


THEO1 = Statistic(
    "theo1", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=2, even=True, tau_factor=0.75, terms_per_point=_theo1_terms_per_point,
)
THEOBR = Statistic(
    "theobr", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=2, even=True, tau_factor=0.75,
)


# --- TheoBR bias factor -----------------------------------------------------------

#: Fewest phase points for which TheoBR's κ is defined (n = ⌊N/30⌋ − 3 ≥ 0).
THEOBR_MIN_POINTS = 90


@dataclass(frozen=True)
class TheoBRKappa:
    """TheoBR's empirical bias factor.

    Attributes
    ----------
    kappa : float
        ``κ = 1/(n+1) Σ_{i=0}^{n} OAVAR(m=9+3i) / Theo1(m=12+4i)``; TheoBR = κ·Theo1.
    n : int
        Upper index of the average, ``⌊N'/30⌋ − 3`` for the N' phase points κ
        was computed on (N' = N unless ``block > 1``).
    n_points : int
        Number of phase points N of the record.
    block : int
        1 when κ follows the published definition on the whole record
        (``method="exact"``, or ``"fast"`` on at most 16384 phase points);
        otherwise the number of phase points averaged into each point of the
        shorter record the fast estimate used.
    """

    kappa: float
    n: int
    n_points: int
    block: int = 1


#: κ methods: the published definition on the whole record, or on a block-averaged copy,
#: or over Stable32's wider "Run" span of ratios.
KappaMethod = Literal["fast", "exact", "run"]
_KAPPA_METHODS = ("fast", "exact", "run")
#: Largest record (phase points) on which the fast κ still uses the published definition.
KAPPA_FAST_POINTS = 16384


def _check_kappa_points(N: int, data_type: str = "phase") -> None:
    if N < THEOBR_MIN_POINTS:
        given = f"{N} phase points" if data_type == "phase" else f"{N - 1} frequency samples"
        raise DataError(
            f"TheoBR needs at least {THEOBR_MIN_POINTS} phase points ({THEOBR_MIN_POINTS - 1}"
            f" frequency samples) to estimate its bias factor κ, got {given}"
            " (κ averages n + 1 ratios with n = ⌊N/30⌋ − 3 ≥ 0)"
        )


def _check_kappa_method(method: object, name: str = "kappa") -> str:
    if not isinstance(method, str) or method not in _KAPPA_METHODS:
        raise ParameterError(f"{name}={method!r} must be one of {_KAPPA_METHODS} (how TheoBR's κ is computed)")
    return method


def _kappa(x: np.ndarray, method: str = "fast") -> TheoBRKappa:
    """κ of the phase record ``x`` (linear trend removed) by ``method``."""
    N = x.size
    _check_kappa_points(N)
    if method == "run":
        return _kappa_exact(x, n=_run_span(N))
    block = 1 if method == "exact" else -(-N // KAPPA_FAST_POINTS)
    if block == 1:
        return _kappa_exact(x)
    # Fast TheoBR (Taylor & Howe 2010): κ of the record averaged in blocks of
    # `block` phase points, at most KAPPA_FAST_POINTS of them. Averaging keeps the
    # long-τ behaviour both variances share and makes κ O(N) + O(1).
    k = N // block
    averaged = x[: k * block].reshape(k, block).mean(axis=1)
    kap = _kappa_exact(averaged)
    if kap.kappa > 0 and theo_noise_id(kap.kappa) >= 1:
        # Block averaging biases κ upwards for phase noise (≈ +25 % at b = 5, +50 % at
        # N = 10^6, Howe–Tasset model); FM noise is within 1 %. Say so rather than hide it.
        warnings.warn(
            f"TheoBR κ = {kap.kappa:.4g} from blocks of {block} points indicates phase noise (WPM/FPM), for"
            f" which Fast TheoBR overestimates κ (by tens of percent at this length); kappa='exact' gives the"
            f" published κ at O(N²) cost", RangeWarning, stacklevel=caller_stacklevel())
    return TheoBRKappa(kappa=kap.kappa, n=kap.n, n_points=int(N), block=int(block))


def _run_span(N: int) -> int:
    """Upper index n of κ's average in Stable32's Run/Plot functions: ⌊N/6⌋ − 3, capped so
    that OAVAR at m = 9+3n keeps at least one term (N − 2m ≥ 1)."""
    return min(N // 6 - 3, ((N - 1) // 2 - 9) // 3)


def _kappa_exact(x: np.ndarray, n: Optional[int] = None) -> TheoBRKappa:
    """κ by its published definition (numerics.md §1.13) on the phase record ``x``;
    ``n`` (default ⌊N/30⌋ − 3) is the upper index of the average."""
    N = x.size
    _check_kappa_points(N)
    n = N // 30 - 3 if n is None else n
    i = np.arange(n + 1)
    oavar, _ = oavar_kernel(x, 9 + 3 * i, 1.0)
    theo, _ = _theo1_kernel(x, 12 + 4 * i, 1.0)
    if np.all(theo <= 0.0) and np.all(oavar <= 0.0):
        # A straight phase line (constant frequency): every variance is zero and so is
        # TheoBR whatever κ; κ = 1 keeps the result finite.
        return TheoBRKappa(kappa=1.0, n=int(n), n_points=int(N))
    if np.any(theo <= 0.0):
        raise DataError(
            "TheoBR's bias factor κ is undefined: Theo1 is zero at some m = 12+4i"
            " while the Allan variance is not"
        )
    return TheoBRKappa(kappa=float(np.mean(oavar / theo)), n=int(n), n_points=int(N))


def _kappa_text(k: TheoBRKappa) -> str:
    if k.block == 1 and k.n > k.n_points // 30 - 3:
        return f"theobr kappa={k.kappa:.6f} (n={k.n}, run span N/6)"
    if k.block == 1:
        return f"theobr kappa={k.kappa:.6f} (n={k.n})"
    return f"theobr kappa={k.kappa:.6f} (n={k.n}, fast: blocks of {k.block} points)"


def _record(stat: Statistic, data: object, rate: object, data_type: object
            ) -> tuple[Optional[GappedPhase], Optional[np.ndarray], float, str, int, int]:
    """``(gapped, phase, rate, data_type, N, exponent)`` of TheoBR's or TheoH's input.

    Without gaps the phase scaled by 2**-k (var(c·x) = c²·var(x) and κ is scale free, so
    unscaling the variance is exact) and ``gapped`` None; with gaps the gap-free runs
    (:func:`sigmatau.core.driver.gapped_phase`) and ``phase`` None.
    """
    gapped = _driver.gapped_phase(stat, data, rate, data_type)
    if gapped is not None:
        return gapped, None, gapped.rate, gapped.data_type, gapped.n_points, gapped.exponent
    p = _driver.prepare_scaled(stat, data, rate, data_type)
    return None, p.phase, p.rate, p.data_type, p.phase.size, p.exponent


# --- records with gaps: the kernels pooled over the gap-free runs --------------------


def _theo1_runs(runs: list, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return pooled_over_runs(_theo1_kernel, runs, _points_of_run, THEO1.max_m, THEO1.min_points, ms, tau0,
                            terms_per_point=_theo1_terms_per_point)


def _oavar_runs(runs: list, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return pooled_over_runs(oavar_kernel, runs, _points_of_run, OAVAR.max_m, OAVAR.min_points, ms, tau0)


def _points_of_run(size: int) -> int:
    return size


def _block_runs(runs: list, block: int) -> list:
    """Each run averaged in blocks of ``block`` phase points on its own grid (Fast TheoBR)."""
    return [r[: (r.size // block) * block].reshape(-1, block).mean(axis=1) for r in runs if r.size >= block]


def _kappa_gaps(g: GappedPhase, method: str) -> TheoBRKappa:
    """κ of a record with gaps: the ratios of OAVAR to Theo1 each pooled over the gap-free
    runs (terms reading a gap are left out of both), averaged over the factors where both
    have terms; Fast TheoBR averages each run in blocks first."""
    N = g.n_points
    _check_kappa_points(N)
    block = 1 if method in ("exact", "run") else -(-N // KAPPA_FAST_POINTS)
    runs = g.runs if block == 1 else _block_runs(g.runs, block)
    n = _run_span(N) if method == "run" else (N // block) // 30 - 3
    i = np.arange(max(n, 0) + 1)
    oavar, n_a, _ = _oavar_runs(runs, 9 + 3 * i, 1.0)
    theo, n_t, _ = _theo1_runs(runs, 12 + 4 * i, 1.0)
    ok = (n_a > 0) & (n_t > 0)
    if not ok.any():
        raise DataError(
            "TheoBR's bias factor κ needs a gap-free stretch of at least"
            f" {13 * block} phase points; the gaps leave none"
        )
    oavar, theo = oavar[ok], theo[ok]
    if np.all(theo <= 0.0) and np.all(oavar <= 0.0):
        return TheoBRKappa(kappa=1.0, n=int(n), n_points=int(N), block=int(block))
    if np.any(theo <= 0.0):
        raise DataError("TheoBR's bias factor κ is undefined: Theo1 is zero at some m = 12+4i"
                        " while the Allan variance is not")
    return TheoBRKappa(kappa=float(np.mean(oavar / theo)), n=int(n), n_points=int(N), block=int(block))


# --- Theo1 bias by noise type --------------------------------------------------------


TheoBias = Literal["none", "published", "auto"]


# --- public functions ---------------------------------------------------------------


@_doc
def theo1(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", bias: TheoBias = "none",
) -> StabilityResult:
    """Theo1 deviation, raw (default) or corrected for the bias of a noise type.

    {common}
    Notes
    -----
    For even ``m`` and N phase points,

    .. math:: \\mathrm{Theo1}(m) = \\frac{1}{0.75\\,(N-m)(mτ_0)^2}
              \\sum_{i=0}^{N-m-1} \\sum_{δ=0}^{m/2-1} \\frac{1}{m/2-δ}
              \\big[(x_i - x_{i-δ+m/2}) + (x_{i+m} - x_{i+δ+m/2})\\big]^2 ,

    reported at **τ = 0.75·m·τ0** (``result.taus``; ``result.m`` holds m). The
    0.75 makes Theo1 equal AVAR at the same τ for white FM; for other noise
    types it is biased (:func:`theobr` removes the bias). ``n = (N-m)·m/2``
    terms, as Stable32's "Thêo1 #" column. The estimator ignores a linear phase
    trend (a frequency offset).

    Only even factors are valid, ``2 ≤ m ≤ N-1``; ``taus`` in seconds are
    rounded to the nearest multiple of 1.5·τ0. Keyword grids run over even m
    from 2 to N-1 (τ up to 0.75 of the record): SP1065 quotes ``m ≥ 10`` and
    Stable32 starts there, but the estimator is defined from m = 2; drop the
    first rows if you need the Stable32 range.

    **Bias** (``bias``, default ``"none"``: the raw estimator). Theo1 equals
    AVAR at the same τ only for white FM; Howe & Tasset (2004, Table 1, as in
    SP1065) give

    .. math:: \\frac{\\mathrm{AVAR}(τ)}{\\mathrm{Theo1}(τ)} = a + \\frac{b}{t^c},
              \\qquad t = 0.75\\,m ,

    with (a, b, c) = WPM (0.09, 0.74, 0.40), FPM (0.14, 0.82, 0.30),
    WFM (1, 0, 0), FFM (1.87, −1.05, 0.79), RWFM (2.70, −1.53, 0.85).
    ``bias="published"`` multiplies the variance (and the interval) by this
    ratio for ``alpha`` when given, else for the noise type identified at
    each τ; ``"auto"`` is the same at the identified type (``alpha`` still
    forces one). Rows whose α has no entry (−3, −4) stay raw and
    ``result.bias`` counts them; ``result.bias_factor`` is the divisor applied
    to raw Theo1, ``1/(a + b/t^c)``, as ``1/κ`` for :func:`theobr`.
    Stable32's Theo1 output with Alpha forced to 0 is the raw value (the
    WFM factor is 1); its "Auto/BR" output is not this table but TheoBR with
    κ over a wider range (:func:`theobr` with ``kappa="run"``).

    Cost: O(N log² m) per τ by lag sums (FFT correlations over overlapping
    segments plus exact end corrections; about 0.5 s for the octave grid at
    N = 10^5), with the plain O(N·m) double sum used when it is cheaper or
    when the fast form could lose more than 1e-10 relative to rounding. Many
    factors at once (``taus="all"``) go through one incremental pass, O(N·m_max).

    References
    ----------
    D. A. Howe & T. N. Tasset, "Theo1: characterization of very long-term
    frequency stability", EFTF 2004; W. J. Riley, NIST SP 1065 (2008);
    numerics.md §1.12, §4.

    Examples
    --------
    >>> import sigmatau
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theo1(nbs1000(), m=[10, 100])
    >>> r.taus.tolist(), [round(float(d), 7) for d in r.dev]
    ([7.5, 75.0], [0.107574, 0.0317893])
    """
    alpha_i, _, _ = check_options(alpha, confidence, ci)
    bias = _check_theo1_bias(bias, alpha_i)
    if bias == "none":
        return run(THEO1, data, rate=rate, data_type=data_type, taus=taus, m=m,
                   points_per_decade=points_per_decade, alpha=alpha, confidence=confidence, ci=ci)
    # The correction needs each row's noise type even when no interval is wanted.
    res = run(THEO1, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
              alpha=alpha, confidence=confidence, ci="chi2" if ci is None else ci)
    res = _apply_theo1_bias(res, bias, alpha_i)
    if ci is None:
        res = replace(res, edf=None, ci_low=None, ci_high=None, confidence=None, ci_reason=None)
    return res


def theobr_kappa(
    data, *, rate: float = 1.0, data_type: DataType = "freq", method: KappaMethod = "fast",
) -> TheoBRKappa:
    """TheoBR's bias factor κ = mean of OAVAR/Theo1 ratios over the record.

    Parameters
    ----------
    data : array_like
        Frequency (default) or phase samples, as for :func:`theobr`.
    rate : float
        Sample rate in Hz.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    method : {"fast", "exact", "run"}
        ``"exact"``: the published definition below on the whole record,
        O(N²) (minutes at N = 10^6). ``"fast"`` (default): the same definition
        on the record averaged in blocks (Fast TheoBR, see Notes); identical to
        ``"exact"`` up to 16384 phase points (``KAPPA_FAST_POINTS``).
        ``"run"``: the same ratios averaged over Stable32's "Run"/"Plot" span,
        ``n = ⌊N/6⌋ − 3`` (capped so that OAVAR at m = 9+3n has a term), on
        the whole record — five times as many ratios, reaching τ ≈ T/2, and
        O(N²). Stable32's Theo1 "Auto/BR" tables are Theo1 times this κ: the
        PHASE.DAT table headed "Alpha = 1" is raw Theo1 × 0.602787 at every
        τ, which is this κ (0.6027870, n = 163) to 1e-6, and its Alpha column
        is the noise type of that κ (nominal ratio 0.6: FPM).

    Returns
    -------
    TheoBRKappa
        ``kappa``, the averaging range ``n``, the number of phase points and
        the averaging ``block`` (1 for the published definition).

    Notes
    -----
    With N phase points and ``n = ⌊0.1·N/3 − 3⌋`` (needs N ≥ 90),

    .. math:: κ = \\frac{1}{n+1} \\sum_{i=0}^{n}
              \\frac{\\mathrm{OAVAR}(m = 9+3i)}{\\mathrm{Theo1}(m = 12+4i)} ,

    both at τ = (9+3i)·τ0; AVAR is the overlapped estimator. κ does not depend
    on the rate. It needs Theo1 and OAVAR at about N/30 factors each: Theo1
    comes from one incremental pass, O(N²/15) in all (about 2 s at N = 10^5
    with OAVAR); factors at which that pass could lose digits (smooth,
    random-walk-FM phase at small m) are recomputed one by one, which is slower.

    **Fast TheoBR** (``method="fast"``, after Taylor & Howe 2010): for
    N > 16384 the phase record is averaged in blocks of ``b = ⌈N/16384⌉``
    points and κ is the published definition applied to the ⌊N/b⌋ averages
    (τ0' = b·τ0; ``n`` then counts ratios of that record). The cost is O(N)
    plus a bounded κ computation (well under 2 s for any N and noise type).
    This **changes the value** of κ where the ratio AVAR/Theo1 depends on m
    itself: the fast κ is that of a record of ⌊N/b⌋ points, so it averages
    the ratios over factors 9 … 0.1·N/b of the shorter record instead of
    9 … 0.1·N. Measured on seeded records (two per type) of N = 65537 and
    131073 phase points (b = 5 and 9): white, flicker and random-walk FM,
    flicker-walk and random-run FM within 0.8 % of the exact κ (+0.6…+0.8 %
    WFM, −0.2…−0.3 % for the others); white PM +25 % and +35 %, flicker PM
    +16 % and +23 %, whose Theo1 bias keeps falling with m (Howe & Tasset's
    bias model a + b/(0.75m)^c reproduces these and predicts about +50 % at
    N = 10^6, b = 62, and +60…67 % at N = 10^7). Use ``method="exact"`` when
    PM noise dominates and the record is long. No correction term is added
    (one implementation adds ``0.00055·(b−1)``, numerics.md §8 item 14,
    unverified).

    References
    ----------
    D. A. Howe, "ThêoH: a hybrid, high-confidence statistic that improves on the
    Allan deviation", Metrologia 43 (2006) S322; W. J. Riley, NIST SP 1065 (2008);
    J. A. Taylor & D. A. Howe, "Fast TheoBR: a method for long data set
    stability analysis", IEEE TUFFC 57(9), 2010, 2091–2094; numerics.md §1.13, §4.

    Examples
    --------
    >>> from sigmatau.datasets import nbs1000
    >>> k = theobr_kappa(nbs1000())
    >>> round(k.kappa, 6), k.n
    (1.085666, 30)
    """
    _check_kappa_method(method, "method")
    gapped = _driver.gapped_phase(THEOBR, data, rate, data_type)
    if gapped is not None:
        return _kappa_gaps(gapped, method)
    # κ is a ratio of variances, so it is computed on the power-of-two-scaled phase.
    p = _driver.prepare_scaled(THEOBR, data, rate, data_type)
    return _kappa(p.phase, method)


@_doc
def theobr(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", kappa: KappaMethod = "fast",
) -> StabilityResult:
    """Bias-removed Theo1 deviation (TheoBR).

    {common}
    Notes
    -----
    .. math:: \\mathrm{TheoBR}(m) = κ·\\mathrm{Theo1}(m),\\qquad
              κ = \\frac{1}{n+1} \\sum_{i=0}^{n}
              \\frac{\\mathrm{OAVAR}(m = 9+3i)}{\\mathrm{Theo1}(m = 12+4i)} ,

    ``n = ⌊0.1·N/3 − 3⌋`` for N phase points, so at least 90 phase points are
    needed (:class:`~sigmatau.errors.DataError` otherwise). κ is the measured
    ratio of AVAR (overlapped) to Theo1 over the τ range where both are
    available; it replaces the noise-type-dependent Theo1 bias table. κ is
    written in ``result.bias`` (``"theobr kappa=1.085666 (n=30)"``),
    ``result.bias_factor`` holds 1/κ (the divisor applied to Theo1) and
    :func:`theobr_kappa` returns it directly. τ, m, n and the grids are those of
    :func:`theo1`.

    ``kappa`` (``"fast"``, ``"exact"`` or ``"run"``) chooses how κ is computed: above
    16384 phase points ``"fast"`` (the default) applies the definition to the
    block-averaged record (Fast TheoBR) and ``result.bias`` says so
    (``"… (n=…, fast: blocks of b points)"``); ``"exact"`` applies it to the
    whole record at O(N²) cost; ``"run"`` averages the ratios over Stable32's
    wider "Run" span n = ⌊N/6⌋ − 3 (reproduces its Theo1 "Auto/BR" tables).
    See :func:`theobr_kappa` for the differences.

    References
    ----------
    D. A. Howe, Metrologia 43 (2006) S322; W. J. Riley, NIST SP 1065 (2008);
    J. A. Taylor & D. A. Howe, IEEE TUFFC 57(9), 2010, 2091–2094; numerics.md §1.13.

    Examples
    --------
    >>> import sigmatau
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theobr(nbs1000(), m=[10, 100])
    >>> r.bias, [round(float(d), 7) for d in r.dev]
    ('theobr kappa=1.085666 (n=30)', [0.1120871, 0.033123])
    """
    check_options(alpha, confidence, ci)
    method = _check_kappa_method(kappa)
    gapped, x, rate_f, dtype, N, exponent = _record(THEOBR, data, rate, data_type)
    _check_kappa_points(N, dtype)
    ms = select_m(
        "theobr", n_points=N, rate=rate_f, taus=taus, m=m, points_per_decade=points_per_decade,
        m_min=THEOBR.min_m, m_max=THEOBR.max_m(N), stop_ratio=THEOBR.stop_ratio, even=True,
        tau_factor=0.75,
    )
    tau0 = 1.0 / rate_f
    n_eff = None
    if gapped is not None:
        kap = _kappa_gaps(gapped, method)
        raw, n, n_eff = _theo1_runs(gapped.runs, ms, tau0)
        ms, raw, n, n_eff = drop_empty_factors("theobr", ms, raw, n, n_eff,
                                               explicit=m is not None or not isinstance(taus, str))
    else:
        kap = _kappa(x, method)
        raw, n = _theo1_kernel(x, ms, tau0) if ms.size else (np.empty(0), np.empty(0, dtype=np.int64))
    var = unscale_variance(np.maximum(kap.kappa * raw, 0.0), exponent, "theobr")
    result = StabilityResult(
        statistic="theobr", taus=0.75 * ms * tau0, m=ms, var=var, dev=np.sqrt(var), n=n,
        rate=rate_f, data_type=dtype, n_points=int(N), bias=_kappa_text(kap),
        bias_factor=np.full(ms.size, 1.0 / kap.kappa),
        n_missing=0 if gapped is None else gapped.n_missing, n_effective=n_eff,
    )
    return finish(result, data, dtype, alpha=alpha, confidence=confidence, ci=ci,
                  identified=_kappa_noise(kap, ms))


def _kappa_noise(kap: TheoBRKappa, ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Noise type of the TheoBR rows from κ (numerics.md §5.5): κ is compared with the fixed
    nominal AVAR/Theo1 ratios 0.4/0.6/1/1.71/2.24, as Stable32 does.

    κ is one average over a span of factors, not a property of each row, so every TheoBR row
    gets the same type; comparing it with the m-dependent ratio at each row's m gave a different
    type per row from the same number (46 of 181 rows of Stable32's PHASE.DAT TheoBR table
    agreed; the fixed ratios give 181 of 181)."""
    if ms.size == 0:
        return np.empty(0), np.empty(0)
    a = np.asarray(theo_noise_id(np.full(ms.size, kap.kappa)), dtype=float)
    return a, np.full(ms.size, np.nan)


# --- TheoH -------------------------------------------------------------------------

# Input validation only (TheoH mixes two estimators; see theoh()).
THEOH = Statistic(
    "theoh", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=1, even=False, tau_factor=1.0,
)


def theoh_split(n_points: int) -> tuple[int, int]:
    """Factors at which TheoH switches from AVAR to TheoBR for N phase points.

    Returns ``(k, m_lo)``: rows with ``m < k`` are OAVAR at τ = m·τ0, rows with
    ``m ≥ m_lo`` (even) are TheoBR at τ = 0.75·m·τ0. ``k = ⌊(N−1)/10⌋`` is the
    largest τ/τ0 not exceeding 10 % of the record ``T = (N−1)·τ0`` and
    ``m_lo`` is the smallest even factor with ``0.75·m_lo ≥ k``.

    Examples
    --------
    >>> theoh_split(1001)
    (100, 134)
    """
    k = (int(n_points) - 1) // 10
    m_lo = 2 * math.ceil(2 * k / 3)
    return k, m_lo


def _theoh_factors(
    n_points: int, rate: float, taus, m, points_per_decade: int,
) -> tuple[np.ndarray, np.ndarray]:
    """AVAR and TheoBR factors of a TheoH request (see :func:`theoh`)."""
    k, m_lo = theoh_split(n_points)
    m_max = n_points - 1
    common = dict(n_points=n_points, rate=rate, points_per_decade=points_per_decade)
    if m is not None or not isinstance(taus, str):
        if m is not None:
            if not (isinstance(taus, str) and taus == "octave"):
                raise ParameterError(f"give either taus={taus!r} or m, not both")
            req = select_m("theoh", taus="octave", m=m, m_min=1, m_max=m_max, stop_ratio=1, **common)
            gap = req[(req >= k) & (req < m_lo)]
            if gap.size:
                raise ParameterError(
                    f"theoh: m={gap.tolist()} falls between the AVAR part (m < {k}) and the"
                    f" TheoBR part (even m ≥ {m_lo}) for {n_points} phase points"
                )
            odd = req[(req >= m_lo) & (req % 2 == 1)]
            if odd.size:
                raise ParameterError(
                    f"theoh: TheoBR part (m ≥ {m_lo}) needs even averaging factors, got m={odd.tolist()}"
                )
            return req[req < k], req[req >= m_lo]
        t = np.atleast_1d(np.asarray(taus, dtype=float)) if is_numeric(taus) else None
        if t is None or t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise ParameterError(
                f"taus={taus!r} must be one of {TAU_GRIDS} or a 1-D array of positive τ in seconds"
            )
        steps = t * rate
        is_a = np.round(steps) < k
        sa, sb = steps[is_a], steps[~is_a]
        ma = np.round(sa).astype(np.int64)
        mb = np.maximum(2 * np.round(sb / 1.5), m_lo).astype(np.int64)
        off = np.concatenate((np.abs(ma - sa) > 1e-6 * np.maximum(sa, 1.0),
                              np.abs(0.75 * mb - sb) > 1e-6 * np.maximum(sb, 1.0)))
        if np.any(off):
            warnings.warn(
                f"theoh: {int(off.sum())} requested τ are not multiples of τ0 (AVAR part) or"
                " 1.5·τ0 (TheoBR part); they were rounded to the nearest usable averaging factor",
                RangeWarning,
                stacklevel=caller_stacklevel(),
            )
        ma = select_m("theoh", taus="octave", m=ma, m_min=1, m_max=k - 1, stop_ratio=1, **common) if ma.size else ma
        mb = (select_m("theoh", taus="octave", m=mb, m_min=m_lo, m_max=m_max, stop_ratio=1, even=True,
                       tau_factor=0.75, **common) if mb.size else mb)
        return ma, mb
    # Keyword grid in units of τ0, split at k; the TheoBR part keeps the grid's τ spacing.
    steps = m_grid(taus, max(1, int(0.75 * m_max)), points_per_decade=points_per_decade)
    ma = steps[steps < k]
    high = steps[steps >= k]
    mb = np.unique(np.maximum(2 * np.round(high / 1.5).astype(np.int64), m_lo))
    mb = mb[mb <= m_max]
    return ma, mb


#: TheoH methods for the TheoBR rows: the definition on the whole record, or Fast TheoBR.
TheoHMethod = Literal["exact", "fast"]
_THEOH_METHODS = ("exact", "fast")
#: Phase points up to which ``theoh(method="fast")`` still computes the TheoBR rows exactly;
#: longer records are averaged in blocks down to at most this many points.
THEOH_FAST_POINTS = 1 << 16


def _check_theoh_method(method: object) -> str:
    if not isinstance(method, str) or method not in _THEOH_METHODS:
        raise ParameterError(f"method={method!r} must be one of {_THEOH_METHODS} (how TheoH's TheoBR rows are computed)")
    return method


def _theoh_block(N: int) -> int:
    """Block of Fast TheoBR for N phase points: 1 (exact) up to THEOH_FAST_POINTS."""
    return max(1, -(-N // THEOH_FAST_POINTS))


def _theobr_rows(x: np.ndarray, mb: np.ndarray, tau0: float, block: int,
                 m_lo: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Factors, Theo1 variances and term counts of TheoH's TheoBR rows (κ not applied).

    ``block`` 1 is the definition on ``x``. A larger block is Fast TheoBR (Taylor &
    Howe 2010): Theo1 of the record averaged in blocks of ``block`` points, at the
    even factors m' nearest to m/block (at least m_lo/block), reported at m = block·m'.
    """
    empty = (np.empty(0, dtype=np.int64), np.empty(0), np.empty(0, dtype=np.int64))
    if mb.size == 0:
        return empty
    if block == 1:
        vb, nb = _theo1_kernel(x, mb, tau0)
        return mb, vb, nb
    k = x.size // block
    averaged = x[: k * block].reshape(k, block).mean(axis=1)
    lowest = 2 * (-(-m_lo // (2 * block)))
    mp = np.unique(np.maximum(2 * np.round(mb / (2.0 * block)).astype(np.int64), lowest))
    mp = mp[mp <= k - 1]
    if mp.size == 0:
        return empty
    vb, nb = _theo1_kernel(averaged, mp, block * tau0)
    return block * mp, vb, nb


def _theobr_rows_gaps(g: GappedPhase, mb: np.ndarray, tau0: float, block: int, m_lo: int,
                      explicit: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_theobr_rows` for a record with gaps: Theo1 pooled over the gap-free runs (each
    averaged in blocks on its own grid for Fast TheoBR); also returns the equivalent
    contiguous record length of each row, in phase points of the original record."""
    if mb.size == 0:
        empty = np.empty(0, dtype=np.int64)
        return empty, np.empty(0), empty, empty
    if block == 1:
        return drop_empty_factors("theoh", mb, *_theo1_runs(g.runs, mb, tau0), explicit=explicit, allow_empty=True)
    averaged = _block_runs(g.runs, block)
    lowest = 2 * (-(-m_lo // (2 * block)))
    mp = np.unique(np.maximum(2 * np.round(mb / (2.0 * block)).astype(np.int64), lowest))
    mp = mp[mp <= g.n_points // block - 1]
    if mp.size == 0:
        empty = np.empty(0, dtype=np.int64)
        return empty, np.empty(0), empty, empty
    mp, vb, nb, neb = drop_empty_factors("theoh", mp, *_theo1_runs(averaged, mp, block * tau0), explicit=explicit,
                                         allow_empty=True)
    return block * mp, vb, nb, neb * block


@_doc
def theoh(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", kappa: KappaMethod = "fast", method: TheoHMethod = "exact",
) -> StabilityResult:
    """Hybrid TheoH deviation: AVAR at short τ, TheoBR at long τ.

    {common}
    Notes
    -----
    With ``k`` the largest τ not exceeding 10 % of the record
    ``T = (N−1)·τ0`` (``k = ⌊(N−1)/10⌋·τ0``),

    .. math:: \\mathrm{TheoH}(τ) =
              \\begin{cases} \\mathrm{AVAR}(τ = mτ_0), & 1 ≤ m < k/τ_0 \\\\
              \\mathrm{TheoBR}(m),\\ τ = 0.75\\,mτ_0, & k/(0.75τ_0) ≤ m ≤ N-1,\\ m \\text{ even} \\end{cases}

    AVAR here is the overlapped estimator (OAVAR, :func:`~sigmatau.stats.allan.oadev`),
    as in TheoBR's κ; κ is computed once for the whole record, by the
    ``kappa`` method of :func:`theobr` (Fast TheoBR above 16384 phase points
    unless ``kappa="exact"``).

    ``method="fast"`` computes the TheoBR rows of records longer than
    :data:`THEOH_FAST_POINTS` phase points on the record averaged in blocks of
    ``b = ⌈N/THEOH_FAST_POINTS⌉`` points (Fast TheoBR, Taylor & Howe 2010),
    at factors ``m = b·m'`` (``m'`` even; τ = 0.75·m·τ0, so each τ moves by
    less than ``b·τ0`` from the exact grid's) and ``n`` counts the averaged
    record's terms. It costs O(N) instead of O(N log² m) per τ; its difference
    from the exact TheoBR is measured in ``docs/theoh-fast.md``. ``result.bias``
    names the block. The AVAR rows are the same. Block averages remove white
    and flicker PM, so when κ indicates phase noise (:func:`sigmatau.noiseid.theo_noise_id`
    of κ at least 1) the exact rows are computed instead, and ``result.bias`` says so.

    Rows are sorted by τ; ``result.m`` is each row's own factor and
    ``result.taus`` its τ. Rows with ``taus < k`` are OAVAR (``taus == m·τ0``,
    ``n = N − 2m``, ``bias_factor == 1``); the others are TheoBR
    (``taus == 0.75·m·τ0``, ``n = (N−m)·m/2``, ``bias_factor == 1/κ``).
    ``result.bias`` states the split and κ, and :func:`theoh_split` returns it.

    Keyword grids are built in τ: grid points below k use AVAR at that m; the
    others use the even TheoBR factor nearest to τ/(0.75·τ0) (at least the first
    TheoBR factor), up to τ = 0.75·(N−1)·τ0. Explicit ``m`` are read per part:
    ``m < k`` is AVAR, even ``m ≥ k/0.75`` is TheoBR; factors in between are
    rejected. Explicit ``taus`` below k go to AVAR, the others to TheoBR.

    References
    ----------
    D. A. Howe, "ThêoH: a hybrid, high-confidence statistic that improves on the
    Allan deviation", Metrologia 43 (2006) S322–S331; W. J. Riley, NIST SP 1065
    (2008) §5.2.16; numerics.md §1.14.

    Examples
    --------
    >>> import sigmatau
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theoh(nbs1000())
    >>> r.m.tolist()
    [1, 2, 4, 8, 16, 32, 64, 170, 342, 682]
    >>> r.bias
    'theoh: oavar for tau < 100 s (m < 100); theobr kappa=1.085666 (n=30) for tau >= 100 s (even m >= 134, tau = 0.75 m tau0)'
    """
    check_options(alpha, confidence, ci)
    kappa_method = _check_kappa_method(kappa)
    theoh_method = _check_theoh_method(method)
    gapped, x, rate_f, dtype, N, exponent = _record(THEOH, data, rate, data_type)
    _check_kappa_points(N, dtype)
    tau0 = 1.0 / rate_f
    ma, mb = _theoh_factors(N, rate_f, taus, m, points_per_decade)
    kap = _kappa(x, kappa_method) if gapped is None else _kappa_gaps(gapped, kappa_method)
    block = _theoh_block(N) if theoh_method == "fast" else 1
    declined = block > 1 and bool(theo_noise_id(kap.kappa) >= 1)
    if declined:
        # Block averages remove white and flicker PM: Fast TheoBR reads it 24-79 % low
        # (docs/theoh-fast.md). κ says the record is PM-dominated: the exact rows instead.
        block = 1
    k, m_lo = theoh_split(N)
    nea = neb = None
    if gapped is None:
        va, na = oavar_kernel(x, ma, tau0) if ma.size else (np.empty(0), np.empty(0, dtype=np.int64))
        mb, vb, nb = _theobr_rows(x, mb, tau0, block, m_lo)
    else:
        explicit = m is not None or not isinstance(taus, str)
        ma, va, na, nea = drop_empty_factors("theoh", ma, *_oavar_runs(gapped.runs, ma, tau0), explicit=explicit,
                                            allow_empty=True)
        mb, vb, nb, neb = _theobr_rows_gaps(gapped, mb, tau0, block, m_lo, explicit)
        if ma.size + mb.size == 0:
            raise DataError("theoh: every term reads a missing sample (gap) at every averaging factor;"
                            " the record has no gap-free stretch long enough")
    var = np.concatenate((np.asarray(va, dtype=float), kap.kappa * vb))
    var = unscale_variance(np.where(var < 0.0, 0.0, var), exponent, "theoh")
    bias = (
        f"theoh: oavar for tau < {k * tau0:g} s (m < {k}); {_kappa_text(kap)} for tau >= {k * tau0:g} s"
        f" (even m >= {m_lo}, tau = 0.75 m tau0)"
    )
    if block > 1 and mb.size:
        bias += f"; fast theobr on blocks of {block} points (m = {block}·even m')"
    elif declined:
        bias += "; exact theobr (kappa indicates phase noise, which block averages would remove)"
    common = dict(rate=rate_f, data_type=dtype, n_points=int(N), bias=bias,
                  n_missing=0 if gapped is None else gapped.n_missing)
    # Each part gets the EDF of its own estimator: Greenhall's OAVAR EDF with the
    # noise identified at m below k, the Theo1 EDF with the noise type from κ above.
    low = StabilityResult(statistic="oadev", taus=ma * tau0, m=ma, var=var[: ma.size],
                          dev=np.sqrt(var[: ma.size]), n=na, n_effective=nea, **common)
    high = StabilityResult(statistic="theoh", taus=0.75 * mb * tau0, m=mb, var=var[ma.size:],
                           dev=np.sqrt(var[ma.size:]), n=nb, n_effective=neb, **common)
    low = finish(low, data, dtype, alpha=alpha, confidence=confidence, ci=ci)
    high = finish(high, data, dtype, alpha=alpha, confidence=confidence, ci=ci,
                  identified=_kappa_noise(kap, mb))
    merged = {}
    for name in ("alpha", "alpha_estimate", "edf", "ci_low", "ci_high"):
        parts = (getattr(low, name), getattr(high, name))
        merged[name] = None if parts[0] is None and parts[1] is None else np.concatenate(
            [p if p is not None else np.full(r, np.nan) for p, r in zip(parts, (ma.size, mb.size))])
    reasons = None
    if ci is not None:
        reasons = (low.ci_reason or ("",) * ma.size) + (high.ci_reason or ("",) * mb.size)
    return StabilityResult(
        statistic="theoh",
        taus=np.concatenate((ma * tau0, 0.75 * mb * tau0)),
        m=np.concatenate((ma, mb)),
        var=var,
        dev=np.sqrt(var),
        n=np.concatenate((na, nb)).astype(np.int64),
        bias_factor=np.concatenate((np.ones(ma.size), np.full(mb.size, 1.0 / kap.kappa))),
        n_effective=None if gapped is None else np.concatenate((nea, neb)).astype(np.int64),
        confidence=low.confidence if low.confidence is not None else high.confidence,
        ci_reason=reasons,
        **common,
        **merged,
    )
