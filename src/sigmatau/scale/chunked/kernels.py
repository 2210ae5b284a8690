"""The streamed kernels: variance and term count of each chunked statistic at each averaging factor.

``kernel(reader, ms, tau0, L) -> (var, n)``, one phase and one frequency kernel
per statistic (:data:`_KERNELS`), built from the sums of :mod:`.streams`.
"""

from __future__ import annotations

import numpy as np

from .streams import (_blocks, _block_sums, _Prefix, _strided, _SumSq, _window_diff, _window_sums, _windows,
                      _with_history)


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


def _totvar(rd, ms, tau0, L):
    # Reflected phase x*_{-j} = 2x_0 - x_j, x*_{N-1+j} = 2x_{N-1} - x_{N-1-j};
    # terms i = 1 … N-2: x*_{i-m} - 2x*_i + x*_{i+m}.
    """TOTVAR from phase: second differences of the reflected extension at every inner sample."""
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

    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for p, l in _blocks(N - 2, L):
            w = _windows(ext, 2 * N, 1 + p - m, (0, m, 2 * m), l)
            acc.add((w[0] - 2.0 * w[1]) + w[2])
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
