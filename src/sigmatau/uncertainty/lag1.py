"""Riley & Greenhall's lag-1 autocorrelation noise identification (numerics.md §5.2).

Public through :mod:`sigmatau.uncertainty.noiseid` (and :mod:`sigmatau.noiseid`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np

from ..core.accel import fused_for
from ..core.gaps import missing_mask
from ..core.numeric import block_means, dot, sumsq
from ..core.shared import memoized
from ..core.validate import as_series, check_data_type
from ..errors import DataError, ParameterError
from .noisebase import InsufficientDataError, _check_d, _check_m

#: Fewest points the lag-1 method accepts (Riley & Greenhall; numerics.md §5.2).
LAG1_MIN_POINTS = 30





@dataclass(frozen=True)
class Lag1Result:
    """Outcome of the lag-1 autocorrelation method at one averaging factor.

    Attributes
    ----------
    alpha : int
        Rounded noise exponent ``−round(2δ) − 2d + 2θ`` (not clipped).
    alpha_estimate : float
        Fractional estimate ``−2(δ + d) + 2θ``; informative for mixed noise.
    d : int
        Number of differences taken before stopping.
    rho1 : float
        Lag-1 autocorrelation ``r1`` of the series at the final ``d``.
    m : int
        Averaging factor.
    n : int
        Length of the decimated (phase) or averaged (frequency) series.
    """

    alpha: int
    alpha_estimate: float
    d: int
    rho1: float
    m: int
    n: int


def _lag1_r1(z: np.ndarray, acf: str = "standard", gaps: bool = False) -> float:
    """Sample lag-1 autocorrelation of ``z`` (times ``(n−1)/n`` for ``acf="stable32"``).

    With ``gaps``, NaN marks a missing point: the mean and the denominator use the
    n points present, the numerator the pairs of neighbours both present, scaled by
    (n − 1)/pairs so that it weighs as in a complete series of n points.
    """
    if gaps:
        return _lag1_r1_gaps(z, acf)
    zc = z - z.mean()
    den = sumsq(zc)
    if den == 0.0:
        raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
    r1 = dot(zc[:-1], zc[1:]) / den
    return r1 * (z.size - 1) / z.size if acf == "stable32" else r1


def _lag1_r1_gaps(z: np.ndarray, acf: str) -> float:
    present = ~np.isnan(z)
    n = int(np.count_nonzero(present))
    zc = np.where(present, z - np.nanmean(z), 0.0) if n else z
    den = sumsq(zc)
    if n < 2 or den == 0.0:
        raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
    # a missing point is 0 after centring, so a pair with one contributes nothing; the
    # n_pairs present replace the n − 1 of a complete series
    pairs = int(np.count_nonzero(present[:-1] & present[1:]))
    if pairs == 0:
        raise InsufficientDataError("no two neighbouring points are both present at this averaging factor")
    r1 = dot(zc[:-1], zc[1:]) / den * (n - 1) / pairs
    return r1 * (n - 1) / n if acf == "stable32" else r1


def _detrend(data: np.ndarray, data_type: str) -> np.ndarray:
    """Remove a least-squares quadratic (phase) or line (frequency), fitted to the points present."""
    t = np.linspace(-1.0, 1.0, data.size)
    deg = 2 if data_type == "phase" else 1
    ok = ~np.isnan(data)
    return data - np.polyval(np.polyfit(t[ok], data[ok], deg), t)


def lag1_acf_noise_id(
    data: object,
    m: int = 1,
    *,
    data_type: Literal["freq", "phase"] = "freq",
    dmin: int = 0,
    dmax: int = 2,
    detrend: bool = False,
    acf: Literal["standard", "stable32"] = "standard",
    min_points: int = LAG1_MIN_POINTS,
) -> Lag1Result:
    """Identify the power-law noise at averaging factor ``m`` from lag-1 autocorrelations.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples.
    m : int
        Averaging factor. Phase data are decimated (``z_k = x_{km}``), frequency
        data averaged over non-overlapped blocks of ``m``.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    dmin, dmax : int
        Fewest and most differences. ``dmax = 2`` resolves α = 2 … −2 (the
        Allan, total and Theo families), ``dmax = 3`` reaches α = −4 on
        frequency data (Hadamard family).
    detrend : bool
        Remove a least-squares quadratic from phase data or a line from
        frequency data before decimating or averaging. Off by default, as in
        Stable32, whose α column the default reproduces; the differencing
        already removes trends whenever ``d ≥ 1``.
    acf : {"standard", "stable32"}
        ``"standard"``: the sample lag-1 autocorrelation below.
        ``"stable32"``: the same multiplied by ``(n−1)/n``, n the current
        length, as Stable32 does; it changes r1 by less than 3 % at n ≥ 30 and
        matters only when α̂ lies within a few hundredths of a rounding
        boundary, where it reproduces Stable32's α column.
    min_points : int
        Fewest points of the decimated/averaged series accepted (30).

    Returns
    -------
    Lag1Result

    Raises
    ------
    InsufficientDataError
        When fewer than ``min_points`` points remain at ``m``; fall back to
        :func:`b1_noise_id` (as :func:`identify` does).

    Notes
    -----
    For a stationary discrete power-law series with spectral exponent
    ``α_z`` the lag-1 autocorrelation is ``ρ1 = −α_z/(2 + α_z)``, so
    ``δ = ρ1/(1 + ρ1) = −α_z/2``; each difference raises ``α_z`` by 2.
    Starting from ``d = 0``, with the sample autocorrelation

    .. math:: r_1 = \\frac{\\sum_{k=0}^{n-2}(z_k - \\bar z)(z_{k+1} - \\bar z)}
                          {\\sum_{k=0}^{n-1}(z_k - \\bar z)^2},
              \\qquad δ = \\frac{r_1}{1 + r_1},

    the loop stops when ``d ≥ dmin`` and (``δ < 0.25`` or ``d ≥ dmax``);
    otherwise ``z`` is differenced and ``d`` incremented. Then
    ``α̂ = −2(δ + d) + 2θ`` and ``α = −round(2δ) − 2d + 2θ``, with θ = 1 for
    phase data and 0 for frequency data.

    At ``m > 1`` the decimated series are differences of τ-averages, whose lag-1
    correlation shifts α̂ (FFM ≈ −1.45, RWFM ≈ −2.4, FWFM ≈ −3.9, which rounds
    to RRFM); see numerics.md §5.2 and §8 item 3.

    References
    ----------
    W. J. Riley and C. A. Greenhall, "Power law noise identification using the
    lag 1 autocorrelation", Proc. 18th EFTF (2004); W. J. Riley, NIST SP 1065
    (2008) §5.6; numerics.md §5.2.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.noiseid import lag1_acf_noise_id
    >>> y = np.random.default_rng(1).standard_normal(4096)      # white FM
    >>> lag1_acf_noise_id(y, 4).alpha
    0
    """
    dtype = check_data_type(data_type)
    series = as_series(data, gaps=True)
    m = _check_m(m)
    dmin, dmax = _check_d(dmin, dmax)
    if acf not in ("standard", "stable32"):
        raise ParameterError(f"acf={acf!r} must be 'standard' or 'stable32'")
    if min_points < 3:
        raise ParameterError(f"min_points={min_points!r} must be at least 3")
    return lag1_of_series(series, m, data_type=dtype, dmin=dmin, dmax=dmax, detrend=detrend, acf=acf,
                          min_points=min_points)


def lag1_of_series(series: np.ndarray, m: int, *, data_type: str, dmin: int, dmax: int, detrend: bool,
                   acf: str, min_points: int) -> Lag1Result:
    """:func:`lag1_acf_noise_id` on a series and options already validated.

    Inside :func:`sigmatau.core.shared.shared_record` the lag-1 autocorrelation
    at each (m, d) is computed once and reused by every statistic of the record
    (the Allan and Hadamard families differ only in how many differences they
    may take), with the same arithmetic, so the result is unchanged.
    """
    n = series.size // m if data_type == "freq" else (series.size + m - 1) // m
    if n < min_points:
        raise InsufficientDataError(
            f"lag-1 noise identification needs at least {min_points} points at m={m},"
            f" got {n} from {series.size} {data_type} samples"
        )
    gaps = missing_mask(series) is not None
    fast = None if gaps or detrend or dmax > 3 else fused_for(series.size)
    if fast is not None:
        r1_at = _fused_r1(fast, series, data_type, m, acf, min_points)
    else:
        diffs = _Differences(series, data_type, m, detrend, min_points)

        def r1_at(d: int) -> float:
            return memoized(series, ("lag1-r1", data_type, m, d, detrend, acf),
                            lambda: _lag1_r1(diffs.at(d), acf, gaps))

    d, delta, r1 = difference_until_white(r1_at, m, dmin, dmax)
    alpha, alpha_est = lag1_alpha(d, delta, data_type)
    return Lag1Result(alpha=alpha, alpha_estimate=alpha_est, d=d, rho1=r1, m=m, n=int(n))


def _fused_r1(fast, series: np.ndarray, dtype: str, m: int, acf: str, min_points: int) -> Callable[[int], float]:
    """``r1_at(d)`` from the compiled kernels (:mod:`sigmatau.core.fused`): the analysis series at m
    made in one pass, r1 in two passes over it, no centred or differenced copy; memoized per d."""
    z = None

    def make(d: int) -> float:
        nonlocal z
        if z is None:
            z = series if m == 1 else (series[::m] if dtype == "phase" else fast.block_means(series, m))
        return fast.lag1_r1(z, d, acf)

    def r1_at(d: int) -> float:
        r1 = memoized(series, ("lag1-r1-fused", dtype, m, d, acf), lambda: make(d))
        if np.isnan(r1):
            raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
        return r1

    return r1_at


def lag1_alpha(d: int, delta: float, data_type: str) -> tuple[int, float]:
    """α (rounded) and its fractional estimate from the differences taken and δ = r1/(1 + r1):
    ``α̂ = −2(δ + d) + 2θ``, θ = 1 for phase data, 0 for frequency data (numerics.md §5.2).

    Examples
    --------
    >>> lag1_alpha(0, 0.5, "freq"), lag1_alpha(1, 0.25, "phase")
    ((-1, -1.0), (0, -0.5))
    """
    theta = 1 if data_type == "phase" else 0
    return -int(np.rint(2.0 * delta)) - 2 * d + 2 * theta, -2.0 * (delta + d) + 2 * theta


class _Differences:
    """The analysis series at ``m`` differenced d times, made only when an r1 is not yet known.

    A class rather than a recursive closure: a nested function that calls itself is a
    reference cycle, and the record-sized series it holds would wait for the garbage
    collector instead of being freed when the identification returns. At most two
    levels are kept.
    """

    def __init__(self, series: np.ndarray, dtype: str, m: int, detrend: bool, min_points: int) -> None:
        self.args = (series, dtype, m, detrend, min_points)
        self.levels: dict[int, np.ndarray] = {}

    def at(self, d: int) -> np.ndarray:
        if d not in self.levels:
            for k in range(d + 1):
                if k not in self.levels:
                    self.levels[k] = _analysis_series(*self.args) if k == 0 else np.diff(self.levels[k - 1])
                    self.levels.pop(k - 2, None)
        return self.levels[d]


def _analysis_series(series: np.ndarray, dtype: str, m: int, detrend: bool, min_points: int) -> np.ndarray:
    """The series the method works on at ``m``: decimated phase or block-averaged frequency.

    Raises
    ------
    InsufficientDataError
        When fewer than ``min_points`` points remain.
    """
    if detrend and series.size > 3:
        series = _detrend(series, dtype)
    # m = 1: the series itself (a mean of one value is that value; no record-sized copy)
    gaps = missing_mask(series) is not None
    # a block holding a gap is missing (its mean from fewer samples would break the telescoping
    # sums of phase-like noise, α ≥ 1, and read as white)
    z = series if m == 1 else (series[::m] if dtype == "phase" else block_means(series, m))
    # with gaps (NaN) only the points present count
    n = int(np.count_nonzero(~np.isnan(z))) if gaps else int(z.size)
    if n < min_points:
        raise InsufficientDataError(
            f"lag-1 noise identification needs at least {min_points} points at m={m},"
            f" got {n} from {series.size} {dtype} samples"
        )
    return z


def difference_until_white(r1_at: Callable[[int], float], m: int, dmin: int, dmax: int) -> tuple[int, float, float]:
    """Difference the series until δ = r1/(1 + r1) < 0.25 (within ``dmin``…``dmax``).

    ``r1_at(d)`` is the lag-1 autocorrelation of the series differenced d times.

    Returns
    -------
    d : int
        Differences taken.
    delta, r1 : float
        δ and the lag-1 autocorrelation at that ``d``.
    """
    d = 0
    while True:
        r1 = r1_at(d)
        if r1 <= -1.0:
            raise DataError(f"lag-1 autocorrelation r1={r1!r} at m={m}, d={d}: the series alternates exactly")
        delta = r1 / (1.0 + r1)
        if d >= dmin and (delta < 0.25 or d >= dmax):
            return d, delta, r1
        d += 1
