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
"""

from __future__ import annotations

import bz2
import csv
import functools
import gzip
import hashlib
import io
import itertools
import lzma
import re
import warnings
import zlib
from collections import Counter
from pathlib import Path
from typing import Iterator

import numpy as np

from ..errors import DataError, ParameterError
from ._columns import recognise, select, strip_name, time_name
from ._errors import FormatError, option_hint, repr_kw
from ._limits import MAX_LINE_CHARS, check_allocation
from ._progress import Progress
from ._registry import Options, Table, register
from ._units import canonical_unit, time_unit_name

__all__ = ["read_csv", "read_stable32"]

_COMMENTS = ("#", "%", "//")
_DELIMITERS: tuple[str | None, ...] = ("\t", ",", ";", "|", None)
_DELIMITER_NAMES = {"\t": "tab", ",": "comma", ";": "semicolon", "|": "pipe", None: "whitespace"}
_SNIFF_ROWS = 200
_SNIFF_MAX_LINES = 20_000
CHUNK_ROWS = 1 << 16
_INT = re.compile(r"^[+-]?\d+$")
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d+(?:[eE][+-]?\d+)?$")
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


def _strip_comment(line: str) -> str:
    cut = len(line)
    for c in _COMMENTS:
        k = line.find(c)
        if k != -1:
            cut = min(cut, k)
    return line[:cut]


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    if not line:
        return []
    if '"' not in line:  # what the csv module would return, without its 131,072-character field limit
        return [f.strip() for f in line.split(delimiter)]
    try:
        fields = next(csv.reader([line], delimiter=delimiter, quotechar='"', skipinitialspace=True), [])
    except csv.Error:  # a quoted field over the csv module's limit: not a number nor a name anyway
        return [f.strip().strip('"') for f in line.split(delimiter)]
    return [f.strip() for f in fields]


def _shown(value: str) -> str:
    """A field for a one-line message: quoted, at most 40 characters of it."""
    if not value:
        return "an empty field"
    return repr(value) if len(value) <= 40 else repr(value[:40]) + f"… ({len(value):,} characters)"


def _lines(text: io.TextIOWrapper) -> Iterator[str]:
    """Lines of at most MAX_LINE_CHARS characters: a longer line arrives cut and is refused
    by :func:`_check_lengths` instead of being held whole in memory."""
    return iter(functools.partial(text.readline, MAX_LINE_CHARS), "")


def _check_lengths(lines: list[str], first: int, display: str) -> None:
    if lines and max(map(len, lines)) >= MAX_LINE_CHARS:
        k = next(i for i, s in enumerate(lines) if len(s) >= MAX_LINE_CHARS)
        raise DataError(
            f"{display}: line {first + k} is longer than {MAX_LINE_CHARS:,} characters; not a table of numbers"
        )


def _is_num(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return "_" not in s


def _tail(split: list[list[str]]) -> tuple[list[list[str]], int, bool]:
    """The last lines (at most 20, at most half), their usual field count, and whether 80 % have it."""
    tail = split[-min(20, (len(split) + 1) // 2):]
    counts = Counter(len(f) for f in tail)
    c, hits = max(counts.items(), key=lambda kv: (kv[1], kv[0]))
    return tail, c, hits >= 0.8 * len(tail)


def _single_name(line: str) -> bool:
    """Whether a line can name a lone column: one word, or a channel or time name with a unit."""
    text = line.strip().strip('"')
    return len(text.split()) == 1 or recognise(text).group is not None or time_name(text) is not None


def _is_units_line(fields: list[str]) -> bool:
    """Whether a line under the header gives units: no numbers, every field a known unit or
    bracketed, at least one known or all bracketed (unknown ones are then refused by name,
    not skipped as a preamble line and replaced by a default unit)."""
    present = [x for x in fields if x]
    if not present or any(_is_num(x) for x in present):
        return False
    known = [bool(canonical_unit(x.strip("[]()")) or time_unit_name(x.strip("[]()"))) for x in present]
    bracketed = [x[:1] in "[(" and x[-1:] in "])" for x in present]
    short = all(len(x) <= 24 and len(x.split()) <= 3 for x in present)
    return short and (all(known) or all(bracketed) or (any(known) and all(k or len(x.split()) == 1
                                                                          for k, x in zip(known, present))))


def _mostly_numeric(values: list[str]) -> bool:
    good = sum(_is_num(v) for v in values)
    return good > 0 and 2 * good > len(values)


class _Sniff:
    """Layout of a text file from its first lines."""

    def __init__(self, head: list[str], delimiter: str | None, display: str, given_delimiter: bool):
        self.display = display
        entries = [(i + 1, line.rstrip("\r\n")) for i, line in enumerate(head)]
        self.comments = [(n, s) for n, s in entries if s.strip().startswith(_COMMENTS)]
        rows = [(n, s) for n, s in entries if s.strip() and not s.strip().startswith(_COMMENTS)]
        if not rows:
            raise DataError(f"{display}: no numeric data (only comments or blank lines)")
        self.delimiter = delimiter if given_delimiter else self._choose(rows)
        d = self.delimiter
        split = [_split(_strip_comment(s), d) for _, s in rows]
        tail, c, consistent = _tail(split)
        if not consistent:
            raise FormatError(
                f"{display}: not a table of numbers: its last lines split into different numbers of"
                f" fields ({_DELIMITER_NAMES.get(d, repr(d))} delimiter); if it is a table, give its delimiter"
                f" with {option_hint('--delimiter', 'delimiter=')}"
            )
        self.ncols = c
        tail = [f for f in tail if len(f) == c]
        # a column is numeric when most of the last lines hold numbers there: a stray bad value
        # is then reported with its line number by the parser instead of hiding the column
        self.numeric = [_mostly_numeric([f[j] for f in tail]) for j in range(c)]
        self.first_bad = [next((f[j] for f in tail if not _is_num(f[j])), None) for j in range(c)]
        if not any(self.numeric):
            raise DataError(f"{display}: no numeric data (no column of the last lines holds numbers)")
        start = next(
            k for k, f in enumerate(split)
            if len(f) == c and all(_is_num(f[j]) for j in range(c) if self.numeric[j])
        )
        self.data_line = rows[start][0]
        self.preamble = rows[:start]
        self.tail = tail
        self.header_line: int | None = None
        names: list[str] | None = None
        for n, s in self.preamble:
            f = [s.strip()] if c == 1 else _split(s, d)
            if len(f) == c and (c > 1 or _single_name(s)):
                names, self.header_line = f, n
                break
        if names is None:
            before = [(n, s) for n, s in self.comments if n < self.data_line]
            if before and not any(n > before[-1][0] for n, _ in self.preamble):
                n, s = before[-1]
                body = s.strip()
                for mark in _COMMENTS:
                    if body.startswith(mark):
                        body = body[len(mark):].strip()
                        break
                f = ([body] if c == 1 else _split(body, d)) if body else []
                if len(f) == c and (c > 1 or _single_name(body)) and not all(_is_num(x) for x in f):
                    names, self.header_line = f, n
        self.has_header = names is not None
        self.names = self._names(names, c)
        for n, s in self.preamble:
            f = _split(_strip_comment(s), d)
            if n != self.header_line and len(f) == c and c > 1:
                nums = [j for j in range(c) if self.numeric[j] and _is_num(f[j])]
                bad = [j for j in range(c) if self.numeric[j] and not _is_num(f[j])]
                if nums and bad:  # a data line with a damaged value, not a preamble line
                    j = bad[0]
                    raise DataError(
                        f"{display}: line {n}: {_shown(f[j])} in column {self.names[j]!r} is not a number")
        self.units_line: dict[str, str] = {}
        after = [(n, s) for n, s in self.preamble if self.header_line and n > self.header_line]
        for _, s in after:
            f = _split(s, d)
            if len(f) == c and _is_units_line(f):
                self.units_line = {self.names[j]: f[j].strip("[]()") for j in range(c) if f[j]}
        self.skipped = sum(1 for n, _ in self.preamble if n != self.header_line)
        self.text = " ".join(s for _, s in self.comments + self.preamble)

    @staticmethod
    def _names(names: list[str] | None, c: int) -> list[str]:
        if names is None:
            return [f"col{j}" for j in range(c)]
        out: list[str] = []
        for j, raw in enumerate(names):
            name = raw.strip().strip('"').strip("'").strip() or f"col{j}"
            if name in out:
                name = f"{name}_{j}"
            out.append(name)
        return out

    def _choose(self, rows: list[tuple[int, str]]) -> str | None:
        best: tuple | None = None
        choice: str | None = None
        for pref, d in enumerate(_DELIMITERS):
            split = [_split(_strip_comment(s), d) for _, s in rows]
            tail, c, consistent = _tail(split)
            tail = [f for f in tail if len(f) == c]
            nnum = sum(_mostly_numeric([f[j] for f in tail]) for j in range(c)) if consistent else 0
            key = (consistent and nnum > 0, nnum, c, -pref)
            if best is None or key > best:
                best, choice = key, d
        assert best is not None
        if best[2] == 1:
            choice = None
        comma_split = _tail([_split(_strip_comment(s), ",") for _, s in rows])[0]
        if choice == "," and not all(_is_num(x) for f in comma_split for x in f):
            for alt in (";", "\t", None):
                tail = _tail([_split(_strip_comment(s), alt) for _, s in rows])[0]
                if all(len(f) == len(tail[-1]) for f in tail) and all(
                    all(_is_num(x) or _DECIMAL_COMMA.match(x) for x in f) for f in tail
                ) and any(_DECIMAL_COMMA.match(x) for f in tail for x in f):
                    raise FormatError(
                        f"{self.display}: the numbers use decimal commas (such as {tail[-1][0]!r}),"
                        " which are not supported; convert them to decimal points"
                    )
        return choice


def _read_head(text: io.TextIOWrapper, display: str) -> list[str]:
    head: list[str] = []
    rows = 0
    for line in _lines(text):
        _check_lengths([line], len(head) + 1, display)
        head.append(line)
        s = line.strip()
        if s and not s.startswith(_COMMENTS):
            rows += 1
        if rows >= _SNIFF_ROWS or len(head) >= _SNIFF_MAX_LINES:
            break
    sample = "".join(head[:200])
    if "\x00" in sample or sample.count("\ufffd") > max(2, len(sample) // 100):
        raise FormatError(f"{display}: not a text file (binary content) and not a recognised binary format")
    if not head:
        raise DataError(f"{display}: the file is empty")
    return head


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
    names = sniff.names
    numeric_idx = [j for j in range(sniff.ncols) if sniff.numeric[j]]
    imu_named = any(recognise(n).group for n in names)
    if flavour is None:  # auto: a lone numeric column (or MJD + value) is a Stable32-style file
        lone = len(numeric_idx) == 1 or (len(numeric_idx) == 2 and _looks_mjd(sniff, numeric_idx[0]))
        explicit = opts.columns is not None or opts.time_column is not None
        flavour = "stable32" if (lone and not imu_named and not explicit) else "csv"

    time_idx: int | None
    stated_unit: str | None
    if flavour == "stable32":
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
            time_idx, chans, stated_unit = numeric_idx[0], (numeric_idx[1],), "d"
            if opts.time_column is False:
                raise ParameterError(f"{display}: time_column=False (--time-column none): a two-column Stable32"
                                     " file has MJD time tags first")
        else:
            time_idx, chans, stated_unit = None, (numeric_idx[0],), None
        skipped: tuple[str, ...] = ()
        unused: tuple[tuple[str, str], ...] = ()
    else:
        sel = select(names, sniff.numeric, columns=opts.columns, time_column=opts.time_column,
                     path=display, first_bad=sniff.first_bad)
        time_idx, chans, stated_unit, skipped = sel.time, sel.channels, sel.time_unit, sel.skipped
        unused = sel.unused
        if time_idx is not None and stated_unit is None and names[time_idx] in sniff.units_line:
            stated_unit = time_unit_name(sniff.units_line[names[time_idx]])

    usecols = ([time_idx] if time_idx is not None else []) + list(chans)
    int_time = False
    if time_idx is not None:
        values = [f[time_idx] for f in sniff.tail]
        int_time = all(_INT.match(v) for v in values) and max(abs(int(v)) for v in values) > 2**53
    if int_time:
        dtype: np.dtype = np.dtype([("t", "<i8")] + [(f"c{k}", "<f8") for k in range(len(chans))])
    else:
        dtype = np.dtype(np.float64)

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
    line_no = sniff.data_line
    while True:
        lines = list(itertools.islice(rest, CHUNK_ROWS))
        if not lines:
            break
        _check_lengths(lines, line_no, display)
        try:
            arr = _loadtxt(lines, sniff.delimiter, "#", usecols, dtype, quoted, int_time)
        except ValueError as exc:
            if quoted:
                raise _diagnose(lines, line_no, sniff, usecols, int_time, display, exc) from None
            try:  # '%' and '//' comments cost numpy a Python call per line: only when needed
                arr = _loadtxt(lines, sniff.delimiter, _COMMENTS, usecols, dtype, quoted, int_time)
            except ValueError as exc2:
                raise _diagnose(lines, line_no, sniff, usecols, int_time, display, exc2) from None
        m = arr.shape[0]
        if n + m > capacity:
            capacity = max(int(capacity * 1.6), n + m)
            check_allocation(display, 8 * capacity * (k + 1), f"{k} column(s) of {capacity:,} rows read so far")
            grown = np.empty((k, capacity))
            grown[:, :n] = buf[:, :n]
            buf = grown
            if tbuf is not None:
                tgrown = np.empty(capacity, dtype=tbuf.dtype)
                tgrown[:n] = tbuf[:n]
                tbuf = tgrown
        if int_time:
            tbuf[n:n + m] = arr["t"]  # type: ignore[index]
            for c in range(k):
                buf[c, n:n + m] = arr[f"c{c}"]
        else:
            offset = 0
            if tbuf is not None:
                tbuf[n:n + m] = arr[:, 0]
                offset = 1
            buf[:, n:n + m] = arr[:, offset:].T
        n += m
        line_no += len(lines)
        progress.update(hashing.nbytes)
    if n == 0:
        raise DataError(f"{display}: no numeric data rows")
    if capacity > n * 1.05 + 16:
        buf = buf[:, :n].copy()
        tbuf = None if tbuf is None else tbuf[:n].copy()
    data = {names[j]: buf[c, :n] for c, j in enumerate(chans)}
    time = None if tbuf is None else tbuf[:n]

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
    table = Table(
        format=flavour, columns=tuple(names), data=data, rows=n, sha256="", size=0,
        time=time, time_name=None if time_idx is None else names[time_idx],
        time_unit=stated_unit, units=units, detail="; ".join(parts), unused=unused,
    )
    if flavour == "stable32":
        dtype_name = opts.data_type or _stable32_type(sniff, path)
        if dtype_name is None:
            raise ParameterError(
                f"{display}: cannot tell whether this Stable32-style file holds phase or frequency data"
                " (neither or both words in its header and name); give it with"
                f" {_DATA_TYPE_HINT}"
            )
        (name,) = data
        table.data_type = dtype_name
        table.rename = {name: dtype_name}
        table.groups = {name: dtype_name}
        table.unit_origin = "format"
        table.units = {name: "s"} if dtype_name == "phase" else {}
        if time_idx is not None:
            table.time_unit_reason = "Stable32 time tags (MJD)"
    elif time_idx is not None and stated_unit is not None:
        table.time_unit_reason = f"from the column name {names[time_idx]!r}"
        if time_name(names[time_idx]) is None:
            table.time_unit_reason = "from the units line"
    return table


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
