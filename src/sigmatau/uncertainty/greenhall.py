"""Greenhall & Riley's EDF of finite-difference variances (Proc. 35th PTTI, 2003).

The generalised autocovariances ``sw``, ``sx``, ``sz``, the basic sum and the
four-case algorithm with its asymptotic Tables 1–3; public through
:mod:`sigmatau.uncertainty.confidence` (:func:`greenhall_edf`, and
:func:`~sigmatau.uncertainty.confidence.edf` for the statistics it covers).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .edfchecks import Version, _check_alpha, _check_int, _check_version

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
    "ldev": (3, True, True),  # τ²·MHVAR·3/10: MHVAR's EDF
}


def _sw_sign(alpha: int) -> float:
    """Sign of sw(t, α): negative for α = 2, −1, −2."""
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
    """sz(t) = Σ_k (−1)^k C(2d, d+k) sx(t + k), k = −d … d."""
    t = np.asarray(t, dtype=float)
    out = math.comb(2 * d, d) * _sx(t, F, alpha)
    for k in range(1, d + 1):
        out = out + (-1) ** k * math.comb(2 * d, d + k) * (_sx(t - k, F, alpha) + _sx(t + k, F, alpha))
    return out


_CHUNK = 1 << 16


def _basic_sum(J: int, M: float, S: float, F: float, alpha: int, d: int) -> float:
    """BasicSum(J, M, S) of Greenhall & Riley (see :func:`greenhall_edf`)."""
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
        (see :func:`~sigmatau.confidence.edf_reason`).

    Raises
    ------
    ParameterError
        For α outside −4 … 2, ``α + 2d ≤ 1``, d outside 1 … 3, F or S not in
        ``{1, m}``, or a non-integer / non-positive m or N.

    Notes
    -----
    With ``sw(t, α)`` = ``−|t|``, ``t² ln|t|``, ``|t|³``, ``−t⁴ ln|t|``,
    ``−|t|⁵``, ``t⁶ ln|t|``, ``|t|⁷`` for α = 2 … −4,

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
    alpha, d, m, F, S, N = _check_greenhall_args(alpha, d, m, F, S, N)
    inv, _ = _greenhall_inverse(alpha, d, m, F == 1, S == m, N, _check_version(version))
    return 1.0 / inv


def _check_greenhall_args(alpha: object, d: object, m: object, F: object, S: object,
                          N: object) -> tuple[int, int, int, int, int, int]:
    """The checked ``(alpha, d, m, F, S, N)`` of :func:`greenhall_edf` (its Raises section)."""
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
    return alpha, d, m, F, S, N
