"""Total family: TOTDEV, MTOTDEV, TTOTDEV and HTOTDEV.

The total variances extend the data beyond both ends by reflection before
differencing, so long averaging times use every sample and get more degrees of
freedom than the plain estimators at the same τ.

* TOTVAR reflects the whole phase record once; O(N) per τ.
* MTOT, TTOT and HTOT detrend and reflect every 3m-point subsequence
  separately. The direct kernel (:func:`_tot_sums`) costs O(N·m) per τ:
  inside each subsequence the m-averages of the 9m-point extension come from
  one running sum of the 3m detrended points. Subsequences are processed in
  blocks whose size keeps every temporary array near :data:`_BLOCK_ELEMENTS`
  values, so the peak memory is O(N) + O(block·m), never O(N·m). It serves
  m = 1; every larger factor goes to :func:`_tot_sums_fast`, which expands
  the sum of squares into running sums and costs O(N) time and memory per τ.

Each estimator ignores a linear phase trend (TOTVAR extends a line as a line,
MTOT removes a slope from every subsequence, HTOT removes a linear frequency
drift, which contains a frequency offset), so the driver may remove the mean
frequency first to protect precision. The plain definitions written with
explicit loops are in ``tests/test_total.py``, which holds these fast paths to
them.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal, Optional

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..core.driver import Statistic
from ..core.taus import STOP_RATIOS
from .engine import finish, run
from ..core.numeric import sumsq
from ..uncertainty.attach import CiMethod, check_options
from ..uncertainty.confidence import ONE_SIGMA
from ..core.validate import DataType
from .allan import _doc
from ..errors import ParameterError
from .hadamard import _ohvar_kernel
from ..core.result import StabilityResult

__all__ = ["totdev", "mtotdev", "ttotdev", "htotdev"]

BiasMode = Literal["none", "auto", "published", "estimator"]
_BIAS_MODES = ("none", "auto", "published", "estimator")

#: Values per temporary array when the 3m-point subsequences are processed in
#: blocks (2**17 float64 = 1 MiB; three such arrays are live at a time).
_BLOCK_ELEMENTS = 1 << 17

_DOC_BIAS = """    bias : {"none", "auto", "published", "estimator"}
        ``"none"`` returns the raw estimator. ``"published"`` divides the
        variance by the bias factors of SP1065/Stable32, ``"estimator"`` by
        factors measured by Monte-Carlo for this very estimator (see Notes).
        The factor is that of ``alpha`` when given, else of the noise type
        identified at each τ. ``"auto"`` is ``"published"`` at the identified
        noise type, as Stable32 1.53 does. ``bias`` and ``bias_factor`` of the
        result say what was applied.

"""

_MTOT_BIAS_NOTE = """    alpha 2, 1, 0, −1, −2; ``"published"`` uses the SP1065/Stable32 factors
    0.94, 0.83, 0.73, 0.70, 0.69, ``"estimator"`` the Monte-Carlo factors of
    this estimator 0.995, 0.85, 0.77, 0.72, 0.68 (numerics.md §3, §8.1). The
    SP1065 tables are raw/0.73 (white FM); Stable32 1.53 all-τ runs divide by
    the factor of the alpha identified at each τ, v1.60 octave and decade
    runs print the raw value."""


def _doc_total(func):
    """Shared parameter docs of :mod:`sigmatau.allan` plus ``bias`` and ``alpha``."""
    func = _doc(func)
    doc = func.__doc__.replace("\n\n    Returns\n", "\n" + _DOC_BIAS + "    Returns\n", 1)
    func.__doc__ = doc.replace("    {mtot_bias}\n", _MTOT_BIAS_NOTE + "\n")
    return func


# --- kernels: (phase x, factors, τ0) -> (variance, number of terms) ---------------


def _totvar_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    n_pts = x.size
    # Doubly reflected phase x*_{-j} = 2x_0 - x_j, x*_{N-1+j} = 2x_{N-1} - x_{N-1-j},
    # j = 1 … N-2; x*_i sits at index i + N - 2 of ``ext``.
    inner = x[n_pts - 2 : 0 : -1]
    ext = np.concatenate((2.0 * x[0] - inner, x, 2.0 * x[-1] - inner))
    c = n_pts - 2
    var = np.empty(ms.size)
    for i, m in enumerate(ms):
        d2 = ext[c + 1 - m : c + n_pts - 1 - m] - 2.0 * ext[c + 1 : c + n_pts - 1] + ext[c + 1 + m : c + n_pts - 1 + m]
        var[i] = sumsq(d2) / (2.0 * (m * tau0) ** 2 * d2.size)
    return var, np.full(ms.size, n_pts - 2, dtype=np.int64)


def _tot_sums(u: np.ndarray, m: int, block: Optional[int] = None) -> tuple[float, int]:
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
    rows = max(1, min(windows, (block or _BLOCK_ELEMENTS) // (length + 1)))
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
# _tot_sums) S_t = P_{n+t} - P_n - b_n·t(t-1)/2, and the running sum of the
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
_FAST_MIN_M = 2

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


def _tot_sums_fast(u: np.ndarray, m: int, block: Optional[int] = None) -> tuple[float, int]:
    """Same result as :func:`_tot_sums` in O(len(u)) time and memory (see above)."""
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


def _tot_total(u: np.ndarray, m: int) -> tuple[float, int]:
    """``Σ_n Σ_j z_j(n)²`` and the window count, by the faster kernel for this m."""
    if m < _FAST_MIN_M:
        return _tot_sums(u, m)
    return _tot_sums_fast(u, m)


def _mtot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        total, windows = _tot_total(x, int(m))
        var[i] = total / (6.0 * m * 2.0 * (m * tau0) ** 2 * windows)
        n[i] = windows
    return var, n


def _ttot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var, n = _mtot_kernel(x, ms, tau0)
    return var * (ms * tau0) ** 2 / 3.0, n


def _htot_formula_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    """HTOT by its defining construction at every factor, m = 1 included."""
    y = np.diff(x) / tau0
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        total, windows = _tot_total(y, int(m))
        var[i] = total / (6.0 * m * 6.0 * windows)
        n[i] = windows
    return var, n


def _htot_kernel(x: np.ndarray, ms: np.ndarray, tau0: float) -> tuple[np.ndarray, np.ndarray]:
    var = np.empty(ms.size)
    n = np.empty(ms.size, dtype=np.int64)
    one = ms == 1  # Stable32 and the SP1065 tables report OHVAR at m = 1
    var[one], n[one] = _ohvar_kernel(x, ms[one], tau0)
    var[~one], n[~one] = _htot_formula_kernel(x, ms[~one], tau0)
    return var, n


TOTVAR = Statistic("totdev", _totvar_kernel, max_m=lambda n: n - 1, stop_ratio=STOP_RATIOS["totdev"], min_points=3)
MTOT = Statistic("mtotdev", _mtot_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["mtotdev"], min_points=3)
TTOT = Statistic("ttotdev", _ttot_kernel, max_m=lambda n: n // 3, stop_ratio=STOP_RATIOS["ttotdev"], min_points=3)
HTOT = Statistic("htotdev", _htot_kernel, max_m=lambda n: (n - 1) // 3, stop_ratio=STOP_RATIOS["htotdev"], min_points=4)


# --- bias corrections ------------------------------------------------------------

# Divisors of the raw variance, by noise exponent alpha (numerics.md §3, §8.1).
_MTOT_PUBLISHED = {2: 0.94, 1: 0.83, 0: 0.73, -1: 0.70, -2: 0.69}
_MTOT_ESTIMATOR = {2: 0.995, 1: 0.85, 0: 0.77, -1: 0.72, -2: 0.68}
_HTOT_PUBLISHED = {0: 1 - 0.005, -1: 1 - 0.149, -2: 1 - 0.229, -3: 1 - 0.283, -4: 1 - 0.321}
_HTOT_ESTIMATOR = {0: 0.994, -1: 0.850, -2: 0.771, -3: 0.717, -4: 0.679}
# TOTVAR: E[TOTVAR]/AVAR = 1 - a·τ/T (Howe); no Monte-Carlo revision.
_TOTVAR_A = {0: 0.0, -1: 1.0 / (3.0 * math.log(2.0)), -2: 0.750}

_FACTORS = {
    "mtotdev": {"published": _MTOT_PUBLISHED, "estimator": _MTOT_ESTIMATOR},
    "ttotdev": {"published": _MTOT_PUBLISHED, "estimator": _MTOT_ESTIMATOR},
    "htotdev": {"published": _HTOT_PUBLISHED, "estimator": _HTOT_ESTIMATOR},
    "totdev": {"published": _TOTVAR_A, "estimator": _TOTVAR_A},
}


def _table_name(bias: str) -> str:
    return "published" if bias == "auto" else bias


def _check_bias(name: str, bias: object, alpha: Optional[int]) -> None:
    """Validate ``bias`` (and a forced ``alpha`` against its table) before computing."""
    if bias not in _BIAS_MODES:
        raise ParameterError(f"bias={bias!r} must be one of {_BIAS_MODES}")
    if bias == "none" or alpha is None:
        return
    table = _FACTORS[name][_table_name(str(bias))]
    if alpha not in table:
        allowed = ", ".join(str(a) for a in sorted(table, reverse=True))
        raise ParameterError(f"{name}: no {_table_name(str(bias))} bias factor for alpha={alpha}; allowed: {allowed}")


def _apply_bias(res: StabilityResult, bias: str, forced: Optional[int]) -> StabilityResult:
    """Divide the variance by the bias factor of each row's noise type (``res.alpha``)."""
    if bias == "none":
        return res
    name = _table_name(bias)
    table = _FACTORS[res.statistic][name]
    alphas = res.alpha if res.alpha is not None else np.full(res.m.size, np.nan)
    coef = np.array([table.get(int(a), np.nan) if np.isfinite(a) else np.nan for a in alphas])
    missing = ~np.isfinite(coef)
    if res.statistic == "totdev":
        record = (res.n_points - 1) / res.rate
        factor = 1.0 - np.where(missing, 0.0, coef) * res.taus / record
    else:
        factor = np.where(missing, 1.0, coef)
        if res.statistic == "htotdev":
            factor[res.m == 1] = 1.0  # the OHVAR value is unbiased
    var = res.var / factor
    scaled = {}
    # A fixed divisor scales a χ² interval exactly as it scales the estimate.
    for field in ("ci_low", "ci_high"):
        if getattr(res, field) is not None:
            scaled[field] = getattr(res, field) / np.sqrt(factor)
    desc = f"{name} alpha={forced}" if forced is not None else f"{name} at the alpha identified per tau"
    if missing.any():
        desc += f" (uncorrected at {int(missing.sum())} tau whose alpha has no factor)"
    return replace(res, var=var, dev=np.sqrt(var), bias=desc, bias_factor=factor, **scaled)


def _run_total(
    stat: Statistic, data: object, rate: object, data_type: object, taus: object, m: object,
    points_per_decade: int, bias: object, alpha: object, confidence: object, ci: object,
) -> StabilityResult:
    alpha_i, _, _ = check_options(alpha, confidence, ci)
    _check_bias(stat.name, bias, alpha_i)
    res = run(stat, data, rate=rate, data_type=data_type, taus=taus, m=m,
              points_per_decade=points_per_decade, raw=True)
    # A bias correction needs each row's noise type even when no interval is wanted.
    need_alpha = bias != "none"
    res = finish(res, data, res.data_type, alpha=alpha_i, confidence=confidence,
                 ci="chi2" if (ci is None and need_alpha) else ci)
    res = _apply_bias(res, str(bias), alpha_i)
    if ci is None and need_alpha:
        res = replace(res, edf=None, ci_low=None, ci_high=None, confidence=None, ci_reason=None)
    return res


# --- public functions ------------------------------------------------------------


@_doc_total
def totdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Total deviation (TOTVAR), from the doubly reflected phase record.

    {common}
    Notes
    -----
    The N phase points are extended at both ends by odd reflection,
    ``x*_{-j} = 2x_0 - x_j`` and ``x*_{N-1+j} = 2x_{N-1} - x_{N-1-j}`` for
    j = 1 … N-2, and

    .. math:: \\mathrm{Tot}\\,σ_y^2(τ) = \\frac{1}{2τ^2(N-2)} \\sum_{i=1}^{N-2}
              (x^*_{i-m} - 2x^*_i + x^*_{i+m})^2 ,

    always ``n = N - 2`` terms, O(N) per τ. The reflection reaches indices
    ``-(N-2) … 2N-3``, so ``m ≤ N - 1``; keyword grids stop at ``m ≤ N/2``
    (Stable32), the range where the bias model holds. For frequency data the
    reflection is a half-sample mirror of the frequency samples at both ends.

    Bias: ``E[TOTVAR]/AVAR = 1 - a·τ/T`` with ``T = (N-1)τ0``, ``a = 0``
    (alpha 0), ``1/(3 ln 2)`` (alpha −1), ``0.750`` (alpha −2); the same
    factors serve both ``"published"`` and ``"estimator"``. ``bias_factor``
    holds ``1 - a·τ/T`` per τ. Stable32 applies this correction with the
    alpha its noise identification finds at each τ.

    Frequency data are differenced directly (no integration to phase), which
    keeps every digit. A program that integrates normalised frequency f/f0 ≈ 1
    to phase in float64 (Stable32 on such a file) adds that phase's rounding,
    about 1e-12 s a point after 2·10^4 points, as white phase noise: on the
    OCXO reference record its TOTDEV is 4.9e-4, 4.4e-4, 3.8e-4 too large at
    m = 1, 2, 4 (up to 1.6e-3 further on; OADEV/OHDEV up to 1.8e-3), while its
    run on y = f/f0 − 1 agrees with this function to 1e-4.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.11; D. A. Howe, "The total deviation
    approach to long-term characterization of frequency stability", IEEE TUFFC
    47(5), 2000; numerics.md §1.8, §3.

    Examples
    --------
    >>> from sigmatau.total import totdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in totdev(y, m=[1, 2]).dev]
    [91.22945, 93.90379]
    """
    return _run_total(TOTVAR, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def mtotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Modified total deviation (MTOT).

    {common}
    Notes
    -----
    For each of the ``N - 3m + 1`` subsequences ``s_k = x_{n+k}`` (k < 3m) the
    half-average slope ``b = [mean(s_{h2…3m-1}) - mean(s_{0…h1-1})]/h2``,
    ``h1 = ⌊3m/2⌋``, ``h2 = ⌈3m/2⌉``, is removed (``s'_k = s_k - b·k``); the
    9m-point extension ``e = [rev s', s', rev s']`` gives m-averages ``a_j`` and
    ``z_j(n) = a_j - 2a_{j+m} + a_{j+2m}``, j = 0 … 6m-1, and

    .. math:: \\mathrm{Mod\\,Tot}\\,σ_y^2(τ) = \\frac{1}{2τ^2(N-3m+1)}
              \\sum_{n=0}^{N-3m} \\frac{1}{6m} \\sum_{j=0}^{6m-1} z_j(n)^2 .

    ``n = N - 3m + 1``; ``m ≤ ⌊N/3⌋``, and keyword grids stop at ``N/3``
    (Stable32). The slope convention reproduces Stable32 at odd and even m.
    Cost O(N) per τ: the sum of squares is expanded into running sums of
    the data, formed block by block (see :mod:`sigmatau.total`).

    Bias: ``bias_factor = B(alpha)``, corrected variance = raw/B, for
    {mtot_bias}

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.12; D. A. Howe & F. Vernotte,
    "Generalization of the total variance approach to the modified Allan
    variance", 31st PTTI (1999); numerics.md §1.9, §3.

    Examples
    --------
    >>> from sigmatau.total import mtotdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in mtotdev(y, m=[1, 2]).dev]
    [64.50896, 64.79436]
    >>> [round(float(d), 4) for d in mtotdev(y, m=[1, 2], bias="published", alpha=0).dev]
    [75.502, 75.8361]
    """
    return _run_total(MTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def ttotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Time total deviation (TTOT = τ²/3 · MTOT), in the unit of the phase data.

    {common}
    Notes
    -----
    .. math:: σ_{x,\\mathrm{tot}}^2(τ) = \\frac{τ^2}{3}\\,\\mathrm{Mod\\,Tot}\\,σ_y^2(τ)

    with MTOT as in :func:`mtotdev` (same ``n`` and range). SP1065 is reported
    to print τ³ in this equation; τ² reproduces its tables.

    Bias: the MTOT factors, for
    {mtot_bias}

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.13; numerics.md §1.10, §3.

    Examples
    --------
    >>> from sigmatau.total import ttotdev
    >>> y = [892, 809, 823, 798, 671, 644, 883, 903, 677]
    >>> [round(float(d), 5) for d in ttotdev(y, m=[1, 2]).dev]
    [37.24427, 74.81809]
    """
    return _run_total(TTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)


@_doc_total
def htotdev(
    data, *, rate: float = 1.0, data_type: DataType = "freq", taus="octave", m=None,
    points_per_decade: int = 10, bias: BiasMode = "none", alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA, ci: Optional[CiMethod] = "chi2",
) -> StabilityResult:
    """Hadamard total deviation (HTOT).

    {common}
    Notes
    -----
    The MTOT construction applied to the M = N - 1 frequency samples: each
    3m-point subsequence of ``y`` loses its half-average slope (a linear
    frequency drift), is extended to 9m points by uninverted reflection, and
    the second differences ``z_j`` of its m-averages give

    .. math:: \\mathrm{Tot}\\,H σ_y^2(τ) = \\frac{1}{6(M-3m+1)}
              \\sum_{n=0}^{M-3m} \\frac{1}{6m} \\sum_{j=0}^{6m-1} z_j(n)^2 ,

    ``n = M - 3m + 1``, ``m ≤ ⌊M/3⌋``, keyword grids stop at ``N/3``; O(N)
    per τ, as for :func:`mtotdev`.

    **At m = 1 the overlapped Hadamard variance OHVAR(τ0) is reported**
    (``n = N - 3``), as Stable32 and the SP1065 tables do: the 3-point
    subsequence leaves the construction almost no freedom (for the NBS set
    it gives 0.208 against OHDEV 0.294).

    Bias: ``E[HTOT]/HVAR = 1 + a`` for alpha 0, −1, −2, −3, −4;
    ``"published"`` uses a = −0.005, −0.149, −0.229, −0.283, −0.321 (Howe
    et al. 2000; SP1065 tables are raw/0.995 for white FM), ``"estimator"``
    the Monte-Carlo factors 0.994, 0.850, 0.771, 0.717, 0.679. The OHVAR
    value at m = 1 gets factor 1.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2.14; D. A. Howe, R. L. Beard,
    C. A. Greenhall, W. J. Riley, "A total estimator of the Hadamard function
    used for GPS operations", 32nd PTTI (2000); numerics.md §1.11, §3, §8.7.

    Examples
    --------
    >>> from sigmatau.total import htotdev
    >>> from sigmatau.datasets import nbs1000
    >>> r = htotdev(nbs1000(), m=[1, 10, 100], bias="published", alpha=0)
    >>> [f"{d:.5e}" for d in r.dev]
    ['2.94388e-01', '9.61479e-02', '3.05810e-02']
    """
    return _run_total(HTOT, data, rate, data_type, taus, m, points_per_decade, bias, alpha, confidence, ci)
