"""The compiled loops (numba) behind :mod:`sigmatau.core.fused`: one pass over the record each.

Every function here is ``@njit(cache=True, nogil=True)``: compiled on first use and cached on
disk next to this file, and run without the GIL, so channels analysed in threads run in
parallel. Loops index views of the record from 0 (``for i in range(count)``): numba then knows
each index is non-negative, drops its negative-index wraparound, and LLVM vectorises the loop.
Nothing is compiled with fast-math, so no operation is reassociated or contracted into an FMA:
each term is formed by the very operations of the numpy kernel it stands for.

This module is longer than the house's 600 lines because numba's on-disk cache checks only the
file a function is defined in: a kernel inlines the helpers it calls (the compensated sums, the
virtual window sums), and a helper changed in another file would leave stale compiled kernels
behind. Everything compiled therefore lives in this one file. Import it only through
:mod:`sigmatau.core.fused` (which :mod:`sigmatau.core.accel` imports on first need): it imports
numba.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True)

#: Terms per block of the compensated sum (a block's buffers stay in L1).
BLOCK = 512

# Kinds of terms read from the window sums at factor m (OAVAR and OHVAR read A, MVAR reads B).
OAVAR, OHVAR, MVAR = 0, 1, 2


# --- summation -----------------------------------------------------------------------


@njit(inline="always", **_JIT)
def _add(acc, v):
    """acc = (sum, compensation) += v (Neumaier)."""
    t = acc[0] + v
    if abs(acc[0]) >= abs(v):
        acc[1] += (acc[0] - t) + v
    else:
        acc[1] += (v - t) + acc[0]
    acc[0] = t


@njit(inline="always", **_JIT)
def _add_squares(acc, buf, n):
    """acc += Σ buf[:n]² (four accumulators, then one compensated addition)."""
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    i = 0
    while i + 4 <= n:
        a = buf[i]
        b = buf[i + 1]
        c = buf[i + 2]
        d = buf[i + 3]
        s0 += a * a
        s1 += b * b
        s2 += c * c
        s3 += d * d
        i += 4
    while i < n:
        a = buf[i]
        s0 += a * a
        i += 1
    _add(acc, (s0 + s1) + (s2 + s3))


# --- phase kernels: Σ terms² at one factor -------------------------------------------
#
# Loops index views of the record from 0 (``for i in range(count)``): numba then knows every
# index is non-negative, drops its negative-index wraparound and LLVM vectorises the loop.


@njit(**_JIT)
def oavar_phase_sum(x, m):
    # numpy: sumsq_combination([(1, x[2m:]), (-2, x[m:-m]), (1, x[:-2m])])
    k = x.size - 2 * m
    x0, x1, x2 = x[2 * m:], x[m:], x
    buf = np.empty(BLOCK)
    acc = np.zeros(2)
    for lo in range(0, k, BLOCK):
        cnt = min(BLOCK, k - lo)
        a0, a1, a2 = x0[lo:lo + cnt], x1[lo:lo + cnt], x2[lo:lo + cnt]
        for i in range(cnt):
            buf[i] = (a0[i] + a1[i] * -2.0) + a2[i]
        _add_squares(acc, buf, cnt)
    return acc[0] + acc[1]


@njit(**_JIT)
def ohvar_phase_sum(x, m):
    # numpy: sumsq_combination([(1, x[3m:]), (-3, x[2m:-m]), (3, x[m:-2m]), (-1, x[:-3m])])
    k = x.size - 3 * m
    x0, x1, x2, x3 = x[3 * m:], x[2 * m:], x[m:], x
    buf = np.empty(BLOCK)
    acc = np.zeros(2)
    for lo in range(0, k, BLOCK):
        cnt = min(BLOCK, k - lo)
        a0, a1, a2, a3 = x0[lo:lo + cnt], x1[lo:lo + cnt], x2[lo:lo + cnt], x3[lo:lo + cnt]
        for i in range(cnt):
            buf[i] = ((a0[i] + a1[i] * -3.0) + a2[i] * 3.0) - a3[i]
        _add_squares(acc, buf, cnt)
    return acc[0] + acc[1]


@njit(**_JIT)
def _second_differences(x, m, start, cnt, out):
    """out[i] = (x[s+2m] - 2.0*x[s+m]) + x[s], s = start + i (numpy: x[2m:] - 2.0*x[m:-m] + x[:-2m])."""
    a0, a1, a2 = x[start + 2 * m:start + 2 * m + cnt], x[start + m:start + m + cnt], x[start:start + cnt]
    for i in range(cnt):
        out[i] = (a0[i] - 2.0 * a1[i]) + a2[i]


@njit(**_JIT)
def mvar_phase_sum(x, m):
    """Σ_j (c[j+m] - c[j])², c the running sum of the second differences (numpy.cumsum: sequential).

    Two cursors run along the same sequential sum, m apart, so every c[j] is the numpy value
    and nothing of the record's size is stored.
    """
    n2 = x.size - 2 * m  # second differences
    ns = n2 + 1 - m  # window sums
    head = np.empty(BLOCK)
    tail = np.empty(BLOCK)
    lead = 0.0  # c[m]
    for lo in range(0, m, BLOCK):
        cnt = min(BLOCK, m - lo)
        _second_differences(x, m, lo, cnt, head)
        for i in range(cnt):
            lead = lead + head[i]
    lag = 0.0  # c[0]
    buf = np.empty(BLOCK)
    acc = np.zeros(2)
    for lo in range(0, ns, BLOCK):
        cnt = min(BLOCK, ns - lo)
        ahead = min(cnt, n2 - m - lo)  # the lead cursor stops at c[n2]
        _second_differences(x, m, lo + m, ahead, head)
        _second_differences(x, m, lo, cnt, tail)
        for i in range(cnt):
            buf[i] = lead - lag
            if i < ahead:
                lead = lead + head[i]
            lag = lag + tail[i]
        _add_squares(acc, buf, cnt)
    return acc[0] + acc[1]


@njit(**_JIT)
def _totvar_edge(x, m, s, e, acc, buf, left, right):
    """TOTVAR terms i = s … e-1 where an operand is reflected, in blocks from s (acc[0:2])."""
    n = x.size
    c0 = 2.0 * x[0]
    c1 = 2.0 * x[n - 1]
    for lo in range(s, e, BLOCK):
        cnt = min(BLOCK, e - lo)
        mid = x[lo:lo + cnt]
        if lo < m:  # x*_{i-m} = 2x_0 - x_{m-i}
            src = x[m - lo - cnt + 1:m - lo + 1][::-1]
            for i in range(cnt):
                left[i] = c0 - src[i]
        else:
            src = x[lo - m:lo - m + cnt]
            for i in range(cnt):
                left[i] = src[i]
        if lo + m >= n:  # x*_{i+m} = 2x_{N-1} - x_{2N-2-i-m}
            top = 2 * n - 2 - m - lo
            src = x[top - cnt + 1:top + 1][::-1]
            for i in range(cnt):
                right[i] = c1 - src[i]
        else:
            src = x[lo + m:lo + m + cnt]
            for i in range(cnt):
                right[i] = src[i]
        for i in range(cnt):
            buf[i] = (left[i] - mid[i] * 2.0) + right[i]
        _add_squares(acc[0:2], buf, cnt)


@njit(**_JIT)
def totvar_sums(x, m, with_oavar):
    """(TOTVAR sum, OAVAR sum) at m, in one pass over the phase x (the OAVAR sum only if asked, else 0).

    TOTVAR: Σ_{i=1}^{N-2} (x*_{i-m} - x_i·2 + x*_{i+m})², x* the record reflected at both ends
    (2.0*x[0] - x[-j] below 0, 2.0*x[N-1] - x[2N-2-j] above N-1: the values of the numpy
    extension, stats.total._totvar_sum). Its interior terms, i = j + m with j = 0 … N-2m-1, read
    the three points of OAVAR's term j, (x[j+2m] + x[j+m]·(-2)) + x[j]: both are formed from the
    same loads, in blocks of j from 0 (the grouping of :func:`oavar_phase_sum`). Then the
    reflected terms at each end, i < m and i ≥ N - m, in their own blocks.
    """
    n = x.size
    buf = np.empty(BLOCK)
    left = np.empty(BLOCK)
    right = np.empty(BLOCK)
    acc = np.zeros(4)
    lo_cut = min(max(m, 1), n - 1)
    hi_cut = max(min(n - 1, n - m), lo_cut)
    cross = n - m  # from here on x*_{i+m} is reflected: within the left end when 2m > N
    if 1 < cross < lo_cut:
        _totvar_edge(x, m, 1, cross, acc, buf, left, right)
        _totvar_edge(x, m, cross, lo_cut, acc, buf, left, right)
    else:
        _totvar_edge(x, m, 1, lo_cut, acc, buf, left, right)
    k = hi_cut - lo_cut  # interior terms: i = lo_cut … hi_cut-1, j = i - m
    if k > 0:
        x0, x1, x2 = x[lo_cut - m:], x[lo_cut:], x[lo_cut + m:]
        for lo in range(0, k, BLOCK):
            cnt = min(BLOCK, k - lo)
            a0, a1, a2 = x0[lo:lo + cnt], x1[lo:lo + cnt], x2[lo:lo + cnt]
            for i in range(cnt):
                buf[i] = (a0[i] - a1[i] * 2.0) + a2[i]
            _add_squares(acc[0:2], buf, cnt)
            if with_oavar:
                for i in range(cnt):
                    buf[i] = (a2[i] + a1[i] * -2.0) + a0[i]
                _add_squares(acc[2:4], buf, cnt)
    _totvar_edge(x, m, hi_cut, n - 1, acc, buf, left, right)
    return acc[0] + acc[1], acc[2] + acc[3]


# --- window sums of frequency samples (WindowSums, with A virtual while short) -------


@njit(inline="always", **_JIT)
def _virtual(y, mean, start, cnt, w, out):
    """out[i] = A_w[start + i] while A is virtual: ((y_s - μ) + (y_{s+1} - μ)) + …, w samples,
    left to right, as WindowSums' restart and unit increments build it."""
    v = y[start:start + cnt + w - 1]
    for i in range(cnt):
        out[i] = v[i] - mean
    for k in range(1, w):
        vk = v[k:k + cnt]
        for i in range(cnt):
            out[i] = out[i] + (vk[i] - mean)


@njit(**_JIT)
def fill_a(a, y, mean, w):
    """Store the virtual A_w (its M - w + 1 values)."""
    n = y.size - w + 1
    for lo in range(0, n, BLOCK):
        cnt = min(BLOCK, n - lo)
        _virtual(y, mean, lo, cnt, w, a[lo:lo + cnt])


@njit(**_JIT)
def fill_b(b, y, mean):
    """B_1 = the centred samples (WindowSums._restart)."""
    for i in range(y.size):
        b[i] = y[i] - mean


@njit(**_JIT)
def increment(a, b, y, mean, w, virtual, has_b):
    """WindowSums._increment from w to w + 1: B first (it reads A_w), then A unless virtual."""
    M = y.size
    aw = np.empty(BLOCK)
    if has_b:
        n = M - 2 * w
        for lo in range(0, n, BLOCK):
            cnt = min(BLOCK, n - lo)
            if virtual:
                _virtual(y, mean, lo + w, cnt, w, aw)
            else:
                src = a[lo + w:lo + w + cnt]
                for i in range(cnt):
                    aw[i] = src[i]
            bb = b[lo:lo + cnt]
            yy = y[lo + 2 * w:lo + 2 * w + cnt]
            for i in range(cnt):
                bb[i] = (bb[i] + aw[i] * 2.0) + (yy[i] - mean)
    if not virtual:
        n = M - w
        yy = y[w:]
        for i in range(n):
            a[i] = a[i] + (yy[i] - mean)


@njit(inline="always", **_JIT)
def _double_a_block(a, y, mean, w, virtual, lo, cnt, scratch):
    """A_2w[j] = A_w[j] + A_w[j+w] for j = lo … lo+cnt-1 (WindowSums._double_step), in place or
    from the virtual A."""
    out = a[lo:lo + cnt]
    if virtual:
        _virtual(y, mean, lo, cnt, w, out)
        _virtual(y, mean, lo + w, cnt, w, scratch)
        for i in range(cnt):
            out[i] = out[i] + scratch[i]
    else:
        ahead = a[lo + w:lo + w + cnt]
        for i in range(cnt):
            out[i] = out[i] + ahead[i]


@njit(**_JIT)
def double_a(a, y, mean, w, virtual):
    n = y.size - 2 * w + 1
    scratch = np.empty(BLOCK)
    for lo in range(0, n, BLOCK):
        _double_a_block(a, y, mean, w, virtual, lo, min(BLOCK, n - lo), scratch)


@njit(inline="always", **_JIT)
def _double_b_block(b, w, lo, cnt):
    """B_2w[j] = (B_w[j] + B_w[j+w]·2) + B_w[j+2w] for j = lo … lo+cnt-1, in place."""
    b0, b1, b2 = b[lo:lo + cnt], b[lo + w:lo + w + cnt], b[lo + 2 * w:lo + 2 * w + cnt]
    for i in range(cnt):
        b0[i] = (b0[i] + b1[i] * 2.0) + b2[i]


@njit(**_JIT)
def double_b(b, w, M):
    n = M - 4 * w + 2
    for lo in range(0, n, BLOCK):
        _double_b_block(b, w, lo, min(BLOCK, n - lo))


@njit(inline="always", **_JIT)
def _a_block_terms(a0, a1, a2, cnt1, cnt2, acc, buf):
    """acc[0:2] += Σ of the cnt1 OAVAR terms A[j+m] - A[j], acc[2:4] += Σ of the cnt2 OHVAR terms
    (A[j+2m] + A[j+m]·(-2)) + A[j] of one block, ``a0``, ``a1``, ``a2`` = A at j, j+m, j+2m."""
    if cnt1 > 0:
        for i in range(cnt1):
            buf[i] = a1[i] - a0[i]
        _add_squares(acc[0:2], buf, cnt1)
    if cnt2 > 0:
        for i in range(cnt2):
            buf[i] = (a2[i] + a1[i] * -2.0) + a0[i]
        _add_squares(acc[2:4], buf, cnt2)


@njit(**_JIT)
def a_terms(a, y, mean, m, k1, k2, virtual):
    """(Σ OAVAR terms², Σ OHVAR terms²) at m from A_m: the first k1 and k2 terms (0: none).

    Both are grouped in blocks of BLOCK terms from j = 0, whichever kernel forms them, so a
    sum does not depend on whether the other was formed with it.
    """
    acc = np.zeros(4)
    buf = np.empty(BLOCK)
    v0 = np.empty(BLOCK)
    v1 = np.empty(BLOCK)
    v2 = np.empty(BLOCK)
    for lo in range(0, max(k1, k2), BLOCK):
        cnt1 = min(BLOCK, k1 - lo)
        cnt2 = min(BLOCK, k2 - lo)
        cnt = max(cnt1, cnt2)
        if virtual:
            _virtual(y, mean, lo, cnt, m, v0)
            _virtual(y, mean, lo + m, cnt, m, v1)
            if cnt2 > 0:
                _virtual(y, mean, lo + 2 * m, cnt2, m, v2)
            _a_block_terms(v0, v1, v2, cnt1, cnt2, acc, buf)
        else:
            a0, a1 = a[lo:lo + cnt], a[lo + m:lo + m + cnt]
            a2 = a[lo + 2 * m:lo + 2 * m + max(cnt2, 0)]
            _a_block_terms(a0, a1, a2, cnt1, cnt2, acc, buf)
    return acc[0] + acc[1], acc[2] + acc[3]


@njit(**_JIT)
def a_double_terms(a, y, mean, w, virtual, k1, k2):
    """Double A from w to m = 2w and form the OAVAR (k1) and OHVAR (k2) sums at m, in one pass.

    A term reads A up to m (OAVAR) or 2m (OHVAR) ahead, so the terms are formed that far behind
    the doubling, from values already doubled, in whole blocks from j = 0 (as :func:`a_terms`).
    """
    n = y.size - 2 * w + 1
    m = 2 * w
    scratch = np.empty(BLOCK)
    buf = np.empty(BLOCK)
    acc = np.zeros(4)
    none = np.empty(0)
    done1 = 0  # OAVAR terms formed so far
    done2 = 0  # OHVAR terms formed so far
    for lo in range(0, n, BLOCK):
        hi = min(lo + BLOCK, n)
        _double_a_block(a, y, mean, w, virtual, lo, hi - lo, scratch)
        top1 = min(hi - m, k1)
        while done1 + BLOCK <= top1:
            _a_block_terms(a[done1:done1 + BLOCK], a[done1 + m:done1 + m + BLOCK], none, BLOCK, 0, acc, buf)
            done1 += BLOCK
        top2 = min(hi - 2 * m, k2)
        while done2 + BLOCK <= top2:
            _a_block_terms(a[done2:done2 + BLOCK], a[done2 + m:done2 + m + BLOCK],
                           a[done2 + 2 * m:done2 + 2 * m + BLOCK], 0, BLOCK, acc, buf)
            done2 += BLOCK
    if done1 < k1:  # the last, partial block
        cnt = k1 - done1
        _a_block_terms(a[done1:done1 + cnt], a[done1 + m:done1 + m + cnt], none, cnt, 0, acc, buf)
    if done2 < k2:
        cnt = k2 - done2
        _a_block_terms(a[done2:done2 + cnt], a[done2 + m:done2 + m + cnt], a[done2 + 2 * m:done2 + 2 * m + cnt],
                       0, cnt, acc, buf)
    return acc[0] + acc[1], acc[2] + acc[3]


@njit(inline="always", **_JIT)
def _b_block_terms(b, m, lo, cnt, buf):
    b0, b1 = b[lo:lo + cnt], b[lo + m:lo + m + cnt]
    for i in range(cnt):
        buf[i] = b1[i] - b0[i]


@njit(**_JIT)
def b_terms(b, m, k):
    """Σ_{j<k} (B[j+m] - B[j])² (MVAR at m)."""
    buf = np.empty(BLOCK)
    acc = np.zeros(2)
    for lo in range(0, k, BLOCK):
        cnt = min(BLOCK, k - lo)
        _b_block_terms(b, m, lo, cnt, buf)
        _add_squares(acc, buf, cnt)
    return acc[0] + acc[1]


@njit(**_JIT)
def b_double_terms(b, w, M, k):
    """Double B from w to m = 2w and sum the squares of the k MVAR terms at m, in one pass."""
    n = M - 4 * w + 2
    m = 2 * w
    buf = np.empty(BLOCK)
    acc = np.zeros(2)
    done = 0
    for lo in range(0, n, BLOCK):
        hi = min(lo + BLOCK, n)
        _double_b_block(b, w, lo, hi - lo)
        top = min(hi - m, k)
        while done + BLOCK <= top:  # whole blocks only: the same grouping as b_terms
            _b_block_terms(b, m, done, BLOCK, buf)
            _add_squares(acc, buf, BLOCK)
            done += BLOCK
    while done < k:  # the last, partial block
        cnt = min(BLOCK, k - done)
        _b_block_terms(b, m, done, cnt, buf)
        _add_squares(acc, buf, cnt)
        done += cnt
    return acc[0] + acc[1]


# --- lag-1 autocorrelation and phase ------------------------------------------------


@njit(**_JIT)
def _differences(z, d, lo, cnt, out):
    """out[i] = z differenced d times (numpy.diff applied d times, d ≤ 3) at lo + i."""
    z0 = z[lo:lo + cnt + d]
    if d == 0:
        for i in range(cnt):
            out[i] = z0[i]
        return
    z1 = z0[1:]
    if d == 1:
        for i in range(cnt):
            out[i] = z1[i] - z0[i]
        return
    z2 = z0[2:]
    if d == 2:
        for i in range(cnt):
            out[i] = (z2[i] - z1[i]) - (z1[i] - z0[i])
        return
    z3 = z0[3:]
    for i in range(cnt):
        out[i] = ((z3[i] - z2[i]) - (z2[i] - z1[i])) - ((z2[i] - z1[i]) - (z1[i] - z0[i]))


@njit(inline="always", **_JIT)
def _unrolled_sum(v, n):
    """numpy's pairwise_sum for 8 ≤ n ≤ 128: eight partial sums, combined as a tree, then the rest."""
    r0, r1, r2, r3, r4, r5, r6, r7 = v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]
    i = 8
    while i < n - (n % 8):
        r0 += v[i]
        r1 += v[i + 1]
        r2 += v[i + 2]
        r3 += v[i + 3]
        r4 += v[i + 4]
        r5 += v[i + 5]
        r6 += v[i + 6]
        r7 += v[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += v[i]
        i += 1
    return res


@njit(**_JIT)
def lag1_sums(z, d):
    """Σ (z⁽ᵈ⁾ − mean)² and Σ (z⁽ᵈ⁾_k − mean)(z⁽ᵈ⁾_{k+1} − mean) of the d-th differences z⁽ᵈ⁾ of z,
    in two passes (the mean, then the centred sums), nothing stored."""
    nd = z.size - d
    buf = np.empty(BLOCK + 1)
    # The mean as numpy's (z⁽ᵈ⁾).mean(), to the bit: r1 of a short series far from zero
    # (block means of a sensor with a bias) moves by ~1e-12 with the mean's last digit.
    mean = (0.0 + pairwise(z, 0, nd, SUM_DIFFERENCES, 0.0, d)) / nd
    acc_den = np.zeros(2)
    acc_num = np.zeros(2)
    for lo in range(0, nd, BLOCK):
        cnt = min(BLOCK + 1, nd - lo)  # one point more: the product that crosses into the next block
        _differences(z, d, lo, cnt, buf)
        for i in range(cnt):
            buf[i] = buf[i] - mean
        own = min(BLOCK, cnt)
        s_den = 0.0
        s_num = 0.0
        for i in range(own):
            s_den += buf[i] * buf[i]
        for i in range(cnt - 1):
            s_num += buf[i] * buf[i + 1]
        _add(acc_den, s_den)
        _add(acc_num, s_num)
    return mean, acc_den[0] + acc_den[1], acc_num[0] + acc_num[1]


# numpy's pairwise summation (``pairwise_sum_DOUBLE``, used by add.reduce, so by sum, mean and var):
# below 8 values a plain loop from 0.0, up to 128 eight partial sums combined as a tree, above
# that the two halves (the first a multiple of 8) summed alike and added. Evaluated here without
# recursion (numba's cache does not reload recursive functions safely) by walking the same tree.

SUM_PLAIN, SUM_SQUARED_DEVIATIONS, SUM_DIFFERENCES = 0, 1, 2


@njit(inline="always", **_JIT)
def _leaf(a, lo, n, kind, mean, d, buf):
    """numpy's sum of a leaf of at most 128 values: a[lo:lo+n] (kind SUM_PLAIN), (a - mean)²
    (SUM_SQUARED_DEVIATIONS, the values ``numpy.var`` sums) or the d-th differences of a
    (SUM_DIFFERENCES, what ``numpy.diff(a, d).mean()`` sums)."""
    if kind == SUM_PLAIN:
        v = a[lo:lo + n]
    elif kind == SUM_SQUARED_DEVIATIONS:
        src = a[lo:lo + n]
        for i in range(n):
            t = src[i] - mean
            buf[i] = t * t
        v = buf
    else:
        _differences(a, d, lo, n, buf)
        v = buf
    if n < 8:
        res = 0.0
        for i in range(n):
            res += v[i]
        return res
    return _unrolled_sum(v, n)


@njit(**_JIT)
def pairwise(a, lo, n, kind, mean, d):
    """numpy's pairwise sum of the n values of ``kind`` from lo (see :func:`_leaf`), bit for bit."""
    return _pairwise(a, lo, n, kind, mean, d, np.empty(128), np.empty((3, 64), dtype=np.int64), np.empty(64))


@njit(inline="always", **_JIT)
def _pairwise(a, lo, n, kind, mean, d, buf, nodes, values):
    """:func:`pairwise` with its work arrays given (a leaf buffer of 128 values, a stack of 64
    tree nodes and of 64 partial sums), for callers that sum many blocks."""
    if n <= 128:
        return _leaf(a, lo, n, kind, mean, d, buf)
    # post-order walk of the halving tree: node (lo, n, stage); values of finished subtrees
    node_lo = nodes[0]
    node_n = nodes[1]
    stage = nodes[2]
    top = 0
    nv = 0
    node_lo[0], node_n[0], stage[0] = lo, n, 0
    while top >= 0:
        s, c, st = node_lo[top], node_n[top], stage[top]
        if c <= 128:
            values[nv] = _leaf(a, s, c, kind, mean, d, buf)
            nv += 1
            top -= 1
            continue
        half = c // 2
        half -= half % 8
        if st == 0:  # the first half
            stage[top] = 1
            top += 1
            node_lo[top], node_n[top], stage[top] = s, half, 0
        elif st == 1:  # then the second
            stage[top] = 2
            top += 1
            node_lo[top], node_n[top], stage[top] = s + half, c - half, 0
        else:  # both done: first + second
            second = values[nv - 1]
            first = values[nv - 2]
            nv -= 2
            values[nv] = first + second
            nv += 1
            top -= 1
    return values[0]


@njit(**_JIT)
def block_sums(y, m, out):
    """out[k] = the sum of block k of m samples, as numpy's ``reshape(k, m).sum(axis=1)``."""
    if m < 8:  # numpy's short case, inline: a call per block would cost more than the block
        for k in range(out.size):
            v = y[k * m:(k + 1) * m]
            res = 0.0
            for i in range(m):
                res += v[i]
            out[k] = res
        return
    buf = np.empty(128)
    nodes = np.empty((3, 64), dtype=np.int64)
    values = np.empty(64)
    for k in range(out.size):
        out[k] = _pairwise(y, k * m, m, SUM_PLAIN, 0.0, 0, buf, nodes, values)


@njit(**_JIT)
def pair_sums(half, out):
    """out[k] = half[2k] + half[2k+1]: numpy's pairwise split of a block into its two halves."""
    for k in range(out.size):
        out[k] = half[2 * k] + half[2 * k + 1]


@njit(**_JIT)
def nan_abs_peak(v):
    """max |v| over the values that are not NaN (0.0 when none): numpy.nanmax(numpy.abs(v))."""
    peak = 0.0
    for i in range(v.size):
        a = abs(v[i])
        if a > peak:
            peak = a
    return peak


@njit(**_JIT)
def non_finite(bits):
    """How many of the float64 values whose bit patterns are ``bits`` are NaN or infinite
    (exponent field all ones): an integer reduction, which the compiler vectorises."""
    count = 0
    for i in range(bits.size):
        count += (bits[i] & 0x7FF0000000000000) == 0x7FF0000000000000
    return count


@njit(**_JIT)
def phase_of_freq(y, mean, scale, x):
    """x[0] = 0, x[i+1] = (Σ_{k≤i} (y_k − μ))·scale: numpy.cumsum of the centred samples, times 1/rate."""
    s = y[0] - mean
    x[0] = 0.0
    x[1] = s * scale
    for i in range(1, y.size):
        s = s + (y[i] - mean)
        x[i + 1] = s * scale
