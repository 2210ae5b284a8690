"""Parabolic deviation PDEV (the square root of PVAR, Vernotte et al. 2016).

PVAR compares the least-squares frequency estimates of two adjacent windows of
m phase points, so it rejects white phase noise like MVAR (slope τ⁻³) while its
response to the FM noise types stays close to AVAR's; it converges for
α > −3 (WPM … RWFM).

The least-squares slope of a window is a parabola-weighted mean of the
frequency samples in it. Its three moment sums are carried from one window
length to the next by exact doubling and unit-step recurrences (as the window
sums of :class:`sigmatau.core.numeric.WindowSums`), so each value is a sum of
about 2·log2(m) terms of its own size instead of a difference of two running
sums of the record: O(N) per factor on an octave or dense grid, O(N log m) at
worst, never O(N·m).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..core.driver import Statistic
from ..core.numeric import CHUNK, sumsq_combination
from ..core.result import StabilityResult
from ..core.taus import STOP_RATIOS
from ..core.validate import DataType
from ..errors import ParameterError
from ..uncertainty.attach import CiMethod
from ..uncertainty.confidence import ONE_SIGMA
from .allan import _doc
from .engine import run

__all__ = ["pdev", "PVAR", "PDEV_STOP_RATIO"]

#: Keyword grids end at m ≤ ⌊N/4⌋, N phase points: Stable32's ratio for the other
#: overlapped two-window statistics (OADEV, MDEV). Explicit factors may go up to
#: ⌊(N−1)/2⌋, one term, as SigmaTheta does (its last factor is N/2).
PDEV_STOP_RATIO = STOP_RATIOS["pdev"]


class _ParabolicSums:
    """Moment sums of the frequency samples over sliding windows of length w.

    For ``y_0 … y_{M-1}`` and ``c_w = (w−1)/2`` the window centre, it holds for
    ``j = 0 … M−w``: ``A[j] = Σ_{k<w} y_{j+k}``, ``C1[j] = Σ_{k<w} (k − c_w) y_{j+k}``,
    ``C2[j] = Σ_{k<w} (k − c_w)² y_{j+k}``. Moving the window length:

    * doubling (the two halves sit at ∓w/2 from the new centre):
      ``C2' = C2[j] − w·C1[j] + w²/4·A[j] + C2[j+w] + w·C1[j+w] + w²/4·A[j+w]``,
      ``C1' = C1[j] − w/2·A[j] + C1[j+w] + w/2·A[j+w]``, ``A' = A[j] + A[j+w]``;
    * unit step (the centre moves by ½, the new sample sits at w/2):
      ``C2' = C2 − C1 + A/4 + w²/4·y_{j+w}``, ``C1' = C1 − A/2 + w/2·y_{j+w}``,
      ``A' = A + y_{j+w}``.

    Updates run in place in increasing j, chunk by chunk: position j reads only
    positions ≥ j, not yet overwritten.
    """

    def __init__(self, y: np.ndarray) -> None:
        self._y = y
        self.a = y.copy()
        self.c1 = np.zeros(y.size)
        self.c2 = np.zeros(y.size)
        self.w = 1
        size = min(CHUNK, y.size)
        self._t = np.empty(size)
        self._u = np.empty(size)
        self.means: Optional[np.ndarray] = None
        self._steps = 0

    #: Unit steps in a row before restarting from the samples (each adds a rounding).
    MAX_STEPS = 8

    def advance(self, w: int) -> None:
        """Move to window length ``w``: through its binary digits when the current length is a
        prefix of them (the octave grid: one doubling and one step), by a few unit steps when
        it is just below (dense grids), else from the samples again."""
        if w == self.w:
            return
        bits, here = bin(w)[2:], bin(self.w)[2:]
        if not bits.startswith(here) and self.w < w <= self.w + self.MAX_STEPS - self._steps:
            for _ in range(w - self.w):
                self._step()
            self._steps += w - self.w
            return
        if not bits.startswith(here):
            np.copyto(self.a, self._y)
            self.c1.fill(0.0)
            self.c2.fill(0.0)
            self.w, here = 1, "1"
        for bit in bits[len(here):]:
            self._double()
            if bit == "1":
                self._step()
        self._steps = 0

    def _double(self) -> None:
        w, a, c1, c2 = self.w, self.a, self.c1, self.c2
        n = self._y.size - 2 * w + 1
        half, quarter = 0.5 * w, 0.25 * w * w
        for lo in range(0, max(n, 0), CHUNK):
            hi = min(lo + CHUNK, n)
            t, u = self._t[: hi - lo], self._u[: hi - lo]
            a0, a1 = a[lo:hi], a[lo + w: hi + w]
            p0, p1 = c1[lo:hi], c1[lo + w: hi + w]
            # c2 ← (c2[j] + c2[j+w]) + w·(c1[j+w] − c1[j]) + w²/4·(a[j] + a[j+w])
            np.subtract(p1, p0, out=t)
            t *= w
            np.add(c2[lo:hi], c2[lo + w: hi + w], out=u)
            u += t
            np.add(a0, a1, out=t)
            t *= quarter
            np.add(u, t, out=c2[lo:hi])
            # c1 ← (c1[j] + c1[j+w]) + w/2·(a[j+w] − a[j]); then a ← a[j] + a[j+w]
            np.subtract(a1, a0, out=t)
            t *= half
            np.add(p0, p1, out=u)
            np.add(u, t, out=p0)
            np.add(a0, a1, out=a0)
        self.w = 2 * w

    def _step(self) -> None:
        w, a, c1, c2, y = self.w, self.a, self.c1, self.c2, self._y
        n = y.size - w
        for lo in range(0, max(n, 0), CHUNK):
            hi = min(lo + CHUNK, n)
            t = self._t[: hi - lo]
            new = y[lo + w: hi + w]
            a0, p0, q0 = a[lo:hi], c1[lo:hi], c2[lo:hi]
            # c2 ← (c2 − c1 + a/4) + w²/4·y[j+w]; c1 ← (c1 − a/2) + w/2·y[j+w]; a ← a + y[j+w]
            q0 -= p0
            np.multiply(a0, 0.25, out=t)
            q0 += t
            np.multiply(new, 0.25 * w * w, out=t)
            q0 += t
            np.multiply(a0, 0.5, out=t)
            p0 -= t
            np.multiply(new, 0.5 * w, out=t)
            p0 += t
            a0 += new
        self.w = w + 1


def _parabolic_means(sums: _ParabolicSums, m: int) -> np.ndarray:
    """``U_j = ½ Σ_{k=0}^{m−2} (k+1)(m−1−k) y_{j+k}`` for j = 0 … M−m+1 (window w = m − 1).

    With u = k − (m−2)/2 the weight is (m/2)² − u², so ``U = ½((m/2)²·A − C2)``.
    """
    count = sums._y.size - (m - 1) + 1
    if sums.means is None:
        # One buffer for every factor: a fresh record-sized array per τ costs more in
        # page faults than the arithmetic.
        sums.means = np.empty(sums._y.size)
    u = sums.means[:count]
    for lo in range(0, count, CHUNK):
        hi = min(lo + CHUNK, count)
        np.multiply(sums.a[lo:hi], 0.25 * m * m, out=u[lo:hi])
        u[lo:hi] -= sums.c2[lo:hi]
        u[lo:hi] *= 0.5
    return u


def _pvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    """PVAR from frequency samples y (M = N − 1 of them), in y²."""
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    sums: Optional[_ParabolicSums] = None
    for i in np.argsort(ms, kind="stable"):
        m = int(ms[i])
        if m == 1:
            # No window to fit: PVAR(τ0) is AVAR(τ0) (Vernotte et al. 2016, §II).
            k = y.size - 1
            var[i] = sumsq_combination([(1.0, y[1:]), (-1.0, y[:-1])], k) / (2.0 * k)
            n[i] = k
            continue
        if sums is None:
            sums = _ParabolicSums(y)
        sums.advance(m - 1)
        u = _parabolic_means(sums, m)
        k = y.size + 1 - 2 * m  # N − 2m terms, as SigmaTheta and Vernotte et al. (2020)
        var[i] = 72.0 * sumsq_combination([(1.0, u[m:]), (-1.0, u[:-m])], k) / (float(m) ** 6 * k)
        n[i] = k
    return var, n


def _pvar_phase(x: np.ndarray, ms: np.ndarray, tau0: float):
    # The phase steps are the frequency samples: the same sums without integrating.
    return _pvar_freq(np.diff(x) / tau0, ms, tau0)


PVAR = Statistic("pdev", _pvar_phase, max_m=lambda n: (n - 1) // 2, stop_ratio=PDEV_STOP_RATIO, min_points=3,
                 compute_freq=_pvar_freq)


@_doc
def pdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Parabolic deviation (PDEV, the square root of PVAR).

    {common}
    Notes
    -----
    With N phase points x_k, τ = mτ0 and ``c_k = (m−1)/2 − k``,

    .. math:: \\mathrm{PVAR}(τ) = \\frac{72}{n\\,m^4 τ^2} \\sum_{i=0}^{n-1}
              \\Big[\\sum_{k=0}^{m-1} c_k\\,(x_{i+k} - x_{i+m+k})\\Big]^2 ,
              \\qquad n = N - 2m ,

    for m ≥ 2, and PVAR(τ0) = AVAR(τ0) (``n = N − 2``). Each inner sum is
    (m³τ0/12 times) the difference of the least-squares frequencies of the windows
    ``x_i … x_{i+m−1}`` and ``x_{i+m} … x_{i+2m−1}``, i.e. of parabola-weighted
    means of the frequency samples. The sum stops at ``i = N − 2m − 1``, one term
    short of the last full pair of windows, as in SigmaTheta (whose values this
    reproduces) and Vernotte et al. (2020).

    Expectations (continuous model, h_α of S_y(f) = h_α f^α): WPM
    ``3h₂/(2π²τ³)``, WFM ``3h₀/(5τ)``; on discrete samples (variance σ²) white
    PM gives ``12σ²(m²−1)/(m³τ²)`` and white FM ``(6/5)σ_y²(1 − m⁻⁴)/m``.

    Keyword grids stop at ``m ≤ N/4`` (:data:`PDEV_STOP_RATIO`); explicit ``m`` may
    go up to ``(N−1)/2`` (a single term; SigmaTheta's last factor) with a
    RangeWarning. Gaps: the estimator is evaluated on each gap-free run and pooled
    (:func:`sigmatau.core.gaps.pooled_over_runs`), as MDEV. The EDF is exact for
    discrete power-law noise (:mod:`sigmatau.uncertainty.pdev_edf`); the noise type
    is identified as for MDEV.

    References
    ----------
    F. Vernotte, M. Lenczner, P.-Y. Bourgeois, E. Rubiola, "The parabolic
    variance (PVAR): a wavelet variance based on the least-square fit", IEEE
    TUFFC 63(4), 611–623 (2016); F. Vernotte, S. Chen, E. Rubiola, "Response and
    uncertainty of the parabolic variance PVAR to non-white frequency noise",
    Metrologia (2020).

    Examples
    --------
    >>> from sigmatau.stats.parabolic import pdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in pdev(y, m=[1, 2], ci=None).dev]
    [91.22945, 87.60538]
    """
    if alpha is not None and not isinstance(alpha, bool) and alpha in (-3, -4):
        raise ParameterError(f"alpha={alpha!r}: PVAR diverges for FWFM and RRFM; pdev takes alpha from -2 to 2")
    return run(PVAR, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
               alpha=alpha, confidence=confidence, ci=ci)
