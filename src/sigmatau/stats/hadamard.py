"""Hadamard family: HDEV (non-overlapped) and OHDEV (overlapped).

Third differences of the phase remove a linear frequency drift, so these
converge for noise down to random-run FM (α > −5).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..core.accel import twin
from ..core.driver import Statistic
from ..core.taus import STOP_RATIOS
from .engine import run
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod
from ..uncertainty.confidence import ONE_SIGMA
from ..core.numeric import sumsq_combination
from ..core.gaps import block_kernel, point_kernel
from ..core.kernels import block_sums_by_factor, window_sums_by_factor
from .allan import _doc
from ..core.result import StabilityResult

__all__ = ["hdev", "ohdev"]


def _hvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        xs = x[: ((x.size - 1) // m) * m + 1 : m]
        k = xs.size - 3
        terms = [(1.0, xs[3:]), (-3.0, xs[2:-1]), (3.0, xs[1:-2]), (-1.0, xs[:-3])]
        var[i] = sumsq_combination(terms, k) / (6.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


@twin("ohvar_phase")
def _ohvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = x.size - 3 * m
        terms = [(1.0, x[3 * m :]), (-3.0, x[2 * m : -m]), (3.0, x[m : -2 * m]), (-1.0, x[: -3 * m])]
        var[i] = sumsq_combination(terms, k) / (6.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


def _hvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, b in block_sums_by_factor(y, ms):
        k = b.size - 2
        var[i] = sumsq_combination([(1.0, b[2:]), (-2.0, b[1:-1]), (1.0, b[:-2])], k) / (6.0 * float(m) ** 2 * k)
        n[i] = k
    return var, n


@twin("ohvar_freq")
def _ohvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # Σ_{i=j}^{j+m-1} (y_{i+2m} - 2y_{i+m} + y_i) = A_m[j+2m] - 2A_m[j+m] + A_m[j] = Δ³_m x_j / τ0
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in window_sums_by_factor(y, ms):
        a = ws.a
        k = y.size - 3 * m + 1
        var[i] = sumsq_combination([(1.0, a[2 * m :]), (-2.0, a[m:-m]), (1.0, a[: -2 * m])], k) / (
            6.0 * float(m) ** 2 * k
        )
        n[i] = k
    return var, n


HVAR = Statistic("hdev", _hvar_kernel, max_m=lambda n: (n - 1) // 3, stop_ratio=STOP_RATIOS["hdev"], min_points=4,
                 compute_freq=_hvar_freq, phase_gaps=point_kernel((-1.0, 3.0, -3.0, 1.0), 6.0, blocks=True),
                 freq_gaps=block_kernel((1.0, -2.0, 1.0), 6.0))
OHVAR = Statistic("ohdev", _ohvar_kernel, max_m=lambda n: (n - 1) // 3, stop_ratio=STOP_RATIOS["ohdev"], min_points=4,
                  compute_freq=_ohvar_freq, phase_gaps=point_kernel((-1.0, 3.0, -3.0, 1.0), 6.0))


@_doc
def hdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Non-overlapped Hadamard deviation (HVAR).

    {common}
    Notes
    -----
    With ``K = ⌊(N-1)/m⌋``,

    .. math:: H σ_y^2(τ) = \\frac{1}{6τ^2(K-2)} \\sum_{k=0}^{K-3}
              (x_{(k+3)m} - 3x_{(k+2)m} + 3x_{(k+1)m} - x_{km})^2 ,

    ``n = K - 2``. The standard 1/6 normalisation makes HVAR equal AVAR for
    white FM; the design tip's code uses ½ (a factor 3 in variance).

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.8; numerics.md §1.6.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 4) for d in sigmatau.hdev(y, m=[1, 2]).dev]
    [70.8061, 116.798]
    """
    return run(HVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def ohdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Overlapped Hadamard deviation (OHVAR).

    {common}
    Notes
    -----
    .. math:: H σ_y^2(τ) = \\frac{1}{6τ^2(N-3m)} \\sum_{i=0}^{N-3m-1}
              (x_{i+3m} - 3x_{i+2m} + 3x_{i+m} - x_i)^2 ,

    ``n = N - 3m``; O(N) per τ. SP1065's tables list this value under "HDEV".

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.9; numerics.md §1.7.

    Examples
    --------
    >>> import sigmatau
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in sigmatau.ohdev(y, m=[1, 2]).dev]
    [70.80607, 85.61487]
    """
    return run(OHVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
