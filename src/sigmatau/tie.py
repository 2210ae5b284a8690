"""Time-error statistics: MTIE and TIE rms.

Both work on the phase (time-error) series itself, not on its differences
alone, so a frequency offset is part of what they measure: the driver keeps
the phase as given (frequency data are integrated from x_0 = 0) instead of
removing the linear trend.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ._driver import Statistic, run
from ._input import DataType
from ._uncertainty import CiMethod
from .allan import _doc
from .confidence import ONE_SIGMA
from .result import StabilityResult

__all__ = ["mtie", "tierms"]


def _window_extremes(x: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Maximum and minimum of every window of ``w`` consecutive points, in O(N).

    van Herk / Gil–Werman: cut the series into blocks of ``w``; a window starting
    at i ends in the next block, so its extreme combines the running extreme
    from i to the end of i's block with the running extreme from the start of
    the next block to i + w - 1.
    """
    N = x.size
    count = N - w + 1
    nb = -(-N // w)
    pad = nb * w - N
    hi = np.concatenate((x, np.full(pad, -np.inf))).reshape(nb, w)
    lo = np.concatenate((x, np.full(pad, np.inf))).reshape(nb, w)
    pre_hi = np.maximum.accumulate(hi, axis=1).ravel()
    suf_hi = np.maximum.accumulate(hi[:, ::-1], axis=1)[:, ::-1].ravel()
    pre_lo = np.minimum.accumulate(lo, axis=1).ravel()
    suf_lo = np.minimum.accumulate(lo[:, ::-1], axis=1)[:, ::-1].ravel()
    wmax = np.maximum(suf_hi[:count], pre_hi[w - 1 : w - 1 + count])
    wmin = np.minimum(suf_lo[:count], pre_lo[w - 1 : w - 1 + count])
    return wmax, wmin


def _mtie_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    N = x.size
    var = np.empty(ms.size)
    for k, m in enumerate(ms):
        wmax, wmin = _window_extremes(x, int(m) + 1)
        var[k] = float(np.max(wmax - wmin)) ** 2
    return var, N - ms


def _tierms_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    for k, m in enumerate(ms):
        d = x[m:] - x[:-m]
        var[k] = float(np.einsum("i,i->", d, d)) / d.size
    return var, x.size - ms


MTIE = Statistic(
    "mtie", _mtie_kernel, max_m=lambda n: n - 1, stop_ratio=2, min_points=3, trend_invariant=False,
)
TIERMS = Statistic(
    "tierms", _tierms_kernel, max_m=lambda n: n - 1, stop_ratio=4, min_points=3, trend_invariant=False,
)


@_doc
def mtie(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Maximum time interval error (MTIE), in the unit of the phase data.

    {common}
    Notes
    -----
    For an observation interval τ = n·τ0 (windows of n + 1 phase points),

    .. math:: \\mathrm{MTIE}(nτ_0) = \\max_{0 ≤ k ≤ N-1-n}
              \\Big[\\max_{k ≤ i ≤ k+n} x_i - \\min_{k ≤ i ≤ k+n} x_i\\Big] ,

    with ``1 ≤ n ≤ N−1``. ``result.dev`` is the MTIE and ``result.var`` its
    square; ``n = N − m`` (the count printed by Stable32). MTIE is an extreme
    value, so no χ² confidence interval applies.

    MTIE is **not** invariant to a frequency offset: it grows linearly with τ
    for a constant offset. Frequency data are integrated as given (from
    x_0 = 0); remove the mean frequency first if the noise alone is wanted.
    Keyword grids stop at N/2 (Stable32 stop ratio 2); Stable32's "MTIE (Fast)"
    runs use the factors 2^k − 1, which can be passed as ``m``.

    Cost: O(N) per τ (van Herk–Gil-Werman running extremes, vectorised).

    References
    ----------
    ITU-T Rec. G.810, "Definitions and terminology for synchronization
    networks" (1996); W. J. Riley, NIST SP 1065 (2008); S. Bregni &
    S. Maccabruni, "Fast computation of maximum time interval error by binary
    decomposition", IEEE TIM 49(6), 2000; M. van Herk, Pattern Recognition
    Letters 13 (1992) and J. Gil & M. Werman, IEEE PAMI 15(5) (1993) (running
    extremes); numerics.md §1.15, §4.

    Examples
    --------
    The NBS frequency set integrated from 0 (its mean frequency, 0.49, dominates):

    >>> import sigmatau.tie
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.tie.mtie(nbs1000(), m=[1, 10, 100])
    >>> [float(f"{d:.6e}") for d in r.dev], r.n.tolist()
    ([0.9957453, 7.59656, 55.38177], [1000, 991, 901])
    """
    return run(MTIE, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)


@_doc
def tierms(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """RMS time interval error (TIE rms), in the unit of the phase data.

    {common}
    Notes
    -----
    .. math:: \\mathrm{TIE_{rms}}(nτ_0) = \\sqrt{\\frac{1}{N-n}
              \\sum_{i=0}^{N-n-1} (x_{i+n} - x_i)^2} ,

    ``result.dev`` is TIE rms, ``result.var`` its square and ``n = N − m``. The
    time-interval errors are not centred, so a frequency offset adds
    ``(offset·τ)²`` to the variance: TIE rms is not invariant to it. Frequency
    data are integrated as given. Keyword grids stop at N/4 (Stable32 stop
    ratio 4). O(N) per τ.

    References
    ----------
    ITU-T Rec. G.810 (1996); W. J. Riley, NIST SP 1065 (2008); numerics.md §1.15.

    Examples
    --------
    >>> import sigmatau.tie
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.tie.tierms(nbs1000(), m=[1, 10, 100])
    >>> [float(f"{d:.6e}") for d in r.dev]
    [0.5683385, 4.975004, 49.42407]
    """
    return run(TIERMS, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
