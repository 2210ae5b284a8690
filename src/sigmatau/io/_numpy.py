"""NumPy ``.npy`` and ``.npz`` files (never unpickled).

* ``.npy``: samples along the first axis. A 1-D array is one channel
  (``col0``), a 2-D array one channel per column (``col0`` …), a structured array
  one channel per field (named, so the time column is found by name).
* ``.npz``: every 1-D array of the common length is a column named by its key; a
  2-D array ``key`` of that length gives ``key_x/y/z`` (3 columns) or
  ``key_0`` …; a scalar ``rate`` (or ``fs``, ``sample_rate``, ``sampling_rate``)
  gives the rate.
"""

from __future__ import annotations

import math
import zipfile
import zlib
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np

from ..errors import DataError, SigmaTauError
from ._columns import select
from ._errors import FormatError
from ._limits import check_allocation
from ._progress import Progress
from ._registry import Options, Table, file_sha256, register

__all__ = ["read_npy", "read_npz", "split_2d", "NpyHeader", "read_npy_header"]

RATE_KEYS = ("rate", "sample_rate", "sampling_rate", "fs")


def split_2d(key: str, k: int) -> list[str]:
    """Column names for a (n, k) member named ``key``."""
    return [f"{key}_{a}" for a in "xyz"] if k == 3 else [f"{key}_{j}" for j in range(k)]


def _numeric_kind(a: np.ndarray) -> bool:
    return a.dtype.kind in "biuf"


def _table_from_columns(
    cols: dict[str, np.ndarray], *, fmt: str, display: str, opts: Options, detail: str,
    rate: float | None = None, units: dict[str, str] | None = None,
) -> Table:
    names = list(cols)
    numeric = [_numeric_kind(cols[n]) for n in names]
    first_bad = [None if numeric[j] else str(cols[n][:1].tolist()[:1] or "")[:40] for j, n in enumerate(names)]
    sel = select(names, numeric, columns=opts.columns, time_column=opts.time_column, path=display,
                 first_bad=first_bad)
    rows = len(cols[names[sel.channels[0]]])
    check_allocation(display, 8 * rows * (len(sel.channels) + (sel.time is not None)),
                     f"{len(sel.channels)} channel(s) of {rows:,} samples as float64")
    data = {names[j]: np.asarray(cols[names[j]], dtype=np.float64) for j in sel.channels}
    time = None
    if sel.time is not None:
        t = np.asarray(cols[names[sel.time]])
        time = t.astype(np.int64) if t.dtype.kind in "iu" else t.astype(np.float64)
    rows = next(iter(data.values())).size
    if rows == 0:
        raise DataError(f"{display}: no numeric data (0 samples)")
    return Table(
        format=fmt, columns=tuple(names), data=data, rows=rows, sha256="", size=0, time=time,
        time_name=None if sel.time is None else names[sel.time], time_unit=sel.time_unit,
        time_unit_reason=f"from the name {names[sel.time]!r}" if sel.time is not None and sel.time_unit
        else "", rate=rate, units={k: v for k, v in (units or {}).items() if k in data}, detail=detail,
        unused=sel.unused,
    )


@dataclass(frozen=True)
class NpyHeader:
    """What a ``.npy`` header declares, read without loading the array.

    ``nbytes`` = prod(shape) × itemsize: the size the array would have in memory.
    """

    shape: tuple[int, ...]
    dtype: np.dtype
    header_bytes: int

    @property
    def nbytes(self) -> int:
        return math.prod(self.shape) * self.dtype.itemsize


def read_npy_header(fh: BinaryIO) -> NpyHeader:
    """Read the magic string and header of a ``.npy`` stream (NEP 1 format, versions 1–3).

    Raises ValueError (or EOFError) when there is no valid header; nothing is unpickled.
    """
    start = fh.tell()
    version = np.lib.format.read_magic(fh)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
    else:  # 2.0 and 3.0 differ only in the header's text encoding (latin-1 vs utf-8)
        shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
    return NpyHeader(tuple(int(s) for s in shape), np.dtype(dtype), fh.tell() - start)


def _header(fh: BinaryIO, what: str) -> NpyHeader:
    try:
        return read_npy_header(fh)
    except (ValueError, EOFError, OSError, SyntaxError, TypeError):
        raise FormatError(f"{what} (no valid NumPy header)") from None


def _plain_text(exc: BaseException) -> str:
    """NumPy's message on one line, without its allow_pickle advice (never for our users)."""
    text = " ".join(str(exc).split())
    return "damaged data" if "pickle" in text.lower() else text


@register("npy", extensions=(".npy",), description="NumPy .npy array: samples along the first axis")
def read_npy(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    with open(path, "rb") as fh:
        head = _header(fh, f"{display}: not a valid .npy file")
    if head.dtype.hasobject:
        raise FormatError(f"{display}: holds Python objects (dtype {head.dtype}), which are never loaded")
    held = path.stat().st_size - head.header_bytes
    if head.nbytes > held:
        raise FormatError(
            f"{display}: not a valid .npy file (its header declares shape {head.shape} of {head.dtype},"
            f" {head.nbytes:,} bytes, but the file holds {held:,})"
        )
    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise FormatError(f"{display}: not a valid .npy file ({_plain_text(exc)})") from None
    if arr.dtype.names:
        if arr.ndim != 1:
            raise FormatError(f"{display}: a structured array must be 1-D, got shape {arr.shape}")
        cols = {name: arr[name] for name in arr.dtype.names}
        bad = [n for n, c in cols.items() if c.ndim != 1]
        if bad:
            raise FormatError(f"{display}: fields {bad} are not scalar per sample")
    elif arr.ndim == 1:
        cols = {"col0": arr}
    elif arr.ndim == 2:
        cols = {f"col{j}": arr[:, j] for j in range(arr.shape[1])}
    else:
        raise DataError(
            f"{display}: array of shape {arr.shape}; expected 1-D (one channel) or 2-D (samples × channels)"
        )
    if arr.shape[0] == 0:
        raise DataError(f"{display}: no numeric data (0 samples)")
    if not any(_numeric_kind(c) for c in cols.values()):
        raise DataError(f"{display}: no numeric data (dtype {arr.dtype})")
    table = _table_from_columns(cols, fmt="npy", display=display, opts=opts,
                                detail=f"array {arr.dtype} of shape {arr.shape}")
    table.sha256, table.size = file_sha256(path)
    return table


def _check_members(fh: BinaryIO, display: str) -> None:
    """Refuse an archive whose members would not fit in memory, or lie about their size,
    from their headers alone (a few hundred bytes each) — before anything is allocated.

    Each member's header declares prod(shape) × itemsize bytes; the zip directory
    declares the uncompressed size, which must be that plus the header. A zip bomb
    (8.7 MB inflating to 2 GB) is refused here when the memory is not there.
    """
    with zipfile.ZipFile(fh) as zf:
        total = 0
        for info in zf.infolist():
            if info.is_dir():
                continue
            key = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
            with zf.open(info) as member:
                head = _header(member, f"{display}: array {key!r} is not a valid .npy array")  # type: ignore[arg-type]
            if head.dtype.hasobject:
                raise FormatError(
                    f"{display}: array {key!r} holds Python objects (dtype {head.dtype}), which are never loaded")
            held = info.file_size - head.header_bytes
            if head.nbytes != held:
                raise FormatError(
                    f"{display}: array {key!r} is corrupt (its header declares shape {head.shape} of"
                    f" {head.dtype}, {head.nbytes:,} bytes, but the archive holds {held:,})"
                )
            total += head.nbytes
    check_allocation(display, total, f"loading its {len(zf.infolist())} array(s)")


@register("npz", extensions=(".npz",), description="NumPy .npz archive: one array per column, optional rate")
def read_npz(path: Path, display: str, opts: Options, progress: Progress) -> Table:
    # The file is opened here, not by np.load: numpy leaves its own handle open when the
    # archive turns out to be corrupt.
    with open(path, "rb") as fh:
        try:
            _check_members(fh, display)
            fh.seek(0)
            archive = np.load(fh, allow_pickle=False)
        except SigmaTauError:
            raise
        except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise FormatError(f"{display}: not a valid .npz file ({_plain_text(exc)})") from None
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise FormatError(f"{display}: not an .npz archive")
        with archive:
            arrays: dict[str, np.ndarray] = {}
            for key in archive.files:
                try:
                    arrays[key] = archive[key]
                except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
                    raise FormatError(f"{display}: array {key!r} is corrupt ({_plain_text(exc)})") from None
    rate = None
    for key in RATE_KEYS:
        if key in arrays and arrays[key].ndim == 0 and _numeric_kind(arrays[key]):
            rate = float(arrays[key])
            break
    lengths = Counter(a.shape[0] for a in arrays.values() if a.ndim in (1, 2) and a.shape[0] > 0)
    if not lengths:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in arrays.items())
        raise DataError(f"{display}: no numeric data (arrays: {shapes})")
    n = lengths.most_common(1)[0][0]
    cols: dict[str, np.ndarray] = {}
    ignored = []
    for key, a in arrays.items():
        if a.ndim == 1 and a.shape[0] == n:
            cols[key] = a
        elif a.ndim == 2 and a.shape[0] == n:
            for j, name in enumerate(split_2d(key, a.shape[1])):
                cols[name] = a[:, j]
        elif key not in RATE_KEYS:
            ignored.append(f"{key} {a.shape}")
    detail = f"{len(arrays)} arrays, {n} samples"
    if ignored:
        detail += f"; not of that length, left out: {', '.join(ignored)}"
    table = _table_from_columns(cols, fmt="npz", display=display, opts=opts, detail=detail, rate=rate)
    if opts.columns is None:  # chosen columns leave the rest out on purpose
        table.unused += tuple((member, f"not of the common length {n}") for member in ignored)
    table.sha256, table.size = file_sha256(path)
    return table
