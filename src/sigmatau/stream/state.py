"""What a stream holds between chunks, and how a block of samples moves it on.

:class:`StreamState` owns every array of a :class:`~sigmatau.stream.Stream`: the
samples waiting to make up a block, the raw frequency samples of the last
``2·P`` (B1 block means, TOTDEV's right end) and the first ``2·P`` (TOTDEV's left
end), the window-sum chain (:class:`~sigmatau.stream.chain.Chain`) and the noise
identification's running moments and block means
(:mod:`sigmatau.stream.noiseid`). Its size is fixed when it is made: nothing
grows with the record.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import DataError
from .buffers import Ring
from .chain import Chain, SparseFeed
from .noiseid import B1Blocks, Lag1Moments

__all__ = ["StreamState"]


def _exponent(v: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Per channel, k with the largest |(v − shift)·2**-k| in [0.5, 1), as ``scale_to_unit`` does;
    that of |v| where v − shift is all zeros (0 where v is too)."""
    peak = np.max(np.abs(v - shift[:, None]), axis=1)
    peak = np.where(peak > 0.0, peak, np.max(np.abs(v), axis=1))
    return np.frexp(peak)[1].astype(np.int64)


class StreamState:
    """The arrays of a stream of ``channels`` channels (see the module docstring).

    Parameters
    ----------
    channels : int
    factor : int
        Largest averaging factor P (a power of two).
    data_type : {"freq", "phase"}
    block : int
        Samples processed at once.
    ohdev, totdev : bool
        Keep what OHDEV (2p window sums per level) and TOTDEV (the first 2P samples) need.
    depth : int
        Orders of difference of the lag-1 method, ``dmax + 1`` (4 with the Hadamard family).
    """

    def __init__(self, channels: int, factor: int, data_type: str, block: int, *, ohdev: bool, totdev: bool,
                 depth: int) -> None:
        self.channels, self.factor, self.data_type, self.block = channels, factor, data_type, block
        self.pending = np.empty((channels, block))
        self.fill = 0
        self.raw = Ring(channels, 2 * factor + 2, block)
        self.head = np.empty((channels, 2 * factor)) if totdev else None
        self.head_fill = 0
        factors = [1 << b for b in range(factor.bit_length())]
        self.factors = factors
        self.lag1 = [Lag1Moments(channels, depth) for _ in factors]
        self.lag1_feeds = [SparseFeed(channels, 256, moments) for moments in self.lag1]
        self.blocks = B1Blocks(channels, factors, hadamard=depth > 3)
        on_blocks = self._block_means if data_type == "freq" else None
        self.chain = Chain(channels, factor, block, hadamard=ohdev, on_block_sums=on_blocks)
        self.n_phase = 0  # phase samples flushed (phase data)
        self.offset = np.zeros(channels)  # provisional offset of the frequency samples
        self.exponent = np.zeros(channels, dtype=np.int64)  # their scale, 2**exponent
        self.x_first = np.zeros(channels)  # phase data: first sample and scale of the decimated series
        self.x_exponent = np.zeros(channels, dtype=np.int64)
        self.last_x = np.zeros(channels)

    @property
    def n_freq(self) -> int:
        """Frequency samples that went through the chain."""
        return self.chain.M

    # ------------------------------------------------------------------ taking samples

    def check_range(self, samples: np.ndarray) -> None:
        """Refuse, before anything changes, samples the running sums could not hold.

        The state holds the samples less an offset and scaled by ``2**-exponent``, both set by
        the first block; window sums of P samples, their squares (MVAR: up to P⁴·r² for
        scaled values r) and sums of N squares must stay below float64's 2**1024. So a value
        ``r`` times the first block's scale is taken while ``log2 r ≤ (1000 − 4·log2 P − 64)/2``
        (N up to 2**64), and nothing beyond ±1e300 (the first block's mean must be finite).
        """
        if not samples.size:
            return
        peak = float(np.max(np.abs(samples)))
        if peak > 1e300:
            raise DataError(f"the chunk holds a value of magnitude {peak:.3g}, beyond ±1e300: a stream's running"
                            " sums would overflow; rescale the data (another unit)")
        limit = 2.0 ** ((1000 - 4 * (self.factor.bit_length() - 1) - 64) // 2)
        checks = []
        if self.data_type == "phase" and self.n_phase:
            x = samples.T
            checks.append(("phase", x - self.x_first[:, None], self.x_exponent))
            ext = np.concatenate((self.last_x[:, None], x), axis=1)
            if self.chain.M:
                checks.append(("frequency", np.diff(ext, axis=1) - self.offset[:, None], self.exponent))
        elif self.data_type == "freq" and self.chain.M:
            checks.append(("", samples.T - self.offset[:, None], self.exponent))
        for what, dev, exponent in checks:
            scaled = np.max(np.abs(dev), axis=1) * np.ldexp(1.0, -exponent)
            if np.any(scaled > limit):
                c = int(np.argmax(scaled))
                ratio = float(scaled[c]) if math.isfinite(float(scaled[c])) else math.inf
                raise DataError(
                    f"channel {c}: the chunk's {what + ' ' if what else ''}values depart from the stream's first"
                    f" samples by {ratio:.3g} times their scale, beyond what its running sums can hold"
                    f" ({limit:.3g}); rescale the data, or start a new stream")

    def take(self, samples: np.ndarray) -> None:
        """Queue ``samples`` (``(length, channels)``), flushing every full block."""
        pos, length = 0, samples.shape[0]
        while pos < length:
            if self.fill == 0 and length - pos >= self.block:
                self.flush(np.ascontiguousarray(samples[pos : pos + self.block].T))
                pos += self.block
                continue
            k = min(self.block - self.fill, length - pos)
            self.pending[:, self.fill : self.fill + k] = samples[pos : pos + k].T
            self.fill += k
            pos += k
            if self.fill == self.block:
                self.fill = 0
                self.flush(self.pending)

    def settle(self) -> None:
        """Flush the samples waiting for a full block and everything held back, before reading."""
        if self.fill:
            fill, self.fill = self.fill, 0
            self.flush(self.pending[:, :fill])
        self.chain.drain()
        for feed in self.lag1_feeds:
            feed.drain()

    def flush(self, block: np.ndarray) -> None:
        """Move the state on by one block of samples (``(channels, length)``) as given."""
        if self.data_type == "phase":
            y = self._phase_block(block)
        else:
            y = block
        if y.shape[1] == 0:
            return
        if self.chain.M == 0:
            self._choose_scale(y)
        self.raw.append(y)
        if self.head is not None and self.head_fill < self.head.shape[1]:
            k = min(self.head.shape[1] - self.head_fill, y.shape[1])
            self.head[:, self.head_fill : self.head_fill + k] = y[:, :k]
            self.head_fill += k
        self.chain.advance(self.scaled(y))
        self.blocks.update(self.raw, self.chain.M)

    def scaled(self, y: np.ndarray) -> np.ndarray:
        """Raw frequency samples as the chain holds them: less the offset, times 2**-exponent
        (a product by a power of two is exact, as ``ldexp``, and three times faster)."""
        out = y - self.offset[:, None]
        out *= np.ldexp(1.0, -self.exponent)[:, None]
        return out

    def _choose_scale(self, y: np.ndarray) -> None:
        """The provisional offset and a power-of-two scale (the squares of data near 1e±300 stay finite).

        The offset is the mean of the first block and stays: what it leaves in y' enters the
        window sums as p·δ (A_p) and p²·δ (B_p), and their round-off with it, but that
        round-off is smooth along the record and cancels in MVAR's differences
        ``B_p[j+p] − B_p[j]``. Moving the offset later (to the running mean) was tried: the
        shift leaves a step in that round-off which does not cancel, and white PM's last MDEV
        rows came out 10–30 times further from the exact value (2e-11 against 7e-13).
        """
        self.offset = np.mean(y, axis=1)
        self.exponent = _exponent(y, self.offset)

    def _phase_block(self, x: np.ndarray) -> np.ndarray:
        """Phase data: feed the lag-1 method its decimated points and return ``y_i = x_{i+1} − x_i``
        (the batch's ``np.diff`` of the phase, value for value)."""
        n0 = self.n_phase
        if n0 == 0:
            self.x_first = x[:, 0].copy()
            self.x_exponent = _exponent(x, self.x_first)
        for level, p in enumerate(self.factors):
            first = -(-n0 // p) * p - n0
            if first < x.shape[1]:
                z = x[:, first::p]
                self.lag1_feeds[level].push(np.ldexp(z - self.x_first[:, None], -self.x_exponent[:, None]))
        ext = x if n0 == 0 else np.concatenate((self.last_x[:, None], x), axis=1)
        self.last_x = x[:, -1].copy()
        self.n_phase += x.shape[1]
        return ext[:, 1:] - ext[:, :-1]

    def _block_means(self, level: int, sums: np.ndarray) -> None:
        """Frequency data: the block means of m samples are the lag-1 method's points."""
        self.lag1_feeds[level].push(sums / self.factors[level])

    # ------------------------------------------------------------------ reading

    def ends(self, channel: int, length: int) -> tuple[np.ndarray, np.ndarray]:
        """The first and last ``length`` frequency samples of a channel, scaled as in the chain."""
        head = self.head[channel : channel + 1, :length]
        m = self.chain.M
        tail = self.raw.read(m - length, m)[channel : channel + 1]
        return self.scaled_one(head, channel), self.scaled_one(tail, channel)

    def scaled_one(self, y: np.ndarray, channel: int) -> np.ndarray:
        """One channel's samples (a ``(1, n)`` array) as the chain holds them."""
        return (y[0] - self.offset[channel]) * np.ldexp(1.0, -int(self.exponent[channel]))

    @property
    def nbytes(self) -> int:
        arrays = [self.pending, self.offset, self.exponent, self.x_first, self.x_exponent, self.last_x]
        if self.head is not None:
            arrays.append(self.head)
        return int(sum(a.nbytes for a in arrays) + self.raw.nbytes + self.chain.nbytes + self.blocks.nbytes
                   + sum(m.nbytes for m in self.lag1) + sum(f.nbytes for f in self.lag1_feeds))
