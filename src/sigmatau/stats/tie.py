"""Time-error statistics: MTIE and TIE rms.

Both work on the phase (time-error) series itself, not on its differences
alone, so a frequency offset is part of what they measure: the driver keeps
the phase as given (frequency data are integrated from x_0 = 0) instead of
removing the linear trend.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..core.driver import Statistic
from ..core.gaps import point_kernel
from .engine import run
from ..core import numeric as _numeric
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod
from .allan import _doc
from ..uncertainty.confidence import ONE_SIGMA
from ..core.result import StabilityResult

__all__ = ["mtie", "tierms"]


class _RunningExtremes:
    """Maximum and minimum of every window of m + 1 consecutive points, for growing m.

    ``hi[i] = max(x_i … x_{i+m})`` and ``lo[i]`` likewise, for i = 0 … N-1-m,
    are kept in two record-sized buffers. A factor twice the current one is
    reached in place by the binary decomposition of Bregni & Maccabruni (a
    window of 2m + 1 points is the union of two windows of m + 1 points sharing
    their middle point), O(N) per octave; any other factor is built afresh by
    van Herk / Gil–Werman running extremes, O(N), block row by block row.
    Nothing else of the record's size is allocated.
    """

    def __init__(self, x: np.ndarray, chunk: Optional[int] = None) -> None:
        chunk = chunk or _numeric.CHUNK
        self._x = x
        self._chunk = chunk
        self.hi = np.empty(x.size)
        self.lo = np.empty(x.size)
        self._tmp = np.empty(min(chunk, x.size))
        self.m = 0

    def advance(self, m: int) -> None:
        q, r = divmod(m, self.m) if self.m else (0, 1)
        if r == 0 and q >= 1 and q & (q - 1) == 0:
            while self.m < m:
                self._double()
        else:
            self._build(m)

    def mtie(self) -> float:
        """``max_i (hi[i] − lo[i])`` over the N − m windows."""
        n = self._x.size - self.m
        best = -np.inf
        for lo in range(0, n, self._chunk):
            hi = min(lo + self._chunk, n)
            t = self._tmp[: hi - lo]
            np.subtract(self.hi[lo:hi], self.lo[lo:hi], out=t)
            best = max(best, float(t.max()))
        return best

    def _double(self) -> None:
        m, C = self.m, self._chunk
        n = self._x.size - 2 * m  # windows of 2m + 1 points
        for arr, op in ((self.hi, np.maximum), (self.lo, np.minimum)):
            for lo in range(0, n, C):
                hi = min(lo + C, n)
                if hi - lo <= m:
                    op(arr[lo:hi], arr[lo + m : hi + m], out=arr[lo:hi])
                else:
                    t = self._tmp[: hi - lo]
                    op(arr[lo:hi], arr[lo + m : hi + m], out=t)
                    arr[lo:hi] = t
        self.m = 2 * m

    def _build(self, m: int) -> None:
        x, w = self._x, m + 1
        N = x.size
        count = N - m
        # Block rows of w points: a window starting in row r ends in row r + 1, so its
        # extreme is max(suffix extreme of row r from i, prefix extreme of row r + 1 to i + m).
        rows = max(1, self._chunk // w)
        for s0 in range(0, count, rows * w):
            nr = min(rows, -(-(count - s0) // w))  # rows of window starts in this group
            seg = x[s0 : s0 + (nr + 1) * w]
            for arr, acc, fill in ((self.hi, np.maximum, -np.inf), (self.lo, np.minimum, np.inf)):
                blocks = np.full((nr + 1) * w, fill)
                blocks[: seg.size] = seg
                blocks = blocks.reshape(nr + 1, w)
                suf = acc.accumulate(blocks[:-1, ::-1], axis=1)[:, ::-1]
                pre = acc.accumulate(blocks[1:], axis=1)
                ext = suf.copy()
                acc(suf[:, 1:], pre[:, :-1], out=ext[:, 1:])
                k = min(nr * w, count - s0)
                arr[s0 : s0 + k] = ext.ravel()[:k]
        self.m = m


def _mtie_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    N = x.size
    var = np.empty(ms.size)
    ext = _RunningExtremes(x)
    for k in np.argsort(ms, kind="stable"):
        ext.advance(int(ms[k]))
        var[k] = ext.mtie() ** 2
    return var, N - ms


def _tierms_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    for k, m in enumerate(ms):
        d = x[m:] - x[:-m]
        var[k] = float(np.einsum("i,i->", d, d)) / d.size
    return var, x.size - ms


MTIE = Statistic(
    "mtie", _mtie_kernel, max_m=lambda n: n - 1, stop_ratio=2, min_points=3, trend_invariant=False, pooling="max",
    min_run_points=2,
)
TIERMS = Statistic(
    "tierms", _tierms_kernel, max_m=lambda n: n - 1, stop_ratio=4, min_points=3, trend_invariant=False,
    phase_gaps=point_kernel((-1.0, 1.0), 1.0, per_tau=False), min_run_points=2,
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

    >>> import sigmatau
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.mtie(nbs1000(), m=[1, 10, 100])
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
    >>> import sigmatau
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.tierms(nbs1000(), m=[1, 10, 100])
    >>> [float(f"{d:.6e}") for d in r.dev]
    [0.5683385, 4.975004, 49.42407]
    """
    return run(TIERMS, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
