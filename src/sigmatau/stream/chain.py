"""The window-sum chain: the running sums of squares of OADEV, OHDEV, MDEV, ADEV and HDEV.

Everything is computed from the frequency samples ``y'`` (phase data are
differenced first, ``y_i = x_{i+1} − x_i``), less a provisional offset and
scaled by a power of two (:class:`sigmatau.stream.state.StreamState` chooses both on
the first block). At each octave factor p = 1, 2, 4 … P the chain keeps, in
buffers of the last few p values (:class:`~sigmatau.stream.buffers.Ring`), the
overlapped window sums

.. math:: A_p[j] = \\sum_{i=j}^{j+p-1} y'_i, \\qquad B_p[j] = \\sum_{k=j}^{j+p-1} A_p[k],

reached from the factor below by the exact doublings of
:class:`sigmatau.core.numeric.WindowSums` (the batch frequency kernels use the
same ones), ``A_2p[j] = A_p[j] + A_p[j+p]`` and
``B_2p[j] = (B_p[j] + 2B_p[j+p]) + B_p[j+2p]``: each window sum is a sum of
about 2·log2(p) rounded terms of its own size, and no running sum over the
record is needed (a sequential prefix sum would also cost ten additions a value
in numpy). The terms of the statistics are differences of these (numerics.md §1,
SP1065 §5.2):

* OAVAR: ``d_j = A_p[j+p] − A_p[j] = Δ²_p x_j/τ0``, j = 0 … M−2p;
* OHVAR: ``d_{j+p} − d_j = Δ³_p x_j/τ0``, j = 0 … M−3p;
* MVAR: ``t_j = B_p[j+p] − B_p[j] = Σ_{i<p} Δ²_p x_{j+i}/τ0``, j = 0 … M−3p+1;
* AVAR, HVAR: first and second differences of the block sums ``b_k = A_p[kp]``.

Each block of new samples adds, at each factor, the terms whose last sample it
holds; the sums of their squares go to compensated totals. A level holds the
last p values of A (2p with OHVAR) and 2p of B, plus a block: about 7·P values
and 4 blocks per factor in all. Cost: about a dozen array operations per factor
and sample, vectorised over the block and the channels.
"""

from __future__ import annotations

from typing import Callable, Optional

import numpy as np

from .buffers import CompensatedSums, Ring, rowdot

__all__ = ["Chain", "SLOTS", "SparseFeed"]

#: Index of each statistic's sum of squares in :attr:`Chain.sums` (last axis).
SLOTS = {"oadev": 0, "ohdev": 1, "mdev": 2, "adev": 3, "hdev": 4}


def _count(total: int, lost: int) -> int:
    """Terms a series of ``total`` samples yields when each term spans ``lost + 1`` of them."""
    return max(0, total - lost)


def _sumsq(v: np.ndarray) -> np.ndarray:
    """Σ v² along the last axis, per channel (in the calling thread: :func:`.buffers.rowdot`)."""
    return rowdot(v, v)


class SparseFeed:
    """A series that arrives a few values per block (the block sums at a long factor), passed on
    to ``consume`` in batches of at least ``size`` values, so that the Python work per block stays
    O(1) whatever the factor. :meth:`drain` passes on what is held (before reading the results)."""

    def __init__(self, channels: int, size: int, consume: Callable[[np.ndarray], None]) -> None:
        self.buffer = np.empty((channels, size))
        self.fill = 0
        self.consume = consume

    def push(self, values: np.ndarray) -> None:
        k = values.shape[1]
        if k == 0:
            return
        if self.fill + k <= self.buffer.shape[1]:
            self.buffer[:, self.fill : self.fill + k] = values
            self.fill += k
            if self.fill == self.buffer.shape[1]:
                self.drain()
            return
        self.drain()
        self.consume(values)

    def drain(self) -> None:
        if self.fill:
            self.consume(self.buffer[:, : self.fill].copy())
            self.fill = 0

    @property
    def nbytes(self) -> int:
        return int(self.buffer.nbytes)


class _BlockDifferences:
    """AVAR and HVAR at one factor: the squares of the first and second differences of the
    non-overlapped block sums ``b_k``, added to the chain's totals as the sums arrive."""

    def __init__(self, chain: "Chain", level: int) -> None:
        self.chain, self.level = chain, level
        self.tail = np.zeros((chain.channels, 2))  # the last two block sums
        self.count = 0

    def __call__(self, b: np.ndarray) -> None:
        keep = min(self.count, 2)
        ext = np.concatenate((self.tail[:, 2 - keep :], b), axis=1) if keep else b
        d1 = ext[:, 1:] - ext[:, :-1]
        d2 = d1[:, 1:] - d1[:, :-1]
        parts = np.zeros((self.chain.channels, len(SLOTS)))
        # only the differences that end in this batch: the history yields none twice
        parts[:, SLOTS["adev"]] = _sumsq(d1[:, max(0, keep - 1) :]) if d1.shape[1] else 0.0
        parts[:, SLOTS["hdev"]] = _sumsq(d2[:, max(0, keep - 2) :]) if d2.shape[1] else 0.0
        self.chain.block_sums.add_level(self.level, parts)
        self.tail = np.concatenate((self.tail, b[:, -2:]), axis=1)[:, -2:].copy()
        self.count += b.shape[1]


class _LevelTotals:
    """The compensated totals of one kind of sum at every level, added one level at a time."""

    def __init__(self, channels: int, levels: int) -> None:
        self.sums = CompensatedSums((channels, levels, len(SLOTS)))

    def add_level(self, level: int, parts: np.ndarray) -> None:
        full = np.zeros(self.sums.hi.shape)
        full[:, level, :] = parts
        self.sums.add(full)


class Chain:
    """Window sums at the octave factors ``1 … max_factor`` and the statistics' running sums.

    Parameters
    ----------
    channels : int
        Channels advanced together (one row each).
    max_factor : int
        Largest averaging factor kept (rounded down to a power of two).
    block : int
        Most samples one call of :meth:`advance` receives (sets the rings' headroom).
    hadamard : bool
        Keep 2p window sums ``A_p`` at every factor p (OHVAR reads ``A_p[j]``, ``A_p[j+p]``,
        ``A_p[j+2p]``).
    on_block_sums : callable, optional
        ``on_block_sums(level, b)``: also receives the block sums ``b_k = A_p[kp]`` of each
        level as they complete (frequency data: the lag-1 noise identification averages them).
    """

    def __init__(self, channels: int, max_factor: int, block: int, *, hadamard: bool,
                 on_block_sums: Optional[Callable[[int, np.ndarray], None]] = None) -> None:
        self.channels, self.hadamard = channels, hadamard
        self.factors = [1 << b for b in range(int(max_factor).bit_length())]
        levels = len(self.factors)
        top = levels - 1
        self.M = 0  # frequency samples seen
        self.ring_a = [Ring(channels, 2 * p if hadamard else p, block) for p in self.factors]
        self.ring_b = [Ring(channels, p if i == top else 2 * p, block) for i, p in enumerate(self.factors)]
        if top > 0:  # A_1 = B_1 = y': one buffer serves both
            self.ring_b[0] = self.ring_a[0] = Ring(channels, 2, block)
        self.sums = CompensatedSums((channels, levels, len(SLOTS)))
        self.block_sums = _LevelTotals(channels, levels)
        self.on_block_sums = on_block_sums
        self.feeds = [SparseFeed(channels, 256, _BlockDifferences(self, i)) for i in range(levels)]

    # ------------------------------------------------------------------ advancing

    def advance(self, y: np.ndarray) -> None:
        """Take the next block of scaled, shifted frequency samples ``y`` (``(channels, L)``)."""
        m0, m1 = self.M, self.M + y.shape[1]
        parts = np.zeros(self.sums.hi.shape)
        self.ring_a[0].append(y)  # A_1 = B_1 = y (one buffer)
        for level, p in enumerate(self.factors):
            if _count(m1, p - 1) == _count(m0, p - 1):
                break  # nothing new at this factor, so nothing at the longer ones either
            self._block_sums(level, p, m0, m1)
            last = level + 1 == len(self.factors)
            self._allan_terms(level, p, m0, m1, parts[:, level], double=not last)
            self._mvar_terms(level, p, m0, m1, parts[:, level])
            if not last:
                self._double_b(level, p, m0, m1)
        self.M = m1
        self.sums.add(parts)

    def _allan_terms(self, level: int, p: int, m0: int, m1: int, parts: np.ndarray, *, double: bool) -> None:
        """OAVAR terms ``d_j = A_p[j+p] − A_p[j]`` ending in this block, OHVAR's
        ``d_{j+p} − d_j``, and the new ``A_2p[j] = A_p[j] + A_p[j+p]`` from the same reads,
        written into the next level's ring (the order of WindowSums)."""
        ring = self.ring_a[level]
        j0, j1 = _count(m0, 2 * p - 1), _count(m1, 2 * p - 1)
        if j1 == j0:
            return
        ahead, behind = ring.read(j0 + p, j1 + p), ring.read(j0, j1)
        d = ahead - behind
        parts[:, SLOTS["oadev"]] = _sumsq(d)
        if self.hadamard:
            k0, k1 = _count(m0, 3 * p - 1), _count(m1, 3 * p - 1)
            if k1 > k0:
                # d_{j+p} are among the new d; d_j, p back, are read again from the ring
                older = ring.read(k0 + p, k1 + p) - ring.read(k0, k1)
                np.subtract(d[:, k0 + p - j0 :], older, out=older)
                parts[:, SLOTS["ohdev"]] = _sumsq(older)
        if double:
            _into(self.ring_a[level + 1], j1 - j0, lambda out: np.add(behind, ahead, out=out))

    def _mvar_terms(self, level: int, p: int, m0: int, m1: int, parts: np.ndarray) -> None:
        """MVAR terms ``t_j = B_p[j+p] − B_p[j]`` ending in this block."""
        t0, t1 = _count(m0, 3 * p - 2), _count(m1, 3 * p - 2)
        if t1 > t0:
            ring = self.ring_b[level]
            parts[:, SLOTS["mdev"]] = _sumsq(ring.read(t0 + p, t1 + p) - ring.read(t0, t1))

    def _double_b(self, level: int, p: int, m0: int, m1: int) -> None:
        """New ``B_2p[j] = (B_p[j] + 2B_p[j+p]) + B_p[j+2p]`` (the order of WindowSums), written
        into the next level's ring."""
        b0, b1 = _count(m0, 4 * p - 2), _count(m1, 4 * p - 2)
        if b1 == b0:
            return
        ring = self.ring_b[level]

        def double(out: np.ndarray) -> None:
            np.multiply(ring.read(b0 + p, b1 + p), 2.0, out=out)
            np.add(ring.read(b0, b1), out, out=out)
            np.add(out, ring.read(b0 + 2 * p, b1 + 2 * p), out=out)

        _into(self.ring_b[level + 1], b1 - b0, double)

    def _block_sums(self, level: int, p: int, m0: int, m1: int) -> None:
        """The block sums ``b_k = A_p[kp]`` of the blocks completed by this block."""
        k0, k1 = -(-_count(m0, p - 1) // p), -(-_count(m1, p - 1) // p)
        if k1 == k0:
            return
        b = self.ring_a[level].read(k0 * p, (k1 - 1) * p + 1)[:, ::p].copy()
        self.feeds[level].push(b)
        if self.on_block_sums is not None:
            self.on_block_sums(level, b)

    # ------------------------------------------------------------------ reading

    def drain(self) -> None:
        """Pass on the block sums held back (before the totals are read)."""
        for feed in self.feeds:
            feed.drain()

    def totals(self) -> np.ndarray:
        """``(channels, levels, len(SLOTS))`` sums of squares so far (call :meth:`drain` first)."""
        return self.sums.total() + self.block_sums.sums.total()

    @property
    def nbytes(self) -> int:
        rings = sum(r.nbytes for r in {id(r): r for r in self.ring_a + self.ring_b}.values())
        return int(rings + self.sums.nbytes + self.block_sums.sums.nbytes + sum(f.nbytes for f in self.feeds))


def _into(ring: Ring, length: int, compute: Callable[[np.ndarray], object]) -> None:
    """Append ``length`` values that ``compute(out)`` writes: straight into the ring's storage
    when it does not wrap there, else through a temporary."""
    out = ring.slot(length)
    if out is not None:
        compute(out)
        ring.commit(length)
        return
    out = np.empty((ring.data.shape[0], length))
    compute(out)
    ring.append(out)
