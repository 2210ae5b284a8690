"""Barnes' bias functions B1, B2, B3 and the dead-time correction of σ(τ).

A counter that measures frequency over gates of length τ repeated every
``T = τ + dead`` (dead-time ratio ``r = T/τ ≥ 1``) gives an Allan variance that
differs from the one of contiguous gates. For power-law noise with
``σ²(τ) ∝ τ^μ`` Barnes expressed the ratios through the phase structure
function ``D(s) = E[(x(t+s) − x(t))²] ∝ |s|^{μ+2}`` (``|s|² ln|s|`` at μ = 0,
and ``D = const`` for s ≠ 0, ``D(0) = 0`` at μ = −2):

* ``B1(N, μ) = ⟨σ²(N, T=τ, τ)⟩/⟨σ²(2, τ, τ)⟩``, N-sample over 2-sample variance;
* ``B2(r, μ) = ⟨σ²(2, T, τ)⟩/⟨σ²(2, τ, τ)⟩``, 2-sample variance with dead time
  over the one without;
* ``B3(2, M, r, μ) = ⟨σ²(2, M, T, τ)⟩/⟨σ²(2, MT, Mτ)⟩``, averages of M gates
  with their dead time spread between them, over one gate of Mτ with all the
  dead time ``M(T − τ)`` at its end.

So a deviation measured at M gates per average is related to the contiguous
deviation at averaging time ``Mτ`` by ``σ²_meas = B3·B2·σ²(Mτ)``.

Each expectation is computed exactly from D: a difference of gate averages is
``Σ c_i x(t_i)`` with ``Σ c_i = 0``, whose mean square is ``−½ Σ c_i c_j D(t_i − t_j)``.

References
----------
J. A. Barnes, "Tables of bias functions, B1 and B2, for variances based on
finite samples of processes with power law spectral densities", NBS Technical
Note 375 (1969); J. A. Barnes and D. W. Allan, "Variances based on data with
dead time between the measurements", NIST Technical Note 1318 (1990);
W. J. Riley, NIST SP 1065 (2008) §5.15 (bias functions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import DataError, ParameterError

__all__ = ["mu_from_alpha", "b1", "b2", "b3", "deadtime_correction", "DeadTimeCorrection"]

#: μ of σ²(τ) ∝ τ^μ for each α (SP1065 §5.15): μ = −α − 1 for the FM types,
#: −2 for white and flicker PM (Barnes' convention for flicker PM, whose
#: τ^−2·ln τ law has no single exponent).
_MU = {2: -2.0, 1: -2.0, 0: -1.0, -1: 0.0, -2: 1.0}


def mu_from_alpha(alpha: int) -> float:
    """Barnes' μ for the noise type α ∈ {2, 1, 0, −1, −2}.

    >>> [mu_from_alpha(a) for a in (2, 1, 0, -1, -2)]
    [-2.0, -2.0, -1.0, 0.0, 1.0]
    """
    if isinstance(alpha, bool) or alpha not in _MU:
        raise ParameterError(f"alpha={alpha!r} must be one of {sorted(_MU)}")
    return _MU[alpha]


def _check_mu(mu: object) -> float:
    try:
        value = float(mu)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"mu={mu!r} must be a number in [-2, 2)") from None
    if not (-2.0 <= value < 2.0):
        raise ParameterError(f"mu={mu!r} must lie in [-2, 2) (Barnes' range of power laws)")
    return value


def _structure(s: np.ndarray, mu: float) -> np.ndarray:
    """D(s) up to a factor, minus a multiple of s² that no frequency difference sees.

    ``(|s|^p − s²)/(p − 2)`` with p = μ + 2 is continuous at μ = 0, where it
    becomes ``s² ln|s|``; D(0) = 0 (which makes μ = −2 white PM).
    """
    a = np.abs(s)
    out = np.zeros_like(a)
    pos = a > 0
    q = mu  # p − 2
    lg = np.log(a[pos])
    out[pos] = a[pos] ** 2 * (lg if q == 0.0 else np.expm1(q * lg) / q)
    return out


def _mean_square(times: np.ndarray, coef: np.ndarray, mu: float) -> float:
    d = _structure(times[:, None] - times[None, :], mu)
    return float(-0.5 * coef @ d @ coef)


def _group(start: float, m: int, period: float, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """Points and coefficients of the mean of m gates (each ``(x(end) − x(start))/gate``)."""
    starts = start + period * np.arange(m)
    times = np.concatenate((starts + gate, starts))
    coef = np.concatenate((np.full(m, 1.0), np.full(m, -1.0))) / (m * gate)
    return times, coef


def _two_sample(m: int, period: float, gate: float, mu: float) -> float:
    """½E[(ȳ_B − ȳ_A)²], each ȳ the mean of m gates, B starting m periods after A."""
    ta, ca = _group(0.0, m, period, gate)
    tb, cb = _group(m * period, m, period, gate)
    return 0.5 * _mean_square(np.concatenate((tb, ta)), np.concatenate((cb, -ca)), mu)


def _check_int(value: object, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ParameterError(f"{name}={value!r} must be an integer >= {least}")
    return int(value)


def _check_r(r: object) -> float:
    try:
        value = float(r)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"r={r!r} must be a number >= 1 (T/τ)") from None
    if not math.isfinite(value) or value < 1.0:
        raise ParameterError(f"r={r!r} must be a number >= 1 (T/τ)")
    return value


def b1(n: int, mu: float) -> float:
    """Barnes' B1(N, μ): N-sample variance over the 2-sample (Allan) variance.

    Notes
    -----
    ``B1(N, μ) = N(1 − N^μ)/(2(N − 1)(1 − 2^μ))`` (SP1065 §5.15), with the
    limit ``N ln N/(2(N − 1) ln 2)`` at μ = 0; it is computed here from the
    structure function (exactly equal; the tests check both).

    Examples
    --------
    >>> b1(2, 0.5), round(b1(10, -1.0), 12)
    (1.0, 1.0)
    """
    n = _check_int(n, "n", 2)
    mu = _check_mu(mu)
    if n == 2:
        return 1.0
    times = np.arange(n + 1, dtype=float)
    # E[(1/(N−1))Σ(y_i − ȳ)²] = (1/(2N(N−1))) Σ_{i,j} E[(y_i − y_j)²]
    total = 0.0
    for k in range(1, n):
        c = np.zeros(n + 1)
        np.add.at(c, [k + 1, k, 1, 0], [1.0, -1.0, -1.0, 1.0])
        total += 2.0 * (n - k) * _mean_square(times, c, mu)
    return total / (2.0 * n * (n - 1)) / _two_sample(1, 1.0, 1.0, mu)


def b2(r: float, mu: float) -> float:
    """Barnes' B2(r, μ): Allan variance with dead time (r = T/τ) over the one without.

    Notes
    -----
    From the structure function ``D ∝ s^{μ+2}``,

    .. math:: B_2(r, μ) = \\frac{2 + 2r^{μ+2} − (r+1)^{μ+2} − |r−1|^{μ+2}}{4 − 2^{μ+2}}

    (limits with ``s² ln s`` at μ = 0; ``|r−1|^0`` read as 0 at r = 1 for μ = −2),
    so B2 = 1 for white FM and ``(3r − 1)/2`` for random-walk FM.

    Examples
    --------
    >>> b2(1.0, 0.3), round(b2(3.0, -1.0), 12), round(b2(3.0, 1.0), 12)
    (1.0, 1.0, 4.0)
    """
    r = _check_r(r)
    mu = _check_mu(mu)
    if r == 1.0:
        return 1.0
    return _two_sample(1, r, 1.0, mu) / _two_sample(1, 1.0, 1.0, mu)


def b3(n: int, m: int, r: float, mu: float) -> float:
    """Barnes' B3(2, M, r, μ): M gates with dead time spread over one gate Mτ with it at the end.

    Only N = 2 (the Allan variance) is implemented, as in SP1065 and Stable32.

    Examples
    --------
    >>> b3(2, 1, 2.0, 0.0), b3(2, 8, 1.0, 1.0), round(b3(2, 8, 5.0, -1.0), 12)
    (1.0, 1.0, 1.0)
    """
    if _check_int(n, "n", 2) != 2:
        raise ParameterError(f"n={n!r}: only B3(2, M, r, μ) is implemented")
    m = _check_int(m, "m", 1)
    r = _check_r(r)
    mu = _check_mu(mu)
    if m == 1 or r == 1.0:
        return 1.0
    return _two_sample(m, r, 1.0, mu) / _two_sample(1, m * r, float(m), mu)


@dataclass(frozen=True)
class DeadTimeCorrection:
    """Deviations corrected for dead time: ``taus`` = Mτ, ``dev``, and ``b2``, ``b3`` per row."""

    taus: np.ndarray
    dev: np.ndarray
    measured: np.ndarray
    b2: float
    b3: np.ndarray
    r: float
    mu: float

    def __repr__(self) -> str:
        return f"DeadTimeCorrection(r={self.r:.4g}, mu={self.mu}, {self.dev.size} rows)"


def deadtime_correction(
    devs: object, m: object, *, gate: float, dead: float, alpha: int
) -> DeadTimeCorrection:
    """Allan deviations measured with dead time, corrected to contiguous gates.

    Parameters
    ----------
    devs : array_like
        Allan deviations computed from the gate frequencies (one sample every
        ``T = gate + dead``) at averaging factors ``m``.
    m : array_like of int
        Averaging factors M (gates per average), same length as ``devs``.
    gate : float
        Gate (measurement) time τ in s.
    dead : float
        Dead time between gates in s (≥ 0).
    alpha : int
        Noise type α ∈ {2, 1, 0, −1, −2}; μ from :func:`mu_from_alpha`.

    Returns
    -------
    DeadTimeCorrection
        ``dev = measured/sqrt(B2(r, μ)·B3(2, M, r, μ))``, the deviation for
        contiguous gates at ``τ = M·gate``, ``r = (gate + dead)/gate``.

    Notes
    -----
    ``σ²(2, M, T, τ) = B3(2, M, r, μ)·B2(r, μ)·σ²(2, Mτ, Mτ)`` (Barnes & Allan,
    NIST TN 1318; SP1065 §5.15): first the M-gate averages are compared with
    one gate of Mτ and dead time M(T − τ) (B3), then that with no dead time (B2).
    The correction is exact only for the single noise type assumed.

    Examples
    --------
    >>> c = deadtime_correction([2e-11], [1], gate=1.0, dead=1.0, alpha=-2)
    >>> round(float(c.dev[0]) * 1e11, 9)  # 2/sqrt(B2(2, 1)) = 2/sqrt(2.5)
    1.264911064
    """
    d = np.atleast_1d(np.asarray(devs, dtype=float))
    ms = np.atleast_1d(np.asarray(m))
    if d.ndim != 1 or d.shape != ms.shape or d.size == 0:
        raise DataError(f"devs and m must be 1-D of equal length, got {d.shape} and {ms.shape}")
    if np.any(~np.isfinite(d)) or np.any(d < 0):
        raise DataError("devs must be finite and >= 0")
    try:
        tau, dt = float(gate), float(dead)
    except (TypeError, ValueError):
        raise ParameterError(f"gate={gate!r} and dead={dead!r} must be numbers (s)") from None
    if not (math.isfinite(tau) and tau > 0 and math.isfinite(dt) and dt >= 0):
        raise ParameterError(f"gate={gate!r} must be > 0 and dead={dead!r} >= 0")
    mu = mu_from_alpha(alpha)
    r = (tau + dt) / tau
    factor2 = b2(r, mu)
    factor3 = np.array([b3(2, k, r, mu) for k in ms.tolist()])
    corrected = d / np.sqrt(factor2 * factor3)
    return DeadTimeCorrection(ms.astype(float) * tau, corrected, d, factor2, factor3, r, mu)
