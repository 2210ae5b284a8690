"""The two containers of a stream's state: ring buffers and compensated running sums.

A :class:`Ring` keeps the most recent values of a series for several channels
at once, addressed by their global index in the series, so that a level of the
window-sum chain can read the values ``p`` or ``2p`` behind its newest ones
without ever moving what it holds. :class:`CompensatedSums` adds the partial
sums of each block to running totals with Neumaier's compensation, so a sum over
10⁹ samples loses no more than one over a block.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

__all__ = ["Ring", "CompensatedSums", "rowdot"]

#: Longest row handed to ``numpy.vecdot`` at once: it calls BLAS ``ddot``, which OpenBLAS runs
#: on several threads above about 10⁴ elements, and those threads stall for milliseconds on a
#: busy machine (see :func:`sigmatau.core.numeric.sumsq`); below that it is single-threaded and
#: 2.5 times faster than ``einsum``.
_VECDOT_PIECE = 8192
_vecdot = getattr(np, "vecdot", None)  # numpy ≥ 2.0


def rowdot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``Σ_j a[i, j]·b[i, j]`` for each row i, in the calling thread."""
    n = a.shape[1]
    if _vecdot is None:
        return np.einsum("ij,ij->i", a, b)
    if n <= _VECDOT_PIECE:
        return _vecdot(a, b)
    out = _vecdot(a[:, :_VECDOT_PIECE], b[:, :_VECDOT_PIECE])
    for lo in range(_VECDOT_PIECE, n, _VECDOT_PIECE):
        out = out + _vecdot(a[:, lo : lo + _VECDOT_PIECE], b[:, lo : lo + _VECDOT_PIECE])
    return out


class Ring:
    """The recent values of a series, for ``channels`` channels, addressed by global index.

    Holds at least the last ``keep`` values plus the ``block`` appended after them, and
    returns any range of them as a ``(channels, length)`` array, a view whenever possible:

    * a short history (``keep ≤ block``) sits in a linear buffer of ``keep + 2·block``
      values; when an append would pass its end, the last ``keep`` values move to the
      front (a copy of ``keep`` values every other block), so every read is a view;
    * a long one in a ring of ``keep + block`` values whose first ``block`` slots are
      repeated after its end, so a read of up to ``block`` values is one view however it
      falls across the end (the repeat costs a copy of at most ``block/(keep + block)``
      of the values written); a longer read that wraps is copied from its two pieces.
    """

    def __init__(self, channels: int, keep: int, block: int) -> None:
        keep, block = max(int(keep), 0), max(int(block), 1)
        self.keep = keep
        self.linear = keep <= block
        self.capacity = keep + 2 * block if self.linear else keep + block
        self.mirror = 0 if self.linear else block
        self.data = np.zeros((channels, self.capacity + self.mirror))
        self.base = 0  # linear: global index of data[:, 0]
        self.end = 0  # global index one past the newest value

    @property
    def start(self) -> int:
        """Global index of the oldest value still held."""
        return self.base if self.linear else max(0, self.end - self.capacity)

    def append(self, values: np.ndarray) -> None:
        """Append ``values`` (``(channels, length)``, length ≤ block) after the newest value."""
        length = values.shape[1]
        if length == 0:
            return
        out = self.slot(length)
        if out is not None:
            out[...] = values
            self.commit(length)
            return
        pos = self.end % self.capacity
        first = self.capacity - pos
        self.data[:, pos : self.capacity] = values[:, :first]
        self.data[:, : length - first] = values[:, first:]
        self._mirror(pos, length)
        self.end += length

    def slot(self, length: int) -> Optional[np.ndarray]:
        """Storage for the next ``length`` values as a writable view (None when a ring would wrap
        there). Fill it, then :meth:`commit`: a result computed straight into the buffer
        (``out=``) saves the copy of :meth:`append`."""
        if self.linear:
            if self.end - self.base + length > self.capacity:
                self._compact()
            pos = self.end - self.base
            return self.data[:, pos : pos + length]
        pos = self.end % self.capacity
        return self.data[:, pos : pos + length] if pos + length <= self.capacity else None

    def commit(self, length: int) -> None:
        """Count the ``length`` values written into :meth:`slot` as appended."""
        if not self.linear:
            self._mirror(self.end % self.capacity, length)
        self.end += length

    def _compact(self) -> None:
        """Linear buffer: move the last ``keep`` values to the front."""
        held = self.end - self.base
        kept = min(self.keep, held)
        self.data[:, :kept] = self.data[:, held - kept : held]
        self.base = self.end - kept

    def _mirror(self, pos: int, length: int) -> None:
        """Ring: repeat what was just written into the first ``mirror`` slots after the end."""
        for lo, hi in ((pos, min(pos + length, self.capacity)), (0, max(0, pos + length - self.capacity))):
            hi = min(hi, self.mirror)
            if hi > lo:
                self.data[:, self.capacity + lo : self.capacity + hi] = self.data[:, lo:hi]

    def read(self, lo: int, hi: int) -> np.ndarray:
        """Values of global indices ``lo … hi-1`` (all of them still held)."""
        if not self.start <= lo <= hi <= self.end:
            raise IndexError(f"the buffer holds {self.start}…{self.end - 1}, asked {lo}…{hi - 1}")
        if self.linear:
            return self.data[:, lo - self.base : hi - self.base]
        pos = lo % self.capacity
        length = hi - lo
        if pos + length <= self.capacity + self.mirror:
            return self.data[:, pos : pos + length]
        return np.concatenate((self.data[:, pos : self.capacity],
                               self.data[:, : length - (self.capacity - pos)]), axis=1)

    @property
    def nbytes(self) -> int:
        return int(self.data.nbytes)


class CompensatedSums:
    """Running totals of many sums at once, each kept as an unevaluated pair ``hi + lo``.

    :meth:`add` adds an array of partial sums of the same shape with Neumaier's
    variant of Kahan summation (the TwoSum error of every addition goes to
    ``lo``), vectorised over the whole array, so the totals carry the rounding of
    the partial sums only, not that of the millions of additions behind them.

    References
    ----------
    A. Neumaier, "Rundungsfehleranalyse einiger Verfahren zur Summation endlicher
    Summen", ZAMM 54 (1974) 39–51; T. Ogita, S. M. Rump, S. Oishi, "Accurate sum
    and dot product", SIAM J. Sci. Comput. 26 (2005) 1955–1988 (TwoSum).
    """

    def __init__(self, shape: tuple[int, ...]) -> None:
        self.hi = np.zeros(shape)
        self.lo = np.zeros(shape)

    def add(self, parts: np.ndarray) -> None:
        """``total += parts``, element by element, with the rounding error kept in ``lo``."""
        s = self.hi + parts
        bp = s - self.hi
        # TwoSum: (hi - (s - bp)) + (parts - bp) is exactly hi + parts - s
        self.lo += (self.hi - (s - bp)) + (parts - bp)
        self.hi = s

    def total(self) -> np.ndarray:
        """The totals, ``hi + lo`` rounded once."""
        return self.hi + self.lo

    @property
    def nbytes(self) -> int:
        return int(self.hi.nbytes + self.lo.nbytes)
