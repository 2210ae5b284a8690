"""Theo1's double sum, fast: FFT lag sums per τ and one incremental pass over many τ.

Split from :mod:`sigmatau.stats.theo` (the public Theo statistics and TheoBR's κ)
because this is the numerical machinery alone: the plain sum (the reference, and
the path wherever it is cheaper or a rounding-error estimate says the fast forms
could lose digits), the lag-sum form in O(N log² m) per τ, and the incremental
pass costing O(N + m) per step. The tests hold every path to the plain sum.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as _fft

from ..core.numeric import CHUNK, dot

__all__ = ["theo1_sum_direct", "theo1_sum_fast", "theo1_sums", "theo1_sums_incremental", "FAST_RTOL"]


# --- the Theo1 sum --------------------------------------------------------------
#
# For even m = 2h, N phase points and K = N - m, the un-normalised sum is
#
#   S(m) = Σ_{i=0}^{K-1} Σ_{L=1}^{h} (1/L) [D_L(i+m-L) - D_L(i)]²,   D_L(i) = x_{i+L} - x_i
#
# (numerics.md §1.12). Writing A_i = x_i + x_{i+m} and c = i + h (the centre of
# each term), the square expands into
#
#   S = H_h Σ A_i² - 2 Σ_L (C(L) + C(m-L))/L + Σ_L (Q[L, L+K) + Q[m-L, m-L+K))/L
#       + 2 Σ_{j=0}^{h-1} G_j/(h-j),
#
# with H_h = Σ_{L≤h} 1/L, C(ℓ) = Σ_{i<K} A_i x_{i+ℓ} (one FFT correlation),
# Q[a, b) = Σ_{a≤i<b} x_i² and G_j = Σ_{c=h}^{N-1-h} x_{c-j} x_{c+j}. G_j is the
# full lag-2j autocorrelation minus the pairs whose centre lies in the first or
# last h samples; the weighted sum of those "triangles" is evaluated by a dyadic
# split into rectangles (FFT correlations) in O(h log² h).
#
# Expanding squares cancels: the terms are of order H_h·Σx² while S may be far
# smaller for smooth (random-walk) phase. Two measures keep the digits: the
# record is cut into overlapping segments of m + max(w·m, _MIN_BLOCK) points
# (w = _WIDE first, 2 where that rounds too much),
# each with its own least-squares line removed (every term is invariant to a
# linear trend), and a rounding-error estimate (every observed error is below
# it) sends any τ that could still lose more than FAST_RTOL to the plain sum.
# The incremental pass works on the whole record and relies on the estimate
# alone.

_LEAF = 16
#: Relative rounding error tolerated from the fast form before the plain sum is used.
FAST_RTOL = 1e-10
#: Rounding-error bound of the fast forms, in units of eps·H_h·Σx² (observed up to ≈ 25).
_FAST_ERR_UNITS = 64.0
#: The plain sum (K·m/2 terms) is used below this many terms per phase point.
_DIRECT_WORK_PER_POINT = 128
#: Overhead of one step (one L) of the plain sum, in plain-sum terms: it matters when
#: N − m is small and the m/2 steps are nearly empty.
_DIRECT_STEP_COST = 2048
#: Smallest segment (in centres) of the fast form.
_MIN_BLOCK = 64
#: Centres per segment, in units of m, of the first (wider, cheaper) fast attempt.
_WIDE = 16


def theo1_sum_direct(x: np.ndarray, m: int) -> float:
    """Plain O((N-m)·m) Theo1 sum in the D_L form (differences first, then squares)."""
    N = x.size
    K = N - m
    e = np.empty(K)
    f = np.empty(K)
    total = 0.0
    for L in range(1, m // 2 + 1):
        # e_i = D_L(i+m-L) - D_L(i) = (x_{i+m} - x_{i+m-L}) - (x_{i+L} - x_i), i < K
        np.subtract(x[m : m + K], x[m - L : m - L + K], out=e)
        np.subtract(x[L : L + K], x[:K], out=f)
        e -= f
        total += dot(e, e) / L
    return total


def _triangle_sums(u: np.ndarray, v: np.ndarray, g: np.ndarray, hankel: bool) -> np.ndarray:
    """Row-wise ``Σ_{a≤b} wt(a, b)·u[:, a]·v[:, b]`` with ``wt = g[b-a]`` or ``g[a+b]`` (hankel).

    ``u`` and ``v`` have shape (rows, P) with P a power of two; ``g`` has at least
    2P entries. The upper triangle is split dyadically: rectangles
    ``[lo, lo+s) × [lo+s, lo+2s)`` are FFT correlations (or convolutions), and
    the diagonal blocks of size ``_LEAF`` are summed directly. Blocks are taken
    in groups of about ``_BATCH_ELEMENTS`` values, so the temporaries stay a few
    times ``u`` at the top level and small below it.
    """
    rows, P = u.shape
    leaf = min(_LEAF, P)
    total = np.zeros(rows)
    s = P // 2
    while s >= leaf:
        nb = P // (2 * s)
        nf = 2 * s
        per = max(1, _BATCH_ELEMENTS // (rows * nf))
        acc = None
        for b0 in range(0, nb, per):
            b1 = min(b0 + per, nb)
            U = u[:, b0 * nf : b1 * nf].reshape(rows, b1 - b0, nf)[:, :, :s]
            V = v[:, b0 * nf : b1 * nf].reshape(rows, b1 - b0, nf)[:, :, s:]
            Uf = _rfft(U, nf)
            Vf = _rfft(V, nf)
            if not hankel:
                np.conjugate(Uf, out=Uf)
                Uf *= Vf
                del Vf
                # b - a = s + r with r = q - p in (-s, s); the weight is the same in every block.
                if acc is None:
                    acc = Uf.sum(axis=1)
                else:
                    acc += Uf.sum(axis=1)
                del Uf
            else:
                Uf *= Vf
                del Vf
                cv = _irfft(Uf, nf)
                del Uf
                start = 2 * np.arange(b0, b1) * nf + s
                for lo in range(0, 2 * s - 1, CHUNK):
                    hi = min(lo + CHUNK, 2 * s - 1)
                    idx = start[:, None] + np.arange(lo, hi)[None, :]
                    total += np.einsum("rbt,bt->r", cv[:, :, lo:hi], g[idx])
                del cv
        if not hankel:
            cc = _irfft(acc, nf)
            del acc
            for lo in range(0, 2 * s - 1, CHUNK):
                r = np.arange(lo, min(lo + CHUNK, 2 * s - 1)) - (s - 1)
                total += np.einsum("ri,i->r", cc[:, r % nf], g[s + r])
            del cc
        s //= 2
    # Diagonal blocks, one diagonal q - p = e at a time.
    nb = P // leaf
    per = max(1, _BATCH_ELEMENTS // (rows * leaf))
    for b0 in range(0, nb, per):
        b1 = min(b0 + per, nb)
        U = u[:, b0 * leaf : b1 * leaf].reshape(rows, b1 - b0, leaf)
        V = v[:, b0 * leaf : b1 * leaf].reshape(rows, b1 - b0, leaf)
        base = 2 * (np.arange(b0, b1) * leaf)[:, None] + 2 * np.arange(leaf)[None, :]
        for e in range(leaf):
            prod = U[:, :, : leaf - e] * V[:, :, e:]
            if hankel:
                total += np.einsum("rbp,bp->r", prod, g[base[:, : leaf - e] + e])
            else:
                total += g[e] * prod.sum(axis=(1, 2))
    return total


def _edge_sums(seg: np.ndarray, h: int) -> np.ndarray:
    """Row-wise ``Σ_{c=0}^{h-1} Σ_{j=0}^{c} seg[c-j]·seg[c+j]/(h-j)`` for seg of shape (rows, 2h-1).

    Pairs (a, b) = (c-j, c+j) with a ≤ b and a + b ≤ 2h-2. Pairs inside the first
    h samples form an upper triangle with Toeplitz weight; pairs reaching into the
    last h-1 samples, with those reversed, form another upper triangle with a
    Hankel weight.
    """
    rows = seg.shape[0]
    P = 1 << max(0, (h - 1).bit_length())
    u = np.zeros((rows, P))
    u[:, :h] = seg[:, :h]
    total = _triangle_sums(u, u, _EdgeWeights(h, reverse=False), hankel=False)
    if h > 1:
        v = np.zeros((rows, P))
        v[:, : h - 1] = seg[:, h : 2 * h - 1][:, ::-1]
        total += _triangle_sums(u, v, _EdgeWeights(h, reverse=True), hankel=True)
    return total


class _EdgeWeights:
    """``ω[d] = 1/(h − d/2)`` for even ``0 ≤ d ≤ 2h−2``, else 0 (``reverse``: ``ω[2h−2−d]``).

    Evaluated where indexed instead of stored: for h near N/2 two stored tables
    would each be as large as the record.
    """

    def __init__(self, h: int, reverse: bool) -> None:
        self._h = h
        self._reverse = reverse

    def __getitem__(self, d):
        d = np.asarray(d)
        out = np.zeros(d.shape)
        flat_d, flat_out = d.reshape(-1), out.reshape(-1)
        top = 2 * self._h - 2
        for lo in range(0, flat_d.size, 1 << 16):  # small temporaries only
            e = flat_d[lo : lo + (1 << 16)]
            if self._reverse:
                e = top - e
            ok = (e >= 0) & (e <= top) & (e % 2 == 0)
            np.divide(1.0, self._h - e // 2, out=flat_out[lo : lo + e.size], where=ok)
        return out


#: Transforms at least this long use numpy.fft, which keeps no plans: scipy.fft
#: caches its last 16, about 8 bytes per point each (141 MB for one transform of
#: 1.8·10^7 points), which stay resident after the call.
_UNCACHED_FFT = 1 << 18


def _rfft(a: np.ndarray, n: int) -> np.ndarray:
    return np.fft.rfft(a, n, axis=-1) if n >= _UNCACHED_FFT else _fft.rfft(a, n, axis=-1)


def _irfft(a: np.ndarray, n: int) -> np.ndarray:
    return np.fft.irfft(a, n, axis=-1) if n >= _UNCACHED_FFT else _fft.irfft(a, n, axis=-1, overwrite_x=True)


def _detrended(X: np.ndarray) -> np.ndarray:
    """Copy of X with each row's least-squares line removed (the time axis in chunks, not stored)."""
    n = X.shape[1]
    X = X - X.mean(axis=1, keepdims=True)
    centre = 0.5 * (n - 1)
    slope = np.zeros(X.shape[0])
    for lo in range(0, n, CHUNK):
        t = np.arange(lo, min(lo + CHUNK, n)) - centre
        slope += np.einsum("ri,i->r", X[:, lo : lo + t.size], t)
    slope /= n * (n * n - 1.0) / 12.0  # Σ t²
    for lo in range(0, n, CHUNK):
        t = np.arange(lo, min(lo + CHUNK, n)) - centre
        X[:, lo : lo + t.size] -= slope[:, None] * t
    return X


def _fft_sums(X: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Theo1 sums of each row of X (rows are independent records) and their error scale.

    Returns ``(S, scale)`` where the rounding error of ``S`` is about
    ``eps·scale`` (``scale = H_h·Σx²`` after removing each row's line).
    Each transform is reduced to the few sums it feeds and freed at once, the
    even-lag autocorrelation comes from half-length transforms, and the
    weighted lag sums read slices chunk by chunk: the peak is X, its detrended
    copy and one transform of X's length (output, work buffer and plan, about
    three times X), ≈ 6.5× X for one record of 10^7 points.
    """
    rows, n = X.shape
    h = m // 2
    K = n - m
    X = _detrended(X)
    # C(ℓ) = Σ_{i<K} A_i x_{i+ℓ}, ℓ ≤ m, never reaches past i + ℓ = n - 1: no padding.
    nfft = _fft.next_fast_len(n, real=True)
    P = _rfft(X[:, :K] + X[:, m:], nfft)
    np.conjugate(P, out=P)
    P *= _rfft(X, nfft)
    C = _irfft(P, nfft)
    del P
    cross = np.zeros(rows)
    harmonic = 0.0
    for lo in range(0, h, CHUNK):
        hi = min(lo + CHUNK, h)
        inv_l = 1.0 / np.arange(lo + 1, hi + 1)  # 1/L for L = lo+1 … hi
        harmonic += float(inv_l.sum())
        # C(L) + C(m-L); the second runs backwards.
        cross += np.einsum("ri,i->r", C[:, lo + 1 : hi + 1] + C[:, m - hi : m - lo][:, ::-1], inv_l)
    del C
    # Autocorrelation at the even lags 2j < m. Samples an even lag apart have the
    # same parity: R(2j) is the lag-j autocorrelation of the even-indexed samples
    # plus that of the odd-indexed ones, from transforms of (n + m)/2 points.
    nfft = _fft.next_fast_len((n + 1) // 2 + h - 1, real=True)
    P = _rfft(X[:, 0::2], nfft)
    np.square(P.real, out=P.real)
    np.square(P.imag, out=P.imag)
    P.real += P.imag
    odd = _rfft(X[:, 1::2], nfft)
    np.square(odd.real, out=odd.real)
    P.real += odd.real
    np.square(odd.imag, out=odd.imag)
    P.real += odd.imag
    del odd
    P.imag = 0.0
    R = _irfft(P, nfft)
    del P
    G = np.zeros(rows)
    for lo in range(0, h, CHUNK):
        j = np.arange(lo, min(lo + CHUNK, h))
        G += np.einsum("ri,i->r", R[:, lo : lo + j.size], 1.0 / (h - j))
    del R
    q = np.empty((rows, n + 1))
    q[:, 0] = 0.0
    np.square(X, out=q[:, 1:])
    np.cumsum(q[:, 1:], axis=1, out=q[:, 1:])
    squares = np.zeros(rows)
    for lo in range(0, h, CHUNK):
        hi = min(lo + CHUNK, h)
        # Q[L, L+K) + Q[m-L, m-L+K) for L = lo+1 … hi; the m-L terms run backwards.
        sq = q[:, lo + 1 + K : hi + 1 + K] - q[:, lo + 1 : hi + 1]
        sq += q[:, m + K - hi : m + K - lo][:, ::-1]
        sq -= q[:, m - hi : m - lo][:, ::-1]
        squares += np.einsum("ri,i->r", sq, 1.0 / np.arange(lo + 1, hi + 1))
    total = np.zeros(rows)
    for lo in range(0, K, CHUNK):
        A = X[:, lo : min(lo + CHUNK, K)] + X[:, m + lo : m + min(lo + CHUNK, K)]
        total += np.einsum("ri,ri->r", A, A)
    total *= harmonic
    total -= 2.0 * cross
    total += squares
    scale = harmonic * q[:, -1]
    del q
    G -= _edge_sums(X[:, : 2 * h - 1], h)
    G -= _edge_sums(X[:, ::-1][:, : 2 * h - 1], h)
    total += 2.0 * G
    return total, scale


#: Segments of the fast form are transformed in batches of about this many samples
#: (the working memory of one batch is a few times this).
_BATCH_ELEMENTS = 1 << 19


def theo1_sum_fast(x: np.ndarray, m: int, width: int = 2) -> tuple[float, float]:
    """Fast Theo1 sum over overlapping segments; returns ``(S, estimated relative error)``.

    Each segment contributes ``max(width·m, _MIN_BLOCK)`` centres. Wider segments
    mean fewer end corrections (the costly part) but larger detrended values, so
    more rounding on smooth phase.
    """
    N = x.size
    K = N - m
    block = max(width * m, _MIN_BLOCK)
    if block >= K:
        parts = [x[None, :]]
    else:
        full = K // block
        windows = np.lib.stride_tricks.sliding_window_view(x, block + m)[: full * block : block]
        per_batch = max(1, _BATCH_ELEMENTS // (block + m))
        parts = [windows[r : r + per_batch] for r in range(0, full, per_batch)]
        rest = K - full * block
        if rest:
            parts.append(x[None, full * block :])
    total = 0.0
    scale = 0.0
    for X in parts:
        s, sc = _fft_sums(X, m)
        total += float(s.sum())
        scale += float(sc.sum())
    if scale == 0.0:
        return 0.0, 0.0
    err = _FAST_ERR_UNITS * np.finfo(float).eps * scale / total if total > 0.0 else math.inf
    return total, err


def theo1_sums_incremental(x: np.ndarray, ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Theo1 sums at many even factors in one pass over h = m/2; O(N) per step.

    Uses the centred form of the expansion (c = i + h, j = h - L, w_j = 1/(h-j)):

      S = H_h Σ_c (x_{c-h} + x_{c+h})² - 2 Σ_j w_j β_j + Σ_j w_j Σ_c (x_{c-j}² + x_{c+j}²) + 2 Σ_j w_j G_j,

    with c over [h, N-h). ``Σ_j w_j β_j`` is ``2 Σ_j w_j (R_{h-j} + R_{h+j})`` less
    the pairs that fall outside the window; those are the pairs (a, b) with
    b < 2h at both ends, weighted by ψ_h(b-a) = 1/ℓ (ℓ < h), 2/h (ℓ = h),
    1/(2h-ℓ) (ℓ > h), and are kept as running lag sums Z_ℓ that grow by two
    samples per step. G_j loses two products per step and gains one new lag.
    Returns ``(S, estimated relative rounding error)`` per factor.
    """
    N = x.size
    t = np.arange(N) - 0.5 * (N - 1)
    x = x - x.mean()
    x = x - (dot(x, t) / dot(t, t)) * t
    hs = np.asarray(ms, dtype=np.int64) // 2
    h_max = int(hs.max())
    wanted = np.zeros(h_max + 1, dtype=bool)
    wanted[hs] = True
    nfft = _fft.next_fast_len(2 * N, real=True)
    Xf = _fft.rfft(x, nfft)
    R = _fft.irfft(Xf * np.conj(Xf), nfft)[: 2 * h_max + 1]
    q = np.zeros(N + 1)
    np.cumsum(x * x, out=q[1:])
    xr = x[::-1].copy()
    zf = np.zeros(2 * h_max + 1)
    zr = np.zeros(2 * h_max + 1)
    G = np.zeros(h_max + 1)
    buf = np.empty(2 * h_max + 1)
    ar = np.arange(2 * h_max + 1)
    sums = {}
    harmonic = 0.0
    for h in range(1, h_max + 1):
        if h == 1:
            G[0] = q[N - 1] - q[1]
            zf[1] = x[0] * x[1]
            zr[1] = xr[0] * xr[1]
        else:
            # The window of centres loses c = h-1 and c = N-h ...
            k = h - 1
            np.multiply(x[k:0:-1], x[k : 2 * k], out=buf[:k])
            G[:k] -= buf[:k]
            np.multiply(x[N - h : N - 2 * h + 1 : -1], x[N - h : N - 1], out=buf[:k])
            G[:k] -= buf[:k]
            # ... and gains the lag 2k, whose window misses only a = 0 and a = N-1-2k.
            G[k] = R[2 * k] - x[0] * x[2 * k] - x[N - 1 - 2 * k] * x[N - 1]
            for b in (2 * h - 2, 2 * h - 1):
                np.multiply(x[b - 1 :: -1][:b], x[b], out=buf[:b])
                zf[1 : b + 1] += buf[:b]
                np.multiply(xr[b - 1 :: -1][:b], xr[b], out=buf[:b])
                zr[1 : b + 1] += buf[:b]
        harmonic += 1.0 / h
        if not wanted[h]:
            continue
        m = 2 * h
        j = ar[:h]
        w = 1.0 / (h - j)
        ell = ar[1 : 2 * h]
        psi = 1.0 / np.minimum(ell, 2 * h - ell)
        psi[h - 1] = 2.0 / h
        # Σ_c (x_{c-h} + x_{c+h})²: the lag-m products cover the whole lag-m autocorrelation.
        alpha = q[N - m] + (q[N] - q[m]) + 2.0 * R[m]
        beta = 2.0 * dot(w, R[h:0:-1] + R[h : 2 * h]) - dot(psi, zf[1 : 2 * h] + zr[1 : 2 * h])
        squares = (q[N - h : N - 2 * h : -1] - q[h:0:-1]) + (q[N - h : N] - q[h : 2 * h])
        sums[m] = harmonic * alpha - 2.0 * beta + dot(w, squares + 2.0 * G[:h])
    total = np.array([sums[int(m)] for m in ms])
    scale = np.array([_harmonic(int(m) // 2) for m in ms]) * q[-1]
    eps = np.finfo(float).eps
    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.where(total > 0.0, _FAST_ERR_UNITS * eps * scale / total, np.where(scale == 0.0, 0.0, np.inf))
    return total, err


def _harmonic(h: int) -> float:
    return float(np.sum(1.0 / np.arange(1, h + 1)))


def _theo1_sum(x: np.ndarray, m: int) -> float:
    """Theo1 sum S(m) by the plain sum or the lag sums, whichever is cheaper and exact enough."""
    if (x.size - m + _DIRECT_STEP_COST) * (m // 2) <= _DIRECT_WORK_PER_POINT * x.size:
        return theo1_sum_direct(x, m)
    # Wide segments first (about half the work); narrow ones where smooth phase
    # makes the wide ones round too much; the plain sum as the last resort.
    for width in (_WIDE, 2):
        total, err = theo1_sum_fast(x, m, width)
        if err <= FAST_RTOL:
            return total
    return theo1_sum_direct(x, m)


def theo1_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """Theo1 sums at even factors ``ms``: per factor, or in one incremental pass when cheaper."""
    N = x.size
    ms = np.asarray(ms, dtype=np.int64)
    if ms.size == 0:
        return np.empty(0)
    # Rough costs in units of one plain-sum term (about 1 ns): a lag-sum evaluation
    # ≈ _DIRECT_WORK_PER_POINT·N; an incremental step is O(m), counted as 4·N to
    # stay on the per-factor path unless many factors are wanted.
    per_factor = np.minimum((N - ms + _DIRECT_STEP_COST) * (ms // 2), _DIRECT_WORK_PER_POINT * N).sum()
    if 4 * N * int(ms.max() // 2) >= per_factor:
        return np.array([_theo1_sum(x, int(m)) for m in ms])
    total, err = theo1_sums_incremental(x, ms)
    for k in np.flatnonzero(~(err <= FAST_RTOL)):
        total[k] = _theo1_sum(x, int(ms[k]))
    return total
