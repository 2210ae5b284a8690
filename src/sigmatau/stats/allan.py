"""Allan family: standard deviation of averages, ADEV, OADEV, MDEV and TDEV.

Every estimator here costs O(N) per averaging factor (O(N/m) for the
non-overlapped ones). The plain filter-chain definitions of the design tip are
in :mod:`sigmatau.filterchain` and the tests hold these fast paths to them.
"""

from __future__ import annotations

from typing import Optional


from .engine import run
from ..core.kernels import AVAR, MVAR, OAVAR, OSTDVAR, STDVAR, TVAR
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod
from ..uncertainty.confidence import ONE_SIGMA
from ..core.result import StabilityResult

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
        :mod:`sigmatau.core.taus`).
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
