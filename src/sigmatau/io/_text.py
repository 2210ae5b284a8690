"""Delimited text (CSV, TSV, semicolon, whitespace) and Stable32 data files, read in chunks.

Detection, from the first 200 non-comment lines:

* compression: gzip, bzip2 and xz by their magic bytes;
* delimiter: tab, comma, semicolon, pipe or runs of whitespace — the one whose
  last lines split into the same number of fields with the most numeric columns;
* comment lines start with ``#``, ``%`` or ``//`` (also after data on a line);
* the first data line is the first one that splits like the last lines; a
  header is the first earlier line with as many fields, or else the comment line
  just before the data (EuRoC's ``#timestamp [ns],w_RS_S_x [rad s^-1],…``);
  other lines before the data are skipped and reported in ``Source.detail``.

The rest of the file is parsed by ``numpy.loadtxt`` in chunks of 65,536 lines
into preallocated column arrays, so memory stays near the size of the chosen
columns as float64 plus one chunk of text.

A large, uncompressed, regular file with a comma, semicolon, tab or pipe
delimiter and no quotes is first tried with pyarrow's multi-threaded CSV parser
when pyarrow is installed (:mod:`._arrowcsv`): it yields the same table and
digest, or gives up on anything irregular and this parser reads the file, so
errors are always this parser's.
"""

from __future__ import annotations

import bz2
import gzip
import hashlib
import io
import itertools
import lzma
import os
import re
import stat
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from ..errors import DataError, ParameterError
from . import _arrowcsv
from ._columns import recognise, select, strip_name, time_name
from ._errors import FormatError, option_hint, repr_kw
from ._limits import check_allocation
from ._progress import Progress
from ._registry import Options, Table, register
from ._units import canonical_unit, time_unit_name
from ._sniff import (
    _DELIMITER_NAMES, _DELIMITERS, _COMMENTS, _INT, _Sniff, _check_lengths, _is_num, _lines, _read_head, _shown, _split, _strip_comment,
)

__all__ = ["read_csv", "read_stable32", "make_table", "row_layout"]

CHUNK_ROWS = 1 << 16
#: Use pyarrow's CSV parser for plain files when it is installed (False: always numpy's loadtxt).
_FAST_CSV = True
#: Smaller files are not worth importing pyarrow and starting a reader thread for.
_FAST_MIN_BYTES = 16 << 20
_MJD = (15_000.0, 100_000.0)  # 1900 … 2132
_DATA_TYPE_HINT = option_hint("--data-type phase|freq", "data_type='phase' or 'freq'")


class _HashingReader(io.RawIOBase):
    """Raw reader that hashes and counts the bytes it passes on (one pass over the file)."""

    def __init__(self, fh: io.BufferedReader) -> None:
        self._fh = fh
        self.sha = hashlib.sha256()
        self.nbytes = 0

    def readable(self) -> bool:
        return True

    def readinto(self, b) -> int:  # type: ignore[no-untyped-def]
        n = self._fh.readinto(b)
        if n:
            self.sha.update(memoryview(b)[:n])
            self.nbytes += n
        return n or 0

    def drain(self) -> None:
        while block := self._fh.read(1 << 20):
            self.sha.update(block)
            self.nbytes += len(block)

    def close(self) -> None:
        self._fh.close()
        super().close()


def _open(path: Path, stream: io.RawIOBase | None = None
          ) -> tuple[_HashingReader, io.TextIOWrapper, str, io.BufferedReader]:
    hashing = _HashingReader(path.open("rb") if stream is None else stream)  # type: ignore[arg-type]
    buffered = io.BufferedReader(hashing, buffer_size=1 << 20)
    magic = buffered.peek(6)[:6]
    stream: io.BufferedIOBase
    if magic.startswith(b"\x1f\x8b"):
        stream, kind = gzip.GzipFile(fileobj=buffered, mode="rb"), "gzip"
    elif magic.startswith(b"BZh"):
        stream, kind = bz2.BZ2File(buffered), "bzip2"
    elif magic.startswith(b"\xfd7zXZ\x00"):
        stream, kind = lzma.LZMAFile(buffered), "xz"
    else:
        stream, kind = buffered, ""
    text = io.TextIOWrapper(stream, encoding="utf-8-sig", errors="replace", newline=None)
    return hashing, text, kind, buffered


def _diagnose(lines: list[str], first: int, sniff: _Sniff, usecols: list[int], int_time: bool,
              display: str, err: Exception) -> DataError:
    d = sniff.delimiter
    for k, line in enumerate(lines):
        s = _strip_comment(line).strip()
        if not s:
            continue
        fields = _split(s, d)
        n = first + k
        if len(fields) != sniff.ncols and (d is None or len(fields) <= max(usecols)):
            return DataError(f"{display}: line {n} has {len(fields)} fields, expected {sniff.ncols}")
        for pos, j in enumerate(usecols):
            value = fields[j]
            ok = _INT.match(value) if (int_time and pos == 0) else _is_num(value)
            if not ok:
                what = "an integer" if (int_time and pos == 0) else "a number"
                return DataError(
                    f"{display}: line {n}: {_shown(value)} in column {sniff.names[j]!r} is not {what}")
    message = " ".join(str(err).split())
    return DataError(f"{display}: cannot parse lines {first}–{first + len(lines) - 1}: {message}")


def _load(path: Path, display: str, opts: Options, progress: Progress, flavour: str | None,
          stream: io.RawIOBase | None = None) -> Table:
    if opts.delimiter is not None and opts.delimiter not in _DELIMITERS and not (
        isinstance(opts.delimiter, str) and len(opts.delimiter) == 1
    ):
        raise ParameterError(f"delimiter={opts.delimiter!r} (--delimiter) must be one character (None: detect)")
    hashing, text, compression, buffered = _open(path, stream)
    size = path.stat().st_size if stream is None else None
    progress.set_total(size)
    # a decompressor does not close the file it was given: close both layers
    with buffered, text:
        try:
            head = _read_head(text, display)
            sniff = _Sniff(head, opts.delimiter, display, opts.delimiter is not None)
            table = _parse(path, display, opts, progress, flavour, hashing, text, head, sniff, compression, size)
        except (OSError, EOFError, lzma.LZMAError, zlib.error) as exc:
            raise FormatError(
                f"{display}: cannot read the {compression or 'text'} data: {' '.join(str(exc).split())}"
            ) from None
        if not table.sha256:  # the fast path hashed the whole file itself
            hashing.drain()
            table.sha256 = hashing.sha.hexdigest()
            table.size = hashing.nbytes
    return table


def _stable32_type(sniff: _Sniff, path: Path) -> str | None:
    words = re.sub(r"[_.\-/]", " ", f"{sniff.text} {path.name}").lower()
    phase = bool(re.search(r"\bphase\b", words))
    freq = bool(re.search(r"\bfreq(uency)?\b", words))
    if phase != freq:
        return "phase" if phase else "freq"
    return None


def _looks_mjd(sniff: _Sniff, j: int) -> bool:
    try:
        values = [float(f[j]) for f in sniff.tail]
    except (ValueError, IndexError):
        return False
    return all(_MJD[0] <= v <= _MJD[1] for v in values) and all(b >= a for a, b in zip(values, values[1:]))


def _loadtxt(lines: list[str], delimiter: str | None, comments: str | tuple[str, ...], usecols: list[int],
             dtype: np.dtype, quoted: bool, structured: bool) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "input contained no data": a comment-only chunk
        return np.loadtxt(lines, delimiter=delimiter, comments=comments, usecols=usecols, dtype=dtype,
                          quotechar='"' if quoted else None, ndmin=1 if structured else 2)


def _parse(path: Path, display: str, opts: Options, progress: Progress, flavour: str | None,
           hashing: _HashingReader, text: io.TextIOWrapper, head: list[str], sniff: _Sniff,
           compression: str, size: int | None) -> Table:
    cols = _choose_columns(display, opts, flavour, sniff)
    data, time, n, digest = _read_rows(path, display, opts, progress, hashing, text, head, sniff, cols,
                                       compression, size)
    return make_table(path, display, opts, head, sniff, cols, compression, data, time, n, digest)


def make_table(path: Path, display: str, opts: Options, head: list[str], sniff: _Sniff, cols: "_Columns",
               compression: str, data: dict, time: np.ndarray | None, n: int, digest: tuple[str, int]) -> Table:
    """The :class:`Table` of a text file from its parsed columns (``data``, ``time``: arrays, or for the
    out-of-core reader (:mod:`._disktext`) readers of them) and what the sniffing found."""
    names = sniff.names
    table = Table(
        format=cols.flavour, columns=tuple(names), data=data, rows=n, sha256=digest[0], size=digest[1],
        time=time, time_name=None if cols.time is None else names[cols.time],
        time_unit=cols.time_unit, units=_column_units(names, cols.channels, sniff),
        detail=_detail(names, head, sniff, compression, cols.skipped), unused=cols.unused,
    )
    if cols.flavour == "stable32":
        _as_stable32(table, display, opts, sniff, path, cols)
    elif cols.time is not None and cols.time_unit is not None:
        table.time_unit_reason = f"from the column name {names[cols.time]!r}"
        if time_name(names[cols.time]) is None:
            table.time_unit_reason = "from the units line"
    return table


@dataclass(frozen=True)
class _Columns:
    """Which columns are read: the flavour (csv or stable32), the time column, the channels."""

    flavour: str
    time: int | None
    channels: tuple[int, ...]
    time_unit: str | None
    skipped: tuple[str, ...]
    unused: tuple[tuple[str, str], ...]


def _choose_columns(display: str, opts: Options, flavour: str | None, sniff: _Sniff) -> _Columns:
    """The flavour (auto: a lone numeric column, or MJD + value, is Stable32-style) and the columns to read."""
    names = sniff.names
    numeric_idx = [j for j in range(sniff.ncols) if sniff.numeric[j]]
    imu_named = any(recognise(n).group for n in names)
    if flavour is None:  # auto: a lone numeric column (or MJD + value) is a Stable32-style file
        lone = len(numeric_idx) == 1 or (len(numeric_idx) == 2 and _looks_mjd(sniff, numeric_idx[0]))
        explicit = opts.columns is not None or opts.time_column is not None
        flavour = "stable32" if (lone and not imu_named and not explicit) else "csv"
    if flavour == "stable32":
        return _stable32_columns(display, opts, numeric_idx)
    sel = select(names, sniff.numeric, columns=opts.columns, time_column=opts.time_column,
                 path=display, first_bad=sniff.first_bad)
    stated_unit = sel.time_unit
    if sel.time is not None and stated_unit is None and names[sel.time] in sniff.units_line:
        stated_unit = time_unit_name(sniff.units_line[names[sel.time]])
    return _Columns("csv", sel.time, tuple(sel.channels), stated_unit, tuple(sel.skipped), tuple(sel.unused))


def _stable32_columns(display: str, opts: Options, numeric_idx: list[int]) -> _Columns:
    """A Stable32 data file: one value per line, or MJD and value."""
    if len(numeric_idx) not in (1, 2):
        raise FormatError(
            f"{display}: a Stable32 data file has one value per line, or MJD and value;"
            f" found {len(numeric_idx)} numeric columns"
            f" (use {option_hint('--format csv', repr_kw('format', 'csv'))})"
        )
    if opts.columns is not None:
        raise ParameterError(
            f"{display}: columns= (--columns) does not apply to Stable32 data files (one value per line)")
    if len(numeric_idx) == 2:
        if opts.time_column is False:
            raise ParameterError(f"{display}: time_column=False (--time-column none): a two-column Stable32"
                                 " file has MJD time tags first")
        return _Columns("stable32", numeric_idx[0], (numeric_idx[1],), "d", (), ())
    return _Columns("stable32", None, (numeric_idx[0],), None, (), ())


def row_layout(sniff: _Sniff, cols: "_Columns") -> tuple[list[int], bool, np.dtype]:
    """The columns to parse (the time column first), whether the time tags are integers beyond
    2**53 (kept as int64), and the dtype :func:`_parse_chunk` gives numpy's loadtxt."""
    time_idx, chans = cols.time, cols.channels
    usecols = ([time_idx] if time_idx is not None else []) + list(chans)
    int_time = False
    if time_idx is not None:
        values = [f[time_idx] for f in sniff.tail]
        int_time = all(_INT.match(v) for v in values) and max(abs(int(v)) for v in values) > 2**53
    if int_time:
        dtype: np.dtype = np.dtype([("t", "<i8")] + [(f"c{k}", "<f8") for k in range(len(chans))])
    else:
        dtype = np.dtype(np.float64)
    return usecols, int_time, dtype


def _read_rows(path: Path, display: str, opts: Options, progress: Progress, hashing: _HashingReader,
               text: io.TextIOWrapper, head: list[str], sniff: _Sniff, cols: _Columns, compression: str,
               size: int | None) -> tuple[dict[str, np.ndarray], np.ndarray | None, int, tuple[str, int]]:
    """The selected columns of every data row, parsed in chunks of CHUNK_ROWS lines into float64 columns
    (int64 time tags when they exceed 2**53), the buffer grown geometrically within the memory check.

    The last item is the file's SHA-256 and size when the fast path read (and hashed) the whole
    file, else ``("", 0)`` and the caller hashes the rest of ``hashing``'s stream.
    """
    names = sniff.names
    time_idx, chans = cols.time, cols.channels
    usecols, int_time, dtype = row_layout(sniff, cols)

    # Lines from the first data line on: the sniffed ones, then the rest of the file.
    start = sniff.data_line - 1
    rest: Iterator[str] = itertools.chain(head[start:], _lines(text))
    data_bytes = sum(len(s) for s in head[start:]) or 1
    data_lines = max(len(head) - start, 1)
    if compression or size is None:
        capacity = 1 << 16
    else:
        capacity = int(size / (data_bytes / data_lines) * 1.02) + 16
    # numpy's loadtxt takes quotes only with a single one-character comment marker
    quoted = any('"' in s for s in head[start:])
    k = len(chans)
    check_allocation(display, 8 * capacity * (k + 1), f"{k} column(s) of about {capacity:,} rows")
    buf = np.empty((k, capacity))
    tbuf = np.empty(capacity, dtype=np.int64 if int_time else np.float64) if time_idx is not None else None
    n = 0
    if _fast_eligible(path, sniff, cols, compression, size, quoted):
        fast = _fast_rows(path, display, progress, head, start, sniff, usecols, int_time, buf, tbuf, capacity)
        if fast is not None:
            buf, tbuf, n, reader = fast
            return _finish(names, chans, buf, tbuf, n) + ((reader.sha256, reader.nbytes),)
    line_no = sniff.data_line
    while True:
        lines = list(itertools.islice(rest, CHUNK_ROWS))
        if not lines:
            break
        _check_lengths(lines, line_no, display)
        arr = _parse_chunk(lines, line_no, sniff, usecols, dtype, quoted, int_time, display)
        _check_no_extra_fields(lines, line_no, sniff, display)
        m = arr.shape[0]
        if n + m > capacity:
            capacity = max(int(capacity * 1.6), n + m)
            check_allocation(display, 8 * capacity * (k + 1), f"{k} column(s) of {capacity:,} rows read so far")
            buf, tbuf = _grown(buf, tbuf, n, capacity)
        _store(arr, buf, tbuf, n, int_time, k)
        n += m
        line_no += len(lines)
        progress.update(hashing.nbytes)
    if n == 0:
        raise DataError(f"{display}: no numeric data rows")
    return _finish(names, chans, buf, tbuf, n) + (("", 0),)


def _finish(names: list[str], chans: Sequence[int], buf: np.ndarray, tbuf: np.ndarray | None,
            n: int) -> tuple[dict[str, np.ndarray], np.ndarray | None, int]:
    """The filled part of the column buffers, copied out when the estimate left much unused."""
    if buf.shape[1] > n * 1.05 + 16:
        buf = buf[:, :n].copy()
        tbuf = None if tbuf is None else tbuf[:n].copy()
    data = {names[j]: buf[c, :n] for c, j in enumerate(chans)}
    return data, None if tbuf is None else tbuf[:n], n


def _fast_eligible(path: Path, sniff: _Sniff, cols: _Columns, compression: str, size: int | None,
                   quoted: bool) -> bool:
    """Whether the file is a case :mod:`._arrowcsv` may try: a large regular uncompressed file, a
    one-character delimiter it splits on like ``str.split``, no quotes in the sniffed data lines."""
    if not _FAST_CSV or size is None or size < _FAST_MIN_BYTES or compression or quoted:
        return False
    if cols.flavour != "csv" or sniff.delimiter not in _arrowcsv.DELIMITERS:
        return False
    try:
        regular = stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False
    return regular and _arrowcsv.usable()


def _fast_rows(path: Path, display: str, progress: Progress, head: list[str], start: int, sniff: _Sniff,
               usecols: list[int], int_time: bool, buf: np.ndarray, tbuf: np.ndarray | None, capacity: int
               ) -> tuple[np.ndarray, np.ndarray | None, int, _arrowcsv.FastReader] | None:
    """The data rows through :mod:`._arrowcsv` into the column buffers, grown as the reference grows
    them; None when it gives up (``_arrowcsv.last_outcome`` says why) and the reference must read."""
    k = buf.shape[0]
    n = 0
    try:
        reader = _arrowcsv.FastReader(path, "".join(head[:start]), sniff.delimiter, sniff.ncols,  # type: ignore[arg-type]
                                      usecols, int_time)
        for columns in reader.batches():
            m = len(columns[0])
            if n + m > capacity:
                capacity = max(int(capacity * 1.6), n + m)
                try:
                    check_allocation(display, 8 * capacity * (k + 1), "")
                except (DataError, MemoryError):  # the reference words it, with its own row count
                    raise _arrowcsv.Fallback("over the memory budget") from None
                buf, tbuf = _grown(buf, tbuf, n, capacity)
            offset = 0
            if tbuf is not None:
                tbuf[n:n + m] = columns[0]
                offset = 1
            for c in range(k):
                buf[c, n:n + m] = columns[offset + c]
            n += m
            progress.update(reader.nbytes)
    except _arrowcsv.Fallback as why:
        _arrowcsv.last_outcome = str(why)
        return None
    if n == 0:  # the reference words "no numeric data rows" and friends
        _arrowcsv.last_outcome = "no data rows"
        return None
    _arrowcsv.last_outcome = "fast"
    return buf, tbuf, n, reader


def _check_no_extra_fields(lines: list[str], first: int, sniff: _Sniff, display: str) -> None:
    """Refuse a data line with more fields than the header: numpy's loadtxt reads only the columns
    asked for and would keep the line, although its values are most likely shifted (a field
    split in two, a missing line break). Empty trailing fields (``1,2,3,``) are not values."""
    d = sniff.delimiter
    want = sniff.ncols
    for k, line in enumerate(lines):
        if d is not None and line.count(d) < want:
            continue  # the common case, one str.count per line: too few delimiters to exceed
        s = _strip_comment(line).strip()
        fields = _split(s, d) if s else []
        if len(fields) > want and any(f.strip() for f in fields[want:]):
            raise DataError(f"{display}: line {first + k} has {len(fields)} fields, expected {want}"
                            " (more values than the header names)")


def _parse_chunk(lines: list[str], line_no: int, sniff: _Sniff, usecols: list[int], dtype: np.dtype,
                 quoted: bool, int_time: bool, display: str) -> np.ndarray:
    """One chunk of lines through numpy's loadtxt; a bad line becomes a one-line error naming it."""
    try:
        return _loadtxt(lines, sniff.delimiter, "#", usecols, dtype, quoted, int_time)
    except ValueError as exc:
        if quoted:
            raise _diagnose(lines, line_no, sniff, usecols, int_time, display, exc) from None
        try:  # '%' and '//' comments cost numpy a Python call per line: only when needed
            return _loadtxt(lines, sniff.delimiter, _COMMENTS, usecols, dtype, quoted, int_time)
        except ValueError as exc2:
            raise _diagnose(lines, line_no, sniff, usecols, int_time, display, exc2) from None


def _grown(buf: np.ndarray, tbuf: np.ndarray | None, n: int,
           capacity: int) -> tuple[np.ndarray, np.ndarray | None]:
    """The column buffers enlarged to ``capacity`` rows, their first ``n`` rows kept."""
    grown = np.empty((buf.shape[0], capacity))
    grown[:, :n] = buf[:, :n]
    if tbuf is None:
        return grown, None
    tgrown = np.empty(capacity, dtype=tbuf.dtype)
    tgrown[:n] = tbuf[:n]
    return grown, tgrown


def _store(arr: np.ndarray, buf: np.ndarray, tbuf: np.ndarray | None, n: int, int_time: bool, k: int) -> None:
    """A parsed chunk into the column buffers from row ``n``."""
    m = arr.shape[0]
    if int_time:
        tbuf[n:n + m] = arr["t"]  # type: ignore[index]
        for c in range(k):
            buf[c, n:n + m] = arr[f"c{c}"]
        return
    offset = 0
    if tbuf is not None:
        tbuf[n:n + m] = arr[:, 0]
        offset = 1
    buf[:, n:n + m] = arr[:, offset:].T


def _column_units(names: list[str], chans: Sequence[int], sniff: _Sniff) -> dict[str, str]:
    """Each channel's unit from its name, its brackets or the units line (recorded as written)."""
    units = {}
    for j in chans:
        rec = recognise(names[j])
        bracket = strip_name(names[j])[1]
        if rec.unit:
            units[names[j]] = rec.unit
        elif bracket:  # recorded as written: read() refuses a gyro or accel unit it does not know
            units[names[j]] = bracket
        elif names[j] in sniff.units_line:
            units[names[j]] = canonical_unit(sniff.units_line[names[j]]) or sniff.units_line[names[j]]
    return units


def _detail(names: list[str], head: list[str], sniff: _Sniff, compression: str, skipped: Sequence[str]) -> str:
    """How the file was read, for the log's source line."""
    parts = [_DELIMITER_NAMES.get(sniff.delimiter, repr(sniff.delimiter)) + "-separated"]
    if compression:
        parts.insert(0, f"{compression}-compressed")
    parts.append(f"header on line {sniff.header_line}" if sniff.has_header else "no header")
    if sniff.skipped:
        parts.append(f"{sniff.skipped} other line(s) before the data skipped")
    if sniff.comments:
        parts.append(f"{len(sniff.comments)} comment line(s) in the first {len(head)} lines")
    if [n_.lower() for n_ in names[:7]] == ["timestamp [ns]", "w_rs_s_x [rad s^-1]", "w_rs_s_y [rad s^-1]",
                                            "w_rs_s_z [rad s^-1]", "a_rs_s_x [m s^-2]", "a_rs_s_y [m s^-2]",
                                            "a_rs_s_z [m s^-2]"]:
        parts.append("EuRoC/ASL imu0/data.csv layout")
    if skipped:
        parts.append(f"numeric columns not recognised as IMU channels left out: {', '.join(skipped)}")
    return "; ".join(parts)


def _as_stable32(table: Table, display: str, opts: Options, sniff: _Sniff, path: Path, cols: _Columns) -> None:
    """A Stable32-style table: its data type (option, header or name), channel name and units."""
    dtype_name = opts.data_type or _stable32_type(sniff, path)
    if dtype_name is None:
        raise ParameterError(
            f"{display}: cannot tell whether this Stable32-style file holds phase or frequency data"
            " (neither or both words in its header and name); give it with"
            f" {_DATA_TYPE_HINT}"
        )
    (name,) = table.data
    table.data_type = dtype_name
    table.rename = {name: dtype_name}
    table.groups = {name: dtype_name}
    table.unit_origin = "format"
    table.units = {name: "s"} if dtype_name == "phase" else {}
    if cols.time is not None:
        table.time_unit_reason = "Stable32 time tags (MJD)"


@register("csv", extensions=(".csv", ".tsv", ".txt", ".tab", ".asc", ".log"),
          description="delimited text: CSV/TSV/semicolon/whitespace, header and comments detected,"
                      " EuRoC imu0/data.csv; gzip/bzip2/xz compressed too",
          options=("delimiter",))
def read_csv(path: Path, display: str, opts: Options, progress: Progress, *, auto: bool = False,
             stream: io.RawIOBase | None = None) -> Table:
    """Read delimited text; with ``auto`` a lone value column is read as a Stable32 data file.

    ``stream``: the input already opened (a pipe, read once), else ``path`` is opened.
    """
    return _load(path, display, opts, progress, None if auto else "csv", stream)


@register("stable32",
          description="Stable32-style data file: header lines, then one value per line (or MJD and value)",
          options=("delimiter",))
def read_stable32(path: Path, display: str, opts: Options, progress: Progress, *, auto: bool = False,
                  stream: io.RawIOBase | None = None) -> Table:
    """Read a Stable32-style phase or frequency data file (``stream`` as for :func:`read_csv`)."""
    return _load(path, display, opts, progress, "stable32", stream)
