"""Noise identification for few averages: Barnes' B1 ratio (§5.3) and R(n) = MVAR/AVAR (§5.4).

Public through :mod:`sigmatau.uncertainty.noiseid` (and :mod:`sigmatau.noiseid`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional, Union

import numpy as np

from ..core.driver import compute
from ..core.kernels import MVAR, OAVAR
from ..core.numeric import block_means
from ..core.powerlaw import EULER_GAMMA as _EULER_GAMMA
from ..core.shared import memoized
from ..core.taus import long_factors_expected
from ..core.validate import as_series, check_data_type
from ..errors import DataError, ParameterError
from .noisebase import InsufficientDataError, _check_count, _check_m, _frequency



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
    series = as_series(data, gaps=True)
    m = _check_m(m)
    return b1_observed(_frequency(series, dtype), m)[0]


def b1_observed(y: np.ndarray, m: int) -> tuple[float, int]:
    """Observed B1 ratio of frequency samples ``y`` at ``m`` and the number of averages ``Nb``."""
    means = block_means(y, m)
    if np.isnan(means).any():
        return _b1_observed_gaps(means, m)
    nb = int(means.size)
    if nb < 2:
        raise InsufficientDataError(f"the B1 ratio needs at least 2 averages at m={m}, got {nb}")
    s2 = float(means.var(ddof=1))
    dif = np.diff(means)
    avar = float(np.einsum("i,i->", dif, dif)) / (2.0 * (nb - 1))
    if avar == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; the B1 ratio is undefined")
    return s2 / avar, nb


def _b1_observed_gaps(means: np.ndarray, m: int) -> tuple[float, int]:
    """B1 from block means some of which are missing (NaN: the block holds a gap): the
    variance of the means present over the Allan variance of the neighbouring pairs present."""
    ok = means[~np.isnan(means)]
    dif = np.diff(means)
    dif = dif[~np.isnan(dif)]
    nb = int(ok.size)
    if nb < 2 or dif.size == 0:
        raise InsufficientDataError(f"the B1 ratio needs at least 2 averages (and a pair of neighbours) at m={m},"
                                    f" got {nb} outside the gaps")
    avar = float(np.dot(dif, dif)) / (2.0 * dif.size)
    if avar == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; the B1 ratio is undefined")
    return float(ok.var(ddof=1)) / avar, nb


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
    series = as_series(data, gaps=True)
    m = _check_m(m)
    if n_expected is not None:
        n_expected = _check_count(n_expected, "n_expected")
    y = _frequency(series, dtype)
    ratio, nb = b1_observed(y, m)
    if nb < 3:
        raise InsufficientDataError(f"B1 noise identification needs at least 3 averages at m={m}, got {nb}")
    mu, mu_hat = b1_classify(ratio, nb, n_expected)
    if hadamard and mu >= 1:
        mu, mu_hat, ratio, nb = _hadamard_pass(y, m, n_expected, (mu, mu_hat, ratio, nb))
    alpha = 1 if mu == -2 else -mu - 1
    return B1Result(alpha=alpha, alpha_estimate=-mu_hat - 1.0, mu=mu, ratio=ratio, nb=nb,
                    ambiguous=(mu == -2), m=m)



def _hadamard_pass(y: np.ndarray, m: int, n_expected: Optional[int],
                   first: tuple[int, float, float, int]) -> tuple[int, float, float, int]:
    """Second B1 pass of :func:`b1_noise_id`'s Hadamard mode, on the differences of ``y``.

    Returns ``(μ, μ̂, ratio, Nb)``: shifted by 2 and held to [1, 3] when the
    second pass has at least 3 averages, else ``first`` unchanged.
    """
    try:
        ratio2, nb2 = b1_observed(np.diff(y), m)
    except (InsufficientDataError, DataError):
        return first
    if nb2 < 3:
        return first
    mu2, mu2_hat = b1_classify(ratio2, nb2, n_expected)
    return min(max(mu2 + 2, 1), 3), min(max(mu2_hat + 2.0, 1.0), 3.0), ratio2, nb2

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


def _rn_variances(series: np.ndarray, dtype: str, m: int) -> tuple[float, float]:
    """MVAR and OAVAR of validated ``series`` at m (the two halves of R(n))."""
    with long_factors_expected():  # long-τ factors are the point here
        mv = compute(MVAR, series, rate=1.0, data_type=dtype, taus="octave", m=[m])[0].var[0]
        av = compute(OAVAR, series, rate=1.0, data_type=dtype, taus="octave", m=[m])[0].var[0]
    return float(mv), float(av)


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
    series = as_series(data, gaps=True)
    m = _check_m(m)
    npts = series.size if dtype == "phase" else series.size + 1
    if npts < 3 * m:
        raise InsufficientDataError(f"R(n) needs at least {3 * m} phase points at m={m}, got {npts}")
    # Each statistic of a record identifies its noise with the same rules: inside a shared_record
    # scope the pair is computed once per m (two record passes per octave of m saved per statistic).
    mv, av = memoized(series, ("rn-ratio", dtype, m), lambda: _rn_variances(series, dtype, m))
    if av == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; R(n) is undefined")
    return float(mv / av)
