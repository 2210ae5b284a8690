r"""EDF of an Allan variance estimate when white PM and white FM noise both contribute.

The EDF rules of :mod:`.confidence` take one dominant power-law noise at each τ. Where two noises
hold comparable shares of the variance, the estimate scatters less than one noise of the same total
variance would: the two contributions to ``σ̂²`` are independent quadratic forms, only partly
correlated. At the crossing of white PM (quantisation, ``3Q²/τ²`` in an IMU's AVAR) and white FM
(``N²/τ``) the dominant-type EDF understated the mixture's by up to a factor of two, and the
intervals of the IMU model's N came out 23–35 % wider than its scatter (77.5–82.5 % coverage at
68.3 %, two sets of 200 simulated records).

Both noises are white, so the exact EDF has a closed form (:func:`white_mixture_edf`, *Notes*).
This is exact for every m and M, where the Greenhall–Riley combined algorithm (:func:`.confidence.edf`,
as Stable32 and allantools compute it) approximates: for white FM, OADEV, N = 4097 it gives
ν = 3205, 2218 and 686 at m = 1, 2 and 8 where the exact values are 2730, 2339 and 751 (Monte Carlo,
4000 records: 2779 ± 62 and 2362 ± 53 at m = 1 and 2; 3000 records: 783 ± 20 at m = 8).

Source: the variance of a Gaussian quadratic form, ``var xᵀAx = 2 tr(AΣAΣ)`` (e.g. Greenhall & Riley,
"Uncertainty of stability variances based on finite differences", PTTI 2003, §2); the
autocovariances follow from the definitions of the two noises (Riley, NIST SP1065, §5.2).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError

__all__ = ["white_mixture_edf"]

_STATISTICS = ("adev", "oadev")


def white_mixture_edf(statistic: str, m: ArrayLike, N: int, pm_share: ArrayLike) -> np.ndarray:
    r"""Exact EDF of the Allan variance at averaging factors ``m`` when white PM holds ``pm_share``
    of the expected variance and white FM the rest.

    ``ν = M²R(0)² / Σ_{|i|<M} (M − |i|) R(iL)²`` with ``R = w·R_P·m²/3 + (1 − w)·R_F·m`` the
    autocovariance of the frequency differences (*Notes*). At ``w = 0`` and ``w = 1`` it is
    the exact EDF of white FM and of white PM alone; in between it is larger than if the two
    contributions were fully correlated, ``2/(w√(2/ν_P) + (1 − w)√(2/ν_F))²``.

    Parameters
    ----------
    statistic : {"oadev", "adev"}
        Overlapping or non-overlapping Allan variance.
    m : array_like of int
        Averaging factors (≥ 1).
    N : int
        Number of phase points (frequency samples + 1).
    pm_share : array_like of float
        Share of the expected variance at each ``m`` from white PM, in 0 … 1 (broadcast with ``m``).

    Returns
    -------
    numpy.ndarray
        ν at each factor (the broadcast shape); NaN where the record holds no difference
        (``M < 1``).

    Notes
    -----
    The Allan variance is
    ``σ̂² = (1/2M) Σ_k d_k²`` over ``M`` frequency differences ``d_k = ȳ_{k+m} − ȳ_k`` (every ``k`` for the
    overlapping estimator, every m-th for the non-overlapping one), and for a Gaussian process

    .. math::

        \operatorname{E}\hat\sigma^2 = \tfrac12 R(0), \qquad
        \operatorname{var}\hat\sigma^2 = \frac{1}{2M^2}\sum_{|i|<M}(M-|i|)\,R(iL)^2, \qquad
        ν = \frac{2(\operatorname{E}\hat\sigma^2)^2}{\operatorname{var}\hat\sigma^2}
          = \frac{M^2R(0)^2}{\sum_{|i|<M}(M-|i|)R(iL)^2},

    with ``R`` the autocovariance of ``d`` and ``L`` the spacing of the terms (1, or m). With ``τ₀ = 1``,
    white PM of unit phase variance gives ``R_P = 6, −4, 1`` (over m²) at lags ``0, ±m, ±2m`` and 0
    elsewhere; white FM of unit variance gives ``R_F(ℓ) = (2m − 3|ℓ|)/m²`` for ``|ℓ| ≤ m`` and
    ``(|ℓ| − 2m)/m²`` for ``m ≤ |ℓ| ≤ 2m``. The mixture holding the share ``w`` of the variance in PM
    has ``R = w·R_P·m²/3 + (1 − w)·R_F·m`` (each part scaled to its expected share).

    Source: the variance of a Gaussian quadratic form, ``var xᵀAx = 2 tr(AΣAΣ)``; the
    autocovariances follow from the definitions of the two noises (NIST SP1065, §5.2).

    Examples
    --------
    >>> from sigmatau.confidence import white_mixture_edf
    >>> [round(float(v)) for v in white_mixture_edf("oadev", [1, 2, 8], 4097, 0.0)]
    [2730, 2339, 751]
    >>> round(float(white_mixture_edf("oadev", 8, 4097, 0.5)))
    1525
    """
    stat = _check(statistic)
    mm = np.asarray(m)
    if mm.size and not (np.issubdtype(mm.dtype, np.number) and np.all(np.isfinite(mm))
                        and np.all(mm >= 1) and np.all(mm <= 2**62) and np.all(mm == np.round(mm))):
        raise ParameterError("m must hold whole averaging factors of at least 1 (and below 2**62)")
    w = np.asarray(pm_share, dtype=float)
    if w.size and not np.all((w >= 0) & (w <= 1)):
        raise ParameterError("pm_share must lie in 0 … 1")
    if not (isinstance(N, (int, np.integer)) and N >= 2):
        raise ParameterError(f"N={N!r} must be a whole number of phase points of at least 2")
    mm, w = np.broadcast_arrays(mm.astype(np.int64), w)
    out = np.array([_one(stat, int(mi), int(N), float(wi)) for mi, wi in zip(mm.ravel(), w.ravel())])
    return out.reshape(mm.shape)


def _one(stat: str, m: int, N: int, w: float) -> float:
    """ν at one factor (see :func:`white_mixture_edf`), in O(1): the lag sum in closed form."""
    n = N - 1
    terms = n - 2 * m + 1 if stat == "oadev" else n // m - 1
    if terms < 1:
        return float("nan")
    f = 1.0 - w
    spikes = {0: 2.0 * w, m: -4.0 * w / 3.0, 2 * m: w / 3.0}   # white PM, R_P·m²/3
    if stat == "adev":  # only the lags 0, m, 2m: white FM's R·m is 2, −1, 0 there
        fm = {0: 2.0 * f, m: -f, 2 * m: 0.0}
        total = terms * (fm[0] + spikes[0]) ** 2
        for k, lag in ((1, m), (2, 2 * m)):
            if k < terms:
                total += 2.0 * (terms - k) * (fm[lag] + spikes[lag]) ** 2
        return float(terms**2 * (fm[0] + spikes[0]) ** 2 / total)
    last = min(2 * m, terms - 1)
    r0 = 2.0 * f + spikes[0]
    total = terms * r0**2
    # White FM: R·m = f(2m − 3ℓ)/m on 1 … m−1 and f(ℓ − 2m)/m on m+1 … 2m−1; the lags m and 2m
    # carry the white PM spikes as well.
    total += 2.0 * _weighted_square_sum(terms, 1, min(m - 1, last), 2.0 * f, -3.0 * f / m)
    total += 2.0 * _weighted_square_sum(terms, m + 1, min(2 * m - 1, last), -2.0 * f, f / m)
    for lag, fm in ((m, -f), (2 * m, 0.0)):
        if lag <= last:
            total += 2.0 * (terms - lag) * (fm + spikes[lag]) ** 2
    return float(terms**2 * r0**2 / total)


def _weighted_square_sum(M: int, a: int, b: int, alpha: float, beta: float) -> float:
    """``Σ_{ℓ=a}^{b} (M − ℓ)(α + βℓ)²`` from the power sums ``Σℓ^k`` (exact integers); 0 when b < a."""
    if b < a:
        return 0.0
    s = [_power_sum(b, k) - _power_sum(a - 1, k) for k in range(4)]
    return float(M * alpha**2 * s[0] + (2.0 * M * alpha * beta - alpha**2) * s[1]
                 + (M * beta**2 - 2.0 * alpha * beta) * s[2] - beta**2 * s[3])


def _power_sum(n: int, k: int) -> int:
    """``Σ_{ℓ=1}^{n} ℓ^k`` for k = 0 … 3 (Faulhaber), 0 for n ≤ 0."""
    if n <= 0:
        return 0
    return (n, n * (n + 1) // 2, n * (n + 1) * (2 * n + 1) // 6, (n * (n + 1) // 2) ** 2)[k]


def _check(statistic: object) -> str:
    stat = statistic.lower() if isinstance(statistic, str) else ""
    if stat not in _STATISTICS:
        raise ParameterError(f"statistic={statistic!r}: the white PM/FM mixture EDF is defined for "
                             "'oadev' and 'adev'")
    return stat
