"""Noise identification: which power-law noise dominates at each averaging time.

Five tools, from the most automatic to the most descriptive:

* :func:`lag1_acf_noise_id` — Riley & Greenhall's lag-1 autocorrelation method,
  good from about 30 analysis points;
* :func:`b1_noise_id` (Barnes' B1 ratio) and :func:`rn_ratio` (R(n) = MVAR/AVAR),
  for the long averaging times where too few points remain;
* :func:`identify` — the Stable32-style per-τ decision between them;
* :func:`theo_noise_id` — the noise type from TheoBR's bias ratio κ;
* :func:`local_slopes` and :func:`fit_power_law` — the design tip's slope table,
  read off a computed deviation curve, and a whole-curve fit of power-law terms.

Noise types are named by the exponent α of the one-sided frequency PSD
``S_y(f) = h_α f^α`` (numerics.md §0): 2 WPM, 1 FPM, 0 WFM, −1 FFM, −2 RWFM,
−3 FWFM, −4 RRFM.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Mapping, Optional, Sequence, Union

import numpy as np

from ..core.validate import as_series, check_data_type, check_rate
from ..core.numeric import block_means, dot, sumsq
from ..core.powerlaw import EULER_GAMMA as _EULER_GAMMA
from ..core.powerlaw import response
from ..core.driver import compute
from ..core.kernels import MVAR, OAVAR
from ..errors import DataError, ParameterError
from ..core.result import StabilityResult
from ..core.taus import STOP_RATIOS, long_factors_expected

__all__ = [
    "NOISE_NAMES",
    "InsufficientDataError",
    "Lag1Result",
    "lag1_acf_noise_id",
    "B1Result",
    "b1_ratio",
    "b1_expected",
    "b1_noise_id",
    "rn_ratio",
    "rn_expected",
    "b1_min_averages",
    "NoiseIdentification",
    "identify",
    "theo_noise_id",
    "LocalSlopes",
    "local_slopes",
    "power_law_variance",
    "PowerLawFit",
    "fit_power_law",
]

#: Short names of the power-law noise types, keyed by the frequency exponent α.
NOISE_NAMES: Mapping[int, str] = {
    2: "WPM", 1: "FPM", 0: "WFM", -1: "FFM", -2: "RWFM", -3: "FWFM", -4: "RRFM",
}

Family = Literal["allan", "modified", "hadamard", "total", "theo"]


#: Fewest points the lag-1 method accepts (Riley & Greenhall; numerics.md §5.2).
LAG1_MIN_POINTS = 30


class InsufficientDataError(DataError):
    """Too few points remain at this averaging factor for the requested method.

    Raised by :func:`lag1_acf_noise_id` (fewer than 30 points) and
    :func:`b1_noise_id` (fewer than 3 averages); :func:`identify` catches it and
    falls back to the next method.
    """


# --------------------------------------------------------------------------- checks


def _check_m(m: object, name: str = "m") -> int:
    if isinstance(m, (bool, np.bool_)) or not isinstance(m, (int, np.integer)):
        if isinstance(m, (float, np.floating)) and float(m).is_integer():
            m = int(m)
        else:
            raise ParameterError(f"{name}={m!r} must be a positive integer averaging factor")
    if m < 1:
        raise ParameterError(f"{name}={m!r} must be a positive integer averaging factor")
    return int(m)


def _check_count(value: object, name: str) -> int:
    """A number of terms: an integer ≥ 1 (0 and 1 leave the default N in place)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ParameterError(f"{name}={value!r} must be a non-negative integer number of terms")
    return int(value)


def _check_d(dmin: object, dmax: object) -> tuple[int, int]:
    for name, value in (("dmin", dmin), ("dmax", dmax)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ParameterError(f"{name}={value!r} must be a non-negative integer")
    if dmin > dmax:  # type: ignore[operator]
        raise ParameterError(f"dmin={dmin!r} must not exceed dmax={dmax!r}")
    return int(dmin), int(dmax)  # type: ignore[arg-type]


def _frequency(data: np.ndarray, data_type: str) -> np.ndarray:
    """Frequency samples up to a constant factor (τ0 cancels in every ratio here)."""
    return np.diff(data) if data_type == "phase" else data


# ------------------------------------------------------------------ lag-1 ACF (§5.2)


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


def _lag1_r1(z: np.ndarray, acf: str = "standard") -> float:
    zc = z - z.mean()
    den = sumsq(zc)
    if den == 0.0:
        raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
    r1 = dot(zc[:-1], zc[1:]) / den
    return r1 * (z.size - 1) / z.size if acf == "stable32" else r1


def _detrend(data: np.ndarray, data_type: str) -> np.ndarray:
    t = np.linspace(-1.0, 1.0, data.size)
    deg = 2 if data_type == "phase" else 1
    return data - np.polyval(np.polyfit(t, data, deg), t)


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
    series = as_series(data)
    m = _check_m(m)
    dmin, dmax = _check_d(dmin, dmax)
    if acf not in ("standard", "stable32"):
        raise ParameterError(f"acf={acf!r} must be 'standard' or 'stable32'")
    if min_points < 3:
        raise ParameterError(f"min_points={min_points!r} must be at least 3")
    if detrend and series.size > 3:
        series = _detrend(series, dtype)
    z = series[::m] if dtype == "phase" else block_means(series, m)
    n = int(z.size)
    if n < min_points:
        raise InsufficientDataError(
            f"lag-1 noise identification needs at least {min_points} points at m={m},"
            f" got {n} from {series.size} {dtype} samples"
        )
    theta = 1 if dtype == "phase" else 0
    d = 0
    while True:
        r1 = _lag1_r1(z, acf)
        if r1 <= -1.0:
            raise DataError(f"lag-1 autocorrelation r1={r1!r} at m={m}, d={d}: the series alternates exactly")
        delta = r1 / (1.0 + r1)
        if d >= dmin and (delta < 0.25 or d >= dmax):
            break
        z = np.diff(z)
        d += 1
    alpha_est = -2.0 * (delta + d) + 2 * theta
    alpha = -int(np.rint(2.0 * delta)) - 2 * d + 2 * theta
    return Lag1Result(alpha=alpha, alpha_estimate=alpha_est, d=d, rho1=r1, m=m, n=n)


# ------------------------------------------------------------------------ B1 (§5.3)


def b1_expected(nb: Union[int, np.ndarray], mu: Union[float, np.ndarray]) -> np.ndarray:
    """Barnes' bias function B1: expected standard variance over Allan variance.

    Parameters
    ----------
    nb : int or array_like
        Number of averages ``Nb ≥ 2`` in the standard variance.
    mu : float or array_like
        Exponent of the Allan variance, ``AVAR ∝ τ^μ``.

    Returns
    -------
    numpy.ndarray (a 0-d array for scalar input)

    Notes
    -----
    With dead-time ratio 1,

    .. math:: B_1(N_b, μ) = \\frac{N_b (1 - N_b^{μ})}{2 (N_b - 1)(1 - 2^{μ})}
              \\quad (μ ≠ 0), \\qquad
              B_1(N_b, 0) = \\frac{N_b \\ln N_b}{2 (N_b - 1) \\ln 2}.

    Closed forms: μ = −2 gives ``2(Nb+1)/(3Nb)``, μ = −1 gives 1, μ = 1 gives
    ``Nb/2`` and μ = 2 gives ``Nb(Nb+1)/6``.

    References
    ----------
    J. A. Barnes, "Tables of bias functions B1 and B2 for variances based on
    finite samples of processes with power law spectral densities", NBS Tech.
    Note 375 (1969); numerics.md §5.3.

    Examples
    --------
    >>> from sigmatau.noiseid import b1_expected
    >>> float(b1_expected(16, 1))
    8.0
    """
    nb_a = np.asarray(nb, dtype=float)
    mu_a = np.asarray(mu, dtype=float)
    if np.any(nb_a < 2):
        raise ParameterError(f"nb={nb!r} must be at least 2")
    nb_b, mu_b = np.broadcast_arrays(nb_a, mu_a)
    out = np.empty(nb_b.shape)
    zero = np.abs(mu_b) < 1e-12
    with np.errstate(invalid="ignore", divide="ignore"):
        general = nb_b * (1.0 - nb_b**mu_b) / (2.0 * (nb_b - 1.0) * (1.0 - 2.0**mu_b))
        at_zero = nb_b * np.log(nb_b) / (2.0 * (nb_b - 1.0) * math.log(2.0))
    out[...] = np.where(zero, at_zero, general)
    return out


def b1_ratio(data: object, m: int = 1, *, data_type: Literal["freq", "phase"] = "freq") -> float:
    """Observed B1 ratio: standard variance of the m-averages over their Allan variance.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples.
    m : int
        Averaging factor.
    data_type : {"freq", "phase"}
        Meaning of ``data``.

    Returns
    -------
    float

    Notes
    -----
    With the ``Nb = ⌊M/m⌋`` non-overlapped averages ``ȳ_k`` of the M frequency
    samples (phase data are differenced first),

    .. math:: B_1 = \\frac{\\frac{1}{N_b-1}\\sum_k (\\bar y_k - \\bar{\\bar y})^2}
                          {\\frac{1}{2(N_b-1)}\\sum_k (\\bar y_{k+1} - \\bar y_k)^2}.

    References
    ----------
    numerics.md §1.1, §5.3; W. J. Riley, NIST SP 1065 (2008) §5.6.
    """
    dtype = check_data_type(data_type)
    series = as_series(data)
    m = _check_m(m)
    return b1_observed(_frequency(series, dtype), m)[0]


def b1_observed(y: np.ndarray, m: int) -> tuple[float, int]:
    means = block_means(y, m)
    nb = int(means.size)
    if nb < 2:
        raise InsufficientDataError(f"the B1 ratio needs at least 2 averages at m={m}, got {nb}")
    s2 = float(means.var(ddof=1))
    dif = np.diff(means)
    avar = float(np.einsum("i,i->", dif, dif)) / (2.0 * (nb - 1))
    if avar == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; the B1 ratio is undefined")
    return s2 / avar, nb


@dataclass(frozen=True)
class B1Result:
    """Outcome of the B1 noise identification at one averaging factor.

    Attributes
    ----------
    alpha : int
        Noise exponent ``−μ − 1``; μ = −2 (WPM or FPM) is reported as α = 1,
        Stable32's convention, with ``ambiguous=True``.
    alpha_estimate : float
        ``−μ̂ − 1`` with μ̂ solving ``B1(Nb, μ̂) = ratio`` on [−2, 2] (clipped).
    mu : int
        Chosen Allan-variance exponent (after the Hadamard shift, if any).
    ratio : float
        Observed B1 ratio (of the second pass in Hadamard mode).
    nb : int
        Number of averages.
    ambiguous : bool
        True when μ = −2, which B1 cannot split into WPM and FPM (use R(n)).
    m : int
        Averaging factor.
    """

    alpha: int
    alpha_estimate: float
    mu: int
    ratio: float
    nb: int
    ambiguous: bool
    m: int


_B1_MUS = (-2, -1, 0, 1, 2)


def b1_classify(ratio: float, nb: int, n_expected: Optional[int] = None) -> tuple[int, float]:
    """Nearest μ (geometric-mean boundaries) and the fractional μ̂.

    ``n_expected`` replaces ``nb`` as the N of the expectation ``B1(N, μ)``
    (Stable32 passes the number of terms of the statistic; see :func:`identify`).
    """
    if n_expected is not None and n_expected >= 2:
        nb = int(n_expected)
    expected = b1_expected(nb, np.array(_B1_MUS, dtype=float))
    bounds = np.sqrt(expected[:-1] * expected[1:])
    mu = _B1_MUS[int(np.searchsorted(bounds, ratio))]
    lo, hi = _B1_MUS[0], _B1_MUS[-1]
    if nb < 3:  # every μ gives B1 = 1
        return mu, float(mu)
    if ratio <= expected[0]:
        mu_hat = float(lo)
    elif ratio >= expected[-1]:
        mu_hat = float(hi)
    else:
        from scipy.optimize import brentq  # imported here: keeps `import sigmatau` light

        mu_hat = brentq(lambda u: float(b1_expected(nb, u)) - ratio, lo, hi, xtol=1e-6)
    return mu, mu_hat


def b1_noise_id(
    data: object,
    m: int = 1,
    *,
    data_type: Literal["freq", "phase"] = "freq",
    hadamard: bool = False,
    n_expected: Optional[int] = None,
) -> B1Result:
    """Identify the noise at ``m`` from the B1 ratio (for few averages).

    Parameters
    ----------
    data : array_like
        Phase or frequency samples.
    m : int
        Averaging factor.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    hadamard : bool
        Reach FWFM and RRFM as needed by the Hadamard family (see Notes).
    n_expected : int, optional
        N of the expectation ``B1(N, μ)`` the observed ratio is compared
        with; default the number of averages ``Nb``. Stable32 uses the number
        of terms of the statistic being computed (the "#" column of its
        tables), which :func:`identify` passes as ``n_terms``.

    Returns
    -------
    B1Result

    Raises
    ------
    InsufficientDataError
        When fewer than 3 averages remain (with 2, B1 ≡ 1 for every noise).

    Notes
    -----
    The observed ratio (:func:`b1_ratio`) is compared with
    ``B1(Nb, μ)`` (:func:`b1_expected`) for μ = −2 … 2, with boundaries at
    the geometric means of neighbouring expectations, and mapped to
    ``α = −μ − 1`` (numerics.md §5.1). μ = −2 covers both WPM and FPM.

    Hadamard mode (``hadamard=True``): when the first pass gives μ ≥ 1
    (α ≤ −2), the frequency samples are treated as phase — a second B1 pass on
    the differences of the frequency series, whose exponent is α + 2, so that
    FWFM and RRFM appear as FFM and RWFM where B1 is well behaved — and 2 is
    added to its μ: ``μ = μ' + 2``, ``α = −μ' − 3``, held to at most −2 and at
    least −4 (RRFM, μ = 3). The first pass decides everything above RWFM,
    which is what Stable32's Hadamard α columns show.

    B1 assumes averaged (counter-type) frequency samples; point-sampled
    random-walk FM gives ``(Nb+1)/3`` instead of ``Nb/2`` at m = 1.

    References
    ----------
    J. A. Barnes, NBS Tech. Note 375 (1969); D. A. Howe, R. L. Beard,
    C. A. Greenhall, F. Vernotte, W. J. Riley, "A total estimator of the
    Hadamard function used for GPS operations", Proc. 32nd PTTI (2000);
    numerics.md §5.3.
    """
    dtype = check_data_type(data_type)
    series = as_series(data)
    m = _check_m(m)
    if n_expected is not None:
        n_expected = _check_count(n_expected, "n_expected")
    y = _frequency(series, dtype)
    ratio, nb = b1_observed(y, m)
    if nb < 3:
        raise InsufficientDataError(f"B1 noise identification needs at least 3 averages at m={m}, got {nb}")
    mu, mu_hat = b1_classify(ratio, nb, n_expected)
    if hadamard and mu >= 1:
        try:
            ratio2, nb2 = b1_observed(np.diff(y), m)
        except (InsufficientDataError, DataError):
            nb2 = 0
        if nb2 >= 3:
            mu2, mu2_hat = b1_classify(ratio2, nb2, n_expected)
            mu = min(max(mu2 + 2, 1), 3)
            mu_hat = min(max(mu2_hat + 2.0, 1.0), 3.0)
            ratio, nb = ratio2, nb2
    alpha = 1 if mu == -2 else -mu - 1
    return B1Result(alpha=alpha, alpha_estimate=-mu_hat - 1.0, mu=mu, ratio=ratio, nb=nb,
                    ambiguous=(mu == -2), m=m)


# ---------------------------------------------------------------------- R(n) (§5.4)


def rn_expected(n: Union[int, np.ndarray], alpha: int) -> np.ndarray:
    """Expected ratio ``R(n) = MVAR/AVAR`` at averaging factor n for noise α.

    Parameters
    ----------
    n : int or array_like
        Averaging factor(s), ≥ 1.
    alpha : {2, 1, 0, -1, -2}
        Noise exponent.

    Returns
    -------
    numpy.ndarray

    Notes
    -----
    With the cut-off ``f_h = 1/(2τ0)``:

    * WPM: ``1/n``, exact for discrete white phase at every n;
    * FPM: ``3 ln(256/27) / (2[3γ − ln 2 + 3 ln(πn)])
      = 3.374/(1.0385 + 3 ln(πn))`` (continuous model);
    * WFM 0.5, FFM ``((27/8) ln 3 − 4 ln 2)/(2 ln 2) = 0.6747`` and RWFM
      ``(11π²/20)/(2π²/3) = 0.825`` are the n → ∞ limits, given for reference:
      R(n) only separates WPM from FPM.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.6; numerics.md §5.4, §6.3.

    Examples
    --------
    >>> from sigmatau.noiseid import rn_expected
    >>> round(float(rn_expected(64, 1)), 4)
    0.1991
    """
    n_a = np.asarray(n, dtype=float)
    if np.any(n_a < 1):
        raise ParameterError(f"n={n!r} must be at least 1")
    if alpha == 2:
        return 1.0 / n_a
    if alpha == 1:
        num = 3.0 * math.log(256.0 / 27.0)
        return num / (2.0 * (3.0 * _EULER_GAMMA - math.log(2.0) + 3.0 * np.log(math.pi * n_a)))
    limits = {
        0: 0.5,
        -1: (27.0 / 8.0 * math.log(3.0) - 4.0 * math.log(2.0)) / (2.0 * math.log(2.0)),
        -2: (11.0 / 20.0) / (2.0 / 3.0),
    }
    if alpha not in limits:
        raise ParameterError(f"alpha={alpha!r} must be one of 2, 1, 0, -1, -2")
    return np.full(n_a.shape, limits[alpha])


def rn_ratio(data: object, m: int = 1, *, data_type: Literal["freq", "phase"] = "freq") -> float:
    """Observed ``R(n) = MVAR(τ)/AVAR(τ)`` at averaging factor m.

    Both variances are the overlapped estimators on the same data (they share
    the expectation of their non-overlapped forms and scatter less).

    Parameters
    ----------
    data : array_like
        Phase or frequency samples.
    m : int
        Averaging factor (MVAR needs ``3m`` phase points).
    data_type : {"freq", "phase"}
        Meaning of ``data``.

    Returns
    -------
    float

    References
    ----------
    numerics.md §5.4.
    """
    dtype = check_data_type(data_type)
    series = as_series(data)
    m = _check_m(m)
    npts = series.size if dtype == "phase" else series.size + 1
    if npts < 3 * m:
        raise InsufficientDataError(f"R(n) needs at least {3 * m} phase points at m={m}, got {npts}")
    with long_factors_expected():  # long-τ factors are the point here
        mv = compute(MVAR, series, rate=1.0, data_type=dtype, taus="octave", m=[m])[0].var[0]
        av = compute(OAVAR, series, rate=1.0, data_type=dtype, taus="octave", m=[m])[0].var[0]
    if av == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; R(n) is undefined")
    return float(mv / av)


# -------------------------------------------------------------- decision logic (§5.5)

FAMILY_ALIASES: dict[str, str] = {
    "allan": "allan", "total": "allan", "theo": "allan",
    "modified": "modified", "hadamard": "hadamard",
    "stdev": "allan", "ostdev": "allan", "adev": "allan", "oadev": "allan", "totdev": "allan",
    "theo1": "allan", "theobr": "allan",
    "mdev": "modified", "tdev": "modified", "mtotdev": "modified", "ttotdev": "modified",
    "theoh": "modified",
    "hdev": "hadamard", "ohdev": "hadamard", "htotdev": "hadamard",
}

#: Range of α each family supports: (dmax, lowest α, highest α).
FAMILY_RULES = {"allan": (2, -2, 2), "modified": (2, -2, 2), "hadamard": (3, -4, 2)}


@dataclass(frozen=True, repr=False, eq=False)
class NoiseIdentification:
    """Per-τ noise identification (see :func:`identify`).

    Attributes
    ----------
    m, taus : numpy.ndarray
        Averaging factors and τ = m/rate.
    alpha : numpy.ndarray of int
        Identified α, clipped to the family's range.
    alpha_estimate : numpy.ndarray of float
        Fractional estimate before clipping (NaN where no method applied).
    method : tuple of str
        ``"lag1"``, ``"b1"``, ``"b1+rn"`` or ``"carried"`` (too few averages
        for B1, or no method applied: α of the nearest smaller identified m,
        else of the nearest one).
    family : str
        ``"allan"``, ``"modified"`` or ``"hadamard"``.
    data_type : str
    """

    m: np.ndarray
    taus: np.ndarray
    alpha: np.ndarray
    alpha_estimate: np.ndarray
    method: tuple[str, ...]
    family: str
    data_type: str

    def __post_init__(self) -> None:
        for name in ("m", "taus", "alpha", "alpha_estimate"):
            arr = np.array(getattr(self, name), copy=True)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.m.size)

    def __repr__(self) -> str:
        names = ", ".join(f"{int(m)}:{NOISE_NAMES.get(int(a), a)}" for m, a in zip(self.m, self.alpha))
        return f"NoiseIdentification({self.family}, {self.data_type} data, m:type = {names})"


def identify(
    data: object,
    ms: Union[int, Sequence[int], np.ndarray],
    *,
    data_type: Literal["freq", "phase"] = "freq",
    family: Union[Family, str] = "allan",
    rate: float = 1.0,
    detrend: bool = False,
    acf: Literal["standard", "stable32"] = "standard",
    n_terms: Optional[Union[Sequence[int], np.ndarray]] = None,
) -> NoiseIdentification:
    """Stable32-style noise identification at each averaging factor.

    Parameters
    ----------
    data : array_like
        Phase or frequency samples (N of them).
    ms : int or sequence of int
        Averaging factors.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    family : str
        ``"allan"`` (also ``"total"``, ``"theo"``), ``"modified"`` or
        ``"hadamard"``, or a statistic name (``"oadev"``, ``"mdev"``,
        ``"tdev"``, ``"hdev"``, ``"ohdev"``, ``"totdev"``, ``"mtotdev"``,
        ``"ttotdev"``, ``"htotdev"``, ``"theo1"``, ``"theobr"``, ``"theoh"`` …).
    rate : float
        Sample rate in Hz, used only for the ``taus`` of the result.
    detrend, acf
        Passed to :func:`lag1_acf_noise_id`; ``acf="stable32"`` reproduces
        Stable32's α at rows where α̂ sits on a rounding boundary.
    n_terms : sequence of int, optional
        Number of terms of the statistic at each factor of ``ms`` (the "#"
        column of a Stable32 table, ``StabilityResult.n``). Where B1 decides,
        it is the N of the expectation ``B1(N, μ)``, as in Stable32; without
        it N is the number of averages ``Nb``. The statistic functions pass
        their own ``n``.

    Returns
    -------
    NoiseIdentification

    Notes
    -----
    At each m (numerics.md §5.5):

    1. if ``⌊N/m⌋ ≥ 30``, N the number of data points as given (phase or
       frequency): lag-1 autocorrelation (:func:`lag1_acf_noise_id`) with
       ``dmax = 2`` for the Allan, total and Theo families and ``dmax = 3``
       for the Hadamard family;
    2. otherwise B1 (:func:`b1_noise_id`, Hadamard mode for that family),
       compared with ``B1(N, μ)`` for N = ``n_terms`` when given; when B1
       finds μ = −2 (WPM or FPM), R(n) = MVAR/AVAR of the data splits WPM (R
       below the geometric mean of the WPM and FPM expectations) from FPM.
       Stable32's manual does this for the modified family only and reports
       α = 1 elsewhere; we do it for every family, because the EDF of OADEV or
       OHDEV for FPM is several times smaller than for WPM and calling white
       PM flicker PM made the 68.3 % intervals cover 99.9 % of the time
       (tests/test_confidence_mc.py). On the Stable32 tables we have, this
       changes no row;
    3. B1 is applied only while the ``Nb = ⌊M/m⌋`` averages of the M
       frequency samples number at least ``2·stop``, twice the Stable32 stop
       ratio of the statistic named by ``family`` (ADEV, HDEV, STDEV: 10;
       OADEV, MDEV, TDEV, OHDEV, OSTDEV: 8; MTOT, TTOT, HTOT: 6; TOTDEV: 4),
       and at least 3 averages for a family name. Past that — and wherever no
       method applies — α is carried from the nearest smaller identified
       factor (``method`` "carried").

    Rules 2 and 3 are those that reproduce Stable32's Alpha column (checked
    on 8138 rows of 115 Stable32 tables: octave, decade and all-τ grids of
    phase and frequency records from 1001 to 241218 points, 99.6 % agree).
    They also stop α from jumping between neighbouring τ where a handful of
    averages cannot tell noise types apart: with ``N = Nb`` the B1 boundaries
    are so close together at small Nb that sampling noise alone moves the
    ratio across them.

    α is clipped to what the family's variance supports: [−2, 2] for the
    Allan and modified families (AVAR and MVAR diverge for α ≤ −3) and
    [−4, 2] for the Hadamard family. ``alpha_estimate`` is left unclipped so
    that an out-of-range value (e.g. FWFM seen by an Allan statistic) stays
    visible.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.6; Riley & Greenhall, Proc. EFTF
    (2004); numerics.md §5.2–§5.5.

    Examples
    --------
    >>> import numpy as np
    >>> from sigmatau.noiseid import identify
    >>> x = np.random.default_rng(0).standard_normal(10_000)   # white phase
    >>> identify(x, [1, 10, 100], data_type="phase").alpha.tolist()
    [2, 2, 2]
    """
    dtype = check_data_type(data_type)
    rate_f = check_rate(rate)
    series = as_series(data)
    fam = FAMILY_ALIASES.get(str(family).lower()) if isinstance(family, str) else None
    if fam is None:
        raise ParameterError(
            f"family={family!r} must be 'allan', 'modified', 'hadamard' or a statistic name"
            f" ({', '.join(sorted(k for k in FAMILY_ALIASES if k not in FAMILY_RULES))})"
        )
    m_arr = np.atleast_1d(np.asarray(ms))
    if m_arr.ndim != 1:
        raise ParameterError(f"ms must be an integer or a 1-D sequence of integers, got shape {m_arr.shape}")
    m_list = [_check_m(v, "ms") for v in m_arr.tolist()]
    dmax, lo, hi = FAMILY_RULES[fam]
    n_data = series.size
    n_freq = n_data - 1 if dtype == "phase" else n_data
    min_averages = b1_min_averages(str(family).lower())
    terms = _check_terms(n_terms, len(m_list))

    alpha = np.zeros(len(m_list), dtype=np.int64)
    est = np.full(len(m_list), np.nan)
    method: list[str] = []
    for i, m in enumerate(m_list):
        if n_data // m >= LAG1_MIN_POINTS:
            try:
                r = lag1_acf_noise_id(series, m, data_type=dtype, dmax=dmax, detrend=detrend, acf=acf)
            except InsufficientDataError:
                pass
            else:
                alpha[i], est[i] = r.alpha, r.alpha_estimate
                method.append("lag1")
                continue
        if n_freq // m < min_averages:
            method.append("carried")
            continue
        try:
            b = b1_noise_id(series, m, data_type=dtype, hadamard=(fam == "hadamard"),
                            n_expected=None if terms is None else terms[i])
        except DataError:
            method.append("carried")
            continue
        alpha[i], est[i] = b.alpha, b.alpha_estimate
        tag = "b1"
        if b.ambiguous:
            try:
                rn = rn_ratio(series, m, data_type=dtype)
            except DataError:
                pass
            else:
                wpm, fpm = float(rn_expected(m, 2)), float(rn_expected(m, 1))
                alpha[i] = 2 if rn < math.sqrt(wpm * fpm) else 1
                # log-interpolated position between the two expectations
                t = (math.log(rn) - math.log(wpm)) / (math.log(fpm) - math.log(wpm)) if fpm != wpm else 0.0
                est[i] = 2.0 - t
                tag = "b1+rn"
        method.append(tag)

    done = [i for i, tag in enumerate(method) if tag != "carried"]
    for i, tag in enumerate(method):
        if tag == "carried":
            if not done:
                raise InsufficientDataError(
                    f"no averaging factor in ms leaves enough data ({n_data} points) for any method"
                )
            alpha[i] = alpha[_carried_from(done, m_list, i)]
    alpha = np.clip(alpha, lo, hi)
    m_out = np.array(m_list, dtype=np.int64)
    return NoiseIdentification(m=m_out, taus=m_out / rate_f, alpha=alpha, alpha_estimate=est,
                               method=tuple(method), family=fam, data_type=dtype)


def b1_min_averages(statistic: str) -> int:
    """Fewest averages ``Nb = ⌊M/m⌋`` at which :func:`identify` applies B1 for ``statistic``.

    Parameters
    ----------
    statistic : str
        A statistic name (``"adev"``, ``"oadev"``, ``"totdev"`` …) or a
        family name.

    Returns
    -------
    int
        Twice the statistic's Stable32 stop ratio (the ``stop_ratio`` its
        keyword grids use): 10 for ADEV, HDEV and STDEV, 8 for OADEV, MDEV,
        TDEV, OHDEV and OSTDEV, 6 for MTOT, TTOT and HTOT, 4 for TOTDEV; 3, the
        least B1 can use, for family names and the Theo family.

    Notes
    -----
    Beyond this factor Stable32 carries the α of the preceding τ instead of
    computing B1: that rule reproduces its Alpha column on every dense grid
    we have (see :func:`identify`).

    Examples
    --------
    >>> from sigmatau.noiseid import b1_min_averages
    >>> b1_min_averages("oadev"), b1_min_averages("totdev"), b1_min_averages("allan")
    (8, 4, 3)
    """
    stop = STOP_RATIOS.get(statistic)
    return 3 if stop is None else max(3, int(round(2 * stop)))


def _check_terms(n_terms: object, size: int) -> Optional[list[int]]:
    if n_terms is None:
        return None
    arr = np.atleast_1d(np.asarray(n_terms))
    if arr.shape != (size,):
        raise ParameterError(f"n_terms has shape {arr.shape}; it must give one count per averaging factor ({size})")
    return [_check_count(v, "n_terms") for v in arr.tolist()]


def _carried_from(done: list[int], m_list: list[int], i: int) -> int:
    """Index whose α row ``i`` takes: the largest identified factor below it, else the nearest."""
    below = [j for j in done if m_list[j] < m_list[i]]
    if below:
        return max(below, key=lambda j: m_list[j])
    return min(done, key=lambda j: (abs(math.log(m_list[j] / m_list[i])), -m_list[j]))


# ------------------------------------------------------------------ Theo κ (§3, §5.5)

_THEO_ALPHAS = (2, 1, 0, -1, -2)
_THEO_NOMINAL = (0.4, 0.6, 1.0, 1.71, 2.24)
#: Howe & Tasset (2004) Table 1: AVAR/Theo1 = a + b/t^c, t = 0.75 m.
_THEO_ABC = ((0.09, 0.74, 0.40), (0.14, 0.82, 0.30), (1.0, 0.0, 0.0), (1.87, -1.05, 0.79), (2.70, -1.53, 0.85))


def theo_noise_id(kappa: Union[float, np.ndarray], *, m: Optional[Union[int, np.ndarray]] = None) -> np.ndarray:
    """Noise type from TheoBR's bias ratio κ = AVAR/Theo1.

    Parameters
    ----------
    kappa : float or array_like
        Observed ratio(s) κ.
    m : int or array_like, optional
        Averaging factor(s). Without it the fixed nominal Theo1 bias factors
        0.4, 0.6, 1.0, 1.71, 2.24 (WPM, FPM, WFM, FFM, RWFM) are used; with it,
        the τ-dependent factors ``a + b/t^c``, t = 0.75 m, of Howe & Tasset.

    Returns
    -------
    numpy.ndarray of int
        α ∈ {2, 1, 0, −1, −2}, shaped like ``kappa`` (broadcast with ``m``).

    Notes
    -----
    κ is compared with the nominal factors; the thresholds are the geometric
    means of neighbouring factors (0.490, 0.775, 1.308, 1.957 for the fixed
    set).

    References
    ----------
    D. A. Howe and T. K. Peppler, "Very long-term frequency stability:
    estimation using a special-purpose statistic", Proc. IEEE FCS (2003);
    D. A. Howe and T. N. Tasset, "Theo1: characterization of very long-term
    frequency stability", Proc. EFTF (2004); numerics.md §3, §5.5.

    Examples
    --------
    >>> from sigmatau.noiseid import theo_noise_id
    >>> theo_noise_id([0.45, 0.7, 1.1, 1.6, 2.5]).tolist()
    [2, 1, 0, -1, -2]
    """
    k = np.asarray(kappa, dtype=float)
    if np.any(~np.isfinite(k)) or np.any(k <= 0):
        raise ParameterError(f"kappa={kappa!r} must be positive and finite")
    if m is None:
        factors = np.broadcast_to(np.array(_THEO_NOMINAL), k.shape + (5,))
    else:
        m_a = np.asarray(m, dtype=float)
        if np.any(m_a < 1):
            raise ParameterError(f"m={m!r} must be at least 1")
        k, m_a = np.broadcast_arrays(k, m_a)
        t = 0.75 * m_a[..., None]
        abc = np.array(_THEO_ABC)
        factors = abc[:, 0] + abc[:, 1] / t ** abc[:, 2]
    bounds = np.sqrt(factors[..., :-1] * factors[..., 1:])
    idx = np.sum(k[..., None] > bounds, axis=-1)
    return np.asarray(_THEO_ALPHAS)[idx]


# ------------------------------------------------------------ local slopes (§5.1)

_SLOPES_ALLAN = ((-1.0, (2, 1)), (-0.5, (0,)), (0.0, (-1,)), (0.5, (-2,)), (1.0, (-3,)), (1.5, (-4,)))
_SLOPES_MOD = ((-1.5, (2,)), (-1.0, (1,)), (-0.5, (0,)), (0.0, (-1,)), (0.5, (-2,)), (1.0, (-3,)), (1.5, (-4,)))
_SLOPES_TIME = tuple((s + 1.0, a) for s, a in _SLOPES_MOD)
_SLOPE_TABLES = {
    "adev": _SLOPES_ALLAN, "oadev": _SLOPES_ALLAN, "totdev": _SLOPES_ALLAN,
    "hdev": _SLOPES_ALLAN, "ohdev": _SLOPES_ALLAN, "htotdev": _SLOPES_ALLAN,
    "theo1": _SLOPES_ALLAN, "theobr": _SLOPES_ALLAN, "theoh": _SLOPES_ALLAN,
    "mdev": _SLOPES_MOD, "mtotdev": _SLOPES_MOD,
    "tdev": _SLOPES_TIME, "ttotdev": _SLOPES_TIME,
}


@dataclass(frozen=True, repr=False, eq=False)
class LocalSlopes:
    """Local log–log slopes of a deviation curve (see :func:`local_slopes`).

    Attributes
    ----------
    statistic : str
    taus : numpy.ndarray
        Geometric mean of each pair of neighbouring τ.
    slope, slope_err : numpy.ndarray
        ``Δ ln σ / Δ ln τ`` and its standard uncertainty.
    nominal : numpy.ndarray
        Nearest slope of the statistic's table.
    alpha : numpy.ndarray of int
        Noise type of that slope; where ADEV-like slopes of −1 cannot split WPM
        from FPM, α = 1 and ``ambiguous`` is True.
    ambiguous : numpy.ndarray of bool
    """

    statistic: str
    taus: np.ndarray
    slope: np.ndarray
    slope_err: np.ndarray
    nominal: np.ndarray
    alpha: np.ndarray
    ambiguous: np.ndarray

    def __post_init__(self) -> None:
        for name in ("taus", "slope", "slope_err", "nominal", "alpha", "ambiguous"):
            arr = np.array(getattr(self, name), copy=True)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.taus.size)

    def __repr__(self) -> str:
        parts = ", ".join(
            f"{t:.3g}s:{s:+.2f}±{e:.2f}({'WPM/FPM' if amb else NOISE_NAMES.get(int(a), a)})"
            for t, s, e, a, amb in zip(self.taus, self.slope, self.slope_err, self.alpha, self.ambiguous)
        )
        return f"LocalSlopes({self.statistic}: {parts})"


def _independent_terms(result: StabilityResult) -> np.ndarray:
    """Terms of the estimator that are not overlapping: ``min(n, ⌊(N−1)/m⌋)``."""
    blocks = np.maximum((result.n_points - 1) // np.maximum(result.m, 1), 1)
    return np.maximum(np.minimum(result.n, blocks), 1).astype(float)


def local_slopes(result: StabilityResult) -> LocalSlopes:
    """Slope of log σ against log τ between neighbouring τ, and the noise it implies.

    Parameters
    ----------
    result : StabilityResult
        A deviation curve of ADEV, OADEV, MDEV, TDEV, HDEV or OHDEV (also
        TOTDEV, MTOT, TTOT, HTOT and the Theo family, read like their parent).

    Returns
    -------
    LocalSlopes

    Notes
    -----
    ``slope_i = (ln σ_{i+1} − ln σ_i)/(ln τ_{i+1} − ln τ_i)``. Uncertainty:
    with an EDF ν (``result.edf``), ``var(ln σ) ≈ 1/(2ν)``; without it the
    design tip's simple estimate, a relative deviation error ``1/√n``, with n
    the number of non-overlapping terms ``min(n, ⌊(N−1)/m⌋)`` (overlapped
    terms are not independent). The errors of the two ends are added in
    quadrature; the positive correlation of neighbouring estimates is ignored,
    which makes ``slope_err`` conservative.

    Deviation slopes (design tip table; numerics.md §5.1):

    ======  =====  =====  =====  =====  =====  =====  =====
    stat    WPM    FPM    WFM    FFM    RWFM   FWFM   RRFM
    ======  =====  =====  =====  =====  =====  =====  =====
    ADEV    −1     −1     −1/2   0      +1/2   +1     +3/2
    MDEV    −3/2   −1     −1/2   0      +1/2   +1     +3/2
    TDEV    −1/2   0      +1/2   +1     +3/2   +2     +5/2
    HDEV    −1     −1     −1/2   0      +1/2   +1     +3/2
    ======  =====  =====  =====  =====  =====  =====  =====

    The same rows serve OADEV (ADEV) and OHDEV (HDEV). Each slope is assigned
    to the nearest tabulated value. AVAR and MVAR do not converge for FWFM and
    RRFM: there the slopes are those of a finite record (as in the tip's
    table), and the Hadamard family should be used. ADEV/HDEV cannot separate
    WPM from FPM (use MDEV or TDEV); FPM's ADEV slope is also only close to −1
    (its logarithmic factor makes it about −0.9).

    References
    ----------
    ST DT0064 (A. Vitali, 2016), noise identification table; W. J. Riley,
    NIST SP 1065 (2008) §5.6; numerics.md §5.1.
    """
    if not isinstance(result, StabilityResult):
        raise ParameterError(f"result must be a StabilityResult, got {type(result).__name__}")
    table = _SLOPE_TABLES.get(result.statistic)
    if table is None:
        raise ParameterError(
            f"result.statistic={result.statistic!r} has no slope table; supported: {sorted(_SLOPE_TABLES)}"
        )
    if len(result) < 2:
        raise DataError(f"local slopes need at least 2 τ values, got {len(result)}")
    dev = np.asarray(result.dev, dtype=float)
    taus = np.asarray(result.taus, dtype=float)
    if np.any(dev <= 0) or np.any(np.diff(taus) <= 0):
        raise DataError("local slopes need positive deviations at strictly increasing τ")
    if result.edf is not None:
        sig = 1.0 / np.sqrt(2.0 * np.asarray(result.edf, dtype=float))
    else:
        sig = 1.0 / np.sqrt(_independent_terms(result))
    dlt = np.diff(np.log(taus))
    slope = np.diff(np.log(dev)) / dlt
    err = np.sqrt(sig[:-1] ** 2 + sig[1:] ** 2) / dlt
    nominal_slopes = np.array([s for s, _ in table])
    bounds = 0.5 * (nominal_slopes[:-1] + nominal_slopes[1:])
    idx = np.searchsorted(bounds, slope)
    cands = [table[i][1] for i in idx]
    alpha = np.array([1 if len(c) > 1 else c[0] for c in cands], dtype=np.int64)
    ambiguous = np.array([len(c) > 1 for c in cands], dtype=bool)
    return LocalSlopes(statistic=result.statistic, taus=np.sqrt(taus[:-1] * taus[1:]), slope=slope,
                       slope_err=err, nominal=nominal_slopes[idx], alpha=alpha, ambiguous=ambiguous)


# ----------------------------------------------------------- power-law fit (§6.3)

_FIT_FAMILY = {"adev": "avar", "oadev": "avar", "mdev": "mvar", "tdev": "tvar", "hdev": "hvar", "ohdev": "hvar"}
_FIT_ALPHAS = {"avar": (2, 1, 0, -1, -2), "mvar": (2, 1, 0, -1, -2), "tvar": (2, 1, 0, -1, -2),
               "hvar": (2, 1, 0, -1, -2, -3, -4)}


def _response(kind: str, alpha: int, tau: np.ndarray, rate: float) -> np.ndarray:
    """Variance produced by S_y = 1·f^α (unit h_α); continuous model, f_h = rate/2."""
    try:
        return response(kind, alpha, tau, rate, sampled=True)
    except KeyError:
        allowed = sorted(_FIT_ALPHAS[kind])
        raise ParameterError(f"alpha={alpha!r} is not supported by this statistic; allowed: {allowed}") from None


def power_law_variance(
    statistic: str,
    alpha: int,
    taus: Union[float, np.ndarray],
    *,
    rate: float = 1.0,
    h: float = 1.0,
) -> np.ndarray:
    """Expected variance of a statistic for one power-law noise ``S_y = h f^α``.

    Parameters
    ----------
    statistic : {"adev", "oadev", "mdev", "tdev", "hdev", "ohdev"}
        Statistic whose variance is wanted (overlapped and non-overlapped forms
        share their expectation).
    alpha : int
        Noise exponent: 2 … −2 (AVAR, MVAR, TVAR), 2 … −4 (HVAR).
    taus : float or array_like
        Averaging times in seconds.
    rate : float
        Sample rate; the WPM and FPM terms use the cut-off ``f_h = rate/2``.
    h : float
        Noise level ``h_α``.

    Returns
    -------
    numpy.ndarray
        σ²(τ) (for TDEV, the time variance TVAR = τ²/3·MVAR, in phase units²).

    Notes
    -----
    Continuous model with a sharp cut-off f_h (numerics.md §6.3), e.g.
    AVAR: WPM ``3 f_h h₂/(4π²τ²)``, FPM ``h₁[3γ − ln 2 + 3 ln(2πf_hτ)]/(4π²τ²)``,
    WFM ``h₀/(2τ)``, FFM ``2 ln 2·h₋₁``, RWFM ``(2π²/3) h₋₂ τ``;
    MVAR: ``3 f_h τ0 h₂/(4π²τ³)``, ``3 ln(256/27) h₁/(8π²τ²)``,
    ``h₀/(4τ)·(1 + 1/m²)``, ``[(27/8) ln 3 − 4 ln 2] h₋₁``, ``(11π²/20) h₋₂ τ``;
    HVAR: ``5 f_h h₂/(6π²τ²)``, ``h₁[10γ − 6 ln 2 + ln 3 + 10 ln(2πf_hτ)]/(12π²τ²)``,
    ``h₀/(2τ)``, ``[4 ln 2 − (3/2) ln 3] h₋₁``, ``(π²/3) h₋₂ τ``,
    ``(π²/6)(27 ln 3 − 32 ln 2) h₋₃ τ²``, ``(11π⁴/15) h₋₄ τ³``.
    The MVAR WPM term and the factor ``(1 + 1/m²)`` of its WFM term are exact
    for sampled data (the published ``h₀/(4τ)`` is their large-m limit).
    The other MVAR terms are large-m limits; FPM, FFM and RWFM also differ by a
    few per cent from the continuous model at m ≲ 4 (numerics.md §6.1).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2, Table 9 (AVAR/MVAR in terms of h_α);
    numerics.md §6.3.

    Examples
    --------
    >>> from sigmatau.noiseid import power_law_variance
    >>> float(power_law_variance("oadev", 0, 10.0, h=2.0))    # h0/(2τ)
    0.1
    """
    kind = _FIT_FAMILY.get(statistic)
    if kind is None:
        raise ParameterError(f"statistic={statistic!r} must be one of {sorted(_FIT_FAMILY)}")
    rate_f = check_rate(rate)
    t = np.asarray(taus, dtype=float)
    if np.any(t <= 0) or not np.all(np.isfinite(t)):
        raise ParameterError("taus must be positive and finite")
    return h * _response(kind, int(alpha), t, rate_f)


@dataclass(frozen=True, repr=False, eq=False)
class PowerLawFit:
    """Sum of power-law asymptotes fitted to a variance curve (see :func:`fit_power_law`).

    Attributes
    ----------
    statistic : str
        Statistic the curve was computed with.
    rate : float
        Sample rate of the data (f_h = rate/2 for the WPM/FPM terms).
    h, h_err : dict of int to float
        Fitted level ``h_α`` of each kept term (S_y = Σ h_α f^α) and its
        standard uncertainty.
    kept, dropped : tuple of int
        Exponents kept and dropped (zero or not significant).
    chi2 : float
        Weighted residual sum of squares of the final fit.
    dof : int
        Number of τ used minus number of kept terms.
    taus : numpy.ndarray
        τ values used in the fit.
    """

    statistic: str
    rate: float
    h: Mapping[int, float]
    h_err: Mapping[int, float]
    kept: tuple[int, ...]
    dropped: tuple[int, ...]
    chi2: float
    dof: int
    taus: np.ndarray = field(default_factory=lambda: np.empty(0))

    def term(self, alpha: int, taus: Union[float, np.ndarray]) -> np.ndarray:
        """Variance contributed by the term α at ``taus`` (0 for a dropped term)."""
        t = np.asarray(taus, dtype=float)
        if alpha not in self.h:
            return np.zeros(t.shape)
        return power_law_variance(self.statistic, alpha, t, rate=self.rate, h=self.h[alpha])

    def terms(self, taus: Union[float, np.ndarray]) -> dict[int, np.ndarray]:
        """Each kept term's variance at ``taus``."""
        return {a: self.term(a, taus) for a in self.kept}

    def variance(self, taus: Union[float, np.ndarray]) -> np.ndarray:
        """The fitted variance curve at ``taus``."""
        t = np.asarray(taus, dtype=float)
        return sum((self.term(a, t) for a in self.kept), np.zeros(t.shape))

    def deviation(self, taus: Union[float, np.ndarray]) -> np.ndarray:
        """The fitted deviation curve ``sqrt(variance)`` at ``taus``."""
        return np.sqrt(self.variance(taus))

    def __repr__(self) -> str:
        terms = ", ".join(f"{NOISE_NAMES[a]} h{a}={self.h[a]:.4g}±{self.h_err[a]:.2g}" for a in self.kept)
        return f"PowerLawFit({self.statistic}: {terms}; chi2/dof={self.chi2:.3g}/{self.dof})"


def _weighted_nnls(design: np.ndarray, var: np.ndarray, nu: np.ndarray, iterations: int):
    """IRLS non-negative fit; weights from the model variance, var(σ²) ≈ 2σ⁴/ν.

    Returns the coefficients, the per-τ standard errors used as weights and the
    weighted χ².
    """
    from scipy.optimize import nnls  # imported here: keeps `import sigmatau` light

    rel = np.sqrt(2.0 / nu)
    sigma = var * rel
    for it in range(iterations + 1):
        a = design / sigma[:, None]
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0] = 1.0
        hs, _ = nnls(a / scale, var / sigma)
        h = hs / scale
        model = design @ h
        if it < iterations:
            sigma = np.where(model > 0, model, var) * rel
    resid = (var - model) / sigma
    return h, sigma, float(np.einsum("i,i->", resid, resid))


#: Correlation of variance estimates one octave apart, by the dominant noise
#: (exponent counted from the statistic's convergence edge: α for the Allan
#: family, α + 2 for the Hadamard family). Monte-Carlo values for octave grids
#: (OADEV, ADEV, MDEV, OHDEV, N = 4096, 300 runs): ≈ 0.3–0.6 white, 0.6–0.7
#: flicker, 0.8–0.9 random walk.
OCTAVE_CORRELATION = {0: 0.5, -1: 0.7, -2: 0.88}


def _tau_correlation(taus: np.ndarray, dominant: np.ndarray) -> np.ndarray:
    """AR(1)-in-log2(τ) correlation matrix of the variance estimates."""
    rho_pt = np.array([OCTAVE_CORRELATION[max(-2, min(0, int(k)))] for k in dominant])
    octaves = np.diff(np.log2(taus))
    step = np.maximum(np.maximum(rho_pt[:-1], rho_pt[1:]) ** octaves, 1e-300)  # conservative end
    logc = np.concatenate(([0.0], np.cumsum(np.log(step))))
    return np.exp(-np.abs(logc[:, None] - logc[None, :]))


def fit_power_law(
    result: StabilityResult,
    *,
    alphas: Optional[Sequence[int]] = None,
    edf: Optional[Union[float, np.ndarray]] = None,
    min_significance: float = 2.0,
    tau_correlation: bool = True,
) -> PowerLawFit:
    """Fit the whole variance curve with non-negative power-law terms.

    Parameters
    ----------
    result : StabilityResult
        ADEV, OADEV, MDEV, TDEV, HDEV or OHDEV curve.
    alphas : sequence of int, optional
        Candidate exponents; default every one the statistic supports
        (2 … −2, and down to −4 for HDEV/OHDEV).
    edf : float or array_like, optional
        Equivalent degrees of freedom per τ; default ``result.edf`` or, without
        it, the number of non-overlapping terms ``min(n, ⌊(N−1)/m⌋)``.
    min_significance : float
        A term is kept only if ``h_α/σ(h_α)`` reaches this value.
    tau_correlation : bool
        Account for the correlation between the variance estimates at
        neighbouring τ in the uncertainties (see Notes). Off, the
        uncertainties of the long-τ terms are too small by a factor ≈ 2.

    Returns
    -------
    PowerLawFit

    Notes
    -----
    Model: ``σ²(τ) = Σ_α h_α R_α(τ)``, ``h_α ≥ 0``, with ``R_α`` the response
    of the statistic to ``S_y = f^α`` (:func:`power_law_variance`;
    f_h = rate/2 for WPM and FPM). Each τ is weighted by the standard error of
    its variance, ``σ²·√(2/ν)`` — taken from the fitted model, not the noisy
    observation, in three reweighting passes (an observation's own value would
    favour low points). The weighted system is solved by
    :func:`scipy.optimize.nnls` on scaled columns.

    Uncertainties: the estimates at neighbouring τ are strongly correlated
    (they share the slow part of the record), so the covariance of the
    coefficients is the sandwich ``B AᵀW C W A B``, ``B = (AᵀWA)⁻¹``, with
    ``C = D R D``, D the per-τ standard errors and R an AR(1) correlation in
    log₂τ whose one-octave value depends on the term dominating at that τ:
    0.5 for white, 0.7 for flicker and 0.88 for random-walk noise (counted
    from the statistic's convergence edge: FWFM and RRFM play FFM's and
    RWFM's parts for the Hadamard family). Those are Monte-Carlo values of the
    correlation of octave-spaced OADEV, ADEV, MDEV and OHDEV estimates; with
    them the z-scores of fitted levels have unit spread within about ±30 %
    (tests/test_noiseid.py). The result is multiplied by ``χ²/dof`` when that
    exceeds 1. Term selection is backward: terms at zero are dropped, then the
    least significant term while its ``h/σ(h)`` is below ``min_significance``,
    refitting each time.

    On ADEV/HDEV the WPM and FPM responses differ only by a logarithm, so
    their split is weak; fit MDEV or TDEV to separate them, or pass
    ``alphas`` without one of them.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2 and Table 9; numerics.md §6.3;
    C. L. Lawson and R. J. Hanson, *Solving Least Squares Problems* (1974), NNLS.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau.noiseid import fit_power_law
    >>> y = np.random.default_rng(3).standard_normal(20_000)   # WFM, h0 = 2
    >>> fit = fit_power_law(sigmatau.oadev(y))
    >>> fit.kept, round(fit.h[0], 1)
    ((0,), 2.0)
    """
    if not isinstance(result, StabilityResult):
        raise ParameterError(f"result must be a StabilityResult, got {type(result).__name__}")
    kind = _FIT_FAMILY.get(result.statistic)
    if kind is None:
        raise ParameterError(f"result.statistic={result.statistic!r} must be one of {sorted(_FIT_FAMILY)}")
    supported = _FIT_ALPHAS[kind]
    if alphas is None:
        cand = list(supported)
    else:
        cand = []
        for a in alphas:
            if isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer)) or int(a) not in supported:
                raise ParameterError(f"alphas contains {a!r}; {result.statistic} supports {list(supported)}")
            if int(a) not in cand:
                cand.append(int(a))
        if not cand:
            raise ParameterError("alphas must name at least one exponent")
    if min_significance < 0:
        raise ParameterError(f"min_significance={min_significance!r} must be non-negative")

    taus = np.asarray(result.taus, dtype=float)
    var = np.asarray(result.var, dtype=float)
    if edf is not None:
        nu = np.broadcast_to(np.asarray(edf, dtype=float), taus.shape).copy()
    elif result.edf is not None:
        nu = np.asarray(result.edf, dtype=float).copy()
    else:
        nu = _independent_terms(result)
    ok = (var > 0) & np.isfinite(var) & (nu > 0) & np.isfinite(nu)
    taus, var, nu = taus[ok], var[ok], nu[ok]
    if taus.size < 2:
        raise DataError(f"fit_power_law needs at least 2 τ with a positive variance, got {taus.size}")

    columns = {a: _response(kind, a, taus, result.rate) for a in cand}
    shift = 2 if kind == "hvar" else 0
    terms = list(cand)
    dropped: list[int] = []
    while True:
        design = np.column_stack([columns[a] for a in terms])
        h, sigma, chi2 = _weighted_nnls(design, var, nu, iterations=3)
        pos = h > 0
        if not pos.any():
            raise DataError("no power-law term fits this curve")
        if not pos.all():
            dropped += [a for a, p in zip(terms, pos) if not p]
            terms = [a for a, p in zip(terms, pos) if p]
            continue
        dof = int(taus.size - len(terms))
        aw = design / sigma[:, None]
        bread = np.linalg.pinv(aw.T @ aw)
        if tau_correlation:
            dominant = np.array(terms)[np.argmax(design * h, axis=1)] + shift
            corr = _tau_correlation(taus, dominant)
            cov = bread @ (aw.T @ corr @ aw) @ bread
        else:
            cov = bread
        if dof > 0:
            cov *= max(1.0, chi2 / dof)
        err = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        with np.errstate(divide="ignore"):
            z = np.where(err > 0, h / err, np.inf)
        worst = int(np.argmin(z))
        if z[worst] < min_significance and len(terms) > 1:
            dropped.append(terms.pop(worst))
            continue
        break
    order = sorted(range(len(terms)), key=lambda i: -terms[i])
    kept = tuple(terms[i] for i in order)
    return PowerLawFit(
        statistic=result.statistic,
        rate=float(result.rate),
        h={terms[i]: float(h[i]) for i in order},
        h_err={terms[i]: float(err[i]) for i in order},
        kept=kept,
        dropped=tuple(sorted(dropped, reverse=True)),
        chi2=chi2,
        dof=dof,
        taus=taus,
    )
