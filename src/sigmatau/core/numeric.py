"""Small numeric building blocks shared by the estimator kernels."""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

__all__ = [
    "sumsq", "dot", "window_sums", "block_means", "sumsq_combination", "centred_sumsq", "WindowSums", "CHUNK",
    "doublings_only",
]


def sumsq(v: np.ndarray) -> float:
    """Σ v_i² without BLAS.

    ``np.dot`` dispatches to a threaded BLAS whose threads stall on a busy
    machine (9x slower than this on the 2-core reference machine); einsum runs
    in the calling thread.
    """
    return float(np.einsum("i,i->", v, v))


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """Σ a_i·b_i without BLAS (see :func:`sumsq`)."""
    return float(np.einsum("i,i->", a, b))


def window_sums(v: np.ndarray, m: int) -> np.ndarray:
    """Sums of ``m`` consecutive values of ``v`` (``v.size - m + 1`` of them), in O(N).

    ``v`` is always a difference series in the kernels, so its running sum stays
    of the order of a few window sums and the subtraction loses no significant
    digits.
    """
    if m == 1:
        return v.copy()
    c = np.empty(v.size + 1)
    c[0] = 0.0
    np.cumsum(v, out=c[1:])
    return c[m:] - c[:-m]


def block_means(y: np.ndarray, m: int) -> np.ndarray:
    """Means of the ``⌊M/m⌋`` non-overlapped blocks of ``m`` samples starting at 0."""
    k = y.size // m
    return y[: k * m].reshape(k, m).mean(axis=1)


#: Elements per chunk of the chunked helpers: a few such buffers stay in the L2
#: cache, and no temporary as large as the record is ever allocated (fresh
#: record-sized arrays cost more in page faults than the arithmetic on them).
CHUNK = 1 << 15


def sumsq_combination(terms: Sequence[tuple[float, np.ndarray]], n: int, chunk: Optional[int] = None) -> float:
    """``Σ_{j<n} (Σ_k c_k·a_k[j])²`` for ``terms = [(c_k, a_k), …]``, chunk by chunk.

    The combination is evaluated left to right exactly as the written
    expression ``c_0·a_0 + c_1·a_1 + …`` (a coefficient ±1 is an exact add or
    subtract), so the result is what the unchunked numpy expression gives, up
    to the order of the final summation.
    """
    if n <= 0:
        return 0.0
    size = min(chunk or CHUNK, n)
    buf = np.empty(size)
    tmp = np.empty(size) if any(abs(c) != 1.0 for c, _ in terms[1:]) else None
    total = 0.0
    for lo in range(0, n, size):
        hi = min(lo + size, n)
        b = buf[: hi - lo]
        _combine(b, tmp, terms, lo, hi)
        total += float(np.einsum("i,i->", b, b))
    return total


def _combine(out: np.ndarray, tmp: Optional[np.ndarray], terms: Sequence[tuple[float, np.ndarray]], lo: int, hi: int) -> None:
    """``out = Σ_k c_k·a_k[lo:hi]`` (left to right)."""
    c0, a0 = terms[0]
    rest = terms[1:]
    if c0 == 1.0 and rest:
        # a0 + c1·a1 written straight into out: the same single rounding as copying a0 and
        # then adding, one pass over the chunk less (OADEV: a[m:] - a[:-m] in one subtract).
        c1, a1 = rest[0]
        rest = rest[1:]
        if c1 == 1.0:
            np.add(a0[lo:hi], a1[lo:hi], out=out)
        elif c1 == -1.0:
            np.subtract(a0[lo:hi], a1[lo:hi], out=out)
        else:
            t = tmp[: hi - lo]
            np.multiply(a1[lo:hi], c1, out=t)
            np.add(a0[lo:hi], t, out=out)
    elif c0 == 1.0:
        np.copyto(out, a0[lo:hi])
    else:
        np.multiply(a0[lo:hi], c0, out=out)
    for c, a in rest:
        if c == 1.0:
            np.add(out, a[lo:hi], out=out)
        elif c == -1.0:
            np.subtract(out, a[lo:hi], out=out)
        else:
            t = tmp[: hi - lo]
            np.multiply(a[lo:hi], c, out=t)
            np.add(out, t, out=out)


def centred_sumsq(v: np.ndarray, chunk: Optional[int] = None) -> tuple[float, float]:
    """``(mean, Σ (v_i − mean)²)`` in two chunked passes (no record-sized temporary)."""
    n = v.size
    mean = float(np.add.reduce(v)) / n
    size = min(chunk or CHUNK, n)
    buf = np.empty(size)
    total = 0.0
    for lo in range(0, n, size):
        hi = min(lo + size, n)
        b = buf[: hi - lo]
        np.subtract(v[lo:hi], mean, out=b)
        total += float(np.einsum("i,i->", b, b))
    return mean, total


class WindowSums:
    """Overlapped window sums of a series, carried from one window length to the next.

    For the series ``y_0 … y_{M-1}`` and window length w the object holds

    * ``a``: ``A_w[j] = Σ_{i=j}^{j+w-1} y_i`` for ``j = 0 … M-w`` (M−w+1 values);
    * ``b`` (with ``double=True``): the window sums of those,
      ``B_w[j] = Σ_{k=j}^{j+w-1} A_w[k]`` (M−2w+2 values), the triangular-weight
      sums behind the modified Allan variance.

    :meth:`advance` moves to a longer or shorter w through the binary digits of
    w, using two exact recurrences,

    * doubling: ``A_2w[j] = A_w[j] + A_w[j+w]``, ``B_2w[j] = B_w[j] + 2B_w[j+w] + B_w[j+2w]``;
    * increment: ``A_{w+1}[j] = A_w[j] + y_{j+w}``, ``B_{w+1}[j] = B_w[j] + 2A_w[j+w] + y_{j+2w}``,

    so each window sum is a sum of about 2·log2(w) rounded terms of its own size
    (a pairwise-like summation), instead of the difference of two running sums
    of the whole record; a factor of two (the octave grid) costs one pass over
    the record, any other at most 2·log2(w) passes. The arrays are updated in
    place, chunk by chunk, so the object holds one (two with ``double``) copies
    of the series and nothing else of its size.
    """

    #: Unit increments tolerated before restarting from the series (each adds a rounding).
    MAX_INCREMENTS = 8

    def __init__(self, y: np.ndarray, *, double: bool = False, chunk: Optional[int] = None) -> None:
        chunk = chunk or CHUNK
        self._y = y
        self._double = double
        self._chunk = chunk
        self._A = np.empty(y.size)
        self._B = np.empty(y.size) if double else None
        self._tmp = np.empty(min(chunk, y.size))
        self._w = 0
        self._steps = 0

    @property
    def w(self) -> int:
        return self._w

    @property
    def a(self) -> np.ndarray:
        """``A_w`` (a view, valid until the next :meth:`advance`)."""
        if self._A is None:
            raise AttributeError("A_w was released (release_a)")
        return self._A[: self._y.size - self._w + 1]

    def release_a(self) -> None:
        """Free ``A`` when only ``B`` is wanted from here on and every later step is a doubling.

        B doubles from B alone; A is needed only by increments and restarts. A
        caller that keeps to doublings (an octave grid past w = 4, where
        :meth:`advance` never chooses increments) saves a record-sized array;
        any later step that would need A raises.
        """
        if self._B is None:
            raise ValueError("release_a needs double=True")
        self._A = None

    @property
    def b(self) -> np.ndarray:
        """``B_w`` (a view, valid until the next :meth:`advance`)."""
        if self._B is None:
            raise AttributeError("WindowSums(double=False) keeps no double sums")
        return self._B[: max(self._y.size - 2 * self._w + 2, 0)]

    def advance(self, w: int) -> None:
        """Move to window length ``w`` (1 ≤ w ≤ M)."""
        w = int(w)
        if not 1 <= w <= self._y.size:
            raise ValueError(f"window length {w} outside 1 … {self._y.size}")
        if w == self._w:
            return
        bits = bin(w)[2:]
        here = bin(self._w)[2:] if self._w else ""
        chain = len(bits) - 1 + bits.count("1") - 1
        extend = len(bits) - len(here) + bits[len(here):].count("1")
        if self._A is None and not (here and bits.startswith(here) and bits[len(here):].count("1") == 0):
            raise ValueError(f"window length {w} from {self._w} needs A_w, which was released")
        if 0 < self._w < w and w - self._w <= min(chain, self.MAX_INCREMENTS - self._steps):
            if self._A is None:
                raise ValueError(f"window length {w} from {self._w} needs A_w, which was released")
            # A few unit steps are cheaper than rebuilding (dense grids).
            for _ in range(w - self._w):
                self._increment()
            self._steps += w - self._w
            return
        if not (here and bits.startswith(here) and extend <= chain):
            self._restart()
            here = "1"
        for bit in bits[len(here):]:
            self._double_step()
            if bit == "1":
                self._increment()
        self._steps = 0

    def _restart(self) -> None:
        np.copyto(self._A, self._y)
        if self._B is not None:
            np.copyto(self._B, self._y)
        self._w = 1

    def _double_step(self) -> None:
        w, M, C, tmp = self._w, self._y.size, self._chunk, self._tmp
        A, B = self._A, self._B
        if B is not None:
            n = M - 4 * w + 2  # length of B_2w
            for lo in range(0, max(n, 0), C):
                hi = min(lo + C, n)
                t = tmp[: hi - lo]
                np.multiply(B[lo + w : hi + w], 2.0, out=t)
                np.add(B[lo:hi], t, out=t)
                np.add(t, B[lo + 2 * w : hi + 2 * w], out=B[lo:hi])
        n = M - 2 * w + 1 if A is not None else 0  # length of A_2w (none once released)
        for lo in range(0, max(n, 0), C):
            hi = min(lo + C, n)
            if hi - lo <= w:
                np.add(A[lo:hi], A[lo + w : hi + w], out=A[lo:hi])
            else:
                t = tmp[: hi - lo]
                np.add(A[lo:hi], A[lo + w : hi + w], out=t)
                np.copyto(A[lo:hi], t)
        self._w = 2 * w

    def _increment(self) -> None:
        w, M, C, tmp, y = self._w, self._y.size, self._chunk, self._tmp, self._y
        A, B = self._A, self._B
        if B is not None:
            # Uses A_w, so it runs before A moves on.
            n = M - 2 * w  # length of B_{w+1}
            for lo in range(0, max(n, 0), C):
                hi = min(lo + C, n)
                t = tmp[: hi - lo]
                np.multiply(A[lo + w : hi + w], 2.0, out=t)
                np.add(B[lo:hi], t, out=t)
                np.add(t, y[lo + 2 * w : hi + 2 * w], out=B[lo:hi])
        n = M - w  # length of A_{w+1}
        np.add(A[:n], y[w : w + n], out=A[:n])
        self._w = w + 1


def doublings_only(m: int, later: np.ndarray) -> bool:
    """Whether every later averaging factor is ``m`` times a power of two (2, 4, …) or ``m``
    itself: then window sums at ``m`` reach every later factor by exact doublings, and the
    kernels may release the sums they no longer need (MVAR's A on an octave grid).

    >>> doublings_only(4, np.array([4, 8, 32]))
    True
    >>> doublings_only(4, np.array([8, 12]))
    False
    """
    for v in later.tolist():
        q, r = divmod(int(v), m)
        if r or q & (q - 1):
            return False
    return True
