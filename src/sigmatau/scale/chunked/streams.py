"""Streamed sums and the derived series the kernels read, chunk by chunk.

numpy's pairwise summation reproduced piecewise (:func:`_pairwise_sum`), the
series derived from a record as the in-memory path derives them (mean removed,
line removed — through the first and last present points when samples are
missing —, integrated, differenced, one gap-free run), the runs of present
samples (:func:`_present_runs`), and the exact running sums, window sums,
block sums and strided reads that the kernels (:mod:`.kernels`) are built from.
See the package docstring (:mod:`sigmatau.scale.chunked`) for how and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Iterator, Optional, Protocol, Sequence

import numpy as np

from ...core.driver import Statistic
from ...core.result import StabilityResult


class _Series(Protocol):
    """What the streamed sums, kernels and noise identification use of a
    :class:`~sigmatau.scale.chunked.sources.ChunkedSeries` (typed by this protocol because
    that module sits above this one: it imports these steps)."""

    n: int
    chunk_size: int
    name: str

    def read(self, start: int, stop: int) -> np.ndarray: ...

    def read_strided(self, start: int, stop: int, step: int) -> np.ndarray: ...

    def __sigmatau_statistic__(self, stat: Statistic, **options: object) -> StabilityResult: ...


@dataclass(frozen=True)
class _Gaps:
    """What the validating pass learns of the missing samples (NaN) of a record."""

    #: Missing (NaN) samples.
    missing: int
    #: Index of the first and of the last present sample.
    first: int
    last: int


# ---------------------------------------------------------------------- pairwise sums


def _pairwise_sum(read: Callable[[int, int], np.ndarray], start: int, n: int, leaf: int,
                  visit: Optional[Callable[[int, np.ndarray], None]] = None) -> float:
    """``Σ`` of ``n`` values from ``start`` in numpy's pairwise order (bit-identical to ``np.sum``).

    numpy halves a contiguous reduction down to blocks of 128 with the split
    rounded to a multiple of 8; the same split applied until a piece fits in
    ``leaf`` and ``np.add.reduce`` on the piece give the same rounding.
    """
    if n <= leaf:
        v = read(start, start + n)
        if visit is not None:
            visit(start, v)
        return float(np.add.reduce(v))
    half = n // 2
    half -= half % 8
    return _pairwise_sum(read, start, half, leaf, visit) + _pairwise_sum(read, start + half, n - half, leaf, visit)


# ------------------------------------------------------------------- derived series
#
# Each reader maps an index range of a derived series (mean removed, line
# removed, integrated, differenced) to values computed exactly as the
# in-memory path computes them element by element.


class _Raw:
    def __init__(self, src: _Series) -> None:
        self.src, self.n = src, src.n

    def read(self, a: int, b: int) -> np.ndarray:
        return self.src.read(a, b)

    def take(self, start: int, step: int, count: int) -> np.ndarray:
        return self.src.read_strided(start, start + (count - 1) * step + 1, step)


class _Centred(_Raw):
    """``y - mean(y)``."""

    def __init__(self, src: _Series, mean: np.float64) -> None:
        super().__init__(src)
        self.mean = mean

    def read(self, a: int, b: int) -> np.ndarray:
        return self.src.read(a, b) - self.mean


class _Detrended(_Raw):
    """``(x - x_0) - linspace(0, x_{N-1} - x_0, N)``, as ``remove_linear_phase``."""

    def __init__(self, src: _Series) -> None:
        super().__init__(src)
        self.x0 = src.read(0, 1)[0]
        self.delta = src.read(self.n - 1, self.n)[0] - self.x0
        self.div = self.n - 1
        self.step = self.delta / self.div

    def _ramp(self, idx: np.ndarray) -> np.ndarray:
        r = idx.astype(np.float64)
        if self.step == 0:  # numpy's branch for a zero or subnormal step
            r /= self.div
            r *= self.delta
        else:
            r *= self.step
        r[idx == self.n - 1] = self.delta
        return r

    def read(self, a: int, b: int) -> np.ndarray:
        return (self.src.read(a, b) - self.x0) - self._ramp(np.arange(a, b))

    def take(self, start: int, step: int, count: int) -> np.ndarray:
        x = self.src.read_strided(start, start + (count - 1) * step + 1, step)
        return (x - self.x0) - self._ramp(start + step * np.arange(count))


class _GapDetrended(_Raw):
    """Phase with gaps minus the line through its first and last present points, as
    :func:`sigmatau.core.gaps.detrended_phase`: ``(x - x_i0) - slope·(i - i0)``, NaN kept.

    ``first`` and ``last`` are the indices of those points (found by the validating pass).
    """

    def __init__(self, src: _Series, first: int, last: int) -> None:
        super().__init__(src)
        self.i0 = first
        self.x0 = src.read(first, first + 1)[0]
        # One point present: no line, only the offset goes (as detrended_phase).
        self.slope = (src.read(last, last + 1)[0] - self.x0) / (last - first) if last > first else None

    def _line(self, idx: np.ndarray) -> np.ndarray:
        return self.slope * (idx.astype(np.float64) - self.i0)

    def read(self, a: int, b: int) -> np.ndarray:
        x = self.src.read(a, b) - self.x0
        return x if self.slope is None else x - self._line(np.arange(a, b))

    def take(self, start: int, step: int, count: int) -> np.ndarray:
        x = self.src.read_strided(start, start + (count - 1) * step + 1, step) - self.x0
        return x if self.slope is None else x - self._line(start + step * np.arange(count))


class _Slice:
    """Samples ``a … b-1`` of a series, indexed from 0 (one gap-free run)."""

    def __init__(self, src: _Series, a: int, b: int) -> None:
        self.src, self.a, self.n = src, a, b - a

    def read(self, a: int, b: int) -> np.ndarray:
        return self.src.read(self.a + a, self.a + b)


def _present_runs(src: _Series, L: int) -> Iterator[tuple[int, int]]:
    """``(start, stop)`` of each run of present (non-NaN) samples, in order, read in chunks of L."""
    open_at: Optional[int] = None
    for a in range(0, src.n, L):
        present = ~np.isnan(src.read(a, min(a + L, src.n)))
        edges = np.diff(present.astype(np.int8), prepend=np.int8(open_at is not None))
        starts = (a + np.flatnonzero(edges == 1)).tolist()
        stops = (a + np.flatnonzero(edges == -1)).tolist()
        if open_at is not None:
            starts.insert(0, open_at)
        open_at = starts.pop() if len(starts) > len(stops) else None
        yield from zip(starts, stops)
    if open_at is not None:
        yield open_at, src.n


class _Integrated:
    """Phase of centred frequency samples: ``x_0 = 0``, ``x_k = τ0·Σ_{i<k} y_i`` (sequential sum).

    The running sum is stored every ``L`` samples, so any range is
    recomputed from the checkpoint before it, bit-identical to ``np.cumsum``.
    """

    def __init__(self, freq: _Centred, tau0: float, leaf: int) -> None:
        self.freq, self.tau0, self.leaf = freq, tau0, leaf
        self.n = freq.n + 1
        marks = [0.0]
        for a in range(0, freq.n, leaf):
            buf = np.empty(min(leaf, freq.n - a) + 1)
            buf[0] = marks[-1]
            buf[1:] = freq.read(a, a + buf.size - 1)
            marks.append(float(np.add.accumulate(buf)[-1]))
        self.marks = marks

    def read(self, a: int, b: int) -> np.ndarray:
        q = a // self.leaf
        base = q * self.leaf
        buf = np.empty(b - base)
        buf[0] = self.marks[q]
        buf[1:] = self.freq.read(base, b - 1)
        np.add.accumulate(buf, out=buf)
        out = buf[a - base :] * self.tau0
        if a == 0:
            out[0] = 0.0
        return out


class _Diff:
    """First differences ``r_{i+1} - r_i`` (frequency of phase data, up to τ0)."""

    def __init__(self, base: object) -> None:
        self.base = base
        self.n = base.n - 1  # type: ignore[attr-defined]

    def read(self, a: int, b: int) -> np.ndarray:
        return np.diff(self.base.read(a, b + 1))  # type: ignore[attr-defined]


# ------------------------------------------------------------------ numeric helpers


class _SumSq:
    """Σ v² over blocks: einsum inside a block, exact (fsum) across blocks."""

    def __init__(self) -> None:
        self.parts: list[float] = []

    def add(self, v: np.ndarray) -> None:
        self.parts.append(float(np.einsum("i,i->", v, v)))

    @property
    def total(self) -> float:
        return math.fsum(self.parts)


class _FiniteSumSq(_SumSq):
    """Σ t² over the finite terms t (NaN marks a term that reads a gap), and how many there are."""

    def __init__(self) -> None:
        super().__init__()
        self.n = 0

    def add(self, v: np.ndarray) -> None:
        ok = v[~np.isnan(v)]
        self.n += ok.size
        super().add(ok)


class _Prefix:
    """Running sum ``P_k = Σ_{i<k} w_i`` of a streamed series, kept as ``hi + lo``.

    Each block is summed by ``np.cumsum``; the rounding error of every
    addition is recovered exactly (Knuth's TwoSum) and summed alongside, so
    ``c_k + e_k`` represents P_k to about eps² of its size, however far the
    sum drifts (random-walk or drifting noise). Differences of such sums at two
    offsets are then window sums rounded about once (:func:`_window_diff`).
    """

    def __init__(self) -> None:
        self.hi = 0.0
        self.lo = 0.0

    def step(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(c, e)`` with ``c + e = P`` at the ``w.size`` positions of this block; advances past it."""
        size = w.size
        c = np.empty(size + 1)
        c[0] = self.hi
        c[1:] = w
        np.add.accumulate(c, out=c)
        before, after = c[:-1], c[1:]
        back = after - before
        e = np.empty(size + 1)
        e[0] = self.lo
        e[1:] = (before - (after - back)) + (w - back)
        np.add.accumulate(e, out=e)
        hi = c[size] + e[size]
        back = hi - c[size]
        self.lo = (c[size] - (hi - back)) + (e[size] - back)
        self.hi = hi
        return c[:size], e[:size]


def _window_diff(c1: np.ndarray, e1: np.ndarray, c0: np.ndarray, e0: np.ndarray) -> np.ndarray:
    """``(c1 + e1) - (c0 + e0)``: the hi difference is split exactly (TwoSum), then rounded once."""
    d = c1 - c0
    back = d - c1
    low = (c1 - (d - back)) + (-c0 - back)
    return d + (low + (e1 - e0))


def _read_padded(read: Callable[[int, int], np.ndarray], n: int, a: int, b: int) -> np.ndarray:
    """Values ``a … b-1``, zero past ``n`` (such values only ever reach a final, unused carry)."""
    if b <= n:
        return read(a, b)
    out = np.zeros(b - a)
    if a < n:
        out[: n - a] = read(a, n)
    return out


def _windows(read: Callable[[int, int], np.ndarray], n: int, start: int, offsets: Sequence[int],
             length: int) -> list[np.ndarray]:
    """``[values start+o … start+o+length-1 for o in offsets]``: one read when they overlap."""
    lo, hi = start + offsets[0], start + offsets[-1] + length
    if all(b - a <= length for a, b in zip(offsets, offsets[1:])):
        buf = _read_padded(read, n, lo, hi)
        return [buf[o - offsets[0] : o - offsets[0] + length] for o in offsets]
    return [_read_padded(read, n, start + o, start + o + length) for o in offsets]


def _blocks(count: int, size: int) -> Iterator[tuple[int, int]]:
    """``(start, size)`` of the consecutive blocks of at most ``size`` covering ``0 … count-1``."""
    for p in range(0, count, size):
        yield p, min(size, count - p)


VFun = Callable[[list[np.ndarray], int], np.ndarray]


def _window_sums(rd: object, m: int, start: int, count: int, L: int, vfun: VFun, span: int,
                 identity_at_1: bool = True) -> Iterator[np.ndarray]:
    """Blocks of ``s_j = Σ_{i<m} v_{j+i} = P_{j+m} - P_j``, j = start … start+count-1.

    ``v_i = vfun(W, 0)`` where ``W[k]`` holds the series from ``i + k·m`` (k ≤
    ``span``); ``vfun(W, 1)`` is then ``v_{i+m}``. P is carried by two
    :class:`_Prefix` chains, one ``m`` ahead of the other, so any m works with
    blocks of L.
    """
    read, n = rd.read, rd.n  # type: ignore[attr-defined]
    if m == 1 and identity_at_1:
        for p, l in _blocks(count, L):
            yield vfun(_windows(read, n, start + p, range(span + 1), l), 0)
        return
    ahead, behind = _Prefix(), _Prefix()
    offsets0 = [k * m for k in range(span + 1)]
    for p, l in _blocks(m, L):
        ahead.step(vfun(_windows(read, n, start + p, offsets0, l), 0))
    offsets = [k * m for k in range(span + 2)]
    for p, l in _blocks(count, L):
        w = _windows(read, n, start + p, offsets, l)
        c0, e0 = behind.step(vfun(w, 0))
        c1, e1 = ahead.step(vfun(w, 1))
        yield _window_diff(c1, e1, c0, e0)


def _block_sums(rd: object, m: int, count: int, L: int) -> Iterator[np.ndarray]:
    """Sums of the ``count`` non-overlapped blocks of m values from 0, in batches (numpy's order)."""
    read = rd.read  # type: ignore[attr-defined]
    if m <= L:
        per = max(1, L // m)
        for k0, k in _blocks(count, per):
            yield read(k0 * m, (k0 + k) * m).reshape(k, m).sum(axis=1)
        return
    batch = max(1, L // 8)
    for k0, k in _blocks(count, batch):
        yield np.array([_pairwise_sum(read, (k0 + i) * m, m, L) for i in range(k)])


def _block_means(rd: object, m: int, count: int, L: int) -> Iterator[np.ndarray]:
    """Means of the blocks, bit-identical to ``block_means`` (reshape and ``mean``)."""
    read = rd.read  # type: ignore[attr-defined]
    if m <= L:
        per = max(1, L // m)
        for k0, k in _blocks(count, per):
            yield read(k0 * m, (k0 + k) * m).reshape(k, m).mean(axis=1)
        return
    for sums in _block_sums(rd, m, count, L):
        yield sums / m


def _strided(rd: object, m: int, count: int, L: int) -> Iterator[np.ndarray]:
    """``x_0, x_m, x_2m, …`` (count values) in batches."""
    for k0, k in _blocks(count, max(L, 64)):
        yield rd.take(k0 * m, m, k)  # type: ignore[attr-defined]


def _with_history(batches: Iterator[np.ndarray], keep: int) -> Iterator[np.ndarray]:
    """Each batch preceded by the last ``keep`` values of the series before it."""
    tail = np.empty(0)
    for b in batches:
        ext = np.concatenate((tail, b)) if tail.size else b
        yield ext
        tail = ext[-keep:] if keep else np.empty(0)
