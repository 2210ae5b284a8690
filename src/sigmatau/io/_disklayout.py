"""How the binary formats lay out their columns, for :func:`sigmatau.io.open_log`: readers of rows.

Each ``*_layout`` function makes, from the headers alone, the column choice of the in-memory
reader of its format (:mod:`._numpy`, :mod:`._hdf5`) — same column names, numeric check,
:func:`._columns.select`, rate attribute or member, left-out members — with, instead of arrays,
functions that read rows ``a … b-1`` of a column from the file's bytes (``.npy``, stored ``.npz``
members) or from HDF5 slices.
"""

from __future__ import annotations

import struct
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional

import numpy as np

from ..errors import DataError, ParameterError
from ._columns import select
from ._errors import FormatError, option_hint, repr_kw
from ._numpy import RATE_KEYS, split_2d
from ._registry import Options, Table

__all__ = ["Layout", "npy_layout", "npz_layout", "hdf5_layout", "as_dtype"]

Reader = Callable[[int, int], np.ndarray]


@dataclass
class Layout:
    """A file's columns as readers of rows: what the readers hand to the common checks."""

    table: Table
    readers: dict[str, Reader]
    time: Optional[Reader]
    rows: int
    closers: list = field(default_factory=list)
    counts: Optional[dict[str, tuple[int, int, int, int]]] = None  # non-finite counts when already known
    workdir: Optional[str] = None  # the temporary directory of a text log


def _header(fh: Any, what: str) -> tuple[tuple[int, ...], bool, np.dtype, int]:
    """Shape, Fortran order, dtype and header length of a ``.npy`` stream (nothing unpickled)."""
    start = fh.tell()
    try:
        version = np.lib.format.read_magic(fh)
        reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = reader(fh)
    except (ValueError, EOFError, OSError, SyntaxError, TypeError):
        raise FormatError(f"{what} (no valid NumPy header)") from None
    dtype = np.dtype(dtype)
    if dtype.hasobject:
        raise FormatError(f"{what}: holds Python objects (dtype {dtype}), which are never loaded")
    return tuple(int(s) for s in shape), bool(fortran), dtype, fh.tell() - start


def _bytes_reader(path: Path, offset: int, dtype: np.dtype, shape: tuple[int, ...], fortran: bool,
                  column: Optional[int] = None, fld: Optional[str] = None) -> Reader:
    """Rows ``a … b-1`` of one column of an array stored at ``offset`` of ``path``: plain reads, so the
    pages stay in the OS cache, not in this process."""
    item = dtype.itemsize
    width = shape[1] if len(shape) == 2 else 1

    def read(a: int, b: int) -> np.ndarray:
        with open(path, "rb") as f:
            if len(shape) == 2 and fortran:
                f.seek(offset + (column * shape[0] + a) * item)  # type: ignore[operator]
                return np.fromfile(f, dtype=dtype, count=b - a)
            f.seek(offset + a * width * item)
            v = np.fromfile(f, dtype=dtype, count=(b - a) * width)
        if len(shape) == 2:
            v = v.reshape(-1, width)[:, column]
        return v[fld] if fld is not None else v

    return read


def _columns_of_array(path: Path, offset: int, shape: tuple[int, ...], fortran: bool, dtype: np.dtype,
                      display: str) -> dict[str, tuple[Reader, np.dtype]]:
    """The columns :func:`sigmatau.io._numpy.read_npy` makes of an array, as readers."""
    if dtype.names:
        if len(shape) != 1:
            raise FormatError(f"{display}: a structured array must be 1-D, got shape {shape}")
        bad = [n for n in dtype.names if dtype[n].shape != ()]
        if bad:
            raise FormatError(f"{display}: fields {bad} are not scalar per sample")
        return {n: (_bytes_reader(path, offset, dtype, shape, fortran, fld=n), dtype[n]) for n in dtype.names}
    if len(shape) == 1:
        return {"col0": (_bytes_reader(path, offset, dtype, shape, fortran), dtype)}
    if len(shape) == 2:
        return {f"col{j}": (_bytes_reader(path, offset, dtype, shape, fortran, column=j), dtype)
                for j in range(shape[1])}
    raise DataError(f"{display}: array of shape {shape}; expected 1-D (one channel) or 2-D (samples × channels)")


def _table_of(cols: dict[str, tuple[Reader, np.dtype]], rows: int, *, fmt: str, display: str, opts: Options,
              detail: str, rate: Optional[float] = None) -> Layout:
    """The column choice of :func:`sigmatau.io._numpy._table_from_columns`, without reading."""
    names = list(cols)
    numeric = [cols[n][1].kind in "biuf" for n in names]
    if not any(numeric):
        raise DataError(f"{display}: no numeric data (dtypes {', '.join(sorted({str(c[1]) for c in cols.values()}))})")
    sel = select(names, numeric, columns=opts.columns, time_column=opts.time_column, path=display)
    if rows == 0:
        raise DataError(f"{display}: no numeric data (0 samples)")
    readers = {names[j]: cols[names[j]][0] for j in sel.channels}
    time = None
    if sel.time is not None:
        raw, kind = cols[names[sel.time]][0], cols[names[sel.time]][1].kind
        time = as_dtype(raw, np.int64 if kind in "iu" else np.float64)
    table = Table(format=fmt, columns=tuple(names), data=readers, rows=rows, sha256="", size=0,  # type: ignore[arg-type]
                  time_name=None if sel.time is None else names[sel.time], time_unit=sel.time_unit,
                  time_unit_reason=f"from the name {names[sel.time]!r}" if sel.time is not None and sel.time_unit
                  else "", rate=rate, detail=detail, unused=sel.unused)
    return Layout(table, readers, time, rows)


def as_dtype(read: Reader, dtype: Any) -> Reader:
    return lambda a, b: np.asarray(read(a, b)).astype(dtype)


def npy_layout(path: Path, display: str, opts: Options) -> Layout:
    with open(path, "rb") as fh:
        shape, fortran, dtype, header = _header(fh, f"{display}: not a valid .npy file")
    held = path.stat().st_size - header
    nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if nbytes > held:
        raise FormatError(f"{display}: not a valid .npy file (its header declares shape {shape} of {dtype},"
                          f" {nbytes:,} bytes, but the file holds {held:,})")
    if not shape:
        raise DataError(f"{display}: array of shape (); expected 1-D (one channel) or 2-D (samples × channels)")
    cols = _columns_of_array(path, header, shape, fortran, dtype, display)
    return _table_of(cols, shape[0], fmt="npy", display=display, opts=opts,
                     detail=f"array {dtype} of shape {shape}")


def _member_offset(fh: Any, info: zipfile.ZipInfo, display: str) -> int:
    """Where a stored member's bytes start: after its local header (30 bytes, name, extra field)."""
    fh.seek(info.header_offset)
    local = fh.read(30)
    if len(local) != 30 or local[:4] != b"PK\x03\x04":
        raise FormatError(f"{display}: not a valid .npz file (damaged local header of {info.filename!r})")
    name_len, extra_len = struct.unpack("<HH", local[26:30])
    return info.header_offset + 30 + name_len + extra_len


def npz_layout(path: Path, display: str, opts: Options) -> Layout:
    members: dict[str, tuple[int, tuple[int, ...], bool, np.dtype]] = {}
    try:
        with open(path, "rb") as fh, zipfile.ZipFile(fh) as zf:
            for info in zf.infolist():
                if info.is_dir():
                    continue
                key = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
                if info.compress_type != zipfile.ZIP_STORED:
                    raise DataError(
                        f"{display}: array {key!r} is compressed (numpy.savez_compressed); out of core an .npz is"
                        " read in place only when its arrays are stored (numpy.savez): save it uncompressed, or"
                        f" read it in memory with {option_hint('--memory in', repr_kw('memory', 'in'))}")
                start = _member_offset(fh, info, display)
                fh.seek(start)
                shape, fortran, dtype, header = _header(fh, f"{display}: array {key!r} is not a valid .npy array")
                nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
                if nbytes != info.file_size - header:
                    raise FormatError(f"{display}: array {key!r} is corrupt (its header declares shape {shape} of"
                                      f" {dtype}, {nbytes:,} bytes, but the archive holds"
                                      f" {info.file_size - header:,})")
                members[key] = (start + header, shape, fortran, dtype)
    except zipfile.BadZipFile as exc:
        raise FormatError(f"{display}: not a valid .npz file ({exc})") from None
    rate = None
    for key in RATE_KEYS:
        if key in members and members[key][1] == () and members[key][3].kind in "biuf":
            off, _, _, dt = members[key]
            with open(path, "rb") as f:
                f.seek(off)
                rate = float(np.fromfile(f, dtype=dt, count=1)[0])
            break
    lengths = [m[1][0] for m in members.values() if len(m[1]) in (1, 2) and m[1][0] > 0]
    if not lengths:
        shapes = ", ".join(f"{k} {m[1]}" for k, m in members.items())
        raise DataError(f"{display}: no numeric data (arrays: {shapes})")
    n = max(set(lengths), key=lambda v: (lengths.count(v), -lengths.index(v)))
    cols: dict[str, tuple[Reader, np.dtype]] = {}
    ignored = []
    for key, (off, shape, fortran, dt) in members.items():
        if len(shape) == 1 and shape[0] == n and not dt.names:
            cols[key] = (_bytes_reader(path, off, dt, shape, fortran), dt)
        elif len(shape) == 2 and shape[0] == n and not dt.names:
            for j, name in enumerate(split_2d(key, shape[1])):
                cols[name] = (_bytes_reader(path, off, dt, shape, fortran, column=j), dt)
        elif key not in RATE_KEYS:
            ignored.append(f"{key} {shape}")
    detail = f"{len(members)} arrays, {n} samples"
    if ignored:
        detail += f"; not of that length, left out: {', '.join(ignored)}"
    layout = _table_of(cols, n, fmt="npz", display=display, opts=opts, detail=detail, rate=rate)
    if opts.columns is None:
        layout.table.unused += tuple((m, f"not of the common length {n}") for m in ignored)
    return layout


def hdf5_layout(path: Path, display: str, opts: Options) -> Layout:
    from . import _hdf5
    from ._errors import require_optional

    h5py = require_optional("h5py", extra="hdf5", package="h5py", what="HDF5 files")
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as exc:
        raise FormatError(f"{display}: not a readable HDF5 file ({' '.join(str(exc).split())})") from None
    try:
        if opts.dataset is not None:
            if opts.dataset not in f:
                raise ParameterError(f"{display}: no dataset or group {opts.dataset!r}; datasets are:"
                                     f" {_hdf5._listing(f)}")
            target = f[opts.dataset]
        else:
            target = _hdf5._auto(f, display)
        cols = _hdf5._columns_of(f, target, display)
        names = list(cols.specs)

        def reader(spec: tuple[Any, Any]) -> Reader:
            ds, sub = spec
            return lambda a, b: (ds[a:b][sub] if isinstance(sub, str) else ds[a:b] if sub is None
                                 else ds[a:b, sub])

        kinds = {"b": "?", "i": "i8", "u": "u8", "f": "f8"}  # the kind decides, as for the in-memory reader
        typed = {nm: (reader(cols.specs[nm]), np.dtype(kinds.get(_hdf5._kind(cols.specs[nm]), "O")))
                 for nm in names}
        layout = _table_of(typed, cols.rows, fmt="hdf5", display=display, opts=opts,
                           detail=f"{'dataset' if cols.single else 'group'} {target.name}, {cols.rows} rows",
                           rate=_hdf5._rate_attribute(target, f))
        layout.table.units = {k: v for k, v in cols.units.items() if k in layout.readers}
        if opts.columns is None:
            layout.table.unused += tuple(cols.left_out)
    except BaseException:
        f.close()
        raise
    layout.closers.append(f.close)
    return layout
