"""The terms of the IMU noise model: their slopes, read-off τ, factors and AVAR columns.

The IEEE Std 952/1554 model is a sum of five terms Q, N, B, K, R (see
:mod:`sigmatau.imu.model`). This module holds what every other part of the
model shares about them: the ADEV slope of each term and the τ at which its
line is read, the factor from the line to the coefficient (:data:`B_FACTOR`
for the bias instability), the power-law exponent α used for the EDF and the
τ-correlation model, the AVAR columns of the fit (``_design``,
:func:`avar_terms`), the warning class, and the small argument and
JSON helpers (``_level``, ``_num``).
"""

from __future__ import annotations

import math
from typing import Optional, Sequence, Union

import numpy as np

from ..errors import ParameterError, SigmaTauWarning
from .units import TERMS

__all__ = ["B_FACTOR", "READ_FACTOR", "ImuWarning", "avar_terms"]

#: σ_min / B for flicker noise: √(2 ln 2 / π) (IEEE Std 952, Annex C).
B_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)

#: Nominal ADEV slope of each term, the τ (s) at which its line is read, and the
#: factor from the line's deviation there to the coefficient.
_SLOPE = {"Q": -1.0, "N": -0.5, "B": 0.0, "K": 0.5, "R": 1.0}
_READ_TAU = {"Q": math.sqrt(3.0), "N": 1.0, "B": 1.0, "K": 3.0, "R": math.sqrt(2.0)}
READ_FACTOR = {"Q": 1.0, "N": 1.0, "B": 1.0 / B_FACTOR, "K": 1.0, "R": 1.0}
#: Power-law exponent α of each term (for the EDF and the τ-correlation model).
_ALPHA = {"Q": 2, "N": 0, "B": -1, "K": -2, "R": -2}
_NAMES = {"Q": "quantization", "N": "white noise (angle/velocity random walk)",
          "B": "bias instability", "K": "rate/acceleration random walk", "R": "rate ramp"}


class ImuWarning(SigmaTauWarning):
    """A noise term is not resolved, or the read-offs and the fit disagree."""


def _num(v: float) -> Optional[float]:
    """``float(v)``, or None for a missing, NaN or infinite value (JSON has no NaN)."""
    return float(v) if v is not None and math.isfinite(v) else None


def _level(value: object, name: str) -> float:
    """``value`` as a non-negative finite float; :class:`ParameterError` naming ``name`` otherwise."""
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} must be a non-negative number")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be a non-negative number") from None
    if not math.isfinite(v) or v < 0:
        raise ParameterError(f"{name}={value!r} must be a non-negative finite number")
    return v


def _design(taus: np.ndarray, rate: float) -> np.ndarray:
    """AVAR columns of Q², N², B², K², R² at ``taus`` (exact for sampled white and random walk)."""
    tau0 = 1.0 / rate
    t = np.asarray(taus, dtype=float)
    return np.column_stack([
        3.0 / t**2,
        1.0 / t,
        np.full(t.shape, B_FACTOR**2),
        t / 3.0 + tau0**2 / (6.0 * t),
        t**2 / 2.0,
    ])


def _gm_column(taus: np.ndarray, rate: float, tau_c: float) -> np.ndarray:
    """AVAR of a unit-variance first-order Gauss–Markov process of correlation time ``tau_c``.

    The continuous form ``(2T/τ)[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))]`` is evaluated as
    ``4[g(x) − g(2x)]``, ``x = τ/T``, ``g(z) = (e^(−z) − 1 + z)/z²`` (a series below x = 0.01:
    the bracket cancels to ``2τ/3T`` when τ ≪ T). When ``rate`` is finite and τ_c < 1000 τ0 the
    sampled process (an AR(1), ``φ = e^(−τ0/τ_c)``) is used instead, exact at every m:
    ``σ²_A = (4D(m) − D(2m))/(2τ²)``, ``D(k) = τ0²[k + 2φ(k(1 − φ) − (1 − φ^k))/(1 − φ)²]``
    (the variance of a sum of k samples, times τ0²); above 1000 τ0 both agree to < 0.1 %
    beyond the first few m, where the term is negligible beside any white noise.
    """
    t = np.asarray(taus, dtype=float)
    tc = float(tau_c)
    a = (1.0 / rate) / tc if math.isfinite(rate) else 0.0
    if a > 1e-3:
        tau0 = 1.0 / rate
        m = np.maximum(t / tau0, 1.0)
        phi = math.exp(-a)
        one = -math.expm1(-a)

        def d(k: np.ndarray) -> np.ndarray:
            return k + 2.0 * phi * (k * one + np.expm1(-a * k)) / one**2

        return tau0**2 * (4.0 * d(m) - d(2.0 * m)) / (2.0 * t**2)
    x = t / tc
    return 4.0 * (_g(x) - _g(2.0 * x))


def _g(z: np.ndarray) -> np.ndarray:
    """``(e^(−z) − 1 + z)/z²`` without cancellation (series ``Σ (−z)^n/(n + 2)!`` for z < 0.02)."""
    z = np.asarray(z, dtype=float)
    small = z < 0.02
    zs = np.where(small, z, 1.0)
    series = sum((-zs) ** n / math.factorial(n + 2) for n in range(7))
    zl = np.where(small, 1.0, z)
    return np.where(small, series, (np.expm1(-zl) + zl) / zl**2)


def _gm_alpha(taus: np.ndarray, rate: float, tau_c: float) -> np.ndarray:
    """Power-law α (0 white … −2 random walk) that the GM term looks like at each τ: from its local
    AVAR slope μ, ``α = −μ − 1`` rounded and clipped to −2…0 (for the EDF and τ-correlation models)."""
    t = np.asarray(taus, dtype=float)
    up, down = _gm_column(t * 1.01, rate, tau_c), _gm_column(t / 1.01, rate, tau_c)
    mu = np.log(up / down) / (2.0 * math.log(1.01))
    return np.clip(np.round(-mu - 1.0), -2, 0).astype(np.int64)


def avar_terms(taus: Union[float, Sequence[float], np.ndarray], *, rate: float = math.inf, Q: float = 0.0,
               N: float = 0.0, B: float = 0.0, K: float = 0.0, R: float = 0.0) -> dict[str, np.ndarray]:
    """Allan-variance contribution of each term of the model at ``taus``.

    Parameters
    ----------
    taus : float or array_like
        Averaging times (s).
    rate : float
        Sample rate; with a finite rate the random-walk term is the exact
        expectation for point samples, ``K²(τ/3 + τ0²/(6τ))``.
    Q, N, B, K, R : float
        Coefficients in consistent units.

    Returns
    -------
    dict of str to numpy.ndarray
        ``3Q²/τ²``, ``N²/τ``, ``(2 ln 2/π)B²``, ``K²τ/3``, ``R²τ²/2`` by term;
        their sum is the model's AVAR.

    Examples
    --------
    >>> from sigmatau.imu import avar_terms
    >>> v = avar_terms([1.0, 3.0], N=2.0, K=3.0)
    >>> [float(x) for x in v["N"]], [float(x) for x in v["K"]]
    ([4.0, 1.3333333333333333], [3.0, 9.0])
    """
    t = np.atleast_1d(np.asarray(taus, dtype=float))
    if np.any(t <= 0) or not np.all(np.isfinite(t)):
        raise ParameterError("taus must be positive and finite")
    r = float(rate)
    cols = _design(t, r) if math.isfinite(r) else _design(t, 1e300)
    coef = [Q, N, B, K, R]
    return {name: cols[:, j] * float(c) ** 2 for j, (name, c) in enumerate(zip(TERMS, coef))}
