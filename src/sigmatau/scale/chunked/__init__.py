"""Statistics of records larger than memory, computed chunk by chunk.

A :class:`ChunkedSeries` is a 1-D series of known length read in pieces: a
``.npy`` or raw binary file (:func:`from_npy`, :func:`from_binary`), an HDF5
dataset (:func:`from_hdf5`, extra ``hdf5``), a dask array (:func:`from_dask`)
or, for tests, an array in memory (:func:`from_array`). The public statistic
functions accept one directly, and a dask array too::

    sigmatau.oadev(sigmatau.chunked.from_npy("gyro_x.npy"), rate=200.0)

:func:`compute` does the same by statistic name and opens a path itself.

Supported: ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev``, ``ohdev`` and
``totdev`` (with its ``bias`` option), on phase or frequency data, with or
without missing samples (NaN gaps, :mod:`sigmatau.core.gaps`). The result is the
:class:`~sigmatau.core.result.StabilityResult` of the in-memory function: same τ
grid, ``n`` (and with gaps ``n_missing`` and ``n_effective``), noise
identification, EDF and interval, and the variance to ≤ 1e-12 relative
(``tests/test_chunked.py``, ``tests/test_chunked_gaps.py``).

How (N samples, chunk of L samples; every pass holds O(L) values)
------------------------------------------------------------------
* One pass validates the record (first non-finite index, as the in-memory
  error) and sums it in numpy's own pairwise order, so the mean removed from
  frequency data is bit-identical to ``y.mean()``; phase data lose the line
  through their end points element by element, as in memory.
* Overlapped statistics at factor m are window sums ``P_{j+m} - P_j`` of a
  running sum P. P is carried from block to block as a double-double: numpy's
  cumulative sum plus the exact rounding error of each addition (TwoSum), so
  the window sums come out rounded about once, however far P drifts with red
  noise; against exact integer arithmetic they agree to a few 1e-16. A block
  of L outputs reads the samples at offsets 0, m, 2m, 3m: one read of L + 3m
  samples when m ≤ L, separate reads of L otherwise, so m may exceed the
  chunk. MDEV of frequency data nests two such sums.
* Non-overlapped statistics stream block sums (numpy's pairwise order inside
  a block, reshaped per chunk when m ≤ L, split recursively when m > L) or
  strided phase samples.
* TOTDEV reads the reflected extension through an index map; for frequency
  data the phase is the running sum of the samples, restarted from a stored
  value every L samples (N/L checkpoints), so any range of it is reproduced
  bit for bit.
* Noise identification at each τ (lag-1 autocorrelation on the decimated or
  averaged series of length N/m, B1 and R(n) where few points remain) streams
  that series twice — for its means, then for its centred lag-0 and lag-1
  sums at every difference order — and follows the decision rules of
  :func:`sigmatau.noiseid.identify`.
* Scale: the validating pass also finds max|x|; every chunk is multiplied by
  the power of two 2**-k that brings it into [0.5, 1) as it is read, and the
  variance by 4**k at the end (exact; as the in-memory path does), so data
  near 1e±150 give the in-memory answer and a variance float64 cannot hold is
  the same one-line DataError, never 0 or inf.

Missing samples (NaN), streamed as the in-memory gap path computes them
------------------------------------------------------------------------
* The validating pass counts them and notes the first and last present sample
  (an infinite value, or a record with nothing present, is the in-memory
  one-line DataError); its sum takes NaN as 0, so the mean of the samples present
  is ``np.nanmean`` bit for bit. A record without NaN takes the path above,
  unchanged.
* Statistics whose in-memory form lets NaN run through the terms (ADEV, OADEV,
  HDEV, OHDEV and TOTDEV of phase; ADEV and HDEV of frequency) stream the same
  sample, window or block terms on the phase less the line through its first and
  last present points, or the frequency less the mean of those present; a term
  that reads a gap is NaN and only the finite ones are summed and counted.
* Statistics that the in-memory path pools over the gap-free runs (OADEV, OHDEV,
  MDEV, TDEV and TOTDEV of frequency; MDEV and TDEV of phase) are pooled the
  same way: one more pass finds the runs; a run that fits in a chunk is read and
  given to the in-memory kernel itself, a longer one is streamed by the kernels
  above as a record of its own (its own line or mean removed, reflected at its
  own ends for TOTDEV), and ``var = Σ var_s·n_s / Σ n_s``. Each run is thus
  prepared with the in-memory arithmetic; one line or mean for the whole record
  would round differently (by 3e-12 on 4·10^5 samples of random-run FM).
* ``n`` counts the terms used, ``n_effective`` the phase points of the
  contiguous record giving as many (:func:`sigmatau.core.gaps.equivalent_points`),
  from which the EDF follows; a factor with no gap-free term is dropped, with the
  in-memory RangeWarning when it was asked for, or the in-memory DataError when
  none is left.
* Noise identification follows the in-memory gap rules: a decimated point or a
  block mean that reads a gap is missing; the lag-1 autocorrelation takes the
  mean and the sum of squares over the points present and the lag-1 products over
  the pairs of neighbours both present; B1 takes the block means present,
  streamed twice when there are more blocks than a chunk holds.

Cost: O(N) time per τ (about five reads of the record: statistic and noise
identification); memory O(L) per pass, plus N/L checkpoints for TOTDEV of
frequency data. Gaps add one read (the runs) for the pooled statistics and
cost about as much as the record without them (2·10^6 samples, 20 single gaps
and a burst: OADEV 0.8 s, MDEV 2.7 s, TOTDEV 1.0 s of frequency, against 1.0,
3.4 and 1.1 s without gaps); each run shorter than L costs one in-memory
kernel call, as it does in memory.

Modules, each importing only those listed after it: :mod:`.compute`
(:func:`compute` by name), :mod:`.sources` (:class:`ChunkedSeries`, the
``from_*`` sources, the validating and scaling pass, and the
:class:`~sigmatau.core.driver.StreamedSeries` protocol that runs a statistic),
:mod:`.noiseid` (streamed noise identification), :mod:`.kernels` (the kernel of
every statistic; with gaps its gap kernel or the pooling over the gap-free runs)
and :mod:`.streams` (pairwise, running, window and block sums; the derived
series; the runs of present samples).
"""

from .compute import compute
from .sources import (DEFAULT_CHUNK, STATISTICS, ChunkedSeries, as_chunked, from_array, from_binary, from_dask,
                      from_hdf5, from_npy, open_series)

__all__ = [
    "DEFAULT_CHUNK",
    "STATISTICS",
    "ChunkedSeries",
    "from_npy",
    "from_binary",
    "from_hdf5",
    "from_dask",
    "from_array",
    "open_series",
    "as_chunked",
    "compute",
]
