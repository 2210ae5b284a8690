"""The streamed kernels: variance and term count of each chunked statistic at each averaging factor.

``kernel(reader, ms, tau0, L) -> (var, n)``, one phase and one frequency kernel
per statistic (:data:`_KERNELS`), built from the sums of :mod:`.streams`, and
:func:`_plain_variance` that runs them on a record; with missing samples
(NaN), :func:`_gap_variance`: the gap kernels of :data:`_GAP_KERNELS`, or the
ordinary kernels pooled over the gap-free runs (:func:`_pooled_runs`), as the
in-memory gap path (:mod:`sigmatau.core.gaps`) does for each statistic.
"""

from __future__ import annotations

from typing import Callable, Iterator, Optional, Sequence

import numpy as np

from ...core.driver import Statistic, gap_free_runs
from .streams import (_blocks, _block_sums, _Centred, _Detrended, _FiniteSumSq, _Gaps, _GapDetrended, _Integrated,
                      _pairwise_sum, _Prefix, _present_runs, _Series, _Slice, _strided, _SumSq, _window_diff,
                      _window_sums, _windows, _with_history)


# --------------------------------------------------------------------------- kernels
#
# kernel(reader, ms, tau0, L) -> (var, n); the reader holds the phase (trend
# removed) or the centred frequency, as the in-memory kernels receive them.
# Element-wise differences are formed in the in-memory order, (a - 2b) + c,
# which matters only for phase data whose values dwarf their differences.


def _d1(W: list[np.ndarray], k: int) -> np.ndarray:
    """First difference of the windows ``W`` at offset k."""
    return W[k + 1] - W[k]


def _d2(W: list[np.ndarray], k: int) -> np.ndarray:
    """Second difference of the windows ``W`` at offset k, in the in-memory order."""
    return (W[k + 2] - 2.0 * W[k + 1]) + W[k]


def _avar_phase(rd, ms, tau0, L):
    """AVAR from phase: second differences of the samples taken every m."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        count = (rd.n - 1) // m + 1
        acc = _SumSq()
        for xs in _with_history(_strided(rd, m, count, L), 2):
            if xs.size >= 3:
                acc.add((xs[2:] - 2.0 * xs[1:-1]) + xs[:-2])
        k = count - 2
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * k), k
    return var, n


def _hvar_phase(rd, ms, tau0, L):
    """HVAR from phase: third differences of the samples taken every m."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        count = (rd.n - 1) // m + 1
        acc = _SumSq()
        for xs in _with_history(_strided(rd, m, count, L), 3):
            if xs.size >= 4:
                acc.add(((xs[3:] - 3.0 * xs[2:-1]) + 3.0 * xs[1:-2]) - xs[:-3])
        k = count - 3
        var[i], n[i] = acc.total / (6.0 * (m * tau0) ** 2 * k), k
    return var, n


def _avar_freq(rd, ms, tau0, L):
    """AVAR from frequency: first differences of the block sums of m."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for b in _with_history(_block_sums(rd, m, rd.n // m, L), 1):
            if b.size >= 2:
                acc.add(b[1:] - b[:-1])
        k = rd.n // m - 1
        var[i], n[i] = acc.total / (2.0 * float(m) ** 2 * k), k
    return var, n


def _hvar_freq(rd, ms, tau0, L):
    """HVAR from frequency: second differences of the block sums of m."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for b in _with_history(_block_sums(rd, m, rd.n // m, L), 2):
            if b.size >= 3:
                acc.add((b[2:] - 2.0 * b[1:-1]) + b[:-2])
        k = rd.n // m - 2
        var[i], n[i] = acc.total / (6.0 * float(m) ** 2 * k), k
    return var, n


def _oavar_phase(rd, ms, tau0, L):
    """OAVAR from phase: second differences at every start."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 2 * m
        acc = _SumSq()
        for p, l in _blocks(k, L):
            acc.add(_d2(_windows(rd.read, rd.n, p, (0, m, 2 * m), l), 0))
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * k), k
    return var, n


def _ohvar_phase(rd, ms, tau0, L):
    """OHVAR from phase: third differences at every start."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m
        acc = _SumSq()
        for p, l in _blocks(k, L):
            w = _windows(rd.read, rd.n, p, (0, m, 2 * m, 3 * m), l)
            acc.add(((w[3] - 3.0 * w[2]) + 3.0 * w[1]) - w[0])
        var[i], n[i] = acc.total / (6.0 * (m * tau0) ** 2 * k), k
    return var, n


def _oavar_freq(rd, ms, tau0, L):
    # s_j = Σ_{i<m} (y_{j+i+m} - y_{j+i}) = Δ²_m x_j / τ0, j = 0 … M-2m
    """OAVAR from frequency: window sums of first differences."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 2 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d1, 1):
            acc.add(s)
        var[i], n[i] = acc.total / (2.0 * float(m) ** 2 * k), k
    return var, n


def _ohvar_freq(rd, ms, tau0, L):
    # s_j = Σ_{i<m} (y_{j+i+2m} - 2y_{j+i+m} + y_{j+i}) = Δ³_m x_j / τ0, j = 0 … M-3m
    """OHVAR from frequency: window sums of second differences."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d2, 2):
            acc.add(s)
        var[i], n[i] = acc.total / (6.0 * float(m) ** 2 * k), k
    return var, n


def _mvar_phase(rd, ms, tau0, L):
    # s_j = Σ_{i<m} Δ²_m x_{j+i}, j = 0 … N-3m
    """MVAR from phase: window sums of second differences."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d2, 2):
            acc.add(s)
        var[i], n[i] = acc.total / (2.0 * m**2 * (m * tau0) ** 2 * k), k
    return var, n


def _mvar_freq(rd, ms, tau0, L):
    # t_j = Σ_{i<m} s_{j+i}, s the OAVAR window sums of the frequency
    """MVAR from frequency: window sums of the OAVAR window sums (two nested running sums)."""
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 2
        acc = _SumSq()
        if m == 1:
            for t in _window_sums(rd, 1, 0, k, L, _d1, 1):
                acc.add(t)
        else:
            # s_j = P_{j+m} - P_j (P: running sum of v_i = y_{i+m} - y_i), t_j = Q_{j+m} - Q_j
            # (Q: running sum of s); P is needed at j, j+m, j+2m and Q at j, j+m.
            read, size = rd.read, rd.n
            p_chains = [_Prefix(), _Prefix(), _Prefix()]
            for lag in (1, 2):
                for p, l in _blocks(lag * m, L):
                    p_chains[lag].step(_d1(_windows(read, size, p, (0, m), l), 0))
            first, second = _Prefix(), _Prefix()
            second.hi, second.lo = p_chains[1].hi, p_chains[1].lo
            q_ahead, q_behind = _Prefix(), _Prefix()
            for p, l in _blocks(m, L):
                w = _windows(read, size, p, (0, m, 2 * m), l)
                c0, e0 = first.step(_d1(w, 0))
                c1, e1 = second.step(_d1(w, 1))
                q_ahead.step(_window_diff(c1, e1, c0, e0))
            for p, l in _blocks(k, L):
                w = _windows(read, size, p, (0, m, 2 * m, 3 * m), l)
                (c0, e0), (c1, e1), (c2, e2) = (ch.step(_d1(w, lag)) for lag, ch in enumerate(p_chains))
                s0 = _window_diff(c1, e1, c0, e0)
                s1 = _window_diff(c2, e2, c1, e1)
                c0, e0 = q_behind.step(s0)
                c1, e1 = q_ahead.step(s1)
                acc.add(_window_diff(c1, e1, c0, e0))
        var[i], n[i] = acc.total / (2.0 * float(m) ** 4 * k), k
    return var, n


def _tvar(kernel):
    """The TVAR kernel of an MVAR kernel: var · τ² / 3."""
    def tvar(rd, ms, tau0, L):
        var, n = kernel(rd, ms, tau0, L)
        return var * (ms * tau0) ** 2 / 3.0, n
    return tvar


def _totvar_terms(rd, m: int, L: int) -> Iterator[np.ndarray]:
    # Reflected phase x*_{-j} = 2x_0 - x_j, x*_{N-1+j} = 2x_{N-1} - x_{N-1-j};
    # terms i = 1 … N-2: x*_{i-m} - 2x*_i + x*_{i+m}.
    """Blocks of the TOTVAR terms, second differences of the reflected extension at every inner sample."""
    N = rd.n
    two_first = 2.0 * rd.read(0, 1)[0]
    two_last = 2.0 * rd.read(N - 1, N)[0]

    def ext(a: int, b: int) -> np.ndarray:
        parts = []
        if a < 0:
            e = min(b, 0)
            parts.append(two_first - rd.read(1 - e, 1 - a)[::-1])
        if a < N and b > 0:
            parts.append(rd.read(max(a, 0), min(b, N)))
        if b > N:
            s = max(a, N)
            parts.append(two_last - rd.read(2 * N - 1 - b, 2 * N - 1 - s)[::-1])
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    for p, l in _blocks(N - 2, L):
        w = _windows(ext, 2 * N, 1 + p - m, (0, m, 2 * m), l)
        yield (w[0] - 2.0 * w[1]) + w[2]


def _totvar(rd, ms, tau0, L):
    """TOTVAR from phase: second differences of the reflected extension at every inner sample."""
    N = rd.n
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for t in _totvar_terms(rd, m, L):
            acc.add(t)
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * (N - 2)), N - 2
    return var, n


# name -> (phase kernel, frequency kernel or None: then the frequency is integrated)
_KERNELS = {
    "adev": (_avar_phase, _avar_freq),
    "oadev": (_oavar_phase, _oavar_freq),
    "mdev": (_mvar_phase, _mvar_freq),
    "tdev": (_tvar(_mvar_phase), _tvar(_mvar_freq)),
    "hdev": (_hvar_phase, _hvar_freq),
    "ohdev": (_ohvar_phase, _ohvar_freq),
    "totdev": (_totvar, None),
}


# ----------------------------------------------------------------------- gap kernels
#
# gap_kernel(reader, ms, tau0, L) -> (var, n, n_equivalent), the streamed form of the
# in-memory gap kernels (sigmatau.core.gaps): the reader holds NaN at the missing samples
# (phase less the line through its first and last present points, or frequency less the
# mean of the samples present), NaN runs through every term that reads a gap, and only
# the finite terms are summed and counted. A term is formed as the in-memory gap kernel
# forms it: Σ_j c_j·w_j left to right, from 0.


GapResult = tuple[np.ndarray, np.ndarray, np.ndarray]


def _combine(coeffs: Sequence[float], parts: Sequence[np.ndarray]) -> np.ndarray:
    """``Σ_j c_j·parts[j]`` in the order of the in-memory gap kernels (a Python ``sum`` from 0)."""
    return sum(c * w for c, w in zip(coeffs, parts))  # type: ignore[return-value]


def _gap_row(acc: _FiniteSumSq, scale: float, k: int, n_points: int, stride: int = 1) -> tuple[float, int, int]:
    """Variance ``Σ t²/(scale·n)`` over the n finite terms of k candidates (NaN when none), n, and
    the phase points of a contiguous record giving n terms (:func:`~sigmatau.core.gaps.equivalent_points`;
    ``stride`` points per term lost: m for non-overlapped blocks)."""
    n = acc.n
    var = acc.total / (scale * n) if n else np.nan
    return var, n, n_points - (k - n) * stride


def _gap_kernel(row: Callable[[object, int, float, int], tuple[float, int, int]]):
    """A gap kernel over the factors from ``row(reader, m, tau0, L) -> (var, n, n_equivalent)``."""
    def kernel(rd, ms, tau0, L) -> GapResult:
        var, n, neq = np.empty(ms.size), np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
        for i, m in enumerate(ms):
            var[i], n[i], neq[i] = row(rd, int(m), tau0, L)
        return var, n, neq
    return kernel


def _point_gaps(coeffs: Sequence[float], scale: float, *, blocks: bool = False):
    """Phase terms ``Σ_j c_j x_{i+jm}`` at every i (``blocks``: i = 0, m, 2m …), as
    :func:`sigmatau.core.gaps.point_kernel`; ADEV/OADEV, HDEV/OHDEV."""
    span = len(coeffs) - 1

    def row(rd, m: int, tau0: float, L: int) -> tuple[float, int, int]:
        acc = _FiniteSumSq()
        if blocks:
            count = (rd.n - 1) // m + 1
            for xs in _with_history(_strided(rd, m, count, L), span):
                if xs.size > span:
                    acc.add(_combine(coeffs, [xs[j : xs.size - span + j] for j in range(span + 1)]))
            k = count - span
        else:
            k = rd.n - span * m
            for p, l in _blocks(k, L):
                acc.add(_combine(coeffs, _windows(rd.read, rd.n, p, [j * m for j in range(span + 1)], l)))
        return _gap_row(acc, scale * (m * tau0) ** 2, k, rd.n, m if blocks else 1)

    return _gap_kernel(row)


def _block_gaps(coeffs: Sequence[float], scale: float):
    """Frequency terms ``Σ_j c_j S_{k+j}`` of the block sums of m on the record's grid, as
    :func:`sigmatau.core.gaps.block_kernel` (a block holding a gap is NaN); ADEV, HDEV."""
    span = len(coeffs) - 1

    def row(rd, m: int, tau0: float, L: int) -> tuple[float, int, int]:
        acc = _FiniteSumSq()
        nb = rd.n // m
        for b in _with_history(_block_sums(rd, m, nb, L), span):
            if b.size > span:
                acc.add(_combine(coeffs, [b[j : b.size - span + j] for j in range(span + 1)]))
        return _gap_row(acc, scale * float(m) ** 2, nb - span, rd.n + 1, m)

    return _gap_kernel(row)


def _totvar_phase_gaps_row(rd, m: int, tau0: float, L: int) -> tuple[float, int, int]:
    """TOTVAR of phase with gaps: the reflected terms whose three points are present (a
    reflected point is missing when its source or the end point it mirrors is)."""
    acc = _FiniteSumSq()
    for t in _totvar_terms(rd, m, L):
        acc.add(t)
    return _gap_row(acc, 2.0 * (m * tau0) ** 2, rd.n - 2, rd.n)


#: name -> (phase gap kernel, frequency gap kernel), the streamed form of the statistic's own
#: in-memory gap kernel (``Statistic.phase_gaps``/``freq_gaps``); None where the in-memory path
#: pools the ordinary kernel over the gap-free runs instead (:func:`_pooled_runs`).
_GAP_KERNELS = {
    "adev": (_point_gaps((1.0, -2.0, 1.0), 2.0, blocks=True), _block_gaps((1.0, -1.0), 2.0)),
    "oadev": (_point_gaps((1.0, -2.0, 1.0), 2.0), None),
    "mdev": (None, None),
    "tdev": (None, None),
    "hdev": (_point_gaps((-1.0, 3.0, -3.0, 1.0), 6.0, blocks=True), _block_gaps((1.0, -2.0, 1.0), 6.0)),
    "ohdev": (_point_gaps((-1.0, 3.0, -3.0, 1.0), 6.0), None),
    "totdev": (_gap_kernel(_totvar_phase_gaps_row), None),
}


# ------------------------------------------------------------------------ variance of a record


def _plain_variance(name: str, src: _Series, dtype: str, ms: np.ndarray, tau0: float, total: float,
                    L: int) -> tuple[np.ndarray, np.ndarray]:
    """``(var, n)`` of a record without missing samples, ``total`` the sum of its samples: the phase
    less the line through its end points, or the frequency less its mean (as
    :func:`sigmatau.core.driver.compute`)."""
    phase_kernel, freq_kernel = _KERNELS[name]
    if ms.size == 0:
        return np.empty(0), np.empty(0, dtype=np.int64)
    if dtype == "phase":
        return phase_kernel(_Detrended(src), ms, tau0, L)
    centred = _Centred(src, np.float64(total) / src.n)
    if freq_kernel is not None:
        return freq_kernel(centred, ms, tau0, L)
    return phase_kernel(_Integrated(centred, tau0, L), ms, tau0, L)


def _gap_variance(stat: Statistic, src: _Series, dtype: str, ms: np.ndarray, rate: float, total: float,
                  gaps: _Gaps) -> GapResult:
    """``(var, n, n_equivalent)`` of a record with missing samples, as the in-memory gap path.

    ``gaps`` is what the validating pass found of the missing samples. A gap kernel reads
    the phase less the line through its first and last present points
    (:func:`sigmatau.core.gaps.detrended_phase`), or the frequency less the mean of the
    samples present (``np.nanmean``: ``total``, the sum with NaN as 0, over their count).
    """
    tau0, L = 1.0 / rate, src.chunk_size
    if ms.size == 0:
        empty = np.empty(0, dtype=np.int64)
        return np.empty(0), empty, empty
    kernel = _GAP_KERNELS[stat.name][0 if dtype == "phase" else 1]
    if kernel is None:
        return _pooled_runs(stat, src, dtype, ms, rate, L)
    if dtype == "phase":
        return kernel(_GapDetrended(src, gaps.first, gaps.last), ms, tau0, L)
    return kernel(_Centred(src, np.float64(total) / (src.n - gaps.missing)), ms, tau0, L)


def _pooled_runs(stat: Statistic, src: _Series, dtype: str, ms: np.ndarray, rate: float, L: int) -> GapResult:
    """The ordinary kernel on every gap-free run, pooled, as :func:`sigmatau.core.gaps.pooled_over_runs`.

    Each run is a record of its own, prepared as in memory (its own line or mean removed,
    integrated). A run that fits in a chunk is read and given to the in-memory kernel itself,
    in the form :func:`sigmatau.core.driver.gap_free_runs` makes; a longer one is streamed
    through :func:`_plain_variance`. ``var = Σ var_s·n_s / Σ n_s`` at each factor the runs
    hold (``m ≤ max_m(points)``), and the phase points of a contiguous record with as many
    terms are ``N_s + (n − n_s)`` for the last run s with terms.
    """
    extra = 1 if dtype == "freq" else 0  # a kernel on S frequency samples sees S + 1 phase points
    minimum = stat.min_points if stat.min_run_points is None else stat.min_run_points
    use_freq = dtype == "freq" and stat.compute_freq is not None
    in_memory = stat.compute_freq if use_freq else stat.compute
    total, count = np.zeros(ms.size), np.zeros(ms.size, dtype=np.int64)
    last_points, last_n = np.zeros(ms.size, dtype=np.int64), np.zeros(ms.size, dtype=np.int64)
    for a, b in _present_runs(src, L):
        points = b - a + extra
        use = np.flatnonzero(ms <= stat.max_m(points)) if points >= minimum else np.empty(0, dtype=np.int64)
        if use.size == 0:
            continue
        found = _run_variance(stat, src, a, b, dtype, ms[use], rate, L, in_memory)
        if found is None:
            continue
        var, n = np.asarray(found[0], dtype=float), np.asarray(found[1], dtype=np.int64)
        total[use] += var * n
        count[use] += n
        last_points[use], last_n[use] = points, n
    with np.errstate(invalid="ignore", divide="ignore"):
        var = total / count
    n_eq = np.rint(last_points + (count - last_n)).astype(np.int64)
    return np.where(count > 0, var, np.nan), count, np.where(count > 0, n_eq, 0)


def _run_variance(stat: Statistic, src: _Series, a: int, b: int, dtype: str, ms: np.ndarray, rate: float, L: int,
                  in_memory: Callable) -> Optional[tuple[np.ndarray, np.ndarray]]:
    """``(var, n)`` of the gap-free run ``a … b-1`` at ``ms`` (None when it is too short to prepare)."""
    tau0 = 1.0 / rate
    if b - a <= L:
        values = src.read(a, b)
        run = next(gap_free_runs(stat, values, np.zeros(values.size, dtype=bool), rate, dtype), None)
        return None if run is None else in_memory(run, ms, tau0)
    run = _Slice(src, a, b)
    # The run's own sum, in numpy's order (its mean removed in memory is run.mean()).
    total = _pairwise_sum(run.read, 0, run.n, L) if dtype == "freq" else 0.0
    return _plain_variance(stat.name, run, dtype, ms, tau0, total, L)
