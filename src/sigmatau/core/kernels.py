"""Kernels of the Allan family: (phase x or frequency y, factors, τ0) -> (variance, terms).

STDVAR, OSTDVAR, AVAR, OAVAR, MVAR and TVAR are described here, below the
statistics layer, because noise identification needs two of them (R(n) is
MVAR/OAVAR, numerics.md §5.4) and sits below the public statistics that attach
it; :mod:`sigmatau.stats.allan` holds the public functions. The block and
window sums by factor are shared with the Hadamard kernels. Every kernel is held
to the filter-chain definitions (:mod:`sigmatau.stats.filterchain`) by the tests.
"""

from __future__ import annotations

import numpy as np

from .accel import twin
from .driver import Statistic
from .gaps import block_kernel, point_kernel, window_mean_kernel
from .taus import STOP_RATIOS
from .numeric import WindowSums, centred_sumsq, doublings_only, sumsq, sumsq_combination

__all__ = [
    "STDVAR", "OSTDVAR", "AVAR", "OAVAR", "MVAR", "TVAR",
    "oavar_kernel", "block_sums_by_factor", "window_sums_by_factor",
]


# --- kernels: (phase x, factors, τ0) -> (variance, number of terms) ---------------
#
# Sums of squares go through sumsq_combination, which forms the differences chunk
# by chunk: a record-sized temporary per τ costs more in page faults than the
# arithmetic itself at N = 10^6.


def _stdvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = (x.size - 1) // m
        xs = x[: k * m + 1 : m]
        _, ss = centred_sumsq(xs[1:] - xs[:-1])
        var[i] = ss / ((m * tau0) ** 2 * (k - 1))
        n[i] = k
    return var, n


def _ostdvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    buf = np.empty(x.size - 1)
    for i, m in enumerate(ms):
        k = x.size - m
        means = buf[:k]
        np.subtract(x[m:], x[:-m], out=means)
        _, ss = centred_sumsq(means)
        var[i] = ss / ((m * tau0) ** 2 * (k - 1))
        n[i] = k
    return var, n


def _avar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        xs = x[: ((x.size - 1) // m) * m + 1 : m]
        k = xs.size - 2
        var[i] = sumsq_combination([(1.0, xs[2:]), (-2.0, xs[1:-1]), (1.0, xs[:-2])], k) / (2.0 * (m * tau0) ** 2 * k)
        n[i] = k
    return var, n


@twin("oavar_phase")
def oavar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        k = x.size - 2 * m
        var[i] = sumsq_combination([(1.0, x[2 * m :]), (-2.0, x[m:-m]), (1.0, x[: -2 * m])], k) / (
            2.0 * (m * tau0) ** 2 * k
        )
        n[i] = k
    return var, n


def _mvar_sums(x: np.ndarray, m: int) -> np.ndarray:
    """Inner sums ``Σ_{i=j}^{j+m-1} Δ²_m x_i`` for j = 0 … N-3m, in O(N).

    A running sum over the second differences themselves (not over x) keeps
    the cumulative sum of the size of the result, so no digits are lost to
    cancellation even for random-run phase.
    """
    d2 = x[2 * m :] - 2.0 * x[m:-m] + x[: -2 * m]
    c = np.concatenate(([0.0], np.cumsum(d2)))
    return c[m:] - c[:-m]


@twin("mvar_phase")
def _mvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        s = _mvar_sums(x, int(m))
        var[i] = sumsq(s) / (2.0 * m**2 * (m * tau0) ** 2 * s.size)
        n[i] = s.size
    return var, n


def _tvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mvar_kernel(x, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


# --- kernels on frequency samples y (mean removed): no integration, so no phase
# round-off; each is algebraically identical to its phase kernel above. The
# window sums A_m (and the double sums B_m of MVAR) are carried from one factor
# to the next by WindowSums: one pass over the record per octave step. ----------


def block_sums_by_factor(y: np.ndarray, ms: np.ndarray):
    """Yield ``(index, m, sums)`` over ``ms`` in increasing order; ``sums`` are the
    ⌊M/m⌋ non-overlapped block sums of m samples from 0. Each factor that is a
    power-of-two multiple of the previous one is reached by pairwise halving,
    O(M/m) per step; any other is summed from the samples."""
    prev_m, prev = 1, y
    for i in np.argsort(ms, kind="stable"):
        m = int(ms[i])
        q, r = divmod(m, prev_m)
        if r == 0 and q & (q - 1) == 0:
            sums = prev
            while q > 1:
                k = sums.size // 2
                sums = sums[0 : 2 * k : 2] + sums[1 : 2 * k : 2]
                q //= 2
        else:
            k = y.size // m
            sums = y[: k * m].reshape(k, m).sum(axis=1)
        prev_m, prev = m, sums
        yield i, m, sums


def window_sums_by_factor(y: np.ndarray, ms: np.ndarray, *, double: bool = False, b_only: bool = False):
    """Yield ``(index, m, ws)`` over ``ms`` in increasing order, ``ws`` a
    :class:`~sigmatau.core.numeric.WindowSums` advanced to m (its arrays are valid until the next step).

    ``b_only`` (with ``double``): the caller reads only the double sums B, so A is freed as soon
    as every factor left is this one times a power of two and m ≥ 4 — from there
    :meth:`~sigmatau.core.numeric.WindowSums.advance` only doubles, with the very operations it
    would use with A kept (a record-sized array less at the peak of MVAR on an octave grid).
    """
    ws = WindowSums(y, double=double)
    order = np.argsort(ms, kind="stable")
    for pos, i in enumerate(order):
        m = int(ms[i])
        ws.advance(m)
        if b_only and double and m >= 4 and doublings_only(m, ms[order[pos + 1:]]):
            ws.release_a()
        yield i, m, ws


def _stdvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, b in block_sums_by_factor(y, ms):
        _, ss = centred_sumsq(b)
        var[i] = ss / (float(m) ** 2 * (b.size - 1))
        n[i] = b.size
    return var, n


def _ostdvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in window_sums_by_factor(y, ms):
        _, ss = centred_sumsq(ws.a)
        var[i] = ss / (float(m) ** 2 * (ws.a.size - 1))
        n[i] = ws.a.size
    return var, n


def _avar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, b in block_sums_by_factor(y, ms):
        k = b.size - 1
        var[i] = sumsq_combination([(1.0, b[1:]), (-1.0, b[:-1])], k) / (2.0 * float(m) ** 2 * k)
        n[i] = k
    return var, n


@twin("oavar_freq")
def _oavar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # Σ_{i=j}^{j+m-1} (y_{i+m} - y_i) = A_m[j+m] - A_m[j] = Δ²_m x_j / τ0, j = 0 … M-2m
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in window_sums_by_factor(y, ms):
        a = ws.a
        k = y.size - 2 * m + 1
        var[i] = sumsq_combination([(1.0, a[m:]), (-1.0, a[:-m])], k) / (2.0 * float(m) ** 2 * k)
        n[i] = k
    return var, n


@twin("mvar_freq")
def _mvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    # Σ_{k=j}^{j+m-1} (A_m[k+m] - A_m[k]) = B_m[j+m] - B_m[j], j = 0 … M-3m+1
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m, ws in window_sums_by_factor(y, ms, double=True, b_only=True):
        b = ws.b
        k = y.size - 3 * m + 2
        var[i] = sumsq_combination([(1.0, b[m:]), (-1.0, b[:-m])], k) / (2.0 * float(m) ** 4 * k)
        n[i] = k
    return var, n


@twin("tvar_freq")
def _tvar_freq(y: np.ndarray, ms: np.ndarray, tau0: float):
    var, n = _mvar_freq(y, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


STDVAR = Statistic("stdev", _stdvar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=STOP_RATIOS["stdev"], min_points=3,
                   compute_freq=_stdvar_freq, phase_gaps=point_kernel((-1.0, 1.0), 1.0, blocks=True, centred=True),
                   freq_gaps=block_kernel((1.0,), 1.0, centred=True))
OSTDVAR = Statistic("ostdev", _ostdvar_kernel, max_m=lambda n: n - 2, stop_ratio=STOP_RATIOS["ostdev"], min_points=3,
                    compute_freq=_ostdvar_freq, phase_gaps=point_kernel((-1.0, 1.0), 1.0, centred=True),
                    freq_gaps=window_mean_kernel())
AVAR = Statistic("adev", _avar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=STOP_RATIOS["adev"], min_points=3,
                 compute_freq=_avar_freq, phase_gaps=point_kernel((1.0, -2.0, 1.0), 2.0, blocks=True),
                 freq_gaps=block_kernel((1.0, -1.0), 2.0))
OAVAR = Statistic("oadev", oavar_kernel, max_m=lambda n: (n - 1) // 2, stop_ratio=STOP_RATIOS["oadev"], min_points=3,
                  compute_freq=_oavar_freq, phase_gaps=point_kernel((1.0, -2.0, 1.0), 2.0))
MVAR = Statistic("mdev", _mvar_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["mdev"], min_points=3, compute_freq=_mvar_freq)
TVAR = Statistic("tdev", _tvar_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["tdev"], min_points=3, compute_freq=_tvar_freq)
