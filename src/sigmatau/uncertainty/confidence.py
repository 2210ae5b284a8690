"""Equivalent degrees of freedom (EDF) and χ² confidence intervals.

A variance estimate ``s²`` with ν equivalent degrees of freedom is modelled as
``ν s²/σ² ~ χ²_ν``; the interval on the true variance follows from two χ²
quantiles, and deviation bounds are their square roots (numerics.md §2.1).
This module holds the EDF rules and the interval arithmetic; it depends on
numpy and scipy only and knows nothing about the estimators themselves.

EDF rules by statistic (numerics.md §2):

* ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev``, ``ohdev`` (and the
  modified Hadamard ``mhdev``): the Greenhall–Riley combined algorithm,
  :func:`greenhall_edf`.
* ``totdev``, ``mtotdev``, ``ttotdev``, ``htotdev``, ``theo1``, ``theobr``,
  ``theoh``: the empirical formulas of SP1065 and Howe et al.
* ``stdev``: ``K − 1`` independent averages (white FM only).

All EDFs take ``N``, the number of **phase** points (frequency samples + 1).
"""

from __future__ import annotations

import functools
import math
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import chdtri

from ..errors import ParameterError

__all__ = [
    "ONE_SIGMA",
    "ConfidenceInterval",
    "EDF_STATISTICS",
    "greenhall_edf",
    "edf",
    "edf_array",
    "edf_reason",
    "edf_oadev_simple",
    "simple_error",
    "chi2_interval",
    "deviation_interval",
]

#: Two-sided coverage of ±1 standard deviation of a normal law, erf(1/√2).
ONE_SIGMA: float = math.erf(1.0 / math.sqrt(2.0))

Version = Literal["full", "simplified"]
Sided = Literal["two", "upper", "lower"]


class ConfidenceInterval(NamedTuple):
    """Lower and upper confidence bounds (scalars or arrays).

    A named tuple, as in :mod:`scipy.stats`: it unpacks as ``low, high`` and is
    immutable.
    """

    low: float | np.ndarray
    high: float | np.ndarray


# --- Greenhall & Riley (PTTI 2003) -------------------------------------------------------

_JMAX = 100

# Table 1: modified variances (F = 1), (a0, a1) by (alpha, d).
_TABLE1 = {
    (2, 1): (2.0 / 3.0, 1.0 / 3.0), (2, 2): (7.0 / 9.0, 0.5), (2, 3): (22.0 / 25.0, 2.0 / 3.0),
    (1, 1): (0.840, 0.345), (1, 2): (0.997, 0.616), (1, 3): (1.141, 0.843),
    (0, 1): (1.079, 0.368), (0, 2): (1.033, 0.607), (0, 3): (1.184, 0.848),
    (-1, 2): (1.048, 0.534), (-1, 3): (1.180, 0.816),
    (-2, 2): (1.302, 0.535), (-2, 3): (1.175, 0.777),
    (-3, 3): (1.194, 0.703),
    (-4, 3): (1.489, 0.702),
}

# Table 2: unmodified variances (F = m), (a0, a1) by (alpha, d). The alpha = 2 row is
# C(4d, 2d)/C(2d, d)² and d/2 (Case 4).
_TABLE2 = {
    (2, 1): (1.5, 0.5), (2, 2): (35.0 / 18.0, 1.0), (2, 3): (231.0 / 100.0, 1.5),
    (1, 1): (78.6, 25.2), (1, 2): (790.0, 410.0), (1, 3): (9950.0, 6520.0),
    (0, 1): (2.0 / 3.0, 1.0 / 6.0), (0, 2): (2.0 / 3.0, 1.0 / 3.0), (0, 3): (7.0 / 9.0, 0.5),
    (-1, 2): (0.852, 0.375), (-1, 3): (0.997, 0.617),
    (-2, 2): (1.079, 0.368), (-2, 3): (1.033, 0.607),
    (-3, 3): (1.053, 0.553),
    (-4, 3): (1.302, 0.535),
}

# Table 3: FPM (alpha = 1) log denominator (b0, b1) by d.
_TABLE3 = {1: (6.0, 4.0), 2: (15.23, 12.0), 3: (47.8, 40.0)}

# (d, F is modified, S is overlapped) for each finite-difference statistic.
_GREENHALL_STATS = {
    "adev": (2, False, False),
    "oadev": (2, False, True),
    "mdev": (2, True, True),
    "tdev": (2, True, True),
    "hdev": (3, False, False),
    "ohdev": (3, False, True),
    "mhdev": (3, True, True),
}


def _sw_sign(alpha: int) -> float:
    return -1.0 if alpha in (2, -1, -2) else 1.0


def _sw(t: np.ndarray, alpha: int) -> np.ndarray:
    """Greenhall's generalised autocovariance sw(t, α), with 0·ln 0 := 0.

    α = 2 … −4: −|t|, t² ln|t|, |t|³, −t⁴ ln|t|, −|t|⁵, t⁶ ln|t|, |t|⁷.
    """
    a = np.abs(t)
    power = a ** (3 - alpha)
    if alpha % 2 == 0:
        return _sw_sign(alpha) * power
    loga = np.log(np.where(a > 0.0, a, 1.0))
    return _sw_sign(alpha) * power * loga


_SERIES_U = 0.1  # below this u = h/|t|, the log part of sx uses its Taylor series
_SERIES_ORDER = 24


def _log_even_coefficients(k: int) -> list[float]:
    """Coefficients e_p (p = 2, 4, …) of (1−u)^k ln(1−u) + (1+u)^k ln(1+u) = Σ e_p u^p."""
    out = []
    for p in range(2, _SERIES_ORDER + 1, 2):
        c = sum(math.comb(k, i) * (-1) ** (p - i + 1) / (p - i) for i in range(min(k, p - 1) + 1))
        out.append(2.0 * c)
    return out


_LOG_COEFFS = {k: _log_even_coefficients(k) for k in (2, 4, 6)}


def _sx(t: np.ndarray, F: float, alpha: int) -> np.ndarray:
    """sx(t, F, α) = F²[2sw(t) − sw(t − 1/F) − sw(t + 1/F)], or sw(t, α+2) for F = ∞.

    For |t| ≥ 1/F the second difference is expanded analytically (binomial sums
    and a Taylor series of the log part), because evaluating it as written
    loses about F² ulps: at m = 10⁷ the EDF would have no correct digit.
    """
    t = np.asarray(t, dtype=float)
    if math.isinf(F):
        return _sw(t, alpha + 2)
    h = 1.0 / F
    a = np.abs(t)
    out = np.empty_like(a)
    near = a < h
    if near.any():
        an = a[near]
        out[near] = 2.0 * _sw(an, alpha) - _sw(an - h, alpha) - _sw(an + h, alpha)
    far = ~near
    if far.any():
        af = a[far]
        k = 3 - alpha
        # 2a^k − (a−h)^k − (a+h)^k, valid for a ≥ h (and for every a when k is even)
        poly = np.zeros_like(af)
        for i in range(1, k // 2 + 1):
            poly -= 2.0 * math.comb(k, 2 * i) * af ** (k - 2 * i) * h ** (2 * i)
        if alpha % 2 == 0:
            second = poly
        else:
            u = h / af
            small = u <= _SERIES_U
            logpart = np.empty_like(af)
            us = u[small]
            acc = np.zeros_like(us)
            for e in reversed(_LOG_COEFFS[k]):
                acc = (acc + e) * us * us
            logpart[small] = acc
            ub = u[~small]
            lm = np.where(ub != 1.0, np.log(np.abs(np.where(ub != 1.0, 1.0 - ub, 1.0))), 0.0)
            logpart[~small] = (1.0 - ub) ** k * lm + (1.0 + ub) ** k * np.log1p(ub)
            second = np.log(af) * poly - af ** k * logpart
        out[far] = _sw_sign(alpha) * second
    return F * F * out


def _sz(t: np.ndarray | float, F: float, alpha: int, d: int) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    out = math.comb(2 * d, d) * _sx(t, F, alpha)
    for k in range(1, d + 1):
        out = out + (-1) ** k * math.comb(2 * d, d + k) * (_sx(t - k, F, alpha) + _sx(t + k, F, alpha))
    return out


_CHUNK = 1 << 16


def _basic_sum(J: int, M: float, S: float, F: float, alpha: int, d: int) -> float:
    inner = 0.0
    for start in range(1, J, _CHUNK):  # chunks bound the memory of the simplified version
        j = np.arange(start, min(start + _CHUNK, J), dtype=float)
        inner += float(np.sum((1.0 - j / M) * _sz(j / S, F, alpha, d) ** 2))
    return float(_sz(0.0, F, alpha, d) ** 2 + (1.0 - J / M) * _sz(J / S, F, alpha, d) ** 2 + 2.0 * inner)


def _greenhall_inverse(alpha: int, d: int, m: int, modified: bool, overlapped: bool, N: int,
                       version: str) -> tuple[float, str]:
    """1/ν of the Greenhall–Riley algorithm, or (nan, reason)."""
    F = 1 if modified else m
    S = m if overlapped else 1
    L = m * (d + 1) if modified else 1 + m * d  # L = m/F + m·d
    if N < L:
        return math.nan, f"N={N} phase points is fewer than the filter length L={L}"
    M = 1 + (S * (N - L)) // m
    J = min(M, (d + 1) * S)
    r = M / S
    sz0 = float(_sz(0.0, F, alpha, d))
    if version == "simplified":
        return _basic_sum(J, M, S, F, alpha, d) / (M * sz0 * sz0), ""
    if F == 1:  # Case 1: modified, or unmodified with m = 1
        if J <= _JMAX:
            return _basic_sum(J, M, S, 1, alpha, d) / (M * sz0 * sz0), ""
        if r >= d + 1:
            a0, a1 = _TABLE1[(alpha, d)]
            return (a0 - a1 / r) / r, ""
        mp = _JMAX / r
        return _basic_sum(_JMAX, _JMAX, mp, 1, alpha, d) / (_JMAX * sz0 * sz0), ""
    if alpha <= 0:  # Case 2
        if J <= _JMAX:
            Fp = float(m) if m * (d + 1) <= _JMAX else math.inf
            szp = float(_sz(0.0, Fp, alpha, d))
            return _basic_sum(J, M, S, Fp, alpha, d) / (M * szp * szp), ""
        if r >= d + 1:
            a0, a1 = _TABLE2[(alpha, d)]
            return (a0 - a1 / r) / r, ""
        mp = _JMAX / r
        szi = float(_sz(0.0, math.inf, alpha, d))
        return _basic_sum(_JMAX, _JMAX, mp, math.inf, alpha, d) / (_JMAX * szi * szi), ""
    if alpha == 1:  # Case 3
        if J <= _JMAX:
            return _basic_sum(J, M, S, m, 1, d) / (M * sz0 * sz0), ""
        b0, b1 = _TABLE3[d]
        den = (b0 + b1 * math.log(m)) ** 2
        if r >= d + 1:
            a0, a1 = _TABLE2[(1, d)]
            return (a0 - a1 / r) / (r * den), ""
        mp = _JMAX / r
        return _basic_sum(_JMAX, _JMAX, mp, mp, 1, d) / (_JMAX * den), ""
    # Case 4: alpha = 2
    K = math.ceil(r)
    if K <= d:
        c = math.comb(2 * d, d)
        acc = sum((1.0 - k / r) * math.comb(2 * d, d - k) ** 2 for k in range(1, K))
        return (1.0 + 2.0 * acc / (c * c)) / M, ""
    a0, a1 = _TABLE2[(2, d)]
    return (a0 - a1 / r) / M, ""


def _check_int(value: object, name: str, minimum: int) -> int:
    try:
        as_float = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}") from None
    if not as_float.is_integer() or as_float < minimum:
        raise ParameterError(f"{name}={value!r} must be an integer >= {minimum}")
    return int(as_float)


def _check_version(version: object) -> str:
    if version not in ("full", "simplified"):
        raise ParameterError(f"version={version!r} must be 'full' or 'simplified'")
    return str(version)


def greenhall_edf(alpha: int, d: int, m: int, F: int, S: int, N: int, *,
                  version: Version = "full") -> float:
    r"""Greenhall–Riley equivalent degrees of freedom of a finite-difference variance.

    Parameters
    ----------
    alpha : int
        Power-law exponent of the dominant noise, ``S_y(f) ∝ f^α``, in −4 … 2.
        Must satisfy ``α + 2d > 1`` (the variance converges).
    d : {1, 2, 3}
        Order of the phase difference: 2 for the Allan family, 3 for Hadamard.
    m : int
        Averaging factor, ``τ = m·τ0``.
    F : int
        Filter factor: ``1`` for a modified variance, ``m`` for an unmodified one.
    S : int
        Stride factor: ``1`` non-overlapped, ``m`` overlapped.
    N : int
        Number of phase points.
    version : {"full", "simplified"}
        ``"full"`` is the four-case algorithm with the asymptotic Tables 1–3 (what
        Stable32 uses); ``"simplified"`` always evaluates the basic sum.

    Returns
    -------
    float
        ν, or NaN when ``N`` is shorter than the filter length ``L = m/F + m·d``
        (see :func:`edf_reason`).

    Raises
    ------
    ParameterError
        For α outside −4 … 2, ``α + 2d ≤ 1``, d outside 1 … 3, F or S not in
        ``{1, m}``, or a non-integer / non-positive m or N.

    Notes
    -----
    With ``sw(t, α)`` = −|t|, t² ln|t|, |t|³, −t⁴ ln|t|, −|t|⁵, t⁶ ln|t|, |t|⁷
    for α = 2 … −4,

    .. math::

        s_x(t) = F^2\,[2 s_w(t) - s_w(t - 1/F) - s_w(t + 1/F)],\qquad
        s_x(t)|_{F=\infty} = s_w(t, α + 2),

        s_z(t) = \sum_{k=-d}^{d} (-1)^k \binom{2d}{d+k} s_x(t + k),

        \mathrm{BasicSum}(J, M, S) = s_z^2(0) + \Bigl(1 - \frac{J}{M}\Bigr) s_z^2(J/S)
            + 2\sum_{j=1}^{J-1}\Bigl(1 - \frac{j}{M}\Bigr) s_z^2(j/S),

    ``M = 1 + ⌊S(N − L)/m⌋`` summands, ``J = min(M, (d+1)S)``, ``r = M/S``.
    The simplified EDF is ``1/ν = BasicSum(J, M, S)/(M s_z²(0))``. The full
    version keeps it while ``J ≤ 100``; beyond, it uses ``1/ν = (a0 − a1/r)/r``
    (Tables 1, 2; for FPM divided by ``(b0 + b1 ln m)²``, Table 3) when
    ``r ≥ d + 1`` and a rescaled basic sum with ``J = M = 100`` otherwise; the
    unmodified filter is replaced by its ``F = ∞`` limit when ``m(d+1) > 100``;
    white PM unmodified has the closed form of Case 4. The boundary ``r = d + 1``
    is given to the table branch (``r ≥ d + 1``; the paper's wording is not
    available to us, and the two branches differ by ≤ 3 % there).

    Numerics: for finite F the second difference in ``s_x`` is expanded
    analytically, since evaluating it as written loses ~F² ulps (no correct
    digit at m = 10⁷). The simplified version sums ``(d+1)·m`` terms when
    overlapped, so its cost grows linearly with m (about 1 s per 10⁶).

    The model assumes phase samples that are τ0-averages of a continuous
    power-law process; at m = 1 … 4 it can differ from point-sampled simulated
    noise by up to ~25 % (numerics.md §2.3, §8 item 4).

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based
    on finite differences", Proc. 35th PTTI, 2003, pp. 267–278 (eqs. 7–10,
    Tables 1–3). W. J. Riley, NIST SP 1065 (2008), §5.3.

    Examples
    --------
    >>> round(greenhall_edf(0, 2, 10, 10, 10, 1001), 3)   # OAVAR, white FM
    135.071
    """
    alpha = _check_alpha(alpha)
    d = _check_int(d, "d", 1)
    if d > 3:
        raise ParameterError(f"d={d} must be 1, 2 or 3")
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    F = _check_int(F, "F", 1)
    S = _check_int(S, "S", 1)
    if F not in (1, m):
        raise ParameterError(f"F={F} must be 1 (modified) or m={m} (unmodified)")
    if S not in (1, m):
        raise ParameterError(f"S={S} must be 1 (non-overlapped) or m={m} (overlapped)")
    if alpha + 2 * d <= 1:
        raise ParameterError(f"alpha={alpha} with d={d}: the variance diverges (needs alpha + 2d > 1)")
    version = _check_version(version)
    inv, _ = _greenhall_inverse(alpha, d, m, F == 1, S == m, N, version)
    return 1.0 / inv


# --- empirical EDF formulas --------------------------------------------------------------

# nu = b·N/m − c (SP1065 Table 7 TOTVAR, Table 8 MTOT/TTOT).
_TOTVAR = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}
_MTOT = {2: (1.90, 2.10), 1: (1.20, 1.40), 0: (1.10, 1.20), -1: (0.85, 0.50), -2: (0.75, 0.31)}
# nu = (M/m)/(b0 + b1·m/M) with M = N − 1 frequency points (Howe et al., PTTI 2000).
_HTOT = {0: (0.559, 1.004), -1: (0.868, 1.140), -2: (0.938, 1.696),
         -3: (2.554, 0.974), -4: (3.149, 1.276)}
# Below this factor Stable32 replaces the HTOT formula (which exceeds M there) by SP1065 Table 5.
_HTOT_MIN_M = 16


def _oadev_simple(alpha: int, m: int, N: int) -> float:
    """SP1065 Table 5 closed forms (unchecked arguments); NaN when undefined."""
    if N < 2 * m + 1:
        return math.nan
    if alpha == 2:
        nu = (N + 1) * (N - 2 * m) / (2.0 * (N - m))
    elif alpha == 1:
        a = math.log((N - 1) / (2.0 * m))
        b = math.log((2 * m + 1) * (N - 1) / 4.0)
        nu = math.exp(math.sqrt(a * b)) if a * b >= 0.0 else math.nan
    elif alpha == 0:
        nu = (3.0 * (N - 1) / (2.0 * m) - 2.0 * (N - 2) / N) * 4.0 * m * m / (4.0 * m * m + 5.0)
    elif alpha == -1:
        nu = 2.0 * (N - 2) / (2.3 * N - 4.9) if m == 1 else 5.0 * N * N / (4.0 * m * (N + 3 * m))
    else:
        nu = (N - 2) / (m * (N - 3.0) ** 2) * ((N - 1) ** 2 - 3.0 * m * (N - 1) + 4.0 * m * m)
    return nu if math.isfinite(nu) and nu > 0.0 else math.nan


def _theo1_edf(alpha: int, m: int, N: int) -> float:
    t = 0.75 * m
    if alpha == 2:
        return 0.86 * (N + 1) * (N - 4.0 * t / 3.0) / (N - t) * (t / (t + 1.14))
    if alpha == 1:
        return ((4.798 * N * N - 6.374 * N * t + 12.387 * t) / (math.sqrt(t + 36.6) * (N - t))
                * (t / (t + 0.3)))
    if alpha == 0:
        t15 = t ** 1.5
        return ((4.1 * N + 0.8) / t - (3.1 * N + 6.5) / N) * (t15 / (t15 + 5.2))
    if alpha == -1:
        return (2.0 * N * N - 1.3 * N * t - 3.5 * t) / (N * t) * (t ** 3 / (t ** 3 + 2.3))
    u = 4.4 * N - 1.0
    return ((4.4 * N - 2.0) / (2.9 * t)
            * ((u * u - 8.6 * t * u + 11.4 * t * t) / (4.4 * N - 3.0) ** 2))


_EMPIRICAL_ALPHAS = {
    "totdev": (1, 0, -1, -2),
    "mtotdev": (2, 1, 0, -1, -2),
    "ttotdev": (2, 1, 0, -1, -2),
    "htotdev": (1, 0, -1, -2, -3, -4),
    "theo1": (2, 1, 0, -1, -2),
    "theobr": (2, 1, 0, -1, -2),
    "theoh": (2, 1, 0, -1, -2),
    "stdev": (0,),
}

#: Statistics with an EDF rule.
EDF_STATISTICS: tuple[str, ...] = tuple(_GREENHALL_STATS) + tuple(_EMPIRICAL_ALPHAS)

_NAMES = {-4: "RRFM", -3: "FWFM", -2: "RWFM", -1: "FFM", 0: "WFM", 1: "FPM", 2: "WPM"}


def _check_alpha(alpha: object) -> int:
    try:
        value = float(alpha)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"alpha={alpha!r} must be an integer in -4 ... 2") from None
    if not value.is_integer() or not -4 <= value <= 2:
        raise ParameterError(f"alpha={alpha!r} must be an integer in -4 ... 2")
    return int(value)


def _check_statistic(statistic: object) -> str:
    if not isinstance(statistic, str) or statistic.lower() not in EDF_STATISTICS:
        raise ParameterError(
            f"statistic={statistic!r} has no EDF rule; choose one of {', '.join(EDF_STATISTICS)}"
        )
    return statistic.lower()


def _check_pair(statistic: str, alpha: int) -> None:
    """Raise ParameterError when (statistic, alpha) has no EDF rule."""
    if statistic in _GREENHALL_STATS:
        d = _GREENHALL_STATS[statistic][0]
        if alpha + 2 * d <= 1:
            raise ParameterError(
                f"{statistic} with alpha={alpha} ({_NAMES[alpha]}): the variance diverges"
                f" (needs alpha > {1 - 2 * d})"
            )
        return
    allowed = _EMPIRICAL_ALPHAS[statistic]
    if alpha == 2 and statistic in ("totdev", "htotdev"):
        raise ParameterError(
            f"{statistic} has no EDF for alpha=2 (WPM): the OAVAR closed form overstates it"
            " up to 3x (Monte Carlo); total variances are meant for FM noise, use oadev"
        )
    if alpha not in allowed:
        raise ParameterError(
            f"{statistic} has no EDF formula for alpha={alpha} ({_NAMES[alpha]});"
            f" tabulated: alpha in {list(allowed)}"
        )


def _row_statistic(statistic: str, m: int) -> str:
    """The estimator whose EDF applies at factor ``m``.

    HTOT at m = 1 *is* OHVAR(τ0) (SP1065 and Stable32 report OHDEV there, and
    so does :func:`sigmatau.htotdev`), so that row takes OHVAR's EDF; the HTOT
    formula and the SP1065 Table 5 forms describe other estimators (Table 5's
    FFM form at m = 1 gives ν ≈ 0.87 for any N, an interval from zero).
    """
    return "ohdev" if statistic == "htotdev" and m == 1 else statistic


# ν depends only on its five arguments; the Greenhall sums cost milliseconds while a
# statistic itself costs microseconds, and the same (statistic, α, m, N) recurs on
# every call with the same record length.
@functools.lru_cache(maxsize=4096)
def _edf_scalar(statistic: str, alpha: int, m: int, N: int, version: str) -> tuple[float, str]:
    if statistic in _GREENHALL_STATS:
        d, modified, overlapped = _GREENHALL_STATS[statistic]
        inv, why = _greenhall_inverse(alpha, d, m, modified, overlapped, N, version)
        return (math.nan, why) if why else (1.0 / inv, "")
    if statistic == "stdev":
        K = (N - 1) // m
        if K < 2:
            return math.nan, f"N={N} phase points give {K} average(s) of m={m}; need 2"
        return float(K - 1), ""
    if statistic in ("totdev", "mtotdev", "ttotdev"):
        need = 2 * m + 1 if statistic == "totdev" else 3 * m + 1
        if N < need:
            return math.nan, f"N={N} phase points is fewer than {need} needed at m={m}"
        if statistic == "totdev" and alpha == 1:
            nu = _oadev_simple(1, m, N)
        else:
            b, c = (_TOTVAR if statistic == "totdev" else _MTOT)[alpha]
            nu = b * N / m - c
    elif statistic == "htotdev":
        M = N - 1
        if M < 3 * m:
            return math.nan, f"M={M} frequency points is fewer than 3m={3 * m}"
        if alpha == 1 or (m < _HTOT_MIN_M and alpha >= -2):
            nu = _oadev_simple(alpha, m, N)
        else:
            b0, b1 = _HTOT[alpha]
            nu = (M / m) / (b0 + b1 * m / M)
    else:  # Theo1 family
        if N < m + 1:
            return math.nan, f"N={N} phase points is fewer than m+1={m + 1}"
        nu = _theo1_edf(alpha, m, N)
    if not (math.isfinite(nu) and nu > 0.0):
        return math.nan, f"the {statistic} EDF formula gives nu={nu:.3g} <= 0 at m={m}, N={N}"
    return nu, ""


def edf(statistic: str, alpha: int, m: int, N: int, *, version: Version = "full") -> float:
    r"""Equivalent degrees of freedom of ``statistic`` at one averaging factor.

    Parameters
    ----------
    statistic : str
        One of :data:`EDF_STATISTICS` (case-insensitive).
    alpha : int
        Dominant power-law noise exponent (2 WPM, 1 FPM, 0 WFM, −1 FFM,
        −2 RWFM, −3 FWFM, −4 RRFM).
    m : int
        Averaging factor (for the Theo family τ = 0.75·m·τ0).
    N : int
        Number of phase points (frequency samples + 1).
    version : {"full", "simplified"}
        Greenhall algorithm variant; ignored by the empirical rules.

    Returns
    -------
    float
        ν, or NaN when the record is too short or the empirical formula gives
        ν ≤ 0; :func:`edf_reason` says why.

    Raises
    ------
    ParameterError
        Unknown statistic, invalid m or N, or an α without a rule (below).

    Notes
    -----
    Rules and supported α (any other α raises :class:`ParameterError`):

    ============================  ========================  ====================
    statistic                     rule                      α
    ============================  ========================  ====================
    adev, oadev, mdev, tdev       Greenhall, d = 2          2 … −2
    hdev, ohdev, mhdev            Greenhall, d = 3          2 … −4
    totdev                        ν = b·N/m − c             0, −1, −2
    totdev                        SP1065 Table 5 (FPM)      1
    mtotdev, ttotdev              ν = b·N/m − c             2 … −2
    htotdev, m ≥ 16               ν = (M/m)/(b0 + b1·m/M)   0 … −4
    htotdev, m ≥ 16               SP1065 Table 5 (FPM)      1
    htotdev, 1 < m < 16           SP1065 Table 5            1 … −2
    htotdev, 1 < m < 16           ν = (M/m)/(b0 + b1·m/M)   −3, −4
    htotdev, m = 1                as ohdev (HTOT is OHVAR)  2 … −4
    theo1, theobr, theoh          Theo1 formulas            2 … −2
    stdev                         ν = ⌊(N−1)/m⌋ − 1         0
    ============================  ========================  ====================

    Greenhall (F, S): adev (m, 1), oadev (m, m), mdev/tdev (1, m), hdev (m, 1),
    ohdev (m, m), mhdev (1, m); see :func:`greenhall_edf`. "SP1065 Table 5" is
    the closed-form OAVAR EDF of :func:`edf_oadev_simple`.

    TOTVAR (SP1065 Table 7): (b, c) = WFM (1.50, 0), FFM (1.17, 0.22),
    RWFM (0.93, 0.36). Nothing is tabulated for WPM/FPM. For FPM the Table 5
    closed form is used: Stable32 does the same (its TOTDEV intervals are
    reproduced to 3e-4), and Monte Carlo of TOTVAR itself agrees (N = 513,
    m = 4/16/64: MC 231/120/40, Table 5 225/123/39; the Greenhall OAVAR rule
    gives 198/96/35). **WPM raises**: Stable32 uses the Table 5 WPM form, but
    Monte Carlo shows it, and the OAVAR EDF, overstating the TOTVAR EDF up to 3×
    (N = 513, m = 64: MC 74, Table 5 220), i.e. intervals too narrow; TOTVAR is
    meant for FM noise — use an OADEV interval for white PM.

    MTOT and TTOT (SP1065 Table 8): (b, c) = WPM (1.90, 2.10), FPM (1.20, 1.40),
    WFM (1.10, 1.20), FFM (0.85, 0.50), RWFM (0.75, 0.31). Stable32 does not
    follow this table: below m = 10 it uses the MDEV Greenhall EDF, above it a
    rule giving ν about 20–45 % larger than the table (not identified).

    HTOT (Howe et al. 2000) with ``M = N − 1`` frequency points: (b0, b1) =
    WFM (0.559, 1.004), FFM (0.868, 1.140), RWFM (0.938, 1.696),
    FWFM (2.554, 0.974), RRFM (3.149, 1.276). The FWFM/RRFM rows are kept as
    published although Monte Carlo gives ν ≈ 2.5× larger: they are very
    conservative. Below m = 16 the formula exceeds the number of samples
    (ν = 1786 for M = 1000 at m = 1) and, as Stable32 does, the Table 5 closed
    form takes over for α = 1 … −2 (reproduces Stable32's HTOT intervals to
    7e-4; not checked by Monte Carlo). FPM uses Table 5 at every m (Stable32's
    own values are 4–12 % higher at m ≥ 128). WPM raises, as for TOTVAR. At
    m = 1 HTOT is OHVAR(τ0) (SP1065, Stable32 and :func:`sigmatau.htotdev`
    report OHDEV there) and ``edf("htotdev", α, 1, N)`` is
    ``edf("ohdev", α, 1, N)``, for every α OHDEV has a rule for. (Stable32's
    HTOT table prints the Table 5 interval at m = 1, ν = 666 for WFM at
    N = 1001, while its OHDEV table prints Greenhall's ν = 609 for the same
    value; Monte Carlo of OHVAR(τ0) on discrete white FM gives 493 ± 3 %
    (2000 runs), and the N − 3 squared second differences of white y,
    correlated at lags 1 and 2 by −4/6 and 1/6, give about
    ``(N−3)/(1 + 2(16+1)/36) = 513``: both rules overstate ν there.)

    Theo1 (Howe & Tasset 2004), ``t = 0.75 m``, each first bracket
    **multiplied** by the second:

    * WPM ``0.86 (N+1)(N − 4t/3)/(N − t) · t/(t + 1.14)``
    * FPM ``(4.798N² − 6.374Nt + 12.387t)/(√(t + 36.6)(N − t)) · t/(t + 0.3)``
    * WFM ``[(4.1N + 0.8)/t − (3.1N + 6.5)/N] · t^{3/2}/(t^{3/2} + 5.2)``
    * FFM ``(2N² − 1.3Nt − 3.5t)/(Nt) · t³/(t³ + 2.3)``
    * RWFM ``(4.4N − 2)/(2.9t) · [(4.4N − 1)² − 8.6t(4.4N − 1) + 11.4t²]/(4.4N − 3)²``

    TheoBR and the TheoBR part of TheoH use the Theo1 EDF (the AVAR part of
    TheoH takes ``edf("oadev", ...)``). The RWFM formula
    turns negative for ``t ≳ 0.63 N``; NaN is returned there.

    References
    ----------
    W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065
    (2008), §5.3 and Tables 7–8. C. A. Greenhall and W. J. Riley, Proc. 35th
    PTTI (2003). D. A. Howe, R. L. Beard, C. A. Greenhall, W. J. Riley, "A total
    estimator of the Hadamard function used for GPS operations", Proc. 32nd
    PTTI (2000). D. A. Howe and T. N. Tasset, "Theo1: characterization of very
    long-term frequency stability", Proc. 18th EFTF (2004).

    Examples
    --------
    >>> round(edf("oadev", 0, 10, 1001), 3)
    135.071
    >>> round(edf("totdev", 0, 10, 1001), 2)
    150.15
    """
    statistic = _check_statistic(statistic)
    alpha = _check_alpha(alpha)
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    version = _check_version(version)
    statistic = _row_statistic(statistic, m)
    _check_pair(statistic, alpha)
    return _edf_scalar(statistic, alpha, m, N, version)[0]


def edf_reason(statistic: str, alpha: int, m: int, N: int, *, version: Version = "full") -> str:
    """Why :func:`edf` returns NaN for these arguments; ``""`` when it does not.

    Examples
    --------
    >>> edf_reason("oadev", 0, 501, 1001)
    'N=1001 phase points is fewer than the filter length L=1003'
    >>> edf_reason("oadev", 0, 10, 1001)
    ''
    """
    statistic = _check_statistic(statistic)
    alpha = _check_alpha(alpha)
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    version = _check_version(version)
    statistic = _row_statistic(statistic, m)
    _check_pair(statistic, alpha)
    return _edf_scalar(statistic, alpha, m, N, version)[1]


def edf_array(statistic: str, alpha: ArrayLike, ms: ArrayLike, N: int, *,
              version: Version = "full", return_reason: bool = False,
              unsupported: Literal["raise", "nan"] = "raise",
              ) -> np.ndarray | tuple[np.ndarray, tuple[str, ...]]:
    """:func:`edf` over many averaging factors.

    Parameters
    ----------
    statistic : str
        As in :func:`edf`.
    alpha : int or array_like of int
        One noise exponent, or one per averaging factor (broadcast with ``ms``).
    ms : array_like of int
        Averaging factors.
    N : int
        Number of phase points.
    version : {"full", "simplified"}
        Greenhall algorithm variant.
    return_reason : bool
        Also return a tuple of strings, ``""`` where ν is defined and the
        reason for NaN elsewhere.
    unsupported : {"raise", "nan"}
        What to do with an α that has no rule for ``statistic``: raise
        :class:`ParameterError` (default), or give NaN with the error message
        as the reason — convenient when α comes from noise identification
        at each τ.

    Returns
    -------
    nu : numpy.ndarray
        ν for each factor, NaN where undefined.
    reasons : tuple of str
        Only when ``return_reason`` is true.

    Raises
    ------
    ParameterError
        As :func:`edf`; with ``unsupported="raise"`` every (statistic, α) pair
        is checked before computing.

    Examples
    --------
    >>> edf_array("mtotdev", 0, [10, 100], 1001).round(2)
    array([108.91,   9.81])
    """
    statistic = _check_statistic(statistic)
    N = _check_int(N, "N", 1)
    version = _check_version(version)
    if unsupported not in ("raise", "nan"):
        raise ParameterError(f"unsupported={unsupported!r} must be 'raise' or 'nan'")
    try:
        a_arr, m_arr = np.broadcast_arrays(np.asarray(alpha), np.asarray(ms))
    except ValueError:
        raise ParameterError(
            f"alpha (shape {np.shape(alpha)}) and ms (shape {np.shape(ms)}) do not broadcast"
        ) from None
    if m_arr.ndim > 1:
        raise ParameterError(f"ms must be a scalar or 1-D, got shape {m_arr.shape}")
    alphas = [_check_alpha(a) for a in a_arr.ravel()]
    factors = [_check_int(v, "m", 1) for v in m_arr.ravel()]
    rows = [(_row_statistic(statistic, v), a, v) for a, v in zip(alphas, factors)]
    refused: dict[tuple[str, int], str] = {}
    for key in sorted({(st, a) for st, a, _ in rows}):
        try:
            _check_pair(*key)
        except ParameterError as exc:
            if unsupported == "raise":
                raise
            refused[key] = str(exc)
    pairs = [(math.nan, refused[st, a]) if (st, a) in refused else _edf_scalar(st, a, v, N, version)
             for st, a, v in rows]
    nu = np.array([p[0] for p in pairs], dtype=float).reshape(m_arr.shape)
    if return_reason:
        return nu, tuple(p[1] for p in pairs)
    return nu


def edf_oadev_simple(alpha: int, m: int, N: int) -> float:
    r"""Closed-form EDF approximation for the overlapped Allan variance.

    Parameters
    ----------
    alpha : {2, 1, 0, -1, -2}
        Dominant noise exponent.
    m : int
        Averaging factor.
    N : int
        Number of phase points.

    Returns
    -------
    float
        ν, NaN when ``N < 2m + 1`` (no OAVAR term) or the formula gives ν ≤ 0.

    Notes
    -----
    SP1065 Table 5 (after Howe, Allan & Barnes 1981 and Stein 1985):

    * WPM ``(N + 1)(N − 2m)/(2(N − m))``
    * FPM ``exp(√(ln((N − 1)/(2m)) · ln((2m + 1)(N − 1)/4)))``
    * WFM ``[3(N − 1)/(2m) − 2(N − 2)/N] · 4m²/(4m² + 5)``
    * FFM m = 1: ``2(N − 2)/(2.3N − 4.9)``; m ≥ 2: ``5N²/(4m(N + 3m))``
    * RWFM ``(N − 2)/(m(N − 3)²) · [(N − 1)² − 3m(N − 1) + 4m²]``

    :func:`greenhall_edf` is the more accurate rule and the one used for
    intervals.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3, Table 5.

    Examples
    --------
    >>> round(edf_oadev_simple(0, 10, 1001), 1)
    146.2
    """
    alpha = _check_alpha(alpha)
    if alpha < -2:
        raise ParameterError(f"alpha={alpha} has no closed-form OAVAR EDF (needs -2 <= alpha <= 2)")
    m = _check_int(m, "m", 1)
    N = _check_int(N, "N", 1)
    return _oadev_simple(alpha, m, N)


# Lesage–Audoin style factors of Stable32 for non-overlapped ADEV, by alpha.
_K_ALPHA = {2: 0.99, 1: 0.99, 0: 0.87, -1: 0.77, -2: 0.75}


def simple_error(dev: ArrayLike, n: ArrayLike, *, alpha: int | None = None) -> np.ndarray:
    """The simple 1-σ error estimate ``dev/√n`` (optionally ``K_α·dev/√n``).

    Parameters
    ----------
    dev : array_like
        Deviations.
    n : array_like
        Number of terms summed by the estimator at each τ.
    alpha : {2, 1, 0, -1, -2}, optional
        When given, multiply by Stable32's noise factor ``K_α`` = 0.99, 0.99,
        0.87, 0.77, 0.75 (WPM … RWFM), meant for the non-overlapped ADEV.

    Returns
    -------
    numpy.ndarray
        The error; NaN where ``n < 1``.

    Notes
    -----
    Exact only for uncorrelated terms (non-overlapped AVAR of white FM); the
    terms of overlapped estimators are correlated and this understates the
    error. Prefer :func:`deviation_interval` with :func:`edf`.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3; Stable32 User Manual ("Kn"
    factors, after Lesage & Audoin).

    Examples
    --------
    >>> float(simple_error(0.1, 100))
    0.01
    """
    d = np.asarray(dev, dtype=float)
    nn = np.asarray(n, dtype=float)
    factor = 1.0
    if alpha is not None:
        a = _check_alpha(alpha)
        if a not in _K_ALPHA:
            raise ParameterError(f"alpha={alpha} has no K_alpha factor (needs -2 <= alpha <= 2)")
        factor = _K_ALPHA[a]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = factor * d / np.sqrt(np.where(nn >= 1.0, nn, np.nan))
    return out


# --- intervals ---------------------------------------------------------------------------


def _check_confidence(confidence: object) -> float:
    try:
        value = float(confidence)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"confidence={confidence!r} must be a number in (0, 1)") from None
    if not 0.0 < value < 1.0:
        raise ParameterError(f"confidence={confidence!r} must be in (0, 1), e.g. 0.683 or 0.95")
    return value


def chi2_interval(var: ArrayLike, edf: ArrayLike, confidence: float = ONE_SIGMA, *,
                  sided: Sided = "two") -> ConfidenceInterval:
    r"""χ² confidence interval on a variance from its equivalent degrees of freedom.

    Parameters
    ----------
    var : array_like
        Variance estimates ``s²`` (≥ 0; NaN propagates).
    edf : array_like
        Equivalent degrees of freedom ν (broadcast with ``var``; non-integer
        allowed). Where ν is NaN or ≤ 0 both bounds are NaN.
    confidence : float
        Coverage probability p in (0, 1); default ``erf(1/√2) ≈ 0.682689``
        (±1σ).
    sided : {"two", "upper", "lower"}
        ``"two"``: equal tails. ``"upper"``: single-sided upper bound, the
        interval ``[0, hi]`` (``low = 0``, the true lower end of a one-sided
        interval on a variance, as for the last low-EDF points of a run).
        ``"lower"``: ``[lo, ∞)`` (``high = inf``).

    Returns
    -------
    ConfidenceInterval
        ``(low, high)`` on the variance; floats for scalar inputs, arrays
        otherwise.

    Raises
    ------
    ParameterError
        Confidence outside (0, 1), an unknown ``sided`` or a negative variance.

    Notes
    -----
    Since ``ν s²/σ² ~ χ²_ν``, with ``χ²_ν(q)`` the q-quantile,

    .. math::

        σ^2_{lo} = \frac{ν s^2}{χ^2_ν\bigl(1 - (1-p)/2\bigr)},\qquad
        σ^2_{hi} = \frac{ν s^2}{χ^2_ν\bigl((1-p)/2\bigr)},

    and the single-sided bounds use ``χ²_ν(p)`` (lower) and ``χ²_ν(1 − p)``
    (upper). Exact quantiles (``scipy.special.chdtri``, the inverse χ² survival
    function) are used; Stable32's
    approximate inverse differs in the 4th digit.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008), §5.3 (eqs. for the χ² interval).

    Examples
    --------
    >>> lo, hi = chi2_interval(1.0, 100.0)
    >>> round(lo, 4), round(hi, 4)
    (0.8765, 1.1641)
    """
    p = _check_confidence(confidence)
    if sided not in ("two", "upper", "lower"):
        raise ParameterError(f"sided={sided!r} must be 'two', 'upper' or 'lower'")
    v = np.asarray(var, dtype=float)
    if np.any(v < 0.0):
        raise ParameterError("var must be >= 0 (got a negative variance)")
    nu = np.asarray(edf, dtype=float)
    v, nu = np.broadcast_arrays(v, nu)
    good = np.isfinite(nu) & (nu > 0.0)
    nu_ok = np.where(good, nu, 1.0)
    scaled = np.where(good, nu_ok * v, np.nan)
    if sided == "two":
        low = scaled / chdtri(nu_ok, (1.0 - p) / 2.0)
        high = scaled / chdtri(nu_ok, (1.0 + p) / 2.0)
    elif sided == "upper":
        low = np.where(good, 0.0, np.nan) * np.where(np.isnan(v), np.nan, 1.0)
        high = scaled / chdtri(nu_ok, p)
    else:
        low = scaled / chdtri(nu_ok, 1.0 - p)
        high = np.where(good, np.inf, np.nan) * np.where(np.isnan(v), np.nan, 1.0)
    if low.ndim == 0:
        return ConfidenceInterval(float(low), float(high))
    return ConfidenceInterval(low, high)


def deviation_interval(dev: ArrayLike, edf: ArrayLike, confidence: float = ONE_SIGMA, *,
                       sided: Sided = "two") -> ConfidenceInterval:
    """χ² confidence interval on a deviation: square roots of :func:`chi2_interval`.

    Parameters
    ----------
    dev : array_like
        Deviations ``s`` (≥ 0).
    edf : array_like
        Equivalent degrees of freedom.
    confidence : float
        Coverage in (0, 1), default ±1σ (0.682689…).
    sided : {"two", "upper", "lower"}
        See :func:`chi2_interval`.

    Returns
    -------
    ConfidenceInterval
        ``(low, high)`` on the deviation.

    Examples
    --------
    >>> lo, hi = deviation_interval(9.159953e-02, edf("oadev", 0, 10, 1001))
    >>> f"{lo:.6e} {hi:.6e}"
    '8.649995e-02 9.772219e-02'
    """
    d = np.asarray(dev, dtype=float)
    if np.any(d < 0.0):
        raise ParameterError("dev must be >= 0 (got a negative deviation)")
    low, high = chi2_interval(d * d, edf, confidence, sided=sided)
    if np.ndim(low) == 0:
        return ConfidenceInterval(math.sqrt(low), math.sqrt(high))
    return ConfidenceInterval(np.sqrt(low), np.sqrt(high))
