"""Statistics of records larger than memory, computed chunk by chunk.

A :class:`ChunkedSeries` is a 1-D series of known length read in pieces: a
``.npy`` or raw binary file (:func:`from_npy`, :func:`from_binary`), an HDF5
dataset (:func:`from_hdf5`, extra ``hdf5``), a dask array (:func:`from_dask`)
or, for tests, an array in memory (:func:`from_array`). The public statistic
functions accept one directly, and a dask array too::

    sigmatau.oadev(sigmatau.chunked.from_npy("gyro_x.npy"), rate=200.0)

:func:`compute` does the same by statistic name and opens a path itself.

Supported: ``adev``, ``oadev``, ``mdev``, ``tdev``, ``hdev``, ``ohdev`` and
``totdev`` (with its ``bias`` option). The result is the
:class:`~sigmatau.core.result.StabilityResult` of the in-memory function: same τ
grid, ``n``, noise identification, EDF and interval, and the variance to
≤ 1e-12 relative (``tests/test_chunked.py``).

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

Cost: O(N) time per τ (about five reads of the record: statistic and noise
identification); memory O(L) per pass, plus N/L checkpoints for TOTDEV of
frequency data.

Modules, each importing only those listed after it: :mod:`.compute`
(:func:`compute` by name), :mod:`.sources` (:class:`ChunkedSeries`, the
``from_*`` sources, the validating and scaling pass, and the
:class:`~sigmatau.core.driver.StreamedSeries` protocol that runs a statistic),
:mod:`.noiseid` (streamed noise identification), :mod:`.kernels` (the kernel of
every statistic) and :mod:`.streams` (pairwise, running, window and block sums;
the derived series).
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
