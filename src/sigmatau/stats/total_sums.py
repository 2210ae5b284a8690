"""The sums of MTOT, TTOT and HTOT: Σ over every 3m-point subsequence, detrended and reflected.

Split from :mod:`sigmatau.stats.total` (the public total variances, their
kernels and bias corrections) because this is the numerical machinery alone:
the direct block kernel :func:`tot_sums`, O(N·m) per τ with O(N) + O(block·m)
memory, which serves m = 1, and :func:`tot_sums_fast`, which expands the sum of
squares into running sums and costs O(N) time and memory per τ.
:func:`tot_total` picks one. ``tests/test_total.py`` and
``tests/test_total_fast.py`` hold both to the plain definitions.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..core.numeric import sumsq

__all__ = ["tot_sums", "tot_sums_fast", "tot_total", "BLOCK_ELEMENTS", "FAST_MIN_M"]


#: Values per temporary array when the 3m-point subsequences are processed in
#: blocks (2**17 float64 = 1 MiB; three such arrays are live at a time).
BLOCK_ELEMENTS = 1 << 17


def tot_sums(u: np.ndarray, m: int, block: Optional[int] = None) -> tuple[float, int]:
    """``Σ_n Σ_j z_j(n)²`` over the subsequences of ``u`` for the MTOT/HTOT construction.

    For every start ``n`` the 3m points ``s_k = u_{n+k}`` lose their
    half-average slope, are extended to ``e = [rev s', s', rev s']`` (9m
    points) and ``z_j = a_j - 2a_{j+m} + a_{j+2m}``, j = 0 … 6m-1, where ``a_j``
    is the mean of ``e_j … e_{j+m-1}``. Returns the double sum and the number
    of subsequences ``len(u) - 3m + 1``.

    With ``S_t = s'_0 + … + s'_{t-1}`` (t = 0 … 3m) and ``T = S_{3m}`` the
    running sum of ``e`` is ``T - S_{3m-t}``, ``T + S_{t-3m}`` and
    ``3T - S_{9m-t}`` on its three thirds, so ``m·z_j`` is a signed sum of four
    m-long slices of ``S`` (forward or reversed) and a multiple of ``T``.
    """
    m = int(m)
    length = 3 * m
    windows = u.size - length + 1
    h1 = length // 2
    h2 = length - h1
    k = np.arange(length, dtype=float)
    k_sum = k.sum()
    rows = max(1, min(windows, (block or BLOCK_ELEMENTS) // (length + 1)))
    view = sliding_window_view(u, length)
    s_buf = np.empty((rows, length + 1))
    line_buf = np.empty((rows, length))
    q_buf = np.empty((rows, m))
    total = 0.0
    for start in range(0, windows, rows):
        blk = view[start : start + rows]
        r = blk.shape[0]
        s_full = s_buf[:r]
        d = s_full[:, 1:]
        # A constant and a line per subsequence do not change z; removing the
        # line and centring keep the running sums small.
        np.subtract(blk, blk[:, :1], out=d)
        lo = d[:, :h1].sum(axis=1)
        hi = d[:, h2:].sum(axis=1)
        mid = d[:, h1] if h2 > h1 else 0.0
        slope = (hi - lo) / (h1 * h2)
        offset = (lo + hi + mid - slope * k_sum) / length
        line = line_buf[:r]
        np.multiply(slope[:, None], k, out=line)
        line += offset[:, None]
        d -= line
        # Running sums of every row at once: each centred row sums to ~0, so
        # one cumulative sum over the flattened block only needs the value
        # carried in from the previous rows removed.
        s_full[:, 0] = 0.0
        flat_s = s_full.reshape(-1)
        np.cumsum(flat_s, out=flat_s)
        s_full -= s_full[:, :1].copy()
        f0, f1, f2 = s_full[:, :m], s_full[:, m : 2 * m], s_full[:, 2 * m : length]
        rev = s_full[:, ::-1]  # rev[:, i] = S_{3m-i}
        r0, r1, r2 = rev[:, :m], rev[:, m : 2 * m], rev[:, 2 * m : length]
        t = s_full[:, length:]
        q = q_buf[:r]
        flat = q.reshape(-1)
        # m·z_j on the six m-long stretches j = 0…m-1, m…2m-1, …, 5m…6m-1.
        np.subtract(r2, r1, out=q)
        q *= 3.0
        q += f0
        q += r0
        total += sumsq(flat)
        np.add(f0, r2, out=q)
        q *= -3.0
        q += f1
        q += r1
        total += sumsq(flat)
        np.subtract(f0, f1, out=q)
        q *= 3.0
        q += f2
        q += r2
        total += sumsq(flat)
        np.subtract(f1, f2, out=q)
        q *= 3.0
        q -= f0
        q -= r0
        q += 2.0 * t
        total += sumsq(flat)
        np.add(r0, f2, out=q)
        q *= 3.0
        q -= f1
        q -= r1
        q -= 4.0 * t
        total += sumsq(flat)
        np.subtract(r1, r0, out=q)
        q *= 3.0
        q -= f2
        q -= r2
        q += 2.0 * t
        total += sumsq(flat)
    return total / m**2, windows


# --- MTOT/HTOT in O(N) per τ ------------------------------------------------------
#
# Let P_t be the sum of the first t samples. In window n (notation of
# tot_sums) S_t = P_{n+t} - P_n - b_n·t(t-1)/2, and the running sum of the
# 9m-point extension is T - S_{3m-τ}, T + S_{τ-3m} or 3T - S_{9m-τ} on its
# three thirds. With j = r·m + i (stretch r = 0 … 5, i < m) the points j,
# j+m, j+2m, j+3m stay in fixed thirds, so
#
#     m·z_j(n) = F_r(n+i) + G_r(n-i) + H_r(n) + b_n·p_r(i),
#
#     F_r(t) = Σ_{A=0..2} f_rA·P_{t+Am},   G_r(t) = Σ_{A=1..3} g_rA·P_{t+Am},
#     H_r(n) = h_r·P_{n+3m} + h'_r·P_n,    p_r a quadratic in i
#
# (coefficients in _tot_terms). Summed over n and i, the square splits into
#
# * F_r(t)² and G_r(t)², weighted by the number of pairs (n, i) that meet at t;
# * F_r(t) and G_r(t) times sums, over the m windows that reach t, of
#   H_r(n) + b_n·p_r(t - n): window sums of P_n, P_{n+3m}, b_n, n·b_n, n²·b_n;
# * the mirror terms F_r(n+i)·G_r(n-i): for fixed a = n + i they need the
#   sum of G_r(a - 2i) over an interval of i, a difference of running sums
#   taken separately over the even and the odd indices;
# * products of H_r(n) and b_n, pointwise in n.
#
# Each part costs O(length). Being products of values of P, the parts are far
# larger than z for smooth (red) noise, and a global P would lose every digit
# to cancellation. So they are formed locally: window starts go in blocks of
# B = _FAST_BLOCK·m, the B + 3m - 1 samples of a block lose their own
# least-squares line and mean (z ignores a line, so nothing changes) and P
# restarts at zero in every block. The parts are then bounded by powers of
# (B + 3m)/m times z, whatever the noise type: measured against the definition
# in extended precision, the worst case (random-run phase) is about 1e-13
# relative. Work and memory are O(N) per τ.

#: Window starts per block of the fast path, in units of m: more amortises the
#: 3m samples every block shares with the next, fewer keeps P smaller.
_FAST_BLOCK = 3

#: Smallest factor for the fast path; at m = 1 the direct kernel is faster.
FAST_MIN_M = 2

#: Values per temporary array in the fast path (blocks are batched up to it;
#: 512 KiB keeps the working set of one batch in cache).
_FAST_ELEMENTS = 1 << 16

_THIRD_DIFF = (-1, 3, -3, 1)


def _power_sums(m: int) -> list[int]:
    """``Σ_{i<m} i^k`` for k = 0 … 4, exactly."""
    top = m - 1
    s1 = top * m // 2
    s2 = top * m * (2 * top + 1) // 6
    s4 = top * m * (2 * top + 1) * (3 * top * top + 3 * top - 1) // 30
    return [m, s1, s2, s1 * s1, s4]


def _tot_terms(m: int) -> dict[str, np.ndarray]:
    """Coefficients of F_r, G_r, H_r and p_r (see the comment above) for factor m.

    With ``E_τ`` the sum of the first τ points of the extension,
    ``m·z_j = Σ_q c_q·E_{(r+q)m+i}`` with ``c = (-1, 3, -3, 1)``, and ``E_τ``
    in the third ``⌊(r+q)/3⌋`` is ``κ·T + σ·S_{A·m ± i}``: ``T - S_{3m-τ}``
    (first), ``T + S_{τ-3m}`` (second), ``3T - S_{9m-τ}`` (third), where
    ``S_t = P_{n+t} - P_n - b·t(t-1)/2`` and ``T = S_{3m}``.
    """
    fwd = np.zeros((6, 3))  # f_rA, A = 0, 1, 2
    rev = np.zeros((6, 3))  # g_rA, A = 1, 2, 3
    h = np.zeros((6, 2))  # coefficients of P_{n+3m} and P_n
    twice_p = [[0, 0, 0] for _ in range(6)]  # 2·p_r(i) = q0 + q1·i + q2·i², integers
    for r in range(6):
        for q, c in enumerate(_THIRD_DIFF):
            step = r + q  # E at step·m + i, in the third ⌊step/3⌋
            if step <= 2:
                kappa, sigma, a, d = 1, -1, 3 - step, -1
            elif step <= 5:
                kappa, sigma, a, d = 1, 1, step - 3, 1
            else:
                kappa, sigma, a, d = 3, -1, 9 - step, -1
            h[r, 0] += c * kappa
            h[r, 1] -= c * (kappa + sigma)
            if d == 1:
                fwd[r, a] += c * sigma
            else:
                rev[r, a - 1] += c * sigma
            # b·[-κ·f(3m) - σ·f(Am + d·i)] with 2·f(t) = t(t-1)
            am = a * m
            twice_p[r][0] -= c * (kappa * 3 * m * (3 * m - 1) + sigma * am * (am - 1))
            twice_p[r][1] -= c * sigma * d * (2 * am - 1)
            twice_p[r][2] -= c * sigma
    # Σ_i p_r(i) and Σ_i p_r(i)² from power sums, in integers (no length-m arrays).
    ps = _power_sums(m)
    p_sum = np.array([(q0 * ps[0] + q1 * ps[1] + q2 * ps[2]) / 2 for q0, q1, q2 in twice_p])
    p_sq = np.array([(q0 * q0 * ps[0] + 2 * q0 * q1 * ps[1] + (q1 * q1 + 2 * q0 * q2) * ps[2]
                      + 2 * q1 * q2 * ps[3] + q2 * q2 * ps[4]) / 4 for q0, q1, q2 in twice_p])
    p = np.array(twice_p, dtype=float) / 2.0
    k = m - 1.0
    # G_r(n - i) is stored at s = n - i + m - 1, where i = m - 1 - (s - n).
    p_rev = np.stack((p[:, 0] + p[:, 1] * k + p[:, 2] * k * k, -p[:, 1] - 2.0 * p[:, 2] * k, p[:, 2]), axis=1)
    def gram(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # Σ_r a_r ⊗ b_r (no BLAS)
        return np.einsum("ri,rj->ij", a, b)

    return {
        "ff": gram(fwd, fwd), "gg": gram(rev, rev), "fg": gram(fwd, rev),
        "fm": gram(fwd, np.hstack((h, p))), "gm": gram(rev, np.hstack((h, p_rev))),
        "h": h, "p_sum": p_sum, "p_sq": p_sq,
    }


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    """Σ a·b over two equally shaped 2-D arrays, in the calling thread (see sumsq)."""
    return float(np.einsum("ij,ij->", a, b))


def _window_totals(v: np.ndarray, m: int, width: int) -> np.ndarray:
    """``out[:, t] = Σ v[:, n]`` over ``max(0, t-m+1) ≤ n ≤ min(t, nb-1)``, t < width.

    ``nb = v.shape[1]``: the sum over the windows n whose m points i = t - n
    include t.
    """
    c = np.cumsum(v, axis=1)
    out = np.empty((v.shape[0], width))
    nb = v.shape[1]
    out[:, :nb] = c
    out[:, nb:] = c[:, -1:]
    out[:, m:] -= c[:, : width - m]
    return out


def _mirror_sums(g: np.ndarray, m: int, nb: int) -> np.ndarray:
    """``out[:, a] = Σ_i g[:, a + m - 1 - 2i]`` over ``max(0, a-nb+1) ≤ i ≤ min(m-1, a)``."""
    rows, width = g.shape
    d = np.zeros((rows, width + 2))  # d[:, s+2]: sum of g at s, s-2, s-4, …
    np.cumsum(g[:, 0::2], axis=1, out=d[:, 2::2])
    np.cumsum(g[:, 1::2], axis=1, out=d[:, 3::2])
    out = np.empty((rows, width))
    out[:, :nb] = d[:, m + 1 : m + 1 + nb]
    out[:, nb:] = d[:, nb + m - 1 : nb : -1]
    out[:, : m - 1] -= d[:, m - 1 : 0 : -1]
    out[:, m - 1 :] -= d[:, :nb]
    return out


def _running_sums(rows: np.ndarray) -> np.ndarray:
    """``P`` of every row after removing the row's least-squares line and mean.

    ``P[:, t]`` is the sum of the first t detrended samples (``P[:, 0] = 0``),
    so each row's P starts and ends at zero.
    """
    pref = np.empty((rows.shape[0], rows.shape[1] + 1))
    pref[:, 0] = 0.0
    d = pref[:, 1:]
    np.subtract(rows, rows[:, :1], out=d)
    length = d.shape[1]
    k = np.arange(length, dtype=float)
    centred = k - (length - 1) / 2.0
    norm = length * (length * length - 1.0) / 12.0  # Σ centred²
    # A steep line goes first, through d_0 = 0 and with its slope rounded to
    # 24 bits: the products with k are exact and, while the line dominates, so
    # are the differences (Sterbenz), so the samples keep the digits of what
    # remains. A second pass removes the small rest of the line.
    slope = (np.einsum("ij,j->i", d, centred) / norm).astype(np.float32).astype(float)
    d -= slope[:, None] * k
    d -= np.einsum("ij,j->i", d, centred)[:, None] / norm * centred
    d -= d.mean(axis=1, keepdims=True)
    np.cumsum(d, axis=1, out=d)
    return pref


def _block_sums(rows: np.ndarray, m: int, nb: int, terms: dict[str, np.ndarray]) -> float:
    """``Σ_n Σ_j (m·z_j(n))²`` over the first ``nb`` windows of every row.

    Each row holds the ``nb + 3m - 1`` consecutive samples those windows use.
    """
    pref = _running_sums(rows)
    width = nb + m - 1  # t = n + i, and s = n - i + m - 1
    h1 = 3 * m // 2
    h2 = 3 * m - h1
    p0 = pref[:, :nb]
    p3 = pref[:, 3 * m : 3 * m + nb]
    slope = ((p3 - pref[:, h2 : h2 + nb]) - (pref[:, h1 : h1 + nb] - p0)) / (h1 * h2)
    xs = [pref[:, a * m : a * m + width] for a in range(3)]  # P_{t+Am}, A = 0, 1, 2
    ys = [pref[:, a * m + 1 : a * m + 1 + width] for a in range(3)]  # P_{s-m+1+Am}, A = 1, 2, 3
    seqs = xs + ys
    cross = np.vstack((terms["fm"], terms["gm"]))  # rows: the six sequences
    t = np.arange(width, dtype=float)
    n = np.arange(nb, dtype=float)
    total = 0.0

    def add_moment(k: int, moment: np.ndarray) -> float:
        return sum(2.0 * cross[i, k] * _dot(seq, moment) for i, seq in enumerate(seqs))

    # Window sums of P_{n+3m}, P_n and of b_n·(t-n)^k, k = 0, 1, 2, one at a time.
    total += add_moment(0, _window_totals(p3, m, width))
    total += add_moment(1, _window_totals(p0, m, width))
    s0 = _window_totals(slope, m, width)
    total += add_moment(2, s0)
    first = _window_totals(slope * n, m, width)
    np.subtract(t * s0, first, out=first)  # Σ b_n·(t-n)
    total += add_moment(3, first)
    second = _window_totals(slope * (n * n), m, width)
    # Σ b_n·(t-n)² = t²·Σb - 2t·Σ n·b + Σ n²·b
    second += t * (2.0 * first - t * s0)
    total += add_moment(4, second)
    del s0, first, second
    weight = np.minimum(t, nb - 1) - np.maximum(0.0, t - m + 1) + 1.0
    for group, gram in ((xs, terms["ff"]), (ys, terms["gg"])):
        for a in range(3):
            weighted = weight * group[a]
            total += gram[a, a] * _dot(group[a], weighted)
            for a2 in range(a + 1, 3):
                total += 2.0 * gram[a, a2] * _dot(group[a2], weighted)
    del weighted
    fg = terms["fg"]
    for a2 in range(3):
        mirror = _mirror_sums(ys[a2], m, nb)
        for a in range(3):
            total += 2.0 * fg[a, a2] * _dot(xs[a], mirror)
    h3, h0 = terms["h"][:, 0], terms["h"][:, 1]
    pp, pq, qq = _dot(p3, p3), _dot(p3, p0), _dot(p0, p0)
    bb, pb, qb = _dot(slope, slope), _dot(p3, slope), _dot(p0, slope)
    per_stretch = (m * (h3 * h3 * pp + 2.0 * h3 * h0 * pq + h0 * h0 * qq) + terms["p_sq"] * bb
                   + 2.0 * terms["p_sum"] * (h3 * pb + h0 * qb))
    return total + float(per_stretch.sum())


def tot_sums_fast(u: np.ndarray, m: int, block: Optional[int] = None) -> tuple[float, int]:
    """Same result as :func:`tot_sums` in O(len(u)) time and memory (see above)."""
    m = int(m)
    windows = u.size - 3 * m + 1
    nb = max(1, min(_FAST_BLOCK * m, windows))
    terms = _tot_terms(m)
    full = windows // nb
    seg_len = nb + 3 * m - 1
    total = 0.0
    if full:
        starts = sliding_window_view(u, seg_len)[: full * nb : nb]
        rows = max(1, (block or _FAST_ELEMENTS) // seg_len)
        for first in range(0, full, rows):
            total += _block_sums(starts[first : first + rows], m, nb, terms)
    rest = windows - full * nb
    if rest:
        total += _block_sums(u[None, full * nb :], m, rest, terms)
    return total / m**2, windows


def tot_total(u: np.ndarray, m: int) -> tuple[float, int]:
    """``Σ_n Σ_j z_j(n)²`` and the window count, by the faster kernel for this m."""
    if m < FAST_MIN_M:
        return tot_sums(u, m)
    return tot_sums_fast(u, m)
