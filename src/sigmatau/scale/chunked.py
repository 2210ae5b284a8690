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
:class:`~sigmatau.result.StabilityResult` of the in-memory function: same τ
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
"""

from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Callable, Iterator, Optional, Sequence, Union

import numpy as np

from ..core.driver import Statistic, register_streamed
from ..stats.engine import id_factors
from ..core.validate import check_data_type, check_rate, unscale_variance
from ..uncertainty.attach import attach, check_options
from ..uncertainty.confidence import EDF_STATISTICS, ONE_SIGMA
from ..errors import DataError, ParameterError
from ..core.result import StabilityResult
from ..core.taus import long_factors_expected, select_m

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

#: Samples per chunk by default (512 KiB of float64: the ~30 arrays of a pass stay near the
#: cache; reads of this size cost little more per sample than larger ones).
DEFAULT_CHUNK = 1 << 16

#: Statistics that accept chunked input.
STATISTICS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev")

PathLike = Union[str, "os.PathLike[str]"]


def _check_chunk(chunk_size: object) -> int:
    if isinstance(chunk_size, (bool, np.bool_)) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 16:
        raise ParameterError(f"chunk_size={chunk_size!r} must be an integer of at least 16 samples")
    return int(chunk_size)


def _check_kind(dtype: np.dtype, what: str) -> None:
    if dtype.fields is not None or dtype.kind not in "biuf":
        raise DataError(f"{what} must hold real numbers, got dtype {dtype}")


# --------------------------------------------------------------------------- sources


class ChunkedSeries:
    """A 1-D series of ``n`` samples read in pieces of ``chunk_size``.

    Built by :func:`from_npy`, :func:`from_binary`, :func:`from_hdf5`,
    :func:`from_dask` or :func:`from_array`; pass it wherever a statistic
    takes ``data``. Only :meth:`read` touches the data, and never writes.

    Attributes
    ----------
    n : int
        Number of samples.
    chunk_size : int
        Samples per read; memory per pass is a small multiple of it.
    name : str
        Shown in error messages (the file name, for files).
    """

    def __init__(
        self,
        read: Callable[[int, int], np.ndarray],
        n: int,
        *,
        chunk_size: int = DEFAULT_CHUNK,
        name: str = "data",
        read_strided: Optional[Callable[[int, int, int], np.ndarray]] = None,
        close: Optional[Callable[[], None]] = None,
    ) -> None:
        self._read = read
        self._read_strided = read_strided
        self._close = close
        self.n = int(n)
        self.chunk_size = _check_chunk(chunk_size)
        self.name = name
        self._scan: Optional[float] = None
        #: Largest |sample|, found by the validating pass (:func:`_scan`).
        self._peak: Optional[float] = None

    def __len__(self) -> int:
        return self.n

    def __repr__(self) -> str:
        return f"ChunkedSeries({self.name!r}, n={self.n}, chunk_size={self.chunk_size})"

    def __enter__(self) -> "ChunkedSeries":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Release the underlying file handle, if any."""
        if self._close is not None:
            self._close()

    def with_chunk_size(self, chunk_size: int) -> "ChunkedSeries":
        """The same series read in pieces of ``chunk_size`` samples."""
        other = ChunkedSeries(self._read, self.n, chunk_size=chunk_size, name=self.name,
                              read_strided=self._read_strided, close=self._close)
        other._scan, other._peak = self._scan, self._peak
        return other

    # The StreamedSeries protocol (sigmatau.core.driver): how the statistics reach this record.
    def __sigmatau_statistic__(self, stat: Statistic, **options: object) -> StabilityResult:
        """Compute ``stat`` piecewise (:func:`sigmatau.stats.engine.run` with this record)."""
        return _run(stat, self, **options)  # type: ignore[arg-type]

    def __sigmatau_finish__(self, result: StabilityResult, data_type: str, **options: object) -> StabilityResult:
        """Attach noise type, EDF and interval, identified piecewise."""
        return _finish(result, self, data_type, **options)  # type: ignore[arg-type]

    def read(self, start: int, stop: int) -> np.ndarray:
        """Samples ``start … stop-1`` as a new float64 array."""
        if not 0 <= start <= stop <= self.n:
            raise ParameterError(f"read({start}, {stop}) outside 0 … {self.n}")
        out = np.array(self._read(start, stop), dtype=np.float64).reshape(-1)
        if out.size != stop - start:
            raise DataError(f"{self.name}: expected {stop - start} samples at {start}, read {out.size} (truncated?)")
        return out

    def read_strided(self, start: int, stop: int, step: int) -> np.ndarray:
        """Samples ``start, start+step, … < stop`` as a new float64 array."""
        count = len(range(start, stop, step))
        if count == 0:
            return np.empty(0)
        if step == 1:
            return self.read(start, start + count)
        if self._read_strided is not None:
            out = np.array(self._read_strided(start, start + (count - 1) * step + 1, step), dtype=np.float64)
            return out.reshape(-1)
        out = np.empty(count)
        if step <= self.chunk_size:
            per = max(1, self.chunk_size // step)
            for k0 in range(0, count, per):
                k = min(per, count - k0)
                a = start + k0 * step
                out[k0 : k0 + k] = self.read(a, a + (k - 1) * step + 1)[::step]
        else:
            for k in range(count):
                i = start + k * step
                out[k] = self.read(i, i + 1)[0]
        return out


def _file_reader(path: Path, dtype: np.dtype, offset: int) -> Callable[[int, int], np.ndarray]:
    item = dtype.itemsize

    def read(start: int, stop: int) -> np.ndarray:
        # Plain reads, not a memory map: the pages then stay in the OS cache
        # rather than in this process, whose memory follows the chunk size.
        with open(path, "rb") as f:
            f.seek(offset + start * item)
            return np.fromfile(f, dtype=dtype, count=stop - start)

    return read


def _existing(path: PathLike) -> Path:
    p = Path(os.fspath(path))
    if not p.is_file():
        from ..io import InputNotFoundError

        raise InputNotFoundError(f"{p}: no such file")
    return p


def from_npy(path: PathLike, *, mmap: bool = False, chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """A 1-D ``.npy`` file (or an (n, 1)/(1, n) one) read in chunks.

    Parameters
    ----------
    path : str or path-like
        The file; never unpickled, never written.
    mmap : bool
        Read through a read-only memory map instead of plain file reads (the
        mapped pages then count in this process's resident memory).
    chunk_size : int
        Samples per read.

    Raises
    ------
    DataError
        A missing file (``InputNotFoundError``), an invalid or pickled file,
        a non-numeric dtype or a shape other than a vector.
    """
    p = _existing(path)
    try:
        arr = np.load(p, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise DataError(f"{p}: not a readable .npy file ({' '.join(str(exc).split())})") from None
    if not isinstance(arr, np.memmap):
        raise DataError(f"{p}: not a readable .npy file")
    _check_kind(arr.dtype, str(p))
    if arr.ndim != 1 and not (arr.ndim == 2 and 1 in arr.shape):
        raise DataError(f"{p}: must hold a 1-D array, got shape {arr.shape}")
    n = int(arr.size)
    if mmap:
        flat = arr.reshape(-1)
        return ChunkedSeries(lambda a, b: flat[a:b], n, chunk_size=chunk_size, name=p.name,
                             read_strided=lambda a, b, s: flat[a:b:s])
    dtype, offset = arr.dtype, int(arr.offset)
    del arr
    return ChunkedSeries(_file_reader(p, dtype, offset), n, chunk_size=chunk_size, name=p.name)


def from_binary(path: PathLike, dtype: object, *, offset: int = 0, count: Optional[int] = None,
                chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """A raw binary file of ``dtype`` samples (e.g. ``"<f8"``, ``"<i4"``) read in chunks.

    ``offset`` bytes are skipped; ``count`` samples are read (default: all
    that follow the offset, which must then be a whole number of samples).
    """
    p = _existing(path)
    try:
        dt = np.dtype(dtype)  # type: ignore[call-overload]
    except TypeError:
        raise ParameterError(f"dtype={dtype!r} is not a numpy dtype") from None
    if dt.fields is not None or dt.kind not in "biuf":
        raise ParameterError(f"dtype={dtype!r} must be a real numeric type (e.g. '<f8', '<f4', '<i4')")
    if isinstance(offset, bool) or not isinstance(offset, (int, np.integer)) or offset < 0:
        raise ParameterError(f"offset={offset!r} must be a non-negative number of bytes")
    size = p.stat().st_size
    avail = max(size - int(offset), 0) // dt.itemsize
    if count is None:
        if (size - offset) % dt.itemsize:
            raise DataError(f"{p}: {size - offset} bytes after offset {offset} are not a whole number of"
                            f" {dt} samples ({dt.itemsize} bytes each); give count=")
        n = avail
    else:
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
            raise ParameterError(f"count={count!r} must be a non-negative number of samples")
        if count > avail:
            raise DataError(f"{p}: count={count} samples requested, the file holds {avail} after offset {offset}")
        n = int(count)
    return ChunkedSeries(_file_reader(p, dt, int(offset)), n, chunk_size=chunk_size, name=p.name)


def from_hdf5(path: PathLike, dataset: str, *, chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """A 1-D HDF5 dataset read in chunks (needs ``h5py``: extra ``hdf5``).

    The file stays open (read-only) until :meth:`ChunkedSeries.close` or the
    end of a ``with`` block.
    """
    p = _existing(path)
    from ..io import require_optional

    h5py = require_optional("h5py", extra="hdf5", package="h5py", what="HDF5 files")
    try:
        f = h5py.File(p, "r")
    except OSError as exc:
        raise DataError(f"{p}: not a readable HDF5 file ({' '.join(str(exc).split())})") from None
    ds = f.get(dataset)
    if not isinstance(ds, h5py.Dataset):
        names: list[str] = []
        f.visititems(lambda k, v: names.append(k) if isinstance(v, h5py.Dataset) else None)
        f.close()
        raise ParameterError(f"{p}: no dataset {dataset!r}; datasets: {', '.join(names) or 'none'}")
    try:
        _check_kind(ds.dtype, f"{p}:{dataset}")
        if ds.ndim != 1 and not (ds.ndim == 2 and 1 in ds.shape):
            raise DataError(f"{p}:{dataset}: must be 1-D, got shape {ds.shape}")
    except DataError:
        f.close()
        raise
    if ds.ndim == 1:
        read, strided = (lambda a, b: ds[a:b]), (lambda a, b, s: ds[a:b:s])
    elif ds.shape[1] == 1:
        read, strided = (lambda a, b: ds[a:b, 0]), (lambda a, b, s: ds[a:b:s, 0])
    else:
        read, strided = (lambda a, b: ds[0, a:b]), (lambda a, b, s: ds[0, a:b:s])
    return ChunkedSeries(read, int(ds.size), chunk_size=chunk_size, name=f"{p.name}:{dataset}",
                         read_strided=strided, close=f.close)


def from_dask(array: object, *, chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """A 1-D dask array; each read computes one slice (the active scheduler is used)."""
    shape = getattr(array, "shape", None)
    if not hasattr(array, "compute") or shape is None:
        raise DataError(f"expected a dask array, got {type(array).__name__}")
    _check_kind(np.dtype(array.dtype), "the dask array")  # type: ignore[attr-defined]
    if any(isinstance(s, float) and math.isnan(s) for s in shape):
        raise DataError(f"the dask array has unknown chunk sizes (shape {shape}); call compute_chunk_sizes() first")
    if len(shape) == 2 and 1 in shape:
        array = array.reshape(-1)  # type: ignore[attr-defined]
    elif len(shape) != 1:
        raise DataError(f"the dask array must be 1-D, got shape {shape}")
    arr = array
    return ChunkedSeries(lambda a, b: np.asarray(arr[a:b].compute()), int(arr.shape[0]),  # type: ignore[index]
                         chunk_size=chunk_size, name="dask array",
                         read_strided=lambda a, b, s: np.asarray(arr[a:b:s].compute()))  # type: ignore[index]


def from_array(data: object, *, chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """An array in memory read in chunks (for tests and comparisons)."""
    arr = np.asarray(data)
    _check_kind(arr.dtype, "data")
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.reshape(-1)
    if arr.ndim != 1:
        raise DataError(f"data must be 1-D, got shape {arr.shape}")
    return ChunkedSeries(lambda a, b: arr[a:b], arr.size, chunk_size=chunk_size, name="data",
                         read_strided=lambda a, b, s: arr[a:b:s])


_HDF5_SUFFIXES = (".h5", ".hdf5", ".he5", ".hdf")


def open_series(path: PathLike, *, dtype: object = None, offset: int = 0, count: Optional[int] = None,
                dataset: Optional[str] = None, mmap: bool = False,
                chunk_size: int = DEFAULT_CHUNK) -> ChunkedSeries:
    """Open a file by its suffix: ``.npy``, HDF5 (``dataset=`` required) or raw binary (``dtype=`` required)."""
    suffix = Path(os.fspath(path)).suffix.lower()
    if suffix == ".npy":
        return from_npy(path, mmap=mmap, chunk_size=chunk_size)
    if suffix in _HDF5_SUFFIXES or dataset is not None:
        if dataset is None:
            raise ParameterError(f"{Path(os.fspath(path)).name}: give the dataset (dataset=, --dataset) to read an HDF5 file in chunks")
        return from_hdf5(path, dataset, chunk_size=chunk_size)
    if dtype is None:
        raise ParameterError(f"{Path(os.fspath(path)).name}: give the sample type (dtype=, --dtype; e.g. '<f8') to read a raw binary file")
    return from_binary(path, dtype, offset=offset, count=count, chunk_size=chunk_size)


def as_chunked(data: object, *, chunk_size: Optional[int] = None, **open_options: object) -> ChunkedSeries:
    """``data`` as a :class:`ChunkedSeries`: one already, a dask array, a path or an array."""
    if isinstance(data, ChunkedSeries):
        return data if chunk_size is None or chunk_size == data.chunk_size else data.with_chunk_size(chunk_size)
    size = DEFAULT_CHUNK if chunk_size is None else chunk_size
    if isinstance(data, (str, os.PathLike)):
        return open_series(data, chunk_size=size, **open_options)  # type: ignore[arg-type]
    if type(data).__module__.startswith("dask."):
        if hasattr(data, "to_dask_array") and not hasattr(data, "rechunk"):
            raise DataError("give a dask array (e.g. series.to_dask_array(lengths=True)), not a dask collection")
        return from_dask(data, chunk_size=size)
    return from_array(data, chunk_size=size)


def _adapt_dask(data: object) -> Optional[ChunkedSeries]:
    """A dask array as a ChunkedSeries (registered with :func:`~sigmatau.core.driver.register_streamed`).

    Recognised by its type's module so that dask is never imported for this test;
    a dask collection that is not an array gets the one-line error of :func:`as_chunked`.
    """
    if type(data).__module__.startswith("dask."):
        return as_chunked(data)
    return None


register_streamed(_adapt_dask)


# ------------------------------------------------------------- validation and sums


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


def _scan(src: ChunkedSeries) -> float:
    """Validate every sample (finite) and return their sum in numpy's pairwise order."""
    if src._scan is not None:
        return src._scan
    if src.n == 0:
        raise DataError(f"{src.name} is empty")
    bad: list[tuple[int, float]] = []
    count = [0]
    peak = [0.0]

    def visit(start: int, v: np.ndarray) -> None:
        finite = np.isfinite(v)
        if v.size and finite.all():
            # The peak costs one more reduction of a chunk already in memory: no extra read.
            peak[0] = max(peak[0], float(np.max(np.abs(v))))
        if not finite.all():
            idx = np.flatnonzero(~finite)
            count[0] += idx.size
            if not bad:
                bad.append((start + int(idx[0]), float(v[idx[0]])))

    total = _pairwise_sum(src.read, 0, src.n, src.chunk_size, visit)
    if bad:
        i, value = bad[0]
        raise DataError(
            f"{src.name} holds {count[0]} non-finite value(s) (first at index {i}: {value}); remove or fill them first"
        )
    src._scan, src._peak = total, peak[0]
    return total


def _scaled(src: ChunkedSeries) -> tuple[ChunkedSeries, int]:
    """``(src·2**-k, k)``: the series scaled as it is read, largest magnitude in [0.5, 1).

    The streamed counterpart of :func:`sigmatau._input.scale_to_unit`: k comes from the
    peak found by the validating pass (:func:`_scan`) and each chunk is multiplied by
    2**-k (``numpy.ldexp``, exact) when read, so no square of data near 1e±170 overflows
    or underflows; a variance from the scaled series is the user's × 4**-k
    (:func:`sigmatau._input.unscale_variance` undoes it). Memory stays O(chunk).
    """
    total = _scan(src)
    peak = src._peak or 0.0
    k = math.frexp(peak)[1] if peak > 0.0 else 0
    if k == 0:
        return src, 0

    def read(a: int, b: int) -> np.ndarray:
        return np.ldexp(src.read(a, b), -k)

    def strided(a: int, b: int, step: int) -> np.ndarray:
        return np.ldexp(src.read_strided(a, b, step), -k)

    out = ChunkedSeries(read, src.n, chunk_size=src.chunk_size, name=src.name, read_strided=strided)
    # A power of two commutes with every rounding of the pairwise sum unless that sum
    # overflowed (data near 1e308): then it is summed again from the scaled chunks.
    scaled_total = math.ldexp(total, -k) if math.isfinite(total) else math.inf
    out._scan = scaled_total if math.isfinite(scaled_total) else _pairwise_sum(out.read, 0, out.n, out.chunk_size)
    out._peak = math.ldexp(peak, -k)
    return out, k


# ------------------------------------------------------------------- derived series
#
# Each reader maps an index range of a derived series (mean removed, line
# removed, integrated, differenced) to values computed exactly as the
# in-memory path computes them element by element.


class _Raw:
    def __init__(self, src: ChunkedSeries) -> None:
        self.src, self.n = src, src.n

    def read(self, a: int, b: int) -> np.ndarray:
        return self.src.read(a, b)

    def take(self, start: int, step: int, count: int) -> np.ndarray:
        return self.src.read_strided(start, start + (count - 1) * step + 1, step)


class _Centred(_Raw):
    """``y - mean(y)``."""

    def __init__(self, src: ChunkedSeries, mean: np.float64) -> None:
        super().__init__(src)
        self.mean = mean

    def read(self, a: int, b: int) -> np.ndarray:
        return self.src.read(a, b) - self.mean


class _Detrended(_Raw):
    """``(x - x_0) - linspace(0, x_{N-1} - x_0, N)``, as ``remove_linear_phase``."""

    def __init__(self, src: ChunkedSeries) -> None:
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


# --------------------------------------------------------------------------- kernels
#
# kernel(reader, ms, tau0, L) -> (var, n); the reader holds the phase (trend
# removed) or the centred frequency, as the in-memory kernels receive them.
# Element-wise differences are formed in the in-memory order, (a - 2b) + c,
# which matters only for phase data whose values dwarf their differences.


def _d1(W: list[np.ndarray], k: int) -> np.ndarray:
    return W[k + 1] - W[k]


def _d2(W: list[np.ndarray], k: int) -> np.ndarray:
    return (W[k + 2] - 2.0 * W[k + 1]) + W[k]


def _avar_phase(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        count = (rd.n - 1) // m + 1
        acc = _SumSq()
        for xs in _with_history(_strided(rd, m, count, L), 2):
            if xs.size >= 3:
                acc.add((xs[2:] - 2.0 * xs[1:-1]) + xs[:-2])
        k = count - 2
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * k), k
    return var, n


def _hvar_phase(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        count = (rd.n - 1) // m + 1
        acc = _SumSq()
        for xs in _with_history(_strided(rd, m, count, L), 3):
            if xs.size >= 4:
                acc.add(((xs[3:] - 3.0 * xs[2:-1]) + 3.0 * xs[1:-2]) - xs[:-3])
        k = count - 3
        var[i], n[i] = acc.total / (6.0 * (m * tau0) ** 2 * k), k
    return var, n


def _avar_freq(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for b in _with_history(_block_sums(rd, m, rd.n // m, L), 1):
            if b.size >= 2:
                acc.add(b[1:] - b[:-1])
        k = rd.n // m - 1
        var[i], n[i] = acc.total / (2.0 * float(m) ** 2 * k), k
    return var, n


def _hvar_freq(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for b in _with_history(_block_sums(rd, m, rd.n // m, L), 2):
            if b.size >= 3:
                acc.add((b[2:] - 2.0 * b[1:-1]) + b[:-2])
        k = rd.n // m - 2
        var[i], n[i] = acc.total / (6.0 * float(m) ** 2 * k), k
    return var, n


def _oavar_phase(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 2 * m
        acc = _SumSq()
        for p, l in _blocks(k, L):
            acc.add(_d2(_windows(rd.read, rd.n, p, (0, m, 2 * m), l), 0))
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * k), k
    return var, n


def _ohvar_phase(rd, ms, tau0, L):
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m
        acc = _SumSq()
        for p, l in _blocks(k, L):
            w = _windows(rd.read, rd.n, p, (0, m, 2 * m, 3 * m), l)
            acc.add(((w[3] - 3.0 * w[2]) + 3.0 * w[1]) - w[0])
        var[i], n[i] = acc.total / (6.0 * (m * tau0) ** 2 * k), k
    return var, n


def _oavar_freq(rd, ms, tau0, L):
    # s_j = Σ_{i<m} (y_{j+i+m} - y_{j+i}) = Δ²_m x_j / τ0, j = 0 … M-2m
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 2 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d1, 1):
            acc.add(s)
        var[i], n[i] = acc.total / (2.0 * float(m) ** 2 * k), k
    return var, n


def _ohvar_freq(rd, ms, tau0, L):
    # s_j = Σ_{i<m} (y_{j+i+2m} - 2y_{j+i+m} + y_{j+i}) = Δ³_m x_j / τ0, j = 0 … M-3m
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d2, 2):
            acc.add(s)
        var[i], n[i] = acc.total / (6.0 * float(m) ** 2 * k), k
    return var, n


def _mvar_phase(rd, ms, tau0, L):
    # s_j = Σ_{i<m} Δ²_m x_{j+i}, j = 0 … N-3m
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 1
        acc = _SumSq()
        for s in _window_sums(rd, m, 0, k, L, _d2, 2):
            acc.add(s)
        var[i], n[i] = acc.total / (2.0 * m**2 * (m * tau0) ** 2 * k), k
    return var, n


def _mvar_freq(rd, ms, tau0, L):
    # t_j = Σ_{i<m} s_{j+i}, s the OAVAR window sums of the frequency
    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        k = rd.n - 3 * m + 2
        acc = _SumSq()
        if m == 1:
            for t in _window_sums(rd, 1, 0, k, L, _d1, 1):
                acc.add(t)
        else:
            # s_j = P_{j+m} - P_j (P: running sum of v_i = y_{i+m} - y_i), t_j = Q_{j+m} - Q_j
            # (Q: running sum of s); P is needed at j, j+m, j+2m and Q at j, j+m.
            read, size = rd.read, rd.n
            p_chains = [_Prefix(), _Prefix(), _Prefix()]
            for lag in (1, 2):
                for p, l in _blocks(lag * m, L):
                    p_chains[lag].step(_d1(_windows(read, size, p, (0, m), l), 0))
            first, second = _Prefix(), _Prefix()
            second.hi, second.lo = p_chains[1].hi, p_chains[1].lo
            q_ahead, q_behind = _Prefix(), _Prefix()
            for p, l in _blocks(m, L):
                w = _windows(read, size, p, (0, m, 2 * m), l)
                c0, e0 = first.step(_d1(w, 0))
                c1, e1 = second.step(_d1(w, 1))
                q_ahead.step(_window_diff(c1, e1, c0, e0))
            for p, l in _blocks(k, L):
                w = _windows(read, size, p, (0, m, 2 * m, 3 * m), l)
                (c0, e0), (c1, e1), (c2, e2) = (ch.step(_d1(w, lag)) for lag, ch in enumerate(p_chains))
                s0 = _window_diff(c1, e1, c0, e0)
                s1 = _window_diff(c2, e2, c1, e1)
                c0, e0 = q_behind.step(s0)
                c1, e1 = q_ahead.step(s1)
                acc.add(_window_diff(c1, e1, c0, e0))
        var[i], n[i] = acc.total / (2.0 * float(m) ** 4 * k), k
    return var, n


def _tvar(kernel):
    def tvar(rd, ms, tau0, L):
        var, n = kernel(rd, ms, tau0, L)
        return var * (ms * tau0) ** 2 / 3.0, n
    return tvar


def _totvar(rd, ms, tau0, L):
    # Reflected phase x*_{-j} = 2x_0 - x_j, x*_{N-1+j} = 2x_{N-1} - x_{N-1-j};
    # terms i = 1 … N-2: x*_{i-m} - 2x*_i + x*_{i+m}.
    N = rd.n
    two_first = 2.0 * rd.read(0, 1)[0]
    two_last = 2.0 * rd.read(N - 1, N)[0]

    def ext(a: int, b: int) -> np.ndarray:
        parts = []
        if a < 0:
            e = min(b, 0)
            parts.append(two_first - rd.read(1 - e, 1 - a)[::-1])
        if a < N and b > 0:
            parts.append(rd.read(max(a, 0), min(b, N)))
        if b > N:
            s = max(a, N)
            parts.append(two_last - rd.read(2 * N - 1 - b, 2 * N - 1 - s)[::-1])
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    var, n = np.empty(ms.size), np.empty(ms.size, dtype=np.int64)
    for i, m in enumerate(ms):
        m = int(m)
        acc = _SumSq()
        for p, l in _blocks(N - 2, L):
            w = _windows(ext, 2 * N, 1 + p - m, (0, m, 2 * m), l)
            acc.add((w[0] - 2.0 * w[1]) + w[2])
        var[i], n[i] = acc.total / (2.0 * (m * tau0) ** 2 * (N - 2)), N - 2
    return var, n


# name -> (phase kernel, frequency kernel or None: then the frequency is integrated)
_KERNELS = {
    "adev": (_avar_phase, _avar_freq),
    "oadev": (_oavar_phase, _oavar_freq),
    "mdev": (_mvar_phase, _mvar_freq),
    "tdev": (_tvar(_mvar_phase), _tvar(_mvar_freq)),
    "hdev": (_hvar_phase, _hvar_freq),
    "ohdev": (_ohvar_phase, _ohvar_freq),
    "totdev": (_totvar, None),
}


# -------------------------------------------------------------- noise identification


def _lag1_streamed(batches: Callable[[], Iterator[np.ndarray]], n: int, dmax: int) -> tuple[list[float], list[float]]:
    """Lag-1 sums of the d-th differences of a streamed series, d = 0 … dmax.

    Returns ``(den_d, num_d)`` with ``den = Σ (z - z̄)²`` and
    ``num = Σ (z_k - z̄)(z_{k+1} - z̄)`` (z̄ the mean of that difference series),
    from two passes: means first, then the centred sums.
    """
    def new_values(ext: np.ndarray, had: int, d: int) -> np.ndarray:
        diff = np.diff(ext, d) if d else ext
        return diff[max(0, had - d) :]

    sums: list[list[float]] = [[] for _ in range(dmax + 1)]
    had = 0
    for ext in _with_history(batches(), dmax):
        for d in range(dmax + 1):
            sums[d].append(float(np.add.reduce(new_values(ext, had, d))))
        had = min(dmax, ext.size)
    means = [math.fsum(sums[d]) / (n - d) for d in range(dmax + 1)]
    den: list[list[float]] = [[] for _ in range(dmax + 1)]
    num: list[list[float]] = [[] for _ in range(dmax + 1)]
    last: list[Optional[float]] = [None] * (dmax + 1)
    had = 0
    for ext in _with_history(batches(), dmax):
        for d in range(dmax + 1):
            zc = new_values(ext, had, d) - means[d]
            if zc.size == 0:
                continue
            den[d].append(float(np.einsum("i,i->", zc, zc)))
            num[d].append(float(np.einsum("i,i->", zc[:-1], zc[1:])))
            if last[d] is not None:
                num[d].append(last[d] * float(zc[0]))
            last[d] = float(zc[-1])
        had = min(dmax, ext.size)
    return [math.fsum(v) for v in den], [math.fsum(v) for v in num]


def _lag1(raw: _Raw, m: int, dtype: str, dmax: int, L: int):
    """α and α̂ by :func:`sigmatau.noiseid.lag1_acf_noise_id` on the decimated or averaged series."""
    from ..uncertainty import noiseid

    nz = len(range(0, raw.n, m)) if dtype == "phase" else raw.n // m

    def batches() -> Iterator[np.ndarray]:
        return _strided(raw, m, nz, L) if dtype == "phase" else _block_means(raw, m, nz, L)

    if nz < noiseid.LAG1_MIN_POINTS:
        raise noiseid.InsufficientDataError(f"lag-1 noise identification needs at least 30 points at m={m}, got {nz}")
    if nz <= L:  # small enough: the in-memory routine itself
        z = np.concatenate(list(batches()))
        r = noiseid.lag1_acf_noise_id(z, 1, data_type=dtype, dmax=dmax)
        return r.alpha, r.alpha_estimate
    den, num = _lag1_streamed(batches, nz, dmax)
    theta = 1 if dtype == "phase" else 0
    d = 0
    while True:
        if den[d] == 0.0:
            raise DataError("the series is constant at this averaging factor; its autocorrelation is undefined")
        r1 = num[d] / den[d]
        if r1 <= -1.0:
            raise DataError(f"lag-1 autocorrelation r1={r1!r} at m={m}, d={d}: the series alternates exactly")
        delta = r1 / (1.0 + r1)
        if delta < 0.25 or d >= dmax:
            break
        d += 1
    return -int(np.rint(2.0 * delta)) - 2 * d + 2 * theta, -2.0 * (delta + d) + 2 * theta


def _b1(freq: object, m: int, hadamard: bool, L: int, n_expected: Optional[int] = None):
    """:func:`sigmatau.noiseid.b1_noise_id` from streamed block means of the frequency series."""
    from ..uncertainty.noiseid import InsufficientDataError, b1_classify, b1_observed

    def obs(series: object) -> tuple[float, int]:
        count = series.n // m  # type: ignore[attr-defined]
        means = np.concatenate([np.empty(0)] + list(_block_means(series, m, count, L)))
        if means.size < 2:
            raise InsufficientDataError(f"the B1 ratio needs at least 2 averages at m={m}, got {means.size}")
        return b1_observed(means, 1)

    ratio, nb = obs(freq)
    if nb < 3:
        raise InsufficientDataError(f"B1 noise identification needs at least 3 averages at m={m}, got {nb}")
    mu, mu_hat = b1_classify(ratio, nb, n_expected)
    if hadamard and mu >= 1:
        try:
            ratio2, nb2 = obs(_Diff(freq))
        except DataError:
            nb2 = 0
        if nb2 >= 3:
            mu2, mu2_hat = b1_classify(ratio2, nb2, n_expected)
            mu = min(max(mu2 + 2, 1), 3)
            mu_hat = min(max(mu2_hat + 2.0, 1.0), 3.0)
    alpha = 1 if mu == -2 else -mu - 1
    return alpha, -mu_hat - 1.0, mu == -2


def _rn(src: ChunkedSeries, m: int, dtype: str) -> float:
    from ..stats.allan import MVAR, OAVAR
    from ..uncertainty.noiseid import InsufficientDataError

    npts = src.n if dtype == "phase" else src.n + 1
    if npts < 3 * m:
        raise InsufficientDataError(f"R(n) needs at least {3 * m} phase points at m={m}, got {npts}")
    with long_factors_expected():  # long-τ factors are the point here
        mv = _run(MVAR, src, rate=1.0, data_type=dtype, taus="octave", m=[m], ci=None).var[0]
        av = _run(OAVAR, src, rate=1.0, data_type=dtype, taus="octave", m=[m], ci=None).var[0]
    if av == 0.0:
        raise DataError(f"the Allan variance is zero at m={m}; R(n) is undefined")
    return float(mv / av)


def _identify(src: ChunkedSeries, ms: np.ndarray, dtype: str, family: str,
              n_terms: Optional[np.ndarray] = None) -> tuple[np.ndarray, np.ndarray]:
    """``(alpha, alpha_estimate)`` per factor, following :func:`sigmatau.noiseid.identify`."""
    from ..uncertainty import noiseid

    fam = noiseid.FAMILY_ALIASES[family]
    dmax, lo, hi = noiseid.FAMILY_RULES[fam]
    raw = _Raw(src)
    freq = _Diff(raw) if dtype == "phase" else raw
    L = src.chunk_size
    m_list = [int(v) for v in ms]
    alpha = np.zeros(len(m_list), dtype=np.int64)
    est = np.full(len(m_list), np.nan)
    method: list[str] = []
    n_freq = src.n - 1 if dtype == "phase" else src.n
    min_averages = noiseid.b1_min_averages(family)
    for i, m in enumerate(m_list):
        if src.n // m >= noiseid.LAG1_MIN_POINTS:
            try:
                alpha[i], est[i] = _lag1(raw, m, dtype, dmax, L)
            except noiseid.InsufficientDataError:
                pass
            else:
                method.append("lag1")
                continue
        if n_freq // m < min_averages:
            method.append("carried")
            continue
        try:
            a, e, ambiguous = _b1(freq, m, fam == "hadamard", L,
                                  None if n_terms is None else int(n_terms[i]))
        except DataError:
            method.append("carried")
            continue
        alpha[i], est[i] = a, e
        if ambiguous:
            try:
                rn = _rn(src, m, dtype)
            except DataError:
                pass
            else:
                wpm, fpm = float(noiseid.rn_expected(m, 2)), float(noiseid.rn_expected(m, 1))
                alpha[i] = 2 if rn < math.sqrt(wpm * fpm) else 1
                t = (math.log(rn) - math.log(wpm)) / (math.log(fpm) - math.log(wpm)) if fpm != wpm else 0.0
                est[i] = 2.0 - t
        method.append("done")
    done = [i for i, tag in enumerate(method) if tag != "carried"]
    for i, tag in enumerate(method):
        if tag == "carried":
            if not done:
                raise noiseid.InsufficientDataError(
                    f"no averaging factor in ms leaves enough data ({src.n} points) for any method"
                )
            below = [j for j in done if m_list[j] < m_list[i]]
            if below:
                source = max(below, key=lambda j: m_list[j])
            else:
                source = min(done, key=lambda j: (abs(math.log(m_list[j] / m_list[i])), -m_list[j]))
            alpha[i] = alpha[source]
    return np.clip(alpha, lo, hi).astype(float), est


def _attach(result: StabilityResult, src: ChunkedSeries, data_type: str, *, alpha: Optional[int],
            confidence: float, ci: Optional[str], id_factors: Optional[np.ndarray] = None,
            identified: Optional[tuple[np.ndarray, np.ndarray]] = None) -> StabilityResult:
    """:func:`sigmatau._uncertainty.attach` with the noise identified chunk-wise."""
    if ci is None or len(result) == 0 or alpha is not None or identified is not None:
        # The data are not looked at on these paths.
        return attach(result, np.empty(0), data_type, alpha=alpha, confidence=confidence, ci=ci,
                      id_factors=id_factors, identified=identified)
    factors = result.m if id_factors is None else id_factors
    try:
        same = np.array_equal(factors, result.m)
        ident = _identify(src, factors, data_type, result.statistic, n_terms=result.n if same else None)
    except DataError as exc:
        nan = np.full(len(result), np.nan)
        out = attach(result, np.empty(0), data_type, alpha=None, confidence=confidence, ci=ci, identified=(nan, nan))
        if ci == "chi2" and result.statistic in EDF_STATISTICS:
            reason = f"noise type not identified ({exc}); give alpha= for an interval"
            out = replace(out, ci_reason=(reason,) * len(result))
        return out
    return attach(result, np.empty(0), data_type, alpha=None, confidence=confidence, ci=ci, identified=ident)


# ------------------------------------------------------------------------ entry points


def _run(
    stat: Statistic,
    data: object,
    *,
    rate: object,
    data_type: object,
    taus: object,
    m: object,
    points_per_decade: int = 10,
    alpha: object = None,
    confidence: object = ONE_SIGMA,
    ci: object = "chi2",
    raw: bool = False,
) -> StabilityResult:
    """:func:`sigmatau.stats.engine.run` for chunked data (same contract and result)."""
    if stat.name not in _KERNELS:
        raise ParameterError(
            f"{stat.name} does not accept chunked data (a ChunkedSeries or dask array);"
            f" chunked statistics: {', '.join(STATISTICS)}"
        )
    alpha_i, conf, ci_m = check_options(alpha, confidence, ci)
    rate_f = check_rate(rate)
    dtype = check_data_type(data_type)
    # Kernels and noise identification run on the data scaled by 2**-k as they are read
    # (as the in-memory path does); the variance is unscaled below.
    src, k = _scaled(as_chunked(data))
    total = _scan(src)
    n_points = src.n if dtype == "phase" else src.n + 1
    if n_points < stat.min_points:
        kind = "phase" if dtype == "phase" else "frequency"
        need = stat.min_points if dtype == "phase" else stat.min_points - 1
        raise DataError(f"{stat.name} needs at least {need} {kind} samples, got {src.n}")
    ms = select_m(
        stat.name, n_points=n_points, rate=rate_f, taus=taus, m=m, points_per_decade=points_per_decade,
        m_min=stat.min_m, m_max=stat.max_m(n_points), stop_ratio=stat.stop_ratio, even=stat.even,
        tau_factor=stat.tau_factor,
    )
    tau0 = 1.0 / rate_f
    L = src.chunk_size
    phase_kernel, freq_kernel = _KERNELS[stat.name]
    if ms.size == 0:
        var, n = np.empty(0), np.empty(0, dtype=np.int64)
    elif dtype == "phase":
        var, n = phase_kernel(_Detrended(src), ms, tau0, L)
    else:
        centred = _Centred(src, np.float64(total) / src.n)
        if freq_kernel is not None:
            var, n = freq_kernel(centred, ms, tau0, L)
        else:
            var, n = phase_kernel(_Integrated(centred, tau0, L), ms, tau0, L)
    var = unscale_variance(np.where(var < 0.0, 0.0, np.asarray(var, dtype=float)), k, stat.name)
    result = StabilityResult(
        statistic=stat.name, taus=stat.tau_factor * ms * tau0, m=ms, var=var, dev=np.sqrt(var),
        n=np.asarray(n, dtype=np.int64), rate=rate_f, data_type=dtype, n_points=int(n_points),
    )
    if raw:
        return result
    return _attach(result, src, dtype, alpha=alpha_i, confidence=conf, ci=ci_m, id_factors=id_factors(stat, ms))


def _finish(result: StabilityResult, data: object, data_type: str, *, alpha: object = None,
            confidence: object = ONE_SIGMA, ci: object = "chi2",
            identified: Optional[tuple[np.ndarray, np.ndarray]] = None) -> StabilityResult:
    """:func:`sigmatau.stats.engine.finish` for chunked data."""
    alpha_i, conf, ci_m = check_options(alpha, confidence, ci)
    # Noise identification is scale free: on the scaled series, as in _run().
    src, _ = _scaled(as_chunked(data))
    return _attach(result, src, data_type, alpha=alpha_i, confidence=conf, ci=ci_m, identified=identified)


def compute(
    statistic: str,
    source: object,
    *,
    rate: float = 1.0,
    data_type: str = "freq",
    taus: object = "octave",
    m: object = None,
    points_per_decade: int = 10,
    alpha: Optional[int] = None,
    confidence: float = ONE_SIGMA,
    ci: Optional[str] = "chi2",
    chunk_size: Optional[int] = None,
    dtype: object = None,
    offset: int = 0,
    dataset: Optional[str] = None,
    **options: object,
) -> StabilityResult:
    """Compute ``statistic`` on a record read chunk by chunk.

    Parameters
    ----------
    statistic : str
        One of :data:`STATISTICS`.
    source : ChunkedSeries, dask array, path or array_like
        A path is opened by :func:`open_series` (``.npy``; HDF5 with
        ``dataset``; raw binary with ``dtype`` and ``offset``).
    rate, data_type, taus, m, points_per_decade, alpha, confidence, ci
        As for the statistic's own function.
    chunk_size : int, optional
        Samples per read (default :data:`DEFAULT_CHUNK`, or the series' own).
    dtype, offset, dataset
        How to read a path (see :func:`open_series`).
    **options
        Further keywords of the statistic (``bias`` for ``totdev``).

    Returns
    -------
    StabilityResult
        The result of ``sigmatau.<statistic>(data_in_memory, ...)``, variance
        within 1e-12 relative.

    Examples
    --------
    >>> import numpy as np, sigmatau
    >>> from sigmatau import chunked
    >>> y = np.random.default_rng(0).standard_normal(5000)
    >>> r = chunked.compute("oadev", y, chunk_size=999, m=[1, 10, 100])
    >>> bool(np.allclose(r.dev, sigmatau.oadev(y, m=[1, 10, 100]).dev, rtol=1e-12))
    True
    """
    if statistic not in STATISTICS:
        raise ParameterError(f"statistic={statistic!r} must be one of {STATISTICS}")
    opened = not isinstance(source, ChunkedSeries) and isinstance(source, (str, os.PathLike))
    src = as_chunked(source, chunk_size=chunk_size, dtype=dtype, offset=offset, dataset=dataset)
    from ..stats import allan, hadamard, total

    func = {"adev": allan.adev, "oadev": allan.oadev, "mdev": allan.mdev, "tdev": allan.tdev,
            "hdev": hadamard.hdev, "ohdev": hadamard.ohdev, "totdev": total.totdev}[statistic]
    try:
        return func(src, rate=rate, data_type=data_type, taus=taus, m=m, points_per_decade=points_per_decade,
                    alpha=alpha, confidence=confidence, ci=ci, **options)
    finally:
        if opened:
            src.close()
