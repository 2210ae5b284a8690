"""Equivalent degrees of freedom of the parabolic variance (PVAR, :func:`sigmatau.stats.parabolic.pdev`).

PVAR is ``72/(n m⁴ τ²) Σ_i S_i²``, a mean of squares of n overlapping terms
``S_i = Σ_k w_k x_{i+k}`` (the filter ``w`` of 2m phase points: the parabolic
weights ``c_k = (m−1)/2 − k`` on one window, ``−c_k`` on the next; the second
difference ``x_{i+2} − 2x_{i+1} + x_i`` at m = 1, where PVAR is AVAR). Under
Gaussian power-law noise the terms form a stationary Gaussian sequence with
autocovariance ``R(k)``, and the estimator is a quadratic form in it, so

.. math:: ν = \\frac{2 (E\\,Q)^2}{\\mathrm{Var}\\,Q}
        = \\frac{(n R_0)^2}{n R_0^2 + 2\\sum_{k=1}^{n-1} (n-k) R_k^2}

exactly (ν = 2E²/Var matches the first two moments with a scaled χ²_ν). ``R(k)``
is the Fourier coefficient of the terms' spectrum
``|2 sin(ω/2)|^{α−2} |W(ω)|²`` (the discrete power-law phase spectrum of
Kasdin & Walter, the process :func:`sigmatau.generate.power_law_noise` makes,
times the filter's response), computed by a midpoint rule (a DCT-II) on a grid
fine enough that it is exact to rounding for even α and O(grid⁻²) accurate for
odd α.

The filter has two vanishing moments (Σ w_k = Σ k w_k = 0), so the terms are
stationary and PVAR converges for α > −3: WPM, FPM, WFM, FFM and RWFM
(α = 2 … −2); FWFM and RRFM make it diverge.

Cost: the sum is cut at ``32·m`` lags, beyond which ``R_k²`` (decaying as k⁻⁴ at
worst, for odd α) changes ν by less than 6e−6 (measured: FFM, n = 50000). For
m > :data:`M_EXACT` the EDF is that at m = :data:`M_EXACT` with the same ratio n/m,
interpolated linearly between whole numbers of terms (the terms' correlation,
measured in units of m, has converged there): against the full computation at
m = 65 … 512 it is within 0.1 % once n ≥ m and within 1.4 % for fewer terms (WPM,
2 … 10 terms, where ν < 4 anyway). Each (α, m, N) therefore costs one FFT of at
most 2¹⁵ points, whatever the record length; results are cached.

References
----------
F. Vernotte, M. Lenczner, P.-Y. Bourgeois, E. Rubiola, "The parabolic variance
(PVAR): a wavelet variance based on the least-square fit", IEEE TUFFC 63(4),
611–623 (2016). N. J. Kasdin & T. Walter, Proc. IEEE FCS (1992) 274–283.
C. A. Greenhall & W. J. Riley, "Uncertainty of stability variances based on
finite differences", Proc. 35th PTTI (2003) (ν = 2E²/Var for quadratic forms).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import ParameterError

__all__ = ["PDEV_ALPHAS", "M_EXACT", "pdev_edf", "pdev_edf_array", "pdev_edf_reason", "pdev_edf_scalar", "pdev_terms"]

#: Noise exponents for which PVAR converges (and has an EDF).
PDEV_ALPHAS: tuple[int, ...] = (2, 1, 0, -1, -2)

#: Largest m computed as such; beyond, the EDF at this m with the same n/m.
M_EXACT = 64

#: Lags kept in the variance sum, in units of the filter's half-length m.
_LAG_SPAN = 32

_NAMES = {-4: "RRFM", -3: "FWFM", -2: "RWFM", -1: "FFM", 0: "WFM", 1: "FPM", 2: "WPM"}


def pdev_terms(m: int, n_points: int) -> int:
    """Number n of PVAR terms for ``n_points`` phase points: N − 2 at m = 1, else N − 2m."""
    return n_points - 2 if m == 1 else n_points - 2 * m


def _check_args(alpha: object, m: object, n_points: object) -> tuple[int, int, int]:
    if isinstance(alpha, (bool, np.bool_)):
        raise ParameterError(f"alpha={alpha!r} must be an integer noise exponent in {list(PDEV_ALPHAS)}")
    try:
        a = float(alpha)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"alpha={alpha!r} must be an integer noise exponent in {list(PDEV_ALPHAS)}") from None
    if not a.is_integer() or int(a) not in PDEV_ALPHAS:
        name = f" ({_NAMES[int(a)]}): PVAR diverges" if a.is_integer() and int(a) in _NAMES else ""
        raise ParameterError(f"alpha={alpha!r}{name}; pdev has an EDF for alpha in {list(PDEV_ALPHAS)}")
    return int(a), _check_count(m, "m", 1), _check_count(n_points, "N", 1)


def _check_count(value: object, name: str, least: int) -> int:
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} must be an integer >= {least}")
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} must be an integer >= {least}") from None
    if not v.is_integer() or v < least:
        raise ParameterError(f"{name}={value!r} must be an integer >= {least}")
    return int(v)


def _filter_response(m: int, omega: np.ndarray, grid: int) -> np.ndarray:
    """``|W(ω)|²`` of the PVAR term on phase at the midpoints ``ω_j = (j+½)π/grid``."""
    s = 2.0 * np.sin(0.5 * omega)
    if m == 1:
        return s**4
    k = np.arange(m)
    c = (m - 1) / 2.0 - k
    # C(ω_j) = Σ_k c_k e^{−ikω_j}: one FFT of c_k e^{−ikπ/(2·grid)}, length 2·grid.
    a = np.zeros(2 * grid, dtype=complex)
    a[:m] = c * np.exp(-1j * k * (math.pi / (2.0 * grid)))
    cw = np.fft.fft(a)[:grid]
    t = 2.0 * np.sin(0.5 * m * omega)
    return (cw.real**2 + cw.imag**2) * t * t


@functools.lru_cache(maxsize=4096)
def _edf_exact(alpha: int, m: int, n: int) -> float:
    """ν for n terms at factor m (no cap on m): the quadratic-form formula above."""
    if n == 1:
        return 1.0
    lags = min(n - 1, _LAG_SPAN * m)
    grid = 1 << max(10, int(math.ceil(math.log2(4 * (2 * m + lags + 1)))))
    omega = (np.arange(grid) + 0.5) * (math.pi / grid)
    spec = (2.0 * np.sin(0.5 * omega)) ** (alpha - 2) * _filter_response(m, omega, grid)
    from scipy import fft  # heavy; only here

    r = fft.dct(spec, type=2)[: lags + 1]
    k = np.arange(1, lags + 1)
    tail = float(np.sum((n - k) * r[1:] ** 2))
    return float((n * r[0]) ** 2 / (n * r[0] ** 2 + 2.0 * tail))


def pdev_edf_scalar(alpha: int, m: int, n_points: int) -> tuple[float, str]:
    """``(ν, "")`` or ``(nan, reason)`` for checked arguments (α in :data:`PDEV_ALPHAS`, m ≥ 1, N ≥ 1).

    The form :func:`sigmatau.uncertainty.confidence.edf` dispatches to.
    """
    n = pdev_terms(m, n_points)
    if n < 1:
        need = 3 if m == 1 else 2 * m + 1
        return math.nan, f"N={n_points} phase points is fewer than the {need} pdev needs at m={m}"
    if m <= M_EXACT:
        return _edf_exact(alpha, m, n), ""
    # Same n/m at m = M_EXACT (the correlation of the terms scales with m), linear
    # in n between the two whole numbers of terms around n·M_EXACT/m.
    n_eq = max(1.0, n * M_EXACT / m)
    lo = int(math.floor(n_eq))
    nu_lo = _edf_exact(alpha, M_EXACT, lo)
    if n_eq == lo:
        return nu_lo, ""
    nu_hi = _edf_exact(alpha, M_EXACT, lo + 1)
    return nu_lo + (n_eq - lo) * (nu_hi - nu_lo), ""


def pdev_edf(alpha: int, m: int, n_points: int) -> float:
    """Equivalent degrees of freedom of PVAR at factor ``m`` for ``n_points`` phase points.

    Parameters
    ----------
    alpha : int
        Power-law noise exponent of S_y(f) ∝ f^α, one of 2, 1, 0, −1, −2.
    m : int
        Averaging factor (τ = m·τ0).
    n_points : int
        Number of phase points N (frequency samples + 1).

    Returns
    -------
    float
        ν, or NaN when N is too short for a single term (N < 2m + 1).

    Raises
    ------
    ParameterError
        For an α for which PVAR diverges or a non-integer argument.

    Notes
    -----
    Exact for the discrete power-law process up to m = :data:`M_EXACT` (module
    docstring); one term gives ν = 1 exactly.

    Examples
    --------
    >>> round(pdev_edf(0, 1, 1001), 1)            # white FM, m = 1 (AVAR)
    666.2
    >>> pdev_edf(2, 500, 1001)                    # a single term
    1.0
    """
    a, mm, N = _check_args(alpha, m, n_points)
    return pdev_edf_scalar(a, mm, N)[0]


def pdev_edf_reason(alpha: int, m: int, n_points: int) -> str:
    """Why :func:`pdev_edf` is NaN for these arguments, ``""`` when it is not.

    Examples
    --------
    >>> pdev_edf_reason(0, 501, 1001)
    'N=1001 phase points is fewer than the 1003 pdev needs at m=501'
    """
    a, mm, N = _check_args(alpha, m, n_points)
    return pdev_edf_scalar(a, mm, N)[1]


def pdev_edf_array(alpha: object, ms: object, n_points: int) -> np.ndarray:
    """:func:`pdev_edf` over averaging factors ``ms`` (``alpha`` one value or one per factor).

    Examples
    --------
    >>> pdev_edf_array(2, [2, 4], 1001).round(1).tolist()
    [570.2, 351.0]
    """
    try:
        a_arr, m_arr = np.broadcast_arrays(np.asarray(alpha), np.asarray(ms))
    except ValueError:
        raise ParameterError(f"alpha (shape {np.shape(alpha)}) and ms (shape {np.shape(ms)}) do not broadcast") from None
    if m_arr.ndim > 1:
        raise ParameterError(f"ms must be a scalar or 1-D, got shape {m_arr.shape}")
    out = [pdev_edf(a, v, n_points) for a, v in zip(a_arr.ravel().tolist(), m_arr.ravel().tolist())]
    return np.array(out, dtype=float).reshape(m_arr.shape)
