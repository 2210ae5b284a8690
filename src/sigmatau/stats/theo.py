"""Theo1 family: Theo1, the bias-removed TheoBR and the hybrid TheoH.

Theo1 reaches averaging times up to 75 % of the record. Its defining double
sum costs O(N·m) per τ. Here it is evaluated from lag sums (FFT correlations
plus exact end corrections) in O(N log² m) per τ, or, when many factors are
wanted (TheoBR's κ, the "all" grid), in one incremental pass over m costing
O(N + m) per step. The plain sum stays beside them
(:func:`_theo1_sum_direct`): it is used where it is cheaper and wherever a
rounding-error estimate says the fast forms could lose digits. TheoBR's bias
factor κ needs Theo1 at about N/30 factors (O(N²)); by default it is computed
on a block-averaged copy of long records (Fast TheoBR, :func:`theobr_kappa`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import Literal, Optional

import numpy as np
from scipy import fft as _fft

from ..core import driver as _driver
from ..core.driver import Statistic
from .engine import finish, run
from ..core.validate import unscale_variance
from ..core.numeric import CHUNK, dot
from ..core.validate import DataType
from ..uncertainty.attach import CiMethod, check_options
from ..core.kernels import oavar_kernel
from .allan import _doc
from ..uncertainty.confidence import ONE_SIGMA
from ..uncertainty.noiseid import theo_noise_id
from ..errors import DataError, ParameterError, RangeWarning
from ..core.result import StabilityResult
from ..core.taus import TAU_GRIDS, is_numeric, m_grid, select_m

__all__ = ["theo1", "theobr", "theoh", "theobr_kappa", "theoh_split", "TheoBRKappa", "KAPPA_FAST_POINTS"]


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
# it) sends any τ that could still lose more than _FAST_RTOL to the plain sum.
# The incremental pass works on the whole record and relies on the estimate
# alone.

_LEAF = 16
#: Relative rounding error tolerated from the fast form before the plain sum is used.
_FAST_RTOL = 1e-10
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


def _theo1_sum_direct(x: np.ndarray, m: int) -> float:
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


def _theo1_sum_fast(x: np.ndarray, m: int, width: int = 2) -> tuple[float, float]:
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


def _theo1_sums_incremental(x: np.ndarray, ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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
        return _theo1_sum_direct(x, m)
    # Wide segments first (about half the work); narrow ones where smooth phase
    # makes the wide ones round too much; the plain sum as the last resort.
    for width in (_WIDE, 2):
        total, err = _theo1_sum_fast(x, m, width)
        if err <= _FAST_RTOL:
            return total
    return _theo1_sum_direct(x, m)


def _theo1_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
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
    total, err = _theo1_sums_incremental(x, ms)
    for k in np.flatnonzero(~(err <= _FAST_RTOL)):
        total[k] = _theo1_sum(x, int(ms[k]))
    return total


def _theo1_kernel(x: np.ndarray, ms: np.ndarray, tau0: float):
    N = x.size
    ms = np.asarray(ms, dtype=np.int64)
    var = _theo1_sums(x, ms) / (0.75 * (N - ms) * (ms * tau0) ** 2)
    return var, (N - ms) * ms // 2


THEO1 = Statistic(
    "theo1", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=2, even=True, tau_factor=0.75,
)
THEOBR = Statistic(
    "theobr", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=2, even=True, tau_factor=0.75,
)


# --- TheoBR bias factor -----------------------------------------------------------

#: Fewest phase points for which TheoBR's κ is defined (n = ⌊N/30⌋ − 3 ≥ 0).
THEOBR_MIN_POINTS = 90


@dataclass(frozen=True)
class TheoBRKappa:
    """TheoBR's empirical bias factor.

    Attributes
    ----------
    kappa : float
        ``κ = 1/(n+1) Σ_{i=0}^{n} OAVAR(m=9+3i) / Theo1(m=12+4i)``; TheoBR = κ·Theo1.
    n : int
        Upper index of the average, ``⌊N'/30⌋ − 3`` for the N' phase points κ
        was computed on (N' = N unless ``block > 1``).
    n_points : int
        Number of phase points N of the record.
    block : int
        1 when κ follows the published definition on the whole record
        (``method="exact"``, or ``"fast"`` on at most 16384 phase points);
        otherwise the number of phase points averaged into each point of the
        shorter record the fast estimate used.
    """

    kappa: float
    n: int
    n_points: int
    block: int = 1


#: κ methods: the published definition on the whole record, or on a block-averaged copy,
#: or over Stable32's wider "Run" span of ratios.
KappaMethod = Literal["fast", "exact", "run"]
_KAPPA_METHODS = ("fast", "exact", "run")
#: Largest record (phase points) on which the fast κ still uses the published definition.
KAPPA_FAST_POINTS = 16384


def _check_kappa_points(N: int, data_type: str = "phase") -> None:
    if N < THEOBR_MIN_POINTS:
        given = f"{N} phase points" if data_type == "phase" else f"{N - 1} frequency samples"
        raise DataError(
            f"TheoBR needs at least {THEOBR_MIN_POINTS} phase points ({THEOBR_MIN_POINTS - 1}"
            f" frequency samples) to estimate its bias factor κ, got {given}"
            " (κ averages n + 1 ratios with n = ⌊N/30⌋ − 3 ≥ 0)"
        )


def _check_kappa_method(method: object, name: str = "kappa") -> str:
    if not isinstance(method, str) or method not in _KAPPA_METHODS:
        raise ParameterError(f"{name}={method!r} must be one of {_KAPPA_METHODS} (how TheoBR's κ is computed)")
    return method


def _kappa(x: np.ndarray, method: str = "fast") -> TheoBRKappa:
    """κ of the phase record ``x`` (linear trend removed) by ``method``."""
    N = x.size
    _check_kappa_points(N)
    if method == "run":
        return _kappa_exact(x, n=_run_span(N))
    block = 1 if method == "exact" else -(-N // KAPPA_FAST_POINTS)
    if block == 1:
        return _kappa_exact(x)
    # Fast TheoBR (Taylor & Howe 2010): κ of the record averaged in blocks of
    # `block` phase points, at most KAPPA_FAST_POINTS of them. Averaging keeps the
    # long-τ behaviour both variances share and makes κ O(N) + O(1).
    k = N // block
    averaged = x[: k * block].reshape(k, block).mean(axis=1)
    kap = _kappa_exact(averaged)
    if kap.kappa > 0 and theo_noise_id(kap.kappa) >= 1:
        # Block averaging biases κ upwards for phase noise (≈ +25 % at b = 5, +50 % at
        # N = 10^6, Howe–Tasset model); FM noise is within 1 %. Say so rather than hide it.
        warnings.warn(
            f"TheoBR κ = {kap.kappa:.4g} from blocks of {block} points indicates phase noise (WPM/FPM), for"
            f" which Fast TheoBR overestimates κ (by tens of percent at this length); kappa='exact' gives the"
            f" published κ at O(N²) cost", RangeWarning, stacklevel=3)
    return TheoBRKappa(kappa=kap.kappa, n=kap.n, n_points=int(N), block=int(block))


def _run_span(N: int) -> int:
    """Upper index n of κ's average in Stable32's Run/Plot functions: ⌊N/6⌋ − 3, capped so
    that OAVAR at m = 9+3n keeps at least one term (N − 2m ≥ 1)."""
    return min(N // 6 - 3, ((N - 1) // 2 - 9) // 3)


def _kappa_exact(x: np.ndarray, n: Optional[int] = None) -> TheoBRKappa:
    """κ by its published definition (numerics.md §1.13) on the phase record ``x``;
    ``n`` (default ⌊N/30⌋ − 3) is the upper index of the average."""
    N = x.size
    _check_kappa_points(N)
    n = N // 30 - 3 if n is None else n
    i = np.arange(n + 1)
    oavar, _ = oavar_kernel(x, 9 + 3 * i, 1.0)
    theo, _ = _theo1_kernel(x, 12 + 4 * i, 1.0)
    if np.all(theo <= 0.0) and np.all(oavar <= 0.0):
        # A straight phase line (constant frequency): every variance is zero and so is
        # TheoBR whatever κ; κ = 1 keeps the result finite.
        return TheoBRKappa(kappa=1.0, n=int(n), n_points=int(N))
    if np.any(theo <= 0.0):
        raise DataError(
            "TheoBR's bias factor κ is undefined: Theo1 is zero at some m = 12+4i"
            " while the Allan variance is not"
        )
    return TheoBRKappa(kappa=float(np.mean(oavar / theo)), n=int(n), n_points=int(N))


def _kappa_text(k: TheoBRKappa) -> str:
    if k.block == 1 and k.n > k.n_points // 30 - 3:
        return f"theobr kappa={k.kappa:.6f} (n={k.n}, run span N/6)"
    if k.block == 1:
        return f"theobr kappa={k.kappa:.6f} (n={k.n})"
    return f"theobr kappa={k.kappa:.6f} (n={k.n}, fast: blocks of {k.block} points)"


# --- Theo1 bias by noise type --------------------------------------------------------

#: ``AVAR/Theo1 = a + b/t^c`` at ``t = 0.75·m`` (τ/τ0), by noise exponent α: Howe & Tasset
#: 2004, Table 1 (as SP1065 and the Stable32 manual give it); numerics.md §3, checked there by
#: Monte Carlo at N = 513 (WPM/FPM within 2 %, WFM 1 %, FFM/RWFM ~7 %).
_THEO1_BIAS = {2: (0.09, 0.74, 0.40), 1: (0.14, 0.82, 0.30), 0: (1.0, 0.0, 0.0),
               -1: (1.87, -1.05, 0.79), -2: (2.70, -1.53, 0.85)}

TheoBias = Literal["none", "published", "auto"]
_THEO_BIAS_MODES = ("none", "published", "auto")


def _check_theo1_bias(bias: object, alpha: Optional[int]) -> str:
    """Validate ``bias`` and a forced ``alpha`` against the table before computing."""
    if not isinstance(bias, str) or bias not in _THEO_BIAS_MODES:
        raise ParameterError(f"bias={bias!r} must be one of {_THEO_BIAS_MODES}")
    if bias != "none" and alpha is not None and alpha not in _THEO1_BIAS:
        raise ParameterError(
            f"theo1: no published bias factor for alpha={alpha}; allowed: 2, 1, 0, -1, -2"
        )
    return bias


def _theo1_avar_ratio(alphas: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """``a + b/(0.75 m)^c`` per row; NaN where the row's α has no entry."""
    out = np.full(ms.size, np.nan)
    for k, (a_k, m_k) in enumerate(zip(alphas, ms)):
        if np.isfinite(a_k) and int(a_k) in _THEO1_BIAS:
            a, b, c = _THEO1_BIAS[int(a_k)]
            out[k] = a + b / (0.75 * float(m_k)) ** c
    return out


def _apply_theo1_bias(res: StabilityResult, bias: str, forced: Optional[int]) -> StabilityResult:
    """Multiply each row's variance by AVAR/Theo1 for its noise type (``res.alpha``)."""
    alphas = res.alpha if res.alpha is not None else np.full(res.m.size, np.nan)
    ratio = _theo1_avar_ratio(np.asarray(alphas, dtype=float), res.m)
    missing = ~np.isfinite(ratio)
    # bias_factor is the divisor applied to raw Theo1 (Theo1/AVAR), as for TheoBR (1/κ).
    factor = np.where(missing, 1.0, 1.0 / np.where(missing, 1.0, ratio))
    var = res.var / factor
    # A fixed divisor scales a χ² interval exactly as it scales the estimate.
    scaled = {f: getattr(res, f) / np.sqrt(factor) for f in ("ci_low", "ci_high") if getattr(res, f) is not None}
    desc = f"published alpha={forced}" if forced is not None else "published at the alpha identified per tau"
    if missing.any():
        desc += f" (uncorrected at {int(missing.sum())} tau whose alpha has no factor)"
    return replace(res, var=var, dev=np.sqrt(var), bias=desc, bias_factor=factor, **scaled)


# --- public functions ---------------------------------------------------------------


@_doc
def theo1(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", bias: TheoBias = "none",
) -> StabilityResult:
    """Theo1 deviation, raw (default) or corrected for the bias of a noise type.

    {common}
    Notes
    -----
    For even ``m`` and N phase points,

    .. math:: \\mathrm{Theo1}(m) = \\frac{1}{0.75\\,(N-m)(mτ_0)^2}
              \\sum_{i=0}^{N-m-1} \\sum_{δ=0}^{m/2-1} \\frac{1}{m/2-δ}
              \\big[(x_i - x_{i-δ+m/2}) + (x_{i+m} - x_{i+δ+m/2})\\big]^2 ,

    reported at **τ = 0.75·m·τ0** (``result.taus``; ``result.m`` holds m). The
    0.75 makes Theo1 equal AVAR at the same τ for white FM; for other noise
    types it is biased (:func:`theobr` removes the bias). ``n = (N-m)·m/2``
    terms, as Stable32's "Thêo1 #" column. The estimator ignores a linear phase
    trend (a frequency offset).

    Only even factors are valid, ``2 ≤ m ≤ N-1``; ``taus`` in seconds are
    rounded to the nearest multiple of 1.5·τ0. Keyword grids run over even m
    from 2 to N-1 (τ up to 0.75 of the record): SP1065 quotes ``m ≥ 10`` and
    Stable32 starts there, but the estimator is defined from m = 2; drop the
    first rows if you need the Stable32 range.

    **Bias** (``bias``, default ``"none"``: the raw estimator). Theo1 equals
    AVAR at the same τ only for white FM; Howe & Tasset (2004, Table 1, as in
    SP1065) give

    .. math:: \\frac{\\mathrm{AVAR}(τ)}{\\mathrm{Theo1}(τ)} = a + \\frac{b}{t^c},
              \\qquad t = 0.75\\,m ,

    with (a, b, c) = WPM (0.09, 0.74, 0.40), FPM (0.14, 0.82, 0.30),
    WFM (1, 0, 0), FFM (1.87, −1.05, 0.79), RWFM (2.70, −1.53, 0.85).
    ``bias="published"`` multiplies the variance (and the interval) by this
    ratio for ``alpha`` when given, else for the noise type identified at
    each τ; ``"auto"`` is the same at the identified type (``alpha`` still
    forces one). Rows whose α has no entry (−3, −4) stay raw and
    ``result.bias`` counts them; ``result.bias_factor`` is the divisor applied
    to raw Theo1, ``1/(a + b/t^c)``, as ``1/κ`` for :func:`theobr`.
    Stable32's Theo1 output with Alpha forced to 0 is the raw value (the
    WFM factor is 1); its "Auto/BR" output is not this table but TheoBR with
    κ over a wider range (:func:`theobr` with ``kappa="run"``).

    Cost: O(N log² m) per τ by lag sums (FFT correlations over overlapping
    segments plus exact end corrections; about 0.5 s for the octave grid at
    N = 10^5), with the plain O(N·m) double sum used when it is cheaper or
    when the fast form could lose more than 1e-10 relative to rounding. Many
    factors at once (``taus="all"``) go through one incremental pass, O(N·m_max).

    References
    ----------
    D. A. Howe & T. N. Tasset, "Theo1: characterization of very long-term
    frequency stability", EFTF 2004; W. J. Riley, NIST SP 1065 (2008);
    numerics.md §1.12, §4.

    Examples
    --------
    >>> import sigmatau.theo
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theo.theo1(nbs1000(), m=[10, 100])
    >>> r.taus.tolist(), [round(float(d), 7) for d in r.dev]
    ([7.5, 75.0], [0.107574, 0.0317893])
    """
    alpha_i, _, _ = check_options(alpha, confidence, ci)
    bias = _check_theo1_bias(bias, alpha_i)
    if bias == "none":
        return run(THEO1, data, rate=rate, data_type=data_type, taus=taus, m=m,
                   points_per_decade=points_per_decade, alpha=alpha, confidence=confidence, ci=ci)
    # The correction needs each row's noise type even when no interval is wanted.
    res = run(THEO1, data, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
              alpha=alpha, confidence=confidence, ci="chi2" if ci is None else ci)
    res = _apply_theo1_bias(res, bias, alpha_i)
    if ci is None:
        res = replace(res, edf=None, ci_low=None, ci_high=None, confidence=None, ci_reason=None)
    return res


def theobr_kappa(
    data, *, rate: float = 1.0, data_type: DataType = "freq", method: KappaMethod = "fast",
) -> TheoBRKappa:
    """TheoBR's bias factor κ = mean of OAVAR/Theo1 ratios over the record.

    Parameters
    ----------
    data : array_like
        Frequency (default) or phase samples, as for :func:`theobr`.
    rate : float
        Sample rate in Hz.
    data_type : {"freq", "phase"}
        Meaning of ``data``.
    method : {"fast", "exact", "run"}
        ``"exact"``: the published definition below on the whole record,
        O(N²) (minutes at N = 10^6). ``"fast"`` (default): the same definition
        on the record averaged in blocks (Fast TheoBR, see Notes); identical to
        ``"exact"`` up to 16384 phase points (``KAPPA_FAST_POINTS``).
        ``"run"``: the same ratios averaged over Stable32's "Run"/"Plot" span,
        ``n = ⌊N/6⌋ − 3`` (capped so that OAVAR at m = 9+3n has a term), on
        the whole record — five times as many ratios, reaching τ ≈ T/2, and
        O(N²). Stable32's Theo1 "Auto/BR" tables are Theo1 times this κ: the
        PHASE.DAT table headed "Alpha = 1" is raw Theo1 × 0.602787 at every
        τ, which is this κ (0.6027870, n = 163) to 1e-6, and its Alpha column
        is the noise type of that κ (nominal ratio 0.6: FPM).

    Returns
    -------
    TheoBRKappa
        ``kappa``, the averaging range ``n``, the number of phase points and
        the averaging ``block`` (1 for the published definition).

    Notes
    -----
    With N phase points and ``n = ⌊0.1·N/3 − 3⌋`` (needs N ≥ 90),

    .. math:: κ = \\frac{1}{n+1} \\sum_{i=0}^{n}
              \\frac{\\mathrm{OAVAR}(m = 9+3i)}{\\mathrm{Theo1}(m = 12+4i)} ,

    both at τ = (9+3i)·τ0; AVAR is the overlapped estimator. κ does not depend
    on the rate. It needs Theo1 and OAVAR at about N/30 factors each: Theo1
    comes from one incremental pass, O(N²/15) in all (about 2 s at N = 10^5
    with OAVAR); factors at which that pass could lose digits (smooth,
    random-walk-FM phase at small m) are recomputed one by one, which is slower.

    **Fast TheoBR** (``method="fast"``, after Taylor & Howe 2010): for
    N > 16384 the phase record is averaged in blocks of ``b = ⌈N/16384⌉``
    points and κ is the published definition applied to the ⌊N/b⌋ averages
    (τ0' = b·τ0; ``n`` then counts ratios of that record). The cost is O(N)
    plus a bounded κ computation (well under 2 s for any N and noise type).
    This **changes the value** of κ where the ratio AVAR/Theo1 depends on m
    itself: the fast κ is that of a record of ⌊N/b⌋ points, so it averages
    the ratios over factors 9 … 0.1·N/b of the shorter record instead of
    9 … 0.1·N. Measured on seeded records (two per type) of N = 65537 and
    131073 phase points (b = 5 and 9): white, flicker and random-walk FM,
    flicker-walk and random-run FM within 0.8 % of the exact κ (+0.6…+0.8 %
    WFM, −0.2…−0.3 % for the others); white PM +25 % and +35 %, flicker PM
    +16 % and +23 %, whose Theo1 bias keeps falling with m (Howe & Tasset's
    bias model a + b/(0.75m)^c reproduces these and predicts about +50 % at
    N = 10^6, b = 62, and +60…67 % at N = 10^7). Use ``method="exact"`` when
    PM noise dominates and the record is long. No correction term is added
    (one implementation adds ``0.00055·(b−1)``, numerics.md §8 item 14,
    unverified).

    References
    ----------
    D. A. Howe, "ThêoH: a hybrid, high-confidence statistic that improves on the
    Allan deviation", Metrologia 43 (2006) S322; W. J. Riley, NIST SP 1065 (2008);
    J. A. Taylor & D. A. Howe, "Fast TheoBR: a method for long data set
    stability analysis", IEEE TUFFC 57(9), 2010, 2091–2094; numerics.md §1.13, §4.

    Examples
    --------
    >>> from sigmatau.datasets import nbs1000
    >>> k = theobr_kappa(nbs1000())
    >>> round(k.kappa, 6), k.n
    (1.085666, 30)
    """
    _check_kappa_method(method, "method")
    # κ is a ratio of variances, so it is computed on the power-of-two-scaled phase.
    p = _driver.prepare_scaled(THEOBR, data, rate, data_type)
    return _kappa(p.phase, method)


@_doc
def theobr(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", kappa: KappaMethod = "fast",
) -> StabilityResult:
    """Bias-removed Theo1 deviation (TheoBR).

    {common}
    Notes
    -----
    .. math:: \\mathrm{TheoBR}(m) = κ·\\mathrm{Theo1}(m),\\qquad
              κ = \\frac{1}{n+1} \\sum_{i=0}^{n}
              \\frac{\\mathrm{OAVAR}(m = 9+3i)}{\\mathrm{Theo1}(m = 12+4i)} ,

    ``n = ⌊0.1·N/3 − 3⌋`` for N phase points, so at least 90 phase points are
    needed (:class:`~sigmatau.errors.DataError` otherwise). κ is the measured
    ratio of AVAR (overlapped) to Theo1 over the τ range where both are
    available; it replaces the noise-type-dependent Theo1 bias table. κ is
    written in ``result.bias`` (``"theobr kappa=1.085666 (n=30)"``),
    ``result.bias_factor`` holds 1/κ (the divisor applied to Theo1) and
    :func:`theobr_kappa` returns it directly. τ, m, n and the grids are those of
    :func:`theo1`.

    ``kappa`` (``"fast"``, ``"exact"`` or ``"run"``) chooses how κ is computed: above
    16384 phase points ``"fast"`` (the default) applies the definition to the
    block-averaged record (Fast TheoBR) and ``result.bias`` says so
    (``"… (n=…, fast: blocks of b points)"``); ``"exact"`` applies it to the
    whole record at O(N²) cost; ``"run"`` averages the ratios over Stable32's
    wider "Run" span n = ⌊N/6⌋ − 3 (reproduces its Theo1 "Auto/BR" tables).
    See :func:`theobr_kappa` for the differences.

    References
    ----------
    D. A. Howe, Metrologia 43 (2006) S322; W. J. Riley, NIST SP 1065 (2008);
    J. A. Taylor & D. A. Howe, IEEE TUFFC 57(9), 2010, 2091–2094; numerics.md §1.13.

    Examples
    --------
    >>> import sigmatau.theo
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theo.theobr(nbs1000(), m=[10, 100])
    >>> r.bias, [round(float(d), 7) for d in r.dev]
    ('theobr kappa=1.085666 (n=30)', [0.1120871, 0.033123])
    """
    check_options(alpha, confidence, ci)
    method = _check_kappa_method(kappa)
    # The kernels run on the phase scaled by 2**-k (prepare() refuses beyond 2**±450);
    # var(c·x) = c²·var(x) and κ is scale free, so unscaling the variance is exact.
    p = _driver.prepare_scaled(THEOBR, data, rate, data_type)
    x, rate_f, dtype = p.phase, p.rate, p.data_type
    _check_kappa_points(x.size, dtype)
    ms = select_m(
        "theobr", n_points=x.size, rate=rate_f, taus=taus, m=m, points_per_decade=points_per_decade,
        m_min=THEOBR.min_m, m_max=THEOBR.max_m(x.size), stop_ratio=THEOBR.stop_ratio, even=True,
        tau_factor=0.75,
    )
    kap = _kappa(x, method)
    tau0 = 1.0 / rate_f
    raw, n = _theo1_kernel(x, ms, tau0) if ms.size else (np.empty(0), np.empty(0, dtype=np.int64))
    var = unscale_variance(np.maximum(kap.kappa * raw, 0.0), p.exponent, "theobr")
    result = StabilityResult(
        statistic="theobr", taus=0.75 * ms * tau0, m=ms, var=var, dev=np.sqrt(var), n=n,
        rate=rate_f, data_type=dtype, n_points=int(x.size), bias=_kappa_text(kap),
        bias_factor=np.full(ms.size, 1.0 / kap.kappa),
    )
    return finish(result, data, dtype, alpha=alpha, confidence=confidence, ci=ci,
                  identified=_kappa_noise(kap, ms))


def _kappa_noise(kap: TheoBRKappa, ms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Noise type of the TheoBR rows from κ (numerics.md §5.5): κ is compared with the fixed
    nominal AVAR/Theo1 ratios 0.4/0.6/1/1.71/2.24, as Stable32 does.

    κ is one average over a span of factors, not a property of each row, so every TheoBR row
    gets the same type; comparing it with the m-dependent ratio at each row's m gave a different
    type per row from the same number (46 of 181 rows of Stable32's PHASE.DAT TheoBR table
    agreed; the fixed ratios give 181 of 181)."""
    if ms.size == 0:
        return np.empty(0), np.empty(0)
    a = np.asarray(theo_noise_id(np.full(ms.size, kap.kappa)), dtype=float)
    return a, np.full(ms.size, np.nan)


# --- TheoH -------------------------------------------------------------------------

# Input validation only (TheoH mixes two estimators; see theoh()).
THEOH = Statistic(
    "theoh", _theo1_kernel, max_m=lambda n: n - 1, stop_ratio=1, min_points=3,
    min_m=1, even=False, tau_factor=1.0,
)


def theoh_split(n_points: int) -> tuple[int, int]:
    """Factors at which TheoH switches from AVAR to TheoBR for N phase points.

    Returns ``(k, m_lo)``: rows with ``m < k`` are OAVAR at τ = m·τ0, rows with
    ``m ≥ m_lo`` (even) are TheoBR at τ = 0.75·m·τ0. ``k = ⌊(N−1)/10⌋`` is the
    largest τ/τ0 not exceeding 10 % of the record ``T = (N−1)·τ0`` and
    ``m_lo`` is the smallest even factor with ``0.75·m_lo ≥ k``.

    Examples
    --------
    >>> theoh_split(1001)
    (100, 134)
    """
    k = (int(n_points) - 1) // 10
    m_lo = 2 * math.ceil(2 * k / 3)
    return k, m_lo


def _theoh_factors(
    n_points: int, rate: float, taus, m, points_per_decade: int,
) -> tuple[np.ndarray, np.ndarray]:
    """AVAR and TheoBR factors of a TheoH request (see :func:`theoh`)."""
    k, m_lo = theoh_split(n_points)
    m_max = n_points - 1
    common = dict(n_points=n_points, rate=rate, points_per_decade=points_per_decade)
    if m is not None or not isinstance(taus, str):
        if m is not None:
            if not (isinstance(taus, str) and taus == "octave"):
                raise ParameterError(f"give either taus={taus!r} or m, not both")
            req = select_m("theoh", taus="octave", m=m, m_min=1, m_max=m_max, stop_ratio=1, **common)
            gap = req[(req >= k) & (req < m_lo)]
            if gap.size:
                raise ParameterError(
                    f"theoh: m={gap.tolist()} falls between the AVAR part (m < {k}) and the"
                    f" TheoBR part (even m ≥ {m_lo}) for {n_points} phase points"
                )
            odd = req[(req >= m_lo) & (req % 2 == 1)]
            if odd.size:
                raise ParameterError(
                    f"theoh: TheoBR part (m ≥ {m_lo}) needs even averaging factors, got m={odd.tolist()}"
                )
            return req[req < k], req[req >= m_lo]
        t = np.atleast_1d(np.asarray(taus, dtype=float)) if is_numeric(taus) else None
        if t is None or t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise ParameterError(
                f"taus={taus!r} must be one of {TAU_GRIDS} or a 1-D array of positive τ in seconds"
            )
        steps = t * rate
        is_a = np.round(steps) < k
        sa, sb = steps[is_a], steps[~is_a]
        ma = np.round(sa).astype(np.int64)
        mb = np.maximum(2 * np.round(sb / 1.5), m_lo).astype(np.int64)
        off = np.concatenate((np.abs(ma - sa) > 1e-6 * np.maximum(sa, 1.0),
                              np.abs(0.75 * mb - sb) > 1e-6 * np.maximum(sb, 1.0)))
        if np.any(off):
            warnings.warn(
                f"theoh: {int(off.sum())} requested τ are not multiples of τ0 (AVAR part) or"
                " 1.5·τ0 (TheoBR part); they were rounded to the nearest usable averaging factor",
                RangeWarning,
                stacklevel=3,
            )
        ma = select_m("theoh", taus="octave", m=ma, m_min=1, m_max=k - 1, stop_ratio=1, **common) if ma.size else ma
        mb = (select_m("theoh", taus="octave", m=mb, m_min=m_lo, m_max=m_max, stop_ratio=1, even=True,
                       tau_factor=0.75, **common) if mb.size else mb)
        return ma, mb
    # Keyword grid in units of τ0, split at k; the TheoBR part keeps the grid's τ spacing.
    steps = m_grid(taus, max(1, int(0.75 * m_max)), points_per_decade=points_per_decade)
    ma = steps[steps < k]
    high = steps[steps >= k]
    mb = np.unique(np.maximum(2 * np.round(high / 1.5).astype(np.int64), m_lo))
    mb = mb[mb <= m_max]
    return ma, mb


@_doc
def theoh(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, alpha: Optional[int] = None, confidence: float = ONE_SIGMA,
    ci: Optional[CiMethod] = "chi2", kappa: KappaMethod = "fast",
) -> StabilityResult:
    """Hybrid TheoH deviation: AVAR at short τ, TheoBR at long τ.

    {common}
    Notes
    -----
    With ``k`` the largest τ not exceeding 10 % of the record
    ``T = (N−1)·τ0`` (``k = ⌊(N−1)/10⌋·τ0``),

    .. math:: \\mathrm{TheoH}(τ) =
              \\begin{cases} \\mathrm{AVAR}(τ = mτ_0), & 1 ≤ m < k/τ_0 \\\\
              \\mathrm{TheoBR}(m),\\ τ = 0.75\\,mτ_0, & k/(0.75τ_0) ≤ m ≤ N-1,\\ m \\text{ even} \\end{cases}

    AVAR here is the overlapped estimator (OAVAR, :func:`~sigmatau.allan.oadev`),
    as in TheoBR's κ; κ is computed once for the whole record, by the
    ``kappa`` method of :func:`theobr` (Fast TheoBR above 16384 phase points
    unless ``kappa="exact"``).

    Rows are sorted by τ; ``result.m`` is each row's own factor and
    ``result.taus`` its τ. Rows with ``taus < k`` are OAVAR (``taus == m·τ0``,
    ``n = N − 2m``, ``bias_factor == 1``); the others are TheoBR
    (``taus == 0.75·m·τ0``, ``n = (N−m)·m/2``, ``bias_factor == 1/κ``).
    ``result.bias`` states the split and κ, and :func:`theoh_split` returns it.

    Keyword grids are built in τ: grid points below k use AVAR at that m; the
    others use the even TheoBR factor nearest to τ/(0.75·τ0) (at least the first
    TheoBR factor), up to τ = 0.75·(N−1)·τ0. Explicit ``m`` are read per part:
    ``m < k`` is AVAR, even ``m ≥ k/0.75`` is TheoBR; factors in between are
    rejected. Explicit ``taus`` below k go to AVAR, the others to TheoBR.

    References
    ----------
    D. A. Howe, "ThêoH: a hybrid, high-confidence statistic that improves on the
    Allan deviation", Metrologia 43 (2006) S322–S331; W. J. Riley, NIST SP 1065
    (2008) §5.2.16; numerics.md §1.14.

    Examples
    --------
    >>> import sigmatau.theo
    >>> from sigmatau.datasets import nbs1000
    >>> r = sigmatau.theo.theoh(nbs1000())
    >>> r.m.tolist()
    [1, 2, 4, 8, 16, 32, 64, 170, 342, 682]
    >>> r.bias
    'theoh: oavar for tau < 100 s (m < 100); theobr kappa=1.085666 (n=30) for tau >= 100 s (even m >= 134, tau = 0.75 m tau0)'
    """
    check_options(alpha, confidence, ci)
    method = _check_kappa_method(kappa)
    # Scaled phase as in theobr(); the variance is unscaled before the low/high split.
    p = _driver.prepare_scaled(THEOH, data, rate, data_type)
    x, rate_f, dtype = p.phase, p.rate, p.data_type
    N = x.size
    _check_kappa_points(N, dtype)
    tau0 = 1.0 / rate_f
    ma, mb = _theoh_factors(N, rate_f, taus, m, points_per_decade)
    kap = _kappa(x, method)
    va, na = oavar_kernel(x, ma, tau0) if ma.size else (np.empty(0), np.empty(0, dtype=np.int64))
    vb, nb = _theo1_kernel(x, mb, tau0) if mb.size else (np.empty(0), np.empty(0, dtype=np.int64))
    var = np.concatenate((np.asarray(va, dtype=float), kap.kappa * vb))
    var = unscale_variance(np.where(var < 0.0, 0.0, var), p.exponent, "theoh")
    k, m_lo = theoh_split(N)
    bias = (
        f"theoh: oavar for tau < {k * tau0:g} s (m < {k}); {_kappa_text(kap)} for tau >= {k * tau0:g} s"
        f" (even m >= {m_lo}, tau = 0.75 m tau0)"
    )
    common = dict(rate=rate_f, data_type=dtype, n_points=int(N), bias=bias)
    # Each part gets the EDF of its own estimator: Greenhall's OAVAR EDF with the
    # noise identified at m below k, the Theo1 EDF with the noise type from κ above.
    low = StabilityResult(statistic="oadev", taus=ma * tau0, m=ma, var=var[: ma.size],
                          dev=np.sqrt(var[: ma.size]), n=na, **common)
    high = StabilityResult(statistic="theoh", taus=0.75 * mb * tau0, m=mb, var=var[ma.size:],
                           dev=np.sqrt(var[ma.size:]), n=nb, **common)
    low = finish(low, data, dtype, alpha=alpha, confidence=confidence, ci=ci)
    high = finish(high, data, dtype, alpha=alpha, confidence=confidence, ci=ci,
                  identified=_kappa_noise(kap, mb))
    merged = {}
    for name in ("alpha", "alpha_estimate", "edf", "ci_low", "ci_high"):
        parts = (getattr(low, name), getattr(high, name))
        merged[name] = None if parts[0] is None and parts[1] is None else np.concatenate(
            [p if p is not None else np.full(r, np.nan) for p, r in zip(parts, (ma.size, mb.size))])
    reasons = None
    if ci is not None:
        reasons = (low.ci_reason or ("",) * ma.size) + (high.ci_reason or ("",) * mb.size)
    return StabilityResult(
        statistic="theoh",
        taus=np.concatenate((ma * tau0, 0.75 * mb * tau0)),
        m=np.concatenate((ma, mb)),
        var=var,
        dev=np.sqrt(var),
        n=np.concatenate((na, nb)).astype(np.int64),
        bias_factor=np.concatenate((np.ones(ma.size), np.full(mb.size, 1.0 / kap.kappa))),
        confidence=low.confidence if low.confidence is not None else high.confidence,
        ci_reason=reasons,
        **common,
        **merged,
    )
