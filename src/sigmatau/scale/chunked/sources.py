"""The chunked series: :class:`ChunkedSeries`, its sources, and how the statistics reach it.

Sources: ``.npy``, raw binary and HDF5 files, dask arrays and arrays in memory
(:func:`from_npy` … :func:`open_series`, :func:`as_chunked`); a dask object
given to a statistic becomes a streamed record through :func:`adapt_dask`. The validating
pass and the scaling as read (:func:`_scan`, :func:`_scaled`) and the
:class:`~sigmatau.core.driver.StreamedSeries` protocol (:func:`_run`,
:func:`_finish`) live here with the class, since they build and call it and
the steps below (:mod:`.streams`, :mod:`.kernels`, :mod:`.noiseid`) must not
import it back.
"""

from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Callable, Optional, Union

import numpy as np

from ...core.driver import Statistic, drop_empty_factors
from ...core.result import StabilityResult
from ...core.taus import select_m
from ...core.validate import check_data_type, check_rate, unscale_variance
from ...errors import DataError, ParameterError
from ...stats.engine import id_factors
from ...uncertainty.attach import check_options
from ...uncertainty.confidence import ONE_SIGMA
from .kernels import _gap_variance, _KERNELS, _plain_variance
from .noiseid import _attach
from .streams import _Gaps, _pairwise_sum


#: Samples per chunk by default (512 KiB of float64: the ~30 arrays of a pass stay near the
#: cache; reads of this size cost little more per sample than larger ones).
DEFAULT_CHUNK = 1 << 16

#: Statistics that accept chunked input.
STATISTICS = ("adev", "oadev", "mdev", "tdev", "hdev", "ohdev", "totdev")

PathLike = Union[str, "os.PathLike[str]"]


def _check_chunk(chunk_size: object) -> int:
    """``chunk_size`` as an int; ParameterError unless it is an integer of at least 16."""
    if isinstance(chunk_size, (bool, np.bool_)) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 16:
        raise ParameterError(f"chunk_size={chunk_size!r} must be an integer of at least 16 samples")
    return int(chunk_size)


def _check_kind(dtype: np.dtype, what: str) -> None:
    """DataError unless ``dtype`` is a plain real numeric type (bool, int, unsigned, float)."""
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
        #: Missing (NaN) samples and the first and last present index, from the same pass.
        self._gaps: Optional[_Gaps] = None
        #: Noise-identification values of this record by what they depend on (the lag-1 sums at
        #: each factor, B1, R(n)), shared by every statistic computed on it: OADEV, OHDEV and
        #: TOTDEV of one channel read the same decimated series, each pass a read of the file.
        #: Shared with the scaled view (:func:`_scaled`): the identification is scale free,
        #: bit for bit (a power of two commutes with every rounding).
        self._memo: dict = {}

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
        other._scan, other._peak, other._gaps = self._scan, self._peak, self._gaps
        other._memo = self._memo  # its keys hold the chunk size where the result depends on it
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
    """A reader of samples ``start … stop-1`` of a file of ``dtype`` samples from byte ``offset``."""
    item = dtype.itemsize

    def read(start: int, stop: int) -> np.ndarray:
        # Plain reads, not a memory map: the pages then stay in the OS cache
        # rather than in this process, whose memory follows the chunk size.
        with open(path, "rb") as f:
            f.seek(offset + start * item)
            return np.fromfile(f, dtype=dtype, count=stop - start)

    return read


def _existing(path: PathLike) -> Path:
    """``path`` as a Path; InputNotFoundError when it is not a file."""
    p = Path(os.fspath(path))
    if not p.is_file():
        from ...io import InputNotFoundError

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
    from ...io import require_optional

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


class _DaskRecord:
    """A dask object given to a statistic: opened as a ChunkedSeries only once the statistic has
    accepted chunked data, so a statistic without a streamed form refuses it first, whatever its shape."""

    def __init__(self, data: object) -> None:
        self.data = data

    def __sigmatau_statistic__(self, stat: Statistic, **options: object) -> StabilityResult:
        return _run(stat, self.data, **options)  # type: ignore[arg-type]

    def __sigmatau_finish__(self, result: StabilityResult, data_type: str, **options: object) -> StabilityResult:
        return _finish(result, self.data, data_type, **options)  # type: ignore[arg-type]


def adapt_dask(data: object) -> _DaskRecord:
    """A dask object as a streamed record: what ``sigmatau/__init__`` registers for dask objects with
    :func:`~sigmatau.core.driver.register_streamed` (this module loads when the first one arrives);
    a dask collection that is not an array gets the one-line error of :func:`as_chunked` when opened."""
    return _DaskRecord(data)


# ------------------------------------------------------- validation and scaling


class _Validation:
    """The validating pass's view of each chunk: infinite values, NaN (gaps), the peak.

    :meth:`visit` returns the chunk with NaN taken as 0, so the pass's pairwise sum is
    ``np.nansum`` (and the plain sum, bit for bit, when nothing is missing).
    """

    def __init__(self) -> None:
        self.peak = 0.0
        self.missing = 0
        self.infinite = 0
        self.first_inf: Optional[tuple[int, float]] = None
        self.first: Optional[int] = None
        self.last = -1

    def visit(self, start: int, v: np.ndarray) -> np.ndarray:
        finite = np.isfinite(v)
        if finite.all():
            if v.size:
                # The peak costs one more reduction of a chunk already in memory: no extra read.
                self.peak = max(self.peak, float(np.max(np.abs(v))))
                self._present(start, start + v.size - 1)
            return v
        nan = np.isnan(v)
        inf = ~finite & ~nan
        if inf.any() and self.first_inf is None:
            i = int(np.flatnonzero(inf)[0])
            self.first_inf = (start + i, float(v[i]))
        self.infinite += int(np.count_nonzero(inf))
        self.missing += int(np.count_nonzero(nan))
        present = np.flatnonzero(~nan)
        if present.size:
            self._present(start + int(present[0]), start + int(present[-1]))
            if finite.any():
                self.peak = max(self.peak, float(np.max(np.abs(v[finite]))))
        return np.where(nan, 0.0, v)

    def _present(self, first: int, last: int) -> None:
        if self.first is None:
            self.first = first
        self.last = last

    def gaps(self, name: str, n: int) -> Optional[_Gaps]:
        """The missing samples found (None when none is), after the in-memory path's errors
        (:func:`sigmatau.core.validate.as_series` with gaps): an infinite value, nothing present."""
        if self.first_inf is not None:
            i, value = self.first_inf
            raise DataError(f"{name} holds {self.infinite} infinite value(s) (first at index {i}: {value});"
                            " a missing sample is NaN, an infinite one is an error in the data")
        if self.first is None:
            raise DataError(f"{name}: every one of its {n} samples is missing (NaN)")
        return _Gaps(self.missing, self.first, self.last) if self.missing else None


def _scan(src: ChunkedSeries) -> float:
    """Validate every sample (finite or NaN, a gap) and return their sum (NaN as 0) in numpy's pairwise order."""
    if src._scan is not None:
        return src._scan
    if src.n == 0:
        raise DataError(f"{src.name} is empty")
    seen = _Validation()

    def read(a: int, b: int) -> np.ndarray:
        return seen.visit(a, src.read(a, b))

    total = _pairwise_sum(read, 0, src.n, src.chunk_size)
    src._gaps = seen.gaps(src.name, src.n)
    src._scan, src._peak = total, seen.peak
    return total


def _scaled(src: ChunkedSeries) -> tuple[ChunkedSeries, int]:
    """``(src·2**-k, k)``: the series scaled as it is read, largest magnitude in [0.5, 1).

    The streamed counterpart of :func:`sigmatau.core.validate.scale_to_unit`: k comes from the
    peak found by the validating pass (:func:`_scan`) and each chunk is multiplied by
    2**-k (``numpy.ldexp``, exact) when read, so no square of data near 1e±170 overflows
    or underflows; a variance from the scaled series is the user's × 4**-k
    (:func:`sigmatau.core.validate.unscale_variance` undoes it). Memory stays O(chunk).
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
    if not math.isfinite(scaled_total):
        def filled(a: int, b: int) -> np.ndarray:  # NaN (gaps) as 0, as in the validating pass
            v = out.read(a, b)
            return np.where(np.isnan(v), 0.0, v) if src._gaps is not None else v

        scaled_total = _pairwise_sum(filled, 0, out.n, out.chunk_size)
    out._scan = scaled_total
    out._peak = math.ldexp(peak, -k)
    out._gaps = src._gaps
    out._memo = src._memo
    return out, k


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
    gaps = src._gaps
    if gaps is None:
        var, n = _plain_variance(stat.name, src, dtype, ms, tau0, total, src.chunk_size)
    else:
        var, n, n_eff = _gap_variance(stat, src, dtype, ms, rate_f, total, gaps)
        explicit = m is not None or not isinstance(taus, str)
        ms, var, n, n_eff = drop_empty_factors(stat.name, ms, var, n, n_eff, explicit=explicit)
    var = unscale_variance(np.where(var < 0.0, 0.0, np.asarray(var, dtype=float)), k, stat.name)
    result = StabilityResult(
        statistic=stat.name, taus=stat.tau_factor * ms * tau0, m=ms, var=var, dev=np.sqrt(var),
        n=np.asarray(n, dtype=np.int64), rate=rate_f, data_type=dtype, n_points=int(n_points),
    )
    if gaps is not None:
        result = replace(result, n_missing=gaps.missing, n_effective=n_eff)
    if raw:
        return result
    return _attach(result, src, dtype, alpha=alpha_i, confidence=conf, ci=ci_m, id_factors=id_factors(stat, ms),
                   gaps=gaps is not None)


def _finish(result: StabilityResult, data: object, data_type: str, *, alpha: object = None,
            confidence: object = ONE_SIGMA, ci: object = "chi2",
            identified: Optional[tuple[np.ndarray, np.ndarray]] = None) -> StabilityResult:
    """:func:`sigmatau.stats.engine.finish` for chunked data."""
    alpha_i, conf, ci_m = check_options(alpha, confidence, ci)
    # Noise identification is scale free: on the scaled series, as in _run().
    src, _ = _scaled(as_chunked(data))
    return _attach(result, src, data_type, alpha=alpha_i, confidence=conf, ci=ci_m, identified=identified,
                   gaps=src._gaps is not None)
