"""Text logs out of core: read once, in chunks, into one temporary float64 ``.npy`` file per column.

A text file cannot be read piecewise by offset (a line's position depends on every line before
it), so :func:`convert` streams it once through the text reader's own parts — detection
(:class:`._sniff._Sniff`), column choice, numpy's ``loadtxt`` per chunk of lines with its
one-line errors, and pyarrow's exact fast path (:class:`._arrowcsv.FastReader`, range by range)
when it applies — and appends each chunk's columns to files in a directory the caller made
(:func:`sigmatau.io._disk.scratch_dir`). Memory: one chunk of lines (or one pyarrow range) at a
time. The files are then read like any ``.npy``; their NaN and infinite values are counted on the
way, so the checks of :func:`sigmatau.io.read` need no second pass.
"""

from __future__ import annotations

import itertools
import lzma
import os
import zlib
from pathlib import Path
from typing import Any, Iterator, Optional

import numpy as np

from ..errors import DataError, ParameterError
from . import _arrowcsv
from ._disklayout import Reader, _bytes_reader
from ._errors import FormatError
from ._progress import Progress
from ._registry import Options, Table
from ._sniff import _DELIMITERS, _Sniff, _check_lengths, _lines, _read_head
from ._text import (CHUNK_ROWS, _check_no_extra_fields, _choose_columns, _fast_eligible, _open, _parse_chunk,
                    make_table, row_layout)

__all__ = ["text_size", "convert"]


#: Bytes of each temporary file's ``.npy`` header (rewritten with the final length at the end).
_HEADER = 128
#: Assumed expansion of compressed text, for the size estimate only (gzip on numeric text: 3–5).
_COMPRESSION_RATIO = 4.0


def _check_delimiter(opts: Options) -> None:
    if opts.delimiter is not None and opts.delimiter not in _DELIMITERS and not (
        isinstance(opts.delimiter, str) and len(opts.delimiter) == 1
    ):
        raise ParameterError(f"delimiter={opts.delimiter!r} (--delimiter) must be one character (None: detect)")


def _sniffed(path: Path, display: str, opts: Options, flavour: Optional[str]) -> tuple[Any, ...]:
    """The head, the sniffing, the columns chosen and the compression of a text file."""
    _check_delimiter(opts)
    hashing, text, compression, buffered = _open(path)
    with buffered, text:
        try:
            head = _read_head(text, display)
        except (OSError, EOFError, lzma.LZMAError, zlib.error) as exc:
            raise FormatError(f"{display}: cannot read the {compression or 'text'} data:"
                              f" {' '.join(str(exc).split())}") from None
        sniff = _Sniff(head, opts.delimiter, display, opts.delimiter is not None)
    cols = _choose_columns(display, opts, flavour, sniff)
    return head, sniff, cols, compression


def text_size(path: Path, display: str, opts: Options, flavour: Optional[str]) -> tuple[int, int, bool]:
    """Estimated rows (file size over the bytes per line of the first data lines; compressed files
    times :data:`_COMPRESSION_RATIO`), channels, and whether there is a time column."""
    head, sniff, cols, compression = _sniffed(path, display, opts, flavour)
    start = sniff.data_line - 1
    per_line = (sum(len(s) for s in head[start:]) or 1) / max(len(head) - start, 1)
    size = path.stat().st_size * (_COMPRESSION_RATIO if compression else 1.0)
    return int(size / per_line) + 1, len(cols.channels), cols.time is not None


class _ColumnFiles:
    """Append-only float64 (int64 time tags) ``.npy`` files, one per column, and their NaN/inf counts."""

    def __init__(self, folder: str, names: list[str], time_dtype: Optional[np.dtype]) -> None:
        self.names = names
        self.paths = [os.path.join(folder, f"c{j}.npy") for j in range(len(names))]
        self.dtypes = [np.dtype("<f8")] * len(names)
        if time_dtype is not None:
            self.paths.append(os.path.join(folder, "time.npy"))
            self.dtypes.append(np.dtype(time_dtype).newbyteorder("<"))
        self.files = [open(p, "wb") for p in self.paths]
        self.reset()

    def reset(self) -> None:
        """Back to no rows (the fast path gave up: the reference parser reads from the start)."""
        for f in self.files:
            f.seek(0)
            f.truncate()
            f.write(b"\0" * _HEADER)
        self.n = 0
        self.counts = {name: [0, -1, 0, -1] for name in self.names}

    def add(self, time: Optional[np.ndarray], columns: list[np.ndarray]) -> None:
        arrays = list(columns) + ([time] if time is not None else [])
        for f, a, dt in zip(self.files, arrays, self.dtypes):
            f.write(np.ascontiguousarray(a, dtype=dt).tobytes())
        for name, v in zip(self.names, columns):
            bad = ~np.isfinite(v)
            if bad.any():
                c = self.counts[name]
                nan = np.isnan(v)
                inf = bad & ~nan
                for k, mask in ((0, nan), (2, inf)):
                    if mask.any():
                        c[k] += int(mask.sum())
                        if c[k + 1] < 0:
                            c[k + 1] = self.n + int(np.flatnonzero(mask)[0])
        self.n += len(columns[0]) if columns else len(time)  # type: ignore[arg-type]

    def finish(self) -> list[Reader]:
        """Write each header (shape ``(n,)``), close the files, and return a reader of each."""
        readers = []
        for f, path, dt in zip(self.files, self.paths, self.dtypes):
            text = f"{{'descr': '{dt.str}', 'fortran_order': False, 'shape': ({self.n},), }}"
            header = b"\x93NUMPY\x01\x00" + (_HEADER - 10).to_bytes(2, "little")
            header += text.encode("latin1").ljust(_HEADER - 11) + b"\n"
            f.seek(0)
            f.write(header)
            f.close()
            readers.append(_bytes_reader(Path(path), _HEADER, dt, (self.n,), False))
        return readers

    def close(self) -> None:
        for f in self.files:
            f.close()


def _split(arr: np.ndarray, int_time: bool, timed: bool, k: int) -> tuple[Optional[np.ndarray], list[np.ndarray]]:
    """A parsed chunk as (time, channels), as :func:`sigmatau.io._text._store` unpacks it."""
    if int_time:
        return arr["t"], [arr[f"c{c}"] for c in range(k)]
    offset = 1 if timed else 0
    return (arr[:, 0] if timed else None), [arr[:, offset + c] for c in range(k)]


def _fast(path: Path, head: list[str], start: int, sniff: _Sniff, usecols: list[int], int_time: bool,
          files: _ColumnFiles, progress: Progress, timed: bool) -> Optional[tuple[str, int]]:
    """The data rows through pyarrow's exact fast path; its digest, or None when it gave up (the files
    are then emptied for the reference parser)."""
    try:
        reader = _arrowcsv.FastReader(path, "".join(head[:start]), sniff.delimiter, sniff.ncols,  # type: ignore[arg-type]
                                      usecols, int_time)
        for columns in reader.batches():
            files.add(columns[0] if timed else None, columns[1:] if timed else columns)
            progress.update(reader.nbytes)
    except _arrowcsv.Fallback as why:
        _arrowcsv.last_outcome = str(why)
        files.reset()
        return None
    if files.n == 0:
        _arrowcsv.last_outcome = "no data rows"
        return None
    _arrowcsv.last_outcome = "fast"
    return reader.sha256, reader.nbytes


def convert(path: Path, display: str, opts: Options, flavour: Optional[str], folder: str,
            progress: Optional[bool]) -> tuple[Table, dict[str, Reader], Optional[Reader], int,
                                               dict[str, tuple[int, int, int, int]]]:
    """Stream a text log into ``folder``: its table (channel readers as data), the time reader, the rows,
    and each column's (NaN count, first NaN, infinite count, first infinite)."""
    head, sniff, cols, compression = _sniffed(path, display, opts, flavour)
    names = sniff.names
    usecols, int_time, dtype = row_layout(sniff, cols)
    timed = cols.time is not None
    chans = [names[j] for j in cols.channels]
    files = _ColumnFiles(folder, chans, (np.int64 if int_time else np.float64) if timed else None)
    try:
        hashing, text, _, buffered = _open(path)
        size = path.stat().st_size
        with buffered, text, Progress(None, f"sigmatau: reading {path.name} in chunks", enabled=progress) as bar:
            bar.set_total(size)
            try:
                head = _read_head(text, display)
                start = sniff.data_line - 1
                quoted = any('"' in s for s in head[start:])
                digest = None
                if _fast_eligible(path, sniff, cols, compression, size, quoted):
                    digest = _fast(path, head, start, sniff, usecols, int_time, files, bar, timed)
                if digest is None:
                    rest: Iterator[str] = itertools.chain(head[start:], _lines(text))
                    line_no = sniff.data_line
                    while lines := list(itertools.islice(rest, CHUNK_ROWS)):
                        _check_lengths(lines, line_no, display)
                        arr = _parse_chunk(lines, line_no, sniff, usecols, dtype, quoted, int_time, display)
                        _check_no_extra_fields(lines, line_no, sniff, display)
                        t, columns = _split(arr, int_time, timed, len(chans))
                        files.add(t, columns)
                        line_no += len(lines)
                        bar.update(hashing.nbytes)
                    if files.n == 0:
                        raise DataError(f"{display}: no numeric data rows")
                    hashing.drain()
                    digest = (hashing.sha.hexdigest(), hashing.nbytes)
            except (OSError, EOFError, lzma.LZMAError, zlib.error) as exc:
                raise FormatError(f"{display}: cannot read the {compression or 'text'} data:"
                                  f" {' '.join(str(exc).split())}") from None
        counts = {name: tuple(c) for name, c in files.counts.items()}
        n = files.n
        readers = files.finish()
    except BaseException:
        files.close()
        raise
    data = dict(zip(chans, readers[:len(chans)]))
    table = make_table(path, display, opts, head, sniff, cols, compression, data, None, n, digest)
    return table, data, (readers[-1] if timed else None), n, counts  # type: ignore[return-value]
