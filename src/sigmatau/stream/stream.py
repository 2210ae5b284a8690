"""The public face of streaming: :class:`Stream`."""

from __future__ import annotations

from typing import Any, Optional, Sequence, Union

import numpy as np

from ..core.result import StabilityResult
from ..core.validate import check_data_type, check_rate
from ..errors import DataError, ParameterError
from ..uncertainty.attach import check_options
from ..uncertainty.confidence import ONE_SIGMA
from ..uncertainty.noiseid import FAMILY_ALIASES, InsufficientDataError
from .chain import SLOTS
from .checks import as_chunk, check_channels, check_max_m, check_name, check_statistics, check_taus
from .noiseid import identify_rows
from .results import SUM_OF, check_length, finish, raw_result, rows, totvar_edges
from .state import StreamState

__all__ = ["Stream", "DEFAULT_STATISTICS", "DEFAULT_MAX_M", "DEFAULT_BLOCK"]

#: What a stream computes unless told otherwise: the statistics of the main job that stream.
DEFAULT_STATISTICS: tuple[str, ...] = ("oadev", "ohdev", "mdev", "tdev", "totdev")
#: Largest averaging factor by default: τ up to 262 s at 1 kHz, about 28 MB per channel.
DEFAULT_MAX_M = 2**18
#: Samples processed at once by default: fewer Python steps per sample; the row dot products
#: stay single-threaded up to this length (:func:`sigmatau.stream.buffers.rowdot`).
DEFAULT_BLOCK = 8192


class Stream:
    """Allan-family statistics of a record that is still being recorded, updated chunk by chunk.

    ``result(name)`` is, at any moment, the batch statistic of every sample given so
    far — ``sigmatau.<name>(all_samples, rate=rate, data_type=data_type)`` on the octave
    grid — with the same τ rows, term counts, noise types, EDF and intervals, computed
    from a state whose size depends on ``max_m`` only, never on the record's length.

    Parameters
    ----------
    rate : float
        Sample rate in Hz (τ0 = 1/rate).
    statistics : str or sequence of str
        Any of ``"adev"``, ``"oadev"``, ``"mdev"``, ``"tdev"``, ``"hdev"``, ``"ohdev"``,
        ``"totdev"`` (default: OADEV, OHDEV, MDEV, TDEV, TOTDEV).
    taus : {"octave"}
        The τ grid. Only the octave grid streams: its factors for N points are a prefix
        of those for more points (the ``"log"`` grid moves with N).
    max_m : int
        Largest averaging factor (τ_max = max_m/rate), default 2**18. The grid of each
        statistic is the batch's octave grid for the samples seen, **truncated at
        max_m**: once the record is long enough for longer τ, the rows simply stop at
        ``max_m`` (``result.m[-1] ≤ max_m``); everything else is unchanged.
    data_type : {"freq", "phase"}
        Rate/fractional-frequency samples (default) or phase (time-error) samples, as
        the batch functions take them.
    confidence : float
        Two-sided coverage of the χ² intervals (default ±1σ, 0.683).
    ci : {"chi2", "simple", None}
        As in the batch functions; None skips noise identification and intervals.
    channels : int, optional
        Number of channels updated together (a 2-D chunk is ``(samples, channels)``);
        taken from the first chunk when not given.
    block : int
        Samples processed at once (a tuning knob; smaller chunks wait in a buffer,
        which :meth:`result` always flushes first).

    Attributes
    ----------
    n : int
        Samples seen per channel.
    nbytes : int
        Bytes held by the stream's arrays (fixed once the first chunk has arrived).

    Notes
    -----
    *What is kept.* Phase data are differenced on arrival, ``y_i = x_{i+1} − x_i``; the
    frequency samples ``y`` less a provisional offset (the mean of the first block) and
    scaled by a power of two feed the window sums ``A_p[j] = Σ_{i=j}^{j+p-1} y_i`` and
    ``B_p[j] = Σ_{k=j}^{j+p-1} A_p[k]`` at p = 1, 2, 4 … P (P the largest power of two
    ≤ max_m), held in ring buffers and reached from p/2 by the batch's exact doublings.
    Each block of samples adds to compensated (Neumaier) running sums, at every p, the
    squares of the terms it completes:

    .. math:: \\mathrm{OAVAR}: (A_p[j+p] - A_p[j])^2,\\;
              \\mathrm{OHVAR}: (A_p[j+2p] - 2A_p[j+p] + A_p[j])^2,\\;
              \\mathrm{MVAR}: (B_p[j+p] - B_p[j])^2,

    with ``A_p[j+p] − A_p[j] = Δ²_p x_j/τ0``; AVAR and HVAR difference the block sums
    ``A_p[kp]``; TVAR = MVAR·τ²/3. TOTVAR's interior terms are OAVAR's; its reflected
    end terms (``x*_{−j} = 2x_0 − x_j``, ``x*_{N−1+j} = 2x_{N−1} − x_{N−1−j}``) need the
    first and the last 2m − 1 samples, kept, and are summed when the result is read.
    Normalisations are the batch's (SP1065 §5.2, numerics.md §1). The noise type at each τ
    follows :func:`sigmatau.noiseid.identify` from running state: lag-1 autocorrelations
    from running moments of the decimated/averaged series differenced 0 … dmax times,
    B1 from the first 30 block means at each factor (the batch's own arithmetic: B1 is
    applied only while fewer than 30 averages exist), R(n) from the stream's MVAR/OAVAR;
    EDF and intervals are then :func:`sigmatau.uncertainty.attach.attach`'s.

    *Equality.* For any chunking the rows, term counts, noise types α, EDF and ``ci_reason``
    are the batch's (B1's block means are computed by the batch's own arithmetic, bit for
    bit; the lag-1 sums in another order, so α̂ agrees to about 1e-12), and the variance
    agrees to 1e-12 relative wherever the batch itself is that close to the exact value.
    Where it is not — phase data with a frequency offset or a random-walk or random-run
    character, from which the batch subtracts the line through the first and last points
    (a stream cannot know the last; up to 3e-10 lost on such data), TOTDEV of frequency
    data, which the batch integrates to phase — the stream stays within 2e-12 of the exact
    value, usually 1e-15. Its own weakest rows are white PM's longest MDEV/TDEV rows and
    random-run FM's shortest OHDEV/HDEV rows, about 1e-12 from the exact value: there one
    rounding of each frequency sample already moves the result by ~5e-13.

    *Memory* per channel, P the largest power of two ≤ max_m and b the block (8192):
    the last ``2P`` raw samples and, with TOTDEV, the first ``2P``; the window sums, ``p``
    of A (``2p`` with OHDEV) and ``2p`` of B at each factor, each with room for two
    blocks; about ``8·(11·P + 4·b·(log2 P + 1))`` bytes with the default statistics
    (28 MB at P = 2**18, 98 MB at 2**20; ``2P`` values less without TOTDEV, ``P`` less
    without OHDEV). ``nbytes`` gives the exact figure; it is fixed when the first chunk
    arrives and never grows with the record.

    *Cost* per sample and channel: about a dozen array operations at each of the
    log2(P) + 1 factors, vectorised over blocks of b samples and over the channels, plus
    the lag-1 moments (a few operations at the shortest factors). Measured with
    ``bench/stream.py`` on one core of a busy 2-core machine, six channels at P = 2**18:
    0.96–1.15e7 samples/s of CPU time (chunks of 1000 or 100 000 samples), 0.4–0.9 times
    allantools' OADEV of the whole record in wall time, in the same run.

    *Not streamable.* STDEV/OSTDEV, MHDEV, LDEV, PDEV, TIE rms (not implemented), the
    modified total family (each subsequence detrended and reflected on its own), the
    Theo family (its τ reach 75 % of the record: O(N) memory), MTIE (window extremes at
    every τ over the record). Missing samples (NaN) are refused: the batch functions
    analyse gaps on a record in memory.

    References
    ----------
    W. J. Riley, NIST SP 1065 (2008) §5.2, §5.6; W. J. Riley and C. A. Greenhall, Proc.
    18th EFTF (2004) (lag-1 noise identification); numerics.md §1, §5.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau.stream import Stream
    >>> y = np.random.default_rng(0).standard_normal(20_000)
    >>> s = Stream(rate=100.0, statistics=("oadev", "mdev"), max_m=2**10)
    >>> for chunk in np.array_split(y, 7):
    ...     s.update(chunk)
    >>> r = s.result("oadev")
    >>> b = sigmatau.oadev(y, rate=100.0)
    >>> bool(np.allclose(r.dev, b.dev[: len(r)], rtol=1e-12)), r.alpha.tolist() == b.alpha[: len(r)].tolist()
    (True, True)
    """

    def __init__(self, rate: float, *, statistics: Union[str, Sequence[str]] = DEFAULT_STATISTICS,
                 taus: str = "octave", max_m: int = DEFAULT_MAX_M, data_type: str = "freq",
                 confidence: float = ONE_SIGMA, ci: Optional[str] = "chi2", channels: Optional[int] = None,
                 block: int = DEFAULT_BLOCK) -> None:
        self.rate = check_rate(rate)
        self.data_type = check_data_type(data_type)
        self.statistics = check_statistics(statistics)
        check_taus(taus)
        self.max_m = check_max_m(max_m)
        _, self.confidence, self.ci = check_options(None, confidence, ci)
        self._channels = check_channels(channels)
        if isinstance(block, (bool, np.bool_)) or not isinstance(block, (int, np.integer)) or block < 16:
            raise ParameterError(f"block={block!r} must be an integer ≥ 16")
        self._block = int(block)
        self._n = 0
        self._state: Optional[StreamState] = None
        self._cache: dict[tuple[str, int], StabilityResult] = {}

    # ------------------------------------------------------------------ input

    def update(self, chunk: Any) -> None:
        """Add samples: a 1-D array of one channel's samples, or 2-D ``(samples, channels)``.

        Any length, one sample to millions; an empty chunk changes nothing.

        Raises
        ------
        DataError
            Non-numeric or complex data, NaN or infinite values (a stream takes no gaps),
            masked values, integers beyond ±2**53, or not 1-D/2-D, or another number of
            channels than the stream's. The stream is left as it was.
        """
        samples = as_chunk(chunk, self._channels)
        if samples.shape[0] == 0:
            return
        if self._state is None:
            self._channels = samples.shape[1]
            self._state = self._new_state()
        self._state.check_range(samples)
        self._cache.clear()
        self._state.take(samples)
        self._n += samples.shape[0]

    def _new_state(self) -> StreamState:
        hadamard = any(FAMILY_ALIASES[s] == "hadamard" for s in self.statistics)
        factor = 1 << (self.max_m.bit_length() - 1)
        return StreamState(self._channels, factor, self.data_type, self._block, ohdev="ohdev" in self.statistics,
                           totdev="totdev" in self.statistics, depth=4 if hadamard else 3)

    # ------------------------------------------------------------------ output

    @property
    def n(self) -> int:
        """Samples seen per channel."""
        return self._n

    @property
    def channels(self) -> Optional[int]:
        """Number of channels (None until the first chunk when not given)."""
        return self._channels

    @property
    def nbytes(self) -> int:
        """Bytes held by the stream's arrays (constant once the first chunk has arrived)."""
        return 0 if self._state is None else self._state.nbytes

    def result(self, name: str, channel: int = 0) -> StabilityResult:
        """The statistic ``name`` of every sample seen so far on ``channel``, as the batch function.

        Raises
        ------
        ParameterError
            ``name`` is not one of this stream's statistics, or ``channel`` is out of range.
        DataError
            Too few samples for the statistic yet (the batch's message).
        """
        check_name(name)
        if name not in self.statistics:
            raise ParameterError(f"{name!r} is not among this stream's statistics ({', '.join(self.statistics)})")
        return self._computed(name, self._check_channel(channel))

    def results(self, channel: int = 0) -> dict[str, StabilityResult]:
        """Every statistic of the stream on ``channel``, by name."""
        ch = self._check_channel(channel)
        return {name: self._computed(name, ch) for name in self.statistics}

    def imu_model(self, *, channel: int = 0, **kwargs: Any) -> Any:
        """The IMU noise model (Q, N, B, K, R with intervals) of the OADEV curve so far.

        ``sigmatau.imu.analyze(<OADEV of the stream>, rate=rate, **kwargs)``; ``unit`` is
        required, as there. Frequency-type (rate) samples only.
        """
        from ..imu import analyze

        if self.data_type != "freq":
            raise ParameterError("an IMU noise model needs rate samples (data_type='freq'), not phase")
        return analyze(self._computed("oadev", self._check_channel(channel)), **{"rate": self.rate, **kwargs})

    def _check_channel(self, channel: object) -> int:
        count = self._channels or 1
        if isinstance(channel, (bool, np.bool_)) or not isinstance(channel, (int, np.integer)) \
                or not 0 <= channel < count:
            raise ParameterError(f"channel={channel!r} must be an integer from 0 to {count - 1}")
        return int(channel)

    def _computed(self, name: str, channel: int) -> StabilityResult:
        key = (name, channel)
        if key not in self._cache:
            self._cache[key] = self._compute(name, channel)
        return self._cache[key]

    def _compute(self, name: str, channel: int) -> StabilityResult:
        n_points = check_length(name, self._n, self.data_type)
        state = self._state
        state.settle()
        ms = rows(name, n_points, self.max_m)
        levels = np.array([m.bit_length() - 1 for m in ms.tolist()], dtype=np.int64)
        sums = state.chain.totals()[channel, levels, SLOTS[SUM_OF[name]]]
        edges = None
        if name == "totdev":
            head, tail = state.ends(channel, 2 * int(ms[-1]) - 1)
            edges = totvar_edges(head, tail, ms, n_points)
        raw = raw_result(name, sums, ms, n_points=n_points, rate=self.rate, data_type=self.data_type,
                         exponent=int(state.exponent[channel]), edges=edges)
        return finish(raw, confidence=self.confidence, ci=self.ci,
                      identified=lambda: self._identify(raw, channel))

    def _identify(self, raw: StabilityResult, channel: int) -> tuple[np.ndarray, np.ndarray]:
        state = self._state
        return identify_rows(raw.statistic, raw.m.tolist(), raw.n.tolist(), data_type=self.data_type,
                             size=self._n, n_freq=state.n_freq, lag1=lambda level: state.lag1[level],
                             blocks=state.blocks, level_of=lambda m: m.bit_length() - 1, channel=channel,
                             rn=lambda m: self._rn(m, channel, raw.n_points))

    def _rn(self, m: int, channel: int, n_points: int) -> float:
        """R(n) = MVAR/OAVAR at m from the stream's sums (:func:`sigmatau.noiseid.rn_ratio`)."""
        if n_points < 3 * m:
            raise InsufficientDataError(f"R(n) needs at least {3 * m} phase points at m={m}, got {n_points}")
        sums = self._state.chain.totals()[channel, m.bit_length() - 1]
        av = sums[SLOTS["oadev"]] / (2.0 * m**2 * (n_points - 2 * m))
        mv = sums[SLOTS["mdev"]] / (2.0 * float(m) ** 4 * (n_points - 3 * m + 1))
        if av == 0.0:
            raise DataError(f"the Allan variance is zero at m={m}; R(n) is undefined")
        return float(mv / av)

    def __repr__(self) -> str:
        return (f"Stream({', '.join(self.statistics)}; {self.data_type} data at {self.rate:g} Hz, n = {self._n},"
                f" channels = {self._channels}, max_m = {self.max_m})")
